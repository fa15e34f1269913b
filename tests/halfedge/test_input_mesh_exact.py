"""The input check decides a sliver's orientation exactly (a float cross product of 0
refused a valid counter-clockwise triangle that Triangle itself produced)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from hypothesis import given, settings, strategies as st

from hammesh.halfedge.input_mesh import prepare_mesh
from hammesh.mesh import Mesh
from hammesh.predicates import orient_points

SLIVER = np.array([[float.fromhex(x) for x in p] for p in [
    ["0x1.869dcfc14a600p-10", "0x1.f26962982761ap-1"], ["0x1.5b9c49f4ea533p-6", "0x1.7e6906b6bf8f5p-1"],
    ["0x1.dfc1a0994632fp-7", "0x1.a513d001e22acp-1"]]])


def _exact_sign(p, q, r) -> int:
    (ax, ay), (bx, by), (cx, cy) = [tuple(map(Fraction, v)) for v in (p, q, r)]
    d = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    return (d > 0) - (d < 0)


def test_a_sliver_whose_float_area_is_zero_is_accepted_and_kept_ccw():
    assert _exact_sign(*SLIVER) == 1
    a, b = SLIVER[1] - SLIVER[0], SLIVER[2] - SLIVER[0]
    assert a[0] * b[1] - a[1] * b[0] == 0.0  # what the float test saw
    for rows in ([[0, 1, 2]], [[0, 2, 1]]):
        mesh, _, _ = prepare_mesh(Mesh(SLIVER, np.array(rows)))
        assert _exact_sign(*mesh.points[mesh.triangles[0]]) == 1


@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.1, 10), st.integers(0, 2**32 - 1))
@settings(max_examples=80, deadline=None)
def test_nearly_collinear_triangles_are_oriented_by_the_exact_sign(x0, y0, length, seed):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=2)
    p = np.array([x0, y0])
    q = p + length * d
    r = p + rng.random() * length * d  # on the line up to rounding: either side, or on it
    r = r + rng.integers(-3, 4) * np.spacing(np.abs(r))
    pts = np.array([p, q, r])
    sign = _exact_sign(*pts)
    assert orient_points(pts, 0, 1, 2) == sign
    if sign == 0:
        return
    mesh, _, _ = prepare_mesh(Mesh(pts, np.array([[0, 1, 2]])))
    assert _exact_sign(*mesh.points[mesh.triangles[0]]) == 1
