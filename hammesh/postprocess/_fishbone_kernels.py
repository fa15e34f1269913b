"""The fishbone hierarchy that ranks the incircle tree's dual edges (numba, issue 14).

A *fishbone* cell (session 11's prototype, ``benchmarks/partition_trees.py``; ported
in session 12) has a *spine*: the triangles its count-median line crosses. The other
triangles fall into four children: the two sides of the line, each halved by count
along it. Every child then hangs from its parent's spine by one dual edge, where the
child's own spine line meets it, so the Thm 2.4 walk visits each child whole, one
run of the cycle: near-low, far-low, far-high, near-high. For ``k = 4^j`` parts the
stretches of the cycle are the level-``j`` cells, for ``k = 2 4^j`` the halves of
those cells cut by their spines (docs/partition.md, "Fishbone trees").

The lines are medians of a sample of the centroids (:func:`kd_lines`: a kd build
with quickselect, two splits a level, the line turning by 90 degrees a level), and
every triangle finds its cells by descending them (:func:`descend`). A line that
crosses a hole leaves its spine in pieces; :func:`join_gaps_into` joins them round
the hole's rim (the triangles touching the boundary, on one side of the line), so
that the children still hang from one path. ``_thm24_kernels.spanning_forest`` turns
all of it into a class per half-edge for Prim's bucket queue: deeper cells first; inside a cell its spine's
edges, then the edges that hang a child (the child's own spine end first, nearest
the point where the child's line meets the spine first), then walls between
children; below the deepest fishbone level the count quadtree's classes
(``_thm24_kernels.edge_class``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

__all__ = [
    "FishLines",
    "FISH_LEVELS",
    "FISH_SAMPLE",
    "FISH_MIN_CELL",
    "HANG_BINS",
    "WALL_BINS",
    "PER_LEVEL",
    "AUTO_ANGLES",
    "ANGLE_SAMPLE",
    "ANGLE_LEVELS",
    "fish_depth",
    "level_offset",
    "kd_lines",
    "fish_angle",
    "spine_cost",
    "GAP_STEPS",
    "GAP_COST",
    "descend_into",
    "descend",
    "turned_box",
    "join_gaps_into",
    "spines_by_level",
    "distance_bin",
    "turned_centroid",
    "sample_centroids",
    "rim_vertices",
]

#: Most fishbone levels (below them the count quadtree ranks the edges).
FISH_LEVELS = 7
#: Centroids the lines are medians of (every ``m // FISH_SAMPLE``-th triangle; all below).
FISH_SAMPLE = 1 << 16
#: Sampled centroids per deepest cell at least (fewer levels on small meshes).
FISH_MIN_CELL = 16
#: Distance classes of the edges that hang a child (each of own-spine / other kid).
HANG_BINS = 32
#: Distance classes of the walls between children.
WALL_BINS = 32
#: Classes per fishbone level: spine, hangs by the child's spine, other hangs, walls.
PER_LEVEL = 1 + 2 * HANG_BINS + WALL_BINS
#: Turns of the top line tried by :func:`fish_angle` (``i * 180 / AUTO_ANGLES`` degrees).
AUTO_ANGLES = 12
#: Triangles sampled to judge the turns.
ANGLE_SAMPLE = 1 << 15
#: Levels whose lines the turn is judged on (k = 8 and k = 64 stretches meet there).
ANGLE_LEVELS = 3


class FishLines(NamedTuple):
    """Result of :func:`kd_lines`: per cell of levels ``0..depth`` (flat, level ``l``'s
    cells from :func:`level_offset`), its spine line (a coordinate across the level's
    axis), the along-medians of its two sides (``fars``, two per cell) and its sample's
    extent (the longer side of its bounding box)."""

    lines: np.ndarray
    fars: np.ndarray
    extent: np.ndarray


def fish_depth(n_sample: int) -> int:
    """Fishbone levels for a sample of ``n_sample`` centroids: at least
    ``FISH_MIN_CELL`` of them per deepest cell, at most ``FISH_LEVELS``."""
    d = 0
    while d < FISH_LEVELS and 4 ** (d + 1) * FISH_MIN_CELL <= n_sample:
        d += 1
    return d


@njit(cache=True, nogil=True, inline="always")
def level_offset(level):
    """First flat index of level ``level``'s cells (``(4^level - 1) / 3``)."""
    return ((1 << (2 * level)) - 1) // 3


@njit(cache=True, nogil=True)
def _nth(key, other, lo, hi, k):
    """Reorder ``key[lo:hi]`` (and ``other`` alongside) so that ``key[k]`` is the
    ``k``-th smallest, none above it before and none below it after (quickselect,
    three-way split; the coordinates move, not indices: sequential memory)."""
    while hi - lo > 1:
        x, y, z = key[lo], key[(lo + hi) // 2], key[hi - 1]
        pivot = max(min(x, y), min(max(x, y), z))  # median of three
        lt, i, gt = lo, lo, hi
        while i < gt:
            v = key[i]
            if v < pivot:
                key[i], key[lt] = key[lt], v
                other[i], other[lt] = other[lt], other[i]
                lt += 1
                i += 1
            elif v > pivot:
                gt -= 1
                key[i], key[gt] = key[gt], v
                other[i], other[gt] = other[gt], other[i]
            else:
                i += 1
        if k < lt:
            hi = lt
        elif k >= gt:
            lo = gt
        else:
            return


@njit(cache=True, nogil=True)
def _kd_lines_into(xy, depth, lines, fars, extent):
    """The kd build of :func:`kd_lines` over the points ``xy`` ((s, 2), turned)."""
    s = xy.shape[0]
    xs = xy[:, 0].copy()
    ys = xy[:, 1].copy()
    seg = np.zeros(2, np.int64)
    seg[1] = s
    for level in range(depth + 1):
        n_cells = 1 << (2 * level)
        off = level_offset(level)
        nxt = np.empty(4 * n_cells + 1, np.int64)
        across = ys if level % 2 == 0 else xs  # the line runs along x at the top
        along = xs if level % 2 == 0 else ys
        for c in range(n_cells):
            a, b = seg[c], seg[c + 1]
            nxt[4 * c : 4 * c + 5] = a
            nxt[4 * c + 4] = b
            lines[off + c] = np.nan
            fars[2 * (off + c)] = np.nan
            fars[2 * (off + c) + 1] = np.nan
            extent[off + c] = 0.0
            if b <= a:
                continue
            x0 = x1 = xs[a]
            y0 = y1 = ys[a]
            for i in range(a + 1, b):
                x0 = min(x0, xs[i])
                x1 = max(x1, xs[i])
                y0 = min(y0, ys[i])
                y1 = max(y1, ys[i])
            extent[off + c] = max(x1 - x0, y1 - y0)
            k = (b - a) // 2
            _nth(across, along, a, b, a + k)
            lines[off + c] = across[a + k]
            if level == depth:
                continue
            nxt[4 * c + 2] = a + k
            for side in range(2):
                sa, sb = (a, a + k) if side == 0 else (a + k, b)
                if sb <= sa:
                    nxt[4 * c + 2 * side + 1] = sa
                    continue
                kk = (sb - sa) // 2
                _nth(along, across, sa, sb, sa + kk)
                fars[2 * (off + c) + side] = along[sa + kk]
                nxt[4 * c + 2 * side + 1] = sa + kk
        seg = nxt


def kd_lines(xy, depth):
    """The fishbone's lines over centroids ``xy`` ((s, 2) float64, in the turned axes).

    Level ``l``'s line runs along x for even ``l`` (a y value), along y for odd: each
    cell's line is the median across of its centroids (the upper side, ``>= line``,
    holding ``ceil(n / 2)``), each side's far half is ``>= `` its median along the line
    (``fars``). A cell holds its spine's centroids too (on their side): a spine's rows
    are walked just before or after the cells beside it, so the regions' counts stay
    equal at every level (session 11: otherwise the errors add up level by level).
    Returns :class:`FishLines` for levels ``0..depth``."""
    n = level_offset(depth + 1)
    out = FishLines(np.empty(n), np.empty(2 * n), np.empty(n))
    _kd_lines_into(np.ascontiguousarray(xy, np.float64), depth, out.lines, out.fars, out.extent)
    return out


@njit(cache=True, nogil=True, inline="always")
def _turn(x, y, ca, sa):
    return ca * x + sa * y, ca * y - sa * x


@njit(cache=True, nogil=True)
def descend(cx, cy, x0, x1, y0, y1, lines, fars, depth):
    """``(cell, spine level)`` of a triangle of turned centroid ``(cx, cy)`` and box
    ``[x0, x1] x [y0, y1]``: the deepest cell (2 bits a level, ``2 * side + far``) and
    the first level whose line its box straddles (``depth``: none)."""
    reg = 0
    spine = depth
    for level in range(depth):
        oc = level_offset(level) + reg
        line = lines[oc]
        if level % 2 == 0:
            a, al, lo, hi = cy, cx, y0, y1
        else:
            a, al, lo, hi = cx, cy, x0, x1
        if spine == depth and lo <= line and line <= hi:
            spine = level
        s = 1 if a >= line else 0
        f = 1 if al >= fars[2 * oc + s] else 0
        reg = 4 * reg + 2 * s + f
    return reg, spine


@njit(cache=True, nogil=True, inline="always")
def turned_box(points, tri, t, ca, sa):
    """Turned centroid and bounding box of triangle ``t``."""
    ax, ay = _turn(points[tri[t, 0], 0], points[tri[t, 0], 1], ca, sa)
    bx, by = _turn(points[tri[t, 1], 0], points[tri[t, 1], 1], ca, sa)
    cx, cy = _turn(points[tri[t, 2], 0], points[tri[t, 2], 1], ca, sa)
    return ((ax + bx + cx) / 3.0, (ay + by + cy) / 3.0, min(ax, bx, cx), max(ax, bx, cx),
            min(ay, by, cy), max(ay, by, cy))


@njit(cache=True, nogil=True)
def descend_into(points, tri, ca, sa, lines, fars, depth, fish_shift, qr, half, lo, hi):
    """Cells of triangles ``lo..hi`` (:func:`descend`): ``qr[t, 2]`` the deepest cell
    ``| spine level << fish_shift`` (``depth``: on no spine), ``half`` the top line's
    side (the two searches' halves)."""
    for t in range(lo, hi):
        cx, cy, x0, x1, y0, y1 = turned_box(points, tri, t, ca, sa)
        reg, sp = descend(cx, cy, x0, x1, y0, y1, lines, fars, depth)
        qr[t, 2] = reg | (sp << fish_shift)
        half[t] = (reg >> (2 * depth - 1)) & 1 if depth > 0 else 0


@njit(cache=True, nogil=True)
def _sample_boxes(points, tri, sample, ca, sa, xy, box):
    for i in range(sample.shape[0]):
        cx, cy, x0, x1, y0, y1 = turned_box(points, tri, sample[i], ca, sa)
        xy[i, 0] = cx
        xy[i, 1] = cy
        box[i, 0] = x0
        box[i, 1] = x1
        box[i, 2] = y0
        box[i, 3] = y1


@njit(cache=True, nogil=True)
def _corner_boxes(corners, ca, sa, xy, box):
    """Turned centroids and boxes of triangles given by their corners ((s, 6): x0 y0 x1 y1 x2 y2)."""
    for i in range(corners.shape[0]):
        ax, ay = _turn(corners[i, 0], corners[i, 1], ca, sa)
        bx, by = _turn(corners[i, 2], corners[i, 3], ca, sa)
        cx, cy = _turn(corners[i, 4], corners[i, 5], ca, sa)
        xy[i, 0] = (ax + bx + cx) / 3.0
        xy[i, 1] = (ay + by + cy) / 3.0
        box[i, 0] = min(ax, bx, cx)
        box[i, 1] = max(ax, bx, cx)
        box[i, 2] = min(ay, by, cy)
        box[i, 3] = max(ay, by, cy)


@njit(cache=True, nogil=True)
def _sampled_spines_into(xy, box, lines, fars, levels, line_of, along_of):
    """The sampled triangles on a spine of the top ``levels`` levels: for each, its
    line (flat cell index) and its coordinate along the line. Returns their number."""
    n = 0
    for i in range(xy.shape[0]):
        cx, cy = xy[i, 0], xy[i, 1]
        reg = 0
        for level in range(levels):
            oc = level_offset(level) + reg
            line = lines[oc]
            if level % 2 == 0:
                a, al, b0, b1 = cy, cx, box[i, 2], box[i, 3]
            else:
                a, al, b0, b1 = cx, cy, box[i, 0], box[i, 1]
            if b0 <= line and line <= b1:
                line_of[n] = oc
                along_of[n] = al
                n += 1
                break
            sd = 1 if a >= line else 0
            f = 1 if al >= fars[2 * oc + sd] else 0
            reg = 4 * reg + 2 * sd + f
    return n


#: A gap along a sampled spine longer than this many times the line's median step is
#: a hole (or a notch) the spine is joined round (:func:`join_gaps_into`).
GAP_STEPS = 4.0
#: What a hole's gap costs, in triangles per missing one: the rim path round half a
#: round hole is pi / 2 times its diameter.
GAP_COST = 1.5


def spine_cost(line_of, along_of):
    """Triangles on the sampled spines, each gap of a line (longer than ``GAP_STEPS``
    median steps) counted as ``GAP_COST`` times the triangles it would hold."""
    o = np.lexsort((along_of, line_of))
    line_of, along_of = line_of[o], along_of[o]
    same = line_of[1:] == line_of[:-1]
    step = np.diff(along_of)[same]
    if not len(step):
        return float(len(line_of))
    med = np.median(step)
    if med <= 0:
        return float(len(line_of))
    gaps = step[step > GAP_STEPS * med]
    return float(len(line_of) + GAP_COST * (gaps / med).sum())


def sample_centroids(points, tri, sample, angle):
    """(s, 2): the turned centroids of triangles ``sample``."""
    xy = np.empty((len(sample), 2))
    box = np.empty((len(sample), 4))
    _sample_boxes(points, tri, np.asarray(sample, np.int64), math.cos(angle), math.sin(angle), xy, box)
    return xy


def fish_angle(points, tri, sample=None):
    """The turn of the fishbone's axes (radians, ``[0, pi)``) whose spines of the top
    ``ANGLE_LEVELS`` levels hold the fewest triangles, each hole a line crosses
    counted as the rim path that joins it (:func:`spine_cost`), judged on a sample
    of the triangles (every ``m // ANGLE_SAMPLE``-th). The stretches of k = 8 and
    k = 64 meet along those lines: on the plate with two holes the top line goes
    between the holes (session 11: 1.38 against 1.82 at k = 8 along the holes)."""
    m = tri.shape[0]
    if m < 4:
        return 0.0
    if sample is None:
        sample = np.arange(0, m, max(1, m // ANGLE_SAMPLE))
    sample = np.asarray(sample, np.int64)
    depth = min(ANGLE_LEVELS, fish_depth(len(sample)))
    if depth == 0:
        return 0.0
    xy = np.empty((len(sample), 2))
    box = np.empty((len(sample), 4))
    corners = np.ascontiguousarray(points[tri[sample]].reshape(len(sample), 6))  # read once, turned 12 times
    best, best_a = np.inf, 0.0
    for i in range(AUTO_ANGLES):
        a = math.pi * i / AUTO_ANGLES
        _corner_boxes(corners, math.cos(a), math.sin(a), xy, box)
        fl = kd_lines(xy, depth - 1)  # lines of levels 0 .. depth - 1, all the spines need
        line_of = np.empty(len(sample), np.int64)
        along_of = np.empty(len(sample))
        n = _sampled_spines_into(xy, box, fl.lines, fl.fars, depth, line_of, along_of)
        cost = spine_cost(line_of[:n], along_of[:n])
        if cost < best * (1.0 - 1e-9):
            best, best_a = cost, a
    return best_a


def rim_vertices(tri, twin, n_points):
    """(n_points,) bool: the vertices on the boundary (an end of a half-edge without twin)."""
    on = np.zeros(n_points, np.bool_)
    _rim_into(tri, twin, on)
    return on


@njit(cache=True, nogil=True)
def _rim_into(tri, twin, on):
    for h in range(twin.shape[0]):
        if twin[h] < 0:
            t, k = h // 3, h % 3
            on[tri[t, k]] = True
            on[tri[t, (k + 1) % 3]] = True


@njit(cache=True, nogil=True, inline="always")
def _on_rim(tri, on, t):
    return on[tri[t, 0]] or on[tri[t, 1]] or on[tri[t, 2]]


@njit(cache=True, nogil=True)
def _root(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True, nogil=True)
def spines_by_level(qr, fish_shift, levels):
    """The triangles on a spine of the top ``levels`` levels (``qr[:, 2]``), grouped
    by level in one pass (a counting sort): ``(triangles, first)``, level ``l``'s at
    ``first[l]:first[l + 1]``, each level's in increasing order."""
    first = np.zeros(levels + 1, np.int64)
    for t in range(qr.shape[0]):
        sp = qr[t, 2] >> fish_shift
        if sp < levels:
            first[sp + 1] += 1
    for lv in range(levels):
        first[lv + 1] += first[lv]
    out = np.empty(first[levels], np.int64)
    fill = first[:levels].copy()
    for t in range(qr.shape[0]):
        sp = qr[t, 2] >> fish_shift
        if sp < levels:
            out[fill[sp]] = t
            fill[sp] += 1
    return out, first


@njit(cache=True, nogil=True)
def join_gaps_into(points, tri, twin, ca, sa, qr, fish_shift, lines, depth, levels, on_rim):
    """Join each cell's spine round the holes its line crosses (session 11's rule),
    for the top ``levels`` levels.

    ``qr[:, 2]``: each triangle's cell ``| spine level << fish_shift``
    (:func:`descend_into`). Level by level from the top, the spine triangles of each
    cell are split into pieces (dual-connected inside the cell's spine); while a
    cell has more than one, a breadth-first search from the first piece through the
    cell's triangles that touch the boundary (``on_rim`` vertices), first below the
    line then above it, finds the shortest such path to another piece, whose
    triangles join the spine. Without a path (the pieces are not apart by a hole)
    the pieces stay. Updates ``qr[:, 2]``; returns the triangles added."""
    m = qr.shape[0]
    low = (1 << fish_shift) - 1
    loc = np.full(m, -1, np.int32)  # a spine triangle's index in its level's list
    seen = np.full(1, -1, np.int32)  # BFS stamp and parent: made at the first search
    via = np.empty(1, np.int32)
    added = 0
    stamp = 0
    levels = min(levels, depth)
    listed, first = spines_by_level(qr, fish_shift, levels)
    for level in range(levels):
        shift = 2 * (depth - level)
        members = listed[first[level] : first[level + 1]]  # (a path moves a triangle up, never down)
        cap = 2 * members.shape[0] + 1024  # room for the paths (rim strips)
        lst = np.empty(cap, np.int64)
        n = 0
        for t in members:
            if (qr[t, 2] >> fish_shift) == level:  # (not moved up by a path above)
                lst[n] = t
                n += 1
        parent = np.arange(cap)
        for j in range(n):
            loc[lst[j]] = j
        for j in range(n):
            t = lst[j]
            for kk in range(3):
                g = twin[3 * t + kk]
                if g < 0:
                    continue
                u = g // 3
                if (qr[u, 2] >> fish_shift) == level and ((qr[u, 2] & low) >> shift) == ((qr[t, 2] & low) >> shift):
                    a, b = _root(parent, j), _root(parent, loc[u])
                    if a != b:
                        parent[max(a, b)] = min(a, b)
        cell_of = np.empty(n, np.int64)
        for j in range(n):
            cell_of[j] = (qr[lst[j], 2] & low) >> shift
        by_cell = np.argsort(cell_of, kind="mergesort")
        oc0 = level_offset(level)
        n0 = n  # the list grows by the paths; the pieces are of the first n0
        i = 0
        while i < n0:
            e = i
            while e < n0 and cell_of[by_cell[e]] == cell_of[by_cell[i]]:
                e += 1
            cell = cell_of[by_cell[i]]
            line = lines[oc0 + cell]
            across = 1 if level % 2 == 0 else 0
            for _ in range(e - i):  # at most one join per piece
                r0 = _root(parent, by_cell[i])
                split = False
                for q in range(i + 1, e):
                    if _root(parent, by_cell[q]) != r0:
                        split = True
                        break
                if not split:
                    break
                joined = False
                if seen.shape[0] < m:
                    seen = np.full(m, -1, np.int32)
                    via = np.empty(m, np.int32)
                for below in range(2):
                    stamp += 1
                    queue = []
                    for q in range(i, e):
                        if _root(parent, by_cell[q]) == r0:
                            t = lst[by_cell[q]]
                            seen[t] = stamp
                            via[t] = -1
                            queue.append(t)
                    hit, end = -1, -1
                    head = 0
                    while head < len(queue) and hit < 0:
                        t = queue[head]
                        head += 1
                        for kk in range(3):
                            g = twin[3 * t + kk]
                            if g < 0:
                                continue
                            u = g // 3
                            if ((qr[u, 2] & low) >> shift) != cell or seen[u] == stamp:
                                continue
                            sp = qr[u, 2] >> fish_shift
                            if sp == level:
                                if loc[u] >= 0 and _root(parent, loc[u]) != r0 and via[t] >= 0:
                                    hit, end = u, t
                                    break
                                continue
                            if sp < level or not _on_rim(tri, on_rim, u):
                                continue
                            cu = turned_centroid(points, tri, u, ca, sa)
                            if (cu[across] < line) != (below == 0):
                                continue
                            seen[u] = stamp
                            via[u] = t
                            queue.append(u)
                    if hit < 0:
                        continue
                    t = end
                    while via[t] >= 0:  # the path joins the spine (and this level's list)
                        qr[t, 2] = (qr[t, 2] & low) | (level << fish_shift)
                        if n < cap:
                            lst[n] = t
                            loc[t] = n
                            parent[n] = _root(parent, loc[hit])
                            n += 1
                        added += 1
                        t = via[t]
                    a, b = _root(parent, loc[hit]), r0
                    if a != b:
                        parent[max(a, b)] = min(a, b)
                    joined = True
                    break
                if not joined:
                    break
            i = e
        for j in range(n):
            loc[lst[j]] = -1
    return added


@njit(cache=True, nogil=True, inline="always")
def distance_bin(x, bins):
    """``x`` in ``[0, 1)`` as one of ``bins`` equal classes; the last for anything else
    (far, NaN, an empty cell's extent)."""
    if not (x >= 0.0 and x < 1.0):
        return bins - 1
    return min(bins - 1, int(x * bins))


@njit(cache=True, nogil=True, inline="always")
def turned_centroid(points, tri, t, ca, sa):
    """``(x, y)``: triangle ``t``'s centroid in the turned axes."""
    x = (points[tri[t, 0], 0] + points[tri[t, 1], 0] + points[tri[t, 2], 0]) / 3.0
    y = (points[tri[t, 0], 1] + points[tri[t, 1], 1] + points[tri[t, 2], 1]) / 3.0
    return _turn(x, y, ca, sa)
