"""Legacy VTK POLYDATA: the POINT_DATA / CELL_DATA arrays are read and carried."""

from __future__ import annotations

import numpy as np
import pytest

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
