"""Theorem 2.4's construction kernels (numba): incenters, the dual spanning forest, the walk.

Arkin, Held, Mitchell, Skiena, Thm 2.4: incenters of the input triangles, one flip
per dual spanning-tree edge (a midpoint where the tree crosses a constrained edge),
and the walk around the tree that writes the Hamiltonian cycle
(``hammesh.postprocess.incircle`` drives them). Conventions as in
``hammesh.halfedge._kernels``: fill kernels behind thin numpy wrappers, problems
reported by return codes.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh import threads
from hammesh import pages
from hammesh.threads import row_ranges, run_all
from hammesh.postprocess import _fishbone_kernels as fk
from hammesh.verify.stream import UNLINKED

__all__ = [
    "Forest",
    "Classes",
    "Frame",
    "QuadFrame",
    "quad_frame",
    "fishbone_frame",
    "forest_classes",
    "edge_class_of",
    "fish_class",
    "FISH_SHIFT",
    "GAP_LEVELS",
    "LEAF_CLASSES",
    "quadtree_coords",
    "top_cross_angle",
    "CROSS_ANGLES",
    "CROSS_GAIN",
    "CROSS_SAMPLE",
    "edge_class",
    "N_CLASSES",
    "QUAD_CLASSES",
    "CELL_BITS",
    "RANK_BINS",
    "RANK_SAMPLE",
    "Slots",
    "incenters",
    "spanning_forest",
    "split_slots",
    "emit_cycles_into",
    "index_dtype",
    "find_root",
    "TREE_BIT",
    "CON_BIT",
    "WALK_STATE",
    "UNLINKED",
]


def index_dtype(n):
    """int32 for indices below ``n`` when they fit (half the memory traffic), else int64."""
    return np.int32 if n < 2**31 - 1 else np.int64


class Forest(NamedTuple):
    """Result of :func:`spanning_forest` (see there)."""

    triangles: np.ndarray
    code: np.ndarray
    order: np.ndarray
    firsts: np.ndarray
    split: np.ndarray


class Slots(NamedTuple):
    """Result of :func:`split_slots` (see there)."""

    mid_h: np.ndarray
    mid_id: np.ndarray
    mid_a: np.ndarray
    mid_b: np.ndarray


def incenters(points, tri, out=None):
    """Incenters ``(|BC| A + |CA| B + |AB| C) / (|BC| + |CA| + |AB|)``, (m, 2).

    ``out`` may be a preallocated (m, 2) float64 array (e.g. a slice of the output's
    point array, saving a copy).
    """
    if out is None:
        out = np.empty((tri.shape[0], 2), np.float64)
    _incenters_into(points, tri, out)
    return out


@njit(cache=True, nogil=True)
def _incenters_into(points, tri, out):
    m = tri.shape[0]
    for t in range(m):
        ax = points[tri[t, 0], 0]
        ay = points[tri[t, 0], 1]
        bx = points[tri[t, 1], 0]
        by = points[tri[t, 1], 1]
        cx = points[tri[t, 2], 0]
        cy = points[tri[t, 2], 1]
        # plain sqrt: np.hypot's overflow guard costs 5x here, and |x| <= 1e30 is
        # validated, so the squares cannot overflow
        la = np.sqrt((cx - bx) * (cx - bx) + (cy - by) * (cy - by))
        lb = np.sqrt((ax - cx) * (ax - cx) + (ay - cy) * (ay - cy))
        lc = np.sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay))
        s = la + lb + lc
        out[t, 0] = (la * ax + lb * bx + lc * cx) / s
        out[t, 1] = (la * ay + lb * by + lc * cy) / s


@njit(cache=True, nogil=True)
def bucket_push(queue, head, free, n_used, c, g):
    """Push half-edge ``g`` on bucket ``c`` of the forest's queue (rows are linked lists
    ``queue[slot] = (next, half-edge)``; a popped row heads the ``free`` list and is
    reused first). Returns the new ``(free, n_used)``."""
    slot = free
    if slot >= 0:
        free = queue[slot, 0]
    else:
        slot = n_used
        n_used += 1
    queue[slot, 0] = head[c]
    queue[slot, 1] = g
    head[c] = slot
    return free, n_used


@njit(cache=True)
def find_root(parent, x):
    """Root of ``x`` in the union-find forest ``parent`` (compressing the path)."""
    root = x
    while parent[root] != root:
        root = parent[root]
    while parent[x] != root:  # path compression
        nxt = parent[x]
        parent[x] = root
        x = nxt
    return root


#: Bits of a packed half-edge code (``spanning_forest``): ``code >> 2`` is the twin
#: plus one (0 on the boundary); bit 1 marks a tree edge, bit 0 a constrained one.
TREE_BIT = 2
CON_BIT = 1


#: Bits per axis of the quadtree that orders the tree's edges (:func:`spanning_forest`).
CELL_BITS = 15
#: Distance classes per quadtree level: edges nearer a cell's centre are taken first.
CENTRE_BINS = 16
#: Histogram bins per axis that turn coordinates into triangle counts (:func:`spanning_forest`).
RANK_BINS = 1024
#: Centroids sampled for those histograms (every ``m // RANK_SAMPLE``-th triangle).
RANK_SAMPLE = 1 << 14
#: Rotations of the quadtree tried (``top_cross_angle``): ``i * 90 / CROSS_ANGLES`` degrees.
CROSS_ANGLES = 8
#: Triangles sampled to judge the rotations (every ``m // CROSS_SAMPLE``-th).
CROSS_SAMPLE = 1 << 12
#: A rotation is taken only if its top cross crosses at most this share of the dual
#: edges the unrotated one crosses (the estimate comes from a sample: no change on noise).
CROSS_GAIN = 0.9
#: Edge classes: ``level * CENTRE_BINS + bin`` for free edges, then one for constrained ones.
N_CLASSES = (CELL_BITS + 1) * CENTRE_BINS + 1
#: Classes of the free edges inside one top-level quadrant (levels below ``CELL_BITS``).
QUAD_CLASSES = CELL_BITS * CENTRE_BINS


def spanning_forest(tri, twin, is_con, points=None, levels=fk.FISH_LEVELS):
    """A compact spanning forest of the dual graph that crosses the fewest constrained edges.

    Prim's algorithm with a bucket queue over edge *classes* (issue 14): a free dual
    edge's class is its *level*, the size of the smallest cell of a quadtree of the
    triangles' centroids (``CELL_BITS`` levels) holding both its triangles, refined by
    how near the edge lies to the centre of that cell (``CENTRE_BINS`` steps); every
    constrained edge is in the last class. The search always takes the lowest class
    edge out of its tree, so the result is a minimum spanning forest for these
    weights, and like every one of them it holds, for each class, a spanning forest
    of the edges up to that class: the triangles of every quadtree cell whose dual is
    connected form one subtree, and a cell's four children hang together near its
    centre. The Thm 2.4 walk around the tree then sweeps the domain cell by cell like
    a space-filling curve, and a stretch of the cycle covers a compact region
    (``hammesh.partition`` cuts the cycle into parts). Constrained edges come last, so
    the forest crosses exactly ``regions - pieces`` of them (a region is a piece of
    the dual cut along every constrained edge), the fewest possible.

    Session 5 grew the same tree by Kruskal's algorithm (a counting sort of the edges
    by class, a union-find); Prim's search needs neither, visits the triangles in
    the order the walk will (cell by cell: the new numbering, so the walk reads memory
    nearly in sequence) and costs about what a plain breadth-first search does
    (``benchmarks/bench_partition.py`` measures both). The first idea, edges ordered
    by Hilbert key alone, links sibling cells anywhere along their shared side; the
    walk then goes out along one side of the chain of cells and back along the other,
    and a stretch of the cycle is a thin strip (cuts 6-16x METIS's instead of 1.5x).

    **Two searches side by side.** The quadtree's coordinates count triangles, so the
    top split of one axis halves them; every edge between the two halves (or between
    any two top-level quadrants) is in the top level's classes, above every edge
    inside a quadrant. So the minimum spanning forest is one of the edges inside the
    quadrants, then joined over the top-level and constrained edges in class order
    (Kruskal's rule over the few of them): :func:`_prim_half_into` runs once per half,
    on its own thread (they share nothing they write), each search inside one
    quadrant; :func:`_join_into` joins them. The searches also write the output
    (``tri_r`` and the packed ``code``) as they go, each pair of half-edges when its
    second triangle is reached, so no second pass over the triangles is needed. The
    result does not depend on the number of threads.

    Each search starts at its lowest input triangle not yet reached; the triangles
    come back renumbered in the order they were reached (the low half first), and the
    half-edge data is packed into one array so that the walk reads one word per
    half-edge. ``firsts`` holds each piece's lowest input triangle. Without
    ``points`` every free edge is in one class (a plain search, on one thread).

    Parameters
    ----------
    tri : (m, 3) int64
    twin : (3 m,) int64
    is_con : (3 m,) bool
    points : (n, 2) float64, optional
        The quadtree's coordinates.

    Returns
    -------
    tri_r : (m, 3) int64
        ``tri[order]``.
    code : (3 m,) int64
        For half-edge ``h = 3 i + k`` of ``tri_r``: ``(twin + 1) << 2 | tree << 1 |
        constrained``, the twin in the new numbering (see ``TREE_BIT``, ``CON_BIT``).
    order : (m,) int64
        New triangle ``i`` is input triangle ``order[i]``.
    firsts : (p,) int64
        One triangle of each connected piece, new numbering, the pieces ordered by
        their lowest input triangle.
    split : (2 q,) int64
        The constrained tree edges (both half-edges, new numbering, sorted): where the
        walk inserts midpoints (``split_slots``).
    """
    m = tri.shape[0]
    spans = row_ranges(m, threads.THREAD_MIN_ROWS)
    # per input triangle: its quadtree coordinates and (-1 until reached) its new
    # number, side by side
    # and its fishbone cell: 12 bytes a triangle, read together
    qr = pages.fresh((m, 3), index_dtype(m))
    out = {}

    def outputs() -> None:  # their pages faulted in beside the classes' first pass
        out["order"] = pages.fresh(m, np.int64)
        out["tri_r"] = pages.fresh(tri.shape, tri.dtype)
        out["code"] = pages.fresh(3 * m, np.int64)

    cl = fishbone_frame(tri, twin, points, qr, side_work=outputs, levels=levels)
    pts, ca, sa = cl.points, cl.ca, cl.sa
    order, tri_r, code = out["order"], out["tri_r"], out["code"]
    # one search per side of the top line (each holds half the triangles), side by side
    n_hi = int(np.count_nonzero(cl.half))
    n_lo = m - n_hi
    starts = np.empty(m, np.int64)  # components' first new numbers: low half from 0, high from n_lo
    # each half's queue rows and cross edges: most rows are written, so small pages
    # faulted at once (or the reserve's) beat numpy's huge pages on first touch
    queue = pages.fresh((3 * m, 2), index_dtype(3 * m))
    halves = [(0, 0, 0, 3 * n_lo), (1, n_lo, 3 * n_lo, 3 * m)]
    calls = [
        (lambda side=side, base=base, a=a, b=b: _prim_half_into(
            tri, twin, is_con, pts, ca, sa, cl.span, cl.lines, cl.extent, cl.depth, cl.n_classes - 1, cl.cross_from, qr,
            cl.half, side, base, order, tri_r, code, starts[base:], queue, a, b))
        for side, base, a, b in halves
    ]
    # on small meshes one thread runs both (same result: the halves share nothing)
    found = run_all(calls) if len(spans) > 1 else [c() for c in calls]
    (c_lo, x_lo), (c_hi, x_hi) = found
    comp_starts = np.concatenate((starts[:c_lo], starts[n_lo : n_lo + c_hi]))
    # the cross edges in the order they were listed (each half's from its top row down)
    cross = np.concatenate((queue[3 * n_lo - x_lo : 3 * n_lo][::-1], queue[3 * m - x_hi :][::-1])).astype(np.int64)
    parent = np.empty(len(comp_starts), np.int64)
    split = np.empty(2 * len(cross), np.int64)
    n_split = _join_into(twin, is_con, qr, order, code, comp_starts, cross, parent, split, cl.cross_from,
                         cl.n_classes)
    firsts = _piece_firsts(parent, comp_starts, order, qr)
    return Forest(tri_r, code, order, firsts, np.sort(split[:n_split]))


class Frame(NamedTuple):
    """Result of :func:`fishbone_frame` (see there)."""

    half: np.ndarray
    lines: np.ndarray
    extent: np.ndarray
    depth: int
    angle: float
    cross_from: int
    n_classes: int
    #: the points the classes are computed from (the input's, or the ring frame's)
    points: np.ndarray
    #: their turn (1, 0 in the ring frame)
    ca: float
    sa: float
    #: the ring frame's angle range (``_fishbone_kernels.ring_frame``), 0: none
    span: float = 0.0


class Classes(NamedTuple):
    """Result of :func:`forest_classes`: ``cls`` (3 m,) int16, each half-edge's class
    (boundary half-edges 0), and the :class:`Frame` it came from."""

    cls: np.ndarray
    frame: Frame


#: Classes of the count quadtree's edges below the fishbone's deepest level.
LEAF_CLASSES = (CELL_BITS + 1) * CENTRE_BINS
#: Fishbone levels whose spines are joined round holes (deeper cells are small; on
#: the plate and the gear 3, 4 and all levels give the same cut, session 12).
GAP_LEVELS = 3
#: Whether a domain that wraps round a hole gets the ring frame
#: (``_fishbone_kernels.ring_frame``; False: every domain the turned kd frame).
RING = True


def fishbone_frame(tri, twin, points, qr, side_work=None, levels=fk.FISH_LEVELS):
    """Everything :func:`spanning_forest`'s edge classes are computed from.

    With ``points`` and at least ``4 * FISH_MIN_CELL`` triangles, the fishbone
    (``_fishbone_kernels``): its axes turned by ``fish_angle``, lines from a sample
    (``kd_lines``), each triangle's cells (:func:`_cells_into`, one pass with the
    quadtree coordinates), the spines of the top ``GAP_LEVELS`` levels joined round
    the holes their lines cross (``join_gaps_into``). The classes (:func:`edge_class_of`): below the
    fishbone's deepest level the count quadtree's (:func:`edge_class`, under
    ``LEAF_CLASSES``), then each level from the deepest up (``PER_LEVEL`` classes
    each), constrained edges last (``n_classes - 1``). The two searches' halves are
    the sides of the top line; ``cross_from`` is the top level's first class (those
    edges are the join's). On smaller meshes the count quadtree alone (``depth`` 0,
    turned by :func:`top_cross_angle`; the halves: the top split of its longer axis,
    the join's edges those between top-level quadrants).

    ``qr``: (m, 3) int array: column 0 gets the quadtree coordinates, 1 -1 (the
    search's "not reached"), 2 the fishbone cell and spine level (``FISH_SHIFT``).
    ``side_work``: run on another thread during the first pass (``spanning_forest``
    faults its outputs' pages there).
    """
    m = tri.shape[0]
    spans = row_ranges(m, threads.THREAD_MIN_ROWS)
    side_work = side_work if side_work is not None else (lambda: None)
    sample = np.arange(0, m, max(1, m // fk.FISH_SAMPLE))
    depth = fk.fish_depth(len(sample), levels) if points is not None else 0
    zeros = np.zeros(1, np.float64)
    if points is None or not m:
        qr[:, 0] = 0
        qr[:, 1] = -1
        qr[:, 2] = 0
        side_work()
        return Frame(np.zeros(m, np.int8), zeros, zeros, 0, 0.0, QUAD_CLASSES, N_CLASSES, np.zeros((1, 2)), 1.0, 0.0)
    if depth == 0:  # too few triangles for a fishbone level: the count quadtree
        angle = top_cross_angle(points, tri, twin)
        _beside(lambda: quadtree_coords(points, tri, qr, [(0, m)], angle), side_work, len(spans) > 1)
        qr[:, 2] = 0
        nx, ny = _half_counts(qr)
        hbit = 2 * CELL_BITS - 1 if abs(2 * nx - m) <= abs(2 * ny - m) else CELL_BITS - 1
        half = ((qr[:, 0] >> hbit) & 1).astype(np.int8)
        return Frame(half, zeros, zeros, 0, angle, QUAD_CLASSES, N_CLASSES, points, math.cos(angle), math.sin(angle))
    found = {}

    def first_pass() -> None:  # the frame (ring or turn), the lines and the quadtree's frame
        ring = fk.ring_frame(points, tri, twin, sample) if depth >= 3 and RING else None
        found["ring"] = ring
        if ring is not None:
            found["angle"] = 0.0
            # the rim's rows are walked between the sectors, not inside them: the
            # sectors' own lines are medians of the other triangles
            off_rim = ~ring.hole[tri[sample]].any(axis=1)
            xy = fk.sample_centroids(ring.points, tri, sample[off_rim], 0.0, ring.span)
            found["lines"] = fk.kd_lines(xy, depth, ring)
            found["frame"] = quad_frame(ring.points, tri, 0.0)
            return
        a = found["angle"] = fk.fish_angle(points, tri, twin)
        found["lines"] = fk.kd_lines(fk.sample_centroids(points, tri, sample, a), depth)
        found["frame"] = quad_frame(points, tri, a)

    _beside(first_pass, side_work, len(spans) > 1)
    angle, fl, fr, ring = found["angle"], found["lines"], found["frame"], found["ring"]
    pts = ring.points if ring is not None else points
    span = ring.span if ring is not None else 0.0
    hole = ring.hole if ring is not None else np.zeros(1, np.bool_)
    half = np.empty(m, np.int8)
    run_all([
        (lambda a=a, b=b: _cells_into(pts, tri, fr.ca, fr.sa, fr.x0, fr.y0, fr.bx, fr.by, fr.cum, fr.fx, fr.fy,
                                      span, hole, fl.lines, fl.fars, depth, qr, half, a, b))
        for a, b in spans
    ])
    on_rim = fk.rim_vertices(tri, twin, points.shape[0])
    levels = min(depth, GAP_LEVELS + (ring is not None))
    fk.join_gaps_into(pts, tri, twin, fr.ca, fr.sa, span, qr, FISH_SHIFT, fl.lines, depth, levels, on_rim)
    cross_from = LEAF_CLASSES + (depth - 1) * fk.PER_LEVEL
    return Frame(half, fl.lines, fl.extent, depth, angle, cross_from, LEAF_CLASSES + depth * fk.PER_LEVEL + 1,
                 pts, fr.ca, fr.sa, span)


def _beside(work, side_work, threaded: bool) -> None:
    """``work`` and ``side_work`` on two threads, or one after the other (a small mesh,
    or a process capped at one thread: ``hammesh.threads.limit``)."""
    if threaded:
        run_all([work, side_work])
    else:
        work()
        side_work()


def forest_classes(tri, twin, is_con, points=None, levels=fk.FISH_LEVELS):
    """The class of every dual edge that :func:`spanning_forest` ranks its tree by
    (:func:`fishbone_frame`; the search computes them as it goes, this lists them).
    Returns :class:`Classes`."""
    m = tri.shape[0]
    qr = np.empty((m, 3), index_dtype(m))
    fr = fishbone_frame(tri, twin, points, qr, levels=levels)
    cls = np.zeros(3 * m, np.int16)
    _edge_classes_into(fr.points, tri, fr.ca, fr.sa, fr.span, twin, is_con, qr, fr.lines, fr.extent, fr.depth,
                       fr.n_classes - 1, cls)
    return Classes(cls, fr)


@njit(cache=True, nogil=True)
def _edge_classes_into(points, tri, ca, sa, span, twin, is_con, qr, lines, extent, depth, con, cls):
    """:func:`edge_class_of` of every half-edge (boundary ones 0, constrained ``con``)."""
    for h in range(twin.shape[0]):
        g = twin[h]
        if g >= 0:
            cls[h] = con if is_con[h] else edge_class_of(points, tri, ca, sa, span, qr, h // 3, g // 3, lines, extent,
                                                         depth)


@njit(cache=True, nogil=True, inline="always")
def edge_class_of(points, tri, ca, sa, span, qr, t, u, lines, extent, depth):
    """Class of the free dual edge between triangles ``t`` and ``u`` (:func:`fishbone_frame`):
    the quadtree's :func:`edge_class` inside one deepest fishbone cell (most edges),
    else :func:`fish_class`."""
    fa = qr[t, 2]
    if fa == qr[u, 2] and (fa >> FISH_SHIFT) == depth:
        return edge_class(qr[t, 0], qr[u, 0])
    return fish_class(points, tri, ca, sa, span, qr, t, u, lines, extent, depth)


@njit(cache=True, nogil=True)
def fish_class(points, tri, ca, sa, span, qr, t, u, lines, extent, depth):
    """Class of the free dual edge between triangles ``t`` and ``u`` (:func:`fishbone_frame`),
    a separate call: the search's loop stays small for the common case.

    ``d``: the deepest fishbone level whose cell holds both triangles and neither in
    an ancestor's spine (the common 2-bit digits of the cells, capped by the spine
    levels; ``qr[:, 2]``). At ``d == depth`` the quadtree's :func:`edge_class`; else level ``d``'s classes from
    ``LEAF_CLASSES + (depth - 1 - d) * PER_LEVEL``: 0 both on the spine; a hang (one
    on it): the child's own spine end first (``HANG_BINS`` more for others), by the
    L-infinity distance of the edge (its centroids' midpoint) from where the child's
    line meets the spine, over the cell's extent; a wall (neither): by its distance
    from the nearer point where one of the two children hangs, so that a child hung
    from its sibling splits it near its entry."""
    fa = qr[t, 2]
    fb = qr[u, 2]
    low = (1 << FISH_SHIFT) - 1
    ka = fa & low
    kb = fb & low
    la = fa >> FISH_SHIFT
    lb = fb >> FISH_SHIFT
    cp = depth - (math.frexp(float(ka ^ kb))[1] + 1) // 2  # equal 2-bit digits from the top
    d = min(cp, la, lb)
    if d >= depth:
        return edge_class(qr[t, 0], qr[u, 0])
    if span > 0.0 and d < 2:
        return ring_class(points, tri, span, t, u, ka, kb, la, lb, lines, extent, depth)
    base = LEAF_CLASSES + (depth - 1 - d) * fk.PER_LEVEL
    if la == d and lb == d:  # along the spine (most of these edges: no geometry needed)
        return base
    oc = fk.level_offset(d) + (ka >> (2 * (depth - d)))
    line = lines[oc]
    ext = extent[oc]
    tx, ty = fk.turned_centroid(points, tri, t, ca, sa, span)
    ux, uy = fk.turned_centroid(points, tri, u, ca, sa, span)
    mx = 0.5 * (tx + ux)
    my = 0.5 * (ty + uy)
    m_along, m_across = (mx, my) if d % 2 == 0 else (my, mx)
    off = fk.level_offset(d + 1)
    shift = 2 * (depth - d - 1)
    if la == d or lb == d:
        kid_key, kid_level = (kb, lb) if la == d else (ka, la)
        meet = lines[off + (kid_key >> shift)]  # the child's line meets the spine there
        dist = max(abs(m_along - meet), abs(m_across - line))
        own = 0 if kid_level == d + 1 else fk.HANG_BINS  # a child hangs by its own spine's end
        return base + 1 + own + fk.distance_bin(dist / ext if ext > 0.0 else np.nan, fk.HANG_BINS)
    ma = lines[off + (ka >> shift)]
    mb = lines[off + (kb >> shift)]
    dist = min(max(abs(m_along - ma), abs(m_across - line)), max(abs(m_along - mb), abs(m_across - line)))
    return base + 1 + 2 * fk.HANG_BINS + fk.distance_bin(dist / ext if ext > 0.0 else np.nan, fk.WALL_BINS)


@njit(cache=True, nogil=True)
def ring_class(points, tri, span, t, u, ka, kb, la, lb, lines, extent, depth):
    """:func:`fish_class` of an edge of the ring frame's top levels (``_fishbone_kernels.ring_frame``:
    ``points`` are (radius, angle), levels 0 and 1 one class level, the top one): the
    rim's own edges first, except the seam's (last: the rim is a path); then the edges
    that hang a sector, nearest the point of the rim where the sector's radial line
    meets it (a sector's own spine first); then the walls between sectors."""
    base = LEAF_CLASSES + (depth - 1) * fk.PER_LEVEL
    walls = base + 1 + 2 * fk.HANG_BINS
    tx, ty = fk.turned_centroid(points, tri, t, 1.0, 0.0, span)
    ux, uy = fk.turned_centroid(points, tri, u, 1.0, 0.0, span)
    if abs(ty - uy) > 0.5 * span:  # across the seam
        if ty < uy:
            ty += span
        else:
            uy += span
    if la == 0 and lb == 0:
        return walls + fk.WALL_BINS - 1 if ty >= span or uy >= span else base
    mr = 0.5 * (tx + ux)
    ma = 0.5 * (ty + uy)
    ext = extent[0]
    off = fk.level_offset(2)
    shift = 2 * (depth - 2)
    r_in = lines[0]
    if la == 0 or lb == 0:
        kid_key, kid_level = (kb, lb) if la == 0 else (ka, la)
        meet = lines[off + (kid_key >> shift)]  # the sector's radial line
        da = abs(ma - meet)
        dist = max(min(da, span - da), abs(mr - r_in))
        own = 0 if kid_level == 2 else fk.HANG_BINS
        return base + 1 + own + fk.distance_bin(dist / ext if ext > 0.0 else np.nan, fk.HANG_BINS)
    da = abs(ma - lines[off + (ka >> shift)])
    db = abs(ma - lines[off + (kb >> shift)])
    dist = max(min(da, db, span - da, span - db), abs(mr - r_in))
    return walls + fk.distance_bin(dist / ext if ext > 0.0 else np.nan, fk.WALL_BINS)


def top_cross_angle(points, tri, twin, sample=None):
    """The rotation of the count quadtree (radians, ``[0, pi / 2)``) whose top cells
    cut the fewest dual edges (session 9, issue 14).

    A cell's four children ring whatever lies at its centre: on a gear with a hole,
    turning the quadtree so that its top lines run through the notches between
    teeth, not along them, cut 9-13 % less at k = 8 (docs/partition.md). Each of
    ``CROSS_ANGLES`` rotations is judged on a sample of the triangles (every
    ``m // CROSS_SAMPLE``-th), with the quadtree's own coordinates
    (the sample's ranks along each turned axis, scaled by the turned box's aspect):
    the sampled dual edges between different cells of the top two levels (4 and 16
    cells), each level counted (:func:`_top_cross_counts_into`, one numba pass: the
    numpy version cost 11-15 ms of thread CPU at 1.5 M triangles, session 10). The
    unrotated quadtree is kept unless a rotation cuts at most ``CROSS_GAIN`` of its
    count.
    """
    m = tri.shape[0]
    if m < 2 or CROSS_ANGLES < 2:
        return 0.0
    if sample is None:
        sample = np.arange(0, m, max(1, m // CROSS_SAMPLE))
    angles = 0.5 * math.pi * np.arange(CROSS_ANGLES) / CROSS_ANGLES
    cuts = np.zeros(CROSS_ANGLES, np.int64)
    if not _top_cross_counts_into(points, tri, twin, np.asarray(sample, np.int64), np.cos(angles), np.sin(angles), cuts):
        return 0.0
    i = int(np.argmin(cuts))
    return float(angles[i]) if cuts[i] <= CROSS_GAIN * cuts[0] and cuts[i] < cuts[0] else 0.0


@njit(cache=True, nogil=True)
def _top_cross_counts_into(points, tri, twin, sample, cos_a, sin_a, cuts):
    """For each rotation (cosine ``cos_a[i]``, sine ``sin_a[i]``), ``cuts[i]``: the
    dual edges from the ``sample`` triangles that cross a border of the turned count
    quadtree's top two levels, each level counted (:func:`top_cross_angle`).

    A border along an axis is a count quantile of the sample's centroids: the
    quadtree coordinate (rank / n x the turned box's aspect along that axis) crosses a
    multiple of 1/2 (4 cells) or 1/4 (16 cells), so the median counts twice. The far
    triangle of an edge is placed against the sample's thresholds. Returns False when
    no sampled triangle has a neighbour (nothing to judge)."""
    n = sample.shape[0]
    k_ang = cos_a.shape[0]
    n_e = 0
    far = np.empty(3 * n, np.int64)  # each sampled edge: (sample row, far triangle)
    near = np.empty(3 * n, np.int64)
    for r in range(n):
        for kk in range(3):
            g = twin[3 * sample[r] + kk]
            if g >= 0:
                near[n_e] = r
                far[n_e] = g // 3
                n_e += 1
    if n_e == 0:
        return False
    cx = np.empty(n)
    cy = np.empty(n)
    for r in range(n):
        t = sample[r]
        cx[r] = (points[tri[t, 0], 0] + points[tri[t, 1], 0] + points[tri[t, 2], 0]) / 3.0
        cy[r] = (points[tri[t, 0], 1] + points[tri[t, 1], 1] + points[tri[t, 2], 1]) / 3.0
    fx = np.empty(n_e)
    fy = np.empty(n_e)
    for e in range(n_e):
        u = far[e]
        fx[e] = (points[tri[u, 0], 0] + points[tri[u, 1], 0] + points[tri[u, 2], 0]) / 3.0
        fy[e] = (points[tri[u, 0], 1] + points[tri[u, 1], 1] + points[tri[u, 2], 1]) / 3.0
    p = np.empty((2, n))  # the sample along both turned axes of one rotation
    q = np.empty((2, n_e))  # the far triangles along them
    scratch = np.empty(n)
    thr = np.empty(6)
    for i in range(k_ang):
        ca, sa = cos_a[i], sin_a[i]
        for r in range(n):  # the turned axes as numpy's ``x * t0 + y * t1`` (same rounding)
            p[0, r] = cx[r] * ca + cy[r] * sa
            p[1, r] = cx[r] * -sa + cy[r] * ca
        for e in range(n_e):
            q[0, e] = fx[e] * ca + fy[e] * sa
            q[1, e] = fx[e] * -sa + fy[e] * ca
        ext0 = p[0].max() - p[0].min()
        ext1 = p[1].max() - p[1].min()
        big = max(max(ext0, ext1), 1e-300)
        total = 0
        for j in range(2):
            aspect = (ext0 if j == 0 else ext1) / big
            n_thr = 0
            scratch[:] = p[j]
            done = 0  # scratch[done:] holds the values not below those selected so far
            for k, d in ((1, 4), (1, 2), (3, 4)):  # ascending ranks (the median once)
                if k < aspect * d:
                    # the rank's value by selection, not a sort: numba's sort of the 16
                    # columns took 5.5 ms and np.partition 3.5 ms (of 4 096 values each)
                    rank = min(n - 1, int(n * k / (aspect * d)))
                    thr[n_thr] = _select(scratch, done, n, rank)
                    done = rank
                    n_thr += 1
            if 1 < aspect * 2:  # the median is a border of both levels: counted twice
                thr[n_thr] = thr[1]  # (1 < 2 aspect implies 1 < 4 aspect: thr[0] is the quartile)
                n_thr += 1
            for e in range(n_e):
                a = p[j, near[e]]
                b = q[j, e]
                for c in range(n_thr):
                    total += (a >= thr[c]) != (b >= thr[c])
        cuts[i] = total
    return True


@njit(cache=True, nogil=True)
def _select(a, lo, hi, k):
    """The ``k``-th smallest value of ``a[lo:hi]`` (``lo <= k < hi``), partly ordering
    that range in place (``_fishbone_kernels.nth``). Afterwards ``a[k:hi]`` holds no
    value below it."""
    fk.nth(a, a, lo, hi, k, False)
    return a[k]


def quadtree_coords(points, tri, out=None, spans=None, angle=0.0):
    """Quadtree coordinates of the triangles for :func:`spanning_forest`, as counts.

    Each axis of a triangle's centroid is mapped to the number of centroids below it
    (from a histogram of ``RANK_BINS`` bins per axis of every ``m // RANK_SAMPLE``-th
    centroid, linear inside a bin; exact up to a bin below ``RANK_SAMPLE``
    triangles), scaled to ``CELL_BITS`` bits times the bounding box's side over its
    longer side: the quadtree's halvings then split the *triangles* (not the box) in halves along each
    axis, so its cells hold nearly equal counts around holes and in graded meshes,
    while the domain's aspect is kept.

    ``angle`` turns the axes counter-clockwise by that many radians first
    (:func:`top_cross_angle`); 0 leaves the coordinates exactly as they are.

    Returns ``out`` ((m, 2) int32, or int64 from 2**31 triangles): column 0 the packed
    ``x << CELL_BITS | y``, column 1 set to -1 (the search's "not reached").
    """
    m = tri.shape[0]
    if out is None:
        out = np.empty((m, 2), index_dtype(m))
    if m == 0:
        return out
    if spans is None:
        spans = row_ranges(m, threads.THREAD_MIN_ROWS)
    fr = quad_frame(points, tri, angle)
    run_all([
        (lambda a=a, b=b: _cell_coords_into(points, tri, fr.ca, fr.sa, fr.x0, fr.y0, fr.bx, fr.by, fr.cum, fr.fx, fr.fy,
                                            out, a, b))
        for a, b in spans
    ])
    return out


class QuadFrame(NamedTuple):
    """Result of :func:`quad_frame`: the turn (``ca``, ``sa``), the turned box's
    corner (``x0``, ``y0``), histogram bins per unit (``bx``, ``by``), the cumulative
    histograms ``cum`` (2, RANK_BINS + 1) and the scales ``fx``, ``fy``."""

    ca: float
    sa: float
    x0: float
    y0: float
    bx: float
    by: float
    cum: np.ndarray
    fx: float
    fy: float


def quad_frame(points, tri, angle=0.0):
    """What :func:`quadtree_coords` maps each centroid through (see there)."""
    m = tri.shape[0]
    ca, sa = math.cos(angle), math.sin(angle)  # exactly 1 and 0 for angle 0
    x0, y0, x1, y1 = _bounds(points, ca, sa)
    span = max(x1 - x0, y1 - y0)
    # each axis is mapped through the cumulative histogram of a sample of the
    # centroids (RANK_SAMPLE of them, every stride-th triangle), so that the quadtree
    # halves the triangles, not the box
    bx = RANK_BINS / (x1 - x0) if x1 > x0 else 0.0
    by = RANK_BINS / (y1 - y0) if y1 > y0 else 0.0
    stride = max(1, m // RANK_SAMPLE)
    cum = np.zeros((2, RANK_BINS + 1), np.float64)
    _sample_histogram_into(points, tri, ca, sa, x0, y0, bx, by, stride, cum)
    top = (1 << CELL_BITS) - 1
    n = cum[0, RANK_BINS]
    fx = top * (x1 - x0) / span / n if span > 0 else 0.0  # the box's aspect is kept
    fy = top * (y1 - y0) / span / n if span > 0 else 0.0
    return QuadFrame(ca, sa, x0, y0, bx, by, cum, fx, fy)


@njit(cache=True, nogil=True)
def _bounds(points, ca, sa):
    """``(x0, y0, x1, y1)``: the bounding box of the points in the axes turned by the
    angle of cosine ``ca`` and sine ``sa`` (:func:`_turned`), one pass."""
    x0, y0 = _turned(points[0, 0], points[0, 1], ca, sa)
    x1, y1 = x0, y0
    for i in range(1, points.shape[0]):
        x, y = _turned(points[i, 0], points[i, 1], ca, sa)
        x0 = min(x0, x)
        x1 = max(x1, x)
        y0 = min(y0, y)
        y1 = max(y1, y)
    return x0, y0, x1, y1


@njit(cache=True, nogil=True, inline="always")
def _turned(x, y, ca, sa):
    """``(x, y)`` in axes turned counter-clockwise by the angle of cosine ``ca``, sine
    ``sa``: ``(ca x + sa y, ca y - sa x)`` (exactly ``(x, y)`` for ``ca = 1, sa = 0``)."""
    if sa == 0.0 and ca == 1.0:
        return x, y
    return ca * x + sa * y, ca * y - sa * x


@njit(cache=True, nogil=True)
def _sample_histogram_into(points, tri, ca, sa, x0, y0, bx, by, stride, cum):
    """Cumulative histograms (``cum[axis, b]``: sampled centroids in bins below b) of
    the centroids of every ``stride``-th triangle, over the box (``bx``, ``by``: bins
    per unit)."""
    for t in range(0, tri.shape[0], stride):
        x, y = _turned(
            (points[tri[t, 0], 0] + points[tri[t, 1], 0] + points[tri[t, 2], 0]) / 3.0,
            (points[tri[t, 0], 1] + points[tri[t, 1], 1] + points[tri[t, 2], 1]) / 3.0,
            ca, sa,
        )
        cum[0, min(max(int((x - x0) * bx), 0), RANK_BINS - 1) + 1] += 1
        cum[1, min(max(int((y - y0) * by), 0), RANK_BINS - 1) + 1] += 1
    for b in range(RANK_BINS):
        cum[0, b + 1] += cum[0, b]
        cum[1, b + 1] += cum[1, b]


@njit(cache=True, nogil=True)
def _cell_coords_into(points, tri, ca, sa, x0, y0, bx, by, cum, fx, fy, qr, lo, hi):
    """Quadtree coordinates (``CELL_BITS`` bits) of triangles lo..hi: each axis of the
    centroid is the number of sampled centroids below it (``cum``, linear inside a
    bin) times ``fx``/``fy``; packed ``x << CELL_BITS | y`` into ``qr[:, 0]``;
    ``qr[:, 1] = -1``."""
    for t in range(lo, hi):
        x, y = _turned(
            (points[tri[t, 0], 0] + points[tri[t, 1], 0] + points[tri[t, 2], 0]) / 3.0,
            (points[tri[t, 0], 1] + points[tri[t, 1], 1] + points[tri[t, 2], 1]) / 3.0,
            ca, sa,
        )
        qr[t, 0] = _packed_coords(x, y, x0, y0, bx, by, cum, fx, fy)
        qr[t, 1] = -1  # not reached yet (``_prim_into``)


@njit(cache=True, nogil=True, inline="always")
def _packed_coords(x, y, x0, y0, bx, by, cum, fx, fy):
    """``x << CELL_BITS | y`` of a turned centroid, each axis as a count (``cum``)."""
    top = (1 << CELL_BITS) - 1
    px = (x - x0) * bx
    py = (y - y0) * by
    i = min(max(int(px), 0), RANK_BINS - 1)
    j = min(max(int(py), 0), RANK_BINS - 1)
    rx = cum[0, i] + min(max(px - i, 0.0), 1.0) * (cum[0, i + 1] - cum[0, i])
    ry = cum[1, j] + min(max(py - j, 0.0), 1.0) * (cum[1, j + 1] - cum[1, j])
    return (min(int(rx * fx), top) << CELL_BITS) | min(int(ry * fy), top)


@njit(cache=True, nogil=True)
def _cells_into(points, tri, fr_ca, fr_sa, x0, y0, bx, by, cum, fx, fy, span, hole, lines, fars, depth, qr, half, lo, hi):
    """One pass over triangles lo..hi for :func:`forest_classes`: the quadtree
    coordinates (``qr[:, 0]``, as :func:`_cell_coords_into`), ``qr[:, 1] = -1``, the
    fishbone's cell and spine level packed in ``qr[:, 2]`` (``key | spine << 16``,
    ``_fishbone_kernels.descend_into``) and the top line's side in ``half``."""
    ring = span > 0.0
    for t in range(lo, hi):
        cx, cy, bx0, bx1, by0, by1 = fk.turned_box(points, tri, t, fr_ca, fr_sa, span)
        qr[t, 0] = _packed_coords(cx, cy, x0, y0, bx, by, cum, fx, fy)
        qr[t, 1] = -1
        rim = ring and (hole[tri[t, 0]] or hole[tri[t, 1]] or hole[tri[t, 2]])
        reg, sp = fk.descend(cx, cy, bx0, bx1, by0, by1, lines, fars, depth, ring, rim)
        qr[t, 2] = reg | (sp << FISH_SHIFT)
        half[t] = (reg >> (2 * depth - 1)) & 1 if depth > 0 else 0


#: ``qr[:, 2]`` of :func:`spanning_forest`: the fishbone cell below this bit, the spine level above.
FISH_SHIFT = 16


@njit(cache=True, nogil=True, inline="always")
def edge_class(qa, qb):
    """Class of the free dual edge between triangles at packed quadtree coordinates
    ``qa``, ``qb``: ``level * CENTRE_BINS + bin``. Level: bit length of the coordinates'
    differing bits (the smallest cell holding both); bin: L-infinity distance of the
    two centroids' midpoint from that cell's centre, in ``CENTRE_BINS`` steps of its
    half side."""
    low = (1 << CELL_BITS) - 1
    ax = qa >> CELL_BITS
    ay = qa & low
    bx = qb >> CELL_BITS
    by = qb & low
    level = math.frexp(float((ax ^ bx) | (ay ^ by)))[1]  # bit length (exact below 2**53)
    b = 0
    if level > 0:
        # twice the midpoint against twice the centre of the level's cell
        cx = ((ax >> level) << level) + (1 << (level - 1))
        cy = ((ay >> level) << level) + (1 << (level - 1))
        d = max(abs(ax + bx - 2 * cx), abs(ay + by - 2 * cy))  # <= 2 ** level
        b = min(CENTRE_BINS - 1, (d * CENTRE_BINS) >> level)
    return level * CENTRE_BINS + b


@njit(cache=True, nogil=True)
def _half_counts(qr):
    """``(nx, ny)``: triangles whose quadtree x (y) coordinate has its top bit set."""
    nx = 0
    ny = 0
    for t in range(qr.shape[0]):
        nx += (qr[t, 0] >> (2 * CELL_BITS - 1)) & 1
        ny += (qr[t, 0] >> (CELL_BITS - 1)) & 1
    return nx, ny


@njit(cache=True, nogil=True)
def _prim_half_into(tri, twin, is_con, points, ca, sa, span, lines, extent, depth, con, cross_from, qr, half_of, side, base,
                    order, tri_r, code, starts, queue, q_lo, q_hi):
    """Prim's search with a bucket queue of edge classes over the triangles of one half.

    The half: triangles ``t`` with ``half_of[t] == side`` (a side of the top line).
    Each edge's class is :func:`edge_class_of` (``con`` if constrained). Only edges of a
    class below ``cross_from`` are searched (inside one top-level cell), so a search
    never reads a triangle the other half's search is numbering: the two halves run
    side by side. Each search (a *component*, inside one top-level cell) starts at
    its lowest input triangle.

    Numbers the half's triangles from ``base`` in the order they are reached: fills
    ``qr[t, 1]`` (-1 on entry), ``order``, ``tri_r`` and ``starts`` (the new number of
    each component's first triangle, ascending). Writes ``code`` of every half-edge of
    a reached triangle except the *cross* edges (constrained, or between quadrants),
    each pair when its second triangle is reached (tree bit on the edge it was
    reached by). The cross edges are listed for :func:`_join_into`, once each (from
    the lower half-edge), as rows ``(class, half-edge)`` of ``queue`` from ``q_hi``
    down; the queue's entries go from ``q_lo`` up (each a link to the next entry of
    its class and a half-edge into a triangle not reached when queued; popped rows
    are reused; a visited triangle makes at most 3 rows of either kind, so
    ``3 x`` its half's triangles rows suffice). A bucket is a stack: the newest edge
    of a class goes first, so the search stays where it is.

    Returns ``(components, cross edges)``.
    """
    m = qr.shape[0]
    head = np.full(cross_from, -1, np.int64)
    free = -1  # popped slots, linked through their first column
    n_used = q_lo
    top = q_hi
    n_seen = base
    n_comp = 0
    for s in range(m):
        if half_of[s] != side or qr[s, 1] >= 0:
            continue
        starts[n_comp] = n_seen
        n_comp += 1
        low = cross_from  # no class below it holds an entry
        t = s
        via = -1  # the half-edge of t its tree edge enters by
        while t >= 0:
            i = n_seen
            qr[t, 1] = i
            order[i] = t
            n_seen += 1
            tri_r[i, 0] = tri[t, 0]
            tri_r[i, 1] = tri[t, 1]
            tri_r[i, 2] = tri[t, 2]
            qt = qr[t, 0]
            ft = qr[t, 2]
            leaf = (ft >> FISH_SHIFT) == depth
            best = cross_from  # the lightest edge out of t goes next without queueing if
            best_g = -1  # nothing queued is lighter (most tree edges)
            for kk in range(3):
                h = 3 * t + kk
                g = twin[h]
                if g < 0:
                    code[3 * i + kk] = CON_BIT if is_con[h] else 0
                    continue
                u = g // 3
                fu = qr[u, 2]
                if is_con[h]:
                    c = con
                elif fu == ft and leaf:  # most edges: inside one deepest cell
                    c = edge_class(qt, qr[u, 0])
                else:
                    c = fish_class(points, tri, ca, sa, span, qr, t, u, lines, extent, depth)
                if c >= cross_from:  # the join's (``_join_into``)
                    if h < g:
                        top -= 1
                        queue[top, 0] = c
                        queue[top, 1] = h
                    continue
                j = qr[u, 1]  # same quadrant: numbered by this search, if at all
                if j >= 0:  # both halves of the edge, now that both numbers are known
                    tb = TREE_BIT if h == via else 0
                    kg = g - 3 * u
                    code[3 * i + kk] = ((3 * j + kg + 1) << 2) | tb
                    code[3 * j + kg] = ((3 * i + kk + 1) << 2) | tb
                    continue
                if c < best:
                    c, best = best, c
                    g, best_g = best_g, g
                if g >= 0:
                    free, n_used = bucket_push(queue, head, free, n_used, c, g)
                    low = min(low, c)
            t = -1
            if best_g >= 0 and best <= low:
                t = best_g // 3
                via = best_g
                continue
            if best_g >= 0:
                free, n_used = bucket_push(queue, head, free, n_used, best, best_g)
                low = min(low, best)
            while low < cross_from:  # the lowest class edge to a triangle not reached
                slot = head[low]
                if slot < 0:
                    low += 1
                    continue
                head[low] = queue[slot, 0]
                g = queue[slot, 1]
                queue[slot, 0] = free  # the slot is reused: the queue touches little memory
                free = slot
                if qr[g // 3, 1] < 0:
                    t = g // 3
                    via = g
                    break
    return n_comp, q_hi - top


@njit(cache=True, nogil=True)
def _component_of(starts, i):
    """Component of new triangle ``i``: the last start at or below it."""
    return np.searchsorted(starts, i, side="right") - 1


@njit(cache=True, nogil=True)
def _join_into(twin, is_con, qr, order, code, starts, cross, parent, split, cross_from, n_classes):
    """Kruskal's join of the components of :func:`_prim_half_into` (new-number
    ``starts``, ascending) over the ``cross`` edges (rows ``(class, half-edge)``),
    lightest class first (a counting sort; constrained edges last), in their order
    inside a class. Writes both codes of every cross edge (tree bit where it joins two
    trees), ``parent`` (a union-find over the components, each root its lowest
    component) and ``split`` (the constrained tree edges, both new half-edges).
    Returns the length of ``split``."""
    n_comp = starts.shape[0]
    for c in range(n_comp):
        parent[c] = c
    n_cross = cross.shape[0]
    n_bins = n_classes - cross_from
    first = np.zeros(n_bins + 1, np.int64)
    for e in range(n_cross):
        first[cross[e, 0] - cross_from + 1] += 1
    for b in range(n_bins):
        first[b + 1] += first[b]
    ranked = np.empty(n_cross, np.int64)
    for e in range(n_cross):
        b = cross[e, 0] - cross_from
        ranked[first[b]] = e
        first[b] += 1
    n_split = 0
    for r in range(n_cross):
        h = cross[ranked[r], 1]
        g = twin[h]
        t = h // 3
        u = g // 3
        i = qr[t, 1]
        j = qr[u, 1]
        a = find_root(parent, _component_of(starts, i))
        b = find_root(parent, _component_of(starts, j))
        tb = 0
        if a != b:
            parent[max(a, b)] = min(a, b)
            tb = TREE_BIT
        cb = CON_BIT if is_con[h] else 0
        hk = 3 * i + h - 3 * t
        gk = 3 * j + g - 3 * u
        code[hk] = ((gk + 1) << 2) | tb | cb
        code[gk] = ((hk + 1) << 2) | tb | cb
        if tb and cb:
            split[n_split] = hk
            split[n_split + 1] = gk
            n_split += 2
    return n_split


@njit(cache=True, nogil=True)
def _piece_firsts(parent, starts, order, qr):
    """New number of each piece's lowest input triangle, the pieces in that order
    (a component starts at its lowest input triangle)."""
    n_comp = starts.shape[0]
    lowest = np.full(n_comp, qr.shape[0], np.int64)
    for c in range(n_comp):
        r = find_root(parent, c)
        lowest[r] = min(lowest[r], order[starts[c]])
    n_pieces = 0
    for c in range(n_comp):
        if parent[c] == c:
            lowest[n_pieces] = lowest[c]
            n_pieces += 1
    keys = np.sort(lowest[:n_pieces])
    firsts = np.empty(n_pieces, np.int64)
    for p in range(n_pieces):
        firsts[p] = qr[keys[p], 1]
    return firsts


def split_slots(tri, code, mid_h=None):
    """The constrained tree edges the walk splits at their midpoints.

    ``mid_h``: their half-edges if known (``spanning_forest``'s last result), else
    found by a scan of ``code``.

    Returns ``(mid_h, mid_id, mid_a, mid_b)``: ``mid_h`` the sorted half-edges (both
    sides of each split edge), ``mid_id`` their midpoint number (``0..q-1``, in order
    of the lower half-edge), ``(mid_a[i], mid_b[i])`` the edge split by midpoint i.
    """
    if mid_h is None:
        mid_h = np.flatnonzero((code & 3) == 3).astype(np.int64)
    g = (code[mid_h] >> 2) - 1
    lower = mid_h < g
    mid_id = np.empty(len(mid_h), np.int64)
    mid_id[lower] = np.arange(int(lower.sum()))
    mid_id[~lower] = mid_id[np.searchsorted(mid_h, g[~lower])]
    lo = mid_h[lower]
    t, k = lo // 3, lo % 3
    return Slots(mid_h, mid_id, tri[t, k].copy(), tri[t, (k + 1) % 3].copy())



@njit(cache=True, nogil=True, inline="always")
def lower_bound(a, x):
    """First index ``i`` with ``a[i] >= x`` in the sorted ``a`` (``len(a)`` if none): a
    plain binary search. numpy's ``searchsorted`` inside a kernel compiles its generic
    implementation with it, and numba's on a scalar costs ~100x more per call."""
    lo = 0
    hi = a.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


#: State of a paused walk (:func:`emit_cycles_into`): piece, slot, first free row, row of
#: the piece's start, the half-edge waiting for its link to the next row, first slot.
WALK_STATE = 6


@njit(cache=True, nogil=True)
def emit_cycles_into(tri, code, firsts, order, n_points, mid_h, mid_id, out, parent, kind, claim, prim,
                     lengths, y2, state, stop):
    """Walk the Thm 2.4 cycles, emitting rows until row ``stop`` (resumable).

    Slot ``h = 3 t + k`` is the sector of input triangle t's incenter ``I_t`` over its
    edge ``a b`` (``a = tri[t, k]``). Sweeping counter-clockwise around ``I_t``:

    * edge not in the tree: emit ``(I_t, a, b)``; continue with slot ``h + 1`` of t;
    * tree edge, free: it is flipped; emit ``(I_t, a, I_u)`` (u across, ``g = twin[h]``)
      and continue in u's sweep after the flipped edge, slot ``g + 1`` of u;
    * tree edge, constrained: it is split at its midpoint M: emit ``(I_t, a, M)`` and
      u's ``(I_u, M, a)`` across ``a M``, then continue with slot ``g + 1`` of u.

    The sweep returns to its first slot after visiting every slot of the tree's
    triangles once: one Hamiltonian cycle per tree (per connected piece). Incenter
    of t is vertex ``n_points + t``, midpoint i is ``n_points + m + i``
    (``split_slots`` gives ``mid_h``, ``mid_id``).

    The walk stops at a slot boundary once ``stop`` rows are out and keeps where it
    is in ``state`` (zeros to start); call again to go on. Rows below ``state[2] - 1``
    are then final together with every claim entry a certificate reads for them, so
    a checker can run on them while the walk goes on (``claim`` must start as
    ``UNLINKED``). ``prim`` starts at -1, ``y2`` at -1.

    Returns 1 when every piece is walked, 0 when paused, -1 if the walk met a slot
    twice or ran out of rows (not a permutation).
    """
    m = tri.shape[0]
    total = out.shape[0]
    c = state[0]
    h = state[1]
    pos = state[2]
    run_start = state[3]
    last_exit = state[4]
    first = state[5]
    fresh = pos == 0 and c == 0 and last_exit == 0  # state all zeros: a new walk
    if fresh:
        last_exit = -1
    # The claimed pairing: a row's "exit" edge pairs with the next row's "entry" edge
    # (a slot's first triangle enters by edge 0 (I_t, a), a split's second triangle by
    # edge 1 (M, a)); the third edge pairs across the input edge (plain slot), with
    # the other flipped triangle (flip) or with the other half of the split sector;
    # whichever of two partners is emitted second makes the link.
    while c < firsts.shape[0]:
        if fresh:
            first = 3 * firsts[c]
            h = first
            run_start = pos
            last_exit = -1
        fresh = True
        while True:
            if pos >= stop:  # pause at a slot boundary
                state[0] = c
                state[1] = h
                state[2] = pos
                state[3] = run_start
                state[4] = last_exit
                state[5] = first
                return 0
            if pos >= total or prim[h] >= 0:  # not a permutation
                state[2] = pos
                return -1
            prim[h] = pos
            if last_exit >= 0:
                claim[last_exit] = 3 * pos
                claim[3 * pos] = last_exit
            t = h // 3
            k = h - 3 * t
            a = tri[t, k]
            inc = n_points + t
            cd = code[h]
            g = (cd >> 2) - 1
            if not (cd & TREE_BIT):
                out[pos, 0] = inc
                out[pos, 1] = a
                out[pos, 2] = tri[t, (k + 1) % 3]
                parent[pos] = order[t]
                kind[pos] = 0
                if g < 0:
                    claim[3 * pos + 1] = -1
                else:
                    pg = prim[g]
                    if pg >= 0:
                        claim[3 * pos + 1] = 3 * pg + 1
                        claim[3 * pg + 1] = 3 * pos + 1
                last_exit = 3 * pos + 2  # (b, I_t)
                pos += 1
                nxt = h + 1 if k < 2 else h - 2
            else:
                u = g // 3
                kg = g - 3 * u
                if not (cd & CON_BIT):
                    out[pos, 0] = inc
                    out[pos, 1] = a
                    out[pos, 2] = n_points + u
                    parent[pos] = order[t]
                    kind[pos] = 1
                    pg = prim[g]
                    if pg >= 0:
                        claim[3 * pos + 2] = 3 * pg + 2
                        claim[3 * pg + 2] = 3 * pos + 2
                    last_exit = 3 * pos + 1  # (a, I_u)
                    pos += 1
                else:
                    if pos + 1 >= total:
                        state[2] = pos
                        return -1
                    ih = lower_bound(mid_h, h)
                    ig = lower_bound(mid_h, g)
                    mv = n_points + m + mid_id[ih]
                    out[pos, 0] = inc
                    out[pos, 1] = a
                    out[pos, 2] = mv
                    parent[pos] = order[t]
                    kind[pos] = 2
                    out[pos + 1, 0] = n_points + u
                    out[pos + 1, 1] = mv
                    out[pos + 1, 2] = a
                    parent[pos + 1] = order[u]
                    kind[pos + 1] = 2
                    y2[ig] = pos + 1
                    claim[3 * pos + 1] = 3 * (pos + 1) + 1  # (a, M) | (M, a)
                    claim[3 * (pos + 1) + 1] = 3 * pos + 1
                    yh = y2[ih]
                    if yh >= 0:  # (M, I_t) | (I_t, M): other half of t's sector
                        claim[3 * pos + 2] = 3 * yh
                        claim[3 * yh] = 3 * pos + 2
                    pg = prim[g]
                    if pg >= 0:  # (I_u, M) | (M, I_u): other half of u's sector
                        claim[3 * (pos + 1)] = 3 * pg + 2
                        claim[3 * pg + 2] = 3 * (pos + 1)
                    last_exit = 3 * (pos + 1) + 2  # (a, I_u)
                    pos += 2
                nxt = g + 1 if kg < 2 else g - 2
            h = nxt
            if h == first:
                break
        claim[last_exit] = 3 * run_start  # the cycle closes
        claim[3 * run_start] = last_exit
        lengths[c] = pos - run_start
        c += 1
    state[0] = c
    state[2] = pos
    return 1

