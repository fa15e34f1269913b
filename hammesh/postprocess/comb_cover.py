"""The comb cover: sparse mode's compact cycle cover from an induced vertex tree
(``hamiltonian(mesh, mode="sparse", tree="comb")``, issue 14; measured in
docs/partition.md, "Session 21", prototyped in ``benchmarks/partition_colourings.py``).

A cycle cover of a planar mesh's dual graph is a 2-colouring of the vertices in which
every triangle is *mixed*: the cover crosses the edges whose ends differ, a monochrome
triangle is uncovered. With the boundary outside, the walk round an *induced tree* of
inside vertices is one cycle through every mixed triangle. This module grows such a
tree so that the cycle sweeps the domain compactly (its stretches cut close to METIS):

* session 11's fishbone cells made on the vertices (:func:`vertex_fishbone_tree`): each
  level's spine a shortest path just below its cell's median line, grown top-down, each
  child hung by its own spine's end;
* the deepest cells filled as *combs* (:func:`comb_keys`): a sweep away from the
  parent's spine, so that teeth one vertex row wide run across it with outside rows
  between them (alternating rows leave no monochrome triangle);
* a vertex whose joining would leave a triangle monochrome for good is deferred
  (:func:`grow_induced_tree`);
* where no join could keep sparse mode's rule at a triangle left monochrome (its
  :func:`lone_join_bounds` below ``keep`` x the input's smallest angle: mostly a
  boundary triangle whose inner vertex stays outside where two teeth meet the boundary),
  the inner vertex of such a boundary triangle joins first in its cell
  (:func:`rim_apexes`), and :func:`mend_tree` moves the grown tree locally (swaps that
  keep it a tree; lone joins that close cycles of a few edges) to leave fewer and
  better monochrome triangles;
* round a hole that the domain wraps round (a gear, an annulus: session 13's *ring
  frame*, :func:`vertex_ring`), the hole's own vertices are the top spine, all inside,
  and eight sectors hang from it, each a fishbone whose spine is its radial middle
  line: the walk sweeps round the ring once (the colouring is then one cycle round
  the hole with trees hanging from it, still one cycle of the cover).

:func:`comb_cover` returns what ``cycle_cover`` returns; sparse mode joins and fans the
uncovered triangles (0.7 %) as usual, with its re-routes off (they would splice
the cycle into long arcs), and certifies the output. No theorem: measured (plate
300 000 triangles: 0.52 % Steiner points, cut 1.38 / 1.34 x METIS at k = 8 / 64;
the gear, ring frame, 0.53 %, 1.20 / 1.38; smallest angle 16-17 degrees, where the
default keeps 27; docs/partition.md, "Session 22, second round").
"""

from __future__ import annotations

import heapq
from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh.errors import InvalidOptionError
from hammesh.postprocess import _fishbone_kernels as fk
from hammesh.postprocess.cycle_cover import CycleCover, corner_angle, cycle_ids_by_halves, lone_join_bound

__all__ = ["InducedTree", "VertexMaps", "vertex_maps", "reverse_entries", "boundary_vertices", "cover_of", "turned", "cell_medians", "spine_paths",
           "grow_induced_tree", "triangles_doomed_by", "vertex_fishbone_tree", "comb_keys", "comb_cover", "STRAIGHT_SPINES",
           "VertexRing", "vertex_ring", "FRAMES", "lone_join_bounds", "triangle_corners", "rim_apexes", "tree_parents",
           "swap_gain", "mend_tree", "BAD_WEIGHT", "MEND_REACH", "MEND_SHORT", "MAX_ALONE"]


class InducedTree(NamedTuple):
    """A grown induced vertex tree: ``inside`` (n,) bool, and how many times a vertex
    was deferred."""

    inside: np.ndarray
    deferrals: int


class VertexMaps(NamedTuple):
    """Each vertex's neighbours (``idx[ptr[v]:ptr[v+1]]``) and triangles
    (``vt_idx[vt_ptr[v]:vt_ptr[v+1]]``), int64."""

    ptr: np.ndarray
    idx: np.ndarray
    vt_ptr: np.ndarray
    vt_idx: np.ndarray


class VertexRing(NamedTuple):
    """The ring frame on vertices (:func:`vertex_ring`): the fishbone's top spine is the
    hole's rim, ``SECTORS`` sectors hang from it."""

    #: (n, 2) float64: each vertex as (radius, angle from the seam x a median radius)
    points: np.ndarray
    #: (n,) bool: the vertices of the hole the sectors hang round
    hole: np.ndarray
    #: (SECTORS - 1,) float64: the sector borders (angle coordinate), by triangles walked
    cuts: np.ndarray
    #: the hole's mean radius (where each sector hangs from the rim)
    r_in: float
    #: the angle coordinate's range (an edge across the seam spans more than half of it)
    span: float


def vertex_ring(points: np.ndarray, tri: np.ndarray, twin: np.ndarray) -> VertexRing | None:
    """The ring frame of a domain that wraps round a hole, else None: session 13's
    decision, seam and polar coordinates (``_fishbone_kernels.ring_frame``), with the
    sector borders recounted for the walk round the hole's vertices: the walk sweeps
    the ring once and never comes back along the hole, so every triangle counts one
    row on the way round (the incircle walk's rim triangles count ``RIM_FORWARD`` of
    their three rows on the way out), and the borders are the octiles of the sampled
    triangles' angles."""
    m = len(tri)
    if m == 0:
        return None
    sample = np.arange(0, m, max(1, m // fk.FISH_SAMPLE))
    ring = fk.ring_frame(points, tri, twin, sample)
    if ring is None:
        return None
    pts, span = ring.points, float(ring.span)
    s = pts[tri[sample], 1]
    wrap = (s.max(axis=1) - s.min(axis=1) > 0.5 * span)[:, None] & (s < 0.5 * span)
    c = np.sort(np.where(wrap, s + span, s).mean(axis=1) % span)  # (a triangle across the seam unwrapped)
    cuts = c[np.arange(1, fk.SECTORS) * len(c) // fk.SECTORS]
    return VertexRing(pts, ring.hole, cuts, float(ring.r_in), span)


@njit(cache=True, nogil=True)
def _vertex_maps_into(tri, vt_ptr, vt_idx, deg, buf):
    """Each vertex's triangles (``vt_ptr``, ``vt_idx``: a counting sort, by triangle)
    and its neighbours' count ``deg`` with the neighbours, sorted, at ``buf[vt_ptr[v] *
    2:]`` (each of its triangles names two, every neighbour at least once)."""
    n = vt_ptr.shape[0] - 1
    m = tri.shape[0]
    for t in range(m):
        for k in range(3):
            vt_ptr[tri[t, k] + 1] += 1
    for v in range(n):
        vt_ptr[v + 1] += vt_ptr[v]
    fill = vt_ptr[:-1].copy()
    for t in range(m):
        for k in range(3):
            v = tri[t, k]
            vt_idx[fill[v]] = t
            fill[v] += 1
    for v in range(n):
        lo = 2 * vt_ptr[v]
        c = 0
        for jj in range(vt_ptr[v], vt_ptr[v + 1]):
            t = vt_idx[jj]
            for k in range(3):
                w = tri[t, k]
                if w == v:
                    continue
                # insertion into the sorted run, duplicates dropped
                i = c
                while i > 0 and buf[lo + i - 1] > w:
                    i -= 1
                if i > 0 and buf[lo + i - 1] == w:
                    continue
                for q in range(c, i, -1):
                    buf[lo + q] = buf[lo + q - 1]
                buf[lo + i] = w
                c += 1
        deg[v] = c


def vertex_maps(tri: np.ndarray, n: int) -> VertexMaps:
    """The :class:`VertexMaps` of ``tri`` (m, 3) int64 over ``n`` vertices: neighbours
    sorted, triangles in index order."""
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    vt_ptr = np.zeros(n + 1, np.int64)
    vt_idx = np.empty(3 * len(tri), np.int64)
    deg = np.zeros(n, np.int64)
    buf = np.empty(6 * len(tri), np.int64)
    _vertex_maps_into(tri, vt_ptr, vt_idx, deg, buf)
    ptr = np.zeros(n + 1, np.int64)
    np.cumsum(deg, out=ptr[1:])
    # each vertex's run starts at 2 vt_ptr[v] in buf: keep its first deg[v] entries
    keep = np.arange(len(buf)) - np.repeat(2 * vt_ptr[:-1], 2 * np.diff(vt_ptr)) < np.repeat(deg, 2 * np.diff(vt_ptr))
    return VertexMaps(ptr, buf[keep], vt_ptr, vt_idx)


@njit(cache=True, nogil=True)
def _reverse_entries_into(ptr, idx, rev):
    for v in range(ptr.shape[0] - 1):
        for j in range(ptr[v], ptr[v + 1]):
            w = idx[j]
            for jj in range(ptr[w], ptr[w + 1]):
                if idx[jj] == v:
                    rev[j] = jj
                    break


def reverse_entries(ptr: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(len(idx),) int64: for each adjacency entry ``v -> w`` of :func:`vertex_maps`, the
    position of ``w -> v``."""
    rev = np.empty(len(idx), np.int64)
    _reverse_entries_into(ptr, idx, rev)
    return rev


def boundary_vertices(tri: np.ndarray, twin: np.ndarray, n: int) -> np.ndarray:
    """(n,) bool: the ends of the boundary half-edges (``twin < 0``)."""
    bh = np.flatnonzero(twin < 0)
    b = np.zeros(n, np.bool_)
    b[tri[bh // 3, bh % 3]] = True
    b[tri[bh // 3, (bh % 3 + 1) % 3]] = True
    return b


def cover_of(tri: np.ndarray, twin: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """(3 m,) bool: the cover of a colouring, the interior half-edges whose ends differ."""
    return ((colour[tri] != colour[np.roll(tri, -1, axis=1)]).ravel()) & (np.asarray(twin) >= 0)


def turned(points: np.ndarray, angle: float) -> np.ndarray:
    """``points`` (n, 2) in axes turned counter-clockwise by ``angle`` degrees."""
    if not angle:
        return points
    t = np.radians(angle)
    return np.ascontiguousarray(points @ np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]))


def cell_medians(cell: np.ndarray, value: np.ndarray, n_cells: int, weight: np.ndarray | None = None) -> np.ndarray:
    """Per cell id, the value at which the cell's members (by ``value``) reach half
    their count, or half their ``weight``; NaN for an empty cell."""
    o = np.lexsort((value, cell))
    cnt = np.bincount(cell, minlength=n_cells)
    start = np.r_[0, np.cumsum(cnt)[:-1]]
    med = np.full(n_cells, np.nan)
    full = cnt > 0
    if weight is None:
        med[full] = value[o][start[full] + cnt[full] // 2]
        return med
    w = weight[o]
    cum = np.cumsum(w)
    before = np.r_[0.0, cum][start]  # weight before each cell's first member
    half = before + 0.5 * np.bincount(cell, weights=weight, minlength=n_cells)
    # first member of each cell whose cumulative weight reaches half the cell's
    at = np.searchsorted(cum, half[full], side="left")
    med[full] = value[o][np.minimum(at, start[full] + cnt[full] - 1)]
    return med


@njit(cache=True)
def triangles_doomed_by(v, ptr, idx, vt_ptr, vt_idx, tri, boundary, inside, count, mark, stamp, weight):
    """The triangles that ``v``'s joining the induced tree would leave monochrome for
    good: round the neighbours that could join until now (interior, outside, one inside
    neighbour; marked ``stamp`` in ``mark``), those whose three vertices are outside and
    each on the boundary or unable to join after ``v`` (two inside neighbours, or a
    marked neighbour of ``v``)."""
    for j in range(ptr[v], ptr[v + 1]):
        w = idx[j]
        if not inside[w] and not boundary[w] and count[w] == 1:
            mark[w] = stamp
    doomed = 0.0
    for j in range(ptr[v], ptr[v + 1]):
        w = idx[j]
        if mark[w] != stamp:
            continue
        for jj in range(vt_ptr[w], vt_ptr[w + 1]):
            t = vt_idx[jj]
            dead = True
            for k in range(3):
                x = tri[t, k]
                if x == v or inside[x] or not (mark[x] == stamp or boundary[x] or count[x] >= 2):
                    dead = False
            if dead:
                doomed += weight[t]
    return doomed


@njit(cache=True)
def _put_inside(v, ptr, idx, wts, boundary, inside, count, heap, seq):
    """``v`` joins the tree: its neighbours count one more inside neighbour, and each
    that now has exactly one (and could join) goes on ``heap`` at its entry's key, in
    sequence from ``seq``. Returns the next sequence number."""
    inside[v] = True
    for j in range(ptr[v], ptr[v + 1]):
        w = idx[j]
        count[w] += 1
        if not inside[w] and not boundary[w] and count[w] == 1:
            heapq.heappush(heap, (wts[j], np.int64(seq), np.int64(w)))
            seq += 1
    return seq


@njit(cache=True)
def _grow_weighted_into(ptr, idx, wts, vt_ptr, vt_idx, tri, boundary, seeds, inside, penalty, max_defer, weight):
    """Prim's search from ``seeds`` (all inside first, whatever their neighbours; then a
    heap of ``(key, sequence, vertex)``; float keys per adjacency entry ``wts``) growing
    an induced tree into ``inside``: a vertex joins when
    it is interior and exactly one neighbour is inside. A vertex whose joining would
    *doom* a triangle (its three vertices outside, each on the boundary or with two
    inside neighbours, so none can join any more) is pushed back by ``penalty`` times
    the triangles it dooms, at most ``max_defer`` times. Returns ``(size, deferrals)``."""
    n = len(boundary)
    count = np.zeros(n, np.int64)
    defer = np.zeros(n, np.int64)
    mark = np.zeros(n, np.int64)
    heap = [(0.0, np.int64(0), np.int64(0))]
    heap.pop()  # (typed empty)
    seq = 1
    size = 0
    stamp = 0
    deferrals = 0
    for v in seeds:
        if inside[v]:
            continue
        seq = _put_inside(v, ptr, idx, wts, boundary, inside, count, heap, seq)
        size += 1
    while len(heap):
        key, _, v = heapq.heappop(heap)
        if inside[v] or boundary[v] or (size > 0 and count[v] != 1):
            continue
        if size > 0 and defer[v] < max_defer:
            stamp += 1
            doomed = triangles_doomed_by(v, ptr, idx, vt_ptr, vt_idx, tri, boundary, inside, count, mark, stamp, weight)
            if doomed > 0:
                defer[v] += 1
                deferrals += 1
                heapq.heappush(heap, (key + penalty * doomed, np.int64(seq), np.int64(v)))
                seq += 1
                continue
        seq = _put_inside(v, ptr, idx, wts, boundary, inside, count, heap, seq)
        size += 1
    return size, deferrals


def grow_induced_tree(ptr: np.ndarray, idx: np.ndarray, wts: np.ndarray, vt_ptr: np.ndarray, vt_idx: np.ndarray,
                      tri: np.ndarray, boundary: np.ndarray, seed, penalty: float = 0.0,
                      max_defer: int = 0, weight: np.ndarray | None = None) -> InducedTree:
    """The induced vertex tree of :func:`_grow_weighted_into` from ``seed`` (a vertex, or
    an array of vertices put inside first; ``ptr``, ``idx``: the neighbours as
    :func:`vertex_maps`; ``wts`` each adjacency entry's key, float64; ``vt_ptr``,
    ``vt_idx``: the vertices' triangles)."""
    inside = np.zeros(len(boundary), np.bool_)
    seeds = np.atleast_1d(np.asarray(seed, dtype=np.int64))
    weight = np.ones(len(tri)) if weight is None else np.ascontiguousarray(weight, dtype=np.float64)
    _, deferrals = _grow_weighted_into(ptr, idx, wts, vt_ptr, vt_idx, tri, boundary, seeds, inside,
                                       float(penalty), int(max_defer), weight)
    return InducedTree(inside, int(deferrals))


#: ``vertex_fishbone_tree``: each spine a shortest path through its band (else the whole band)
STRAIGHT_SPINES = True


@njit(cache=True)
def _spine_paths_into(ptr, idx, cand, lab, order, spine):
    """For each cell's band of spine candidates (``order``: by cell, then along the
    line), each connected piece's shortest path (breadth-first, inside the band) from its
    first vertex along the line to the farthest one it reaches along the line."""
    n = cand.shape[0]
    seen = np.zeros(n, np.bool_)
    par = np.full(n, -1, np.int64)
    pos = np.full(n, -1, np.int64)
    for i in range(order.shape[0]):
        pos[order[i]] = i
    queue = np.empty(order.shape[0] + 1, np.int64)
    for i in range(order.shape[0]):
        s = order[i]
        if seen[s]:
            continue
        seen[s] = True
        par[s] = -1
        head, tail = 0, 1
        queue[0] = s
        far = s
        while head < tail:
            u = queue[head]
            head += 1
            if pos[u] > pos[far]:
                far = u
            for j in range(ptr[u], ptr[u + 1]):
                w = idx[j]
                if cand[w] and not seen[w] and lab[w] == lab[s]:
                    seen[w] = True
                    par[w] = u
                    queue[tail] = w
                    tail += 1
        x = far
        while x >= 0:
            spine[x] = True
            x = par[x]

def spine_paths(ptr: np.ndarray, idx: np.ndarray, cand: np.ndarray, lab: np.ndarray, order: np.ndarray) -> np.ndarray:
    """(n,) bool: the spines of :func:`_spine_paths_into` (``cand``: the bands' vertices;
    ``lab``: their cells; ``order``: the candidates by cell, then along the line)."""
    spine = np.zeros(len(cand), np.bool_)
    _spine_paths_into(ptr, idx, cand, lab, order, spine)
    return spine


def vertex_fishbone_tree(points: np.ndarray, tri: np.ndarray, twin: np.ndarray, axis: int = 0,
                         min_cell: int = 1024, penalty: float = 0.0, max_defer: int = 0,
                         levels: int = 0, fill: str = "grow", pitch: float = 0.02,
                         ring: VertexRing | None = None, first: np.ndarray | None = None,
                         weight: np.ndarray | None = None, maps: VertexMaps | None = None) -> np.ndarray:
    """(n,) bool: an induced vertex tree in session 11's fishbone cells made on the
    vertices (``partition_trees.fishbone_labels``; no gap joins round holes). A level's
    spine is the path of vertices just below its cell's median line (each with a
    neighbour of the same cell above it). Grown *top-down* (an induced tree grown
    bottom-up, cells first, blocks the spine beside each cell): spines from the top
    level down, each child hung by its own spine's end nearest where its line meets the
    parent's (the deepest cells by any vertex), the deepest cells' insides next, walls
    last. ``levels`` (> 0) fixes the depth, else cells of about ``min_cell`` vertices;
    ``penalty``, ``max_defer``: :func:`deferring_tree`'s deferral. ``fill``: the deepest
    cells grown breadth-first from where they hang (``"grow"``: equal keys), or as combs
    (``"comb"``: a sweep away from the parent's spine, :func:`comb_keys`, in steps of
    ``pitch`` median edges; the deferral's penalty then counts steps). ``ring``
    (:func:`vertex_ring`; ``points`` are then its polar ``points`` and ``axis`` 1): level
    0's spine is the hole's own boundary vertices, all inside, and its children the
    ``SECTORS`` sectors, each hung from the hole by its own spine (the radial line
    through its median angle), whose innermost vertex is put inside (with its
    neighbour next to the hole if it is not): the walk then sweeps round the ring once,
    sector after sector, with no strip along the hole to come back by. Not an induced
    tree then: one cycle round the hole (the hole is no triangle), and each hanging
    vertex next to two hole vertices leaves their triangle monochrome (about
    ``SECTORS`` triangles uncovered). ``maps``: :func:`vertex_maps` of ``tri`` if the
    caller made them already."""
    if fill not in ("grow", "comb"):
        raise InvalidOptionError(f"fill must be 'grow' or 'comb', not {fill!r}")
    n = len(points)
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    ptr, idx, vt_ptr, vt_idx = vertex_maps(tri, n) if maps is None else maps  # (the caller's, if made)
    src = np.repeat(np.arange(n), np.diff(ptr))
    keep = src < idx
    a, b = src[keep], idx[keep]
    bnd = boundary_vertices(tri, twin, n)
    if bnd.all():  # no interior vertex (a fan, a strip one triangle wide): no tree; all uncovered
        return np.zeros(n, np.bool_)
    depth = levels if levels > 0 else max(1, int(np.log(max(n / min_cell, 1.0)) / np.log(4.0)))
    lab = np.zeros(n, np.int64)
    region = np.zeros(n, np.int64)
    spine_level = np.full(n, -1)
    labels, lines = [], []
    cells = 1
    for level in range(depth + 1):
        labels.append(lab)
        along = (axis + level) % 2
        across = 1 - along
        top_ring = ring is not None and level == 0
        line = np.array([ring.r_in]) if top_ring else cell_medians(region, points[:, across], cells)
        lines.append(line)
        if level == depth:
            break
        cand = np.zeros(n, bool)
        if top_ring:  # the hole's vertices are the spine (below); the sectors by angle
            region = np.searchsorted(ring.cuts, points[:, 1], side="right")
            cells = len(ring.cuts) + 1
        else:
            at = line[region]
            upper = points[:, across] >= at
            side = 2 * region + upper
            far = points[:, along] >= cell_medians(side, points[:, along], 2 * cells)[side]
            region = 2 * side + far
            cells *= 4
            cross = (lab[a] == lab[b]) & (lab[a] >= 0) & (upper[a] != upper[b])
            cand[np.where(upper[a], b, a)[cross]] = True
            cand &= ~bnd
        spine = np.zeros(n, bool)
        if top_ring:
            spine = ring.hole.copy()
        elif STRAIGHT_SPINES:  # an induced path: a shortest path along each piece of the band
            o = np.flatnonzero(cand)
            o = o[np.lexsort((points[o, along], lab[o]))].astype(np.int64)
            spine = spine_paths(ptr, idx, cand, lab, o)
        else:
            spine = cand
        lab = np.where((lab >= 0) & ~spine, region, -1)
        spine_level[spine] = level
    deepest = np.full(len(a), -1)
    for level, lb in enumerate(labels):
        deepest[(lb[a] == lb[b]) & (lb[a] >= 0)] = level
    mid = 0.5 * (points[a] + points[b])
    scale = 2.0 * float(np.ptp(points, axis=0).max()) + 1e-300
    w = np.full(len(a), 1e6)
    for level in range(depth + 1):
        sel = deepest == level
        base = 10.0 * level
        if level == depth:
            w[sel] = base
            continue
        along = (axis + level) % 2
        sa, sb = spine_level[a] == level, spine_level[b] == level
        w[sel & sa & sb] = base
        hang = np.flatnonzero(sel & (sa ^ sb))
        kid = np.where(sa, b, a)[hang]
        child = labels[level + 1][kid]
        target = np.empty((len(hang), 2))
        target[:, along] = lines[level + 1][np.maximum(child, 0)]
        target[:, 1 - along] = lines[level][labels[level][a[hang]]]
        own = (spine_level[kid] == level + 1) | (level + 1 == depth)
        d = np.sqrt(((mid[hang] - target) ** 2).sum(1)) / scale
        w[hang] = np.where(own, base + 1.0 + d, 1e5 + d)
        walls = np.flatnonzero(sel & ~sa & ~sb)
        w[walls] = 2e5 + np.abs(mid[walls, 1 - along] - lines[level][labels[level][a[walls]]]) / scale
    # the keys in vertex_maps' order (by source, then neighbour): each edge's twice
    pos = np.flatnonzero(keep)
    twice = np.empty(len(idx), np.int64)
    twice[pos] = np.arange(len(pos))
    twice[reverse_entries(ptr, idx)[pos]] = np.arange(len(pos))
    w2 = w[twice]
    if fill == "comb":
        w2 = comb_keys(points, src, idx, w2, deepest[twice] == depth, labels[depth - 1][idx],
                       lines[depth - 1], (axis + depth - 1) % 2, 10.0 * depth, pitch, scale)
    if first is not None:  # (joined first within their comb cell: ``comb_cover``'s ``rim``)
        w2 = np.where(first[idx] & (deepest[twice] == depth), 10.0 * depth, w2)
    if ring is not None:
        seed = np.r_[np.flatnonzero(ring.hole), _sector_hangs(points, ptr, idx, ring.hole, spine_level, labels[1],
                                                              len(ring.cuts) + 1)]
        bnd = bnd & ~ring.hole
    else:
        top = np.flatnonzero((spine_level == 0) & ~bnd)
        cen = points[~bnd].mean(axis=0)
        seed = top[np.argmin(((points[top] - cen) ** 2).sum(1))] if len(top) else np.flatnonzero(~bnd)[0]
    return grow_induced_tree(ptr, idx, w2.astype(np.float64), vt_ptr, vt_idx, tri, bnd,
                             seed, float(penalty), int(max_defer), weight).inside


def _sector_hangs(points, ptr, idx, hole, spine_level, sector, sectors):
    """The vertices that hang each sector from the hole: its radial spine's innermost
    vertex, and if that is not next to the hole, its neighbour next to the hole nearest
    the centre (if it has none, nothing: the sector is reached by the growth)."""
    n = len(hole)
    src = np.repeat(np.arange(n), np.diff(ptr))
    next_to = np.zeros(n, bool)
    next_to[idx[hole[src]]] = True
    next_to &= ~hole
    out = []
    for j in range(sectors):
        sp = np.flatnonzero((spine_level == 1) & (sector == j))
        if not len(sp):
            continue
        x = int(sp[np.argmin(points[sp, 0])])
        if next_to[x]:
            out.append(x)
            continue
        nb = idx[ptr[x]:ptr[x + 1]]
        nb = nb[next_to[nb]]
        if len(nb):  # (else no seed: one apart from the hole would be a second tree; the growth reaches it)
            out += [x, int(nb[np.argmin(points[nb, 0])])]
    return np.array(out, np.int64)


def comb_keys(points: np.ndarray, src: np.ndarray, dst: np.ndarray, keys: np.ndarray, deep: np.ndarray,
              parent: np.ndarray, parent_line: np.ndarray, along: int, base: float, pitch: float,
              scale: float) -> np.ndarray:
    """Prim's keys of the directed edges ``src -> dst`` inside the deepest cells for the
    comb fill: ``dst``'s distance from its parent's spine line (the spine runs along
    ``along``) in whole steps of ``pitch`` median edges, ties by its coordinate along
    the spine. The growth sweeps away from the spine, so each inside vertex extends the
    tooth it is next to across the spine (and a vertex that would touch two teeth stays
    out): teeth about one vertex row wide, outside rows between them. (A deferral's
    penalty is counted in steps: 5 steps of 0.05 edges put a vertex back by a quarter
    of an edge.)"""
    keys = keys.copy()
    v = dst[deep]
    d = points[v] - points[src[deep]]
    step = pitch * float(np.median(np.sqrt((d ** 2).sum(1))))
    off = np.floor(np.abs(points[v, 1 - along] - parent_line[parent[deep]]) / step)
    keys[deep] = base + off + (points[v, along] - points[:, along].min()) / scale
    return keys


def lone_join_bounds(points: np.ndarray, tri: np.ndarray, twin: np.ndarray,
                     corners: np.ndarray | None = None) -> np.ndarray:
    """(m,) float64, radians: what sparse mode's joins could keep at best at each
    triangle if the cover left it off alone (every neighbour covered): the formula of
    ``sparse.join_bounds`` (one join divides the corners opposite the edge it crosses,
    in the triangle and its neighbour; a bridge splits the triangle at its incenter),
    for every triangle (``cycle_cover.lone_join_bound``). A triangle with a boundary edge opposite a wide corner
    (33/33/114 degrees) bounds any join to about 16 degrees. ``corners``: the
    :func:`triangle_corners` if at hand."""
    c = triangle_corners(points, tri) if corners is None else corners
    g = np.asarray(twin).reshape(-1, 3)
    inner = g >= 0
    gg = np.where(inner, g, 0)
    u_opp = c[gg // 3, (gg % 3 + 2) % 3]  # the neighbour's corner opposite the shared edge
    return lone_join_bound(c, u_opp, inner)


def triangle_corners(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(m, 3) float64, radians: each triangle's corner at each of its vertices."""
    pts = np.asarray(points)[:, :2]
    rows = np.arange(len(tri))
    return np.stack([corner_angle(pts, tri, rows, np.full(len(tri), k)) for k in range(3)], axis=1)


def rim_apexes(tri: np.ndarray, twin: np.ndarray, n: int, bad: np.ndarray) -> np.ndarray:
    """(n,) bool: the inner vertex of each triangle with one boundary edge that is
    ``bad`` ((m,) bool). Left outside, it leaves that triangle uncovered; the comb's
    teeth meet the boundary head on, so such a vertex joins first in its cell."""
    g = np.asarray(twin).reshape(-1, 3)
    bt = np.flatnonzero(((g < 0).sum(axis=1) == 1) & bad)
    k = np.argmax(g[bt] < 0, axis=1)
    out = np.zeros(n, np.bool_)
    out[tri[bt, (k + 2) % 3]] = True
    return out


#: most inside neighbours of a vertex :func:`mend_tree` lets join alone
MAX_ALONE = 4


@njit(cache=True, nogil=True)
def tree_parents(ptr, idx, inside, parent, depth):
    """Breadth-first parents (-1 at each root) and depths of the inside vertices
    (``parent`` -2 and ``depth`` -1 outside), from the lowest vertex of each piece."""
    n = inside.shape[0]
    parent[:] = -2
    depth[:] = -1
    queue = np.empty(n, np.int64)
    for r in range(n):
        if not inside[r] or depth[r] >= 0:
            continue
        parent[r] = -1
        depth[r] = 0
        head, tail = 0, 1
        queue[0] = r
        while head < tail:
            u = queue[head]
            head += 1
            for j in range(ptr[u], ptr[u + 1]):
                w = idx[j]
                if inside[w] and depth[w] < 0:
                    depth[w] = depth[u] + 1
                    parent[w] = u
                    queue[tail] = w
                    tail += 1


@njit(cache=True, nogil=True)
def _monochrome_weight(t, tri, inside, weight):
    c0 = inside[tri[t, 0]]
    if inside[tri[t, 1]] != c0 or inside[tri[t, 2]] != c0:
        return 0.0
    return weight[t]


@njit(cache=True, nogil=True)
def _around(v, w, vt_ptr, vt_idx, tri, inside, weight):
    """The monochrome weight of ``v``'s triangles (those without ``w``)."""
    s = 0.0
    for jj in range(vt_ptr[v], vt_ptr[v + 1]):
        t = vt_idx[jj]
        if tri[t, 0] != w and tri[t, 1] != w and tri[t, 2] != w:
            s += _monochrome_weight(t, tri, inside, weight)
    return s


@njit(cache=True, nogil=True)
def _around_pair(w, p, vt_ptr, vt_idx, tri, inside, weight):
    """The monochrome weight of ``w``'s triangles and (if ``p >= 0``) ``p``'s others."""
    s = _around(w, -1, vt_ptr, vt_idx, tri, inside, weight)
    if p >= 0:
        s += _around(p, w, vt_ptr, vt_idx, tri, inside, weight)
    return s


@njit(cache=True, nogil=True)
def swap_gain(w, p, vt_ptr, vt_idx, tri, inside, weight):
    """How much monochrome weight putting ``w`` inside and ``p`` (if >= 0) outside
    takes away (negative: adds)."""
    before = _around_pair(w, p, vt_ptr, vt_idx, tri, inside, weight)
    inside[w] = True
    if p >= 0:
        inside[p] = False
    after = _around_pair(w, p, vt_ptr, vt_idx, tri, inside, weight)
    inside[w] = False
    if p >= 0:
        inside[p] = True
    return before - after


@njit(cache=True, nogil=True)
def _tree_distance(x, y, parent, depth, used, most):
    """Steps between inside ``x`` and ``y`` along the parents, or ``most + 1`` if more
    (or if the climb meets a vertex moved in this pass)."""
    s = 0
    while x != y and s <= most:
        if x < 0 or y < 0 or used[x] or used[y]:
            return most + 1
        if depth[x] >= depth[y]:
            x = parent[x]
        else:
            y = parent[y]
        s += 1
    return s if x == y else most + 1


@njit(cache=True, nogil=True)
def _mend_pass(ptr, idx, vt_ptr, vt_idx, tri, boundary, fixed, inside, parent, depth, weight, reach, short, used):
    """One pass of :func:`mend_tree`'s moves, each vertex moved at most once and its
    neighbours left alone (the parents are a pass old). Returns the moves made."""
    moves = 0
    nb = np.empty(MAX_ALONE, np.int64)
    path = np.empty(2 * reach + 2, np.int64)
    for t in range(tri.shape[0]):
        if inside[tri[t, 0]] or _monochrome_weight(t, tri, inside, weight) == 0.0:
            continue  # (an outside monochrome triangle)
        for k in range(3):
            w = tri[t, k]
            if inside[w] or boundary[w] or used[w]:
                continue
            c = 0
            for j in range(ptr[w], ptr[w + 1]):
                if inside[idx[j]]:
                    if c < MAX_ALONE:
                        nb[c] = idx[j]
                    c += 1
            if c == 0 or c > max(2, MAX_ALONE if short > 0 else 2):
                continue
            best, gain = -2, 1e-9
            n_path = 0
            if c == 1:  # a leaf: still one tree
                g = swap_gain(w, -1, vt_ptr, vt_idx, tri, inside, weight)
                if g > gain:
                    best, gain = -1, g
            elif c == 2:  # w closes a cycle through its two inside neighbours: one of the path's vertices goes out
                x, y = nb[0], nb[1]
                clean = True
                while x != y and n_path < reach:
                    if used[x] or used[y] or x < 0 or y < 0:
                        clean = False
                        break
                    if depth[x] >= depth[y]:
                        path[n_path] = x
                        x = parent[x]
                    else:
                        path[n_path] = y
                        y = parent[y]
                    n_path += 1
                if not clean:
                    continue
                for q in range(n_path):
                    p = path[q]
                    if fixed[p]:
                        continue
                    cnt = 0  # p's inside neighbours with w inside: just its two on the cycle
                    for j in range(ptr[p], ptr[p + 1]):
                        if inside[idx[j]] or idx[j] == w:
                            cnt += 1
                    if cnt != 2:
                        continue
                    g = swap_gain(w, p, vt_ptr, vt_idx, tri, inside, weight)
                    if g > gain:
                        best, gain = p, g
            if best == -2 and c >= 2 and short > 0:  # alone, if every cycle it closes is short
                ok = True
                for i in range(c):
                    for j in range(i + 1, c):
                        if _tree_distance(nb[i], nb[j], parent, depth, used, short) > short:
                            ok = False
                if ok:
                    g = swap_gain(w, -1, vt_ptr, vt_idx, tri, inside, weight)
                    if g > gain:
                        best, gain = -1, g
            if best == -2:
                continue
            for q in range(n_path):  # (their parents change)
                used[path[q]] = True
            inside[w] = True
            used[w] = True
            for j in range(ptr[w], ptr[w + 1]):
                used[idx[j]] = True
            if best >= 0:
                inside[best] = False
                for j in range(ptr[best], ptr[best + 1]):
                    used[idx[j]] = True
            moves += 1
            break
    return moves


def mend_tree(inside: np.ndarray, maps: VertexMaps, tri: np.ndarray, boundary: np.ndarray, fixed: np.ndarray,
              weight: np.ndarray, reach: int = 3, passes: int = 12, short: int = 0) -> int:
    """Take weight off the triangles an induced tree leaves monochrome, in place, by
    moves that keep it a tree (``inside`` (n,) bool): an outside vertex of a monochrome
    triangle joins, as a leaf, or, if it has two inside neighbours, with a vertex of the
    cycle it closes (within ``reach`` steps of them, with no other inside neighbour)
    taken out; a move is made when the weight (``weight`` (m,) float64 per monochrome
    triangle) falls. ``boundary`` vertices never join, ``fixed`` ones never leave.
    With ``short`` > 0 a vertex with 2 to ``MAX_ALONE`` inside neighbours, each pair
    at most ``short`` steps apart in the tree, may also join alone: each cycle it closes
    then rings a few outside vertices (a small extra cycle of the cover, which sparse
    mode joins like the default cover's, rather than an uncovered triangle).
    Returns the moves made (at most ``passes`` passes)."""
    n = len(inside)
    parent = np.empty(n, np.int64)
    depth = np.empty(n, np.int64)
    total = 0
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    weight = np.ascontiguousarray(weight, dtype=np.float64)
    for _ in range(passes):
        tree_parents(maps.ptr, maps.idx, inside, parent, depth)
        used = np.zeros(n, np.bool_)
        moves = _mend_pass(maps.ptr, maps.idx, maps.vt_ptr, maps.vt_idx, tri, boundary, fixed, inside, parent, depth,
                           weight, int(reach), int(short), used)
        total += moves
        if moves == 0:
            break
    return total


#: :func:`mend_tree`'s weight of a monochrome triangle that no join keeps to sparse
#: mode's rule (``comb_cover``'s ``keep``), against 1 for the others
BAD_WEIGHT = 10.0
#: :func:`mend_tree`'s ``reach`` in ``comb_cover`` (3: measured, docs/partition.md "Session 22")
MEND_REACH = 3
#: :func:`mend_tree`'s ``short`` in ``comb_cover`` (0: the tree stays a tree, one cycle)
MEND_SHORT = 3

#: ``comb_cover``'s frames: ``"auto"`` the ring frame round a hole the domain wraps
#: round (:func:`vertex_ring`), else the kd frame; ``"kd"`` always the kd frame.
FRAMES = ("auto", "kd")


def comb_cover(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, axis: int | None = None,
               angle: float = 0.0, levels: int = 2, penalty: float = 5.0, max_defer: int = 8,
               pitch: float = 0.02, frame: str = "auto", keep: float = 0.9, mend: int = 6) -> CycleCover:
    """The comb cover of a planar mesh: the cover of :func:`vertex_fishbone_tree`'s
    induced tree (``fill="comb"``), as ``cycle_cover`` returns it.

    Parameters
    ----------
    points : (n', 2) float64
        Rows past the triangles' largest vertex are ignored (room left by the caller).
    triangles : (m, 3) int64, counter-clockwise
    twin : (3 m,) int64, -1 on the boundary
    axis : int, optional
        The top spine runs along this axis (of the axes turned by ``angle``); default:
        across the domain's bounding box the short way (x if the box is taller than
        wide, else y: session 11's fishbone crosses the domain shortest).
    angle : float
        Degrees the fishbone's axes are turned counter-clockwise.
    levels, penalty, max_defer, pitch
        :func:`vertex_fishbone_tree`'s (session 21's measured settings).
    frame : {"auto", "kd"}
        ``"auto"``: round a hole that the domain wraps round, the ring frame
        (:func:`vertex_ring`; ``axis`` and ``angle`` then unused), else the kd frame.
    keep : float
        A triangle whose :func:`lone_join_bounds` is below ``keep`` x the input's
        smallest angle is *bad* (sparse mode's parent rule: a join there breaks it):
        the inside vertex of a bad triangle on the boundary joins first in its cell
        (:func:`rim_apexes`), and :func:`mend_tree` weighs a bad monochrome triangle
        ``BAD_WEIGHT`` times. 0: neither.
    mend : int
        :func:`mend_tree`'s passes (0: none).

    Returns
    -------
    CycleCover
        ``is_cov``, ``cycle`` (-1: uncovered), ``n_cycles`` (1 on a connected domain,
        plus the small cycles closed by :func:`mend_tree`'s lone joins: 5 on the gear at
        300 000 triangles; sparse mode joins them as the default cover's),
        ``n_uncovered``; ``n_unmatched`` 0.
    """
    if frame not in FRAMES:
        raise InvalidOptionError(f"frame must be one of {FRAMES}, not {frame!r}")
    if axis not in (None, 0, 1):
        raise InvalidOptionError(f"axis must be 0 or 1, got {axis!r}")
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    n = int(tri.max()) + 1 if len(tri) else 0
    pts = np.ascontiguousarray(np.asarray(points)[:n, :2], dtype=np.float64)
    pts0 = pts
    ring = vertex_ring(pts, tri, tw) if frame == "auto" else None
    if ring is not None:
        pts, axis = ring.points, 1  # (level 0 runs along the rim: the angle coordinate)
    else:
        pts = turned(pts, angle)
        if axis is None:
            ext = np.ptp(pts, axis=0) if n else np.ones(2)
            axis = 0 if ext[1] > ext[0] else 1
    bad = None
    if keep > 0 and n:
        corners = triangle_corners(pts0, tri)
        bad = lone_join_bounds(pts0, tri, tw, corners) < keep * corners.min()
    first = rim_apexes(tri, tw, n, bad) if bad is not None else None
    maps = vertex_maps(tri, n)  # (once: the growth's and the mending's)
    inside = vertex_fishbone_tree(pts, tri, tw, int(axis), penalty=penalty, max_defer=max_defer, levels=levels,
                                  fill="comb", pitch=pitch, ring=ring, first=first, maps=maps)
    if mend > 0 and n:
        bnd = boundary_vertices(tri, tw, n)
        fixed = ring.hole if ring is not None else np.zeros(n, np.bool_)
        weight = np.where(bad, BAD_WEIGHT, 1.0) if bad is not None else np.ones(len(tri))
        mend_tree(inside, maps, tri, bnd & ~fixed, fixed, weight, MEND_REACH, int(mend), MEND_SHORT)
    is_cov = cover_of(tri, tw, inside.astype(np.int8))
    cyc, n_cyc = cycle_ids_by_halves(tw, is_cov)
    return CycleCover(is_cov=is_cov, cycle=cyc, n_cycles=int(n_cyc), n_uncovered=int((cyc < 0).sum()),
                      n_unmatched=0)
