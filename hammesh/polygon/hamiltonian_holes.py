"""Hamiltonian triangulations of small polygons with holes, exactly (Arkin et al., Thm 2.2).

With holes, deciding whether some triangulation (no Steiner points) has a Hamiltonian
dual is NP-complete (Theorem 2.2), so this is an exponential exact search, limited to
:data:`MAX_VERTICES` vertices in all; past it, or to always get an answer, use
:func:`~hammesh.polygon.steiner_hamiltonian` with ``holes=`` (Thm 2.3, Steiner points).

Search: the candidate triangles are the *empty* triangles (no vertex inside or on them
besides their corners) whose sides are boundary edges or diagonals (open segments in the
interior: crossing no edge, through no vertex, midpoint inside).  Two of them overlap
iff two sides cross properly or they share a side and lie on the same side of it.
A depth-first search grows the dual path one triangle at a time: the next triangle
shares a side with the last and overlaps no placed one.  Any ``N + 2h - 2`` pairwise
non-overlapping empty triangles form a triangulation (a partial triangulation can be
completed, and every triangulation has that many triangles).  Pruning: every boundary
edge not yet covered must still have a compatible triangle on it.  Bit masks (Python
integers) hold the sets.
"""

from __future__ import annotations

import itertools

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.polygon._holes import point_in_ring, as_domain
from hammesh.polygon.verify import verify_polygon_triangulation
from hammesh.predicates import orient

__all__ = ["hamiltonian_triangulation_holes", "MAX_VERTICES"]

#: Largest number of vertices (outer ring plus holes) for the exact search.
MAX_VERTICES = 16

KINDS = ("path", "cycle")


def hamiltonian_triangulation_holes(points, holes, kind: str = "path") -> np.ndarray | None:
    """A triangulation of a polygon with holes whose dual has a Hamiltonian path/cycle.

    Parameters
    ----------
    points : (n, 2) array_like of float
        The outer ring, either orientation.
    holes : sequence of (n_i, 2) array_like of float
        Hole rings, either orientation (may be empty).
    kind : {"path", "cycle"}
        Hamiltonian path of the dual, or cycle (the last row also shares an edge with
        the first).

    Returns
    -------
    (N + 2h - 2, 3) int64 or None
        Counter-clockwise triangles in dual-path order, indexing the outer ring's points
        followed by each hole's points; ``None`` if no such triangulation exists.

    Raises
    ------
    InvalidDomainError
        Invalid rings (see :func:`~hammesh.polygon.steiner_hamiltonian`).
    InvalidOptionError
        More than :data:`MAX_VERTICES` vertices in all, or an unknown ``kind``.

    Examples
    --------
    >>> square = [[0, 0], [6, 0], [6, 6], [0, 6]]
    >>> T = hamiltonian_triangulation_holes(square, [[[2, 2], [4, 2], [3, 4]]])
    >>> T.shape
    (7, 3)
    """
    if kind not in KINDS:
        raise InvalidOptionError(f"kind must be one of {', '.join(map(repr, KINDS))}, got {kind!r}")
    dom = as_domain(points, holes)
    N = dom.n
    if N > MAX_VERTICES:
        raise InvalidOptionError(
            f"the exact search for a Hamiltonian triangulation of a polygon with holes (NP-complete, "
            f"Thm 2.2) is limited to {MAX_VERTICES} vertices, got {N}; use "
            f"polygon.steiner_hamiltonian(points, kind, holes=holes) (Thm 2.3, Steiner points)")
    tri = _search(dom, kind)
    if tri is None:
        return None
    T = dom.order[tri]
    rings = [np.asarray(points, dtype=np.float64)] + [np.asarray(h, dtype=np.float64) for h in holes]
    verify_polygon_triangulation(rings, np.concatenate(rings), T, kind)
    return T


def _segments_cross(P, a, b, c, d) -> bool:
    if len({a, b, c, d}) < 4:
        return False
    o = lambda p, q, r: orient(P[p, 0], P[p, 1], P[q, 0], P[q, 1], P[r, 0], P[r, 1])  # noqa: E731
    return o(a, b, c) * o(a, b, d) < 0 and o(c, d, a) * o(c, d, b) < 0


def _search(dom, kind):
    P = dom.points
    N = dom.n
    nxt = dom.nxt.tolist()
    boundary = {frozenset((v, nxt[v])) for v in range(N)}
    edges = list(boundary)
    rings = _rings(nxt)

    def o(p, q, r):
        return orient(P[p, 0], P[p, 1], P[q, 0], P[q, 1], P[r, 0], P[r, 1])

    def on_open_segment(w, a, b):
        return (o(a, b, w) == 0 and min(P[a, 0], P[b, 0]) <= P[w, 0] <= max(P[a, 0], P[b, 0])
                and min(P[a, 1], P[b, 1]) <= P[w, 1] <= max(P[a, 1], P[b, 1]))

    def inside(pt):
        return point_in_ring(pt, P[rings[0]]) and not any(point_in_ring(pt, P[r]) for r in rings[1:])

    ok = set(boundary)
    for a, b in itertools.combinations(range(N), 2):
        e = frozenset((a, b))
        if e in boundary:
            continue
        if any(on_open_segment(w, a, b) for w in range(N) if w not in (a, b)):
            continue
        if any(_segments_cross(P, a, b, *tuple(f)) for f in edges):
            continue
        if inside((P[a] + P[b]) / 2):
            ok.add(e)
    cands = []
    for a, b, c in itertools.combinations(range(N), 3):
        if not (frozenset((a, b)) in ok and frozenset((b, c)) in ok and frozenset((a, c)) in ok):
            continue
        s = o(a, b, c)
        if s == 0:
            continue
        t = (a, b, c) if s > 0 else (a, c, b)
        if any(o(t[0], t[1], w) >= 0 and o(t[1], t[2], w) >= 0 and o(t[2], t[0], w) >= 0
               for w in range(N) if w not in t):
            continue
        if inside(P[list(t)].mean(axis=0)):
            cands.append(t)
    C = len(cands)
    sides = [[frozenset((t[k], t[(k + 1) % 3])) for k in range(3)] for t in cands]
    conflict = [1 << i for i in range(C)]
    adjacent = [0] * C
    for i, j in itertools.combinations(range(C), 2):
        ti, tj = cands[i], cands[j]
        shared = set(sides[i]) & set(sides[j])
        clash = any(_segments_cross(P, *tuple(e), *tuple(f)) for e in sides[i] for f in sides[j])
        if not clash and shared:
            a, b = tuple(next(iter(shared)))
            ci = next(v for v in ti if v not in (a, b))
            cj = next(v for v in tj if v not in (a, b))
            clash = o(a, b, ci) * o(a, b, cj) > 0
            if not clash:
                adjacent[i] |= 1 << j
                adjacent[j] |= 1 << i
        if clash:
            conflict[i] |= 1 << j
            conflict[j] |= 1 << i
    cover = {e: 0 for e in edges}
    for i in range(C):
        for e in sides[i]:
            if e in cover:
                cover[e] |= 1 << i
    M = N + 2 * (len(rings) - 1) - 2
    cover_list = list(cover.values())
    path: list[int] = []

    def bits(mask):
        while mask:
            low = mask & -mask
            yield low.bit_length() - 1
            mask ^= low

    def dfs(blocked: int, covered: int) -> bool:
        if len(path) == M:
            return kind == "path" or M == 1 or bool(adjacent[path[-1]] >> path[0] & 1)
        # every boundary edge not yet covered needs a compatible triangle
        for cm in cover_list:
            if not cm & covered and not cm & ~blocked:
                return False
        for j in bits(adjacent[path[-1]] & ~blocked):
            path.append(j)
            if dfs(blocked | conflict[j], covered | (1 << j)):
                return True
            path.pop()
        return False

    starts = range(C)
    if kind == "cycle":   # some triangle is on boundary edge 0 -> start there
        starts = list(bits(cover_list[0]))
    for s in starts:
        path[:] = [s]
        if dfs(conflict[s], 1 << s):
            return np.array([cands[i] for i in path], dtype=np.int64)
    return None


def _rings(nxt):
    seen = [False] * len(nxt)
    rings = []
    for v in range(len(nxt)):
        if not seen[v]:
            ring, w = [], v
            while not seen[w]:
                seen[w] = True
                ring.append(w)
                w = nxt[w]
            rings.append(ring)
    return rings
