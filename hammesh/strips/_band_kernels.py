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

__all__ = ["equal_pivots_into", "piece_cost", "level_cuts_into", "move_cuts", "orient_pieces"]


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
