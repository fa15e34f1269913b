"""Sparse cycles as vertex colourings (issue 14, session 21): measurements, not
constructions sparse mode uses (docs/partition.md, "Session 21").

A cycle cover of a triangle mesh's dual graph is a 2-colouring of the vertices in which
every triangle is *mixed* (both colours): the cover crosses exactly the edges whose ends
differ, each mixed triangle has one monochrome edge (its matching edge), and a
monochrome triangle is uncovered. On a planar domain with its boundary one colour
(outside), the cover has ``components(inside) + components(outside) - 1`` cycles, so one
Hamiltonian cycle is a mixed colouring whose two colours are each connected: the walk
round an induced tree of inside vertices (``partition_ceilings.vertex_tree_cover``).
A vertex whose link alternates in colour can flip without unmixing a triangle: a star
rotation of the cover, which merges the cycles through its star when they are pairwise
distinct.

* :func:`colour_of_cover` / :func:`cover_of`: the two views of one cover;
* :func:`deferring_tree`: the induced vertex tree grown by Prim's search over the count
  quadtree's classes (as ``vertex_tree_cover``), deferring a vertex whose joining would
  *doom* a triangle (all three vertices outside and none able to join any more);
* :func:`small_loop_adds`: uncovered triangles covered by taking one of their vertices
  inside where every loop it closes through the inside is short (a small island: one
  small cycle more, not a split of the tree's cycle);
* :func:`scale_rotations`, :func:`capped_rotations`: star rotations merging cycles,
  Kruskal-like by scale (aligned cells, finest first) or never two big cycles;
* :func:`compact_cover`: the three above as a ``cycle_cover`` for sparse mode (the
  benchmark swaps it in for sparse mode's own; sparse's joins and fans do the rest and
  the output is certified as usual);
* ``vertex_fishbone_tree`` (now in ``hammesh.postprocess.comb_cover``, with
  ``vertex_maps``, ``boundary_vertices``, ``cover_of``, ``turned``, re-exported here):
  session 11's fishbone cells made on the vertices, grown top-down; its deepest cells
  grown breadth-first or (``fill="comb"``) as combs, which sparse mode takes as
  ``tree="comb"``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hammesh.postprocess._thm24_kernels import edge_class, quadtree_coords
from hammesh.postprocess.comb_cover import (boundary_vertices, cover_of, grow_induced_tree, turned,  # noqa: F401
                                            vertex_fishbone_tree, vertex_maps)

__all__ = ["vertex_maps", "boundary_vertices", "colour_of_cover", "cover_of", "flip_keeps_mixed", "deferring_tree",
           "small_loop_adds", "scale_rotations", "capped_rotations", "compact_cover", "vertex_fishbone_tree",
           "cycle_sizes", "seeded_cover", "turned", "FISH_FRAMES", "order_jumps"]

#: the vertex fishbone's frame per benchmark domain (axis, turn in degrees): the plate's
#: top spine along y between its holes (session 11's choice); the gear's turn the best
#: k = 64 of eight frames at 300 000 triangles (docs/partition.md, session 21)
FISH_FRAMES = {"plate_2_holes": (1, 0.0), "gear": (0, 75.0), "square": (1, 0.0), "rect_2x1": (0, 0.0)}


@njit(cache=True)
def _colour_into(tri, twin, is_cov, colour):
    """Breadth-first over the triangles: a cover half-edge ``3 t + k`` (vertices ``k``,
    ``k + 1`` of ``t``) separates its ends' colours, any other joins them. Returns the
    edges that disagree (0 for a cover of closed cycles on a domain where each cycle
    separates, e.g. planar)."""
    m = tri.shape[0]
    colour[:] = -1
    seen = np.zeros(m, np.bool_)
    queue = np.empty(m, np.int64)
    conflicts = 0
    for s in range(m):
        if seen[s]:
            continue
        if colour[tri[s, 0]] < 0:
            colour[tri[s, 0]] = 0
        seen[s] = True
        head, tail = 0, 1
        queue[0] = s
        while head < tail:
            t = queue[head]
            head += 1
            for _ in range(2):  # a triangle reached through one vertex settles the others
                for k in range(3):
                    a, b = tri[t, k], tri[t, (k + 1) % 3]
                    d = 1 if is_cov[3 * t + k] else 0
                    if colour[a] >= 0 and colour[b] < 0:
                        colour[b] = colour[a] ^ d
                    elif colour[b] >= 0 and colour[a] < 0:
                        colour[a] = colour[b] ^ d
            for k in range(3):
                a, b = tri[t, k], tri[t, (k + 1) % 3]
                if (colour[a] ^ colour[b]) != (1 if is_cov[3 * t + k] else 0):
                    conflicts += 1
                h = twin[3 * t + k]
                if h >= 0 and not seen[h // 3]:
                    seen[h // 3] = True
                    queue[tail] = h // 3
                    tail += 1
    return conflicts


def colour_of_cover(tri: np.ndarray, twin: np.ndarray, is_cov: np.ndarray,
                    boundary: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """``(colour, conflicts)``: the vertex colouring (int8, 0 / 1) whose bichromatic
    edges are the cover's ``is_cov`` half-edges; with ``boundary`` (bool per vertex)
    swapped so that most boundary vertices are 0 (outside)."""
    n = int(tri.max()) + 1
    colour = np.empty(n, np.int8)
    conflicts = _colour_into(np.ascontiguousarray(tri, dtype=np.int64), np.ascontiguousarray(twin, dtype=np.int64),
                             np.ascontiguousarray(is_cov, dtype=np.bool_), colour)
    if boundary is not None and boundary.any() and colour[boundary].mean() > 0.5:
        colour ^= 1
    return colour, int(conflicts)


def cycle_sizes(cyc: np.ndarray, n_cyc: int) -> np.ndarray:
    """Triangles per cycle id (``cyc`` -1 for uncovered)."""
    return np.bincount(cyc[cyc >= 0], minlength=n_cyc).astype(np.int64)


@njit(cache=True)
def _find(uf, x):
    r = x
    while uf[r] != r:
        r = uf[r]
    while uf[x] != r:
        nx = uf[x]
        uf[x] = r
        x = nx
    return r


@njit(cache=True)
def flip_keeps_mixed(v, tri, vt_ptr, vt_idx, colour):
    """Whether flipping ``v`` leaves no triangle round it with all three vertices of
    ``v``'s new colour (for a vertex whose triangles are mixed: its link alternates)."""
    y = 1 - colour[v]
    for j in range(vt_ptr[v], vt_ptr[v + 1]):
        t = vt_idx[j]
        same = 0
        for k in range(3):
            u = tri[t, k]
            if u != v and colour[u] == y:
                same += 1
        if same == 2:
            return False
    return True


@njit(cache=True)
def _edge_class_keys_into(ptr, idx, q, keys):
    """Each adjacency entry ``v -> idx[j]``'s key: the count quadtree's ``edge_class``."""
    for v in range(ptr.shape[0] - 1):
        for j in range(ptr[v], ptr[v + 1]):
            keys[j] = edge_class(q[v], q[idx[j]])


def deferring_tree(points: np.ndarray, tri: np.ndarray, twin: np.ndarray, penalty: int = 64,
                   max_defer: int = 8) -> tuple[np.ndarray, int]:
    """``(inside, deferrals)``: the induced vertex tree of ``partition_ceilings.vertex_tree_cover``
    (the count quadtree's classes on the vertices, seeded at the interior vertex nearest
    the mean point), grown by ``comb_cover.grow_induced_tree`` (lowest ``edge_class`` first,
    deferring a vertex at most ``max_defer`` times); ``max_defer = 0`` gives
    ``vertex_tree_cover``'s tree. ``points`` (n, 2); ``tri`` (m, 3) int64; ``twin`` (3 m,)."""
    n = len(points)
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    ptr, idx, vt_ptr, vt_idx = vertex_maps(tri, n)
    boundary = boundary_vertices(tri, twin, n)
    q = quadtree_coords(points, np.repeat(np.arange(n, dtype=np.int64), 3).reshape(n, 3))[:, 0].astype(np.int64)
    inside = np.zeros(n, np.bool_)
    interior = np.flatnonzero(~boundary)
    if not len(interior):
        return inside, 0
    seed = interior[np.argmin(((points[interior] - points.mean(axis=0)) ** 2).sum(axis=1))]
    keys = np.empty(len(idx), np.float64)
    _edge_class_keys_into(ptr, idx, q, keys)
    return tuple(grow_induced_tree(ptr, idx, keys, vt_ptr, vt_idx, tri, boundary, int(seed), float(penalty),
                                   int(max_defer)))


@njit(cache=True)
def _near_inside(ptr, idx, c, src, dst, avoid, lmax, mark, stamp, queue, dist):
    """Whether ``dst`` is at most ``lmax`` steps from ``src`` through inside vertices,
    avoiding ``avoid``."""
    mark[src] = stamp
    dist[src] = 0
    head, tail = 0, 1
    queue[0] = src
    while head < tail:
        u = queue[head]
        head += 1
        if u == dst:
            return True
        if dist[u] >= lmax:
            continue
        for j in range(ptr[u], ptr[u + 1]):
            w = idx[j]
            if w != avoid and c[w] == 1 and mark[w] != stamp:
                mark[w] = stamp
                dist[w] = dist[u] + 1
                queue[tail] = w
                tail += 1
    return False


@njit(cache=True)
def _small_loop_adds_into(tri, ptr, idx, vt_ptr, vt_idx, boundary, c, lmax, passes, stats):
    m = tri.shape[0]
    n = c.shape[0]
    mark = np.zeros(n, np.int64)
    dist = np.zeros(n, np.int64)
    queue = np.empty(n, np.int64)
    nbrs = np.empty(64, np.int64)
    stamp = 0
    for _ in range(passes):
        changed = 0
        for t in range(m):
            if c[tri[t, 0]] + c[tri[t, 1]] + c[tri[t, 2]] != 0:
                continue
            best = -1
            bestn = 1000
            for k in range(3):
                a = tri[t, k]
                if boundary[a] or not flip_keeps_mixed(a, tri, vt_ptr, vt_idx, c):
                    continue
                ns = 0
                for j in range(ptr[a], ptr[a + 1]):
                    if c[idx[j]] == 1 and ns < 64:
                        nbrs[ns] = idx[j]
                        ns += 1
                ok = True
                for i in range(1, ns):
                    stamp += 1
                    if _near_inside(ptr, idx, c, nbrs[0], nbrs[i], a, lmax, mark, stamp, queue, dist):
                        continue  # a short loop: a small island
                    stamp += 1
                    if _near_inside(ptr, idx, c, nbrs[0], nbrs[i], a, n, mark, stamp, queue, dist):
                        ok = False  # a long loop: it would cut the tree's cycle in two big ones
                        break
                # a leaf (one inside neighbour) makes no cycle; a vertex with none, or
                # each loop closed, makes one more (small) cycle
                cost = 1 if ns == 0 else ns - 1
                if ok and cost < bestn:
                    best = a
                    bestn = cost
            if best >= 0:
                c[best] = 1
                stats[0] += 1
                stats[1] += bestn == 0
                stats[2] += bestn
                changed += 1
        if changed == 0:
            break


def small_loop_adds(tri: np.ndarray, twin: np.ndarray, colour: np.ndarray, lmax: int = 16,
                    passes: int = 4) -> np.ndarray:
    """Cover uncovered (all-outside) triangles, in place: one of each one's vertices goes
    inside where no triangle becomes all inside and every loop it closes through the
    inside has at most ``lmax + 2`` vertices (or it joins separate inside pieces); of a
    triangle's vertices the one making fewest new cycles (a leaf none; a vertex with no
    inside neighbour, or each short loop closed, one small cycle). Returns ``[adds,
    leaves, cycles made]`` (an add that joins separate pieces is counted as making
    them, an upper bound)."""
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    n = len(colour)
    ptr, idx, vt_ptr, vt_idx = vertex_maps(tri, n)
    stats = np.zeros(3, np.int64)
    _small_loop_adds_into(tri, ptr, idx, vt_ptr, vt_idx, boundary_vertices(tri, twin, n), colour, int(lmax),
                          int(passes), stats)
    return stats


@njit(cache=True)
def _rotation_roots(v, tri, vt_ptr, vt_idx, c, cyc, uf, roots):
    """The cycles (roots) of the arcs through ``v``'s star, if pairwise distinct and at
    least two (else 0): the arcs cross the bichromatic spokes, each seen from its two
    triangles."""
    nr = 0
    nspoke = 0
    for j in range(vt_ptr[v], vt_ptr[v + 1]):
        t = vt_idx[j]
        if cyc[t] < 0:
            return 0
        r = _find(uf, cyc[t])
        for k in range(3):
            x = tri[t, k]
            if x != v and c[x] != c[v]:
                nspoke += 1
                seen = False
                for q in range(nr):
                    if roots[q] == r:
                        seen = True
                if not seen:
                    if nr == roots.shape[0]:
                        return 0
                    roots[nr] = r
                    nr += 1
    if nspoke % 2 != 0 or nspoke // 2 < 2 or nr != nspoke // 2:
        return 0
    return nr


@njit(cache=True)
def _rotation_candidate(v, tri, vt_ptr, vt_idx, boundary, c, cyc, uf, roots):
    """The distinct cycles (their union-find roots, into ``roots``) that a star
    rotation at interior vertex ``v`` would merge, or 0 where ``v`` cannot flip
    without unmixing a triangle (or is on the boundary)."""
    if boundary[v] or not flip_keeps_mixed(v, tri, vt_ptr, vt_idx, c):
        return 0
    return _rotation_roots(v, tri, vt_ptr, vt_idx, c, cyc, uf, roots)


@njit(cache=True)
def _scale_rotations_into(tri, vt_ptr, vt_idx, boundary, c, cyc, uf, bx0, bx1, by0, by1, px, py, levels, order):
    merged = 0
    roots = np.empty(64, np.int64)
    for rnd in range(levels + 1):
        s = 2.0 ** (-(levels - rnd))
        while True:
            changed = 0
            for i in range(order.shape[0]):
                v = order[i]
                nr = _rotation_candidate(v, tri, vt_ptr, vt_idx, boundary, c, cyc, uf, roots)
                if nr == 0:
                    continue
                x0, x1, y0, y1 = px[v], px[v], py[v], py[v]
                for q in range(nr):
                    r = roots[q]
                    x0, x1 = min(x0, bx0[r]), max(x1, bx1[r])
                    y0, y1 = min(y0, by0[r]), max(y1, by1[r])
                if rnd < levels and (np.floor(x0 / s) != np.floor(x1 / s) or np.floor(y0 / s) != np.floor(y1 / s)):
                    continue
                c[v] = 1 - c[v]
                top = roots[0]
                for q in range(1, nr):
                    uf[roots[q]] = top
                bx0[top], bx1[top], by0[top], by1[top] = x0, x1, y0, y1
                merged += nr - 1
                changed += 1
            if changed == 0:
                break
    return merged


def scale_rotations(points: np.ndarray, tri: np.ndarray, twin: np.ndarray, colour: np.ndarray, levels: int = 10) -> int:
    """Merge cycles by star rotations, in place, Kruskal-like by scale: in round ``r``
    (of ``levels``) only where the merged cycles' box (of their centroids) and the
    vertex fit one aligned cell of side ``2^-(levels - r)`` of the domain's square, then
    anywhere; vertices in index order each round (``levels = 0``: index order only).
    Returns the cycles merged away."""
    from hammesh.postprocess.cycle_cover import cycle_ids_by_halves

    tri = np.ascontiguousarray(tri, dtype=np.int64)
    n = len(colour)
    _, _, vt_ptr, vt_idx = vertex_maps(tri, n)
    cyc, n_cyc = cycle_ids_by_halves(twin, cover_of(tri, twin, colour))
    lo = points.min(axis=0)
    ext = float((points.max(axis=0) - lo).max()) * 1.0001
    p = (points - lo) / ext
    cen = p[tri].mean(axis=1)
    bx0, bx1 = np.full(n_cyc, 2.0), np.full(n_cyc, -1.0)
    by0, by1 = np.full(n_cyc, 2.0), np.full(n_cyc, -1.0)
    on = cyc >= 0
    np.minimum.at(bx0, cyc[on], cen[on, 0])
    np.maximum.at(bx1, cyc[on], cen[on, 0])
    np.minimum.at(by0, cyc[on], cen[on, 1])
    np.maximum.at(by1, cyc[on], cen[on, 1])
    return int(_scale_rotations_into(tri, vt_ptr, vt_idx, boundary_vertices(tri, twin, n), colour, cyc,
                                     np.arange(n_cyc, dtype=np.int64), bx0, bx1, by0, by1,
                                     np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]), int(levels),
                                     np.arange(n, dtype=np.int64)))


@njit(cache=True)
def _capped_rotations_into(tri, vt_ptr, vt_idx, boundary, c, cyc, uf, size, big, order):
    merged = 0
    roots = np.empty(64, np.int64)
    while True:
        changed = 0
        for i in range(order.shape[0]):
            v = order[i]
            nr = _rotation_candidate(v, tri, vt_ptr, vt_idx, boundary, c, cyc, uf, roots)
            if nr == 0:
                continue
            nbig = 0
            top = roots[0]
            for q in range(nr):
                if size[roots[q]] > big:
                    nbig += 1
                    top = roots[q]
            if nbig > 1:
                continue
            c[v] = 1 - c[v]
            total = 0
            for q in range(nr):
                total += size[roots[q]]
                if roots[q] != top:
                    uf[roots[q]] = top
            size[top] = total
            merged += nr - 1
            changed += 1
        if changed == 0:
            break
    return merged


def capped_rotations(tri: np.ndarray, twin: np.ndarray, colour: np.ndarray, big: int = 2000) -> int:
    """Merge cycles by star rotations, in place, never two of more than ``big`` triangles
    (a small cycle merged into a neighbour is a local detour; two big ones merged
    anywhere re-glue the tree elsewhere). Returns the cycles merged away."""
    from hammesh.postprocess.cycle_cover import cycle_ids_by_halves

    tri = np.ascontiguousarray(tri, dtype=np.int64)
    n = len(colour)
    _, _, vt_ptr, vt_idx = vertex_maps(tri, n)
    cyc, n_cyc = cycle_ids_by_halves(twin, cover_of(tri, twin, colour))
    return int(_capped_rotations_into(tri, vt_ptr, vt_idx, boundary_vertices(tri, twin, n), colour, cyc,
                                      np.arange(n_cyc, dtype=np.int64), cycle_sizes(cyc, n_cyc), int(big),
                                      np.arange(n, dtype=np.int64)))


#: ``compact_cover``'s settings (the benchmark's ``--colourings`` sets them per row):
#: the tree (``"quadtree"``: :func:`deferring_tree`; ``"fishbone"``:
#: :func:`vertex_fishbone_tree` with ``FISH_AXIS``, ``FISH_LEVELS``), the deferrals, the
#: small loops' bound (0: none) and the capped rotations' bound
TREE = "quadtree"
FISH_AXIS = 0
FISH_ANGLE = 0.0  # degrees: the fishbone's axes turned counter-clockwise
FISH_LEVELS = 2
FISH_FILL = "grow"  # the deepest cells: ``"grow"`` breadth-first, ``"comb"`` teeth across the spine
LMAX = 16
BIG = 2000
DEFER = 8
#: what the last ``compact_cover`` call made: tree's uncovered, cycles, uncovered
LAST: dict = {}


def compact_cover(triangles: np.ndarray, twin: np.ndarray, **kw):
    """A ``cycle_cover`` stand-in (same call; ``points`` used, the rest ignored): a
    vertex tree (``TREE``, deferring ``DEFER`` times a vertex, 0: none), small loops
    added (``LMAX``, 0: none), small cycles merged by capped rotations (``BIG``)."""
    from hammesh.postprocess.cycle_cover import CycleCover, cycle_ids_by_halves

    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    n = int(tri.max()) + 1
    pts = np.ascontiguousarray(np.asarray(kw["points"])[:n, :2], dtype=np.float64)
    if TREE == "fishbone":
        c = vertex_fishbone_tree(turned(pts, FISH_ANGLE), tri, tw, FISH_AXIS, penalty=5.0, max_defer=DEFER,
                                 levels=FISH_LEVELS, fill=FISH_FILL).astype(np.int8)
    else:
        c = deferring_tree(pts, tri, tw, 64, DEFER)[0].astype(np.int8)
    LAST.clear()
    LAST["tree_uncovered"] = int((c[tri].sum(axis=1) == 0).sum())
    if LMAX > 0:
        small_loop_adds(tri, tw, c, LMAX)
        capped_rotations(tri, tw, c, BIG)
    is_cov = cover_of(tri, tw, c)
    cyc, n_cyc = cycle_ids_by_halves(tw, is_cov)
    n_unc = int((cyc < 0).sum())
    LAST.update(cycles=int(n_cyc), uncovered=n_unc)
    return CycleCover(is_cov=is_cov, cycle=cyc, n_cycles=int(n_cyc), n_uncovered=n_unc, n_unmatched=0)


def seeded_cover(points: np.ndarray, tri: np.ndarray, twin: np.ndarray, colour: np.ndarray):
    """Sparse mode's cover (``cycle_cover``, no rotations, no split into halves) with its
    matching seeded from ``colour`` (session 16's scratch, kept: each mixed triangle
    matched across its monochrome edge, each uncovered one to a free neighbour) and
    completed by the cover's own augmenting searches. Returns the ``CycleCover``."""
    from hammesh.postprocess import _cover_kernels as ck
    from hammesh.postprocess import cycle_cover as cc

    tri = np.ascontiguousarray(tri, dtype=np.int64)

    def seeded(nb, active, side, half, rule, good, online, budget, mate, parent, fa, label, stamp):
        m = nb.shape[0]
        c3 = colour[tri]
        mono = c3 == np.roll(c3, -1, axis=1)
        act = np.asarray(active).copy()
        nbl = np.asarray(nb).astype(np.int64)
        nmono = mono.sum(axis=1)
        mixed = nmono == 1
        p = nbl[np.arange(m), np.argmax(mono, axis=1)]
        ok = mixed & act & (p >= 0)
        ok &= act[np.maximum(p, 0)] & mixed[np.maximum(p, 0)]
        mate[np.flatnonzero(ok)] = p[ok]
        for t in np.flatnonzero((nmono == 3) & act):
            for j in range(3):
                u = nbl[t, j]
                if u >= 0 and act[u] and mate[u] < 0 and mate[t] < 0:
                    mate[t], mate[u] = u, t
        queue = np.empty(budget + 16, np.int32)
        return ck._augment_every_free(nb, act, act, mate, parent, fa, label, stamp, 1, queue, budget)

    orig = ck.match_half
    ck.match_half = seeded
    try:
        return cc.cycle_cover(tri, twin, online=0, rotate=False, points=points)
    finally:
        ck.match_half = orig


def order_jumps(points_in: np.ndarray, tri_in: np.ndarray, order_in: np.ndarray, points_out: np.ndarray,
                tri_out: np.ndarray, big: int = 10_000) -> tuple[int, int]:
    """``(jumps, largest)``: how far an output cycle (``tri_out``'s rows in order) strays
    from an input cycle (``order_in``: ``tri_in``'s rows in cycle order). Each output row
    that is an input triangle unchanged (found by its centroid, to 1e-7) is placed at its
    position along the input cycle; ``jumps`` counts consecutive placed rows more than
    ``big`` positions apart (the short way round), ``largest`` the largest such step: a
    cycle that only had small pieces inserted has none; one cut into long arcs and
    spliced in another order has one per splice (session 21: sparse's re-routes)."""
    pos = np.full(len(tri_in), -1, np.int64)
    pos[order_in] = np.arange(len(order_in))

    def key(p, t):
        c = np.round(p[t].mean(axis=1) * 1e7).astype(np.int64)
        return c[:, 0] * np.int64(1 << 32) + c[:, 1]

    kin, kout = key(points_in, tri_in), key(points_out, tri_out)
    srt = np.argsort(kin, kind="stable")
    i = np.minimum(np.searchsorted(kin[srt], kout), len(kin) - 1)
    q = np.where(kin[srt][i] == kout, pos[srt[i]], -1)
    q = q[q >= 0]
    if len(q) < 2:
        return 0, 0
    d = np.abs(np.diff(q))
    d = np.minimum(d, len(order_in) - d)
    return int((d > big).sum()), int(d.max())
