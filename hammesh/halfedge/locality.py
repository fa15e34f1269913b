"""Triangles and vertices renumbered along a space-filling curve (issue 13, session 10).

Triangle numbers its triangles and vertices in the order its refinement made them:
a triangle's neighbours sit a median ~5,600 rows apart at 1.5 M triangles, so every
pass that reads a triangle's neighbours (the cover's matching and searches, judging
edges, the output walk) or a row's corners misses the cache at almost every read.
:func:`renumber_local` renumbers a mesh once so that triangles near each other in
the plane are near each other in memory: the rows in Hilbert-curve order of the grid
cell holding their centroid (a counting sort by cell, stable inside a cell), the
vertices in order of first use by the new rows. A construction runs on the
renumbered arrays and maps its output back (``triangle_order``, ``vertex_order``).

The cells are a uniform grid over the points' bounding box with
``TRIANGLES_PER_CELL`` to 4 x that many triangles a cell on average (``cell_bits``);
a cell's triangles keep their relative order, so a graded mesh's dense cells stay
as local as Triangle made them. The Hilbert keys of the cells come from a table
(:func:`cell_grid`), each triangle's key from its centroid's cell (:func:`cell_keys`,
or the validation's orientation pass, which reads the corners anyway:
``prepare_mesh(cells=True)``).

Measured at 1.5 M triangles (Triangle, square with a hole, q30): neighbours a median
5,653 rows apart (p90 58,010) before, 4 (p90 65) after; sparse mode's whole first
call 2.603 -> 2.403 s CPU, the renumbering and mapping back 0.14 s of it
(docs/sparse.md, "Session 10"). The Hilbert curve's construction follows Hamilton,
*Compact Hilbert indices* (Dalhousie CS-2006-07), in Wikipedia's ``xy2d`` form.
"""

from __future__ import annotations

import math
import threading
from typing import NamedTuple

import numpy as np

from hammesh import threads
from hammesh.halfedge import _kernels
from hammesh.pages import fresh
from hammesh.threads import row_ranges, run_all

__all__ = ["Renumbered", "CellGrid", "CellKeys", "renumber_local", "renumber_from_neighbors", "cell_order", "cell_grid",
           "hilbert_table", "grid_frame", "cell_keys", "empty_cell_keys", "restore_vertices", "cell_bits",
           "TRIANGLES_PER_CELL", "MAX_CELL_BITS"]

#: average triangles per grid cell of the order (a cell's triangles keep their order)
TRIANGLES_PER_CELL = 4
#: at most ``2**MAX_CELL_BITS`` cells a side (a histogram of ``4**bits`` entries per thread)
MAX_CELL_BITS = 10


class Renumbered(NamedTuple):
    """Result of :func:`renumber_local`: a mesh renumbered for locality."""

    points: np.ndarray  # (n, d) float64, new vertex j is old vertex_order[j]
    triangles: np.ndarray  # (m, 3) int64, new row i is old row triangle_order[i], in new vertex numbers
    twin: np.ndarray  # (3 m,) int64 half-edge twins in the new numbering (-1 boundary)
    marks: np.ndarray  # (3 m,) bool per half-edge marks carried along (empty if none given)
    triangle_order: np.ndarray  # (m,) int64 old row of each new row
    vertex_order: np.ndarray  # (n,) int64 old vertex of each new vertex


def cell_bits(m: int) -> int:
    """Bits per axis of the grid: ``TRIANGLES_PER_CELL`` to 4 x that many triangles a
    cell (512 x 512 cells at 1.5 M triangles, 5.8 a cell)."""
    cells = max(1, m // TRIANGLES_PER_CELL)
    return int(min(MAX_CELL_BITS, max(1, math.floor(0.5 * math.log2(cells)))))


class CellGrid(NamedTuple):
    """The grid of :func:`cell_order`: cells of ``1 / scale`` from ``(x0, y0)``, ``2**bits``
    a side, ``table[x << bits | y]`` the Hilbert key of cell ``(x, y)``."""

    x0: float
    y0: float
    scale: float
    bits: int
    table: np.ndarray


class CellKeys(NamedTuple):
    """Each triangle's cell key and the keys' histogram per row range (:func:`cell_keys`)."""

    key: np.ndarray  # (m,) int64; :func:`cell_order` overwrites it with the inverse order
    count: np.ndarray  # (ranges, 4**bits) int64; :func:`cell_order` overwrites it with the sort's slots
    spans: list  # the row ranges, [(lo, hi), ...]


#: cells of the Hilbert table per thread below which it is made in one call
TABLE_MIN_CELLS = 32_768
#: :func:`renumber_local`: the thread of the serial vertex pass also renumbers the first
#: ``1 / VERTEX_SIDE_SHARE`` of the rows' twins (the other thread the rest), so both
#: finish together (at 1.5 M: vertices 0.032 s, twins 0.044 s on one thread)
VERTEX_SIDE_SHARE = 8


def grid_frame(points: np.ndarray, m: int, ranges: tuple[list[float], list[float]] | None = None
               ) -> tuple[float, float, float, int]:
    """``(x0, y0, scale, bits)`` of :func:`cell_grid` without its Hilbert table: cell
    ``(int((x - x0) * scale), int((y - y0) * scale))`` (clamped to ``2**bits - 1``) of a
    point, for code that needs only the cells (the cover's quadrant cut).
    ``ranges``: the points' column ranges ``(lo, hi)``, if the caller has them
    (``hammesh.domain.validate.column_ranges``; the validation's)."""
    pts = np.asarray(points)
    bits = cell_bits(m)
    if ranges is None:
        ranges = ([float(pts[:, 0].min()), float(pts[:, 1].min())], [float(pts[:, 0].max()), float(pts[:, 1].max())])
    (x0, y0), (x1, y1) = ranges[0][:2], ranges[1][:2]
    side = max(x1 - x0, y1 - y0)
    return x0, y0, (1 << bits) / side if side > 0 else 0.0, bits


_tables: dict[int, np.ndarray] = {}
_tables_lock = threading.Lock()


def hilbert_table(bits: int) -> np.ndarray:
    """``table[x << bits | y]``: the Hilbert key of cell ``(x, y)`` of the ``2**bits`` a
    side grid, made once per process and size and shared (callers must not write
    into it; at most ``MAX_CELL_BITS + 1`` tables, 8 MB for the largest).

    Why kept: the table depends on the size only, and making it is ~3 ms of the
    validation's critical path at 1.5 M triangles (both cores, 512 x 512 cells): a
    process that expects a mesh can make it while it waits (``quality_mesh`` while
    Triangle runs), and a second call never pays it."""
    bits = int(bits)
    with _tables_lock:
        table = _tables.get(bits)
    if table is None:
        table = np.empty(1 << (2 * bits), np.int64)
        # (a cell's key is a chain of ``bits`` steps, ~20 ns, a triangle row's pass ~5 ns:
        # threads from TABLE_MIN_CELLS cells each; 512 x 512 cells ran serially before, 6 ms)
        run_all([
            (lambda lo=lo, hi=hi: _kernels.hilbert_table_into(bits, table, lo, hi))
            for lo, hi in row_ranges(1 << bits, max(1, TABLE_MIN_CELLS >> bits))
        ])
        with _tables_lock:
            table = _tables.setdefault(bits, table)
    return table


def cell_grid(points: np.ndarray, m: int, ranges: tuple[list[float], list[float]] | None = None) -> CellGrid:
    """The grid over ``points``' bounding box for ``m`` triangles (:func:`cell_bits`);
    ``ranges`` as :func:`grid_frame`'s. Its table is :func:`hilbert_table`'s (shared)."""
    x0, y0, scale, bits = grid_frame(points, m, ranges)
    return CellGrid(x0, y0, scale, bits, hilbert_table(bits))


def empty_cell_keys(grid: CellGrid, m: int) -> CellKeys:
    """Arrays for the keys of ``m`` triangles on ``grid``, over this process's row ranges
    (to be filled by a pass that reads the corners anyway: ``orient_ccw(cells=...)``)."""
    spans = row_ranges(m, threads.THREAD_MIN_ROWS)
    return CellKeys(fresh(m, np.int64), np.zeros((len(spans), len(grid.table)), np.int64), spans)


def cell_keys(points: np.ndarray, triangles: np.ndarray, grid: CellGrid | None = None) -> CellKeys:
    """Every triangle's cell key (its centroid's cell on ``grid``, default :func:`cell_grid`)."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    g = cell_grid(pts, len(tri)) if grid is None else grid
    keys = empty_cell_keys(g, len(tri))
    run_all([
        (lambda r=r, lo=lo, hi=hi: _kernels.cell_keys_into(
            pts, tri, g.x0, g.y0, g.scale, g.bits, g.table, keys.key, keys.count[r], lo, hi))
        for r, (lo, hi) in enumerate(keys.spans)
    ])
    return keys


def cell_order(
    points: np.ndarray, triangles: np.ndarray, keys: CellKeys | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Triangles in Hilbert order of the grid cell of their centroid: ``(order, inverse)``.

    ``order[i]`` is the triangle taking place ``i``; ``inverse[t]`` the place of ``t``.
    A counting sort by cell (each thread counts and places its own row range, so the
    order inside a cell is the input's whatever the number of threads). Planar
    (``points`` (n, 2)); the centroid's first two coordinates otherwise. ``keys``:
    the keys found already (:func:`cell_keys` or a pass that filled
    :func:`empty_cell_keys`); their ``key`` array becomes ``inverse``, their ``count``
    the sort's slots (both consumed).
    """
    m = len(triangles)
    order = fresh(m, np.int64)
    if m == 0:
        return order, np.zeros(0, np.int64)
    if keys is None:
        keys = cell_keys(points, triangles)
    key, place, spans = keys
    # each range's first slot of each key: keys in order, ranges in order inside a key
    _kernels.first_slots_in_place(place)  # (the histogram is not needed after it)
    run_all([
        (lambda r=r, lo=lo, hi=hi: _kernels.scatter_by_key_into(key, place[r], order, lo, hi))
        for r, (lo, hi) in enumerate(spans)
    ])
    return order, key  # (the keys' array holds the inverse now)


def renumber_local(
    points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, marks: np.ndarray | None = None,
    keys: CellKeys | None = None, room: tuple[int, int] = (0, 0),
) -> Renumbered:
    """The mesh renumbered for locality: rows in :func:`cell_order`, vertices by first use.

    Parameters
    ----------
    points : (n, d) float64
    triangles : (m, 3) int64
    twin : (3 m,) int64
        Half-edge twins (``h = 3 t + k``), -1 on the boundary.
    marks : (3 m,) bool, optional
        Per half-edge flags to carry along (constrained edges).
    keys : CellKeys, optional
        The triangles' cell keys if a pass found them already (``prepare_mesh(...,
        cells=True)``: ``info["validated"]["cells"]``); consumed.
    room : (int, int)
        Rows of memory to leave after the new triangles (and their twins and marks)
        and after the new points: the arrays returned are the first ``m`` (``n``) rows
        of buffers that long, so that a construction that appends a few rows later
        (sparse mode's ring fans, its Steiner points) can grow them in place.

    Returns
    -------
    Renumbered
        The same mesh: row ``i`` is old row ``triangle_order[i]`` with its corners in
        the same rotation (so half-edge ``3 i + k`` is old ``3 triangle_order[i] + k``),
        vertex ``j`` is old vertex ``vertex_order[j]``.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    mk = np.zeros(0, np.bool_) if marks is None else np.ascontiguousarray(marks, dtype=np.bool_)

    def half_edges(order, inverse, twin_new, marks_new, lo, hi) -> None:
        _kernels.renumber_half_edges_into(tw, mk, order, inverse, twin_new, marks_new, lo, hi)

    return _renumbered(pts, tri, keys, room, len(mk) > 0, half_edges, VERTEX_SIDE_SHARE)[0]


def renumber_from_neighbors(
    points: np.ndarray, triangles: np.ndarray, neighbors: np.ndarray, segments: np.ndarray,
    keys: CellKeys | None = None, room: tuple[int, int] = (0, 0),
) -> tuple[Renumbered, np.ndarray] | None:
    """:func:`renumber_local` of a mesh whose twins are not matched yet: matched once,
    in the new order, from a neighbour array in the old one (Triangle's).

    ``renumber_local`` renumbers twins matched in the input's order: two passes of
    scattered reads (the matching's and the renumbering's). Here the renumbering's
    pass reads the neighbour array instead (``_kernels.neighbor_rows_into``: which
    new row lies across each half-edge), and the matching runs on the renumbered
    rows, where a neighbour's row is near (``twins_in_rows_into``, ``twins_agree``).
    The neighbours are trusted on the test ``_kernels.twins_from_neighbors`` makes:
    each one in range, holding the edge the other way and naming the row back.

    Parameters
    ----------
    points, triangles, keys, room
        As :func:`renumber_local` (``triangles`` counter-clockwise, no repeated vertex).
    neighbors : (m, 3) int64
        ``neighbors[t, k]``: the triangle across edge ``(k, k + 1)`` of ``t``, -1 none.
    segments : (s, 2) int64
        Constrained edges (old vertex numbers), marked in ``marks``.

    Returns
    -------
    (Renumbered, found) or None
        ``marks``: the half-edges on a segment; ``found[s]``: whether segment ``s`` is
        an edge of the mesh. None if the neighbours are not to be trusted (then the
        caller matches the half-edges itself; ``keys`` are consumed either way).
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    nbr = np.ascontiguousarray(neighbors, dtype=np.int64)
    ok: list[bool] = []

    def rows_across(order, inverse, twin_new, marks_new, lo, hi) -> None:
        ok.append(_kernels.neighbor_rows_into(nbr, order, inverse, twin_new, lo, hi))

    # (the neighbours' pass is the shorter here: 1.5 M rows 0.022 against the vertex
    # pass's 0.032 s, so it takes all its rows: 0.035 -> 0.032 s for the pair)
    leaving = fresh(len(pts), np.int64)  # (a half-edge leaving each vertex: the segments' rotations)
    # rows across -> twins (in place: each range reads only rows; the neighbours'
    # values are in range even where not trusted), with the points' gather: one wait fewer
    r, vertex_new, parts = _renumbered(pts, tri, keys, room, True, rows_across, 0, leaving,
                                       _kernels.twins_in_rows_into)
    if not all(ok) or not all(parts):
        return None
    # then each twin's twin
    if not all(run_all([(lambda lo=lo, hi=hi: _kernels.twins_agree(r.twin, lo, hi))
                        for lo, hi in row_ranges(len(tri), threads.THREAD_MIN_ROWS)])):
        return None
    segs = vertex_new[np.ascontiguousarray(segments, dtype=np.int64).reshape(-1, 2)]
    r.marks[:] = False
    return r, _kernels.mark_segments_into(r.triangles, r.twin, leaving, segs, r.marks)


def _renumbered(pts: np.ndarray, tri: np.ndarray, keys: CellKeys | None, room: tuple[int, int], carry: bool,
                half_edges, side_share: int, leaving: np.ndarray | None = None, rows_after=None
                ) -> tuple[Renumbered, np.ndarray, list]:
    """The renumbering of :func:`renumber_local` with its half-edge pass
    ``half_edges(order, inverse, twin_new, marks_new, lo, hi)`` (new rows ``lo..hi``);
    ``carry``: a marks buffer to fill; the vertex pass's thread also takes the first
    ``1 / side_share`` of the half-edge pass's rows (none if 0); ``leaving``: filled
    with a half-edge leaving each new vertex (``renumber_vertices_into``);
    ``rows_after(tri_new, twin_new, lo, hi)``, if given: a pass over the new rows run
    with the points' gather (one wait for both). Also returns ``vertex_new`` (old ->
    new vertex) and ``rows_after``'s results, one per row range."""
    m, n = len(tri), len(pts)
    order, inverse = cell_order(pts, tri, keys)
    rt, rp = (max(0, int(r)) for r in room)
    tri_new = fresh((m + rt, 3), np.int64)[:m]
    vertex_new = fresh(n, np.int64, 0)  # (from the reserve: zeroed already)
    vertex_order = fresh(n, np.int64)
    twin_new = fresh(3 * (m + rt), np.int64)[: 3 * m]
    marks_new = fresh(3 * (m + rt) if carry else 0, np.bool_)[: 3 * m if carry else 0]
    # the serial vertex pass on one thread, the twins (reading the inverse) on the other;
    # the twins' pass is the longer (1.5 M rows: 0.044 against 0.032 s), so the vertex
    # pass's thread also takes the first VERTEX_SIDE_SHARE of the twins' rows
    cut = m // side_share if threads.cores() > 1 and side_share else 0

    def vertices_first() -> None:
        _kernels.renumber_vertices_into(tri, order, n, vertex_new, vertex_order, tri_new,
                                        np.zeros(0, np.int64) if leaving is None else leaving)
        half_edges(order, inverse, twin_new, marks_new, 0, cut)

    run_all([vertices_first, lambda: half_edges(order, inverse, twin_new, marks_new, cut, m)])
    pts_new = fresh((n + rp,) + pts.shape[1:], np.float64)[:n]
    spans = row_ranges(max(n, m if rows_after else 0), threads.THREAD_MIN_ROWS)

    def gather_and_after(i: int):
        k = len(spans)
        _kernels.gather_points_into(pts, vertex_order, pts_new, n * i // k, n * (i + 1) // k)
        return None if rows_after is None else rows_after(tri_new, twin_new, m * i // k, m * (i + 1) // k)

    after = run_all([(lambda i=i: gather_and_after(i)) for i in range(len(spans))])
    return Renumbered(pts_new, tri_new, twin_new, marks_new, order, vertex_order), vertex_new, after


def restore_vertices(rows: np.ndarray, vertex_order: np.ndarray) -> np.ndarray:
    """An output's rows (in place) with the renumbered vertices back in old numbers.

    Vertex numbers below ``len(vertex_order)`` are mapped through it; later ones
    (points a construction added) stay. Returns ``rows``.
    """
    n = len(vertex_order)
    run_all([
        (lambda lo=lo, hi=hi: _kernels.restore_vertices_into(rows, vertex_order, n, lo, hi))
        for lo, hi in row_ranges(len(rows), threads.THREAD_MIN_ROWS)
    ])
    return rows
