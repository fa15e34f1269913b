"""Exact search for sequential triangulations of small point sets (paper §4).

A triangulation is *sequential* when its dual has a Hamiltonian path whose turns
alternate: it is one triangle strip ``v1 v2 ... v_{m+2}`` whose triangle ``i`` is
``(v_i, v_{i+1}, v_{i+2})`` (a vertex may occur several times).  The search grows such
strips triangle by triangle:

* the candidates are the *empty* triangles (no other point inside or on an edge);
  two of them may both be used only if their interiors are disjoint (no two edges
  cross properly), a table computed once with exact predicates;
* the next triangle of the strip is a compatible empty triangle on the exit edge
  ``(v_{i+1}, v_{i+2})``; it adds ``v_{i+3}``;
* ``m = 2 n - h - 2`` pairwise-disjoint empty triangles are a complete triangulation
  (every partial triangulation extends to one with exactly ``m`` triangles), so the
  search stops there;
* pruning: a hull edge not yet covered must keep a compatible triangle, and failed
  states ``(triangles used, exit edge)`` are remembered.

Every strip found is re-checked with :func:`hammesh.strips.sequential_order` (Thm 4.3).
The search is exponential; :data:`SEARCH_LIMIT` points is the documented maximum
(n = 9, the size of the Thm 4.1 example, takes well under a second).
"""

from __future__ import annotations

from itertools import combinations, permutations

import numpy as np

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.mesh import Mesh
from hammesh.predicates import orient
from hammesh.pointset.validate import as_points, convex_hull
from hammesh.pointset.verify import verify_point_triangulation

__all__ = ["sequential_triangulation", "search_sequential", "SEARCH_LIMIT", "check_sequential"]

#: Largest point set :func:`search_sequential` accepts.
SEARCH_LIMIT = 12


def _o(pts: np.ndarray, a: int, b: int, c: int) -> int:
    return int(orient(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1]))


def _empty_triangles(pts: np.ndarray) -> list[tuple[int, int, int]]:
    n = len(pts)
    out = []
    for a, b, c in combinations(range(n), 3):
        s = _o(pts, a, b, c)
        if s == 0:
            continue
        if s < 0:
            b, c = c, b
        if all(
            not (_o(pts, a, b, q) >= 0 and _o(pts, b, c, q) >= 0 and _o(pts, c, a, q) >= 0)
            for q in range(n)
            if q not in (a, b, c)
        ):
            out.append((a, b, c))
    return out


def _cross(pts: np.ndarray, p1: int, p2: int, q1: int, q2: int) -> bool:
    if len({p1, p2, q1, q2}) < 4:
        return False
    return (
        _o(pts, p1, p2, q1) * _o(pts, p1, p2, q2) < 0
        and _o(pts, q1, q2, p1) * _o(pts, q1, q2, p2) < 0
    )


def check_sequential(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Triangles in the order of their alternating strip, certified by Thm 4.3.

    Raises
    ------
    VerificationError
        ``triangles`` is no triangulation of ``points`` or not sequential.
    """
    from hammesh.strips import sequential_order

    tri = np.asarray(triangles, dtype=np.int64)
    verify_point_triangulation(points, tri, None)
    seq = sequential_order(Mesh(points=np.asarray(points, dtype=np.float64), triangles=tri))
    if seq is None:
        raise VerificationError("the triangulation is not sequential (Thm 4.3 test)")
    out = tri[seq.order]
    verify_point_triangulation(points, out, "path")
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
    hull = convex_hull(pts)
    m = 2 * n - hull.h - 2
    tris = _empty_triangles(pts)
    T = len(tris)
    compat = [0] * T
    for i, s in enumerate(tris):
        ei = [(s[0], s[1]), (s[1], s[2]), (s[2], s[0])]
        mask = 0
        for j, r in enumerate(tris):
            if i == j:
                continue
            ej = [(r[0], r[1]), (r[1], r[2]), (r[2], r[0])]
            if not any(_cross(pts, a, b, c, d) for a, b in ei for c, d in ej):
                mask |= 1 << j
        compat[i] = mask
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
            return True
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
            strip[:] = [v1, v2, v3]
            if dfs(1 << i, compat[i], v2, v3, 1):
                rows = [strip[k : k + 3] for k in range(len(strip) - 2)]
                out = np.array(rows, dtype=np.int64)
                neg = np.array([_o(pts, *r) < 0 for r in rows])
                out[neg] = out[neg][:, ::-1]
                return check_sequential(pts, out)
    return None


def sequential_triangulation(points: np.ndarray) -> np.ndarray | None:
    """A sequential triangulation (one alternating strip) of ``points``, or ``None``.

    Uses Lemma 4.2's construction for sets in convex position, the exact search
    (:func:`search_sequential`) for sets of at most :data:`SEARCH_LIMIT` points.

    Returns
    -------
    (2 n - h - 2, 3) int64 or None
        Counter-clockwise triangles in strip order, certified by Thm 4.3; ``None`` when
        the exact search proves there is none.

    Raises
    ------
    InvalidOptionError
        The set is too large to decide: more than :data:`SEARCH_LIMIT` points and
        not in convex position (the message says which).
    InvalidDomainError
        Invalid points (see :func:`hammesh.pointset.validate.as_points`).
    """
    from hammesh.pointset.lemma42_sequential import convex_sequential

    pts = as_points(points)
    n = len(pts)
    hull = convex_hull(pts)
    if hull.h == n:
        try:
            return convex_sequential(pts)
        except InvalidOptionError:
            if n > SEARCH_LIMIT:
                raise
    if n <= SEARCH_LIMIT:
        return search_sequential(pts)
    inner = n - hull.h
    why = (
        "Lemma 4.2 guarantees one, but only its convex case is implemented"
        if inner <= 2
        else "no construction is known and the exact search is exponential"
    )
    raise InvalidOptionError(
        f"cannot decide whether these {n} points ({inner} interior) have a sequential "
        f"triangulation: {why}; the exact search handles up to {SEARCH_LIMIT} points"
    )
