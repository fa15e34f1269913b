"""Non-local repair of a stalled insertion (collinear points on interior edges).

A point ``p`` on an interior edge ``uv`` whose two triangles ``T1 -> T2`` are
consecutive in the cycle, entered and left at *opposite* pieces of the 4-split, has
no local fix (the four pieces form a ring and the entry and exit pieces are not
adjacent in it).  When the insertion kernel stalls on such points:

1. :func:`insert_by_chain` inserts one of them by re-triangulating a small region:
   a window of up to ``2 + max_half`` consecutive cycle triangles around ``T1 -> T2``,
   or the pair plus a window around one of their other neighbours (two runs of the
   cycle).  A depth-first search builds the new triangles run by run, each run
   starting at the edge by which the cycle enters the old run and ending at the edge
   by which it leaves it; every triangle is CCW, empty of the region's vertices and
   interior-disjoint from the others, and the boundary of the result (as a chain of
   directed edges) must equal the region's boundary.  Then the triangles tile the
   region exactly (their indicator functions sum to the boundary's winding number),
   the outside is untouched and the runs splice back into one cycle.
2. Failing that, :func:`repair` makes one *cycle-preserving flip* near the point: for
   consecutive ``F -> G`` forming a strictly convex quadrilateral, replace their shared
   edge by the other diagonal when the cycle's entry edge of ``F`` and exit edge of
   ``G`` end up in different new triangles.  The kernel then resumes.

Bucket points of replaced triangles are re-partitioned and appended at the end of
``B`` (``lo``/``hi`` point there), so the kernel's contiguous-slice invariant holds.
This is Python (it runs only for stalled points, a few per hundred grid points).
"""

from __future__ import annotations

import numpy as np

from hammesh.predicates import orient_points, orient_rows

__all__ = ["repair"]


def _rot(tri, nbr, f, g):
    """Vertices ``(a, b, c)`` of ``f`` with ``a -> b`` the edge shared with ``g``, and its index."""
    for e in range(3):
        if nbr[f, e] == g:
            return tri[f, e], tri[f, (e + 1) % 3], tri[f, (e + 2) % 3], e
    raise AssertionError("triangles are not adjacent")


def _neighbor_across(tri, nbr, t, a, b):
    for e in range(3):
        if tri[t, e] == a and tri[t, (e + 1) % 3] == b:
            return nbr[t, e]
    raise AssertionError("edge not in triangle")


def flip_consecutive(pts, tri, nbr, nxt, prv, lo, hi, B, f, g):
    """Flip the edge of consecutive triangles ``f -> g`` if that keeps the cycle.

    Returns ``(done, B)``; on success the arrays are updated in place and the new
    ``B`` (with the re-partitioned buckets appended) is returned.
    """
    if nxt[f] != g:
        return False, B
    a, b, c, _ = _rot(tri, nbr, f, g)
    _, _, d, _ = _rot(tri, nbr, g, f)
    # quad a, d, b, c (CCW); new triangles N1 = (c, a, d), N2 = (d, b, c)
    if orient_points(pts, a, d, c) <= 0 or orient_points(pts, d, b, c) <= 0:
        return False, B
    n_bc = _neighbor_across(tri, nbr, f, b, c)
    n_ca = _neighbor_across(tri, nbr, f, c, a)
    n_ad = _neighbor_across(tri, nbr, g, a, d)
    n_db = _neighbor_across(tri, nbr, g, d, b)
    p, q = prv[f], nxt[g]
    if p < 0 or q < 0:
        return False, B
    if p == n_ca and q == n_db:
        first, second = (c, a, d), (d, b, c)
        fn, sn = (n_ca, n_ad, g), (n_db, n_bc, f)
    elif p == n_bc and q == n_ad:
        first, second = (d, b, c), (c, a, d)
        fn, sn = (n_db, n_bc, g), (n_ca, n_ad, f)
    else:
        return False, B
    pool = np.concatenate([B[lo[f]:hi[f]], B[lo[g]:hi[g]]])
    tri[f] = first
    nbr[f] = fn
    tri[g] = second
    nbr[g] = sn
    for t in (f, g):
        for e in range(3):
            x = nbr[t, e]
            if x >= 0:
                u, v = tri[t, e], tri[t, (e + 1) % 3]
                for k in range(3):
                    if tri[x, k] == v and tri[x, (k + 1) % 3] == u:
                        nbr[x, k] = t
    # f's internal edge runs first[2] -> first[0] (d -> c or c -> d): its side of it
    if len(pool):
        side = np.array([orient_points(pts, first[2], first[0], int(r)) >= 0 for r in pool])
        mine, theirs = pool[side], pool[~side]
        start = len(B)
        B = np.concatenate([B, mine, theirs])
        lo[f], hi[f] = start, start + len(mine)
        lo[g], hi[g] = start + len(mine), start + len(pool)
    else:
        lo[f] = hi[f] = lo[g] = hi[g] = 0
    return True, B


def _stuck_pair(pts, tri, nbr, nxt, prv, lo, hi, B, t):
    """The consecutive pair ``(F, G)`` whose shared edge holds a point of ``t``'s bucket."""
    for r in B[lo[t]:hi[t]]:
        for k in range(3):
            if orient_points(pts, tri[t, k], tri[t, (k + 1) % 3], int(r)) == 0:
                t2 = nbr[t, k]
                if t2 >= 0:
                    if nxt[t] == t2:
                        return t, t2
                    if prv[t] == t2:
                        return t2, t
    return None


def repair(pts, tri, nbr, nxt, prv, lo, hi, B, n_tri, rng):
    """One cycle-preserving flip near a stalled point; returns ``(done, B)``."""
    stalled = [t for t in range(n_tri) if hi[t] > lo[t]]
    rng.shuffle(stalled)
    for t in stalled:
        pair = _stuck_pair(pts, tri, nbr, nxt, prv, lo, hi, B, t)
        if pair is None:
            continue
        f, g = pair
        cands = [(f, g)]
        back, fwd = f, g
        for _ in range(3):
            if prv[back] >= 0:
                cands.append((prv[back], back))
                back = prv[back]
            if nxt[fwd] >= 0:
                cands.append((fwd, nxt[fwd]))
                fwd = nxt[fwd]
        # the edge itself first, then the nearest others in random order
        rest = cands[1:]
        rng.shuffle(rest)
        for x, y in [cands[0], *rest]:
            done, B = flip_consecutive(pts, tri, nbr, nxt, prv, lo, hi, B, x, y)
            if done:
                return True, B
    return False, B


# --------------------------------------------------------------- local re-triangulation
def _orient(pts, a, b, c):
    return int(orient_points(pts, int(a), int(b), int(c)))


def _orient_table(pts, V):
    """``o(a, b, c)`` for points of ``V`` from one exact table (the searches repeat them)."""
    k = len(V)
    ix = {v: i for i, v in enumerate(V)}
    g = np.arange(k)
    a, b, c = (x.ravel() for x in np.meshgrid(g, g, g, indexing="ij"))
    P = pts[np.asarray(V, dtype=np.int64)]
    O = orient_rows(P[a], P[b], P[c]).reshape(k, k, k).tolist()

    def o(p, q, r):
        return O[ix[p]][ix[q]][ix[r]]

    return o


def _empty(o, tri3, V):
    a, b, c = tri3
    for q in V:
        if q in tri3:
            continue
        if o(a, b, q) >= 0 and o(b, c, q) >= 0 and o(c, a, q) >= 0:
            return False
    return True


def _disjoint(o, s, t):
    for x, y in ((s, t), (t, s)):
        for e in range(3):
            a, b = x[e], x[(e + 1) % 3]
            if all(o(a, b, q) <= 0 for q in y):
                return True
    return False


def _edges(t3):
    return ((t3[0], t3[1]), (t3[1], t3[2]), (t3[2], t3[0]))


def _solve_segments(pts, tri, nbr, prv, nxt, segments, p, budget):
    # budget: [steps used, step limit], shared by the caller's searches
    """Triangles re-triangulating the union of ``segments`` with the point ``p`` added.

    ``segments`` are disjoint runs of consecutive cycle triangles.  The new triangles
    come as the same number of runs, run ``s`` starting at the edge by which the
    cycle enters ``segments[s][0]`` and ending at the edge by which it leaves
    ``segments[s][-1]``; the boundary of the union is kept.  The triangles are CCW,
    empty and pairwise interior-disjoint, and their boundary (as a chain of directed
    edges) equals the union's boundary, so they tile the union exactly (the sum of
    their indicator functions is the winding number of the boundary).
    Returns ``(runs, bnd)`` or None.
    """
    cset = {t for seg in segments for t in seg}
    bnd = {}
    for t in cset:
        for e in range(3):
            if nbr[t, e] not in cset:
                bnd[(int(tri[t, e]), int(tri[t, (e + 1) % 3]))] = int(nbr[t, e])
    e_in, e_out = [], []
    for seg in segments:
        first = _edges(tuple(int(v) for v in tri[seg[0]]))
        last = _edges(tuple(int(v) for v in tri[seg[-1]]))
        ei = [e for e in first if e in bnd and bnd[e] == prv[seg[0]]]
        eo = [e for e in last if e in bnd and bnd[e] == nxt[seg[-1]]]
        if len(ei) != 1 or len(eo) != 1 or ei[0] == eo[0]:
            return None
        e_in.append(ei[0])
        e_out.append(eo[0])
    V = sorted({int(v) for t in cset for v in tri[t]} | {int(p)})
    o = _orient_table(pts, V)
    L = len(cset) + 2
    S = len(segments)
    rev_bnd = {(b, a) for (a, b) in bnd}
    cache = {}
    steps = budget

    def candidates(x, y):
        # empty CCW triangles (x, y, z) with z in V, not reaching outside the union
        key = (x, y)
        if key not in cache:
            out = []
            for z in V:
                if z in (x, y) or o(x, y, z) <= 0:
                    continue
                t3 = (x, y, z)
                if any(e in rev_bnd for e in _edges(t3)):
                    continue
                if _empty(o, t3, V):
                    out.append(t3)
            cache[key] = out
        return cache[key]

    path = []
    cuts = []
    used = set()

    def push(t3):
        path.append(t3)
        used.update(_edges(t3))

    def pop():
        used.difference_update(_edges(path.pop()))

    def ok_to_add(t3):
        if any(e in used for e in _edges(t3)):
            return False
        return all(_disjoint(o, t3, s) for s in path)

    def finish():
        if not set(bnd) <= used:
            return False
        for (a, b) in used:
            if (a, b) not in bnd and (b, a) not in used:
                return False
        return {v for t3 in path for v in t3} == set(V)

    def start(seg):
        a, b = e_in[seg]
        for t3 in candidates(a, b):
            if ok_to_add(t3):
                push(t3)
                cuts.append(len(path) - 1)
                if dfs(seg, e_in[seg]):
                    return True
                cuts.pop()
                pop()
        return False

    def dfs(seg, entry):
        steps[0] += 1
        if steps[0] > steps[1]:
            return False
        cur = path[-1]
        if e_out[seg] in _edges(cur):
            if seg == S - 1:
                return len(path) == L and finish()
            return start(seg + 1)
        if len(path) >= L:
            return False
        for (a, b) in _edges(cur):
            if (a, b) == entry or (a, b) in bnd:
                continue
            for t3 in candidates(b, a):
                if ok_to_add(t3):
                    push(t3)
                    if dfs(seg, (b, a)):
                        return True
                    pop()
        return False

    if not start(0):
        return None
    runs = [path[c:(cuts[i + 1] if i + 1 < len(cuts) else len(path))] for i, c in enumerate(cuts)]
    return runs, bnd


def _commit_segments(pts, tri, nbr, nxt, prv, lo, hi, B, segments, p, runs, bnd, n_tri):
    old = [t for seg in segments for t in seg]
    ids = old + [n_tri, n_tri + 1]
    ends = [(int(prv[seg[0]]), int(nxt[seg[-1]])) for seg in segments]
    pool = np.concatenate([B[lo[t]:hi[t]] for t in old])
    pool = pool[pool != p]
    new = [t3 for run in runs for t3 in run]
    where = {}
    for i, t3 in enumerate(new):
        for e in _edges(t3):
            where[e] = i
    for i, t3 in enumerate(new):
        t = ids[i]
        tri[t] = t3
        for e, (a, b) in enumerate(_edges(t3)):
            if (a, b) in bnd:
                x = bnd[(a, b)]
                nbr[t, e] = x
                if x >= 0:
                    for k in range(3):
                        if tri[x, k] == b and tri[x, (k + 1) % 3] == a:
                            nbr[x, k] = t
            else:
                nbr[t, e] = ids[where[(b, a)]]
    i = 0
    for run, (before, after) in zip(runs, ends):
        for j in range(len(run)):
            t = ids[i + j]
            prv[t] = ids[i + j - 1] if j > 0 else before
            nxt[t] = ids[i + j + 1] if j + 1 < len(run) else after
        nxt[before] = ids[i]
        prv[after] = ids[i + len(run) - 1]
        i += len(run)
    groups = [[] for _ in new]
    for r in pool:
        for i, (a, b, c) in enumerate(new):
            if (_orient(pts, a, b, r) >= 0 and _orient(pts, b, c, r) >= 0
                    and _orient(pts, c, a, r) >= 0):
                groups[i].append(int(r))
                break
        else:  # pragma: no cover - the new triangles tile the old union
            raise AssertionError("a bucket point fell outside the re-triangulated region")
    start = len(B)
    B = np.concatenate([B, np.array([r for g in groups for r in g], dtype=np.int64)])
    for i, g in enumerate(groups):
        lo[ids[i]], hi[ids[i]] = start, start + len(g)
        start += len(g)
    return B


def _window(prv, nxt, f, g, lead, trail):
    chain = [f, g]
    for _ in range(lead):
        chain.insert(0, int(prv[chain[0]]))
    for _ in range(trail):
        chain.append(int(nxt[chain[-1]]))
    return chain


def _regions(tri, nbr, prv, nxt, f, g, max_half):
    """Candidate regions around the consecutive pair ``f -> g``: runs of the cycle."""
    for half in range(max_half + 1):
        for lead in range(half + 1):
            yield [_window(prv, nxt, f, g, lead, half - lead)]
    # the pair plus a window around a neighbor the cycle does not reach from the pair
    for t in (f, g):
        for e in range(3):
            x = int(nbr[t, e])
            if x < 0 or x in (f, g, prv[f], nxt[g]):
                continue
            for half in range(max_half):
                for lead in range(half + 1):
                    other = [x]
                    for _ in range(lead):
                        other.insert(0, int(prv[other[0]]))
                    for _ in range(half - lead):
                        other.append(int(nxt[other[-1]]))
                    yield [[f, g], other]


def _valid(segments, prv, nxt, n_tri):
    flat = [t for seg in segments for t in seg]
    if min(flat) < 0 or len(set(flat)) != len(flat) or len(flat) + 2 > n_tri:
        return False
    for seg in segments:
        if prv[seg[0]] < 0 or nxt[seg[-1]] < 0 or prv[seg[0]] in flat or nxt[seg[-1]] in flat:
            return False
    return True


def insert_by_chain(pts, tri, nbr, nxt, prv, lo, hi, B, n_tri, max_half=6, budget=20000):
    """Insert one stalled point by re-triangulating a few runs of the cycle around it.

    ``budget`` bounds the search steps of the whole call (all points and regions).
    Returns ``(n_new_triangles, B, steps)``; ``0`` new triangles if no stalled point
    could be inserted; ``steps`` is the search work spent.
    """
    steps = [0, budget]
    for t in range(n_tri):
        if hi[t] <= lo[t]:
            continue
        for r in B[lo[t]:hi[t]]:
            r = int(r)
            for k in range(3):
                if steps[0] > steps[1]:
                    return 0, B, steps[0]
                if _orient(pts, tri[t, k], tri[t, (k + 1) % 3], r) != 0:
                    continue
                t2 = int(nbr[t, k])
                if t2 < 0:
                    continue
                if nxt[t] == t2:
                    f, g = t, t2
                elif prv[t] == t2:
                    f, g = t2, t
                else:
                    continue
                for segments in _regions(tri, nbr, prv, nxt, f, g, max_half):
                    if not _valid(segments, prv, nxt, n_tri):
                        continue
                    sol = _solve_segments(pts, tri, nbr, prv, nxt, segments, r, steps)
                    if sol is not None:
                        runs, bnd = sol
                        B = _commit_segments(pts, tri, nbr, nxt, prv, lo, hi, B, segments, r,
                                             runs, bnd, n_tri)
                        return 2, B, steps[0]
    return 0, B, steps[0]
