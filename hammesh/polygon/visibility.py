"""Visibility graph of a simple polygon (the input of Thm 2.1 and Thm 4.4).

Vertices ``i`` and ``j`` *see each other* when the open segment ``ij`` lies in the
interior of the polygon: it may not touch the boundary, so a segment through a third
vertex (collinear vertices) or along an edge does not count, and polygon edges are not
visibility edges.  These are exactly the diagonals a triangulation may use.

Algorithm: triangulate the polygon once (Triangle, no Steiner points), then from every
vertex ``i`` walk the triangulation outwards while narrowing the wedge of directions
still visible from ``i`` (a funnel walk through the dual tree); the vertex opposite
the entry edge of each reached triangle is visible iff it lies strictly inside the
wedge.  Every triangle is entered at most once per source, so the walk costs ``O(n)``
per vertex and ``O(n^2)`` in all (parallel over sources), plus ``O(n^2)`` memory for
the dense matrix.  All orientation tests are exact (:mod:`hammesh.predicates`).  Measured:
2,000 vertices in well under a second (``benchmarks/bench_polygon.py``).
"""

from __future__ import annotations

import numba
import numpy as np

from hammesh.polygon._polygon import Polygon, as_polygon
from hammesh.predicates import orient
from hammesh.polygon._triangulate import triangle_neighbors, triangulate_polygon

__all__ = ["visibility_graph", "visibility_matrix"]


def visibility_graph(points) -> np.ndarray:
    """All pairs of vertices of a simple polygon that see each other through its interior.

    Parameters
    ----------
    points : (n, 2) array_like of float
        Simple polygon, clockwise or counter-clockwise.

    Returns
    -------
    (e, 2) int64
        Pairs ``i < j`` of input indices, sorted; polygon edges are excluded.

    Raises
    ------
    InvalidDomainError
        ``points`` is not a simple polygon (see :func:`~hammesh.polygon.validate_polygon`).

    Examples
    --------
    >>> visibility_graph([[0, 0], [1, 0], [1, 1], [0, 1]]).tolist()
    [[0, 2], [1, 3]]
    >>> visibility_graph([[0, 0], [2, 0], [1, 1], [2, 2], [0, 2]]).tolist()  # 0-3 passes through 2
    [[0, 2], [2, 4]]
    """
    poly = as_polygon(points)
    vis = visibility_matrix(poly)
    i, j = np.nonzero(np.triu(vis))
    pairs = np.sort(np.stack([poly.order[i], poly.order[j]], axis=1), axis=1)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def visibility_matrix(poly: Polygon) -> np.ndarray:
    """Dense symmetric ``(n, n) bool`` visibility matrix in the internal (CCW) order."""
    pts = np.ascontiguousarray(poly.points)
    n = poly.n
    tri = triangulate_polygon(pts)
    nb = triangle_neighbors(tri)
    # triangles around each vertex (CSR)
    flat = tri.reshape(-1)
    order = np.argsort(flat, kind="stable")
    start = np.searchsorted(flat[order], np.arange(n + 1))
    around = (order // 3).astype(np.int64)
    return _walk_all(pts, tri, nb, start, around)


@numba.njit(cache=True, parallel=True)
def _walk_all(pts, tri, nb, start, around):
    n = pts.shape[0]
    vis = np.zeros((n, n), np.bool_)
    for i in numba.prange(n):
        _walk(i, pts, tri, nb, start, around, vis)
    return vis


@numba.njit(cache=True, inline="always")
def _push_wedge(st, top, t, a, b, right, left):
    """Push "enter triangle ``t`` across edge ``(a, b)`` with the wedge from ray ``i right``
    counter-clockwise to ray ``i left``" onto the walk's stack; the new stack size."""
    st[top, 0] = t
    st[top, 1] = a
    st[top, 2] = b
    st[top, 3] = right
    st[top, 4] = left
    return top + 1


@numba.njit(cache=True)
def _walk(i, pts, tri, nb, start, around, vis):
    n = pts.shape[0]
    m = tri.shape[0]
    # stack of (triangle, a, b, R, L): entered across edge (a, b), wedge from ray iR
    # counter-clockwise to ray iL (open)
    st = np.empty((m + 3, 5), np.int64)
    top = 0
    xi, yi = pts[i, 0], pts[i, 1]
    for s in range(start[i], start[i + 1]):
        t = around[s]
        k = 0
        while tri[t, k] != i:
            k += 1
        a = tri[t, (k + 1) % 3]
        b = tri[t, (k + 2) % 3]
        for v in (a, b):
            d = (v - i) % n
            if d != 1 and d != n - 1:
                vis[i, v] = True
        u = nb[t, (k + 1) % 3]
        if u >= 0:
            top = _push_wedge(st, top, u, a, b, a, b)
    while top > 0:
        top -= 1
        u = st[top, 0]
        a = st[top, 1]
        b = st[top, 2]
        R = st[top, 3]
        L = st[top, 4]
        kb = 0
        while tri[u, kb] != b:
            kb += 1
        c = tri[u, (kb + 2) % 3]
        r = orient(xi, yi, pts[R, 0], pts[R, 1], pts[c, 0], pts[c, 1])
        l = orient(xi, yi, pts[L, 0], pts[L, 1], pts[c, 0], pts[c, 1])
        ua = nb[u, (kb + 1) % 3]  # across edge (a, c)
        ub = nb[u, (kb + 2) % 3]  # across edge (c, b)
        if r > 0 and l < 0:
            vis[i, c] = True
            if ua >= 0:
                top = _push_wedge(st, top, ua, a, c, R, c)
            if ub >= 0:
                top = _push_wedge(st, top, ub, c, b, c, L)
        elif r <= 0 and l < 0:
            if ub >= 0:
                top = _push_wedge(st, top, ub, c, b, R, L)
        elif r > 0 and l >= 0:
            if ua >= 0:
                top = _push_wedge(st, top, ua, a, c, R, L)
