"""Other spanning trees for the incircle cycle, to measure their cycle cut (issue 14).

Thm 2.4's cycle is the walk around a spanning tree of the dual graph, and the cut of
its stretches is decided by that tree (docs/partition.md). The shipped tree is a
minimum spanning forest for edge classes of a fishbone over a count quadtree
(``_thm24_kernels.spanning_forest``, Prim's search in numba; session 12 ported
:func:`fishbone_weights` there). ``quadtree`` below is the tree shipped until
session 11 (the count quadtree alone, but not turned by ``top_cross_angle``). Here any other class
scheme is tried the slow way: an edge weight per dual edge, scipy's minimum spanning
tree, and the result handed to the incircle construction in place of the shipped
forest (:func:`tree`), so that the output is built, verified and partitioned as
usual. ``bench_partition.py --trees`` prints the cut of each scheme against METIS's.

Schemes (weights: lower is taken first; every scheme ranks constrained edges last):

* ``quadtree``: the count quadtree's classes (``edge_class``) through scipy's tree:
  session 11's shipped tree (unturned), the control for the fishbone;
* ``bisection``: recursive bisection, each cell cut where its triangles' centroids
  are halved by count along the direction (of 16) that crosses the fewest dual edges;
  two levels form one class level (a cell and its four grandchildren, as in the
  quadtree), ranked by distance from the *junction* (the edge of the cell's line
  nearest both children's lines); below ``depth`` the quadtree classes;
* ``cross``: four-way cells cut by an *equipartition cross* (Courant and Robbins: two
  lines cut any planar mass into four equal parts): for each of 8 directions the
  first line halves the cell by count, the second is the ham-sandwich cut of the two
  halves (the direction whose bisector of one half also bisects the other; each half
  then split at its own median along it, so the counts are exact); the cross that
  crosses the fewest dual edges is kept, and the edges between the four children
  rank by distance from the crossing (moved to the nearest of those edges, so into
  the material); ``levels`` such levels, then the quadtree classes;
* ``cross_sampled``, ``cross_exact``, ``cross_exact64`` (and ``_l3``, ``_l4``: fewer
  levels): the crosses as a numba port would cut them (session 10), through a sample
  of the centroids, judged on the sampled triangles' dual edges, every triangle then
  placed by descending the crosses (:func:`cross_labels_sampled`); ``exact`` moves
  each line to its cell's median of all triangles; ``cross_unsampled`` is the same
  rules with every triangle sampled (the control); ``cross_local_l2``, ``_l3``: that
  many levels of them, then a count quadtree of each cross cell of its own
  (:func:`local_quadtree_weights`), and ``quadtree_local_l0`` its control (one cell);
* ``fishbone_x``, ``fishbone_y`` (session 11): every child pendant from its parent's
  spine (:func:`fishbone_weights`), the top spine along x or y, a line's gaps joined
  round the boundary (``_plain``: not joined); ``fishbone_y_15`` ... ``_75``: the axes
  turned by that many degrees; ``fishbone_auto``: the turn whose top spines are
  smallest (:func:`fishbone_auto`); :func:`runs_of_cells` gives the cut its cells
  would have if their counts matched the stretches exactly;
* ``ring`` (session 13, ported as ``_fishbone_kernels.ring_frame``): the fishbone round
  a hole (:func:`ring_weights`): the triangles touching the largest hole are the top
  spine, cut open at a seam, sectors of equal rows hang from it at their middles, and
  each sector is a fishbone in polar coordinates (its top spine radial);
  ``ring_seam{a}``, ``ring_s{s}_seam{a}``: the seam at ``a`` degrees, ``s`` sectors.
"""

from __future__ import annotations

from contextlib import contextmanager
from functools import partial
from typing import NamedTuple

import numpy as np

__all__ = ["forest_from_weights", "tree", "quadtree_weights", "bisection_weights", "cross_weights", "cross_sampled_weights",
           "fishbone_labels", "fishbone_of", "fishbone_weights", "fishbone_auto", "runs_of_cells", "Fishbone",
           "AUTO_ANGLES", "SCHEMES", "Ring", "ring_labels", "ring_weights"]

#: Weight of a constrained dual edge: above every free one (the forest crosses the fewest).
CON_WEIGHT = 1e9
#: Offset of the hierarchy's classes above the quadtree's (``N_CLASSES`` < 300).
LEVEL_BASE = 1000.0


def forest_from_weights(tri: np.ndarray, twin: np.ndarray, is_con: np.ndarray, weight: np.ndarray):
    """A minimum spanning forest of the dual graph for ``weight`` (one per half-edge,
    the same on both halves), as ``_thm24_kernels.Forest`` in the input numbering."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components, minimum_spanning_tree

    from hammesh.postprocess._thm24_kernels import CON_BIT, TREE_BIT, Forest

    m = len(tri)
    h = np.arange(3 * m)
    inner = np.flatnonzero(twin > h)
    a, b = inner // 3, twin[inner] // 3
    # scipy drops explicit zeros: every weight is made positive
    g = coo_matrix((weight[inner] - weight[inner].min() + 1.0, (a, b)), shape=(m, m)).tocsr()
    t = minimum_spanning_tree(g).tocoo()
    key = np.minimum(a, b) * m + np.maximum(a, b)
    o = np.argsort(key)
    r, s = t.row.astype(np.int64), t.col.astype(np.int64)  # scipy's int32 would overflow the key
    at = np.searchsorted(key[o], np.minimum(r, s) * m + np.maximum(r, s))
    picked = inner[o[at]]
    assert len(picked) == len(r) and np.array_equal(key[o][at], np.minimum(r, s) * m + np.maximum(r, s))
    in_tree = np.zeros(3 * m, bool)
    in_tree[picked] = True
    in_tree[twin[picked]] = True
    code = ((twin + 1) << 2) | (in_tree.astype(np.int64) * TREE_BIT) | (is_con.astype(np.int64) * CON_BIT)
    n_comp, comp = connected_components(t + t.T, directed=False)
    lowest = np.full(n_comp, m)
    np.minimum.at(lowest, comp, np.arange(m))
    split = np.flatnonzero(in_tree & is_con)
    return Forest(tri.copy(), code.astype(np.int64), np.arange(m), np.sort(lowest), split)


@contextmanager
def tree(weights):
    """Inside the block, ``hammesh.hamiltonian(mode="incircle")`` walks the minimum
    spanning forest of ``weights(points, tri, twin, is_con)`` instead of the shipped
    tree (``None``: the shipped tree)."""
    from hammesh.postprocess import _thm24_kernels, incircle

    if weights is not None:
        def forest(tri, twin, is_con, points=None, levels=None):
            return forest_from_weights(tri, twin, is_con, weights(points, tri, twin, is_con))

        incircle._kernels = _Kernels(_thm24_kernels, forest)
    try:
        yield
    finally:
        incircle._kernels = _thm24_kernels


class _Kernels:
    """``_thm24_kernels`` with another ``spanning_forest`` (the module is left alone)."""

    def __init__(self, module, forest) -> None:
        self._module = module
        self.spanning_forest = forest

    def __getattr__(self, name: str):
        return getattr(self._module, name)


def _edges(tri: np.ndarray, twin: np.ndarray):
    m = len(tri)
    h = np.arange(3 * m)
    g = np.where(twin >= 0, twin, h)
    return h // 3, g // 3, twin > h


def quadtree_weights(points, tri, twin, is_con) -> np.ndarray:
    """Session 11's shipped classes (``_thm24_kernels.edge_class`` of the count quadtree)."""
    from hammesh.postprocess._cover_kernels import edge_classes
    from hammesh.postprocess._thm24_kernels import quadtree_coords

    a, b, _ = _edges(tri, twin)
    q = quadtree_coords(points, tri)[:, 0].astype(np.int64)
    w = np.empty(len(a), np.int64)
    edge_classes(q[a], q[b], w)
    w = w.astype(np.float64)
    w[is_con] = CON_WEIGHT
    return w


def _median_split(c: np.ndarray, lab: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Per cell (``lab``), True for the upper half by count along ``direction``."""
    m = len(c)
    cnt = np.bincount(lab)
    o = np.lexsort((c @ direction, lab))
    start = np.r_[0, np.cumsum(cnt)][lab[o]]
    side = np.empty(m, bool)
    side[o] = np.arange(m) - start >= cnt[lab[o]] // 2
    return side


def bisection_labels(c: np.ndarray, a: np.ndarray, b: np.ndarray, depth: int, directions: int = 16) -> np.ndarray:
    """Cell of each triangle after ``depth`` count-halving cuts (bits, top cut first),
    each cell cut along the direction (of ``directions``) crossing the fewest of the
    dual edges ``a``-``b`` inside it."""
    m = len(c)
    lab = np.zeros(m, np.int64)
    ang = np.pi * np.arange(directions) / directions
    for _ in range(depth):
        n_cells = int(lab.max()) + 1
        same = lab[a] == lab[b]
        sides = [_median_split(c, lab, np.array([np.cos(t), np.sin(t)])) for t in ang]
        costs = np.stack([np.bincount(lab[a][same & (s[a] != s[b])], minlength=n_cells) for s in sides])
        best = np.argmin(costs, axis=0)
        lab = 2 * lab + np.stack(sides)[best[lab], np.arange(m)]
    return lab


def _hub_distances(mid, c, lab, cell_of_edge, sel, hub_of) -> np.ndarray:
    """Distance of each selected edge's midpoint from its cell's hub, over the cell's radius."""
    dist = np.zeros(len(mid))
    for cid in np.unique(cell_of_edge[sel]):
        s = sel & (cell_of_edge == cid)
        hub, members = hub_of(cid, s)
        r = np.sqrt(((c[members] - hub) ** 2).sum(1)).max() + 1e-300
        dist[s] = np.sqrt(((mid[s] - hub) ** 2).sum(1)) / r
    return dist


def bisection_weights(points, tri, twin, is_con, depth: int = 12, directions: int = 16) -> np.ndarray:
    """Recursive best-direction bisection, two levels a class level, junction hubs."""
    from scipy.spatial import cKDTree

    a, b, inner = _edges(tri, twin)
    c = points[tri].mean(axis=1)
    lab = bisection_labels(c, a[inner], b[inner], depth, directions)
    w = quadtree_weights(points, tri, twin, is_con)
    x = lab[a] ^ lab[b]
    diff = x != 0
    bl = np.zeros(len(a), np.int64)
    bl[diff] = np.floor(np.log2(x[diff])).astype(np.int64) + 1
    cut_depth = depth - bl  # depth of the cell whose line separates the two triangles
    top = 2 * (cut_depth // 2)  # its class level's top cell
    mid = 0.5 * (c[a] + c[b])
    dist = np.zeros(len(a))
    for d in np.unique(top[diff]):
        sel = diff & (top == d)
        cell = lab[a] >> (depth - d)

        def hub_of(cid, s, d=d):
            e = np.flatnonzero(s & inner)
            line = e[cut_depth[e] == d]
            below = e[cut_depth[e] != d]
            members = np.flatnonzero((lab >> (depth - d)) == cid)
            if not len(line) or not len(below):
                return mid[e].mean(axis=0), members
            side = (lab[a[below]] >> (depth - d - 1)) & 1
            near = sum(cKDTree(mid[below[side == k]]).query(mid[line])[0] for k in (0, 1) if (side == k).any())
            return mid[line[np.argmin(near)]], members

        dist += _hub_distances(mid, c, lab, cell, sel, hub_of)
    levels = int(top.max()) // 2 + 1 if diff.any() else 1
    w[diff] = LEVEL_BASE + (levels - top[diff] // 2) * 20 + 16 * np.minimum(dist[diff], 1.0)
    w[is_con] = CON_WEIGHT
    return w


def _cross(c: np.ndarray, ea: np.ndarray, eb: np.ndarray, directions: int, steps: int = 64):
    """The equipartition cross of points ``c`` crossing the fewest edges ``ea``-``eb``:
    ``(quadrant 0..3 of each point, crossing point)``."""
    best = None
    n = len(c)
    for t in np.pi * np.arange(directions) / directions:
        d1 = np.array([np.cos(t), np.sin(t)])
        s1 = c @ d1
        o1 = np.median(s1)
        up = s1 >= o1
        lo_, hi_ = c[~up], c[up]
        if len(lo_) < 2 or len(hi_) < 2:
            continue
        # ham-sandwich direction: the bisector of one half that halves the other
        phis = np.pi * np.arange(steps) / steps
        dirs = np.c_[np.cos(phis), np.sin(phis)]
        off = np.median(lo_ @ dirs.T, axis=0)
        miss = np.abs((hi_ @ dirs.T >= off).mean(axis=0) - 0.5)
        j = int(np.argmin(miss))
        d2 = dirs[j]
        s2 = c @ d2
        right = np.zeros(n, bool)
        for half in (~up, up):  # each half split at its own median: exact counts
            idx = np.flatnonzero(half)
            right[idx[np.argsort(s2[idx], kind="stable")[len(idx) // 2:]]] = True
        quad = 2 * up + right
        cost = np.count_nonzero(quad[ea] != quad[eb])
        if best is None or cost < best[0]:
            try:
                hub = np.linalg.solve(np.array([d1, d2]), np.array([o1, off[j]]))
            except np.linalg.LinAlgError:
                hub = c.mean(axis=0)
            best = (cost, quad, hub)
    if best is None:
        return np.zeros(n, np.int64), c.mean(axis=0)
    return best[1].astype(np.int64), best[2]


def cross_labels(c: np.ndarray, a: np.ndarray, b: np.ndarray, levels: int, directions: int = 8):
    """Cell of each triangle after ``levels`` equipartition crosses (two bits a level),
    and the crossing point of each cell's cross, ``hubs[(level, cell)]``."""
    m = len(c)
    lab = np.zeros(m, np.int64)
    hubs = {}
    for level in range(levels):
        new = 4 * lab
        o = np.argsort(lab, kind="stable")
        starts = np.r_[0, np.flatnonzero(np.diff(lab[o])) + 1, m]
        inside = lab[a] == lab[b]
        local = np.full(m, -1)
        for s0, s1 in zip(starts[:-1], starts[1:]):
            idx = o[s0:s1]
            cid = int(lab[idx[0]])
            if len(idx) < 8:
                hubs[(level, cid)] = c[idx].mean(axis=0)
                continue
            local[idx] = np.arange(len(idx))
            sel = inside & (lab[a] == cid)
            quad, hubs[(level, cid)] = _cross(c[idx], local[a[sel]], local[b[sel]], directions)
            new[idx] += quad
        lab = new
    return lab, hubs


def local_quadtree_weights(points, tri, twin, is_con, lab: np.ndarray) -> np.ndarray:
    """The quadtree classes of a count quadtree of each cell ``lab`` of its own (ranks
    inside the cell along x and y, the cell's box aspect kept), so that its cells nest
    in the cell; edges between cells get a class too (the caller overrides them)."""
    from hammesh.postprocess._cover_kernels import edge_classes
    from hammesh.postprocess._thm24_kernels import CELL_BITS

    a, b, _ = _edges(tri, twin)
    c = points[tri].mean(axis=1)
    top = (1 << CELL_BITS) - 1
    q = np.zeros(len(c), np.int64)
    o = np.argsort(lab, kind="stable")
    starts = np.r_[0, np.flatnonzero(np.diff(lab[o])) + 1, len(c)]
    for s0, s1 in zip(starts[:-1], starts[1:]):
        idx = o[s0:s1]
        n = len(idx)
        ext = c[idx].max(axis=0) - c[idx].min(axis=0)
        f = top * ext / max(float(ext.max()), 1e-300) / n
        rank = np.empty((n, 2))
        for ax in (0, 1):
            rank[np.argsort(c[idx, ax], kind="stable"), ax] = np.arange(n)
        qx, qy = np.minimum((rank * f).astype(np.int64), top).T
        q[idx] = (qx << CELL_BITS) | qy
    w = np.empty(len(a), np.int64)
    edge_classes(q[a], q[b], w)
    w = w.astype(np.float64)
    w[is_con] = CON_WEIGHT
    return w


def cross_weights(points, tri, twin, is_con, levels: int = 6, directions: int = 8, labels=None,
                  local: bool = False) -> np.ndarray:
    """Equipartition crosses, ``levels`` levels, then the quadtree classes (``labels``:
    :func:`cross_labels_sampled` cuts them on a sample; ``local``: each cross cell gets
    a count quadtree of its own, :func:`local_quadtree_weights`, not the global one)."""
    a, b, inner = _edges(tri, twin)
    c = points[tri].mean(axis=1)
    if labels is None:
        lab, hubs = cross_labels(c, a[inner], b[inner], levels, directions)
    else:
        lab, hubs = labels(c, np.asarray(twin), levels, directions)
    if local:
        w = local_quadtree_weights(points, tri, twin, is_con, lab)
    else:
        w = quadtree_weights(points, tri, twin, is_con)
    x = lab[a] ^ lab[b]
    diff = x != 0
    digit = np.zeros(len(a), np.int64)
    digit[diff] = np.floor(np.log2(x[diff])).astype(np.int64) // 2 + 1
    level = levels - digit  # level of the cross that separates the two triangles
    mid = 0.5 * (c[a] + c[b])
    dist = np.zeros(len(a))
    for lv in range(levels):
        sel = diff & (level == lv)
        if not sel.any():
            continue
        cell = lab[a] >> (2 * (levels - lv))

        def hub_of(cid, s, lv=lv):
            e = np.flatnonzero(s)  # the crossing moved onto the nearest edge of the cross
            hub = mid[e[np.argmin(((mid[e] - hubs[(lv, int(cid))]) ** 2).sum(1))]]
            return hub, np.flatnonzero((lab >> (2 * (levels - lv))) == cid)

        dist += _hub_distances(mid, c, lab, cell, sel, hub_of)
    w[diff] = LEVEL_BASE + (levels - level[diff]) * 20 + 16 * np.minimum(dist[diff], 1.0)
    w[is_con] = CON_WEIGHT
    return w


def _cross_params(c: np.ndarray, ea: np.ndarray, eb: np.ndarray, n_own: int, directions: int, steps: int):
    """:func:`_cross` judged on a sample: the cross is cut through the first ``n_own``
    points of ``c`` (the sampled centroids of one cell); the edges ``ea``-``eb`` (into
    ``c``, whose other points are the sampled triangles' neighbours in the cell) count
    its crossings. Returns ``(d1, o1, d2, o_lo, o_hi, hub)``: a point ``x`` is in quadrant
    ``2 (x.d1 >= o1) + (x.d2 >= (o_hi if x.d1 >= o1 else o_lo))``; None below 8 points."""
    own = c[:n_own]
    if n_own < 8:
        return None
    best = None
    phis = np.pi * np.arange(steps) / steps
    dirs = np.c_[np.cos(phis), np.sin(phis)]
    for t in np.pi * np.arange(directions) / directions:
        d1 = np.array([np.cos(t), np.sin(t)])
        s1 = own @ d1
        o1 = np.sort(s1)[n_own // 2]  # the upper half holds ceil(n / 2) of the sample
        up = s1 >= o1
        lo_, hi_ = own[~up], own[up]
        if len(lo_) < 2 or len(hi_) < 2:
            continue
        off = np.median(lo_ @ dirs.T, axis=0)
        miss = np.abs((hi_ @ dirs.T >= off).mean(axis=0) - 0.5)
        d2 = dirs[int(np.argmin(miss))]
        o_lo = np.sort(lo_ @ d2)[len(lo_) // 2]
        o_hi = np.sort(hi_ @ d2)[len(hi_) // 2]
        cu = c @ d1 >= o1
        quad = 2 * cu + (c @ d2 >= np.where(cu, o_hi, o_lo))
        cost = np.count_nonzero(quad[ea] != quad[eb])
        if best is None or cost < best[0]:
            try:
                hub = np.linalg.solve(np.array([d1, d2]), np.array([o1, 0.5 * (o_lo + o_hi)]))
            except np.linalg.LinAlgError:
                hub = own.mean(axis=0)
            best = (cost, (d1, o1, d2, o_lo, o_hi, hub))
    return None if best is None else best[1]


def cross_labels_sampled(c: np.ndarray, twin: np.ndarray, levels: int, directions: int = 8, steps: int = 16,
                         sample: int = 1 << 14, exact: bool = False):
    """:func:`cross_labels` as a numba port would do it: every cross is cut through a
    sample of the centroids (every ``m // sample``-th triangle) and judged on the
    sampled triangles' dual edges; then every triangle is placed by descending the
    crosses (two dot products a level). ``exact``: the lines keep the sample's
    directions but move to the medians of all the cell's triangles (exact counts, as
    :func:`cross_labels`: one selection per cell and line). Returns ``(labels, hubs)``."""
    m = len(c)
    s = np.arange(0, m, max(1, m // sample))
    nb = twin.reshape(m, 3)[s]
    has = nb >= 0
    ns = len(s)
    probe = np.r_[s, nb[has] // 3]  # the sample, then each sampled edge's far triangle
    ea = np.repeat(np.arange(ns), 3)[has.ravel()]
    eb = ns + np.arange(int(has.sum()))
    lab_all = np.zeros(m, np.int64)
    lab = np.zeros(len(probe), np.int64)
    hubs = {}
    for level in range(levels):
        new_all, new = 4 * lab_all, 4 * lab
        for cid in np.unique(lab[:ns]):
            own = np.flatnonzero(lab[:ns] == cid)
            far = ns + np.flatnonzero(lab[ns:] == cid)
            pts = np.r_[own, far]
            pos = np.full(len(probe), -1)
            pos[pts] = np.arange(len(pts))
            keep = (pos[ea] >= 0) & (pos[eb] >= 0)
            prm = _cross_params(c[probe[pts]], pos[ea[keep]], pos[eb[keep]], len(own), directions, steps)
            cell_all = np.flatnonzero(lab_all == cid)
            if prm is None:
                hubs[(level, int(cid))] = c[cell_all].mean(axis=0)
                continue
            d1, o1, d2, o_lo, o_hi, hubs[(level, int(cid))] = prm
            if exact:
                x = c[cell_all]
                s1 = x @ d1
                o1 = np.sort(s1)[len(x) // 2]
                up = s1 >= o1
                s2 = x @ d2
                o_lo = np.sort(s2[~up])[int((~up).sum()) // 2]
                o_hi = np.sort(s2[up])[int(up.sum()) // 2]
                try:  # where the first line meets the second (as :func:`_cross`)
                    hubs[(level, int(cid))] = np.linalg.solve(np.array([d1, d2]), np.array([o1, o_lo]))
                except np.linalg.LinAlgError:
                    pass
            for idx, x, out in ((pts, c[probe[pts]], new), (cell_all, c[cell_all], new_all)):
                up = x @ d1 >= o1
                out[idx] += 2 * up + (x @ d2 >= np.where(up, o_hi, o_lo))
        lab_all, lab = new_all, new
    return lab_all, hubs


def cross_sampled_weights(points, tri, twin, is_con, levels: int = 6, directions: int = 8) -> np.ndarray:
    """:func:`cross_weights` with the crosses cut on a sample (:func:`cross_labels_sampled`)."""
    return cross_weights(points, tri, twin, is_con, levels, directions, labels=cross_labels_sampled)


def cross_exact_weights(points, tri, twin, is_con, levels: int = 6, directions: int = 8) -> np.ndarray:
    """:func:`cross_sampled_weights` with each line moved to its exact median (``exact``)."""
    def labels(c, tw, lv, dirs):
        return cross_labels_sampled(c, tw, lv, dirs, steps=16, exact=True)

    return cross_weights(points, tri, twin, is_con, levels, directions, labels=labels)


def cross_exact64_weights(points, tri, twin, is_con, levels: int = 6, directions: int = 8) -> np.ndarray:
    """:func:`cross_exact_weights` with 64 ham-sandwich directions (as :func:`cross_weights`)."""
    def labels(c, tw, lv, dirs):
        return cross_labels_sampled(c, tw, lv, dirs, steps=64, exact=True)

    return cross_weights(points, tri, twin, is_con, levels, directions, labels=labels)


def cross_local_weights(points, tri, twin, is_con, levels: int = 3, directions: int = 8) -> np.ndarray:
    """``levels`` levels of crosses cut on a sample (:func:`cross_exact64_weights`'
    rules, each cell's lines at its exact medians), then a count quadtree inside each
    cross cell (``local``): the top levels, where a sample of 16 384 holds hundreds of
    triangles a cell, from the crosses; the rest nested in them."""
    def labels(c, tw, lv, dirs):
        return cross_labels_sampled(c, tw, lv, dirs, steps=64, exact=True)

    return cross_weights(points, tri, twin, is_con, levels, directions, labels=labels, local=True)


def cross_unsampled_weights(points, tri, twin, is_con, levels: int = 6, directions: int = 8) -> np.ndarray:
    """:func:`cross_exact64_weights` with every triangle in the "sample": the control that
    tells what the sampling costs from what the port's other choices do."""
    def labels(c, tw, lv, dirs):
        return cross_labels_sampled(c, tw, lv, dirs, steps=64, sample=1 << 40, exact=True)

    return cross_weights(points, tri, twin, is_con, levels, directions, labels=labels)


def _cell_medians(cell: np.ndarray, value: np.ndarray, n_cells: int) -> np.ndarray:
    """Per cell id (``cell`` >= 0), the value at rank ``count // 2`` of its members
    (so that the upper side, ``value >= median``, holds ``ceil(count / 2)`` of distinct
    values); NaN for an empty cell."""
    o = np.lexsort((value, cell))
    cnt = np.bincount(cell, minlength=n_cells)
    start = np.r_[0, np.cumsum(cnt)[:-1]]
    med = np.full(n_cells, np.nan)
    full = cnt > 0
    med[full] = value[o][start[full] + cnt[full] // 2]
    return med


class Fishbone(NamedTuple):
    """Cells of :func:`fishbone_labels`."""

    #: ``labels[l]``: the cell (0 .. 4**l - 1) of each triangle at level ``l``, -1 once
    #: the triangle has been taken into a spine above
    labels: list
    #: level at which each triangle is in its cell's spine, -1 for none
    spine_level: np.ndarray
    #: ``lines[l]``: each level-``l`` cell's spine line (a coordinate across its axis)
    lines: list
    #: ``regions[l]``: the level-``l`` cell each triangle counts in, spine triangles included
    regions: list
    #: axis (0: x, 1: y) along which the top cell's spine runs; level ``l``'s is ``(axis + l) % 2``
    axis: int


def fishbone_labels(points: np.ndarray, tri: np.ndarray, axis: int = 0, min_cell: int = 8,
                    twin: np.ndarray | None = None, gap_levels: int = 99) -> Fishbone:
    """Cells of a *fishbone* hierarchy (session 11). Each cell has a spine: the
    triangles its count-median line crosses (the line runs along ``axis`` at the top,
    and each level turns it by 90 degrees). The other triangles fall into four
    children: the two sides of the line, each halved by count along the line. So a
    child's own spine starts on its parent's spine, where the child hangs from it. The
    lines are medians of every triangle of the cell's region, its own and its
    ancestors' spine triangles included (on their centroid's side), so the regions hold
    equal counts (within one). With ``twin`` (half-edge twins, -1 on the boundary), a
    line that leaves the domain and comes back (a hole, a notch) is joined round the
    gap by the triangles touching the boundary there, on its lower side: the spine
    stays one path, so the children hang from it as on a domain without holes.
    Levels until cells hold about ``min_cell`` triangles."""
    c = points[tri].mean(axis=1)
    lo, hi = points[tri].min(axis=1), points[tri].max(axis=1)
    m = len(c)
    depth = max(1, int(np.log(max(m / min_cell, 1.0)) / np.log(4.0)))
    labels, lines, regions = [], [], []
    spine_level = np.full(m, -1)
    lab = np.zeros(m, np.int64)
    # the cell a triangle counts in, spines included: a spine's rows are walked
    # just before or after the cells beside it (the first and last children of the
    # cell below, which hangs from it), so they count in those cells' medians
    region = np.zeros(m, np.int64)
    for level in range(depth + 1):
        labels.append(lab)
        regions.append(region)
        along = (axis + level) % 2
        across = 1 - along
        line = _cell_medians(region, c[:, across], 4**level)
        lines.append(line)
        if level == depth:
            break
        at = line[region]
        side = 2 * region + (c[:, across] >= at)
        far = c[:, along] >= _cell_medians(side, c[:, along], 2 * 4**level)[side]
        region = 2 * side + far
        spine = (lab >= 0) & (lo[:, across] <= at) & (at <= hi[:, across])
        if twin is not None and level < gap_levels:
            _join_round_gaps(spine, lab, c, at, along, twin, tri)
        lab = np.where((lab >= 0) & ~spine, region, -1)
        spine_level[spine] = level
    return Fishbone(labels, spine_level, lines, regions, axis)


def _join_round_gaps(spine: np.ndarray, lab: np.ndarray, c: np.ndarray, at: np.ndarray, along: int,
                     twin: np.ndarray, tri: np.ndarray) -> None:
    """Add to ``spine`` (in place), for each cell whose spine has a gap along its line
    (the line crosses a hole or runs outside the domain), the triangles with a vertex on
    the boundary that lie in the gap below the line and connect its two ends."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(c)
    across = 1 - along
    on_rim = np.zeros(int(tri.max()) + 1, bool)
    on_rim[tri.ravel()[twin < 0]] = True
    rim = on_rim[tri].any(axis=1)
    idx = np.flatnonzero(spine)
    idx = idx[np.lexsort((c[idx, along], lab[idx]))]
    step = np.diff(c[idx, along])
    same = lab[idx[1:]] == lab[idx[:-1]]
    if not same.any():
        return
    typical = np.median(step[same])
    for g in np.flatnonzero(same & (step > 6.0 * typical)):
        t0, t1 = idx[g], idx[g + 1]
        cell = lab[t0]
        slack = 4.0 * typical
        cand = np.flatnonzero((lab == cell) & rim & ~spine & (c[:, along] > c[t0, along] - slack)
                              & (c[:, along] < c[t1, along] + slack) & (c[:, across] < at))
        if not len(cand):
            continue
        line_own = idx[lab[idx] == cell]
        line_own = line_own[(line_own != t0) & (line_own != t1)]
        nodes = np.r_[t0, t1, cand, line_own]  # the line's own triangles: the ends' neighbours
        pos = np.full(m, -1)
        pos[nodes] = np.arange(len(nodes))
        h = (3 * nodes[:, None] + np.arange(3)).ravel()
        nb = np.where(twin[h] >= 0, pos[np.maximum(twin[h], 0) // 3], -1)
        src = np.repeat(np.arange(len(nodes)), 3)
        ok = nb >= 0
        g_ = coo_matrix((np.ones(ok.sum()), (src[ok], nb[ok])), shape=(len(nodes), len(nodes)))
        _, comp = connected_components(g_, directed=False)
        if comp[0] == comp[1]:  # a path round the gap from one end to the other
            spine[cand[comp[2:2 + len(cand)] == comp[0]]] = True


def _turned(points: np.ndarray, angle: float) -> np.ndarray:
    """``points`` in axes turned counter-clockwise by ``angle`` degrees."""
    if not angle:
        return points
    t = np.radians(angle)
    return points @ np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])


def fishbone_of(points, tri, twin, axis: int = 0, holes: bool = True, angle: float = 0.0,
                gap_levels: int = 99) -> Fishbone:
    """The cells :func:`fishbone_weights` builds its tree from (same arguments)."""
    return fishbone_labels(_turned(points, angle), tri, axis, twin=twin if holes else None, gap_levels=gap_levels)


def _deepest(labels: list, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per edge ``a``-``b``: the deepest level whose cell (``labels[level]``, -1 once on
    a spine above) holds both triangles."""
    deepest = np.full(len(a), -1)
    for level, lab in enumerate(labels):
        deepest[(lab[a] == lab[b]) & (lab[a] >= 0)] = level
    return deepest


def fishbone_weights(points, tri, twin, is_con, axis: int = 0, holes: bool = True, angle: float = 0.0,
                     gap_levels: int = 99) -> np.ndarray:
    """The fishbone tree (:func:`fishbone_labels`): inside each cell, the spine's own
    edges first, then each child hangs from the spine by the edge nearest the point
    where the child's spine line meets it, then the edges between children (walls,
    taken only where a hole cuts a spine); deeper cells before their parents. The walk
    then visits each child whole (every child is pendant): a cell is walked as
    near-left, far-left, far-right, near-right child, so that for ``k = 4^j`` the
    stretches are cells and for ``k = 2 * 4^j`` halves of cells split by their spine,
    with no offset at any level (the quadtree's entry child is split, docs/partition.md)."""
    fb = fishbone_of(points, tri, twin, axis, holes, angle, gap_levels)
    points = _turned(points, angle)
    c = points[tri].mean(axis=1)
    a, b, _ = _edges(tri, twin)
    depth = len(fb.labels) - 1
    mid = 0.5 * (c[a] + c[b])
    scale = 2.0 * float(np.ptp(c, axis=0).max()) + 1e-300  # distances below 1/2
    deepest = _deepest(fb.labels, a, b)
    w = np.zeros(len(a))
    for level in range(depth + 1):
        sel = deepest == level
        base = 10.0 * (depth - level)
        if level == depth:
            w[sel] = base
            continue
        along = (axis + level) % 2
        sa, sb = fb.spine_level[a] == level, fb.spine_level[b] == level
        w[sel & sa & sb] = base
        hang = np.flatnonzero(sel & (sa ^ sb))
        kid = np.where(sa, b, a)[hang]
        child = fb.labels[level + 1][kid]
        target = np.empty((len(hang), 2))
        target[:, along] = fb.lines[level + 1][child]  # the child's spine line
        target[:, 1 - along] = fb.lines[level][fb.labels[level][a[hang]]]  # meets the parent's
        # a child hangs by its own spine's end: hung by another of its triangles, the
        # walk would enter a grandchild first and split it in two runs
        off_spine = 2.0 * (fb.spine_level[kid] != level + 1)
        w[hang] = base + 1.0 + off_spine + np.sqrt(((mid[hang] - target) ** 2).sum(1)) / scale
        walls = np.flatnonzero(sel & ~sa & ~sb)
        line = fb.lines[level][fb.labels[level][a[walls]]]
        w[walls] = base + 5.0 + np.abs(mid[walls, 1 - along] - line) / scale
    w[is_con] = CON_WEIGHT
    return w


#: Turns :func:`fishbone_auto` tries (degrees; the lines repeat every 90, the axes every 180).
AUTO_ANGLES = tuple(range(0, 180, 15))


def fishbone_auto(points, tri, twin, is_con, levels: int = 3) -> np.ndarray:
    """:func:`fishbone_weights` with the top axis turned by the angle (of
    ``AUTO_ANGLES``) whose spines of the top ``levels`` levels hold the fewest
    triangles: those spines are the cuts between the stretches at k = 8 (two levels)
    and k = 64 (three); the walls between the cells are not counted (a guess that
    they vary less with the angle; measured in docs/partition.md, not proven)."""
    cost = []
    for a in AUTO_ANGLES:
        fb = fishbone_of(points, tri, twin, 0, True, a)
        cost.append(int(np.count_nonzero((fb.spine_level >= 0) & (fb.spine_level < levels))))
    return fishbone_weights(points, tri, twin, is_con, angle=AUTO_ANGLES[int(np.argmin(cost))])


def runs_of_cells(parent: np.ndarray, cell: np.ndarray) -> np.ndarray:
    """Cut a cycle (output rows in order, ``parent``: each row's input triangle) where
    a cell (``cell``: one per input triangle, -1 for none) is first reached, counting
    from the first row of the cell reached second (so that the cell the cycle starts
    in is not split; rows of no cell go with the run before them). Returns each row's
    run: what the stretches would be if every cell's count matched the stretch size
    exactly (the cells' own cut, unbalanced)."""
    m = len(parent)
    lab = cell[parent]
    rows = np.flatnonzero(lab >= 0)
    first = np.full(int(lab.max()) + 1, m)
    np.minimum.at(first, lab[rows], rows)
    reached = np.sort(first[first < m])
    pos = (np.arange(m) - (reached[1] if len(reached) > 1 else 0)) % m
    first[:] = m  # again from there: the cell the cycle starts in is now in one piece
    np.minimum.at(first, lab[rows], pos[rows])
    starts = np.sort(first[first < m])
    return np.searchsorted(starts, pos, side="right") - 1


#: ``--trees`` schemes: name -> weights function (None: the shipped numba forest).
SCHEMES = {
    "shipped": None,
    "quadtree": quadtree_weights,
    "bisection": bisection_weights,
    "cross": cross_weights,
    "cross_sampled": cross_sampled_weights,
    "cross_exact": cross_exact_weights,
    "cross_exact64": cross_exact64_weights,
    "cross_exact64_l3": partial(cross_exact64_weights, levels=3),
    "cross_exact64_l4": partial(cross_exact64_weights, levels=4),
    "cross_unsampled": cross_unsampled_weights,
    "cross_local_l2": partial(cross_local_weights, levels=2),
    "cross_local_l3": cross_local_weights,
    "quadtree_local_l0": partial(cross_local_weights, levels=0),
    "fishbone_x": fishbone_weights,
    "fishbone_y": partial(fishbone_weights, axis=1),
    "fishbone_auto": fishbone_auto,
    "fishbone_x_plain": partial(fishbone_weights, holes=False),
    "fishbone_y_plain": partial(fishbone_weights, axis=1, holes=False),
    **{f"fishbone_y_{a}": partial(fishbone_weights, axis=1, angle=a) for a in (15, 30, 45, 60, 75)},
}


class Ring(NamedTuple):
    """Cells of :func:`ring_labels`: a :class:`Fishbone` in polar coordinates."""

    labels: list
    spine_level: np.ndarray
    lines: list
    #: the unrolled polar coordinates of the centroids: (angle from the seam x the
    #: reference radius, radius)
    c: np.ndarray
    rim: np.ndarray
    sectors: int


def ring_labels(points: np.ndarray, tri: np.ndarray, twin: np.ndarray, sectors: int = 8, seam: float = 0.0,
                min_cell: int = 8) -> Ring:
    """A fishbone for an annulus. The triangles touching the largest hole form the
    *rim spine* (level 0), cut open at the angle ``seam`` (radians); the rest is cut
    into ``sectors`` sectors of equal counts by angle, each hanging from the rim spine
    at its middle, and each sector is a fishbone (:func:`fishbone_labels`' rules) whose
    top spine is the radial line through its middle. The walk then sweeps the ring
    once: along the rim's outer side, sector after sector (each one run), and back
    along the rim's own hole side."""
    from hammesh.postprocess._fishbone_kernels import boundary_loops

    label = boundary_loops(tri, twin, len(points))
    loops = [np.flatnonzero(label == i) for i in np.unique(label[label >= 0])]
    ext = [float(np.ptp(points[lp], axis=0).max()) for lp in loops]
    outer = int(np.argmax(ext))
    holes = [i for i in range(len(loops)) if i != outer]
    hole = loops[max(holes, key=lambda i: ext[i])]
    centre = points[hole].mean(axis=0)
    cen = points[tri].mean(axis=1) - centre
    th = (np.arctan2(cen[:, 1], cen[:, 0]) - seam) % (2 * np.pi)
    r = np.hypot(cen[:, 0], cen[:, 1])
    r_ref = float(np.median(r))
    c = np.c_[th * r_ref, r]
    vx = points[tri] - centre  # (m, 3, 2)
    vth = np.arctan2(vx[..., 1], vx[..., 0]) - seam
    dth = (vth - th[:, None] + np.pi) % (2 * np.pi) - np.pi
    vu = (th[:, None] + dth) * r_ref
    vr = np.hypot(vx[..., 0], vx[..., 1])
    lo = np.c_[vu.min(1), vr.min(1)]
    hi = np.c_[vu.max(1), vr.max(1)]
    on_hole = np.zeros(int(tri.max()) + 1, bool)
    on_hole[hole] = True
    rim = on_hole[tri].any(axis=1)
    m = len(c)
    spine_level = np.full(m, -1)
    spine_level[rim] = 0
    # sectors by count along the angle (every triangle counts: the rim's rows are
    # walked between the sectors)
    # sectors by output rows walked on the way out (three a triangle, about two for
    # a rim triangle: about one of its rows is on the rim's hole side, walked on the
    # way back after the last sector), so that sector j starts at row j n / sectors
    o = np.argsort(c[:, 0], kind="stable")
    fwd = np.where(rim, 2.0, 3.0)[o]
    region = np.empty(m, np.int64)
    region[o] = np.minimum((np.cumsum(fwd) - 0.5 * fwd) * sectors // (3.0 * m), sectors - 1)
    lab = np.where(rim, -1, region)
    labels, lines = [np.zeros(m, np.int64), lab], [np.full(1, np.nan)]
    depth = 1 + max(1, int(np.log(max(m / (sectors * min_cell), 1.0)) / np.log(4.0)))
    for level in range(1, depth + 1):
        n_cells = sectors * 4 ** (level - 1)
        along = level % 2  # level 1: the spine runs along the radius
        across = 1 - along
        line = _cell_medians(region, c[:, across], n_cells)
        lines.append(line)
        if level == depth:
            break
        at = line[region]
        side = 2 * region + (c[:, across] >= at)
        far = c[:, along] >= _cell_medians(side, c[:, along], 2 * n_cells)[side]
        region = 2 * side + far
        spine = (lab >= 0) & (lo[:, across] <= at) & (at <= hi[:, across])
        _join_round_gaps(spine, lab, c, at, along, twin, tri)
        lab = np.where((lab >= 0) & ~spine, region, -1)
        spine_level[spine] = level
        labels.append(lab)
    return Ring(labels, spine_level, lines, c, rim, sectors)


def ring_weights(points, tri, twin, is_con, sectors: int = 8, seam: float = 0.0) -> np.ndarray:
    """The tree of :func:`ring_labels` (weights as :func:`fishbone_weights`: deeper
    cells first; in a cell its spine, then each child hung by its own spine's end
    nearest where its line meets the spine, then the walls). At the ring level the
    rim's edges across the seam are walls, so the rim spine is a path round the hole."""
    rg = ring_labels(points, tri, twin, sectors, seam)
    c = rg.c
    a, b, _ = _edges(tri, twin)
    depth = len(rg.labels) - 1
    mid = 0.5 * (c[a] + c[b])
    span = float(np.ptp(c[:, 0]))
    scale = 2.0 * float(np.ptp(c, axis=0).max()) + 1e-300
    deepest = _deepest(rg.labels, a, b)
    w = np.zeros(len(a))
    r_in = float(c[rg.rim, 1].min())
    # (inside the deepest cells every edge weighs 0)
    for level in range(depth):
        base, sel = 10.0 * (depth - level), deepest == level
        sa, sb = rg.spine_level[a] == level, rg.spine_level[b] == level
        hang = np.flatnonzero(sel & (sa ^ sb))
        kid = np.where(sa, b, a)[hang]
        child = rg.labels[level + 1][kid]
        target = np.empty((len(hang), 2))
        if level == 0:
            seam_edge = np.abs(c[a, 0] - c[b, 0]) > 0.5 * span
            w[sel & sa & sb & ~seam_edge] = base
            w[sel & sa & sb & seam_edge] = base + 5.0
            target[:, 0] = rg.lines[1][child]
            target[:, 1] = r_in
        else:
            along = level % 2
            w[sel & sa & sb] = base
            target[:, along] = rg.lines[level + 1][child]
            target[:, 1 - along] = rg.lines[level][rg.labels[level][a[hang]]]
        off_spine = 2.0 * (rg.spine_level[kid] != level + 1)
        w[hang] = base + 1.0 + off_spine + np.sqrt(((mid[hang] - target) ** 2).sum(1)) / scale
        walls = np.flatnonzero(sel & ~sa & ~sb)
        w[walls] = base + 5.0 + 0.5
    w[is_con] = CON_WEIGHT
    return w


#: the ring prototype (session 13): 8 sectors, the seam at 0 degrees; ``ring_seam{a}``:
#: at ``a`` degrees; ``ring_s{s}_seam{a}``: ``s`` sectors
SCHEMES.update({
    "ring": ring_weights,
    **{f"ring_seam{a}": partial(ring_weights, seam=np.radians(a)) for a in range(0, 45, 5)},
    **{f"ring_s{s}_seam{a}": partial(ring_weights, sectors=s, seam=np.radians(a))
       for s in (2, 4, 16) for a in (0, 5, 15, 20, 30)},
})
