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
    "nth",
    "kd_lines",
    "fish_angle",
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
    "RingFrame",
    "ring_frame",
    "boundary_loops",
    "SECTORS",
    "SEAMS",
    "RING_RAYS",
    "RING_ASPECT",
    "RIM_FORWARD",
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
ANGLE_SAMPLE = 1 << 13
#: Levels whose lines the turn is judged on (k = 8 and k = 64 stretches meet there).
ANGLE_LEVELS = 3
#: What a hole's gap costs against a line's length inside the domain (:func:`fish_angle`):
#: the rim path round half a round hole is pi / 2 times its diameter.
GAP_COST = 1.5


class FishLines(NamedTuple):
    """Result of :func:`kd_lines`: per cell of levels ``0..depth`` (flat, level ``l``'s
    cells from :func:`level_offset`), its spine line (a coordinate across the level's
    axis), the along-medians of its two sides (``fars``, two per cell) and its sample's
    extent (the longer side of its bounding box)."""

    lines: np.ndarray
    fars: np.ndarray
    extent: np.ndarray


def fish_depth(n_sample: int, levels: int = FISH_LEVELS) -> int:
    """Fishbone levels for a sample of ``n_sample`` centroids: at least
    ``FISH_MIN_CELL`` of them per deepest cell, at most ``levels`` (0: none, the count
    quadtree alone)."""
    d = 0
    while d < levels and 4 ** (d + 1) * FISH_MIN_CELL <= n_sample:
        d += 1
    return d


@njit(cache=True, nogil=True, inline="always")
def level_offset(level):
    """First flat index of level ``level``'s cells (``(4^level - 1) / 3``)."""
    return ((1 << (2 * level)) - 1) // 3


@njit(cache=True, nogil=True)
def nth(key, other, lo, hi, k, carry):
    """Reorder ``key[lo:hi]`` so that ``key[k]`` is the ``k``-th smallest, none above
    it before and none below it after (quickselect with a three-way split: equal
    values, as on a grid, cost no extra passes); with ``carry`` ``other`` moves
    alongside (the coordinates move, not indices: sequential memory)."""
    while hi - lo > 1:
        x, y, z = key[lo], key[(lo + hi) // 2], key[hi - 1]
        pivot = max(min(x, y), min(max(x, y), z))  # median of three
        lt, i, gt = lo, lo, hi
        while i < gt:
            v = key[i]
            if v < pivot:
                key[i], key[lt] = key[lt], v
                if carry:
                    other[i], other[lt] = other[lt], other[i]
                lt += 1
                i += 1
            elif v > pivot:
                gt -= 1
                key[i], key[gt] = key[gt], v
                if carry:
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
def _box_extent(xs, ys, a, b):
    """The longer side of the bounding box of points ``a..b`` (0 for none)."""
    if b <= a:
        return 0.0
    x0 = x1 = xs[a]
    y0 = y1 = ys[a]
    for i in range(a + 1, b):
        x0 = min(x0, xs[i])
        x1 = max(x1, xs[i])
        y0 = min(y0, ys[i])
        y1 = max(y1, ys[i])
    return max(x1 - x0, y1 - y0)


@njit(cache=True, nogil=True)
def _kd_lines_into(xy, depth, lines, fars, extent, sectors, cuts):
    """The kd build of :func:`kd_lines` over the points ``xy`` ((s, 2), turned). With
    ``sectors`` (the ring frame: ``xy`` sorted by angle, ``sectors[j]`` the first of
    sector ``j``, ``cuts`` the borders and the rim's radius) levels 0 and 1 are the
    ring's (:func:`descend`) and the plain build starts at level 2."""
    s = xy.shape[0]
    xs = xy[:, 0].copy()
    ys = xy[:, 1].copy()
    seg = np.zeros(2, np.int64)
    seg[1] = s
    start = 0
    if sectors.shape[0] > 0:
        start = 2
        lines[0] = cuts[7]  # the rim's radius: where the sectors hang
        lines[lines.shape[0] - 1] = cuts[3]
        fars[0] = cuts[1]
        fars[1] = cuts[5]
        extent[0] = _box_extent(xs, ys, 0, s)
        seg = np.empty(17, np.int64)
        for i in range(4):  # quarter i: sectors 2i and 2i + 1, its cells 0 and 2 at level 2
            lines[1 + i] = cuts[2 * i]
            fars[2 + 2 * i] = np.nan
            fars[3 + 2 * i] = np.nan
            extent[1 + i] = _box_extent(xs, ys, sectors[2 * i], sectors[2 * i + 2])
            seg[4 * i] = sectors[2 * i]
            seg[4 * i + 1] = sectors[2 * i + 1]
            seg[4 * i + 2] = sectors[2 * i + 1]
            seg[4 * i + 3] = sectors[2 * i + 2]
        seg[16] = s
    for level in range(start, depth + 1):
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
            extent[off + c] = _box_extent(xs, ys, a, b)
            k = (b - a) // 2
            nth(across, along, a, b, a + k, True)
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
                nth(along, across, sa, sb, sa + kk, True)
                fars[2 * (off + c) + side] = along[sa + kk]
                nxt[4 * c + 2 * side + 1] = sa + kk
        seg = nxt


def kd_lines(xy, depth, ring=None):
    """The fishbone's lines over centroids ``xy`` ((s, 2) float64, in the turned axes).

    Level ``l``'s line runs along x for even ``l`` (a y value), along y for odd: each
    cell's line is the median across of its centroids (the upper side, ``>= line``,
    holding ``ceil(n / 2)``), each side's far half is ``>= `` its median along the line
    (``fars``). A cell holds its spine's centroids too (on their side): a spine's rows
    are walked just before or after the cells beside it, so the regions' counts stay
    equal at every level (session 11: otherwise the errors add up level by level).
    With ``ring`` (a :class:`RingFrame`; ``xy`` in its frame, ``depth`` >= 2) levels 0
    and 1 are the rim and its eight sectors (:func:`descend`), and ``lines`` has one
    more entry, last: the middle sector border.
    Returns :class:`FishLines` for levels ``0..depth``."""
    n = level_offset(depth + 1)
    xy = np.ascontiguousarray(xy, np.float64)
    sectors = np.zeros(0, np.int64)
    cuts = np.zeros(0)
    if ring is not None:
        xy = xy[np.argsort(xy[:, 1], kind="stable")]
        cuts = np.r_[ring.cuts, ring.r_in]
        sectors = np.r_[0, np.searchsorted(xy[:, 1], ring.cuts), len(xy)].astype(np.int64)
    out = FishLines(np.empty(n + (ring is not None)), np.empty(2 * n), np.empty(n))
    _kd_lines_into(xy, depth, out.lines, out.fars, out.extent, sectors, cuts)
    return out


@njit(cache=True, nogil=True, inline="always")
def _turn(x, y, ca, sa):
    return ca * x + sa * y, ca * y - sa * x


@njit(cache=True, nogil=True)
def descend(cx, cy, x0, x1, y0, y1, lines, fars, depth, ring, on_hole):
    """``(cell, spine level)`` of a triangle of turned centroid ``(cx, cy)`` and box
    ``[x0, x1] x [y0, y1]``: the deepest cell (2 bits a level, ``2 * side + far``) and
    the first level whose line its box straddles (``depth``: none).

    ``ring``: the ring frame (:func:`ring_frame`; ``x`` the radius, ``y`` the angle):
    level 0's spine is the triangles touching the hole (``on_hole``), its four
    children the quarters of the angle (``lines[-1]`` the middle border, ``fars`` the
    others), level 1 halves each quarter by angle with no spine of its own, so that
    eight sectors hang from the rim; the levels below are the plain ones."""
    reg = 0
    spine = depth
    for level in range(depth):
        oc = level_offset(level) + reg
        if ring and level < 2:
            if level == 0:
                if on_hole:
                    spine = 0
                s = 1 if cy >= lines[lines.shape[0] - 1] else 0
                f = 1 if cy >= fars[2 * oc + s] else 0
            else:
                s = 1 if cy >= lines[oc] else 0
                f = 0
            reg = 4 * reg + 2 * s + f
            continue
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
def _unwrap(ay, by, cy, span):
    """The ring frame's angle coordinates (``y``, in ``[0, span)``) of a triangle's
    corners, the ones past the seam moved by ``span`` so that the triangle is whole,
    its centroid back in ``[0, span)`` (``span`` 0: the plain frame, unchanged)."""
    if span > 0.0 and max(ay, by, cy) - min(ay, by, cy) > 0.5 * span:
        ay = ay + span if ay < 0.5 * span else ay
        by = by + span if by < 0.5 * span else by
        cy = cy + span if cy < 0.5 * span else cy
        if ay + by + cy >= 3.0 * span:
            ay, by, cy = ay - span, by - span, cy - span
    return ay, by, cy


@njit(cache=True, nogil=True, inline="always")
def turned_box(points, tri, t, ca, sa, span):
    """Turned centroid and bounding box of triangle ``t`` (``span`` > 0: the ring
    frame's points, unturned, a triangle across the seam made whole, :func:`_unwrap`)."""
    ax, ay = _turn(points[tri[t, 0], 0], points[tri[t, 0], 1], ca, sa)
    bx, by = _turn(points[tri[t, 1], 0], points[tri[t, 1], 1], ca, sa)
    cx, cy = _turn(points[tri[t, 2], 0], points[tri[t, 2], 1], ca, sa)
    ay, by, cy = _unwrap(ay, by, cy, span)
    return ((ax + bx + cx) / 3.0, (ay + by + cy) / 3.0, min(ax, bx, cx), max(ax, bx, cx),
            min(ay, by, cy), max(ay, by, cy))


@njit(cache=True, nogil=True)
def descend_into(points, tri, ca, sa, span, hole, lines, fars, depth, fish_shift, qr, half, lo, hi):
    """Cells of triangles ``lo..hi`` (:func:`descend`): ``qr[t, 2]`` the deepest cell
    ``| spine level << fish_shift`` (``depth``: on no spine), ``half`` the top line's
    side (the two searches' halves). ``span`` > 0: the ring frame, ``hole`` the hole's
    vertices (:func:`ring_frame`)."""
    ring = span > 0.0
    for t in range(lo, hi):
        cx, cy, x0, x1, y0, y1 = turned_box(points, tri, t, ca, sa, span)
        rim = ring and (hole[tri[t, 0]] or hole[tri[t, 1]] or hole[tri[t, 2]])
        reg, sp = descend(cx, cy, x0, x1, y0, y1, lines, fars, depth, ring, rim)
        qr[t, 2] = reg | (sp << fish_shift)
        half[t] = (reg >> (2 * depth - 1)) & 1 if depth > 0 else 0


@njit(cache=True, nogil=True)
def _sample_centroids_into(points, tri, sample, ca, sa, span, xy):
    for i in range(sample.shape[0]):
        xy[i, 0], xy[i, 1] = turned_centroid(points, tri, sample[i], ca, sa, span)


def sample_centroids(points, tri, sample, angle, span=0.0):
    """(s, 2): the turned centroids of triangles ``sample`` (``span`` > 0: ``points``
    in the ring frame, :func:`turned_box`)."""
    xy = np.empty((len(sample), 2))
    ca, sa = (1.0, 0.0) if span > 0 else (math.cos(angle), math.sin(angle))
    _sample_centroids_into(points, tri, np.asarray(sample, np.int64), ca, sa, float(span), xy)
    return xy


def fish_angle(points, tri, twin, sample=None):
    """The turn of the fishbone's axes (radians, ``[0, pi)``, one of ``AUTO_ANGLES``)
    whose lines of the top ``ANGLE_LEVELS`` levels are shortest inside the domain,
    each hole or notch a line crosses counted ``GAP_COST`` times its width (the
    spine is joined round it, :func:`join_gaps_into`). The stretches of k = 8 and
    k = 64 meet along those lines: on the plate with two holes the top line goes
    between the holes (session 11: 1.38 against 1.82 at k = 8 along the holes).

    The lines are medians of a sample of the centroids (every ``m // ANGLE_SAMPLE``-th
    triangle); their lengths are exact, from the boundary edges (``twin < 0``) they
    cross (:func:`_line_costs`). Session 12 first counted the sampled triangles on the
    spines: as slow at 2**15 triangles a turn, and at 2**13 the sample's noise picked
    wrong turns on the plate. Lengths are not weighted by the mesh's density (a
    graded mesh's lines are judged as if it were uniform)."""
    m = tri.shape[0]
    if sample is None:
        sample = np.arange(0, m, max(1, m // ANGLE_SAMPLE))
    sample = np.asarray(sample, np.int64)
    depth = min(ANGLE_LEVELS, fish_depth(len(sample)))
    if depth == 0:
        return 0.0
    h = np.flatnonzero(twin < 0)
    ends = np.ascontiguousarray(np.c_[points[tri[h // 3, h % 3]], points[tri[h // 3, (h % 3 + 1) % 3]]])
    centroids = points[tri[sample]].mean(axis=1)
    costs = np.empty(AUTO_ANGLES)
    for i in range(AUTO_ANGLES):
        a = math.pi * i / AUTO_ANGLES
        ca, sa = math.cos(a), math.sin(a)
        xy = np.c_[ca * centroids[:, 0] + sa * centroids[:, 1], ca * centroids[:, 1] - sa * centroids[:, 0]]
        fl = kd_lines(xy, depth - 1)  # lines of levels 0 .. depth - 1
        costs[i] = _line_costs(fl.lines, fl.fars, depth, ends, ca, sa)
    return math.pi * int(np.argmin(costs)) / AUTO_ANGLES


@njit(cache=True, nogil=True)
def _line_costs(lines, fars, levels, ends, ca, sa):
    """Length inside the domain of each line of levels ``< levels`` within its cell
    (a rectangle in the turned axes, bounded by its ancestors' lines and far
    medians), plus ``GAP_COST`` times each gap between two inside stretches of it.
    ``ends``: (b, 4) boundary edges ``x0 y0 x1 y1``; a point of the line is inside
    when an odd number of them cross the line before it (the domain is closed)."""
    nb = ends.shape[0]
    ex = np.empty((nb, 4))
    for e in range(nb):
        ex[e, 0], ex[e, 1] = _turn(ends[e, 0], ends[e, 1], ca, sa)
        ex[e, 2], ex[e, 3] = _turn(ends[e, 2], ends[e, 3], ca, sa)
    hits = np.empty(nb)
    total = 0.0
    for level in range(levels):
        across = 1 if level % 2 == 0 else 0
        for cell in range(1 << (2 * level)):
            lo = np.array([-np.inf, -np.inf])  # the cell's rectangle
            hi = np.array([np.inf, np.inf])
            reg = 0
            for up in range(level):  # from the top: each ancestor's side and far half
                digit = (cell >> (2 * (level - 1 - up))) & 3
                s, f = digit >> 1, digit & 1
                oc = level_offset(up) + reg
                ac = 1 if up % 2 == 0 else 0
                if s:
                    lo[ac] = max(lo[ac], lines[oc])
                else:
                    hi[ac] = min(hi[ac], lines[oc])
                far = fars[2 * oc + s]
                if f:
                    lo[1 - ac] = max(lo[1 - ac], far)
                else:
                    hi[1 - ac] = min(hi[1 - ac], far)
                reg = 4 * reg + digit
            line = lines[level_offset(level) + cell]
            if not (line >= lo[across] and line <= hi[across]):
                continue  # an empty cell (NaN)
            n = 0
            for e in range(nb):  # where the boundary crosses the line, along it
                a0, a1 = ex[e, across], ex[e, 2 + across]
                if (a0 < line) != (a1 < line):
                    w = (line - a0) / (a1 - a0)
                    hits[n] = ex[e, 1 - across] + w * (ex[e, 3 - across] - ex[e, 1 - across])
                    n += 1
            xs = np.sort(hits[:n])
            inside = 0.0
            gaps = 0.0
            last_end = np.nan  # where the last inside stretch (within the cell) ended
            for j in range(0, n - 1, 2):  # inside between crossings 2i and 2i + 1
                a = max(xs[j], lo[1 - across])
                b = min(xs[j + 1], hi[1 - across])
                if b <= a:
                    continue
                if last_end == last_end:  # not NaN: a gap since the last stretch
                    gaps += a - last_end
                inside += b - a
                last_end = b
            total += inside + GAP_COST * gaps
    return total


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
def join_gaps_into(points, tri, twin, ca, sa, span, qr, fish_shift, lines, depth, levels, on_rim):
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
                            cu = turned_centroid(points, tri, u, ca, sa, span)
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
def turned_centroid(points, tri, t, ca, sa, span):
    """``(x, y)``: triangle ``t``'s centroid in the turned axes (``span`` > 0: in the
    ring frame, :func:`turned_box`)."""
    x = (points[tri[t, 0], 0] + points[tri[t, 1], 0] + points[tri[t, 2], 0]) / 3.0
    if span > 0.0:
        ay, by, cy = _unwrap(points[tri[t, 0], 1], points[tri[t, 1], 1], points[tri[t, 2], 1], span)
        return x, (ay + by + cy) / 3.0
    y = (points[tri[t, 0], 1] + points[tri[t, 1], 1] + points[tri[t, 2], 1]) / 3.0
    return _turn(x, y, ca, sa)


#: Sectors of the ring frame (k = 8 stretches are sectors: every end on the rim).
SECTORS = 8
#: Rays from the hole :func:`ring_frame` measures the domain's width along, and
#: the most the longest may be of the shortest for the ring frame (a guess: the gear
#: and a square round a square hole are about 1.4, a 2:1 plate round a hole 3.5).
RING_RAYS = 16
RING_ASPECT = 2.5
#: Rows of a rim triangle counted as walked on the way out, of its three (the rest lie
#: on the rim's hole side, walked after the last sector). Session 13 on the gear: 1.4
#: to 1.6 measured from the walk (rows after the last sector over rim triangles: 1.61
#: at 100 000 input triangles, 1.67 at 10 000), 1.6 leaves the sector starts within
#: 0.3 % of a sector's rows of ``j n / 8``, and cuts least (three meshes, 1.4-2.0 tried).
RIM_FORWARD = 1.6
#: Seams tried by :func:`ring_frame` (``i * 2 pi / (SECTORS * SEAMS)`` radians: the
#: sector borders repeat every ``2 pi / SECTORS``).
SEAMS = 16


class RingFrame(NamedTuple):
    """Result of :func:`ring_frame`."""

    #: (n, 2) float64: each vertex as (radius, angle from the seam x ``r_ref``)
    points: np.ndarray
    #: ``2 pi r_ref``: the angle coordinate's range (a triangle across the seam is unwrapped)
    span: float
    #: (n,) bool: the vertices of the hole the sectors hang round
    hole: np.ndarray
    #: (SECTORS - 1,): the sector borders (angle coordinate), by rows walked
    cuts: np.ndarray
    #: the hole's radius (mean over its vertices): where each sector hangs from the rim
    r_in: float
    #: the seam (radians), the centre
    seam: float
    centre: np.ndarray


@njit(cache=True, nogil=True)
def _loops_into(tri, twin, label):
    """``label[v]``: a boundary vertex's loop (a union-find root of the boundary edges;
    -1 for the others)."""
    for h in range(twin.shape[0]):
        if twin[h] < 0:
            t, k = h // 3, h % 3
            u, v = tri[t, k], tri[t, (k + 1) % 3]
            if label[u] < 0:
                label[u] = u
            if label[v] < 0:
                label[v] = v
            a, b = _root(label, u), _root(label, v)
            if a != b:
                label[max(a, b)] = min(a, b)
    for v in range(label.shape[0]):
        if label[v] >= 0:
            label[v] = _root(label, v)


def boundary_loops(tri, twin, n_points):
    """(n_points,) int64: each boundary vertex's loop id (its lowest vertex), -1 inside."""
    label = np.full(n_points, -1, np.int64)
    _loops_into(tri, twin, label)
    return label


def _inside(p, a, b):
    """Whether point ``p`` is inside the polygon of edges ``a[i] -> b[i]`` (even-odd)."""
    cross = (a[:, 1] > p[1]) != (b[:, 1] > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (p[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(cross & (x > p[0])) % 2)


def _ray_lengths(centre, angles, a, b):
    """(r,): length inside the domain of the ray from ``centre`` (in the hole) at each
    of ``angles``: crossings of the boundary edges ``a -> b``, inside between the
    crossings ``2 i`` and ``2 i + 1`` (the centre is outside the domain). Each ray is
    nudged by a thousandth of a radian: a ray through a vertex (polygons are often
    drawn at round angles) would count its crossing twice or not at all."""
    angles = np.asarray(angles, np.float64) + 1e-3
    d = np.c_[np.cos(angles), np.sin(angles)]  # (r, 2)
    e = b - a
    p = a - centre
    den = e[None, :, 0] * d[:, None, 1] - e[None, :, 1] * d[:, None, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = (p[None, :, 1] * d[:, None, 0] - p[None, :, 0] * d[:, None, 1]) / den
        t = (p[None, :, 0] + w * e[None, :, 0]) * d[:, None, 0] + (p[None, :, 1] + w * e[None, :, 1]) * d[:, None, 1]
    t = np.where((w >= 0) & (w < 1) & (t > 0), t, np.inf)
    t.sort(axis=1)
    out = np.zeros(len(angles))
    for i, row in enumerate(t):
        row = row[np.isfinite(row)]
        out[i] = float((row[1::2] - row[: 2 * (len(row) // 2) : 2]).sum())
    return out


def _sector_cuts(th, rim, seam):
    """The ``SECTORS - 1`` inner borders (angles from ``seam``) of sectors of equal
    rows walked on the way out: three rows a triangle, ``RIM_FORWARD`` for a rim
    triangle (the rest of its rows lie on the rim's hole side, walked on the way back
    after the last sector, which is shorter by them). ``th``: the sampled centroids' angles in
    ``[0, 2 pi)``, sorted; ``rim``: theirs (one sort for every seam tried)."""
    start = int(np.searchsorted(th, seam))
    u = np.roll(th, -start) - seam
    u[u < 0] += 2 * math.pi
    w = np.where(np.roll(rim, -start), RIM_FORWARD, 3.0)
    pos = (np.cumsum(w) - 0.5 * w) * SECTORS / (3.0 * len(u))
    at = np.searchsorted(pos, np.arange(1, SECTORS))
    return u[np.minimum(at, len(u) - 1)]


def ring_frame(points, tri, twin, sample):
    """The ring frame of a domain that wraps round a hole, else None.

    An annulus has no good kd cells (session 12: the gear's fishbone cut 1.66 x
    METIS's at k = 8 and k = 64): the walk must go round the hole, and the cheapest
    way is along its rim. So when the largest hole holds the centroid of the sampled
    triangles, the fishbone is built in polar coordinates round the hole's centre:
    the triangles touching the hole are level 0's spine (the rim, cut open at a
    *seam*), ``SECTORS`` sectors of equal rows hang from it at their middles, and each
    sector is a plain fishbone whose top spine is the radial line through its
    middle (:func:`descend`). The walk then sweeps the ring once, sector after sector,
    and returns along the rim's hole side: at k = 8 the stretches are the sectors,
    every end on the rim (the tour of the ends costs the rim, not radial spines).

    The seam (one of ``SEAMS`` turns) is the one whose sector borders are shortest
    inside the domain (rays from the centre, :func:`_ray_lengths`): on the gear,
    through notches rather than teeth."""
    n = points.shape[0]
    if len(sample) < 4 ** 3 * FISH_MIN_CELL:
        return None
    label = boundary_loops(tri, twin, n)
    on = np.flatnonzero(label >= 0)
    ids, loop = np.unique(label[on], return_inverse=True)
    if len(ids) < 2:
        return None
    lo = np.full((len(ids), 2), np.inf)
    hi = np.full((len(ids), 2), -np.inf)
    np.minimum.at(lo, loop, points[on])  # each loop's box, one pass (a domain may have many holes)
    np.maximum.at(hi, loop, points[on])
    ext = (hi - lo).max(axis=1)
    outer = int(np.argmax(ext))
    ext[outer] = -1.0
    hole_id = ids[int(np.argmax(ext))]
    h = np.flatnonzero(twin < 0)
    ua, ub = tri[h // 3, h % 3], tri[h // 3, (h % 3 + 1) % 3]
    on = label[ua] == hole_id
    a, b = points[ua[on]], points[ub[on]]
    c = points[tri[sample]].mean(axis=1)
    mean = c.mean(axis=0)
    if not _inside(mean, a, b):
        return None
    hole = label == hole_id
    centre = points[hole].mean(axis=0)
    if not _inside(centre, a, b):
        centre = mean
    all_a, all_b = points[ua], points[ub]
    rays = _ray_lengths(centre, np.arange(RING_RAYS) * (2 * math.pi / RING_RAYS), all_a, all_b)
    if not rays.min() > 0 or rays.max() > RING_ASPECT * rays.min():
        return None  # a long domain round a hole: its sectors would be long wedges
    r_in = float(np.hypot(*(points[hole] - centre).T).mean())
    d = c - centre
    th = np.arctan2(d[:, 1], d[:, 0]) % (2 * math.pi)
    r_ref = float(np.median(np.hypot(d[:, 0], d[:, 1])))
    o = np.argsort(th)
    th = th[o]
    rim = hole[tri[sample[o]]].any(axis=1)
    best = None
    step = max(1, len(th) // ANGLE_SAMPLE)  # the seams judged on a sample of the sample
    for i in range(SEAMS):
        seam = 2 * math.pi * i / (SECTORS * SEAMS)
        cuts = _sector_cuts(th[::step], rim[::step], seam)
        cost = float(_ray_lengths(centre, np.r_[seam, seam + cuts], all_a, all_b).sum())
        if best is None or cost < best[0]:
            best = (cost, seam)
    seam = best[1]
    cuts = _sector_cuts(th, rim, seam)
    dp = points - centre
    pts = np.empty((n, 2))
    pts[:, 0] = np.hypot(dp[:, 0], dp[:, 1])
    pts[:, 1] = ((np.arctan2(dp[:, 1], dp[:, 0]) - seam) % (2 * math.pi)) * r_ref
    return RingFrame(pts, 2 * math.pi * r_ref, hole, cuts * r_ref, r_in, seam, centre)
