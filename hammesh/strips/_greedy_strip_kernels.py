"""Compiled one-pass greedy strips: cover, direction and restart-joined emission, path by path.

``encode(mesh, fast=True)`` used to make three passes over the mesh in path order: the
greedy cover (:func:`~hammesh.strips._cover_kernels.greedy_path_cover`), the choice of
each path's direction (:func:`~hammesh.strips._path_kernels.orient_paths`) and the
writer (:func:`~hammesh.strips._emit_kernels.restart_buffer`).  Triangle's numbering is
scattered, so each of them missed the cache at almost every triangle (at 1M triangles
~0.3 s each).  Here each path is turned and written as soon as it is grown, while its
records are still in the cache: the same buffer, index for index (a test compares),
for the price of the cover alone.

meshoptimizer's stripifier (``src/stripifier.cpp``, github.com/zeux/meshoptimizer) is
fast for the same reason: it writes each strip while it walks it, looking only at a
small window of triangles.  It builds no adjacency, so on scattered rows its strips are
short; we keep the global greedy cover (fewest free neighbours first) and borrow only
the write-as-you-walk.  Our code.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.strips._cover_kernels import grow_path, pop_fewest_free, queue_free_degrees, take_triangle
from hammesh.strips._dual_kernels import REC_TWIN
from hammesh.strips._numba import NEXT_CORNER, kernel, loop_helper
from hammesh.strips._path_kernels import vertex_between

__all__ = ["GreedyStrip", "StripWork", "strip_work", "greedy_strip_buffer"]

#: :func:`greedy_strip_buffer`'s result: the buffer ``indices``; the rows in draw order
#: ``order`` with the path offsets ``starts``; ``index_starts[s]``, where path ``s``'s
#: first index is in ``indices`` (after its restart); swaps written; the largest vertex
#: index written.
GreedyStrip = namedtuple("GreedyStrip", ["indices", "order", "starts", "index_starts", "n_swaps", "max_index"])


@loop_helper
def _edge_to(rec, t, u):
    """Local edge of ``t`` whose twin is in triangle ``u`` (records' twin columns), or -1."""
    e0 = np.int64(rec[t, REC_TWIN] // 3 == u)  # a boundary's -1 // 3 is -1: never u
    e1 = np.int64(rec[t, REC_TWIN + 1] // 3 == u)
    e2 = np.int64(rec[t, REC_TWIN + 2] // 3 == u)
    return (1 - e0) * (e1 + (1 - e1) * (3 * e2 - 1))


@loop_helper
def _swap_after_first(rec, a, b, c):
    """Does a path starting ``a, b, c`` need a swap after ``a``?  (Its exit tail is ``b``'s pivot.)"""
    kab = _edge_to(rec, a, b)
    kba = _edge_to(rec, b, a)
    kbc = _edge_to(rec, b, c)
    return rec[a, kab] == vertex_between(rec, b, kba, kbc)


@loop_helper
def _write_path(rec, order, a, b, out, pos):
    """Write path ``order[a:b]`` at ``out[pos]``; returns ``(new pos, swaps, largest index)``.

    Head: the first triangle's vertex opposite its exit edge, then the exit half-edge's
    tail and head (so the first triangle keeps its winding at an even position); then one
    new vertex per triangle, preceded by the previous pivot where two pivots coincide.
    """
    t = order[a]
    mx = max(rec[t, 0], rec[t, 1], rec[t, 2])
    if b - a == 1:
        for j in range(3):
            out[pos + j] = rec[t, j]
        return pos + 3, 0, mx
    k = _edge_to(rec, t, order[a + 1])
    out[pos] = rec[t, (k + 2) % 3]
    out[pos + 1] = rec[t, k]
    out[pos + 2] = rec[t, NEXT_CORNER[k]]
    pos += 3
    prev_pivot = rec[t, k]
    swaps = 0
    for i in range(a + 1, b):
        u = order[i]
        kin = rec[t, REC_TWIN + k] - 3 * u
        v = rec[u, (kin + 2) % 3]
        if i < b - 1:
            kout = _edge_to(rec, u, order[i + 1])
            p = rec[u, kout if kout == NEXT_CORNER[kin] else kin]
            # a swap (two equal pivots) in ~1 of 5 positions: written always, kept by
            # advancing or not (a branch here would be mispredicted at every swap)
            sw = np.int64(p == prev_pivot)
            out[pos] = prev_pivot
            pos += sw
            swaps += sw
            prev_pivot = p
            k = kout
        out[pos] = v
        pos += 1
        mx = max(mx, v)
        t = u
    return pos, swaps, mx


#: :func:`strip_work`'s arrays: the bucket queue and the two growth buffers (the records'
#: dtype), the draw order, path offsets and index offsets, the seed order (``m - 1``
#: down to 0) and the index buffer.
StripWork = namedtuple("StripWork", ["bucket", "fwd", "bwd", "top", "order", "starts", "index_starts", "seeds", "out"])


def strip_work(m: int, dtype) -> StripWork:
    """Work arrays of :func:`greedy_strip_buffer` for ``m`` triangles, pages faulted in now.

    Made on a second thread while the first pairs the edges (``encode(fast=True)``):
    ~15 bytes per triangle of new memory that the cover would otherwise fault in page by
    page (:func:`hammesh.pages.fresh`).
    """
    from hammesh.pages import fresh

    small = fresh(4 * m + 2 * m + 4, dtype)
    bucket, fwd, bwd, top = small[: 4 * m].reshape(4, m), small[4 * m : 5 * m], small[5 * m : 6 * m], small[6 * m :]
    big = fresh(4 * m + 3, np.int64)
    order, starts, index_starts, seeds = big[:m], big[m : 2 * m + 1], big[2 * m + 1 : 3 * m + 2], big[3 * m + 2 :]
    seeds[:m] = np.arange(m - 1, -1, -1)
    # bound: a path of k >= 2 triangles writes at most 2 k indices (k + 2 and at most
    # k - 2 swaps), one of 1 triangle 3; plus a restart before each path but the first
    return StripWork(bucket, fwd, bwd, top, order, starts, index_starts, seeds[:m], fresh(4 * m, np.int64))


def greedy_strip_buffer(rec, w_swap, restart, work: StripWork | None = None) -> GreedyStrip:
    """The greedy cover's restart-joined GL buffer in one pass (:class:`GreedyStrip`).

    Paths exactly as :func:`~hammesh.strips._cover_kernels.greedy_path_cover` makes them
    with seeds ``m - 1, ..., 0`` (``rec``'s scratch column is overwritten), each reversed
    where :func:`~hammesh.strips._path_kernels.orient_paths` would reverse it, written as
    :func:`~hammesh.strips._emit_kernels.restart_buffer` writes it.  ``restart`` is
    written between paths; the caller checks it is no vertex index (``max_index``).
    ``work``: :func:`strip_work` ``(m, rec.dtype)``, made here if not given.
    """
    w = strip_work(rec.shape[0], rec.dtype) if work is None else work
    S, n, n_swaps, mx = _greedy_strip_into(
        rec, w_swap, w.seeds, restart, w.bucket, w.fwd, w.bwd, w.top, w.order, w.starts, w.index_starts, w.out
    )
    return GreedyStrip(w.out[:n], w.order, w.starts[: S + 1], w.index_starts[:S], int(n_swaps), int(mx))


@kernel
def _greedy_strip_into(rec, w_swap, seed_order, restart, bucket, fwd, bwd, top, order, starts, index_starts, out):
    queue_free_degrees(rec, seed_order, bucket, top)
    L = 0
    S = 0
    pos = 0
    n_swaps = 0
    mx = -1
    starts[0] = 0
    while True:
        seed = pop_fewest_free(rec, bucket, top)
        if seed < 0:
            break
        take_triangle(seed, rec, bucket, top)
        a = L
        fw = grow_path(seed, -1, -1, rec, bucket, top, fwd, w_swap)
        nbk = 0
        if fw.count > 0:
            # the triangle after the seed: its pivot is what the seed's turn must avoid
            p1 = -1
            if fw.count >= 2:
                u = fwd[0]
                ein = rec[seed, REC_TWIN + fw.first_exit] - 3 * u
                eout = -1
                for k in range(3):  # the last edge towards fwd[1], as the cover kernel finds it
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
        b = L - 1
        # the better direction: only the swap after the first triangle depends on it
        if b - a >= 2 and _swap_after_first(rec, order[a], order[a + 1], order[a + 2]):
            if not _swap_after_first(rec, order[b], order[b - 1], order[b - 2]):
                for i in range((b - a + 1) // 2):
                    x = order[a + i]
                    order[a + i] = order[b - i]
                    order[b - i] = x
        if S > 0:
            out[pos] = restart
            pos += 1
        index_starts[S] = pos
        pos, sw, top_v = _write_path(rec, order, a, L, out, pos)
        n_swaps += sw
        mx = max(mx, top_v)
        S += 1
        starts[S] = L
    return S, pos, n_swaps, mx
