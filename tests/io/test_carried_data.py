"""Never lose data: a mesh file's named cell data and point data reach the output.

A foreign file's per-triangle fields (any name, scalar or vector) become named
``triangle_attributes`` columns, carried to each output triangle from its parent; its
per-point fields become ``point_data``, kept at the input points and interpolated at
Steiner points (:mod:`hammesh.point_data`); writers that can hold them write them back
under their names; anything that cannot be carried is reported, never dropped in silence.
"""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import hammesh
from hammesh.io import meshio_format, read_mesh, unwritten_data, write
from hammesh.io.raw import RawMesh
from hammesh.mesh import Mesh
from hammesh.numbering import renumber
from hammesh.point_data import carry_point_data
from tests.helpers import plate, star_pslg


def linear(points: np.ndarray, a: float = 3.0, b: float = -2.0, c: float = 1.0) -> np.ndarray:
    return a * points[:, 0] + b * points[:, 1] + c


@pytest.fixture(scope="module")
def base() -> Mesh:
    return plate(2, 1, max_area=0.01)


def with_data(m: Mesh) -> Mesh:
    """``m`` with two named cell fields (one a vector) and three point fields."""
    centroid = m.points[m.triangles].mean(axis=1)
    region = (centroid[:, 0] > 0.5).astype(np.float64) + 1
    normal = np.column_stack([centroid, np.arange(m.n_triangles, dtype=np.float64)])
    return replace(
        m,
        triangle_attributes=np.column_stack([region, normal]),
        attribute_names=("region", "normal[0]", "normal[1]", "normal[2]"),
        point_data={
            "temperature": linear(m.points),
            "velocity": np.column_stack([linear(m.points, 1, 1, 0), linear(m.points, 0, 2, 5)]),
            "label": (np.arange(m.n_points) % 5).astype(np.int32),
        },
    )


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_hamiltonian_carries_names_and_point_data(base, mode):
    m = with_data(base)
    h = hammesh.hamiltonian(m, mode=mode)
    assert h.attribute_names == m.attribute_names
    np.testing.assert_array_equal(h.triangle_attributes, m.triangle_attributes[h.parent])
    n0 = m.n_points
    assert h.n_points > n0  # (Steiner points: something to interpolate)
    for name, values in m.point_data.items():
        out = h.point_data[name]
        assert out.dtype == values.dtype and out.shape[1:] == values.shape[1:]
        np.testing.assert_array_equal(out[:n0], values)
    # a linear field is reproduced exactly at every new point (P1 interpolation)
    np.testing.assert_allclose(h.point_data["temperature"], linear(h.points), atol=1e-12)
    np.testing.assert_allclose(h.point_data["velocity"][:, 1], linear(h.points, 0, 2, 5), atol=1e-12)
    # a label stays a label: a new point takes one of its parent's corners' labels
    assert set(h.point_data["label"][n0:].tolist()) <= set(m.point_data["label"].tolist())


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), a=st.floats(-5, 5), b=st.floats(-5, 5), mode=st.sampled_from(["sparse", "incircle"]))
def test_linear_point_data_is_interpolated_exactly(dom, a, b, mode):
    m = hammesh.quality_mesh(dom, min_angle=25, max_area=0.02)
    m = replace(m, point_data={"f": linear(m.points, a, b, 0.5)})
    h = hammesh.hamiltonian(m, mode=mode)
    scale = 1.0 + abs(a) + abs(b)
    np.testing.assert_allclose(h.point_data["f"], linear(h.points, a, b, 0.5), atol=1e-12 * scale * 10)


def test_carry_finds_points_placed_off_their_parents():
    """A Steiner point outside every row's parent (sparse mode places some for their
    angles) is located in the input triangles around them."""
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    tri = np.array([[0, 1, 2], [1, 3, 2]])
    out = np.vstack([pts, [[0.75, 0.75]]])  # inside input row 1
    out_tri = np.array([[0, 1, 4], [1, 3, 4], [3, 2, 4], [2, 0, 4]])
    parent = np.zeros(4, dtype=np.int64)  # every row claims parent 0, which misses the point
    f = linear(pts)
    carried = carry_point_data({"f": f}, pts, tri, out, out_tri, parent)["f"]
    assert carried[4] == pytest.approx(linear(out[4:])[0])


def test_renumbering_moves_point_data(base):
    h = hammesh.hamiltonian(with_data(base))
    r, info = renumber(h, "rcm")
    np.testing.assert_array_equal(r.point_data["label"], h.point_data["label"][info["order"]])
    np.testing.assert_allclose(r.point_data["temperature"], linear(r.points), atol=1e-12)


def foreign_file(m: Mesh, path: Path) -> None:
    """``m`` with its data written by meshio itself (not by hammesh), integer region."""
    pts3 = np.column_stack([m.points, np.zeros(m.n_points)])
    region = (m.points[m.triangles].mean(axis=1)[:, 0] > 0.5).astype(np.int32) + 1
    cell_data = {"region": [region], "normal": [np.tile([0.0, 0.0, 1.0], (m.n_triangles, 1))]}
    point_data = {"temperature": linear(m.points), "label": (np.arange(m.n_points) % 5).astype(np.int32)}
    if path.suffix == ".msh":  # Gmsh: regions are physical surfaces
        cell_data = {"gmsh:physical": [region], "gmsh:geometrical": [region]}
        meshio.write(path, meshio.Mesh(pts3, [("triangle", m.triangles)], cell_data=cell_data,
                                       point_data={"temperature": point_data["temperature"]}),
                     file_format="gmsh22", binary=True)
        return
    meshio.write(path, meshio.Mesh(pts3, [("triangle", m.triangles)], cell_data=cell_data, point_data=point_data))


@pytest.mark.parametrize("suffix", [".vtu", ".vtk", ".xdmf", ".msh"])
@pytest.mark.parametrize("out_suffix", [".vtu", ".msh", ".ele"])
def test_foreign_fields_reach_the_output(base, tmp_path, suffix, out_suffix):
    src = tmp_path / f"in{suffix}"
    foreign_file(base, src)
    m = read_mesh(src)
    region_name = "physical" if suffix == ".msh" else "region"
    assert region_name in m.attribute_names
    h = hammesh.hamiltonian(m)
    dst = tmp_path / f"out{out_suffix}"
    write(h, dst)
    back = read_mesh(dst)
    assert unwritten_data(h, dst) == []
    j = m.attribute_names.index(region_name)
    k = back.attribute_names.index(region_name)
    expected = m.triangle_attributes[h.parent, j]
    np.testing.assert_array_equal(back.triangle_attributes[:, k], expected)
    np.testing.assert_allclose(back.point_data["temperature"].reshape(-1), linear(back.points), atol=1e-12)
    if suffix != ".msh":
        np.testing.assert_array_equal(back.point_data["label"][: m.n_points], m.point_data["label"])
        if out_suffix != ".msh":
            assert [x for x in back.attribute_names if x.startswith("normal")] == [f"normal[{i}]" for i in range(3)]


def test_vector_cell_data_is_written_as_one_array(base, tmp_path):
    h = hammesh.hamiltonian(with_data(base))
    write(h, tmp_path / "o.vtu")
    o = meshio.read(tmp_path / "o.vtu")
    assert o.cell_data["normal"][0].shape == (h.n_triangles, 3)
    assert o.point_data["velocity"].shape == (h.n_points, 2)


def test_hammesh_files_do_not_grow_fields(base, tmp_path):
    """hammesh's own output fields are re-derived, not read back as the user's data."""
    h = hammesh.hamiltonian(with_data(base))
    for suffix in (".vtu", ".msh", ".ele"):
        write(h, tmp_path / f"a{suffix}")
        again = read_mesh(tmp_path / f"a{suffix}")
        assert again.attribute_names == h.attribute_names, suffix
        assert sorted(again.point_data) == sorted(h.point_data), suffix


def test_what_cannot_be_carried_is_listed():
    raw = RawMesh(
        points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        cells=[meshio.CellBlock("triangle", np.array([[0, 1, 2]]))],
        cell_data={"name": [np.array(["steel"])], "ok": [np.array([2.0])]},
        point_data={"tag": np.array(["a", "b", "c"])},
    )
    m = meshio_format.to_mesh(raw, Path("x.vtu"))
    assert m.attribute_names == ("ok",)
    notes = m.info["not_carried"]
    assert any("'name'" in x for x in notes) and any("'tag'" in x for x in notes)


def test_cli_reports_data_a_format_cannot_hold(base, tmp_path):
    src = tmp_path / "in.vtu"
    foreign_file(base, src)
    out = subprocess.run(
        [sys.executable, "-m", "hammesh", "mesh", str(src), "-o", str(tmp_path / "o.obj"),
         "--report", str(tmp_path / "r.json")],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    assert "not written: cell data 'region' (.obj holds geometry only)" in out.stdout
    assert "'normal'" in out.stdout and "'temperature'" in out.stdout
    report = json.loads((tmp_path / "r.json").read_text())
    assert any("'label'" in x for x in report["not_carried"])


def test_triangle_node_attributes_are_point_data(tmp_path):
    """Triangle's own ``.node`` vertex attributes (unnamed) are read and carried."""
    (tmp_path / "t.node").write_text("4 2 1 0\n0 0 0 10\n1 1 0 20\n2 1 1 30\n3 0 1 40\n")
    (tmp_path / "t.ele").write_text("2 3 0\n0 0 1 2\n1 0 2 3\n")
    m = read_mesh(tmp_path / "t.ele")
    np.testing.assert_array_equal(m.point_data["attribute_0"], [10, 20, 30, 40])
    h = hammesh.hamiltonian(m, mode="incircle")
    write(h, tmp_path / "o.ele")
    back = read_mesh(tmp_path / "o.ele")
    np.testing.assert_array_equal(back.point_data["attribute_0"][:4], [10, 20, 30, 40])
    assert np.all((back.point_data["attribute_0"] >= 10) & (back.point_data["attribute_0"] <= 40))


@pytest.mark.parametrize("suffix", [".vtu", ".msh", ".ele"])
def test_user_fields_named_like_hammesh_fields_are_kept(tmp_path, suffix):
    # someone else's mesh with cell fields called kind and part: data, read and carried
    square = meshio.Mesh(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float), [("triangle", np.array([[0, 1, 2], [0, 2, 3]]))],
                         cell_data={"kind": [np.array([4.0, 5.0])], "part": [np.array([7, 8])]})
    src = tmp_path / "in.vtu"
    square.write(src)
    m = hammesh.io.read_mesh(src)
    assert set(m.attribute_names) == {"kind", "part"}
    h = hammesh.hamiltonian(m, mode="incircle")
    out = tmp_path / f"out{suffix}"
    hammesh.io.write(h, out)
    back = hammesh.io.read_mesh(out)
    # hammesh's own kind is not read back as data; the user's is, under input_kind
    kind = back.triangle_attributes[:, back.attribute_names.index("input_kind")]
    np.testing.assert_array_equal(kind, m.triangle_attributes[h.parent, m.attribute_names.index("kind")])
    assert "kind" not in back.attribute_names
    part = back.triangle_attributes[:, back.attribute_names.index("input_part")]
    np.testing.assert_array_equal(part, m.triangle_attributes[h.parent, m.attribute_names.index("part")])
