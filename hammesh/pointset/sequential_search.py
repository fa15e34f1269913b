"""Exact search for sequential triangulations of small point sets (paper §4).

A triangulation is *sequential* when its dual has a Hamiltonian path whose turns
alternate: it is one triangle strip ``v1 v2 ... v_{m+2}`` whose triangle ``i`` is
``(v_i, v_{i+1}, v_{i+2})`` (a vertex may occur several times).  The search grows such
strips triangle by triangle:

* the candidates are the *empty* triangles (no other point inside or on an edge);
  two of them may both be used only if their interiors are disjoint (no two edges
  cross properly); both from a table of every triple's exact orientation, computed
  once with numpy;
* the next triangle of the strip is a compatible empty triangle on the exit edge
  ``(v_{i+1}, v_{i+2})``; it adds ``v_{i+3}``;
* ``m = 2 n - h - 2`` pairwise-disjoint empty triangles are a complete triangulation
  (every partial triangulation extends to one with exactly ``m`` triangles), so the
  search stops there;
* pruning: a hull edge not yet covered must keep a compatible triangle, and failed
  states ``(triangles used, exit edge)`` are remembered.

Every strip found is re-checked with :func:`hammesh.strips.sequential_order` (Thm 4.3).
The search is exponential; :data:`SEARCH_LIMIT` points is the documented maximum.
The worst case measured is a set with no strip (the search is exhaustive): the
Thm 4.1 family takes about 0.1 s at n = 9 and 1-1.7 s at n = 12; random 12-point
sets 0.02-0.15 s.  :func:`strip_search` is also the core solver of Lemma 4.2.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from itertools import combinations, permutations

import numpy as np

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.predicates import orient_many, orient_rows
from hammesh.pointset.validate import as_points, convex_hull
from hammesh.pointset.verify import verify_point_triangulation

__all__ = [
    "search_sequential",
    "strip_search",
    "strip_triangles",
    "SEARCH_LIMIT",
    "check_sequential",
]

#: Largest point set :func:`search_sequential` accepts.
SEARCH_LIMIT = 12


def _orient_table(pts: np.ndarray) -> np.ndarray:
    """``O[a, b, c]``: exact orientation sign of every triple of ``pts (k, 2)``."""
    k = len(pts)
    a, b, c = (g.ravel() for g in np.meshgrid(np.arange(k), np.arange(k), np.arange(k), indexing="ij"))
    return orient_rows(pts[a], pts[b], pts[c]).astype(np.int64).reshape(k, k, k)


def _empty_triangles(O: np.ndarray) -> np.ndarray:
    """``(T, 3)`` counter-clockwise triangles with no other point inside or on an edge."""
    k = O.shape[0]
    tri = np.array(list(combinations(range(k), 3)), dtype=np.int64).reshape(-1, 3)
    s = O[tri[:, 0], tri[:, 1], tri[:, 2]]
    tri = tri[s != 0]
    cw = s[s != 0] < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]
    a, b, c = tri.T
    inside = (O[a, b, :] >= 0) & (O[b, c, :] >= 0) & (O[c, a, :] >= 0)
    rows = np.arange(len(tri))
    for v in (a, b, c):
        inside[rows, v] = False
    return tri[~inside.any(axis=1)]


def _compatible(O: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """``(T, T)`` bool: the two triangles' interiors are disjoint (no edges cross properly)."""
    # C[p, q, r, s]: segment pq crosses segment rs at a point interior to both
    pq_r = O[:, :, :, None]
    pq_s = O[:, :, None, :]
    rs_p = O.transpose(2, 0, 1)[:, None, :, :]  # O[r, s, p] at [p, q, r, s]
    rs_q = O.transpose(2, 0, 1)[None, :, :, :]
    C = (pq_r * pq_s < 0) & (rs_p * rs_q < 0)
    E = np.stack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]], axis=1)  # (T, 3, 2)
    X = C[
        E[:, None, :, None, 0], E[:, None, :, None, 1], E[None, :, None, :, 0], E[None, :, None, :, 1]
    ].any(axis=(2, 3))
    np.fill_diagonal(X, True)
    return ~X


def check_sequential(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Triangles in the order of their alternating strip, certified by Thm 4.3.

    Raises
    ------
    VerificationError
        ``triangles`` is no triangulation of ``points`` or not sequential.
    """
    from hammesh.halfedge import half_edge_twins
    from hammesh.strips import sequential_order
    from hammesh.strips.dual import DualMesh

    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    verify_point_triangulation(pts, tri, None)
    # the exact checks above replace dual_mesh's floating-point area test, which would
    # reject nearly-flat (but positive) triangles of nearly-collinear points
    twin, _ = half_edge_twins(tri, len(pts))
    seq = sequential_order(DualMesh(points=pts, triangles=tri, twin=twin))
    if seq is None:
        raise VerificationError("the triangulation is not sequential (Thm 4.3 test)")
    out = tri[seq.order]
    verify_point_triangulation(pts, out, "path")
    return out


def strip_search(
    pts: np.ndarray,
    idx: Sequence[int] | None = None,
    start_ok: Callable[[int, int], bool] | None = None,
    end_ok: Callable[[int, int], bool] | None = None,
) -> list[int] | None:
    """Vertex sequence of an alternating strip triangulating ``pts[idx]``, or ``None``.

    The exhaustive search of :func:`search_sequential` on the points ``idx`` (all by
    default) of ``pts``, which must be distinct and not all collinear; the result
    ``v1 .. v_{m+2}`` (global indices) has ``m = 2 k - h - 2`` triangles
    ``(v_i, v_{i+1}, v_{i+2})`` (possibly clockwise) tiling the hull of ``pts[idx]``.
    ``start_ok(v1, v2)`` and ``end_ok(v_{m+1}, v_{m+2})``, when given, must hold
    (Lemma 4.2 uses them to attach the rest of the set to the strip's two ends).
    Nothing is verified here.
    """
    ids = list(range(len(pts))) if idx is None else [int(i) for i in idx]
    sub = np.ascontiguousarray(pts[ids])
    k = len(ids)
    hull = convex_hull(sub)
    m = 2 * k - hull.h - 2
    O = _orient_table(sub)
    tri_arr = _empty_triangles(O)
    tris = [tuple(int(v) for v in t) for t in tri_arr]
    ok = _compatible(O, tri_arr)
    compat = [sum(1 << int(j) for j in np.flatnonzero(row)) for row in ok]
    on_edge: dict[tuple[int, int], int] = {}
    for i, (a, b, c) in enumerate(tris):
        for u, v in ((a, b), (b, c), (c, a)):
            key = (min(u, v), max(u, v))
            on_edge[key] = on_edge.get(key, 0) | (1 << i)
    hb = hull.boundary.tolist()
    hull_masks = [on_edge.get((min(u, v), max(u, v)), 0) for u, v in zip(hb, hb[1:] + hb[:1])]
    failed: set[tuple[int, int, int]] = set()
    strip: list[int] = []

    def dfs(used: int, allowed: int, x: int, y: int, count: int) -> bool:
        if count == m:
            return end_ok is None or end_ok(ids[x], ids[y])
        key = (used, x, y)
        if key in failed:
            return False
        for hm in hull_masks:
            if not (hm & used) and not (hm & allowed):
                failed.add(key)
                return False
        cand = on_edge.get((min(x, y), max(x, y)), 0) & allowed & ~used
        while cand:
            low = cand & -cand
            j = low.bit_length() - 1
            cand ^= low
            z = next(v for v in tris[j] if v != x and v != y)
            strip.append(z)
            if dfs(used | low, allowed & compat[j], y, z, count + 1):
                return True
            strip.pop()
        failed.add(key)
        return False

    for i, s in enumerate(tris):
        for v1, v2, v3 in permutations(s):
            if start_ok is not None and not start_ok(ids[v1], ids[v2]):
                continue
            strip[:] = [v1, v2, v3]
            if dfs(1 << i, compat[i], v2, v3, 1):
                return [ids[v] for v in strip]
    return None


def strip_triangles(pts: np.ndarray, strip: Sequence[int]) -> np.ndarray:
    """Rows ``(v_i, v_{i+1}, v_{i+2})`` of a strip, each made counter-clockwise."""
    s = np.asarray(strip, dtype=np.int64)
    out = np.stack([s[:-2], s[1:-1], s[2:]], axis=1)
    neg = orient_many(pts, out) < 0
    out[neg] = out[neg][:, ::-1]
    return out


def search_sequential(points: np.ndarray) -> np.ndarray | None:
    """A sequential triangulation of a small point set, or ``None`` if it has none.

    Parameters
    ----------
    points : (n, 2) float64
        Distinct points, not all collinear, ``n <= SEARCH_LIMIT``.

    Returns
    -------
    (2 n - h - 2, 3) int64 or None
        Counter-clockwise triangles in strip order (consecutive rows share an edge,
        turns alternate), verified; ``None`` when the exhaustive search finds none.

    Raises
    ------
    InvalidOptionError
        More than :data:`SEARCH_LIMIT` points.
    """
    pts = as_points(points)
    n = len(pts)
    if n > SEARCH_LIMIT:
        raise InvalidOptionError(
            f"exact sequential search is limited to {SEARCH_LIMIT} points, got {n}"
        )
    strip = strip_search(pts)
    if strip is None:
        return None
    return check_sequential(pts, strip_triangles(pts, strip))
