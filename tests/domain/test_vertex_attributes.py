"""Triangle's vertex attributes: read from .node/.poly, kept through repairs,
interpolated by Triangle at the points it inserts, carried to the Hamiltonian mesh."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import hammesh
from hammesh.domain import Domain, read_domain
from hammesh.errors import InvalidDomainError
from tests.helpers import star_pslg

CROSSING_POLY = """# square with two internal segments that cross; attribute = 2x + 3y
6 2 1 1
0 0 0 0 1
1 2 0 4 1
2 2 2 10 1
3 0 2 6 1
4 0.5 0.5 2.5 0
5 1.5 1.5 7.5 0
6 1
0 0 1 1
1 1 2 1
2 2 3 1
3 3 0 1
4 4 5 0
5 1 3 0
0
"""


def field(points: np.ndarray) -> np.ndarray:
    return 2 * points[:, 0] + 3 * points[:, 1]


def test_poly_attributes_are_read_and_kept_through_a_crossing_repair(tmp_path):
    (tmp_path / "c.poly").write_text(CROSSING_POLY)
    d = read_domain(tmp_path / "c.poly")
    assert [r.kind for r in d.repairs] == ["crossing"]
    assert d.vertex_attributes.shape == (len(d.vertices), 1)
    np.testing.assert_allclose(d.vertex_attributes[:, 0], field(d.vertices))  # the crossing: interpolated


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), a=st.floats(-3, 3), mode=st.sampled_from(["sparse", "incircle"]))
def test_linear_vertex_attributes_survive_meshing_and_hamiltonian(dom, a, mode):
    values = np.column_stack([a * dom.vertices[:, 0] - dom.vertices[:, 1], np.ones(len(dom.vertices))])
    d = Domain(dom.vertices, dom.segments, dom.holes, vertex_attributes=values)
    m = hammesh.quality_mesh(d, min_angle=25, max_area=0.02)
    assert sorted(m.point_data) == ["attribute_0", "attribute_1"]
    np.testing.assert_allclose(m.point_data["attribute_0"], a * m.points[:, 0] - m.points[:, 1], atol=1e-12)
    h = hammesh.hamiltonian(m, mode=mode)
    np.testing.assert_allclose(h.point_data["attribute_0"], a * h.points[:, 0] - h.points[:, 1], atol=1e-12)
    np.testing.assert_allclose(h.point_data["attribute_1"], 1.0)


def test_cli_writes_vertex_attributes(tmp_path):
    (tmp_path / "c.poly").write_text(CROSSING_POLY)
    out = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(tmp_path / "c.poly"), "-q", "30",
                          "-a", "0.02", "-o", str(tmp_path / "c.vtu")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    o = meshio.read(tmp_path / "c.vtu")
    np.testing.assert_allclose(o.point_data["attribute_0"], field(o.points), atol=1e-12)


def test_meshpy_backend_reports_what_it_cannot_carry():
    pytest.importorskip("meshpy")
    d = Domain([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1], [1, 2], [2, 3], [3, 0]],
               vertex_attributes=[[1.0], [2.0], [3.0], [4.0]])
    m = hammesh.quality_mesh(d, min_angle=30, max_area=0.05, backend="meshpy")
    assert not m.point_data
    assert "meshpy" in m.info["not_carried"][0]


def test_bad_vertex_attribute_shape_is_refused():
    with pytest.raises(InvalidDomainError, match="vertex_attributes"):
        Domain([[0, 0], [1, 0], [0, 1]], vertex_attributes=np.zeros((2, 1)))
