"""Sparse mode keeps Triangle's finite-element accuracy (issue 13, item 5): P1 Poisson."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

import hammesh

pytest.importorskip("skfem")

_spec = importlib.util.spec_from_file_location(
    "poisson_skfem", Path(__file__).parent.parent.parent / "examples" / "poisson_skfem.py"
)
poisson = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(poisson)  # type: ignore[union-attr]


def test_p1_converges_on_triangle_mesh() -> None:
    # the error measure itself: halving h divides the L2 error by about 4
    coarse = hammesh.quality_mesh(poisson.domain(), min_angle=30, max_area=4e-3)
    fine = hammesh.quality_mesh(poisson.domain(), min_angle=30, max_area=1e-3)
    e_c = poisson.poisson_errors(coarse.points, coarse.triangles)
    e_f = poisson.poisson_errors(fine.points, fine.triangles)
    assert 3.0 < e_c[0] / e_f[0] < 5.0
    assert 1.6 < e_c[1] / e_f[1] < 2.4


def test_sparse_errors_within_3_percent_of_triangle() -> None:
    mesh = hammesh.quality_mesh(poisson.domain(), min_angle=30, max_area=5e-4)
    h = hammesh.hamiltonian(mesh, mode="sparse")
    e_tri = poisson.poisson_errors(mesh.points, mesh.triangles)
    e_ham = poisson.poisson_errors(h.points, h.triangles)
    assert e_ham[0] <= 1.03 * e_tri[0]  # L2, the bar
    assert e_ham[1] <= 1.03 * e_tri[1]  # H1
