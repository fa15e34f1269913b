"""VTK XML UnstructuredGrid (.vtu) read by hammesh's own reader (hammesh.io.vtk_xml):
every data mode, header type and compressor VTK's writer has gives the mesh VTK's own
reader gives; meshio refused the LZ4 files and any ASCII file naming a compressor."""

from __future__ import annotations

import numpy as np
import pytest

from hammesh.errors import FileFormatError
from hammesh.io import read_mesh
from hammesh.io.vtk_xml import read_vtk_xml

pv = pytest.importorskip("pyvista")
vtk = pytest.importorskip("vtk")


def _grid():
    """Quads, triangles, a pixel and a polyline in one grid, with cell and point data."""
    plane = pv.Plane(i_resolution=4, j_resolution=3).cast_to_unstructured_grid()  # quads
    pts = np.array(plane.points)
    cells = plane.cells.reshape(-1, 5)[:, 1:]
    tris = np.r_[cells[:2, [0, 1, 2]], cells[:2, [0, 2, 3]]]
    quads = cells[2:]
    n = len(pts)
    pts = np.r_[pts, [[2, 0, 0], [3, 0, 0], [2, 1, 0], [3, 1, 0]]]  # a pixel's corners, row by row
    flat = np.r_[np.c_[np.full(len(tris), 3), tris].ravel(), np.c_[np.full(len(quads), 4), quads].ravel(),
                 [4, n, n + 1, n + 2, n + 3], [3, 0, 1, 2]]
    types = np.r_[np.full(len(tris), 5), np.full(len(quads), 9), [8], [4]].astype(np.uint8)
    grid = pv.UnstructuredGrid(flat, types, pts)
    grid.cell_data["mat"] = np.arange(grid.n_cells, dtype=np.int32) * 10
    grid.point_data["h"] = np.asarray(grid.points)[:, 0] * 2
    return grid


def _write(grid, path, mode, header, compressor):
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(grid)
    w.SetFileName(str(path))
    {"appended": w.SetDataModeToAppended, "binary": w.SetDataModeToBinary, "ascii": w.SetDataModeToAscii}[mode]()
    if mode == "appended":
        w.EncodeAppendedDataOff()  # raw bytes, VTK's default
    (w.SetHeaderTypeToUInt64 if header == "UInt64" else w.SetHeaderTypeToUInt32)()
    {"zlib": w.SetCompressorTypeToZLib, "lz4": w.SetCompressorTypeToLZ4, "lzma": w.SetCompressorTypeToLZMA,
     None: w.SetCompressorTypeToNone}[compressor]()
    w.Write()


@pytest.mark.parametrize("compressor", ["zlib", "lz4", "lzma", None])
@pytest.mark.parametrize("mode", ["appended", "binary", "ascii"])
@pytest.mark.parametrize("header", ["UInt32", "UInt64"])
def test_every_encoding_vtk_writes(tmp_path, compressor, mode, header):
    grid = _grid()
    path = tmp_path / "g.vtu"
    _write(grid, path, mode, header, compressor)
    raw = read_vtk_xml(path)
    np.testing.assert_array_equal(raw.points, grid.points)
    kinds = [b.type for b in raw.cells]
    assert kinds == ["triangle", "quad", "line"]
    # the pixel (type 8) is read as the quad of its corners in boundary order
    quads = raw.cells[1].data
    n = len(grid.points) - 4
    assert quads[-1].tolist() == [n, n + 1, n + 3, n + 2]
    # each cell's data follows it (10 quads and the pixel are cells 4..14, the polyline cell 15)
    per_block = [v.tolist() for v in raw.cell_data["mat"]]
    assert per_block == [[0, 10, 20, 30], list(range(40, 150, 10)), [150, 150]]
    np.testing.assert_allclose(raw.point_data["h"], np.asarray(grid.points)[:, 0] * 2)


@pytest.mark.parametrize("mode, compressor", [("appended", "lz4"), ("binary", "lz4"), ("ascii", "zlib")])
def test_files_meshio_refuses_read_like_the_zlib_one(tmp_path, mode, compressor):
    # read_mesh: meshio first (KeyError on LZ4, AssertionError on ASCII naming a
    # compressor), then hammesh's reader
    grid = _grid()
    a, b = tmp_path / "z.vtu", tmp_path / "l.vtu"
    _write(grid, a, "appended", "UInt64", "zlib")
    _write(grid, b, mode, "UInt32", compressor)
    ma, mb = read_mesh(a), read_mesh(b)
    np.testing.assert_array_equal(ma.triangles, mb.triangles)
    np.testing.assert_array_equal(ma.triangle_attributes, mb.triangle_attributes)
    np.testing.assert_array_equal(ma.segments, mb.segments)


def test_large_lz4_arrays_span_several_blocks(tmp_path):
    # VTK compresses in 32 KiB blocks: a 200k-point sphere's arrays are many blocks
    sphere = pv.Sphere(theta_resolution=400, phi_resolution=300).cast_to_unstructured_grid()
    path = tmp_path / "s.vtu"
    _write(sphere, path, "appended", "UInt32", "lz4")
    raw = read_vtk_xml(path)
    np.testing.assert_array_equal(raw.points, sphere.points)
    np.testing.assert_array_equal(np.concatenate([b.data for b in raw.cells]), sphere.cells.reshape(-1, 4)[:, 1:])


def test_volume_cells_are_refused_by_name(tmp_path):
    grid = pv.UnstructuredGrid(np.array([4, 0, 1, 2, 3]), np.array([10], dtype=np.uint8),
                               np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float))
    path = tmp_path / "t.vtu"
    grid.save(path)
    with pytest.raises(FileFormatError, match="tetra"):
        read_mesh(path, dim=None)


def test_a_polydata_file_named_vtu_is_refused(tmp_path):
    path = tmp_path / "p.vtu"
    pv.Sphere().save(tmp_path / "p.vtp")
    path.write_bytes((tmp_path / "p.vtp").read_bytes())
    with pytest.raises(FileFormatError, match="UnstructuredGrid"):
        read_mesh(path, dim=3)


def test_a_pvtu_of_lz4_pieces_written_by_vtk(tmp_path):
    # VTK's parallel writer, LZ4 pieces (meshio refuses them): read through hammesh's reader
    from hammesh.io import read_mesh as read

    plane = pv.Plane(i_resolution=6, j_resolution=5).triangulate().cast_to_unstructured_grid()
    plane.cell_data["mat"] = np.arange(plane.n_cells, dtype=np.int32)
    w = vtk.vtkXMLPUnstructuredGridWriter()
    w.SetInputData(plane)
    w.SetFileName(str(tmp_path / "p.pvtu"))
    w.SetNumberOfPieces(1)  # (without a streaming source every piece would hold all cells)
    w.SetCompressorTypeToLZ4()
    w.Write()
    assert len(list(tmp_path.glob("p_*.vtu"))) == 1
    m = read(tmp_path / "p.pvtu")
    assert len(m.triangles) == plane.n_cells
    u = m.points[m.triangles[:, 1]] - m.points[m.triangles[:, 0]]
    v = m.points[m.triangles[:, 2]] - m.points[m.triangles[:, 0]]
    area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum()
    assert area == pytest.approx(1.0)
    assert sorted(m.triangle_attributes[:, m.attribute_names.index("mat")].tolist()) == list(range(plane.n_cells))


@pytest.mark.parametrize("compressor", ["zlib", None])
def test_cells_meshio_skips_are_read_not_lost(tmp_path, compressor):
    # meshio 5 skips VTK triangle strips (6) and polylines (4) in a .vtu with a warning:
    # read_mesh must give every triangle and segment VTK sees, each with its cell data
    plane = pv.Plane(i_resolution=5, j_resolution=4).triangulate()
    strips = plane.strip()  # PolyData strips
    pts = np.asarray(strips.points)
    flat = np.r_[np.asarray(strips.strips), [4, 0, 1, 2, 3]]
    n_strips = int(strips.n_strips)
    types = np.r_[np.full(n_strips, 6), [4]].astype(np.uint8)
    grid = pv.UnstructuredGrid(flat, types, pts)
    grid.cell_data["mat"] = np.arange(grid.n_cells, dtype=np.int32) + 1
    path = tmp_path / "strips.vtu"
    _write(grid, path, "appended", "UInt64", compressor)
    m = read_mesh(path, dim=3)
    vtk_tris = grid.triangulate()  # VTK's own reading: strips as triangles
    want = {tuple(sorted(c)) for c in vtk_tris.cells_dict[5].tolist()}
    assert {tuple(sorted(c)) for c in m.triangles.tolist()} == want
    assert len(m.triangles) == len(want) == plane.n_cells
    assert sorted(map(tuple, np.sort(m.segments, axis=1).tolist())) == [(0, 1), (1, 2), (2, 3)]
    # each triangle carries its strip's value, each segment the polyline's
    tri_mat = m.triangle_attributes[:, m.attribute_names.index("mat")] if "mat" in m.attribute_names else None
    assert tri_mat is not None and set(tri_mat.tolist()) == set(range(1, n_strips + 1))
