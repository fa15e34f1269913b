"""Compiled greedy dual path cover and the renumbering of the mesh in path order.

Both read the per-triangle records of :mod:`hammesh.strips._dual_kernels` (vertices,
twins and a scratch column in one half cache line; ``int32`` or ``int64``, one kernel
for both: numba compiles a specialisation per dtype).

Row numbers that are known to be valid are turned into ``np.uint64`` (:data:`~hammesh.strips._numba.row`)
before they index an array: numba then leaves out Python's negative-index wraparound (a
compare and a select per access), which had been ~10% of the greedy cover's time.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.strips._dual_kernels import REC_SCRATCH, REC_TWIN
from hammesh.strips._numba import CORNERS, NEXT_CORNER, carve, kernel, loop_helper, row
from hammesh.strips._path_kernels import vertex_between

__all__ = [
    "LONGEST_CHAIN",
    "SHORTEST_CHAIN",
    "queue_free_degrees",
    "pop_fewest_free",
    "Step",
    "free_step",
    "take_triangle",
    "grow_path",
    "grow_both_ways",
    "PathCover", "greedy_path_cover", "zigzag_path_cover", "Renumbered", "renumber_in_path_order"]

#: A dual path cover: ``order`` every triangle once, path after path; ``starts`` the
#: ``(S + 1,)`` path offsets.
PathCover = namedtuple("PathCover", ["order", "starts"])

#: :func:`grow_path`'s result: triangles appended, the local edge the start was left by
#: and the pivot there.
GrownPath = namedtuple("GrownPath", ["count", "first_exit", "first_pivot"])


@loop_helper
def queue_free_degrees(rec, seed_order, bucket, top):
    """Free degrees into the scratch column; every triangle queued in bucket ``d``, ``seed_order`` order
    (empty: ``m - 1, ..., 0``, with no array of ``m`` to fill and read)."""
    m = rec.shape[0]
    top[:] = 0
    given = seed_order.shape[0] > 0
    if given:  # the degrees first: a seed order may name a row before its degree is known
        for t in range(m):
            rec[t, REC_SCRATCH] = _free_degree(rec, row(t))
    for i in range(m):
        t = row(seed_order[i] if given else m - 1 - i)
        # no seed order: each row's degree when it is queued, in one pass over the records
        # (two passes had been ~5% of the one-pass greedy strips at 1M triangles)
        d = row(rec[t, REC_SCRATCH] if given else _free_degree(rec, t))
        rec[t, REC_SCRATCH] = d
        j = top[d]
        bucket[d, row(j)] = t
        top[d] = j + 1


@loop_helper
def _free_degree(rec, t):
    """Neighbours of row ``t`` (twins ``>= 0``); all free before the cover starts."""
    return (rec[t, REC_TWIN] >= 0) + (rec[t, REC_TWIN + 1] >= 0) + (rec[t, REC_TWIN + 2] >= 0)


@loop_helper
def pop_fewest_free(rec, bucket, top):
    """A free triangle with the fewest free neighbours (most recently queued first), or -1.

    Stale entries (taken triangles, or degrees that dropped since) are discarded.
    """
    for d in range(4):
        while top[d] > 0:
            j = top[d] - 1
            top[d] = j
            t = bucket[d, row(j)]
            if rec[row(t), REC_SCRATCH] == d:
                return t
    return -1


#: :func:`free_step`'s result: the half-edge to a free neighbour (-1: none that way), the
#: neighbour's free degree, the pivot of leaving by that edge and 1 if that is a swap.
Step = namedtuple("Step", ["h", "degree", "pivot", "swap"])


@loop_helper
def free_step(rec, cur, entry, k, prev_pivot):
    """Leaving ``cur`` (entered by local edge ``entry``, -1: the path's first) by edge ``k``: a :class:`Step`."""
    h = rec[cur, REC_TWIN + k]
    if k == entry or h < 0:
        return Step(-1, -1, -1, 0)
    du = rec[row(h) // CORNERS, REC_SCRATCH]
    if du < 0:  # taken
        return Step(-1, -1, -1, 0)
    pivot = rec[cur, k] if entry < 0 else vertex_between(rec, cur, entry, k)
    swap = 1 if (prev_pivot >= 0 and pivot == prev_pivot) else 0
    return Step(np.int64(h), np.int64(du), np.int64(pivot), swap)  # one type for int32 and int64 records


@loop_helper
def take_triangle(t, rec, bucket, top):
    """Mark ``t`` taken (free degree -1) and requeue its free neighbours one degree lower."""
    tr = row(t)
    rec[tr, REC_SCRATCH] = -1
    for k in range(3):
        h = rec[tr, REC_TWIN + k]
        if h < 0:
            continue
        u = row(h) // CORNERS
        d = rec[u, REC_SCRATCH]
        if d >= 0:
            d -= 1
            rec[u, REC_SCRATCH] = d
            dd = row(d)
            j = top[dd]
            bucket[dd, row(j)] = u
            top[dd] = j + 1


@loop_helper
def grow_path(cur, entry, prev_pivot, rec, bucket, top, out, w_swap):
    """Extend a path from ``cur`` (entered through local edge ``entry``, -1: none).

    Each step takes the free neighbour with the least ``2 * free degree + w_swap *
    swap`` (few free neighbours first, so no triangle is stranded; then the
    alternating turn).  Appends to ``out``; returns a :class:`GrownPath`.
    """
    at = row(cur)  # unsigned from here on (see the module docstring)
    n = 0
    first_exit = -1
    first_pivot = -1
    while True:
        best = -1
        best_score = 1 << 30
        best_pivot = -1
        for k in range(3):
            st = free_step(rec, at, entry, k, prev_pivot)
            if st.h < 0:
                continue
            score = 2 * st.degree + w_swap * st.swap
            if score < best_score:
                best_score = score
                best = k
                best_pivot = st.pivot
        if best < 0:
            break
        if n == 0:
            first_exit = best
            first_pivot = best_pivot
        h = row(rec[at, REC_TWIN + best])
        u = h // CORNERS
        take_triangle(u, rec, bucket, top)
        out[n] = u
        n += 1
        prev_pivot = best_pivot
        entry = np.int64(h - CORNERS * u)
        at = u
    return GrownPath(n, first_exit, first_pivot)


def greedy_path_cover(rec, w_swap, seed_order) -> PathCover:
    """Partition the dual graph into paths, greedily (O(m)).

    Seeds are taken with the fewest free neighbours (a bucket queue, most recent
    first, so new paths start along the previous ones; ties at the start broken by
    ``seed_order``, last first; empty: ``m - 1, ..., 0``); each path is grown forward from its seed, then
    backward through the seed's remaining edges, turn-aware.  Overwrites the records'
    scratch column (free degrees).  ``order`` is a view into the work buffer (of the
    records' dtype: half the bytes of the bucket queue when ``int32``).
    """
    m = rec.shape[0]
    bucket, order, starts, fwd, bwd, top = carve(rec.dtype, (4, m), m, m + 1, m, m, 4)
    S = _greedy_path_cover_into(rec, w_swap, seed_order, bucket, order, starts, fwd, bwd, top)
    return PathCover(order, starts[: S + 1].astype(np.int64))


@loop_helper
def grow_both_ways(seed, rec, bucket, top, fwd, bwd, order, L, w_swap):
    """Take ``seed``, grow a path from it forward, then backward through its other edges.

    The path (backward part reversed, the seed, the forward part) is written at
    ``order[L:]``; returns the new end ``L``.  The backward growth avoids a swap at the
    seed: the triangle after the seed fixes the pivot the seed's turn must not repeat.
    """
    take_triangle(seed, rec, bucket, top)
    fw = grow_path(seed, -1, -1, rec, bucket, top, fwd, w_swap)
    nbk = 0
    if fw.count > 0:
        p1 = -1
        if fw.count >= 2:
            u = fwd[0]
            ein = rec[seed, REC_TWIN + fw.first_exit] - 3 * u
            eout = -1
            for k in range(3):
                h = rec[u, REC_TWIN + k]
                if h >= 0 and h // 3 == fwd[1]:
                    eout = k
            p1 = vertex_between(rec, u, ein, eout)
        nbk = grow_path(seed, fw.first_exit, p1, rec, bucket, top, bwd, w_swap).count
    for i in range(nbk):
        order[L] = bwd[nbk - 1 - i]
        L += 1
    order[L] = seed
    L += 1
    for i in range(fw.count):
        order[L] = fwd[i]
        L += 1
    return L


@kernel
def _greedy_path_cover_into(rec, w_swap, seed_order, bucket, order, starts, fwd, bwd, top):
    queue_free_degrees(rec, seed_order, bucket, top)
    L = 0
    S = 0
    starts[0] = 0
    while True:
        seed = pop_fewest_free(rec, bucket, top)
        if seed < 0:
            break
        L = grow_both_ways(seed, rec, bucket, top, fwd, bwd, order, L, w_swap)
        S += 1
        starts[S] = L
    return S


#: The mesh renumbered so that row ``i`` is triangle ``order[i]``: rows ``tri``, their
#: pairing ``twin`` in the new numbering, ``new_id[t]`` the new number of triangle ``t``.
Renumbered = namedtuple("Renumbered", ["tri", "twin", "new_id"])


def renumber_in_path_order(rec, order) -> Renumbered:
    """The mesh renumbered in path order, one record read per row (:class:`Renumbered`).

    In path order, neighbours along the paths are neighbours in memory: the improvement
    moves and the emission then read mostly cached rows.  ``tri`` and ``twin`` have the
    records' dtype (``int32`` where the values fit: half the bytes for every later pass),
    ``new_id`` is ``int64``.
    """
    m = rec.shape[0]
    tri2, twin2 = carve(rec.dtype, (m, 3), 3 * m)
    new_id = np.empty(m, np.int64)
    _renumber_into(rec, order, tri2, twin2, new_id)
    return Renumbered(tri2, twin2, new_id)


@kernel
def _renumber_into(rec, order, tri2, twin2, new_id):
    m = rec.shape[0]
    for i in range(m):
        new_id[order[i]] = i
    for i in range(m):
        t = order[i]
        for k in range(3):
            tri2[i, k] = rec[t, k]
            h = rec[t, REC_TWIN + k]
            if h >= 0:
                u = h // 3
                twin2[3 * i + k] = 3 * new_id[u] + (h - 3 * u)
            else:
                twin2[3 * i + k] = -1


@loop_helper
def _zigzag_step(rec, cur, kout, prev, stamp, mark):
    """Follow the alternating (swap-free) chain one triangle from ``cur`` leaving by ``kout``.

    Returns ``(u, kout2, pivot)``: the next triangle, the edge it must leave by for the
    turns to keep alternating, its pivot; ``u = -1`` at the boundary, at a taken
    triangle or at one already on this chain (``stamp[u] == mark``).
    """
    h = rec[cur, REC_TWIN + kout]
    if h < 0:
        return -1, -1, -1
    u = h // 3
    if rec[u, REC_SCRATCH] < 0 or stamp[u] == mark:
        return -1, -1, -1
    kin = h - 3 * u
    k1 = NEXT_CORNER[kin]
    p1 = rec[u, k1]  # pivot when leaving by the edge after the entry
    if p1 != prev:
        return u, k1, p1
    return u, NEXT_CORNER[k1], rec[u, kin]


#: :func:`zigzag_path_cover`'s choice among a seed's chains: the longest, or the shortest
#: non-empty one.
LONGEST_CHAIN, SHORTEST_CHAIN = 0, 1


def zigzag_path_cover(rec, seed_order, rule=LONGEST_CHAIN) -> PathCover:
    """Cover the dual graph with swap-free (alternating) chains, longest first from each seed.

    Seeds as in :func:`greedy_path_cover` (fewest free neighbours first); from a seed,
    each free neighbour starts a forced chain (Thm 4.3: in an alternating strip each
    triangle fixes the next), the longest (``rule=LONGEST_CHAIN``) or the shortest
    non-empty one (``SHORTEST_CHAIN``) is taken.  On a structured grid (pyvista's
    ``load_random_hills``, latitude-longitude spheres) these are its rows, which the
    degree-first greedy cover bends into L shapes that each cost a swap.  On a
    latitude-longitude sphere the longest chain from a pole triangle is a staircase
    spiralling round the sphere (111 triangles on pyvista's ``sphere.ply``), which
    leaves triangular patches of ever shorter chains beside it; the shortest runs down a
    meridian to the other pole, and the next seeds, beside it, take the parallel
    meridians (``sphere.ply``: 1.150 -> 1.104 indices per triangle after the end moves,
    NvTriStrip 1.120).
    """
    m = rec.shape[0]
    bucket, order, starts, top, stamp = carve(np.int64, (4, m), m, m + 1, 4, m)
    S = _zigzag_path_cover_into(rec, seed_order, rule, bucket, order, starts, top, stamp)
    return PathCover(order, starts[: S + 1].copy())


@kernel
def _zigzag_path_cover_into(rec, seed_order, rule, bucket, order, starts, top, stamp):
    stamp[:] = -1
    queue_free_degrees(rec, seed_order, bucket, top)
    L = 0
    S = 0
    mark = 0
    starts[0] = 0
    while True:
        seed = pop_fewest_free(rec, bucket, top)
        if seed < 0:
            break
        take_triangle(seed, rec, bucket, top)
        best_k = -1
        best_n = 0
        for k0 in range(3):
            mark += 1
            stamp[seed] = mark
            n = 0
            cur = seed
            kout = k0
            prev = rec[seed, k0]
            while True:
                u, kout, prev = _zigzag_step(rec, cur, kout, prev, stamp, mark)
                if u < 0:
                    break
                stamp[u] = mark
                n += 1
                cur = u
            if n > 0 and (best_k < 0 or (n < best_n if rule == SHORTEST_CHAIN else n > best_n)):
                best_n = n
                best_k = k0
        order[L] = seed
        L += 1
        if best_k >= 0:
            mark += 1
            cur = seed
            kout = best_k
            prev = rec[seed, best_k]
            while True:
                u, kout, prev = _zigzag_step(rec, cur, kout, prev, stamp, mark)
                if u < 0:
                    break
                take_triangle(u, rec, bucket, top)
                order[L] = u
                L += 1
                cur = u
        S += 1
        starts[S] = L
    return S
