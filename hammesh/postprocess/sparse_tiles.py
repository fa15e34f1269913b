"""Sparse mode's compact cycle with the fishbone's cells as tiles (issue 14).

A sparse join inserts one cycle whole into another, so a cell that is joined to the
rest by joins sitting close together along its own cycle is (nearly) one run of the
final cycle (docs/partition.md, "Session 14"). Here, for
``hamiltonian(mesh, mode="sparse", tree="fishbone")`` with ``TILES`` on:

1. the deepest cells of the incircle fishbone (``sparse_cells.fishbone_cells(...,
   tiles=True)``: no bands, cells of about ``sparse_cells.CELL_TRIANGLES``) become
   *tiles*: every dual edge between two cells is cut (the half-edge twins there set
   to -1) and sparse mode itself (``sparse_cycles``: cover, fans, joins, placement,
   improvement, every rule of issue 13) runs on the result, so each connected piece
   of each cell gets its own cycle, made and judged as any sparse cycle; the cut
   edges are the pieces' boundary, so no Steiner point lands on them and the output
   is one conforming mesh of the whole domain;
2. the pieces' cycles are joined across the cut edges, one join per edge of a
   spanning tree of the pieces (as ``hammesh.parallel.joins`` joins its tiles'
   cycles, written again here for rows of one mesh): Kruskal in the fishbone's class
   order (the bit length of the two cells' numbers' xor: siblings first, then up
   the levels), each join a *swap* of the two triangles across the edge where the
   new angles keep the local rule (no Steiner point), else Thm 2.4's *bridge*
   between two triangles kept whole (Arkin, Held, Mitchell, Skiena, Thm 2.4, Fig. 9:
   both split at their incenters, the shared edge flipped between them: every new
   angle at least half one of theirs). Inside a class a join is placed near the
   first join of each of its cycles (``_sparse_tiles_kernels.plan_tile_joins_into``):
   the cell's joins sit close together along its cycle, so the arcs between them
   are short but one.

If the joins cannot make one cycle per connected piece (a piece of a cell without
a usable join), the caller's construction runs on the uncut mesh instead (the
report says ``tile_fallback``). The certificate checks the output as any other.

Measured at 300 000 triangles (docs/partition.md, "Session 14, second round") it cuts
plate 2.51 / 1.94 and gear 2.89 / 1.96 x METIS's at k = 8 / 64, against the confined
cover's (``sparse_cells``, round one) 3.23 / 2.17 and 2.48 / 2.18: about 10 % less at
k = 64, within the spread at k = 8, for 1.3-1.4x its Steiner points (0.58-0.82 %) and
1.5-1.6x its CPU. So it is off (``TILES``): a cell is nearly but not quite one run
(its joins' candidates lie far apart along its cycle), and even cells walked whole
cut 1.3-2.0 / 1.5-1.6 (the cells' own sparse cycles wind).
"""

from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

from hammesh.halfedge import half_edge_twins
from hammesh.postprocess import _sparse_tiles_kernels as _k
from hammesh.postprocess.sparse_cells import fishbone_cells

__all__ = ["tiled_cycles", "TILES", "MIN_PIECE", "ROUNDS", "tile_cells"]

#: ``tree="fishbone"`` in sparse mode builds the cells as tiles (this module); False
#: (the default: measured, it does not beat it): the cover confined to cells and
#: bands in one construction (``sparse_cells``).
TILES = False
#: Pieces of a cell with fewer triangles move to a neighbouring cell first (a cycle
#: of one or two triangles has no two links to join at).
MIN_PIECE = 16
#: Passes of each class in the joins' plan (``plan_tile_joins_into``).
ROUNDS = 3
#: Inside a class, the join between the two cells nearest in the fishbone's order
#: first (the cells' numbers: a cell's halves joined where they meet in that order).
ORDERED = False
#: Passes moving each join along its two cycles towards their other joins
#: (``tighten_joins_into``; 0: the plan's choice).
SWEEPS = 3
#: The local rule's margin, and the largest new angle's slack, as sparse mode's.
SWAP_MARGIN = 1e-6
MAX_ANGLE_SLACK_DEG = 5.0
_KIND_SECTOR, _KIND_FLIP, _KIND_WHOLE, _KIND_SWAP = 0, 1, 3, 4


def tile_cells(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray) -> np.ndarray:
    """The tile (deepest fishbone cell) of every triangle, pieces of fewer than
    ``MIN_PIECE`` triangles moved to a neighbouring cell ((m,) int64: the cells'
    numbers, whose bits are the fishbone's levels, the top level highest)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    cell = fishbone_cells(points, triangles, twin, tiles=True).cell.copy()
    m = len(triangles)
    h = np.flatnonzero(twin >= 0)
    a, b = h // 3, twin[h] // 3
    for _ in range(4):  # (a small piece joins a neighbour's cell; rarely twice)
        same = cell[a] == cell[b]
        g = coo_matrix((np.ones(int(same.sum()), np.int8), (a[same], b[same])), shape=(m, m))
        _, piece = connected_components(g, directed=False)
        size = np.bincount(piece)
        small = size[piece] < MIN_PIECE
        move = small[a] & ~same & ~small[b]
        if not move.any():
            break
        cell[a[move]] = cell[b[move]]  # (any neighbour's: the last write wins)
        # a piece's other triangles follow the one that moved
        moved = np.zeros(len(size), np.int64) - 1
        moved[piece[a[move]]] = cell[b[move]]
        follow = small & (moved[piece] >= 0)
        cell[follow] = moved[piece[follow]]
    return cell


def _angles(p: np.ndarray) -> np.ndarray:
    """The three angles (radians) of triangles ``p`` ((k, 3, 2) corners)."""
    e = [p[:, (i + 1) % 3] - p[:, i] for i in range(3)]
    out = np.empty((len(p), 3))
    for i in range(3):
        u, v = e[i], -e[(i + 2) % 3]
        out[:, i] = np.arctan2(np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]), (u * v).sum(axis=1))
    return out


def _area2(p: np.ndarray) -> np.ndarray:
    return (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])


def _incenters(p: np.ndarray) -> np.ndarray:
    la = np.linalg.norm(p[:, 1] - p[:, 2], axis=1)
    lb = np.linalg.norm(p[:, 2] - p[:, 0], axis=1)
    lc = np.linalg.norm(p[:, 0] - p[:, 1], axis=1)
    s = (la + lb + lc)[:, None]
    return (la[:, None] * p[:, 0] + lb[:, None] * p[:, 1] + lc[:, None] * p[:, 2]) / s


def tiled_cycles(build: Callable, points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, is_con: np.ndarray,
                 min_angle: float, *, keep: float, beside_cover=None, local: bool = False, tree: str = "fishbone"):
    """``sparse_cycles``' contract (a ``SparseResult``) with the cells as tiles (module
    docstring); ``build`` is ``sparse.sparse_cycles`` (run on the cut mesh, and on the
    whole one if the joins fail)."""
    t0, c0 = time.perf_counter(), time.process_time()
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    con = np.ascontiguousarray(is_con, dtype=np.bool_)
    n, m = len(pts), len(tri)
    if pts.shape[1] != 2 or m < 2:
        return build(pts, tri, tw, con, min_angle, keep=keep, beside_cover=beside_cover, local=local)
    cell = tile_cells(pts, tri, tw)
    h = np.arange(3 * m)
    cut = (tw >= 0) & (cell[h // 3] != cell[np.maximum(tw, 0) // 3])
    # each cell its own copies of its border vertices: the construction's own twins
    # (made again after its fans) then cannot cross a cut either
    tri_cut, dup_of = _cut_vertices(tri, cell, n)
    t_cells = time.perf_counter() - t0, time.process_time() - c0
    r = build(np.concatenate([pts, pts[dup_of]]), tri_cut, np.where(cut, -1, tw), con, min_angle, keep=keep,
              beside_cover=beside_cover, local=local)
    r = _glued(r, n, dup_of)
    t1, c1 = time.perf_counter(), time.process_time()
    joined = _join_tiles(r, pts, tri, con, cell, n, min_angle, keep)
    if joined is None:
        r2 = build(pts, tri, tw, con, min_angle, keep=keep, local=local)
        r2.counts["tile_fallback"] = 1
        return r2
    wall, cpu = dict(r.counts["step_seconds"]), dict(r.counts["step_cpu_seconds"])
    wall["tile_cells"], cpu["tile_cells"] = t_cells
    wall["tile_joins"], cpu["tile_joins"] = time.perf_counter() - t1, time.process_time() - c1
    joined.counts["step_seconds"], joined.counts["step_cpu_seconds"] = wall, cpu
    return joined


def _cut_vertices(tri: np.ndarray, cell: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``tri`` with a copy of every vertex for each further cell it is a corner in
    (numbered from ``n``), and the original of each copy."""
    key = tri * (int(cell.max()) + 1) + cell[:, None]
    pairs, back = np.unique(key.reshape(-1), return_inverse=True)
    v = pairs // (int(cell.max()) + 1)
    first = np.r_[True, v[1:] != v[:-1]]
    ids = np.where(first, v, n + np.cumsum(~first) - 1)
    return ids[back].reshape(tri.shape), v[~first]


def _glued(r, n: int, dup_of: np.ndarray):
    """The construction ``r`` on the cut mesh in the input's vertex numbers (the
    copies dropped from the points)."""
    from dataclasses import replace

    nd = len(dup_of)
    if not nd:
        return r

    def back(v):
        v = np.asarray(v, np.int64)
        return np.where(v < n, v, np.where(v < n + nd, dup_of[np.clip(v - n, 0, nd - 1)], v - nd))

    pts = np.concatenate([r.points[:n], r.points[n + nd:]])
    return replace(r, points=pts, triangles=back(r.triangles), mid_a=back(r.mid_a), mid_b=back(r.mid_b))


def _tightened(take, usable, pref, rt, ru, ct, cu, pt, pu, L, m1) -> np.ndarray:
    """The plan's joins, each moved to the candidate between the same two cycles that
    keeps both cycles' joins closest together (``tighten_joins_into``)."""
    cur = np.flatnonzero(take)
    c = len(L)
    key = lambda x: np.minimum(ct[x], cu[x]) * c + np.maximum(ct[x], cu[x])  # noqa: E731
    alt = usable[np.argsort(key(usable), kind="stable")]
    ka = key(alt)
    ke = key(cur)
    alt_ptr = np.r_[np.searchsorted(ka, ke, side="left"), 0]
    hi_ = np.searchsorted(ka, ke, side="right")
    # (edge e's alternatives are alt[alt_ptr[e]:hi_[e]]: laid out one range after another)
    alt_e = np.concatenate([alt[lo:hi] for lo, hi in zip(alt_ptr[:-1], hi_)]) if len(cur) else alt[:0]
    ptr = np.r_[0, np.cumsum(hi_ - alt_ptr[:-1])]
    ends = np.stack([ct[cur], cu[cur]], axis=1)
    inc_cyc = ends.reshape(-1)
    inc_order = np.argsort(inc_cyc, kind="stable")
    inc_edge = (inc_order // 2).astype(np.int64)
    inc_ptr = np.r_[0, np.cumsum(np.bincount(inc_cyc, minlength=c))]
    _k.tighten_joins_into(cur, ends, inc_ptr, inc_edge, ptr, alt_e, rt, ru, ct, cu, pt, pu, pref, L, m1, SWEEPS)
    out = np.zeros_like(take)
    out[cur] = True
    return out


def _join_tiles(r, pts_in, tri_in, con_in, cell, n, min_angle, keep):
    """The cut construction's cycles ``r`` joined across the cut edges (module
    docstring, step 2), or None where they do not make one cycle per piece."""
    from dataclasses import replace

    P, T = r.points, r.triangles
    m1 = len(T)
    full, bad = half_edge_twins(T, len(P))
    if bad >= 0:
        return None
    L = np.asarray(r.lengths, np.int64)
    cyc = np.repeat(np.arange(len(L)), L)
    start = np.cumsum(L) - L
    pos = np.arange(m1) - start[cyc]
    bh = np.flatnonzero((full >= 0) & (r.claim < 0))
    bh = bh[bh < full[bh]]
    rt, ru = bh // 3, full[bh] // 3
    k = bh % 3
    a, b, c = T[rt, k], T[rt, (k + 1) % 3], T[rt, (k + 2) % 3]
    kb = full[bh] % 3  # (u's half-edge b -> a)
    d = T[ru, (kb + 2) % 3]
    ok = (cyc[rt] != cyc[ru]) & (L[cyc[rt]] >= 3) & (L[cyc[ru]] >= 3)
    # constrained edges (segments, region borders): never flipped nor swapped
    ih = np.flatnonzero(con_in)
    ckeys = np.unique(np.minimum(tri_in[ih // 3, ih % 3], tri_in[ih // 3, (ih % 3 + 1) % 3]) * len(P)
                      + np.maximum(tri_in[ih // 3, ih % 3], tri_in[ih // 3, (ih % 3 + 1) % 3]))
    ok &= ~np.isin(np.minimum(a, b) * len(P) + np.maximum(a, b), ckeys)
    # swap: abc + bad -> adc + dbc, where the new angles keep the local rule
    old = np.minimum(_angles(P[T[rt]][:, :, :2]).min(axis=1), _angles(P[T[ru]][:, :, :2]).min(axis=1))
    amax_in = _angles(pts_in[tri_in]).max() if len(tri_in) else math.pi
    hi = amax_in + math.radians(MAX_ANGLE_SLACK_DEG)
    floor = 0.5 * min_angle * (1.0 + SWAP_MARGIN)
    X = P[np.stack([a, d, c], axis=1)][:, :, :2]
    Y = P[np.stack([d, b, c], axis=1)][:, :, :2]
    ax, ay = _angles(X), _angles(Y)
    new_min = np.minimum(ax.min(axis=1), ay.min(axis=1))
    new_max = np.maximum(ax.max(axis=1), ay.max(axis=1))
    swap = ok & (_area2(X) > 0) & (_area2(Y) > 0) & (new_min >= np.maximum(keep * old, floor)) & (new_max <= hi)
    bridge = ok & ~swap & (r.kind[rt] == _KIND_WHOLE) & (r.kind[ru] == _KIND_WHOLE)
    usable = np.flatnonzero(swap | bridge)
    cls = np.frexp((cell[r.parent[rt]] ^ cell[r.parent[ru]]).astype(np.float64))[1].astype(np.int64)  # (0: one cell)
    pref = np.where(swap, 0, 1).astype(np.int64)
    order = usable[np.lexsort((pref[usable], cls[usable]))]
    take = np.zeros(len(bh), np.bool_)
    ct, cu, pt, pu = cyc[rt], cyc[ru], pos[rt], pos[ru]
    wt, wu = cell[r.parent[rt]], cell[r.parent[ru]]
    far = np.abs(wt - wu) if ORDERED else np.zeros(len(bh), np.int64)
    _k.plan_tile_joins_into(order, cls, pref, far, rt, ru, ct, cu, pt, pu, L, m1, ROUNDS, take)
    if SWEEPS:
        take = _tightened(take, usable, pref, rt, ru, ct, cu, pt, pu, L, m1)
    sw, br = np.flatnonzero(take & swap), np.flatnonzero(take & ~swap)
    # the rows' links: r's rows cross the edges to their neighbours in the run
    link = np.zeros((m1, 3), np.bool_)
    prev = start[cyc] + (pos - 1) % L[cyc]
    nxt = start[cyc] + (pos + 1) % L[cyc]
    cl = r.claim.reshape(m1, 3)
    link[:] = (cl >= 0) & ((cl // 3 == prev[:, None]) | (cl // 3 == nxt[:, None]))
    # new points: the bridges' incenters, before the cut construction's midpoints
    # (``split_segments`` numbers those from n + fans + incenters)
    q = n + int(r.counts.get("fans", 0)) + int(r.counts["incenters"])
    nb = len(br)
    inc = np.concatenate([_incenters(P[T[rt[br]]][:, :, :2]), _incenters(P[T[ru[br]]][:, :, :2])])
    shift = lambda v: np.where(v >= q, v + 2 * nb, v)  # noqa: E731
    It, Iu = q + np.arange(nb), q + nb + np.arange(nb)
    As, Bs, Cs, Ds = shift(a), shift(b), shift(c), shift(d)
    rows = [shift(T)]
    parent = [r.parent]
    kind = [r.kind]
    links = [link]
    # swaps: adc (links ad, ca) and dbc (db, bc)
    x = sw
    rows += [np.stack([As[x], Ds[x], Cs[x]], 1), np.stack([Ds[x], Bs[x], Cs[x]], 1)]
    parent += [r.parent[rt[x]], r.parent[ru[x]]]
    kind += [np.full(len(x), _KIND_SWAP, np.int8)] * 2
    links += [np.tile([True, False, True], (len(x), 1)), np.tile([True, True, False], (len(x), 1))]
    # bridges: (I_t c a) (I_t a I_u) (I_u a d) [u's cycle] (I_u d b) (I_u b I_t) (I_t b c)
    x = br
    tri6 = [(It, Cs[x], As[x]), (It, As[x], Iu), (Iu, As[x], Ds[x]), (Iu, Ds[x], Bs[x]), (Iu, Bs[x], It), (It, Bs[x], Cs[x])]
    lk6 = [(False, True, True), (True, True, False), (True, True, False), (False, True, True), (True, True, False),
           (True, True, False)]
    side = [rt, rt, ru, ru, ru, rt]
    kinds6 = [_KIND_SECTOR, _KIND_FLIP, _KIND_SECTOR, _KIND_SECTOR, _KIND_FLIP, _KIND_SECTOR]
    for tv, lk, s_, kd in zip(tri6, lk6, side, kinds6):
        rows.append(np.stack(tv, 1))
        parent.append(r.parent[s_[x]])
        kind.append(np.full(len(x), kd, np.int8))
        links.append(np.tile(lk, (len(x), 1)))
    gone = np.zeros(m1, np.bool_)
    gone[rt[sw]] = gone[ru[sw]] = gone[rt[br]] = gone[ru[br]] = True
    keep_rows = np.concatenate([~gone, np.ones(sum(len(v) for v in rows[1:]), np.bool_)])
    F = np.concatenate(rows)[keep_rows]
    par = np.concatenate(parent)[keep_rows]
    knd = np.concatenate(kind)[keep_rows]
    lnk = np.concatenate(links)[keep_rows]
    pts = np.concatenate([P[:q], inc.astype(P.dtype) if P.shape[1] == 2 else np.c_[inc, np.zeros(len(inc))], P[q:]])
    tw2, bad = half_edge_twins(F, len(pts))
    if bad >= 0:
        return None
    order = np.empty(len(F), np.int64)
    lengths = np.empty(len(F), np.int64)
    runs = _k.walk_links_into(tw2, lnk, order, lengths)
    if runs < 0:
        return None
    # one run per connected piece of the domain, or the joins failed somewhere
    pieces = _pieces(tri_in)
    if runs != pieces:
        return None
    inv = np.empty(len(F), np.int64)
    inv[order] = np.arange(len(F))
    g = tw2.reshape(-1, 3)[order].reshape(-1)
    claim = np.where(g >= 0, 3 * inv[np.maximum(g, 0) // 3] + g % 3, -1)
    counts = dict(r.counts)
    counts["incenters"] = int(counts["incenters"]) + 2 * nb
    counts["tile_pieces"] = int(len(L))
    counts["tile_swaps"] = int(len(sw))
    counts["tile_bridges"] = int(nb)
    return replace(r, points=pts, triangles=F[order], lengths=lengths[:runs], parent=par[order], kind=knd[order],
                   claim=claim, mid_a=shift(r.mid_a), mid_b=shift(r.mid_b), counts=counts)


def _pieces(tri: np.ndarray) -> int:
    """Connected pieces of a mesh (across edges)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    tw, _ = half_edge_twins(tri, int(tri.max()) + 1)
    h = np.flatnonzero(tw >= 0)
    m = len(tri)
    g = coo_matrix((np.ones(len(h), np.int8), (h // 3, tw[h] // 3)), shape=(m, m))
    return int(connected_components(g, directed=False)[0])
