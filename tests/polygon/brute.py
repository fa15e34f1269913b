"""Independent brute-force references for the polygon tests (exact rationals, no numba).

Nothing here calls :mod:`hammesh.polygon`, so a bug there cannot hide itself.
"""

from __future__ import annotations

import itertools
from fractions import Fraction
from functools import lru_cache

import numpy as np


def orient(a, b, c) -> int:
    d = ((Fraction(b[0]) - Fraction(a[0])) * (Fraction(c[1]) - Fraction(a[1]))
         - (Fraction(b[1]) - Fraction(a[1])) * (Fraction(c[0]) - Fraction(a[0])))
    return int(d > 0) - int(d < 0)


def _on_segment(p, a, b) -> bool:
    return (orient(a, b, p) == 0
            and min(a[0], b[0]) <= p[0] <= max(a[0], b[0])
            and min(a[1], b[1]) <= p[1] <= max(a[1], b[1]))


def segments_intersect(a, b, c, d) -> bool:
    """Closed segments ab and cd share a point."""
    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return (_on_segment(c, a, b) or _on_segment(d, a, b)
            or _on_segment(a, c, d) or _on_segment(b, c, d))


def is_simple(pts) -> bool:
    n = len(pts)
    if len({tuple(p) for p in pts}) < n:
        return False
    for i in range(n):
        for j in range(i + 1, n):
            a, b = pts[i], pts[(i + 1) % n]
            c, d = pts[j], pts[(j + 1) % n]
            if j == i + 1 or (i == 0 and j == n - 1):
                # adjacent: only the shared vertex in common (no fold-back)
                shared = b if j == i + 1 else a
                other1 = a if j == i + 1 else b
                other2 = d if j == i + 1 else c
                if orient(other1, shared, other2) == 0 and (
                        _on_segment(other2, other1, shared) or _on_segment(other1, shared, other2)):
                    return False
                continue
            if segments_intersect(a, b, c, d):
                return False
    return signed_area2(pts) != 0


def signed_area2(pts) -> Fraction:
    n = len(pts)
    return sum(Fraction(pts[i][0]) * Fraction(pts[(i + 1) % n][1])
               - Fraction(pts[(i + 1) % n][0]) * Fraction(pts[i][1]) for i in range(n))


def ccw(pts):
    """(ccw points as list of tuples, index map to the input)."""
    idx = list(range(len(pts)))
    if signed_area2(pts) < 0:
        idx = idx[::-1]
    return [tuple(pts[i]) for i in idx], idx


def is_diagonal(pts, i, j) -> bool:
    """O'Rourke's Diagonal on a CCW polygon: open segment ij strictly inside."""
    n = len(pts)
    if (j - i) % n in (0, 1, n - 1):
        return False

    def in_cone(a, b):
        a0, a1 = pts[(a - 1) % n], pts[(a + 1) % n]
        pa, pb = pts[a], pts[b]
        if orient(pa, a1, a0) >= 0:  # convex or straight
            return orient(pa, pb, a0) > 0 and orient(pb, pa, a1) > 0
        return not (orient(pa, pb, a1) >= 0 and orient(pb, pa, a0) >= 0)

    if not (in_cone(i, j) and in_cone(j, i)):
        return False
    for k in range(n):
        k1 = (k + 1) % n
        if k in (i, j) or k1 in (i, j):
            continue
        if segments_intersect(pts[i], pts[j], pts[k], pts[k1]):
            return False
    return True


def visibility_pairs(pts) -> set:
    n = len(pts)
    P, idx = ccw(pts)
    out = set()
    for a in range(n):
        for b in range(a + 1, n):
            if is_diagonal(P, a, b):
                out.add(tuple(sorted((idx[a], idx[b]))))
    return out


def all_triangulations(pts):
    """Every triangulation of the polygon as a list of (sorted ccw-index) triangles."""
    P, idx = ccw(pts)
    n = len(P)
    ok = {(a, b): (b - a) % n in (1, n - 1) or is_diagonal(P, a, b)
          for a in range(n) for b in range(n) if a != b}

    @lru_cache(maxsize=None)
    def sub(i, j):  # triangulations of chain i..j (ccw) closed by (i, j)
        if (j - i) % n < 2:
            return [()]
        res = []
        k = (i + 1) % n
        while k != j:
            if ok[(i, k)] and ok[(k, j)]:
                for left in sub(i, k):
                    for right in sub(k, j):
                        res.append(left + right + ((i, k, j),))
            k = (k + 1) % n
        return res

    return [[tuple(idx[v] for v in t) for t in tr] for tr in sub(0, n - 1)]


def dual_edges(tris):
    edges = []
    for a, b in itertools.combinations(range(len(tris)), 2):
        if len(set(tris[a]) & set(tris[b])) == 2:
            edges.append((a, b))
    return edges


def is_hamiltonian(tris) -> bool:
    deg = [0] * len(tris)
    for a, b in dual_edges(tris):
        deg[a] += 1
        deg[b] += 1
    return len(tris) == 1 or sum(d == 1 for d in deg) == 2 and max(deg) <= 2


def path_orders(tris):
    """Both orders of the dual path of a Hamiltonian triangulation."""
    adj = {t: [] for t in range(len(tris))}
    for a, b in dual_edges(tris):
        adj[a].append(b)
        adj[b].append(a)
    ends = [t for t in adj if len(adj[t]) <= 1]
    orders = []
    for s in ends[:2]:
        seq, prev = [s], None
        while True:
            nxt = [u for u in adj[seq[-1]] if u != prev]
            if not nxt:
                break
            prev = seq[-1]
            seq.append(nxt[0])
        orders.append([tris[t] for t in seq])
    return orders


def is_sequential_order(tris) -> bool:
    """No three consecutive crossed edges share a vertex."""
    crossed = [frozenset(tris[k]) & frozenset(tris[k + 1]) for k in range(len(tris) - 1)]
    for k in range(len(crossed) - 2):
        if crossed[k] & crossed[k + 1] & crossed[k + 2]:
            return False
    return True


def is_sequential(tris) -> bool:
    if not is_hamiltonian(tris):
        return False
    return any(is_sequential_order(o) for o in path_orders(tris))


def random_simple_polygon(rng, n, grid=20, tries=200):
    """A random simple polygon on an integer grid (2-opt untangling), or None."""
    for _ in range(tries):
        pts = [tuple(int(v) for v in p) for p in rng.integers(0, grid + 1, size=(n, 2))]
        if len(set(pts)) < n:
            continue
        pts = untangle(pts)
        if pts is not None and is_simple(pts):
            return pts
    return None


def untangle(pts, max_steps=500):
    pts = list(pts)
    n = len(pts)
    for _ in range(max_steps):
        changed = False
        for i in range(n):
            for j in range(i + 2, n):
                if i == 0 and j == n - 1:
                    continue
                a, b, c, d = pts[i], pts[i + 1], pts[j], pts[(j + 1) % n]
                if segments_intersect(a, b, c, d):
                    pts[i + 1:j + 1] = pts[i + 1:j + 1][::-1]
                    changed = True
        if not changed:
            return pts
    return None


def min_path_partition_size(m, edges) -> int:
    """Minimum number of vertex-disjoint paths covering a forest with m nodes."""
    best = m
    for r in range(len(edges), 0, -1):
        if m - r >= best:
            break
        for sub in itertools.combinations(edges, r):
            deg = np.zeros(m, int)
            for a, b in sub:
                deg[a] += 1
                deg[b] += 1
            if deg.max() <= 2:
                best = min(best, m - r)
                break
    return best


def min_convex_pieces(pts) -> int:
    """Fewest convex pieces (straight angles allowed) cut by non-crossing diagonals.

    Tries every set of diagonals by increasing size, splitting the polygon along them
    one at a time and checking each piece's angles; for small polygons only.
    """
    P, _ = ccw(pts)
    n = len(P)
    diags = sorted(visibility_pairs(P))

    def crossing(d, e):
        if set(d) & set(e):
            return False
        return segments_intersect(P[d[0]], P[d[1]], P[e[0]], P[e[1]])

    def convex(piece):
        L = len(piece)
        return all(orient(P[piece[s - 1]], P[piece[s]], P[piece[(s + 1) % L]]) >= 0
                   for s in range(L))

    for size in range(len(diags) + 1):
        for chosen in itertools.combinations(diags, size):
            if any(crossing(d, e) for d, e in itertools.combinations(chosen, 2)):
                continue
            pieces = [list(range(n))]
            for i, j in chosen:
                f = next(f for f in pieces if i in f and j in f)
                a, b = f.index(i), f.index(j)
                if a > b:
                    a, b = b, a
                pieces.remove(f)
                pieces += [f[a:b + 1], f[b:] + f[:a + 1]]
            if all(convex(f) for f in pieces):
                return size + 1
    raise AssertionError("unreachable: a triangulation is convex")  # pragma: no cover
