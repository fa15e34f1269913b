"""Misused public functions raise HammeshError subclasses naming the problem."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import hammesh
from hammesh.errors import InvalidOptionError

P3 = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
T = np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize("kwargs, needle", [
    ({"triangle_attributes": np.zeros((5, 1))}, "triangle_attributes"),
    ({"triangle_attributes": np.zeros(2)}, "triangle_attributes"),
    ({"triangle_attributes": np.zeros((2, 1)), "attribute_names": ("a", "b")}, "attribute_names"),
    ({"point_data": {"a": np.zeros(2)}}, "point_data['a']"),
    ({"max_fold_deg": -1}, "max_fold_deg=-1"),
    ({"max_fold_deg": 181}, "max_fold_deg=181"),
])
def test_surface_options_checked(kwargs, needle):
    from hammesh.surface import surface_hamiltonian

    with pytest.raises(InvalidOptionError) as info:
        surface_hamiltonian(P3, T, **kwargs)
    assert needle in str(info.value)


def test_surface_options_that_fit_are_taken():
    from hammesh.surface import surface_hamiltonian

    h = surface_hamiltonian(P3, T, triangle_attributes=np.array([[1.0], [2.0]]), attribute_names=("a",),
                            point_data={"t": np.arange(4.0)})
    assert h.attribute_names == ("a",) and sorted(np.unique(h.triangle_attributes)) == [1.0, 2.0]


def test_write_refuses_a_domain(tmp_path):
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    with pytest.raises(InvalidOptionError, match="Domain"):
        hammesh.write(dom, tmp_path / "d.vtu")
    assert not (tmp_path / "d.vtu").exists()


def test_hamiltonian_of_a_hamiltonian_mesh_keeps_it():
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.01))
    again = hammesh.hamiltonian(h)
    np.testing.assert_array_equal(again.triangles, h.triangles)
    np.testing.assert_array_equal(again.points, h.points)
    assert again.report["kept_input_cycle"]


def test_subpackages_reachable_after_plain_import():
    code = ("import hammesh; hammesh.io.unwritten_data; hammesh.fem.boundary_facets; "
            "hammesh.domain.write_poly; hammesh.surface.surface_hamiltonian; hammesh.meshing.quality_mesh; "
            "import types; assert isinstance(hammesh.verify, types.FunctionType); "
            "assert isinstance(hammesh.partition, types.FunctionType)")
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("kwargs, needle", [
    ({"triangle_attributes": np.array([[1.0], [2.0], [3.0]])}, "triangle_attributes"),
    ({"vertex_markers": np.array([5, 6, 7])}, "vertex_markers"),
    ({"segments": np.array([[0, 1]]), "segment_markers": np.array([4, 9])}, "segment_markers"),
])
def test_mesh_fields_of_another_length_are_refused(kwargs, needle):
    from hammesh.errors import InvalidMeshError

    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    with pytest.raises(InvalidMeshError, match=needle):
        hammesh.Mesh(pts, T, **kwargs)


def test_mesh_fields_absent_or_flat_are_taken():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
    m = hammesh.Mesh(pts, T, triangle_attributes=np.array([7.0, 8.0]), segments=np.array([[0, 1]]))
    assert m.triangle_attributes.tolist() == [[7.0], [8.0]]
    assert m.segment_markers.tolist() == [0] and m.vertex_markers.tolist() == [0, 0, 0, 0]


def test_triangle_files_with_a_byte_order_mark(tmp_path):
    poly = "4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n"
    (tmp_path / "b.poly").write_text("\ufeff" + poly, encoding="utf-8")
    dom = hammesh.read_domain(tmp_path / "b.poly")
    assert len(dom.vertices) == 4 and len(dom.segments) == 4
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.1))
    hammesh.write(h, tmp_path / "h.ele")
    for name in ("h.node", "h.ele"):
        text = (tmp_path / name).read_text(encoding="utf-8")
        (tmp_path / name).write_text("\ufeff" + text, encoding="utf-8")
    back = hammesh.read_mesh(tmp_path / "h.ele")
    np.testing.assert_array_equal(back.triangles, h.triangles)


@pytest.mark.parametrize("scale", [1e-70, 1e-150])
def test_domain_too_small_for_float64_is_refused_naming_its_extent(scale):
    from hammesh.errors import InvalidDomainError

    with pytest.raises(InvalidDomainError, match="spans only"):
        hammesh.Domain.from_polygon(np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) * scale)


def test_small_domain_above_the_limit_is_meshed():
    s = 1e-40
    dom = hammesh.Domain.from_polygon(np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) * s)
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=0.01 * s * s))
    assert h.report["verified"] and h.report["min_angle_output_deg"] >= 15


@pytest.mark.parametrize("scale", [1e-200, 1e-300])
def test_point_set_too_small_is_refused_not_called_collinear(scale):
    from hammesh.errors import InvalidDomainError
    from hammesh.pointset import hamiltonian_triangulation

    p = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0.4]])
    with pytest.raises(InvalidDomainError, match="span only"):
        hamiltonian_triangulation(p * scale)
    assert len(hamiltonian_triangulation(p * 1e-100)) == 4
