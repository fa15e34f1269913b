"""``encode(fast=True)`` in two halves on two threads, each proved as soon as it is written.

On one core the fast encoder's steps are serial and bound by cache misses in Triangle's
scattered numbering: the edge pairing, the greedy cover and the proof each touch every
triangle's neighbours at random.  Here the mesh is cut by a plane through the median
vertex along its longest axis (a row goes to the side of its least vertex index), and
each half runs on its own thread: its rows copied out cell by cell of a grid
(:func:`vertex_cells`: neighbouring triangles near each other in memory, which the
pairing and the greedy strips read at random), its face census, its edge pairing
straight into triangle records (:func:`~hammesh.strips._halves_kernels.pair_records_into`),
the one-pass greedy strips (:func:`~hammesh.strips._greedy_strip_kernels.greedy_strip_buffer`)
and the fingerprint of what its own part of the buffer draws
(:func:`~hammesh.strips._fingerprint_kernels.draws_fingerprint`), so the proof of one half
overlaps the encoding of the other.  The two buffers are joined by one restart index; the
halves' fingerprints must add up to the input rows' (each thread then takes half of the
input rows by their numbers, whichever half it encoded): the proof reads no claim of the
encoder (:mod:`hammesh.strips._fingerprint_kernels`).

A plane cuts few edges (0.18% of the dual edges of a q30 square at 100k triangles,
0.06% at 1M), so the halves' covers end only a few more paths than one cover would
(+0.001-0.002 indices per triangle; measured in ``docs/strips.md``).  The edges the
halves share are settled afterwards from each half's unpaired half-edges
(:func:`~hammesh.strips._halves_kernels.shared_edges`): if one is not a proper edge (a
non-manifold or flipped edge across the cut), or a half has such an edge or a row
repeating a vertex, or the dual graph may be a forest (fewer proper edges than
triangles: Lemma 5.1's cover applies), :func:`encode_in_halves` returns ``None`` and
:func:`~hammesh.strips.encode.encode` takes its one-thread path, which reports the
defects.
"""

from __future__ import annotations

import threading
import time
from collections import namedtuple
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.strips._dual_kernels import REC_TWIN, REC_WIDTH, count_pillows, face_flags, records_dtype
from hammesh.strips._fingerprint_kernels import draws_fingerprint, fingerprint_keys, rows_fingerprint_into
from hammesh.strips._greedy_strip_kernels import NO_SEED_ORDER, StripWork, greedy_strip_buffer
from hammesh.strips._halves_kernels import (
    pair_records_into,
    row_cells_into,
    rows_of_cells_into,
    shared_edges,
    vertex_cells_into,
)
from hammesh.strips.defects import ZERO_AREA_RTOL, MeshDefects
from hammesh.strips.gl import GLStrip, verify_gl_strip
from hammesh.strips.scratch import Scratch, borrow

__all__ = ["HALVES_FROM", "CELL_TRIANGLES", "VertexCells", "vertex_cells", "pillow_rows", "encode_in_halves"]

#: Triangles from which ``encode(fast=True)`` runs in two halves on two threads (and
#: ``hammesh.threads.cores()`` allows two); below, the copies and the second thread
#: cost more than they save.
HALVES_FROM = 50_000

#: A half with fewer than this fraction of the rows (points piled on the median): the
#: one-thread path instead.
_SMALLEST_HALF = 1 / 8

#: One half's result: its rows (numbers in its copy) in draw order, its part of the buffer, the
#: greedy strip's figures, and what the join needs (pairing buckets, unpaired half-edges,
#: census counts, the :class:`~hammesh.strips._fingerprint_kernels.DrawsFingerprint` of its
#: part or ``None``).  ``failed``: a reason to take the one-thread path.
_Half = namedtuple(
    "_Half",
    ["failed", "order", "indices", "n_strips", "n_swaps", "max_index", "start", "keys", "loose", "n_loose",
     "pairs", "zero_area", "pillows", "proof"],
)


#: Triangles per cell (about) of the grid a half's rows are copied in (:func:`vertex_cells`).
#: At 1M triangles on the development machine 1k-16k all gave greedy strips ~20% faster than
#: Triangle's order; larger cells cost fewer index gaps in the second pass of the copy.  Over
#: the whole two-halves call (critical path in thread CPU, A/B in one process, session 15),
#: 4,096 took 0.968-0.975 of 16,384's time at 1M (three runs of 10-14 rounds; 8,192 0.978-0.993,
#: 65,536 1.047, 262,144 1.093) and the same at 100k, for +0.0001-0.0002 indices per triangle.
CELL_TRIANGLES = 4_096

#: :func:`vertex_cells`'s result: each vertex's cell ``label`` (``(n,) uint16``, ``int32``
#: beyond 65,535 cells: half the bytes for the rows pass to look up), the first
#: label of side 1 (``split``), the number of cells and whether every coordinate is
#: finite (``finite``; if not, the labels mean nothing).
VertexCells = namedtuple("VertexCells", ["label", "split", "cells", "finite"])


def vertex_cells(points: np.ndarray, n_triangles: int, cell_triangles: int = CELL_TRIANGLES, pool=None) -> VertexCells:
    """The cut and the cells: side 1 beyond the median along the longest axis, each side a grid of
    square cells of ~``cell_triangles`` triangles (:func:`~hammesh.strips._halves_kernels.vertex_cells_into`).

    Axes, extents and the median come from a sample of ~4,000 points (neither the split
    nor the grid need be exact: points outside the sample's box go to the nearest cell).
    ``pool``: an executor whose thread labels the second half of the points meanwhile.
    """
    n = len(points)
    # one row per axis, contiguous: numpy's min and max along the rows of a narrow (k, 2)
    # array took ~65 us each (the same values in ~5 us this way; on the critical path)
    sample = np.ascontiguousarray(points[:: max(1, n // 4096)].T)
    lo = sample.min(axis=1)
    with np.errstate(over="ignore", invalid="ignore"):
        ext = sample.max(axis=1) - lo
        axes = np.argsort(ext, kind="stable")[::-1]
        a, b = int(axes[0]), int(axes[1])
        cut = float(np.median(sample[a]))
        cells = max(2, n_triangles // cell_triangles)
        h = max(float(np.sqrt(ext[a] * ext[b] / cells)), float(ext[a]) / cells)
        sizes = ((cut - lo[a]) / h, (lo[a] + ext[a] - cut) / h, ext[b] / h)
    if not (0 < h < np.inf and np.isfinite(sizes).all()):
        # one point, or coordinates whose differences overflow: one cell a side
        h, sizes = np.inf, (1, 1, 1)
    n0, n1, ny = (max(1, int(np.ceil(x))) for x in sizes)
    label = np.empty(n, np.uint16 if (n0 + n1) * ny <= 0xFFFF else np.int32)
    args = (a, b, cut, float(lo[a]), float(lo[b]), h, n0, n1, ny)
    if pool is None:
        finite = vertex_cells_into(points, *args, label)
    else:
        mid = n // 2
        other = pool.submit(vertex_cells_into, points[mid:], *args, label[mid:])
        finite = vertex_cells_into(points[:mid], *args, label[:mid])
        finite = other.result() and finite
    return VertexCells(label, n0 * ny, (n0 + n1) * ny, bool(finite))


def _half_work(k: int, out: np.ndarray | None, scratch: Scratch, side: int) -> StripWork:
    """:func:`~hammesh.strips._greedy_strip_kernels.strip_work` for a half from ``scratch``:
    new buffers in small pages, the part the call writes faulted in at once
    (:func:`~hammesh.strips.scratch.new_buffer`; the path and index offsets and the buffer
    are sized for the worst case, ~1/3 of them is written, the rest is never faulted in),
    but the bucket queue, used at random, in huge pages."""
    bucket = scratch.take(f"{side}.bucket", (4, k), np.int32, huge=True)  # then the proof's 3 k draws
    grow = scratch.take(f"{side}.grow", (2, k), np.int32, written=0)  # a path at a time
    big = scratch.take(f"{side}.big", 3 * k + 2, np.int64, written=1 / 3)  # the order; the offsets: one per path
    # the second half's part is copied into the whole buffer: its own can be kept
    out = scratch.take(f"{side}.out", 4 * k, np.int64, written=1 / 3) if out is None else out
    return StripWork(bucket, grow[0], grow[1], np.zeros(4, np.int32), big[:k], big[k : 2 * k + 1], big[2 * k + 1 :], NO_SEED_ORDER, out)


def _failed(reason: str) -> _Half:
    return _Half(reason, *([None] * (len(_Half._fields) - 1)))


class _Join:
    """The one-pass buffer of the whole mesh, shared by the halves: the first half writes its
    part at the head (``buffer``, made by it once it knows its size) and says how long it is
    (``first_len``, -1 if it failed; ``written`` set either way); the second half then
    places its own part after a restart index, on its own thread, and compares the copy
    (``placed``).  The copy so runs while the first half still fingerprints its part, not
    on the calling thread after both (~1.5 ms of the critical path at 1M triangles)."""

    def __init__(self) -> None:
        self.buffer: np.ndarray | None = None
        self.first_len = -1
        self.written = threading.Event()
        self.placed = False

    def place_second(self, indices: np.ndarray, restart: int) -> None:
        """Copy the second half's part after the first's and a restart (waits for the first)."""
        self.written.wait()
        la, lb = self.first_len, len(indices)
        if la < 0 or self.buffer is None or la + 1 + lb > len(self.buffer):
            return
        self.buffer[la] = restart
        self.buffer[la + 1 : la + 1 + lb] = indices
        self.placed = bool(np.array_equal(self.buffer[la + 1 : la + 1 + lb], indices))


def _timed_half(clock, key, *args):
    """:func:`_encode_half`, its thread CPU seconds written to ``clock[key]`` (when a dict)."""
    t = time.thread_time()
    try:
        return _encode_half(*args)
    finally:
        if clock is not None:
            clock[key] = time.thread_time() - t


def _encode_half(pts, tri, cells, row_label, counts, side, w_swap, restart, fp_keys, fp_rows, stop, scratch,
                 finish=None, join=None) -> _Half:
    """One half: rows in cell order, census, pairing, strips, the fingerprint of its part;
    then the fingerprint of input rows ``[0, m // 2)`` (side 0) or ``[m // 2, m)`` (side 1)
    into ``fp_rows[0]``.

    ``row_label``, ``counts``: each input row's cell and the rows of each cell
    (:func:`~hammesh.strips._halves_kernels.row_cells_into`).
    ``fp_keys``: the fingerprint's keys (:func:`~hammesh.strips._fingerprint_kernels.fingerprint_keys`),
    ``None``: no proof.

    ``finish``: ``None`` for the one-pass greedy strips, or the encoder
    ``(points, rows, records, twin) -> (indices, order, n_strips, n_swaps)`` of the
    default mode (:func:`hammesh.strips.encode.encode`'s cover, end moves and writer).
    ``join`` (one-pass only): the :class:`_Join` of the whole buffer, whose head side 0
    writes (and proves) in place and after which side 1 places its part.  ``scratch``:
    where the work arrays come from (:mod:`hammesh.strips.scratch`; roles named by ``side``).
    """
    try:
        h = _encode_half_work(pts, tri, cells, row_label, counts, side, w_swap, restart, fp_keys, fp_rows, stop,
                              scratch, finish, join)
    finally:
        if join is not None and side == 0:
            join.written.set()  # also when this half failed or raised: the other never waits forever
    if join is not None and side == 1 and not h.failed:
        join.place_second(h.indices, restart)
    return h


def _encode_half_work(pts, tri, cells, row_label, counts, side, w_swap, restart, fp_keys, fp_rows, stop, scratch,
                      finish, join) -> _Half:
    """:func:`_encode_half` but for the second half's placing."""
    m, n = len(tri), len(pts)
    first, last = (0, cells.split) if side == 0 else (cells.split, cells.cells)
    take = scratch.take
    # sized for any split, about half of each written (``written``: faulted in at once)
    mine = counts[first:last]
    k = int(mine.sum())
    if k < _SMALLEST_HALF * m:
        stop[0] = True
        return _failed("unbalanced")
    part = take(f"{side}.part", (m, 3), np.int32, written=1 / 2)[:k]  # int32 records (checked by the caller): half the bytes
    offsets = np.zeros(last - first, np.int64)
    np.cumsum(mine[:-1], out=offsets[1:])
    rows_of_cells_into(tri, row_label, first, last, offsets, part)
    if stop[0]:
        return _failed("the other half failed")
    n_zero = face_flags(pts, part, ZERO_AREA_RTOL, take(f"{side}.flags", m, np.int8, written=1 / 2)[:k])[1]
    start = take(f"{side}.start", n + 1, np.int32)
    keys = take(f"{side}.keys", 3 * k, np.int64, huge=True)  # read and written at random: huge pages
    rec = take(f"{side}.rec", (k, REC_WIDTH), np.int32, huge=True)
    loose = take(f"{side}.loose", (3 * k, 2), np.int64, written=0)  # the edges on the cut and the boundary
    paired = pair_records_into(part, start, take(f"{side}.mark", n, np.int32), keys, rec, loose)
    if paired.pairs < 0 or stop[0]:
        stop[0] = True
        return _failed("an edge is not proper")
    if finish is not None:
        pillows = int(count_pillows(rec))
        twin = rec[:, REC_TWIN : REC_TWIN + 3].astype(np.int64).reshape(-1)  # one copy (C order), not two
        indices, local, n_strips, n_swaps = finish(pts, part.astype(np.int64), rec, twin)
        max_index = -1  # the writer checked the restart index itself
    else:
        head = join is not None and side == 0
        if head:
            # bound of the whole buffer: this half's 4 k, a restart, the other half's 4 (m - k)
            join.buffer = np.empty(4 * m + 1, np.int64)
        work = _half_work(k, join.buffer[: 4 * k] if head else None, scratch, side)
        g = greedy_strip_buffer(rec, w_swap, restart, work)
        indices, local, n_strips, n_swaps, max_index = g.indices, g.order, len(g.starts) - 1, g.n_swaps, g.max_index
        if head:  # its part is final: the second half may place its own after it
            join.first_len = len(indices)
            join.written.set()
        pillows = pillow_rows(rec, g.order, g.starts)
    # what this part draws, decoded from the buffer alone (no claim of the encoder read)
    proof = None
    if fp_keys is not None:
        proof = draws_fingerprint(indices, restart, True, fp_keys)
        # half of the input rows, by their numbers: the halves' selection of rows is the
        # encoder's, and a row both left out would not be missed in their own rows
        mid = m // 2
        rows_fingerprint_into((tri[:mid] if side == 0 else tri[mid:]).reshape(-1), fp_keys, fp_rows)
    return _Half(None, local, indices, n_strips, n_swaps, max_index, start, keys, loose,
                 int(paired.n_loose), int(paired.pairs), int(n_zero), pillows, proof)


def pillow_rows(rec: np.ndarray, order: np.ndarray, starts: np.ndarray) -> int:
    """Rows whose three edges all lead to one other triangle (the two sides of a closed
    two-triangle piece), found among the paths of two triangles of a greedy cover.

    Such a pair has no other neighbour, and the greedy growth never stops at a free
    neighbour, so each pair is one path of its own: the few paths of two are all that
    need a look (:func:`~hammesh.strips._dual_kernels.count_pillows` reads every record,
    ~2 ms a half at 1M triangles).  ``rec``: the records (twin columns), ``order`` and
    ``starts``: the cover in their numbering.
    """
    a = starts[:-1][np.diff(starts) == 2]
    t, u = order[a], order[a + 1]
    return 2 * int(np.count_nonzero((rec[t, REC_TWIN : REC_TWIN + 3] // 3 == u[:, None]).all(axis=1)))


def _plain_arrays(points, triangles) -> tuple[np.ndarray, np.ndarray] | None:
    """``float64`` ``(n, 2 | 3)`` points and ``int64`` ``(m, 3)`` rows, C-contiguous (copied
    only if they are not), or ``None`` for anything else (the one-thread path's checks
    then name it).  Finite coordinates and indices in range are checked by the kernels."""
    pts = np.asarray(points)
    tri = np.asarray(triangles)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or len(pts) == 0:
        return None
    if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0 or not np.issubdtype(tri.dtype, np.integer):
        return None
    return np.ascontiguousarray(pts, dtype=np.float64), np.ascontiguousarray(tri, dtype=np.int64)


def encode_in_halves(
    points, triangles, restart: int, verify: bool, w_swap: int, finish=None, clock: dict | None = None,
    pooled: bool = True,
) -> GLStrip | None:
    """A restart-joined buffer from two halves on two threads, or ``None``.

    ``finish``: ``None`` for ``encode(fast=True)``'s one-pass greedy strips, else the
    default mode's encoder of one half (see :func:`_encode_half`).  ``clock``: a dict
    that receives each half's thread CPU seconds (``"first"`` on the calling thread,
    ``"second"`` on the other), for benchmarks on a loaded machine.  ``pooled``: take the
    work arrays from :mod:`hammesh.strips.scratch`'s pool and give them back (``False``:
    arrays of its own; :func:`hammesh.strips.warm.prepare`'s small grid, which must not
    take a large call's kept arrays from under it).

    ``points``, ``triangles``: the mesh's arrays as given.  Only the cheap checks run
    here (shapes, integer rows; ``float64`` / ``int64`` contiguous copies where needed);
    the kernels that first read every point and row check that the coordinates are
    finite (:func:`~hammesh.strips._halves_kernels.vertex_cells_into`) and that every
    index is in range (:func:`~hammesh.strips._halves_kernels.row_cells_into`, before
    it uses one): the passes :func:`hammesh.halfedge.mesh_arrays` would spend on them
    (~5 ms at 1M triangles, on the critical path) are saved.  Anything wrong gives
    ``None``, and the one-thread path's :func:`~hammesh.halfedge.mesh_arrays` names the
    problem.  The buffer draws every row once with its winding; with ``verify`` each
    half's part is proved against the rows on its thread, and every row must be drawn by
    one of them (a failed claim falls back to :func:`~hammesh.strips.gl.verify_gl_strip`'s
    full comparison, which names the problem).  ``None`` when the one-thread path must
    decide (see the module docstring).
    """
    arrays = _plain_arrays(points, triangles)
    if arrays is None:
        return None
    pts, tri = arrays
    m, n = len(tri), len(pts)
    if records_dtype(m, n) is not np.int32:
        return None
    if not pooled:  # work arrays of its own, the pool left alone
        return _joined_halves(pts, tri, restart, verify, w_swap, finish, clock, Scratch({}))
    scratch = borrow()
    try:
        return _joined_halves(pts, tri, restart, verify, w_swap, finish, clock, scratch)
    finally:
        scratch.give_back()  # nothing returned lives in the kept arrays


def _joined_halves(pts, tri, restart, verify, w_swap, finish, clock, scratch) -> GLStrip | None:
    """:func:`encode_in_halves` on checked arrays, its work arrays taken from ``scratch``."""
    m = len(tri)
    keys = fingerprint_keys() if verify else None
    fingerprint = np.zeros(2, np.uint64)  # the input rows', a half of them on each thread
    stop = np.zeros(1, np.bool_)
    join = None if finish else _Join()
    with ThreadPoolExecutor(1) as pool:
        cells = vertex_cells(pts, m, pool=pool)
        if not cells.finite:
            return None
        # each row's cell, half the rows on each thread (each half then scans the labels,
        # not all the input rows); a bad row (an index out of range, a repeated vertex):
        # the one-thread path names it
        row_label = scratch.take("row_label", m, cells.label.dtype)
        mid = m // 2
        counts = np.zeros((2, cells.cells), np.int64)  # rows of each cell, on each thread
        other = pool.submit(row_cells_into, tri[mid:], cells.label, row_label[mid:], counts[1])
        if min(row_cells_into(tri[:mid], cells.label, row_label[:mid], counts[0]), other.result()) < 0:
            return None
        counts = counts[0] + counts[1]
        second = pool.submit(_timed_half, clock, "second", pts, tri, cells, row_label, counts, 1, w_swap, restart,
                             keys, fingerprint[1:], stop, scratch, finish, join)
        a = _timed_half(clock, "first", pts, tri, cells, row_label, counts, 0, w_swap, restart, keys, fingerprint[:1],
                        stop, scratch, finish, join)
        b = second.result()
    if a.failed or b.failed:
        return None
    ab = shared_edges(a.loose, a.n_loose, b.start, b.keys)
    ba = shared_edges(b.loose, b.n_loose, a.start, a.keys)
    if not (ab.ok and ba.ok) or a.pairs + b.pairs + ab.proper < m:
        return None  # a defect across the cut, or maybe a dual forest: the one-thread path
    la, lb = len(a.indices), len(b.indices)
    placed = join is not None and join.placed  # the second half placed its part itself
    if join is not None:
        indices = join.buffer[: la + lb + 1]  # the first half's part is in place
    else:
        indices = np.empty(la + lb + 1, np.int64)
        indices[:la] = a.indices
    if not placed:
        indices[la] = restart
        indices[la + 1 :] = b.indices
    S = a.n_strips + b.n_strips
    if 0 <= restart <= max(a.max_index, b.max_index) and np.count_nonzero(indices == restart) != S - 1:
        raise InvalidOptionError(f"restart index {restart} is a vertex index of the mesh")
    if verify:
        # each half's draws were fingerprinted where they were written (the first in place
        # with the one-pass writer): m draws whose hashes add up to the input rows', and
        # the copies equal; otherwise the full comparison names the problem
        drawn = (int(a.proof.sum) + int(b.proof.sum)) % 2**64  # the kernels sum modulo 2**64
        rows = (int(fingerprint[0]) + int(fingerprint[1])) % 2**64
        proved = a.proof.count + b.proof.count == m and drawn == rows and indices[la] == restart
        copied = (placed or np.array_equal(indices[la + 1 :], b.indices)) and (
            join is not None or np.array_equal(indices[:la], a.indices))
        if not (proved and copied):
            verify_gl_strip(tri, indices, restart)
    defects = MeshDefects(repeated_vertex=0, zero_area=a.zero_area + b.zero_area, double_sided=(a.pillows + b.pillows) // 2)
    return GLStrip(indices, restart, m, S, a.n_swaps + b.n_swaps, defects=defects)
