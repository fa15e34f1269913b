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

from hammesh import _threads
from hammesh._threads import row_ranges, run_all
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


def spanning_forest(tri, twin, is_con, points=None):
    """Spanning forest of the dual graph that crosses the fewest constrained edges.

    First a depth-first search over free (flippable) dual edges only: its trees span
    the *regions* (pieces of the dual cut along every constrained edge). Then the
    regions are joined by union-find over the constrained dual edges, each taken only
    if it joins two regions not yet joined: exactly ``regions - pieces`` crossings,
    the fewest possible (a crossing joins two regions).

    On a large mesh (``points`` given, ``hammesh._threads.THREAD_MIN_ROWS`` rows per core) the search
    runs in threads, one per *part*: the triangles split into slabs by the x of their
    first corner (at quantiles of a sample), each slab searched by its own thread as if
    the slab's border were constrained. The slabs' trees are joined first across free
    border edges (flips, as any tree edge), then across constrained edges: still the
    fewest crossings, since constrained edges come last.

    The triangles come back renumbered in the order the search took them off its
    stack (part by part): the Thm 2.4 walk follows the tree, so in this numbering its
    reads are nearly sequential (memory locality), and the half-edge data is packed
    into one array so that the walk reads one word per half-edge.

    Parameters
    ----------
    tri : (m, 3) int64
    twin : (3 m,) int64
    is_con : (3 m,) bool
    points : (n, 2) float64, optional
        Enables the threaded search (the slabs need coordinates).

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
    spans = row_ranges(m, _threads.THREAD_MIN_ROWS)
    k = len(spans) if points is not None else 1
    part = np.zeros(m, np.uint8)
    sizes = np.array([m], np.int64)
    if k > 1:
        sample = points[tri[:: max(1, m // 20_000), 0], 0]
        cuts = np.quantile(sample, np.arange(1, k) / k)
        counts = run_all([
            (lambda lo=lo, hi=hi: _assign_parts(points, tri, cuts, part, lo, hi)) for lo, hi in spans
        ])
        sizes = np.sum(counts, axis=0)
    k = len(sizes)
    base = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    region = np.full(m, -1, np.int64)
    order = np.empty(m, np.int64)
    rank = np.empty(m, np.int64)
    tri_r = np.empty_like(tri)
    code = np.empty(3 * m, np.int64)
    work = [
        tuple(np.empty(s, np.int64) for s in (sizes[p], sizes[p], 3 * sizes[p], 3 * sizes[p], sizes[p]))
        for p in range(k)
    ]  # per part: stack, via, border edges, constrained edges, region seeds
    found = run_all([
        (lambda p=p: _forest_part(tri, twin, is_con, part, p, k, base[p], region, order, rank, tri_r,
                                  code, *work[p]))
        for p in range(k)
    ])
    border = np.sort(np.concatenate([work[p][2][: found[p][0]] for p in range(k)]))
    con = np.sort(np.concatenate([work[p][3][: found[p][1]] for p in range(k)]))
    seeds = np.full(k * max(f[2] for f in found), -1, np.int64)  # region r: seeds[r]
    for p in range(k):
        seeds[p : k * found[p][2] : k] = work[p][4][: found[p][2]]
    firsts, split = _join_regions(twin, region, rank, code, border, con, seeds)
    run_all([
        (lambda lo=lo, hi=hi: _renumber_twins(code, rank, 3 * lo, 3 * hi)) for lo, hi in spans
    ])
    return Forest(tri_r, code, order, firsts, np.sort(split))


@njit(cache=True, nogil=True)
def _assign_parts(points, tri, cuts, part, lo, hi):
    """``part[t]``: the slab of t's first corner's x among ``cuts``; counts per slab."""
    counts = np.zeros(cuts.shape[0] + 1, np.int64)
    for t in range(lo, hi):
        x = points[tri[t, 0], 0]
        p = 0
        while p < cuts.shape[0] and x >= cuts[p]:
            p += 1
        part[t] = p
        counts[p] += 1
    return counts


@njit(cache=True, nogil=True)
def _forest_part(tri, twin, is_con, part, p, k, base, region, order, rank, tri_r, code,
                 stack, via, border, con, seeds):
    """Depth-first search of slab ``p`` over free edges inside it (one thread).

    Numbers its triangles ``base, base + 1, ...`` in the order they leave the stack;
    region ``j`` of the slab gets id ``p + k j`` and seed ``seeds[j]`` (its lowest
    triangle). Free edges to a higher slab go to ``border``, constrained interior
    edges (from their lower half-edge) to ``con``. Returns the three counts.
    """
    m = tri.shape[0]
    n_seen = base
    n_reg = 0
    n_border = 0
    n_con = 0
    for s in range(m):
        if part[s] != p or region[s] >= 0:
            continue
        rid = p + k * n_reg
        seeds[n_reg] = s
        n_reg += 1
        region[s] = rid
        stack[0] = s
        via[0] = -1
        top = 1
        while top > 0:
            top -= 1
            t = stack[top]
            entry = via[top]  # t's half-edge of the tree edge it was reached by
            i = n_seen
            n_seen += 1
            order[i] = t
            rank[t] = i
            for kk in range(3):
                h = 3 * t + kk
                tri_r[i, kk] = tri[t, kk]
                g = twin[h]
                bits = CON_BIT if is_con[h] else 0
                if h == entry:
                    bits |= TREE_BIT
                elif g >= 0:
                    u = g // 3
                    if is_con[h]:
                        if h < g:
                            con[n_con] = h
                            n_con += 1
                    elif part[u] != p:
                        if part[u] > p:
                            border[n_border] = h
                            n_border += 1
                    elif region[u] < 0:
                        region[u] = rid
                        bits |= TREE_BIT
                        stack[top] = u
                        via[top] = g
                        top += 1
                code[3 * i + kk] = ((g + 1) << 2) | bits  # twin still in input numbering
    return n_border, n_con, n_reg


@njit(cache=True)
def _join_regions(twin, region, rank, code, border, con, seeds):
    """Join the searched regions into one tree per piece: free border edges first,
    then constrained edges, each only if it joins two trees. Returns the first
    triangle (new numbering) of each piece, pieces ordered by lowest input triangle,
    and the constrained edges taken (both half-edges, new numbering)."""
    uf = np.arange(seeds.shape[0])
    split = np.empty(2 * con.shape[0], np.int64)
    n_split = 0
    for step in range(2):
        edges = border if step == 0 else con
        for e in range(edges.shape[0]):
            h = edges[e]
            g = twin[h]
            a = find_root(uf, region[h // 3])
            b = find_root(uf, region[g // 3])
            if a != b:
                uf[a] = b
                jh = 3 * rank[h // 3] + h % 3
                jg = 3 * rank[g // 3] + g % 3
                code[jh] |= TREE_BIT
                code[jg] |= TREE_BIT
                if step == 1:
                    split[n_split] = jh
                    split[n_split + 1] = jg
                    n_split += 2
    low = np.full(seeds.shape[0], -1, np.int64)  # per root: the piece's lowest triangle
    for r in range(seeds.shape[0]):
        if seeds[r] < 0:
            continue
        a = find_root(uf, r)
        if low[a] < 0 or seeds[r] < low[a]:
            low[a] = seeds[r]
    firsts = np.sort(low[low >= 0])
    for j in range(firsts.shape[0]):
        firsts[j] = rank[firsts[j]]
    return firsts, split[:n_split]


@njit(cache=True, nogil=True)
def _renumber_twins(code, rank, lo, hi):
    for j in range(lo, hi):
        g = (code[j] >> 2) - 1
        if g >= 0:
            code[j] = ((3 * rank[g // 3] + g % 3 + 1) << 2) | (code[j] & 3)


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

