"""hammesh's own text writers (.obj .off .stl .xdmf .node/.ele): exact, read back by meshio too."""

from __future__ import annotations

import io
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

import hammesh.io as hio
from hammesh.io.cell_data import triangle_cell_data
from hammesh.io.stl_format import facet_normals
from hammesh.io.text_rows import format_rows, write_rows
from hammesh.mesh import Mesh

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@given(hnp.arrays(np.float64, st.tuples(st.integers(0, 40), st.integers(1, 4)), elements=finite),
       st.integers(1, 7))
@settings(max_examples=60, deadline=None)
def test_float_rows_read_back_bit_for_bit(values, chunk):
    f = io.StringIO()
    write_rows(f, list(values.T), chunk=chunk)
    text = f.getvalue()
    assert text.count("\n") == len(values)
    back = np.array([[float(x) for x in line.split()] for line in text.splitlines()]).reshape(values.shape)
    assert np.array_equal(back.view(np.int64), values.view(np.int64)) or np.array_equal(back, values)


@given(st.lists(st.tuples(st.integers(-2**62, 2**62), finite, st.booleans()), max_size=30))
def test_mixed_columns_keep_their_kind(rows):
    ints = np.array([r[0] for r in rows], dtype=np.int64)
    floats = np.array([r[1] for r in rows], dtype=np.float64)
    flags = np.array([r[2] for r in rows], dtype=bool)
    lines = format_rows([ints, floats, flags], prefix="r ").splitlines()
    assert len(lines) == len(rows)
    for line, (i, x, b) in zip(lines, rows):
        word, a, c, d = line.split()
        assert (word, int(a), float(c), int(d)) == ("r", i, x, int(b))


def _surface(rng: np.random.Generator) -> Mesh:
    points = rng.normal(size=(30, 3)) * 10.0 ** rng.integers(-5, 5)
    triangles = np.array([rng.choice(30, 3, replace=False) for _ in range(40)], dtype=np.int64)
    return Mesh(points, triangles)


@pytest.mark.parametrize("suffix", [".obj", ".off", ".xdmf", ".stl"])
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning")  # (meshio.read of ASCII STL)
def test_surface_round_trip_is_exact(tmp_path, suffix, seed):
    mesh = _surface(np.random.default_rng(seed))
    path = tmp_path / f"s{suffix}"
    hio.write(mesh, path)
    ours, theirs = hio.read_mesh(path, dim=3), meshio.read(path)
    corners = mesh.points[mesh.triangles]
    if suffix == ".stl":  # a soup: the corners of every facet, in order
        assert np.array_equal(ours.points[ours.triangles], corners)
        assert np.array_equal(theirs.points[theirs.cells[0].data], corners)
        normals = np.array([[float(v) for v in line.split()[2:]] for line in path.read_text().splitlines()
                            if line.startswith("facet")])
        assert np.allclose(normals, facet_normals(mesh.points, mesh.triangles))
    else:
        assert np.array_equal(ours.points, mesh.points) and np.array_equal(ours.triangles, mesh.triangles)
        assert np.array_equal(theirs.points, mesh.points)
        assert np.array_equal(theirs.cells[0].data, mesh.triangles)


@pytest.mark.parametrize("suffix", [".obj", ".off"])
@pytest.mark.parametrize("width", [3, 4])
def test_vertex_colours_are_written_and_read_back(tmp_path, suffix, width):
    mesh = _surface(np.random.default_rng(2))
    colours = np.random.default_rng(3).random((len(mesh.points), width))
    coloured = Mesh(mesh.points, mesh.triangles, point_data={"color": colours})
    path = tmp_path / f"c{suffix}"
    assert hio.unwritten_data(coloured, path) == []
    hio.write(coloured, path)
    back = hio.read_mesh(path, dim=3)
    assert np.array_equal(back.point_data["color"], colours)


def test_xdmf_keeps_the_cycle_fields(tmp_path, hexagon):
    path = tmp_path / "h.xdmf"
    hio.write(hexagon, path)
    got = meshio.read(path)
    assert np.array_equal(got.cell_data["cycle_position"][0], triangle_cell_data(hexagon)["cycle_position"])
    assert got.cell_data["cycle_position"][0].dtype.kind == "i"
    assert np.array_equal(got.points[:, :2], hexagon.points)


def test_ply_keeps_every_field_of_a_hamiltonian_mesh(tmp_path):
    import hammesh

    domain = hammesh.read_domain(Path(hammesh.__file__).parent / "data" / "demo.poly")
    h = hammesh.hamiltonian(hammesh.quality_mesh(domain, min_angle=30, max_area=0.05))
    hio.write(h, tmp_path / "h.ply")
    hio.write(h, tmp_path / "h.vtu")
    a, b = hio.read_mesh(tmp_path / "h.ply"), hio.read_mesh(tmp_path / "h.vtu")
    for field in ("points", "triangles", "segments", "segment_markers", "triangle_attributes", "vertex_markers"):
        assert np.array_equal(getattr(a, field), getattr(b, field), equal_nan=True), field
    assert a.vertex_markers.any() and len(a.segments)
    assert hio.unwritten_data(h, tmp_path / "h.ply") == []
    theirs = meshio.read(tmp_path / "h.ply")  # (ASCII: meshio's binary reader fails on face properties)
    assert np.array_equal(theirs.cell_data["cycle_position"][0], triangle_cell_data(h)["cycle_position"])
    assert np.array_equal(theirs.cells[0].data, h.triangles)


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=25, deadline=None)
def test_ply_round_trips_point_and_cell_data_of_any_dtype(seed):
    import tempfile

    rng = np.random.default_rng(seed)
    mesh = _surface(rng)
    n, m = len(mesh.points), len(mesh.triangles)
    dtypes = [np.int8, np.uint8, np.int16, np.int32, np.int64, np.float32, np.float64, bool]
    point_data = {f"p{j}": (rng.normal(size=(n, int(rng.integers(1, 4)))) * 100).astype(dt)
                  for j, dt in enumerate(rng.choice(dtypes, 3))}
    point_data["big"] = rng.integers(-2**52, 2**52, n)  # beyond int32: written as double, exact
    point_data["x"] = rng.normal(size=n)  # a name PLY uses for the coordinates
    attrs = rng.normal(size=(m, 2))
    mesh = Mesh(mesh.points, mesh.triangles, triangle_attributes=attrs, attribute_names=("a b", "c"),
                point_data=point_data)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "d.ply"
        hio.write(mesh, path)
        back = hio.read_mesh(path, dim=3)
        theirs = meshio.read(path)  # meshio reads it too (ASCII: face properties; no brackets in names)
        assert np.array_equal(theirs.points, mesh.points)
    assert np.array_equal(back.points, mesh.points) and np.array_equal(back.triangles, mesh.triangles)
    assert np.array_equal(back.triangle_attributes, attrs)
    assert back.attribute_names == ("a b", "c")  # (exact: a "comment hammesh name" line)
    for name, values in point_data.items():
        got = back.point_data[name]  # (x too: written as input_x, named back by its comment)
        assert np.array_equal(got.reshape(values.shape), values.astype(got.dtype).reshape(values.shape)), name
        assert np.array_equal(got.astype(np.float64).reshape(values.shape), values.astype(np.float64)), name
