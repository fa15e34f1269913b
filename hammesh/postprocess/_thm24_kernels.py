"""Theorem 2.4's construction kernels (numba): incenters, the dual spanning forest, the walk.

Arkin, Held, Mitchell, Skiena, Thm 2.4: incenters of the input triangles, one flip
per dual spanning-tree edge (a midpoint where the tree crosses a constrained edge),
and the walk around the tree that writes the Hamiltonian cycle
(``hammesh.postprocess.incircle`` drives them). Conventions as in
``hammesh.halfedge._kernels``: fill kernels behind thin numpy wrappers, problems
reported by return codes.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh import threads
from hammesh.threads import row_ranges, run_all
from hammesh.verify.stream import UNLINKED

__all__ = [
    "Forest",
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
CELL_BITS = 16
#: Distance classes per quadtree level: edges nearer a cell's centre are taken first.
CENTRE_BINS = 16


def spanning_forest(tri, twin, is_con, points=None):
    """A compact spanning forest of the dual graph that crosses the fewest constrained edges.

    Kruskal's algorithm over the dual edges, in the order of a quadtree of the
    triangles' centroids (``CELL_BITS`` levels; issue 14): an edge's *level* is the
    size of the smallest quadtree cell holding both its triangles, and edges are taken
    level by level, smallest first, and inside a level nearest the centre of that cell
    first (``CENTRE_BINS`` classes, a counting sort). So the triangles of every cell
    whose dual is connected form one subtree, and a cell's four children hang together
    at its centre: the Thm 2.4 walk around the tree then sweeps the domain cell by
    cell, as a space-filling curve does, and any stretch of the cycle covers a
    compact region (``hammesh.partition`` cuts the cycle into parts). The first idea,
    edges ordered by Hilbert key alone, links sibling cells anywhere along their
    shared side; the walk then goes out along one side of the chain of cells and
    back along the other, and a stretch of the cycle is a thin strip (cuts 6-16x
    METIS's instead of 1.5x).

    Constrained edges come after all free ones, each taken only if it joins two
    trees: the forest crosses exactly ``regions - pieces`` of them (a region is a
    piece of the dual cut along every constrained edge), the fewest possible.

    The triangles come back renumbered in the quadtree's Morton order (a counting
    sort): the union-find and the walk, which sweeps cell by cell, then read memory
    nearly in sequence; the half-edge data is packed into one array so that the walk
    reads one word per half-edge. Without ``points`` the input order is kept and
    the edges are taken in that order.

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
    qx = np.zeros(m, np.int64)
    qy = np.zeros(m, np.int64)
    if points is not None and m:
        lo = points.min(axis=0)
        span = float((points.max(axis=0) - lo).max())
        scale = ((1 << CELL_BITS) - 1) / span if span > 0 else 0.0
        run_all([
            (lambda a=a, b=b: _cell_coords_into(points, tri, lo[0], lo[1], scale, qx, qy, a, b)) for a, b in spans
        ])
    # everything below runs in the quadtree's (Morton) order of the triangles: the
    # union-find and the walk then read memory nearly in sequence
    rank = np.empty(m, np.int64)
    qr = np.empty(m, np.int64)  # coordinates in the new order, packed (x << 32 | y)
    order, key = _morton_order(qx, qy, MORTON_BITS, rank, qr)
    tri_r = np.empty_like(tri)
    code = np.empty(3 * m, np.int64)
    bucket = np.empty(3 * m, np.int16)
    run_all([
        (lambda a=a, b=b: _pack_code_into(tri, twin, is_con, order, rank, qr, tri_r, code, bucket, a, b))
        for a, b in spans
    ])
    levels = CELL_BITS + 1
    edges, group = _bucket_order(bucket, 2 * levels, CENTRE_BINS)
    uf = np.arange(m)
    kr = key[order]
    if len(spans) > 1:
        # below SPLIT_LEVEL an edge stays inside one cell of that level: the two halves
        # of the Morton order, cut between two such cells, are joined in two threads
        # (disjoint union-find entries); the coarse and the constrained edges after
        shift = 2 * (SPLIT_LEVEL - (CELL_BITS - MORTON_BITS))
        cut = int(np.searchsorted(kr >> shift, kr[m // 2] >> shift))
        at = [np.searchsorted(edges[group[v] : group[v + 1]], 3 * cut) + group[v] for v in range(SPLIT_LEVEL)]
        low = np.concatenate([edges[group[v] : at[v]] for v in range(SPLIT_LEVEL)])
        high = np.concatenate([edges[at[v] : group[v + 1]] for v in range(SPLIT_LEVEL)])
        run_all([(lambda e=e: _kruskal_into(code, e, bucket, kr, uf)) for e in (low, high)])
        edges = edges[group[SPLIT_LEVEL] :]
    _kruskal_into(code, edges, bucket, kr, uf)
    firsts = _piece_firsts(uf, order, rank)
    split = np.flatnonzero((code & 3) == 3).astype(np.int64)
    return Forest(tri_r, code, order, firsts, split)


#: Bits per axis of the Morton order the forest is built in (a counting sort).
MORTON_BITS = 10
#: Edges below this level are joined in two threads, one per half of the Morton order.
SPLIT_LEVEL = 13


@njit(cache=True, nogil=True)
def _morton_order(qx, qy, bits, rank, qr):
    """Triangles sorted by the Morton key of their top ``bits`` bits per axis (stable),
    and the key of each triangle; ``rank`` gets each triangle's place, ``qr`` its
    coordinates packed ``x << 32 | y`` at that place."""
    m = qx.shape[0]
    shift = CELL_BITS - bits
    n_keys = 1 << (2 * bits)
    key = np.empty(m, np.int64)
    start = np.zeros(n_keys + 1, np.int64)
    for t in range(m):
        x = qx[t] >> shift
        y = qy[t] >> shift
        k = 0
        for j in range(bits):
            k |= ((x >> j) & 1) << (2 * j) | ((y >> j) & 1) << (2 * j + 1)
        key[t] = k
        start[k + 1] += 1
    for k in range(n_keys):
        start[k + 1] += start[k]
    order = np.empty(m, np.int64)
    for t in range(m):
        k = key[t]
        order[start[k]] = t
        rank[t] = start[k]
        qr[start[k]] = (qx[t] << 32) | qy[t]
        start[k] += 1
    return order, key


@njit(cache=True, nogil=True)
def _pack_code_into(tri, twin, is_con, order, rank, qr, tri_r, code, bucket, lo, hi):
    """Rows ``tri_r`` and ``code`` of new triangles lo..hi (tree bit clear), and the
    Kruskal class of each dual edge from its lower half-edge (-1 on the others).

    Class: ``level * CENTRE_BINS + bin`` (level: bit length of the two triangles'
    differing coordinate bits; bin: L-infinity distance of the edge's midpoint from
    the centre of that level's cell, in ``CENTRE_BINS`` steps of its half side), plus
    ``(CELL_BITS + 1) * CENTRE_BINS`` for a constrained edge.
    """
    con_base = (CELL_BITS + 1) * CENTRE_BINS
    low = (1 << 32) - 1
    for i in range(lo, hi):
        t = order[i]
        ax = qr[i] >> 32
        ay = qr[i] & low
        for kk in range(3):
            h = 3 * t + kk
            j = 3 * i + kk
            tri_r[i, kk] = tri[t, kk]
            g = twin[h]
            con = is_con[h]
            if g < 0:
                code[j] = CON_BIT if con else 0
                bucket[j] = -1
                continue
            u = g // 3
            gj = 3 * rank[u] + g - 3 * u
            code[j] = ((gj + 1) << 2) | (CON_BIT if con else 0)
            if gj < j:
                bucket[j] = -1
                continue
            bx = qr[gj // 3] >> 32
            by = qr[gj // 3] & low
            diff = (ax ^ bx) | (ay ^ by)
            level = 0
            while diff > 0:
                level += 1
                diff >>= 1
            b = 0
            if level > 0:
                # twice the midpoint against twice the centre of the level's cell
                cx = ((ax >> level) << level) + (1 << (level - 1))
                cy = ((ay >> level) << level) + (1 << (level - 1))
                d = max(abs(ax + bx - 2 * cx), abs(ay + by - 2 * cy))  # <= 2 ** level
                b = min(CENTRE_BINS - 1, (d * CENTRE_BINS) >> level)
            c = level * CENTRE_BINS + b
            if con:
                c += con_base
            bucket[j] = c


@njit(cache=True, nogil=True)
def _cell_coords_into(points, tri, x0, y0, scale, qx, qy, lo, hi):
    """Quadtree coordinates (``CELL_BITS`` bits) of the centroids of triangles lo..hi."""
    top = (1 << CELL_BITS) - 1
    for t in range(lo, hi):
        x = (points[tri[t, 0], 0] + points[tri[t, 1], 0] + points[tri[t, 2], 0]) / 3.0
        y = (points[tri[t, 0], 1] + points[tri[t, 1], 1] + points[tri[t, 2], 1]) / 3.0
        ix = int((x - x0) * scale)
        iy = int((y - y0) * scale)
        qx[t] = min(max(ix, 0), top)
        qy[t] = min(max(iy, 0), top)


@njit(cache=True, nogil=True)
def _bucket_order(bucket, n_bins, per_bin):
    """The lower half-edges, sorted by ``bucket // per_bin`` (stable counting sort), and
    where each class starts among them (``n_bins + 1`` offsets)."""
    start = np.zeros(n_bins + 1, np.int64)
    for h in range(bucket.shape[0]):
        if bucket[h] >= 0:
            start[bucket[h] // per_bin + 1] += 1
    for b in range(n_bins):
        start[b + 1] += start[b]
    group = start.copy()
    out = np.empty(start[n_bins], np.int64)
    for h in range(bucket.shape[0]):
        if bucket[h] >= 0:
            b = bucket[h] // per_bin
            out[start[b]] = h
            start[b] += 1
    return out, group


@njit(cache=True, nogil=True)
def _cell_of(key, h, level):
    """The quadtree cell at ``level`` of half-edge h's triangle (from its Morton key)."""
    shift = 2 * (level - (CELL_BITS - MORTON_BITS))
    return key[h // 3] >> shift if shift > 0 else key[h // 3]


@njit(cache=True, nogil=True)
def _kruskal_into(code, edges, bucket, key, uf):
    """Kruskal over ``edges`` (grouped by level, Morton order inside a level): set the
    tree bit of (both halves of) each edge that joins two trees of ``uf``.

    A level's edges come cell by cell (a cell is a run of the Morton order), and
    inside a cell by their centre class (a counting sort of the run): the same tree
    as one global sort by class, since cells of one level share no triangle, but the
    union-find's reads stay in one cell's stretch of memory.
    """
    n = edges.shape[0]
    levels = CELL_BITS + 1
    run = np.empty(n, np.int64)
    count = np.zeros(CENTRE_BINS + 1, np.int64)
    e = 0
    while e < n:
        lev = bucket[edges[e]] // CENTRE_BINS
        level = lev % levels
        cell = _cell_of(key, edges[e], level)
        f = e + 1
        while f < n and bucket[edges[f]] // CENTRE_BINS == lev and _cell_of(key, edges[f], level) == cell:
            f += 1
        count[:] = 0
        for x in range(e, f):
            count[bucket[edges[x]] % CENTRE_BINS + 1] += 1
        for b in range(CENTRE_BINS):
            count[b + 1] += count[b]
        for x in range(e, f):
            b = bucket[edges[x]] % CENTRE_BINS
            run[count[b]] = edges[x]
            count[b] += 1
        for x in range(f - e):
            h = run[x]
            g = (code[h] >> 2) - 1
            ra = h // 3
            while uf[ra] != ra:  # path halving
                uf[ra] = uf[uf[ra]]
                ra = uf[ra]
            rb = g // 3
            while uf[rb] != rb:
                uf[rb] = uf[uf[rb]]
                rb = uf[rb]
            if ra != rb:
                if ra < rb:
                    uf[rb] = ra
                else:
                    uf[ra] = rb
                code[h] |= TREE_BIT
                code[g] |= TREE_BIT
        e = f


@njit(cache=True, nogil=True)
def _piece_firsts(uf, order, rank):
    """Per piece (tree of ``uf``), its lowest input triangle's new number, the pieces
    in that order."""
    m = uf.shape[0]
    low = np.full(m, m, np.int64)  # per root: lowest input triangle
    for i in range(m):
        r = find_root(uf, i)
        if order[i] < low[r]:
            low[r] = order[i]
    firsts = np.sort(low[low < m])
    for j in range(firsts.shape[0]):
        firsts[j] = rank[firsts[j]]
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
                    ih = np.searchsorted(mid_h, h)
                    ig = np.searchsorted(mid_h, g)
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

