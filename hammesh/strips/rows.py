"""Row cover: dual paths that never cross a triangle's edge most parallel to a direction.

In a triangle a strip enters by one edge and leaves by another; the segment joining
their midpoints is parallel to the third edge (the midline), so a strip heads along the
edges it does *not* cross.  Each triangle here refuses to cross its edge most parallel
to an axis; two neighbours are linked when neither refuses their common edge.  Every
triangle then has at most two links, so the links are paths (and the odd cycle, opened
where it is met): rows running along the axis, as a structured grid's rows run, with
few swaps (two consecutive turns the same way need the strip to cross an edge nearly
parallel to its heading).  On q30 planar meshes (10k-12k triangles) the rows have
~0.11 swaps per triangle at ~13 triangles per row; the end moves
(:func:`~hammesh.strips._moves_kernels.improve_cover`) then join them into strips of
~25 triangles: 1.214-1.254 indices per triangle against the greedy cover's 1.270-1.282
and the swap-free chains' 1.264-1.268 (measured in ``docs/strips.md``, session 12).

Planar meshes only (the axes are those of the ``x, y`` plane); :data:`ROW_AXES` are the
directions tried (``encode`` keeps the shortest buffer).  Our construction; the midline
observation is elementary geometry.
"""

from __future__ import annotations

import numpy as np

from collections import namedtuple

from hammesh.strips._band_kernels import equal_pivots_into, join_heading_pieces, level_cuts_into, move_cuts, orient_pieces
from hammesh.strips._cover_kernels import PathCover
from hammesh.strips._row_kernels import link_paths_into, row_links_into

__all__ = ["ROW_AXES", "BAND_SLACK", "band_slack", "BAND_MERGE", "BAND_DRIFT", "JOIN_SHORT", "EVEN_COLUMNS", "band_reach",
           "path_columns", "parallel_edges", "row_links", "row_path_cover", "BandFrame", "band_frame", "band_layout"]

#: Directions (radians from the x axis) the row cover is tried along.
ROW_AXES = (0.0, np.pi / 2)


def parallel_edges(points: np.ndarray, triangles: np.ndarray, angle: float) -> np.ndarray:
    """``(m,)`` local index ``k`` of each triangle's edge ``(v_k, v_k+1)`` most parallel to ``angle``
    (numpy; :func:`row_path_cover` computes it and :func:`row_links` in one compiled kernel,
    :func:`~hammesh.strips._row_kernels.row_links_into`, and the tests compare the two).

    The measure is ``|sin|`` of the angle between edge and axis; a zero-length edge
    (coincident points) counts as parallel.
    """
    p = np.asarray(points, np.float64)[:, :2]
    tri = np.asarray(triangles)
    # coordinates whose differences overflow give inf / nan: any choice is a valid cover
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        e = p[np.roll(tri, -1, axis=1)] - p[tri]  # (m, 3, 2): edge k from v_k to v_k+1
        across = np.abs(e[..., 1] * np.cos(angle) - e[..., 0] * np.sin(angle))
        sine = np.nan_to_num(across / np.hypot(e[..., 0], e[..., 1]), nan=0.0)
    return np.argmin(sine, axis=1)


def row_links(twin: np.ndarray, refused: np.ndarray) -> np.ndarray:
    """``(m, 3)`` linked neighbour across each edge, -1 where either side refuses it.

    ``twin``: ``(3 m,)`` half-edge pairing (-1: no proper neighbour); ``refused``: each
    triangle's refused local edge (:func:`parallel_edges`).
    """
    m = len(refused)
    tw = np.asarray(twin, np.int64).reshape(m, 3)
    u, ku = tw // 3, tw % 3
    ok = (tw >= 0) & (np.arange(3) != refused[:, None])
    ok &= refused[np.where(ok, u, 0)] != ku
    return np.where(ok, u, -1)


def row_path_cover(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, angle: float) -> PathCover:
    """The rows along ``angle`` as a dual path cover (:class:`~hammesh.strips._cover_kernels.PathCover`:
    ``order (m,)``, ``starts (S + 1,)`` int64)."""
    p = np.asarray(points, np.float64)
    tri = np.asarray(triangles)
    m = len(tri)
    link = np.empty((m, 3), np.int64)
    row_links_into(p, tri, np.asarray(twin, np.int64).reshape(-1), np.cos(angle), np.sin(angle), np.empty(m, np.int64), link)
    order = np.empty(m, np.int64)
    starts = np.empty(m + 1, np.int64)
    S = link_paths_into(link, order, starts)
    return PathCover(order, starts[: S + 1].copy())


#: Longest row of a band, in triangles, is ``cache - band_slack(cache)`` (:func:`band_layout`),
#: the slack at least ``BAND_SLACK``: a row whose vertices all missed loads about ``L + 2``
#: of them, and the next row finds its far side still in a FIFO of ``N`` entries only while
#: ``L + 2 <= N - 1``: shorter rows recover after a miss, longer ones pass it on (measured
#: on the q30 square of 10k triangles, FIFO 16: rows of ~14 triangles ACMR 0.66-0.70, of
#: ~18 0.87-0.94).
BAND_SLACK = 3


def band_slack(cache: int) -> int:
    """Triangles a band's rows stay below the FIFO size: ``max(BAND_SLACK, 5 * cache // 16)``.

    The rows are not a grid's (they end at vertices of degree other than 6, and the end
    moves join them into strips of ~25 triangles that the columns cut), so the recovery
    bound above is optimistic for larger FIFOs: at ``cache - 3`` the ACMR of the bands
    grows with the FIFO (q30 square 10k: 0.670 at 16, 0.691 at 32, 0.708 at 48, 0.724 at
    64), while rows of at most three quarters of it keep it falling (0.663 at 16, 0.629 at
    32, 0.619 at 48, 0.608 at 64, before :data:`BAND_MERGE`; measured in ``docs/strips.md``,
    session 13).  Session 14's joins of short pieces across column borders
    (:data:`JOIN_SHORT`) load a few vertices early; rows of at most ``11/16`` of the FIFO
    pay for them (FIFO 32, q30 square 10k / A 12k / 100k: slack 8 1.2871 / 0.631, 1.2967
    / 0.644, 1.2781 / 0.630; slack 10 1.2871 / 0.631, 1.2981 / 0.624, 1.2818 / 0.620
    indices per triangle / ACMR32, meshoptimizer vcache + stripify 0.636-0.643).
    """
    return max(BAND_SLACK, 5 * int(cache) // 16)


#: :func:`band_frame`'s result: each triangle's ``column`` (``(m,)`` int64, counted across
#: the rows), ``height`` and ``along`` (its centroid across and along the rows) and the
#: ``row_height`` of the mesh (a mean edge's equilateral height), or ``None`` for all four
#: where the coordinates give no finite frame.
BandFrame = namedtuple("BandFrame", ["column", "height", "along", "row_height"])


#: :func:`band_layout`'s joins also take a piece of at most this many triangles into a
#: neighbouring piece's end whatever their columns and headings (the tail of a row just
#: past a column border, a short row at the boundary or a hole; each alone costs a restart
#: and two start indices): q30 meshes at FIFO 32, 0 / 2 / 3 / 4 / 6: square 10k 1.2959 /
#: 1.2915 / 1.2871 / 1.2838 / 1.2748 indices per triangle at ACMR32 0.625 / 0.627 / 0.631 /
#: 0.635 / 0.658 (slack 8; session 14).
JOIN_SHORT = 3

#: :func:`band_frame` divides the rows' extent into equal columns no wider than the target
#: (instead of target-wide columns and a thin last one, whose short rows cost a restart
#: each): q30 meshes ~10k, ACMR 0.691 → 0.669 at FIFO 16, 0.580 → 0.560 at 64, about the
#: same indices (session 14).
EVEN_COLUMNS = True


def band_frame(points: np.ndarray, tri: np.ndarray, cache: int, angle: float = 0.0) -> BandFrame:
    """Columns at most ``(cache - band_slack(cache)) / 2`` mean edge lengths wide across rows
    along ``angle``, all of one width (:data:`EVEN_COLUMNS`).

    A row crossing a column then has at most about ``cache - band_slack(cache)`` triangles.
    Depends only on the rows' vertices, not on their order.
    """
    p = np.asarray(points, np.float64)[:, :2]
    ca, sa = np.cos(angle), np.sin(angle)
    p = np.c_[p[:, 0] * ca + p[:, 1] * sa, p[:, 1] * ca - p[:, 0] * sa]  # along the rows, across them
    with np.errstate(over="ignore", invalid="ignore"):
        c = p[tri].mean(axis=1)  # (m, 2) centroids
        e = p[tri[:, 1]] - p[tri[:, 0]]
        edge = float(np.mean(np.hypot(e[:, 0], e[:, 1])))
        width = max(1.0, (int(cache) - band_slack(cache)) / 2) * edge
        x = c[:, 0]
        if not (len(x) and width > 0 and np.isfinite(width) and np.isfinite(c).all()):
            return BandFrame(None, None, None, None)
        lo, extent = x.min(), x.max() - x.min()
        if EVEN_COLUMNS and extent > 0 and np.isfinite(extent):
            width = extent / np.ceil(extent / width)  # equal columns, none thin at the end
        column = np.minimum(np.floor((x - lo) / width), max(0.0, np.ceil(extent / width) - 1))
        return BandFrame(column.astype(np.int64), c[:, 1], x, edge * np.sqrt(3) / 2)


#: A path's run of fewer triangles than this in one column stays with the path's run
#: before it (:func:`path_columns`): a single triangle over a border is not a piece of its
#: own.  Longer runs kept (3-10) gave fewer indices but more loads (FIFO 16 q30 square 10k,
#: merge 3: 1.403 / 0.679; FIFO 64 merge 6 or 10: ACMR64 above meshoptimizer's; session 13).
BAND_MERGE = 2


def path_columns(column: np.ndarray, order: np.ndarray, starts: np.ndarray, merge: int) -> np.ndarray:
    """Column of each position of ``order``: its triangle's ``column``, except that a run of
    fewer than ``merge`` consecutive triangles of one path in one column takes the column
    of the path's run before it (at the path's first run: the run after it).

    Why: a path crossing a column border by a triangle or two would leave a piece of one or
    two triangles, 3 indices each for a restart and a new start; kept with its neighbour it
    costs nothing and loads the few vertices it has beyond the border early (q30 square
    10k, FIFO 16: 1.434 / 0.663 → 1.413 / 0.647 indices per triangle / ACMR16 at merge 2;
    session 13).  Runs are those of the original columns (one pass: two short runs in a
    row may still be cut between them).
    """
    col = np.asarray(column)[order]
    n = len(col)
    if merge <= 1 or n == 0:
        return col
    brk = np.zeros(n + 1, np.bool_)
    brk[starts] = True
    brk[1:-1] |= col[1:] != col[:-1]
    rs = np.flatnonzero(brk[:-1])
    ln = np.diff(np.r_[rs, n])
    path = np.searchsorted(starts, rs, side="right") - 1
    rcol = col[rs]
    same_prev = np.r_[False, path[1:] == path[:-1]]
    same_next = np.r_[path[:-1] == path[1:], False]
    short = ln < merge
    new = rcol.copy()
    prev = np.flatnonzero(short & same_prev)
    new[prev] = rcol[prev - 1]
    nxt = np.flatnonzero(short & ~same_prev & same_next)
    new[nxt] = rcol[nxt + 1]
    return np.repeat(new, ln)


#: A piece is cut where its triangles' centroids have drifted more than this many row
#: heights across the rows from its first triangle's (:func:`band_layout`): the end moves
#: join rows into staircases, and a piece climbing three or more rows inside a column
#: reloaded ~8 vertices its rows' neighbours had loaded (q30 square 10k, FIFO 32: 30
#: pieces, 920 triangles, 7.9 reloads each against ~1 for one-row pieces).  Cut at 3 rows:
#: FIFO 32 ipt / ACMR 1.3012 / 0.630 with :func:`band_reach`, at 2.5: 1.3047 / 0.629, at 4:
#: 1.2991 / 0.645 (docs/strips.md, session 14).
BAND_DRIFT = 3.0


def band_reach(cache: int) -> int:
    """Positions a cut of :func:`band_layout` may move along its path to save indices:
    ``max(1, min(4, cache // 8))``.

    A cut at a swap removes the swap (the two pieces' ends do not turn), so moving the
    column and drift cuts by a few triangles saves ~0.02 indices per triangle (q30 square
    10k, FIFO 32, reach 4: 1.3196 → 1.2978); the triangles it moves across a column border
    are drawn in the other column's pass and reload a vertex or two there (ACMR 0.633 →
    0.652 at reach 4 without the drift cuts; 0.641 at 1; at FIFO 16 reach 4 gives 0.710
    against 0.691 at 2), hence less reach for smaller FIFOs (session 14).
    """
    return max(1, min(4, int(cache) // 8))


def band_layout(
    frame: BandFrame,
    tri: np.ndarray,
    twin: np.ndarray,
    order: np.ndarray,
    starts: np.ndarray,
    merge: int = 0,
    reach: int = 0,
    drift: float = 0.0,
    join: bool = False,
) -> PathCover:
    """Pieces of the paths sent column by column (left to right), inside a column by the mean
    height of their centroids, alternately upwards and downwards (a serpentine, so the first
    rows of a column meet the last ones of the one before), each in its cheaper direction.

    A path is cut where it crosses a column border, unless it has fewer than ``merge``
    triangles on one side (:func:`path_columns`), and (``drift > 0``) where its centroids
    leave its last cut's height by more than ``drift`` row heights
    (:func:`~hammesh.strips._band_kernels.level_cuts_into`); then each of those cuts moves
    by at most ``reach`` triangles along its path to where its two pieces cost fewest
    indices (:func:`~hammesh.strips._band_kernels.move_cuts`).  A piece's column is its
    middle triangle's.  With ``join``, pieces of one column whose ends are neighbours and
    that head the same way along the rows are joined where that saves indices, and so is a
    piece of at most :data:`JOIN_SHORT` triangles with any neighbouring end
    (:func:`~hammesh.strips._band_kernels.join_heading_pieces`).  Each piece is then turned
    to the direction with fewer swaps, on a tie to run along the rows' axis
    (:func:`~hammesh.strips._band_kernels.orient_pieces`):
    each row finds the vertices of its lower side in the FIFO, loaded by the row before, in
    the order it loaded them.  ``frame``: :func:`band_frame` of the rows ``tri``
    (``twin`` its pairing) that ``order`` refers to.  Returns the new ``(order, starts)``.
    """
    order = np.asarray(order, np.int64)
    starts = np.asarray(starts, np.int64)
    if frame.column is None:
        return PathCover(order, starts)
    n = len(order)
    col = path_columns(frame.column, order, starts, merge)
    cut = np.zeros(n + 1, np.bool_)
    cut[starts] = True
    cut[1:-1] |= col[1:] != col[:-1]
    bounds = np.flatnonzero(cut)
    if drift > 0:
        out = np.empty(n + 1, np.int64)
        bounds = out[: level_cuts_into(frame.height, order, bounds, float(drift) * frame.row_height, out)]
    twin3 = np.asarray(twin).reshape(-1, 3)
    if reach > 0 and len(bounds) > 2:
        natural = np.zeros(n + 1, np.bool_)
        natural[starts] = True
        cum = np.empty(n + 1, np.int64)
        equal_pivots_into(tri, twin3, order, starts, cum)
        bounds = bounds.copy()
        move_cuts(tri, twin3, order, cum, bounds, ~natural[bounds], int(reach))
    lo, lens = bounds[:-1], np.diff(bounds)
    pcol = col[lo + lens // 2]
    if join:
        column = np.empty(n, np.int64)
        column[order] = np.repeat(pcol, lens)
        link = np.empty((n, 2), np.int64)
        work = np.empty((4, n), np.int64)
        out = np.empty(n + 1, np.int64)
        K = join_heading_pieces(tri, twin3, frame.along, column, order, bounds, link, work[0], work[1], work[2],
                                JOIN_SHORT, work[3], out)
        order, bounds = work[3], out[: K + 1]
        lo, lens = bounds[:-1], np.diff(bounds)
        pcol = column[order[lo]]
    height = np.add.reduceat(frame.height[order], lo) / lens
    pick = np.lexsort((np.where(pcol % 2 == 0, height, -height), pcol))  # serpentine
    k = lens[pick]
    new_starts = np.r_[0, np.cumsum(k)].astype(np.int64)
    # piece j's triangles: order[lo[pick[j]] + i], i < k[j], placed from new_starts[j]
    new = order[np.repeat(lo[pick] - new_starts[:-1], k) + np.arange(n)]
    orient_pieces(tri, twin3, frame.along, new, new_starts)
    return PathCover(new, new_starts)
