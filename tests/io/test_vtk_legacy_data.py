"""Legacy VTK POLYDATA: the POINT_DATA / CELL_DATA arrays are read and carried."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.errors import FileFormatError
from hammesh.io import read_mesh

# a unit square: 2 triangles as one strip, 1 triangle polygon on top, one polyline;
# cell order: the line (LINES first), then the polygon, then the strip
ASCII = """# vtk DataFile Version 3.0
square
ASCII
DATASET POLYDATA
POINTS 5 double
0 0 0 1 0 0 1 1 0 0 1 0 0.5 1.5 0
LINES 1 3
2 0 1
POLYGONS 1 4
3 3 2 4
TRIANGLE_STRIPS 1 5
4 0 1 3 2
POINT_DATA 5
SCALARS height float 1
LOOKUP_TABLE default
0 1 2 1 2.5
VECTORS velocity double
0 0 0 1 0 0 1 1 0 0 1 0 0.5 1.5 0
CELL_DATA 3
SCALARS material int 1
LOOKUP_TABLE default
7 8 9
FIELD extra 2
density 1 3 double
0.5 1.5 2.5
ids 2 3 int
1 2 3 4 5 6
LOOKUP_TABLE mine 2
0 0 0 1 1 1 1 1
"""


def test_ascii_arrays_reach_the_mesh(tmp_path):
    path = tmp_path / "sq.vtk"
    path.write_text(ASCII)
    m = read_mesh(path)
    np.testing.assert_array_equal(m.point_data["height"], [0, 1, 2, 1, 2.5])
    assert m.point_data["velocity"].shape == (5, 3)
    # triangles: the polygon (cell 1), then the strip's two (cell 2)
    names = m.attribute_names
    material = m.triangle_attributes[:, names.index("material")]
    np.testing.assert_array_equal(material, [8, 9, 9])
    np.testing.assert_array_equal(m.triangle_attributes[:, names.index("density")], [1.5, 2.5, 2.5])
    np.testing.assert_array_equal(m.triangle_attributes[:, [names.index("ids[0]"), names.index("ids[1]")]],
                                  [[3, 4], [5, 6], [5, 6]])
    assert m.segments.tolist() == [[0, 1]]


def test_arrays_go_through_hamiltonian(tmp_path):
    path = tmp_path / "sq.vtk"
    path.write_text(ASCII)
    m = read_mesh(path)
    h = hammesh.hamiltonian(m, mode="incircle")
    # height = x + y on the square's corners: linear there, so exact at new points inside it
    inside = np.flatnonzero(h.points[:, 1] <= 1.0)
    np.testing.assert_allclose(h.point_data["height"][inside], h.points[inside].sum(axis=1), atol=1e-12)
    np.testing.assert_array_equal(h.triangle_attributes, m.triangle_attributes[h.parent])


def test_wrong_array_length_is_refused(tmp_path):
    path = tmp_path / "bad.vtk"
    path.write_text(ASCII.replace("CELL_DATA 3", "CELL_DATA 2").replace("7 8 9", "7 8"))
    with pytest.raises(FileFormatError, match="cell data"):
        read_mesh(path)


def test_binary_51_file_from_pyvista(tmp_path):
    pv = pytest.importorskip("pyvista")
    p = pv.Plane(i_resolution=4, j_resolution=3).triangulate()
    p.clear_data()
    p.point_data["elev"] = p.points[:, 0] * 2 + p.points[:, 1]
    p.cell_data["mat"] = np.arange(p.n_cells) % 3
    p.save(tmp_path / "p.vtk", binary=True)
    m = read_mesh(tmp_path / "p.vtk")
    np.testing.assert_array_equal(m.point_data["elev"], np.asarray(p.point_data["elev"]))
    np.testing.assert_array_equal(m.triangle_attributes[:, m.attribute_names.index("mat")],
                                  np.asarray(p.cell_data["mat"]))


def test_binary_file_with_vtk_id_type_arrays_from_a_pyvista_filter(tmp_path):
    # extract_surface adds vtkOriginalCellIds (vtkIdType: 4 bytes each in a binary file)
    pv = pytest.importorskip("pyvista")
    p = pv.Plane(i_resolution=3, j_resolution=3).triangulate().extract_surface(algorithm="dataset_surface")
    p.save(tmp_path / "es.vtk", binary=True)
    m = read_mesh(tmp_path / "es.vtk")
    assert m.n_triangles == p.n_cells
    ids = m.triangle_attributes[:, m.attribute_names.index("vtkOriginalCellIds")]
    np.testing.assert_array_equal(ids, np.asarray(p.cell_data["vtkOriginalCellIds"]))


def _binary_square(bits: bytes, values: np.ndarray) -> bytes:
    """A binary legacy file: the unit square's two triangles, a bit array and doubles per cell."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=">f8")
    polys = np.array([3, 0, 1, 2, 3, 0, 2, 3], dtype=">i4")
    return (b"# vtk DataFile Version 3.0\nsq\nBINARY\nDATASET POLYDATA\nPOINTS 4 double\n"
            + pts.tobytes() + b"\nPOLYGONS 2 8\n" + polys.tobytes()
            + b"\nCELL_DATA 2\nSCALARS flag bit 1\nLOOKUP_TABLE default\n" + bits
            + b"\nSCALARS value double 1\nLOOKUP_TABLE default\n" + values.astype(">f8").tobytes() + b"\n")


def test_bit_arrays_and_nan_values_are_data(tmp_path):
    # ASCII bits are 0/1 words; binary bits are packed eight to a byte, most significant first
    ascii_file = tmp_path / "a.vtk"
    ascii_file.write_text(ASCII.replace("SCALARS material int 1", "SCALARS material bit 1")
                          .replace("7 8 9", "1 0 1"))
    m = read_mesh(ascii_file)
    np.testing.assert_array_equal(m.triangle_attributes[:, m.attribute_names.index("material")], [0, 1, 1])

    binary_file = tmp_path / "b.vtk"
    binary_file.write_bytes(_binary_square(bytes([0b01000000]), np.array([np.nan, 2.0])))
    m = read_mesh(binary_file)
    np.testing.assert_array_equal(m.triangle_attributes[:, m.attribute_names.index("flag")], [0, 1])
    value = m.triangle_attributes[:, m.attribute_names.index("value")]
    assert np.isnan(value[0]) and value[1] == 2.0

    # a NaN in the user's cell data is carried to the output, not refused after all the work
    h = hammesh.hamiltonian(m, mode="incircle")
    out = tmp_path / "out.vtu"
    hammesh.io.write(h, out)
    back = read_mesh(out)
    carried = back.triangle_attributes[:, back.attribute_names.index("value")]
    np.testing.assert_array_equal(np.isnan(carried), np.isnan(value[h.parent]))


# an unstructured grid with every surface cell kind: a quad, two triangles, a pixel
# (corners row by row), a polyline and a vertex; dataset-level FIELD data before POINTS
GRID_CELLS = [[0, 1, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 6, 7], [0, 3, 6], [2]]
GRID_TYPES = [9, 5, 5, 8, 4, 1]


def _grid_text(layout: str) -> str:
    head = ("# vtk DataFile Version {v}\ngrid\nASCII\nDATASET UNSTRUCTURED_GRID\n"
            "FIELD FieldData 1\nTIME 1 1 double\n1.5\n"
            "POINTS 8 double\n0 0 0 1 0 0 2 0 0 0 1 0 1 1 0 2 1 0 0 2 0 1 2 0\n")
    if layout == "classic":
        size = sum(len(c) + 1 for c in GRID_CELLS)
        cells = f"CELLS 6 {size}\n" + "\n".join(f"{len(c)} " + " ".join(map(str, c)) for c in GRID_CELLS)
        head = head.format(v="4.2")
    else:
        offsets = np.cumsum([0] + [len(c) for c in GRID_CELLS])
        conn = [i for c in GRID_CELLS for i in c]
        cells = (f"CELLS 7 {len(conn)}\nOFFSETS vtktypeint64\n" + " ".join(map(str, offsets))
                 + "\nCONNECTIVITY vtktypeint64\n" + " ".join(map(str, conn)))
        head = head.format(v="5.1")
    return (head + cells + "\nCELL_TYPES 6\n" + " ".join(map(str, GRID_TYPES))
            + "\nCELL_DATA 6\nFIELD FieldData 1\nmat 1 6 vtktypeint32\n0 10 20 30 40 50\n"
            + "POINT_DATA 8\nSCALARS x float 1\nLOOKUP_TABLE default\n0 1 2 0 1 2 0 1\n")


@pytest.mark.parametrize("layout", ["classic", "5.1"])
def test_unstructured_grid_cells_and_data(tmp_path, layout):
    path = tmp_path / "grid.vtk"
    path.write_text(_grid_text(layout))
    m = read_mesh(path)
    # every cell's area is kept (quad and pixel split into two triangles each), all CCW
    p = m.points[m.triangles]
    u, v = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = 0.5 * (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    assert (area > 0).all() and area.sum() == pytest.approx(3.0)
    # a triangle's cell value is its cell's: the pixel's two triangles lie in y >= 1, x <= 1
    mat = m.triangle_attributes[:, m.attribute_names.index("mat")]
    centroid = p.mean(axis=1)
    in_pixel = (centroid[:, 1] > 1) & (centroid[:, 0] < 1)
    assert (mat[in_pixel] == 30).all() and in_pixel.sum() == 2
    assert sorted(set(mat.tolist())) == [0, 10, 20, 30]
    assert sorted(map(sorted, m.segments.tolist())) == [[0, 3], [3, 6]]
    np.testing.assert_array_equal(m.point_data["x"], m.points[:, 0])


def test_volume_cells_are_refused_by_name(tmp_path):
    path = tmp_path / "tet.vtk"
    path.write_text("# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                    "POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n")
    with pytest.raises(FileFormatError, match="tetra"):
        read_mesh(path, dim=None)


def test_encoded_names_are_decoded(tmp_path):
    # VTK's writer encodes a space in an array name as %20
    path = tmp_path / "sq.vtk"
    path.write_text(ASCII.replace("SCALARS height float 1", "SCALARS my%20height float 1"))
    assert "my height" in read_mesh(path).point_data


def _row_of_squares(kinds: list[bool], order: list[int]) -> tuple[str, list[list[int]], list[int]]:
    """A row of unit squares, each one quad (True) or two triangles, cells in ``order``."""
    n = len(kinds)
    points = " ".join(f"{x} {y} 0" for y in (0, 1) for x in range(n + 1))
    cells: list[list[int]] = []
    types: list[int] = []
    for i, quad in enumerate(kinds):
        a, b, c, d = i, i + 1, n + 2 + i, n + 1 + i
        if quad:
            cells.append([a, b, c, d]), types.append(9)
        else:
            cells += [[a, b, c], [a, c, d]]
            types += [5, 5]
    cells = [cells[k % len(cells)] for k in order] if order else cells
    types = [types[k % len(types)] for k in order] if order else types
    return f"POINTS {2 * (n + 1)} double\n{points}\n", cells, types


@given(kinds=st.lists(st.booleans(), min_size=1, max_size=40),
       order=st.permutations(list(range(80))))
@settings(max_examples=40, deadline=None)
def test_classic_cells_of_mixed_sizes_read_as_the_51_layout(tmp_path_factory, kinds, order):
    # the classic layout interleaves sizes and indices; cells of mixed sizes are found by
    # following the sizes, which must give the same cells as the 5.1 layout's offsets
    points, cells, types = _row_of_squares(kinds, [])
    perm = [k for k in order if k < len(cells)]
    cells, types = [cells[k] for k in perm], [types[k] for k in perm]
    head = "# vtk DataFile Version {v}\nrow\nASCII\nDATASET UNSTRUCTURED_GRID\n" + points
    tail = (f"\nCELL_TYPES {len(cells)}\n" + " ".join(map(str, types))
            + f"\nCELL_DATA {len(cells)}\nSCALARS id int 1\nLOOKUP_TABLE default\n"
            + " ".join(map(str, range(len(cells)))) + "\n")
    size = sum(len(c) + 1 for c in cells)
    classic = (head.format(v="4.2") + f"CELLS {len(cells)} {size}\n"
               + "\n".join(f"{len(c)} " + " ".join(map(str, c)) for c in cells) + tail)
    offsets = np.cumsum([0] + [len(c) for c in cells])
    v51 = (head.format(v="5.1") + f"CELLS {len(cells) + 1} {offsets[-1]}\nOFFSETS vtktypeint64\n"
           + " ".join(map(str, offsets)) + "\nCONNECTIVITY vtktypeint64\n"
           + " ".join(str(i) for c in cells for i in c) + tail)
    d = tmp_path_factory.mktemp("row")
    (d / "classic.vtk").write_text(classic)
    (d / "v51.vtk").write_text(v51)
    a, b = read_mesh(d / "classic.vtk"), read_mesh(d / "v51.vtk")
    np.testing.assert_array_equal(a.triangles, b.triangles)
    np.testing.assert_array_equal(a.triangle_attributes, b.triangle_attributes)
    assert len(a.triangles) == 2 * len(kinds)


@pytest.mark.parametrize("cells, message", [
    ("CELLS 3 9\n3 0 1 2\n4 0 1 2 3\n", "data ends after 2"),       # a cell missing
    ("CELLS 2 9\n3 0 1 2\n5 0 1 2 3\n", "does not match the cells. lengths \\(10\\)"),  # a size too big
    ("CELLS 2 10\n3 0 1 2\n-2 0 1 2 3 4\n", "negative cell size"),
    ("CELLS 2 10\n3 0 1 2\n2 0 1 2 3 4\n", "does not match the cells. lengths \\(7\\)"),        # data left over
])
def test_classic_cell_lists_that_do_not_add_up_are_named(tmp_path, cells, message):
    path = tmp_path / "bad.vtk"
    path.write_text("# vtk DataFile Version 4.2\nb\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                    "POINTS 4 double\n0 0 0 1 0 0 1 1 0 0 1 0\n" + cells + "CELL_TYPES 2\n5 9\n")
    with pytest.raises(FileFormatError, match=message):
        read_mesh(path)


@pytest.mark.parametrize("dataset, geometry", [
    ("STRUCTURED_POINTS", "DIMENSIONS 3 2 1\nORIGIN 0 0 0\nSPACING 1 1 1\n"),
    ("STRUCTURED_GRID", "DIMENSIONS 2 2 1\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 1 1 0\n"),
    ("RECTILINEAR_GRID", "DIMENSIONS 2 2 1\nX_COORDINATES 2 float\n0 1\nY_COORDINATES 2 float\n0 1\n"
                         "Z_COORDINATES 1 float\n0\n"),
])
def test_structured_grids_are_named_with_the_way_out(tmp_path, dataset, geometry):
    # (meshio failed on them with "TypeError: object of type 'NoneType' has no len()")
    path = tmp_path / "g.vtk"
    path.write_text(f"# vtk DataFile Version 3.0\ngrid\nASCII\nDATASET {dataset}\n{geometry}")
    with pytest.raises(FileFormatError, match=f"{dataset} dataset.*cast_to_unstructured_grid"):
        read_mesh(path)


@pytest.mark.parametrize("suffix, dataset", [(".vti", "ImageData"), (".vts", "StructuredGrid"),
                                             (".vtr", "RectilinearGrid")])
def test_xml_structured_grids_are_named_with_the_way_out(tmp_path, suffix, dataset):
    path = tmp_path / f"g{suffix}"
    path.write_text(f'<VTKFile type="{dataset}"></VTKFile>')
    with pytest.raises(FileFormatError, match=f"{dataset}.*cast_to_unstructured_grid"):
        read_mesh(path)
