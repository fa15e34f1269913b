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

The helpers it inlines (:func:`~hammesh.strips._cover_kernels.grow_both_ways`,
:func:`~hammesh.strips._emit_kernels.write_path`) index with unsigned row numbers
(:data:`~hammesh.strips._numba.row`).  numba's cache of this module does not notice
an edit of theirs: change this file too (this note) when they change, or its cached
kernel keeps the old code (session 15: ``queue_free_degrees`` takes each degree as it queues the row).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.strips._cover_kernels import grow_both_ways, pop_fewest_free, queue_free_degrees
from hammesh.strips._dual_kernels import REC_TWIN
from hammesh.strips._emit_kernels import write_path
from hammesh.strips._numba import kernel
from hammesh.strips._path_kernels import turn_path_if_better

__all__ = ["GreedyStrip", "StripWork", "NO_SEED_ORDER", "strip_work", "greedy_strip_buffer"]

#: The greedy strips' seed order: empty, read as ``m - 1, ..., 0``.
NO_SEED_ORDER = np.empty(0, np.int64)

#: :func:`greedy_strip_buffer`'s result: the buffer ``indices``; the rows in draw order
#: ``order`` with the path offsets ``starts``; ``index_starts[s]``, where path ``s``'s
#: first index is in ``indices`` (after its restart); swaps written; the largest vertex
#: index written.
GreedyStrip = namedtuple("GreedyStrip", ["indices", "order", "starts", "index_starts", "n_swaps", "max_index"])


#: :func:`strip_work`'s arrays: the bucket queue and the two growth buffers (the records'
#: dtype), the draw order, path offsets and index offsets, the seed order (empty:
#: ``m - 1`` down to 0, :func:`~hammesh.strips._cover_kernels.queue_free_degrees`) and the
#: index buffer.
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
    big = fresh(3 * m + 2, np.int64)
    order, starts, index_starts = big[:m], big[m : 2 * m + 1], big[2 * m + 1 :]
    # bound: a path of k >= 2 triangles writes at most 2 k indices (k + 2 and at most
    # k - 2 swaps), one of 1 triangle 3; plus a restart before each path but the first
    return StripWork(bucket, fwd, bwd, top, order, starts, index_starts, NO_SEED_ORDER, fresh(4 * m, np.int64))


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
        rec, rec[:, REC_TWIN : REC_TWIN + 3], w_swap, w.seeds, restart, w.bucket, w.fwd, w.bwd, w.top, w.order, w.starts, w.index_starts, w.out
    )
    return GreedyStrip(w.out[:n], w.order, w.starts[: S + 1], w.index_starts[:S], int(n_swaps), int(mx))


@kernel
def _greedy_strip_into(rec, twin3, w_swap, seed_order, restart, bucket, fwd, bwd, top, order, starts, index_starts, out):
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
        a = L
        L = grow_both_ways(seed, rec, bucket, top, fwd, bwd, order, L, w_swap)
        turn_path_if_better(rec, twin3, order, a, L - 1)
        if S > 0:
            out[pos] = restart
            pos += 1
        index_starts[S] = pos
        w = write_path(rec, twin3, order, a, L, out, pos)
        pos = w.pos
        n_swaps += w.swaps
        mx = max(mx, w.max_index)
        S += 1
        starts[S] = L
    return S, pos, n_swaps, mx
