"""Compiled loops (numba, ``cache=True``, serial) of the point-set algorithms.

* :func:`hull_boundary`: Andrew's monotone chain keeping collinear boundary points.
* :func:`fan_locate`: first point location, every point into a triangle of the start fan.
* :func:`insert_points`: the randomized splitter insertion of Thm 3.1 / Lemma 3.2 with
  bucket partitioning (quicksort-like, in place) and the cycle-preserving local updates.

Kernels never raise; they return status codes that the Python callers turn into
hammesh exceptions.  Every geometric decision uses the exact :func:`orient`.
"""

from __future__ import annotations

from itertools import permutations

import numpy as np
from numba import njit

from hammesh.predicates import orient_points

__all__ = ["hull_boundary", "all_collinear", "fan_locate", "insert_points", "cycle_order",
           "OK", "STUCK", "BROKEN"]

OK, STUCK, BROKEN = 0, 1, 2
#: Random splitters tried per triangle before one that leaves points on its new
#: edges is accepted (general position: the first one always passes).
AVOID_TRIES = 32

_PERM2 = np.array(list(permutations(range(2))), dtype=np.int64)
_PERM3 = np.array(list(permutations(range(3))), dtype=np.int64)
_PERM4 = np.array(list(permutations(range(4))), dtype=np.int64)


# --------------------------------------------------------------------------- hull
@njit(cache=True)
def all_collinear(pts, a, b):
    """True if every point is on the line through points ``a`` and ``b``."""
    for q in range(pts.shape[0]):
        if orient_points(pts, a, b, q) != 0:
            return False
    return True


@njit(cache=True)
def hull_boundary(pts, order):
    """Boundary points of the convex hull, counter-clockwise, collinear ones included.

    ``order`` is the lexicographic (x, then y) order of distinct, not all collinear
    points.  Returns ``(boundary, corner)``: indices in CCW order starting at the
    lexicographically smallest point, and a flag per boundary point that is True for
    strictly convex corners.
    """
    n = order.shape[0]
    stack = np.empty(2 * n + 2, np.int64)
    k = 0
    for i in range(n):
        q = order[i]
        while k >= 2 and orient_points(pts, stack[k - 2], stack[k - 1], q) < 0:
            k -= 1
        stack[k] = q
        k += 1
    lower = k
    for i in range(n - 2, -1, -1):
        q = order[i]
        while k >= lower + 1 and orient_points(pts, stack[k - 2], stack[k - 1], q) < 0:
            k -= 1
        stack[k] = q
        k += 1
    b = stack[: k - 1].copy()
    h = b.shape[0]
    corner = np.zeros(h, np.bool_)
    for i in range(h):
        corner[i] = orient_points(pts, b[(i - 1) % h], b[i], b[(i + 1) % h]) > 0
    return b, corner


# ------------------------------------------------------------------ first location
@njit(cache=True)
def fan_locate(pts, apex, spokes, cyclic, guess, which):
    """Triangle of the start fan holding each point of ``which`` (closed containment).

    Fan triangle ``i`` is ``(apex, spokes[i], spokes[i + 1])`` (indices mod ``s`` when
    ``cyclic``).  ``guess`` is an angular first guess per point; it is corrected with
    exact orientation tests.  Returns the triangle per point (-1 where none holds it)
    and the number of points on a spoke (an interior edge of the fan when cyclic).
    """
    s = spokes.shape[0]
    nt = s if cyclic else s - 1
    out = np.empty(which.shape[0], np.int64)
    n_on = 0
    for r in range(which.shape[0]):
        q = which[r]
        i = min(max(guess[r], 0), nt - 1)
        found = -1
        for _ in range(nt + 1):
            a = spokes[i]
            b = spokes[(i + 1) % s]
            left = orient_points(pts, apex, a, q)
            right = orient_points(pts, b, apex, q)
            if left >= 0 and right >= 0:
                found = i
                if left == 0 or right == 0:
                    n_on += 1
                break
            if left < 0:
                i = i - 1 if i > 0 else (nt - 1 if cyclic else 0)
            else:
                i = i + 1 if i < nt - 1 else (0 if cyclic else nt - 1)
        out[r] = found
    return out, n_on


# ------------------------------------------------------------------ insertion
@njit(cache=True)
def _rand(state):
    x = state[0]
    x ^= (x << np.uint64(13))
    x ^= (x >> np.uint64(7))
    x ^= (x << np.uint64(17))
    state[0] = x
    return x


@njit(cache=True)
def _swap(B, i, j):
    t = B[i]
    B[i] = B[j]
    B[j] = t


@njit(cache=True)
def _partition_line(pts, B, lo, hi, p, w):
    """Move the points of ``B[lo:hi]`` with ``orient(p, w, q) >= 0`` to the front."""
    i = lo
    j = hi - 1
    while i <= j:
        if orient_points(pts, p, w, B[i]) >= 0:
            i += 1
        else:
            _swap(B, i, j)
            j -= 1
    return i


@njit(cache=True)
def _partition_sector(pts, B, lo, hi, p, a, b):
    """Front: points ``q`` with ``orient(p, a, q) >= 0`` and ``orient(p, b, q) < 0``.

    Also counts the points on the lines ``p a`` or ``p b`` (future on-edge points).
    """
    i = lo
    j = hi - 1
    zeros = 0
    while i <= j:
        q = B[i]
        da = orient_points(pts, p, a, q)
        db = orient_points(pts, p, b, q)
        if da == 0 or db == 0:
            zeros += 1
        if da >= 0 and db < 0:
            i += 1
        else:
            _swap(B, i, j)
            j -= 1
    return i, zeros


@njit(cache=True)
def _adjacent(code, i, x):
    for e in range(3):
        if code[i, e] == x:
            return True
    return False


@njit(cache=True)
def _route(code, K, S, segP, segN, result):
    """Order the K new pieces into S cycle segments (brute force, K <= 4).

    ``code[i, e]`` is the neighbor of piece ``i`` across its edge ``e``: ``>= 0`` an
    outside triangle, ``-1`` the hull, ``-(2 + j)`` piece ``j``.  Segment ``s`` must start
    next to ``segP[s]`` and end next to ``segN[s]`` (``-1``: a path end, free).  On
    success ``result[:K]`` holds the order and the return value is the length of the
    first segment; otherwise -1.
    """
    if K == 2:
        perms = _PERM2
    elif K == 3:
        perms = _PERM3
    else:
        perms = _PERM4
    for r in range(perms.shape[0]):
        pr = perms[r]
        lmin = K if S == 1 else 1
        lmax = K if S == 1 else K - 1
        for l1 in range(lmin, lmax + 1):
            ok = True
            for s in range(S):
                a = 0 if s == 0 else l1
                b = l1 if s == 0 else K
                if segP[s] >= 0 and not _adjacent(code, pr[a], segP[s]):
                    ok = False
                    break
                if segN[s] >= 0 and not _adjacent(code, pr[b - 1], segN[s]):
                    ok = False
                    break
                for i in range(a, b - 1):
                    if not _adjacent(code, pr[i], -(2 + pr[i + 1])):
                        ok = False
                        break
                if not ok:
                    break
            if ok:
                for i in range(K):
                    result[i] = pr[i]
                return l1
    return -1


@njit(cache=True)
def _edge_index(tri, nbr, x, old, a, b):
    """Edge of triangle ``x`` from ``a`` to ``b`` whose neighbor is ``old``, or -1."""
    for e in range(3):
        if nbr[x, e] == old and tri[x, e] == a and tri[x, (e + 1) % 3] == b:
            return e
    return -1


@njit(cache=True)
def _commit(tri, nbr, nxt, prv, ids, pv, code, K, old0, old1, order, l1, S, segP, segN):
    for i in range(K):
        t = ids[i]
        for e in range(3):
            tri[t, e] = pv[i, e]
        for e in range(3):
            c = code[i, e]
            if c <= -2:
                nbr[t, e] = ids[-c - 2]
            else:
                nbr[t, e] = c
    # outside neighbors now point at the pieces
    for i in range(K):
        t = ids[i]
        for e in range(3):
            x = code[i, e]
            if x >= 0:
                a = pv[i, e]
                b = pv[i, (e + 1) % 3]
                j = _edge_index(tri, nbr, x, old0, b, a)
                if j < 0 and old1 >= 0:
                    j = _edge_index(tri, nbr, x, old1, b, a)
                if j >= 0:
                    nbr[x, j] = t
    for s in range(S):
        a = 0 if s == 0 else l1
        b = l1 if s == 0 else K
        first = ids[order[a]]
        last = ids[order[b - 1]]
        prv[first] = segP[s]
        if segP[s] >= 0:
            nxt[segP[s]] = first
        for i in range(a, b - 1):
            nxt[ids[order[i]]] = ids[order[i + 1]]
            prv[ids[order[i + 1]]] = ids[order[i]]
        nxt[last] = segN[s]
        if segN[s] >= 0:
            prv[segN[s]] = last


@njit(cache=True)
def _try_insert(pts, tri, nbr, nxt, prv, lo, hi, B, pos, t, state, work, avoid=False):
    """Insert point ``B[pos]`` (in the bucket of ``t``); returns (done, n_new, bad).

    ``state``: [n_tri]; ``work``: stack arrays. A point strictly inside ``t`` splits it
    into three (Figure 12); on a hull edge it splits ``t`` into two; on an edge shared
    with ``t2`` it splits both into four.  The cycle (or path) is rerouted through the
    pieces; if no routing exists the mesh is left unchanged and ``done`` is False.
    With ``avoid`` a 3-split that would leave points on its new edges is declined
    (such points are the only source of stalls, so another splitter is preferred).
    """
    p = B[pos]
    a = tri[t, 0]
    b = tri[t, 1]
    c = tri[t, 2]
    o0 = orient_points(pts, a, b, p)
    o1 = orient_points(pts, b, c, p)
    o2 = orient_points(pts, c, a, p)
    if o0 < 0 or o1 < 0 or o2 < 0:
        return False, 0, True
    pv = np.empty((4, 3), np.int64)
    code = np.empty((4, 3), np.int64)
    segP = np.empty(2, np.int64)
    segN = np.empty(2, np.int64)
    order = np.empty(4, np.int64)
    ids = np.empty(4, np.int64)
    n_tri = state[0]
    t2 = -1
    if o0 > 0 and o1 > 0 and o2 > 0:
        K = 3
        pv[0, 0] = a; pv[0, 1] = b; pv[0, 2] = p
        pv[1, 0] = b; pv[1, 1] = c; pv[1, 2] = p
        pv[2, 0] = c; pv[2, 1] = a; pv[2, 2] = p
        code[0, 0] = nbr[t, 0]; code[0, 1] = -3; code[0, 2] = -4
        code[1, 0] = nbr[t, 1]; code[1, 1] = -4; code[1, 2] = -2
        code[2, 0] = nbr[t, 2]; code[2, 1] = -2; code[2, 2] = -3
        S = 1
        segP[0] = prv[t]
        segN[0] = nxt[t]
    else:
        k = 0 if o0 == 0 else (1 if o1 == 0 else 2)
        u = tri[t, k]
        v = tri[t, (k + 1) % 3]
        w = tri[t, (k + 2) % 3]
        n_vw = nbr[t, (k + 1) % 3]
        n_wu = nbr[t, (k + 2) % 3]
        t2 = nbr[t, k]
        if t2 < 0:
            K = 2
            pv[0, 0] = u; pv[0, 1] = p; pv[0, 2] = w
            pv[1, 0] = p; pv[1, 1] = v; pv[1, 2] = w
            code[0, 0] = -1; code[0, 1] = -3; code[0, 2] = n_wu
            code[1, 0] = -1; code[1, 1] = n_vw; code[1, 2] = -2
            S = 1
            segP[0] = prv[t]
            segN[0] = nxt[t]
        else:
            j = _edge_index(tri, nbr, t2, t, v, u)
            if j < 0:
                return False, 0, True
            w2 = tri[t2, (j + 2) % 3]
            n_uw2 = nbr[t2, (j + 1) % 3]
            n_w2v = nbr[t2, (j + 2) % 3]
            K = 4
            pv[0, 0] = u; pv[0, 1] = p; pv[0, 2] = w
            pv[1, 0] = p; pv[1, 1] = v; pv[1, 2] = w
            pv[2, 0] = v; pv[2, 1] = p; pv[2, 2] = w2
            pv[3, 0] = p; pv[3, 1] = u; pv[3, 2] = w2
            code[0, 0] = -5; code[0, 1] = -3; code[0, 2] = n_wu
            code[1, 0] = -4; code[1, 1] = n_vw; code[1, 2] = -2
            code[2, 0] = -3; code[2, 1] = -5; code[2, 2] = n_w2v
            code[3, 0] = -2; code[3, 1] = n_uw2; code[3, 2] = -4
            if nxt[t] == t2:
                S = 1
                segP[0] = prv[t]
                segN[0] = nxt[t2]
            elif prv[t] == t2:
                S = 1
                segP[0] = prv[t2]
                segN[0] = nxt[t]
            else:
                S = 2
                segP[0] = prv[t]
                segN[0] = nxt[t]
                segP[1] = prv[t2]
                segN[1] = nxt[t2]
    l1 = _route(code, K, S, segP, segN, order)
    if l1 < 0:
        return False, 0, False
    # ids: piece 0 reuses t; with a neighbor split piece 2 reuses t2
    ids[0] = t
    nxt_id = n_tri
    for i in range(1, K):
        if K == 4 and i == 2:
            ids[i] = t2
        else:
            ids[i] = nxt_id
            nxt_id += 1
    # remove p from the bucket of t
    _swap(B, pos, lo[t])
    start = lo[t] + 1
    end = hi[t]
    if K == 3:
        m1, z1 = _partition_sector(pts, B, start, end, p, a, b)
        m2, z2 = _partition_sector(pts, B, m1, end, p, b, c)
        if avoid and z1 + z2 > 0:
            return False, 0, False  # nothing committed: the slice was only permuted
        lo[ids[0]] = start; hi[ids[0]] = m1
        lo[ids[1]] = m1; hi[ids[1]] = m2
        lo[ids[2]] = m2; hi[ids[2]] = end
    else:
        w = pv[0, 2]
        m1 = _partition_line(pts, B, start, end, p, w)
        lo[ids[0]] = start; hi[ids[0]] = m1
        lo[ids[1]] = m1; hi[ids[1]] = end
        if K == 4:
            w2 = pv[2, 2]
            s2 = lo[t2]
            e2 = hi[t2]
            m3 = _partition_line(pts, B, s2, e2, p, w2)
            lo[ids[2]] = s2; hi[ids[2]] = m3
            lo[ids[3]] = m3; hi[ids[3]] = e2
    _commit(tri, nbr, nxt, prv, ids, pv, code, K, t, t2, order, l1, S, segP, segN)
    state[0] = nxt_id
    # push the pieces that still hold points
    for i in range(K):
        x = ids[i]
        if hi[x] > lo[x]:
            work[state[1]] = x
            state[1] += 1
    return True, nxt_id - n_tri, False


@njit(cache=True)
def _strictly_inside(pts, tri, t, q):
    return (
        orient_points(pts, tri[t, 0], tri[t, 1], q) > 0
        and orient_points(pts, tri[t, 1], tri[t, 2], q) > 0
        and orient_points(pts, tri[t, 2], tri[t, 0], q) > 0
    )


@njit(cache=True)
def _neighbor_of_point(pts, tri, nbr, t, q):
    for k in range(3):
        if orient_points(pts, tri[t, k], tri[t, (k + 1) % 3], q) == 0:
            return nbr[t, k]
    return -1


@njit(cache=True)
def insert_points(pts, tri, nbr, nxt, prv, lo, hi, B, n_tri0, seed):
    """Insert every bucketed point (Thm 3.1 with random splitters, Lemma 3.2).

    ``tri, nbr, nxt, prv, lo, hi`` are preallocated to the final triangle count and
    hold the start fan in their first ``n_tri0`` rows; ``B`` lists the points to insert,
    grouped by triangle (``B[lo[t]:hi[t]]`` are the points inside triangle ``t``).

    Each step takes a triangle with points, inserts a random one of them (the
    splitter) and partitions the others among the pieces, in place.  A point on an
    interior edge whose 4-split cannot keep the cycle (entry and exit pieces
    opposite) is replaced by a strictly interior splitter of either triangle (that
    turns the configuration around, see ``docs/pointset.md``) or, failing that, by
    another point of the bucket; a triangle with no usable point is retried after
    all others (its neighbors may have changed).  Returns ``(n_tri, status)``.
    On ``STUCK`` the arrays are consistent (nothing half-committed): the caller may
    repair the mesh (``_cycle_repair``) and call again with the current ``n_tri``.
    """
    m_max = tri.shape[0]
    state = np.zeros(2, np.int64)
    state[0] = n_tri0
    rng = np.zeros(1, np.uint64)
    rng[0] = np.uint64(seed) * np.uint64(2654435761) + np.uint64(88172645463325252)
    if rng[0] == 0:
        rng[0] = np.uint64(1)
    work = np.empty(4 * m_max + 16, np.int64)
    deferred = np.empty(m_max + 1, np.int64)
    n_def = 0
    for t in range(n_tri0):
        if hi[t] > lo[t]:
            work[state[1]] = t
            state[1] += 1
    while True:
        progress = 0
        while state[1] > 0:
            state[1] -= 1
            t = work[state[1]]
            size = hi[t] - lo[t]
            if size <= 0:
                continue
            if state[1] + 8 >= work.shape[0]:
                return state[0], BROKEN
            done = False
            bad = False
            for _ in range(AVOID_TRIES):
                pos = lo[t] + np.int64(_rand(rng) % np.uint64(size))
                if _strictly_inside(pts, tri, t, B[pos]):
                    done, _, bad = _try_insert(pts, tri, nbr, nxt, prv, lo, hi, B, pos, t, state, work, True)
                    if done or bad:
                        break
            if not done and not bad:
                pos = lo[t] + np.int64(_rand(rng) % np.uint64(size))
                done, _, bad = _try_insert(pts, tri, nbr, nxt, prv, lo, hi, B, pos, t, state, work)
            if bad:
                return state[0], BROKEN
            if done:
                progress += 1
                continue
            # the splitter sits on an edge and the cycle cannot pass: other choices
            inserted = False
            for pos2 in range(lo[t], hi[t]):
                if _strictly_inside(pts, tri, t, B[pos2]):
                    done, _, bad = _try_insert(pts, tri, nbr, nxt, prv, lo, hi, B, pos2, t, state, work)
                    inserted = done
                    break
            if not inserted:
                t2 = _neighbor_of_point(pts, tri, nbr, t, B[pos])
                if t2 >= 0:
                    for pos2 in range(lo[t2], hi[t2]):
                        if _strictly_inside(pts, tri, t2, B[pos2]):
                            done, _, bad = _try_insert(
                                pts, tri, nbr, nxt, prv, lo, hi, B, pos2, t2, state, work
                            )
                            if done:
                                inserted = True
                                work[state[1]] = t
                                state[1] += 1
                            break
            if not inserted:
                for pos2 in range(lo[t], hi[t]):
                    done, _, bad = _try_insert(pts, tri, nbr, nxt, prv, lo, hi, B, pos2, t, state, work)
                    if done:
                        inserted = True
                        break
            if not inserted:
                t2 = _neighbor_of_point(pts, tri, nbr, t, B[pos])
                if t2 >= 0:
                    for pos2 in range(lo[t2], hi[t2]):
                        done, _, bad = _try_insert(
                            pts, tri, nbr, nxt, prv, lo, hi, B, pos2, t2, state, work
                        )
                        if done:
                            inserted = True
                            work[state[1]] = t
                            state[1] += 1
                            break
            if bad:
                return state[0], BROKEN
            if inserted:
                progress += 1
            else:
                deferred[n_def] = t
                n_def += 1
        if n_def == 0:
            return state[0], OK
        if progress == 0:
            return state[0], STUCK
        for i in range(n_def):
            work[state[1]] = deferred[i]
            state[1] += 1
        n_def = 0


@njit(cache=True)
def cycle_order(nxt, prv, n_tri):
    """Triangles in cycle (or path) order; empty if the links do not visit all once."""
    start = 0
    for t in range(n_tri):
        if prv[t] < 0:
            start = t
            break
    out = np.empty(n_tri, np.int64)
    seen = np.zeros(n_tri, np.bool_)
    t = start
    for i in range(n_tri):
        if t < 0 or t >= n_tri or seen[t]:
            return out[:0]
        seen[t] = True
        out[i] = t
        t = nxt[t]
    return out
