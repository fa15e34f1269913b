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
