"""Compiled steps of cache mode's band layout (:func:`hammesh.strips.rows.band_layout`): cuts
where a piece drifts across the rows, each cut moved to where it costs fewest indices, and
each piece turned to its cheaper direction (along the rows on a tie).

The cost of a piece ``order[lo:hi]`` of one dual path, in its better direction, is
``k + 2`` indices plus its interior swaps plus one if both directions start with a swap
(``k = hi - lo``; interior pivots do not depend on the direction, only the swap after the
first triangle does: :func:`~hammesh.strips._path_kernels.turn_path_if_better`).  The
interior swaps of every piece are one prefix sum over the whole cover
(:func:`equal_pivots_into`), so a piece's cost is O(1) wherever its ends are.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel, loop_helper
from hammesh.strips._path_kernels import edge_to_neighbour, starts_with_swap, vertex_between

__all__ = ["equal_pivots_into", "piece_cost", "level_cuts_into", "move_cuts", "orient_pieces", "chain_cost",
           "join_heading_pieces"]


@loop_helper
def _pivot(tri, twin3, order, i):
    """Pivot of position ``i`` (its two path neighbours ``i - 1``, ``i + 1`` given)."""
    t = order[i]
    return vertex_between(tri, t, edge_to_neighbour(twin3, t, order[i - 1]), edge_to_neighbour(twin3, t, order[i + 1]))


@kernel
def equal_pivots_into(tri, twin3, order, starts, cum):
    """``cum`` ``(m + 1,)``: ``cum[i + 1] - cum[j]`` counts the positions ``j..i`` whose pivot
    equals the one before (a swap), for positions at least two from their path's first and
    last triangle (where both pivots are interior to the path)."""
    cum[0] = 0
    for p in range(starts.shape[0] - 1):
        a, b = starts[p], starts[p + 1]
        prev = np.int64(-1)
        for i in range(a, b):
            same = 0
            if a + 1 <= i <= b - 2:
                pv = _pivot(tri, twin3, order, i)
                same = np.int64(i >= a + 2 and pv == prev)
                prev = pv
            cum[i + 1] = cum[i] + same


@loop_helper
def piece_cost(tri, twin3, order, cum, lo, hi):
    """Indices of the piece ``order[lo:hi]`` (one dual path's consecutive triangles) in its
    better direction, its restart not counted."""
    k = hi - lo
    if k < 3:
        return k + 2
    both = starts_with_swap(tri, twin3, order[lo], order[lo + 1], order[lo + 2]) and starts_with_swap(
        tri, twin3, order[hi - 1], order[hi - 2], order[hi - 3]
    )
    return k + 2 + (cum[hi - 1] - cum[lo + 2]) + np.int64(both)


@kernel
def level_cuts_into(height, order, bounds, limit, out):
    """Piece offsets ``bounds`` (``(K + 1,)`` into ``order``) with a cut added wherever a
    piece's triangle ``height`` differs from that of the piece's (or the last cut's) first
    triangle by more than ``limit``; into ``out`` (``(len(order) + 1,)``), returns how many."""
    n = 0
    for p in range(bounds.shape[0] - 1):
        a, b = bounds[p], bounds[p + 1]
        out[n] = a
        n += 1
        ref = height[order[a]]
        for i in range(a + 1, b):
            h = height[order[i]]
            if abs(h - ref) > limit:
                out[n] = i
                n += 1
                ref = h
    out[n] = bounds[bounds.shape[0] - 1]
    return n + 1


@kernel
def move_cuts(tri, twin3, order, cum, bounds, movable, reach):
    """Move each ``movable`` cut of ``bounds`` (in place, left to right) by at most ``reach``
    positions to where its two pieces cost fewest indices (:func:`piece_cost`; on a tie the
    nearest, then the earlier position), keeping every piece non-empty.  Returns the
    indices saved."""
    saved = 0
    for j in range(1, bounds.shape[0] - 1):
        if not movable[j]:
            continue
        lo, c0, hi = bounds[j - 1], bounds[j], bounds[j + 1]
        best = c0
        best_cost = piece_cost(tri, twin3, order, cum, lo, c0) + piece_cost(tri, twin3, order, cum, c0, hi)
        base = best_cost
        for c in range(max(lo + 1, c0 - reach), min(hi - 1, c0 + reach) + 1):
            cost = piece_cost(tri, twin3, order, cum, lo, c) + piece_cost(tri, twin3, order, cum, c, hi)
            if cost < best_cost or (cost == best_cost and abs(c - c0) < abs(best - c0)):
                best, best_cost = c, cost
        bounds[j] = best
        saved += base - best_cost
    return saved


@kernel
def orient_pieces(tri, twin3, along, order, starts):
    """Reverse (in place) each piece that starts with a swap only in its current direction,
    and each piece that costs the same both ways but runs backwards along ``along`` (its last
    triangle's coordinate below its first's): rows sent the same way reuse the row before
    evenly.  Returns the number reversed."""
    flipped = 0
    for p in range(starts.shape[0] - 1):
        a, b = starts[p], starts[p + 1] - 1
        if b <= a:
            continue
        fw = False
        bw = False
        if b - a >= 2:
            fw = starts_with_swap(tri, twin3, order[a], order[a + 1], order[a + 2])
            bw = starts_with_swap(tri, twin3, order[b], order[b - 1], order[b - 2])
        if (fw and not bw) or (fw == bw and along[order[b]] < along[order[a]]):
            for i in range((b - a + 1) // 2):
                x = order[a + i]
                order[a + i] = order[b - i]
                order[b - i] = x
            flipped += 1
    return flipped


@loop_helper
def _along_chain(link, t, prev):
    """The chain neighbour of ``t`` that is not ``prev`` (-1 at an end); ``link`` ``(m, 2)``
    holds each triangle's (at most two) chain neighbours in either slot, -1 for none."""
    a = link[t, 0]
    return link[t, 1] if a == prev else a


@loop_helper
def chain_cost(tri, twin3, link, start):
    """:func:`piece_cost` of the chain of ``link`` that ends at ``start`` (walked from it)."""
    k = 0
    prev = np.int64(-1)
    cur = np.int64(start)
    swaps = 0
    last_pivot = np.int64(-1)
    t0 = t1 = t2 = np.int64(-1)
    a = b = c = np.int64(-1)
    while cur >= 0:
        nxt = np.int64(_along_chain(link, cur, prev))
        if prev >= 0 and nxt >= 0:
            pv = vertex_between(tri, cur, edge_to_neighbour(twin3, cur, prev), edge_to_neighbour(twin3, cur, nxt))
            if k >= 2 and pv == last_pivot:
                swaps += 1
            last_pivot = pv
        if k == 0:
            t0 = cur
        elif k == 1:
            t1 = cur
        elif k == 2:
            t2 = cur
        a, b, c = b, c, cur
        k += 1
        prev, cur = cur, nxt
    if k < 3:
        return k + 2
    both = starts_with_swap(tri, twin3, t0, t1, t2) and starts_with_swap(tri, twin3, c, b, a)
    return k + 2 + swaps + np.int64(both)


@kernel
def join_heading_pieces(tri, twin3, along, column, order, bounds, link, other, cost, size, short, out_order, out_bounds):
    """Join pieces of one column whose ends are dual neighbours, heading the same way along
    the rows, where the joined piece costs fewer indices than the two and a restart; returns
    how many pieces are left, written path after path into ``out_order`` / ``out_bounds``.

    ``column``: each triangle's column (a joined piece takes the larger piece's, written
    at its ends); ``along``: its centroid along the rows.  The ends are visited in
    ``order``'s order; a piece may join at both ends, and again once joined.  No U-turn:
    with both pieces of two or more triangles, the first must run towards the join along
    the rows and the second away from it (a U-turn would send the second row back over the
    first and reload its far side).  A piece of at most ``short`` triangles joins whatever
    the columns and headings.  Work arrays (``m`` triangles): ``link`` ``(m, 2)``,
    ``other``, ``cost``, ``size`` ``(m,)``.
    """
    m = order.shape[0]
    K = bounds.shape[0] - 1
    for i in range(m):
        link[i, 0] = -1
        link[i, 1] = -1
    for p in range(K):
        a, b = bounds[p], bounds[p + 1]
        for i in range(a, b - 1):
            link[order[i], 1] = order[i + 1]
            link[order[i + 1], 0] = order[i]
        other[order[a]] = order[b - 1]
        other[order[b - 1]] = order[a]
        size[order[a]] = b - a
        size[order[b - 1]] = b - a
    for p in range(K):
        c = chain_cost(tri, twin3, link, order[bounds[p]])
        cost[order[bounds[p]]] = c
        cost[order[bounds[p + 1] - 1]] = c
    for p in range(K):
        for end in range(2):
            e = order[bounds[p]] if end == 0 else order[bounds[p + 1] - 1]
            for k in range(3):
                if link[e, 0] >= 0 and link[e, 1] >= 0:
                    break  # no longer an end
                h = twin3[e, k]
                if h < 0:
                    continue
                u = h // 3
                if (link[u, 0] >= 0 and link[u, 1] >= 0) or other[e] == u:
                    continue
                fx, fy = other[e], other[u]
                tiny = min(size[e], size[u]) <= short
                if column[u] != column[e] and not tiny:
                    continue
                if fx != e and fy != u and (along[e] - along[fx]) * (along[fy] - along[u]) < 0 and not tiny:
                    continue  # a U-turn
                se = 0 if link[e, 0] < 0 else 1
                su = 0 if link[u, 0] < 0 else 1
                link[e, se] = u
                link[u, su] = e
                joined = chain_cost(tri, twin3, link, fx)
                if joined < cost[e] + cost[u] + 1:
                    col = column[e] if size[e] >= size[u] else column[u]
                    k = size[e] + size[u]
                    for end, far in ((fx, fy), (fy, fx)):  # the joined chain's figures, at both its ends
                        other[end] = far
                        cost[end] = joined
                        size[end] = k
                        column[end] = col
                else:
                    link[e, se] = -1
                    link[u, su] = -1
    # chains, in the order their first-met end appears in ``order``
    n = 0
    S = 0
    out_bounds[0] = 0
    for i in range(m):
        t = order[i]
        if (link[t, 0] >= 0 and link[t, 1] >= 0) or cost[t] < 0:
            continue
        prev = np.int64(-1)
        cur = np.int64(t)
        while cur >= 0:
            out_order[n] = cur
            n += 1
            cost[cur] = -1  # emitted
            nxt = np.int64(_along_chain(link, cur, prev))
            prev, cur = cur, nxt
        S += 1
        out_bounds[S] = n
    return S
