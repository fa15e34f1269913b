"""hammesh's own ``.vtu`` writer: what meshio, pyvista and scikit-fem read back is what was written."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hammesh.io as hio
from hammesh.io import vtu
from hammesh.io.meshio_format import as_meshio

from tests.helpers import plate


def _assert_same(a: meshio.Mesh, b: meshio.Mesh) -> None:
    assert np.array_equal(a.points, b.points)
    assert [c.type for c in a.cells] == [c.type for c in b.cells]
    for x, y in zip(a.cells, b.cells):
        assert np.array_equal(x.data, y.data)
    assert sorted(a.cell_data) == sorted(b.cell_data)
    for name in a.cell_data:
        for x, y in zip(a.cell_data[name], b.cell_data[name]):
            assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
    assert sorted(a.point_data) == sorted(b.point_data)
    for name in a.point_data:
        assert np.array_equal(a.point_data[name], b.point_data[name]), name


@pytest.mark.parametrize("threads", [1, 3])
def test_reads_back_like_meshios_own_file(tmp_path, threads):
    h = plate(n_loops=2, pieces=2, max_area=0.002)
    import hammesh

    m = as_meshio(hammesh.hamiltonian(h), ".vtu")
    meshio.write(tmp_path / "meshio.vtu", m, file_format="vtu")
    vtu.write(tmp_path / "ours.vtu", m, threads=threads)
    _assert_same(meshio.read(tmp_path / "meshio.vtu"), meshio.read(tmp_path / "ours.vtu"))


@settings(max_examples=30, deadline=None)
@given(
    n=st.integers(1, 3 * vtu.BLOCK_BYTES // 24 + 5),  # meshio reads no empty cell block
    dtype=st.sampled_from([np.int8, np.uint8, np.int32, np.int64, np.float32, np.float64]),
    width=st.sampled_from([1, 3]),
    lines=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
)
def test_any_size_and_dtype_round_trips(tmp_path_factory, n, dtype, width, lines, seed):
    """Arrays of 1, several and partial 32 KiB blocks, every dtype hammesh writes, 2-D data."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n + 3, 3))
    tri = rng.integers(0, n + 3, size=(n, 3))
    cells = [("triangle", tri)]
    values = rng.normal(size=(n, width)) * 100
    data = [values.astype(dtype).reshape(n, -1) if width > 1 else values.astype(dtype).reshape(n)]
    if lines:
        seg = rng.integers(0, n + 3, size=(5, 2))
        cells.append(("line", seg))
        data.append(np.zeros((5, width) if width > 1 else 5, dtype))
    m = meshio.Mesh(points, cells, point_data={"marker": np.arange(n + 3)}, cell_data={"field": data})
    path = tmp_path_factory.mktemp("vtu") / "x.vtu"
    vtu.write(path, m, threads=2)
    back = meshio.read(path)
    assert np.array_equal(back.points, points)
    assert [c.type for c in back.cells] == [kind for kind, _ in cells]
    for c, (_, arr) in zip(back.cells, cells):
        assert np.array_equal(c.data.reshape(arr.shape), arr)
    got = np.concatenate([np.asarray(x).reshape(len(x), -1) for x in back.cell_data["field"]])
    want = np.concatenate([x.reshape(len(x), -1) for x in data])
    assert got.dtype == np.dtype(dtype) and np.array_equal(got, want)
    assert np.array_equal(back.point_data["marker"], np.arange(n + 3))


def test_hammesh_write_uses_it_and_pyvista_reads_it(tmp_path):
    pv = pytest.importorskip("pyvista")
    h = plate(n_loops=1, pieces=1)
    import hammesh

    hm = hammesh.hamiltonian(h)
    hio.write(hm, tmp_path / "out.vtu")
    assert b"created by hammesh" in (tmp_path / "out.vtu").read_bytes()[:300]
    grid = pv.read(tmp_path / "out.vtu")
    assert grid.n_cells == hm.n_triangles
    assert np.array_equal(np.asarray(grid.cell_data["cycle_position"]), as_meshio(hm).cell_data["cycle_position"][0])
    back = hio.read_mesh(tmp_path / "out.vtu")
    assert np.array_equal(back.triangles, hm.triangles)


def test_unknown_cell_type_is_a_programming_error(tmp_path):
    m = meshio.Mesh(np.zeros((4, 3)), [("quad", np.array([[0, 1, 2, 3]]))])
    with pytest.raises(ValueError, match="quad"):
        vtu.write(tmp_path / "q.vtu", m)
