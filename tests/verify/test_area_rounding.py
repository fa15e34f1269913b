"""The certificate's area comparison allows what float64 rounding can explain and no
more (:func:`hammesh.verify.certificate.area_rounding_bound`): a valid mesh with one
vertex far out (float areas 2e-9 apart, exact areas equal) is verified."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.verify.certificate import area_rounding_bound

GRID = np.array([[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1], [0, 2], [1, 2], [2, 2]], float)
ROWS = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8], [4, 8, 7]])


def _exact_area(points: np.ndarray, rows: np.ndarray) -> Fraction:
    total = Fraction(0)
    for a, b, c in rows.tolist():
        (ax, ay), (bx, by), (cx, cy) = (map(Fraction, points[i]) for i in (a, b, c))
        total += ((bx - ax) * (cy - by) - (by - ay) * (cx - bx)) / 2
    return total


def _float_area(points: np.ndarray, rows: np.ndarray) -> float:
    """The certificate kernel's formula: (p1 - p0) x (p2 - p1) / 2, summed in row order."""
    total = 0.0
    for a, b, c in rows.tolist():
        ax, ay = points[b] - points[a]
        bx, by = points[c] - points[b]
        total += 0.5 * (ax * by - ay * bx)
    return total


@settings(max_examples=200, deadline=None)
@given(st.floats(1.0, 1e15), st.floats(-1e15, -1.0), st.integers(0, 8))
def test_the_bound_covers_the_float_error(far, y, corner):
    pts = GRID.copy()
    pts[[2, 6, 8][corner % 3]] = [far, y] if corner % 3 != 1 else [y, far]
    rows = ROWS
    e1, e2 = pts[rows[:, 1]] - pts[rows[:, 0]], pts[rows[:, 2]] - pts[rows[:, 1]]
    if np.any(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] <= 0):
        return  # (only meshes whose rows stay counter-clockwise)
    err = abs(Fraction(_float_area(pts, rows)) - _exact_area(pts, rows))
    assert err <= Fraction(area_rounding_bound(pts, rows))


@pytest.mark.parametrize("far, y", [(1e8, -1e8), (1e10, -1.0), (1e12, 0.5)])
@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_a_far_vertex_mesh_is_verified(far, y, mode):
    pts = GRID.copy()
    pts[2] = [far, y]
    h = hammesh.hamiltonian(hammesh.Mesh(pts, ROWS), mode=mode)
    assert h.report["verified"]
    assert _exact_area(h.points, h.triangles) == _exact_area(pts, ROWS)  # (truly the same domain)
