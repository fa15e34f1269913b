"""Exact orientation predicate (numba), shared by the polygon and point-set algorithms.

``orient(ax, ay, bx, by, cx, cy)`` returns the sign (-1, 0, +1) of the determinant
``| b - a, c - a |``: +1 when ``a, b, c`` turn counter-clockwise.  A floating-point
filter (Shewchuk's ``ccwerrboundA``) decides almost every call; the uncertain ones
are decided exactly: the determinant is expanded into six products of input
coordinates, each split into two doubles (Dekker's TwoProduct), and the twelve
terms are summed into a non-overlapping expansion (Shewchuk's Grow-Expansion) whose
last non-zero component has the sign of the sum.  Exact for all finite inputs whose
products neither overflow nor underflow (|coordinates| within about 1e-150..1e150).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["orient", "orient_points", "orient_many", "orient_rows", "ERRBOUND"]

_SPLITTER = 134217729.0  # 2**27 + 1
#: Shewchuk's ``ccwerrboundA``: a 2x2 orientation determinant ``left - right`` computed in
#: floating point has the right sign when its magnitude exceeds ``ERRBOUND * (|left| + |right|)``.
ERRBOUND = 3.3306690738754716e-16  # (3 + 16 eps) eps


@njit(cache=True, inline="always")
def _two_product(a, b):
    x = a * b
    c = _SPLITTER * a
    ahi = c - (c - a)
    alo = a - ahi
    c = _SPLITTER * b
    bhi = c - (c - b)
    blo = b - bhi
    err = x - ahi * bhi
    err -= alo * bhi
    err -= ahi * blo
    return x, alo * blo - err


@njit(cache=True)
def _exact_sign(ax, ay, bx, by, cx, cy):
    terms = np.empty(12, np.float64)
    # det = ax*by - ay*bx + bx*cy - by*cx + cx*ay - cy*ax
    terms[0], terms[1] = _two_product(ax, by)
    terms[2], terms[3] = _two_product(-ay, bx)
    terms[4], terms[5] = _two_product(bx, cy)
    terms[6], terms[7] = _two_product(-by, cx)
    terms[8], terms[9] = _two_product(cx, ay)
    terms[10], terms[11] = _two_product(-cy, ax)
    e = np.zeros(13, np.float64)
    n = 0
    for i in range(12):
        q = terms[i]
        for j in range(n):
            x = q + e[j]
            bv = x - q
            av = x - bv
            e[j] = (q - av) + (e[j] - bv)
            q = x
        e[n] = q
        n += 1
    for j in range(n - 1, -1, -1):
        if e[j] > 0.0:
            return 1
        if e[j] < 0.0:
            return -1
    return 0


@njit(cache=True)
def orient(ax, ay, bx, by, cx, cy):
    """Sign of the orientation of ``(a, b, c)``: +1 CCW, -1 CW, 0 collinear (exact)."""
    detleft = (ax - cx) * (by - cy)
    detright = (ay - cy) * (bx - cx)
    det = detleft - detright
    bound = ERRBOUND * (abs(detleft) + abs(detright))
    if det > bound:
        return 1
    if -det > bound:
        return -1
    if detleft == 0.0 and detright == 0.0:
        return 0
    return _exact_sign(ax, ay, bx, by, cx, cy)


@njit(cache=True)
def orient_points(pts, a, b, c):
    """:func:`orient` of the points with indices ``a, b, c`` of ``pts (n, 2)``."""
    return orient(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1])


@njit(cache=True)
def orient_many(pts, tri):
    """Orientation sign of every row of ``tri (m, 3)`` (int8 array)."""
    m = tri.shape[0]
    out = np.empty(m, np.int8)
    for t in range(m):
        out[t] = orient_points(pts, tri[t, 0], tri[t, 1], tri[t, 2])
    return out


@njit(cache=True)
def orient_rows(a, b, c):
    """:func:`orient` over rows of three ``(k, 2)`` point arrays -> ``(k,) int8``."""
    k = a.shape[0]
    out = np.empty(k, np.int8)
    for i in range(k):
        out[i] = orient(a[i, 0], a[i, 1], b[i, 0], b[i, 1], c[i, 0], c[i, 1])
    return out
