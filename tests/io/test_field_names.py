"""Point and cell data names of any text survive every writer that holds data."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.io.text_rows import header_token

P = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]])
T = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])

names = st.text(st.characters(blacklist_categories=("Cs", "Cc", "Zl", "Zp")), min_size=1, max_size=10).map(
    lambda s: "f" + s)


def mesh_with(point_name: str, cell_name: str) -> hammesh.Mesh:
    return hammesh.Mesh(P, T, triangle_attributes=np.arange(4.0)[:, None], attribute_names=(cell_name,),
                        point_data={point_name: P[:, 0] + 3 * P[:, 1]})


@pytest.mark.parametrize("suffix", [".vtk", ".ply", ".ele", ".vtu", ".msh", ".xdmf"])
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(point_name=names, cell_name=names)
def test_names_round_trip(tmp_path, suffix, point_name, cell_name):
    if point_name == cell_name or (suffix == ".msh" and '"' in point_name + cell_name):
        return  # (Gmsh's string tags are quoted and have no escape: see docs/input.md)
    path = tmp_path / f"m{suffix}"
    hammesh.write(mesh_with(point_name, cell_name), path)
    back = hammesh.read_mesh(path)
    assert list(back.point_data) == [point_name]
    np.testing.assert_array_equal(back.point_data[point_name], P[:, 0] + 3 * P[:, 1])
    assert back.attribute_names == (cell_name,)


@pytest.mark.parametrize("suffix", [".vtk", ".ply"])
def test_other_readers_read_them(tmp_path, suffix):
    path = tmp_path / f"m{suffix}"
    hammesh.write(mesh_with("température", "zone id"), path)
    other = meshio.read(path)
    assert len(other.point_data) == 1 and len(other.cells_dict["triangle"]) == 4
    if suffix == ".vtk":
        pv = pytest.importorskip("pyvista")
        grid = pv.read(path)
        assert "température" in grid.point_data.keys() and "zone id" in grid.cell_data.keys()


def test_header_token_is_vtks_encoding():
    assert header_token("my field") == "my%20field"
    assert header_token("température") == "temp%C3%A9rature"
    assert header_token('a"b%c') == "a%22b%25c"
    assert header_token("") == "_"


@pytest.mark.parametrize("suffix", [".obj", ".off", ".stl"])
def test_geometry_only_formats_name_the_lost_segments_and_markers(suffix):
    from hammesh.io import unwritten_data

    segs = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    m = hammesh.Mesh(P, T, segments=segs, segment_markers=np.array([1, 2, 2, 5]),
                     vertex_markers=np.array([1, 2, 2, 5, 0]))
    lost = " | ".join(unwritten_data(m, f"m{suffix}"))
    assert "4 constrained edges (segments) and their markers 1..5" in lost
    assert "vertex markers 1..5" in lost
    assert unwritten_data(m, "m.vtu") == []
    bare = hammesh.Mesh(P, T, segments=segs)
    assert [x for x in unwritten_data(bare, f"m{suffix}") if "markers" in x] == []
