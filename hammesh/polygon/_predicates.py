"""Exact orientation predicate (numba kernel shared by the polygon algorithms).

:func:`orient` returns the exact sign of the determinant
``(b - a) x (c - a)`` for float64 inputs: a float evaluation with Shewchuk's static
error bound answers almost every call; the undecided ones (nearly or exactly collinear
points, e.g. every collinear triple of an integer grid polygon) are re-evaluated
exactly with floating-point expansions (Dekker's two-product, Shewchuk's
grow-expansion).  Exact as long as no intermediate product underflows (coordinates
whose differences are below about 1e-150 are not supported).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["orient", "orient_many"]

_EPS = 2.0 ** -53
_CCW_ERRBOUND = (3.0 + 16.0 * _EPS) * _EPS
_SPLITTER = 134217729.0  # 2**27 + 1


@numba.njit(cache=True, inline="always")
def _two_sum(a, b):
    x = a + b
    bv = x - a
    av = x - bv
    return x, (a - av) + (b - bv)


@numba.njit(cache=True, inline="always")
def _two_diff(a, b):
    x = a - b
    bv = a - x
    av = x + bv
    return x, (a - av) + (bv - b)


@numba.njit(cache=True, inline="always")
def _split(a):
    c = _SPLITTER * a
    big = c - a
    hi = c - big
    return hi, a - hi


@numba.njit(cache=True, inline="always")
def _two_product(a, b):
    x = a * b
    ahi, alo = _split(a)
    bhi, blo = _split(b)
    err = x - ahi * bhi
    err = err - alo * bhi
    err = err - ahi * blo
    return x, alo * blo - err


@numba.njit(cache=True)
def _orient_exact(ax, ay, bx, by, cx, cy):
    # det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax), every step exact
    terms = np.empty(16)
    p1, p0 = _two_diff(bx, ax)
    q1, q0 = _two_diff(cy, ay)
    r1, r0 = _two_diff(by, ay)
    s1, s0 = _two_diff(cx, ax)
    k = 0
    for u in (p1, p0):
        for v in (q1, q0):
            hi, lo = _two_product(u, v)
            terms[k] = hi
            terms[k + 1] = lo
            k += 2
    for u in (r1, r0):
        for v in (s1, s0):
            hi, lo = _two_product(u, v)
            terms[k] = -hi
            terms[k + 1] = -lo
            k += 2
    # grow-expansion: e stays non-overlapping with increasing magnitude
    e = np.zeros(16)
    m = 0
    for t in range(16):
        q = terms[t]
        for i in range(m):
            q, h = _two_sum(q, e[i])
            e[i] = h
        e[m] = q
        m += 1
    for i in range(m - 1, -1, -1):
        if e[i] > 0.0:
            return 1
        if e[i] < 0.0:
            return -1
    return 0


@numba.njit(cache=True)
def orient(ax, ay, bx, by, cx, cy):
    """Exact sign of the turn a -> b -> c: +1 counter-clockwise, -1 clockwise, 0 collinear."""
    left = (bx - ax) * (cy - ay)
    right = (by - ay) * (cx - ax)
    det = left - right
    bound = _CCW_ERRBOUND * (abs(left) + abs(right))
    if det > bound:
        return 1
    if -det > bound:
        return -1
    return _orient_exact(ax, ay, bx, by, cx, cy)


@numba.njit(cache=True)
def orient_many(a, b, c):
    """Vectorized :func:`orient` over rows of three ``(k, 2)`` arrays -> ``(k,) int8``."""
    k = a.shape[0]
    out = np.empty(k, np.int8)
    for i in range(k):
        out[i] = orient(a[i, 0], a[i, 1], b[i, 0], b[i, 1], c[i, 0], c[i, 1])
    return out
