"""Compiled loops (numba) of the sparse Hamiltonian construction (``sparse.py``).

The cover's loops are in ``_cover_kernels.py``. Nopython, ``cache=True``,
``nogil``; every kernel is O(m) over plain int64/float64/bool arrays and reports
problems by a return value, never by raising. The output's two big passes run on
both cores behind thin Python wrappers: the walk (:func:`walk_links`, its first
cycle from both ends) and the gather (:func:`rows_in_cycle_order`, one row range per
thread, into arrays from ``hammesh.pages``). Half-edge ``h = 3 t + k`` runs from ``tri[t, k]`` to
``tri[t, (k + 1) % 3]``; ``twin[h]`` is the opposite half-edge or -1.

Codes shared with ``sparse.py``:

* triangle status: ``PASS`` (kept whole, on a cover cycle), ``SPLIT`` (split at its
  incenter), ``SWAP`` (one of a pair whose shared edge was flipped without Steiner
  point), ``EDGE`` (one of a pair whose shared edge was split at its midpoint, each
  triangle into two, no incenter);
* slot (half-edge of a split triangle): ``PLAIN`` (its sector ``(I, a, b)``), ``FLIP``
  (bridge: the edge is flipped between two incenters), ``MID`` (bridge: the edge is
  split at its midpoint).
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh import threads
from hammesh.pages import fresh
from hammesh.prefetch import prefetch_row
from hammesh.threads import row_ranges, run_all

from hammesh.postprocess._join_kernels import (
    CORNER_BOUND_RTOL, half_smallest_corner, place_fan, quad_corners, swap_merge_outcome, new_walk_memo,
)
from hammesh.postprocess._thm24_kernels import find_root as _find
from hammesh.postprocess._thm24_kernels import lower_bound

PASS, SPLIT, SWAP, EDGE = 0, 1, 2, 3
PLAIN, FLIP, MID = 0, 1, 2


@njit(cache=True, nogil=True)
def _sides(twin, cyc, h):
    """``(g, ct, cu)``: the twin of half-edge h and the cycles of its two triangles (-1:
    uncovered); ``g`` -1 on the boundary (then the cycles are meaningless)."""
    g = twin[h]
    if g < 0:
        return g, -1, -1
    return g, cyc[h // 3], cyc[g // 3]


def join_candidates(twin, cyc) -> np.ndarray:
    """Half-edges across which a join can merge two nodes, ascending.

    ``h`` of a covered triangle t whose twin is in an uncovered triangle (an
    absorbing join) or in a covered triangle of another cycle (then only ``h < twin``,
    one per edge). One range of half-edges per core (:func:`_join_candidates_range`),
    joined in order.
    """
    parts = run_all([partial(_join_candidates_range, twin, cyc, lo, hi)
                     for lo, hi in row_ranges(twin.shape[0], threads.THREAD_MIN_ROWS)])
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


@njit(cache=True, nogil=True)
def _join_candidates_range(twin, cyc, lo, hi):
    """:func:`join_candidates` among the half-edges ``lo..hi``."""
    out = np.empty(hi - lo, np.int64)
    n = 0
    for h in range(lo, hi):
        g, ct, cu = _sides(twin, cyc, h)
        if g < 0 or ct < 0 or ct == cu or (cu >= 0 and g < h):
            continue
        out[n] = h
        n += 1
    return out[:n]


@njit(cache=True, nogil=True)
def _node(cyc, n_cyc, unc, t):
    """Union-find node of triangle t: its cover cycle, or ``n_cyc + i`` if it is the
    uncovered triangle ``unc[i]`` (``unc``: the uncovered triangles, ascending; a few,
    so the union-finds hold ``n_cyc + len(unc)`` nodes, not ``n_cyc + m``)."""
    return cyc[t] if cyc[t] >= 0 else n_cyc + lower_bound(unc, t)


@njit(cache=True, nogil=True)
def _free_pair(twin, used, h):
    """``(t, u, free)``: the triangles on both sides of half-edge h, ``free`` if neither is in a join yet."""
    t = h // 3
    u = twin[h] // 3
    return t, u, not (used[t] or used[u])


def open_candidates(twin, cyc, n_cyc, cand, meets):
    """Which candidate joins could still be taken after every join that meets the rule?

    ``cand`` in Kruskal's order, ``meets[i]`` its join meets the rule unplaced. The
    joins meeting it are taken as :func:`plan_merges` takes them (union-find over the
    nodes, one join per triangle); a candidate that does not meet it is *open* if its
    two triangles are still free and its nodes still apart. Only open candidates can
    gain from placing their split's Steiner point (``sparse.sparse_cycles`` places no
    other): Kruskal never reaches the rest.

    The joins meeting the rule are taken on one core (:func:`_take_meeting_into`), then
    the other candidates judged in one range per core (:func:`_open_rest_into`; at
    1.5 M the whole was ~12 ms of one core); the marks from ``hammesh.pages``."""
    m = cyc.shape[0]
    unc = np.flatnonzero(cyc < 0)
    uf, used = np.empty(n_cyc + len(unc), np.int64), fresh(m, np.bool_)
    _take_meeting_into(twin, cyc, n_cyc, unc, cand, meets, uf, used)
    out = np.zeros(cand.shape[0], np.bool_)
    run_all([partial(_open_rest_into, twin, cyc, n_cyc, unc, cand, meets, uf, used, out, lo, hi)
             for lo, hi in row_ranges(cand.shape[0], min(OPEN_MIN_ROWS, threads.THREAD_MIN_ROWS))])
    return out


#: candidates per thread from which :func:`open_candidates` judges them on two (a
#: random read or three each: ~0.1 ms per thousand; 122 k at 1.5 M)
OPEN_MIN_ROWS = 20_000


@njit(cache=True, nogil=True)
def _take_meeting_into(twin, cyc, n_cyc, unc, cand, meets, uf, used):
    """:func:`open_candidates`' first part: the joins meeting the rule taken
    (``used``, ``uf``), then every node's entry in ``uf`` set to its root (the second
    part reads roots only: its ranges side by side write nothing shared)."""
    m = cyc.shape[0]
    for x in range(uf.shape[0]):
        uf[x] = x
    for t in range(m):
        used[t] = False
    for i in range(cand.shape[0]):
        if not meets[i]:
            continue
        t, u, free = _free_pair(twin, used, cand[i])
        if not free:
            continue
        rt = _find(uf, cyc[t])
        ru = _find(uf, _node(cyc, n_cyc, unc, u))
        if rt == ru:
            continue
        uf[rt] = ru
        used[t] = True
        used[u] = True
    for x in range(uf.shape[0]):
        uf[x] = _find(uf, x)


@njit(cache=True, nogil=True)
def _open_rest_into(twin, cyc, n_cyc, unc, cand, meets, uf, used, out, lo, hi):
    """:func:`open_candidates`' second part over candidates ``lo..hi``, after
    :func:`_take_meeting_into` (``uf``: each node's root)."""
    for i in range(lo, hi):
        if meets[i]:
            continue
        t, u, free = _free_pair(twin, used, cand[i])
        if free:
            out[i] = uf[cyc[t]] != uf[_node(cyc, n_cyc, unc, u)]


class Plan(NamedTuple):
    """Result of :func:`plan_merges`."""

    status: np.ndarray  # (m,) int8
    slot: np.ndarray  # (3 m,) int8
    swap_he: np.ndarray  # (m,) int64
    join: np.ndarray  # (m,) int64
    counts: np.ndarray  # (4,) int64
    bad: np.ndarray  # (m,) bool


def plan_merges(tri, twin, is_con, cyc, n_cyc, cand, ckind, no_absorb, flip_bridges, joinable, room=0) -> Plan:
    """Join the cover cycles and the uncovered triangles into one cycle per piece
    (:func:`_plan_merges_into`; its big arrays from ``hammesh.pages``: a first call
    faults no pages for them where ``quality_mesh`` left a reserve). ``joinable``:
    :func:`join_candidates` of this cover (all of them; ``cand`` is the caller's choice
    of them, in its order). ``room``: rows of memory left after ``status``, ``slot``,
    ``swap_he`` and ``join`` (each the start of a buffer that much longer), for a
    caller that appends rows to the plan later. From ``PLAN_SIDE_MIN_ROWS`` rows (and
    two cores) the pieces (:func:`_pieces_into`) are found on the other core beside
    Kruskal's joins (:func:`_kruskal_joins_into`); the plan is the serial one."""
    m = tri.shape[0]
    status = fresh(m + room, np.int8)[:m]
    slot = fresh(3 * (m + room), np.int8)[: 3 * m]
    swap_he = fresh(m + room, np.int64)[:m]
    join = fresh(m + room, np.int64)[:m]
    unc = np.flatnonzero(cyc < 0)  # (the union-finds' nodes: cycles and these, ``_node``)
    uf = np.empty(n_cyc + len(unc), np.int64)
    pu = np.empty(n_cyc + len(unc), np.int64)
    cross = crossing_half_edges(twin, cyc, unc, joinable)
    # (the plan's arrays set to "nothing planned" one range per core: O(m), ~30 MB)
    run_all([partial(_plan_fill_range, cyc, status, slot, swap_he, join, lo, hi)
             for lo, hi in row_ranges(m, threads.THREAD_MIN_ROWS)])
    if m < PLAN_SIDE_MIN_ROWS or threads.cores() < 2:
        counts, bad = _plan_merges_into(
            tri, twin, is_con, cyc, n_cyc, unc, cand, ckind, no_absorb, flip_bridges, status, slot, swap_he, join,
            uf, pu, cross,
        )
        return Plan(status, slot, swap_he, join, counts, bad)
    # the pieces (the node graph's components over the crossing edges) need nothing of
    # Kruskal's joins: found on the other core meanwhile, with each crossing edge's two
    # nodes, which the bridges' stages then read in a row instead of looking them up
    ends = np.empty((len(cross), 2), np.int64)
    counts = run_all([
        partial(_kruskal_joins_into, twin, cyc, n_cyc, unc, cand, ckind, no_absorb, status, swap_he, join, uf),
        partial(_pieces_into, twin, cyc, n_cyc, unc, cross, pu, ends),
    ])[0]
    counts, bad = _bridges_into(tri, twin, is_con, cyc, n_cyc, unc, flip_bridges, status, slot, uf, pu, cross, ends,
                                counts)
    return Plan(status, slot, swap_he, join, counts, bad)


#: rows from which :func:`plan_merges` finds the pieces on another core beside
#: Kruskal's joins (below: one serial kernel, the thread hand-off not worth it)
PLAN_SIDE_MIN_ROWS = 200_000


def crossing_half_edges(twin, cyc, unc, joinable) -> np.ndarray:
    """One half-edge of each edge between two different nodes (cover cycles, uncovered
    triangles), in no order (:func:`plan_merges`), from ``joinable``
    (:func:`join_candidates` of ``cyc``: one side of each such edge with a covered
    triangle) and the edges between two of the uncovered triangles ``unc``
    (ascending), instead of a pass over every half-edge (at 1.5 M triangles ~45 ms
    CPU)."""
    hs = (3 * unc[:, None] + np.arange(3)).reshape(-1)
    g = twin[hs]
    between = g > hs  # (the lower half: each edge once)
    between[between] = cyc[g[between] // 3] < 0
    return np.concatenate([joinable, hs[between]])


@njit(cache=True, nogil=True)
def _plan_fill_range(cyc, status, slot, swap_he, join, lo, hi):
    """Rows ``lo..hi`` of the plan before any step (:func:`_plan_merges_into`): no join,
    plain slots, an uncovered triangle split (unless a join absorbs it)."""
    for h in range(3 * lo, 3 * hi):
        slot[h] = PLAIN
    for t in range(lo, hi):
        status[t] = SPLIT if cyc[t] < 0 else PASS
        swap_he[t] = -1
        join[t] = -1


def _plan_merges_into(tri, twin, is_con, cyc, n_cyc, unc, cand, ckind, no_absorb, flip_bridges, status, slot,
                      swap_he, join, uf, pu, cross):
    """Join the cover cycles and the uncovered triangles into one cycle per piece.

    Nodes are the cover cycles and the uncovered triangles; a dual edge between two
    nodes can join them (union-find, best first, Kruskal):

    A. the judged joins ``cand`` (half-edge of the covered triangle) in the caller's
       order (those meeting the local rule first, Steiner-free swaps before splits,
       larger slack first), ``ckind[i]`` a ``_join_kernels`` kind: swap (0 Steiner
       points) or split (1); a join with an uncovered triangle absorbs it into the
       cycle (unless ``no_absorb[u]``); a triangle takes part in one join at most;
    B. every uncovered triangle left is split at its incenter (1 point each);
    C. two split uncovered triangles: bridge across their edge (0 more points);
    D. split uncovered + cover triangle: split the cover one, bridge (1 point);
    E. two cover triangles: split both, bridge (2 points);
    F. constrained edges last: a midpoint bridge (1 point + the splits).

    A bridge over a free edge is a flip between the incenters (Thm 2.4) if
    ``flip_bridges``, else a midpoint (surfaces: keeps the geometry exactly).

    Fills ``status (m,) int8, slot (3m,) int8, swap_he (m,) int64, join (m,)
    int64``, handed in as :func:`_plan_fill_range` leaves them (and the union-finds
    ``uf``, ``pu``: ``(n_cyc + len(unc),)`` int64 scratch, any contents; ``unc`` the
    uncovered triangles ascending, :func:`_node`); ``cross``: one half-edge of each
    edge between two different nodes, in any order (:func:`crossing_half_edges`;
    overwritten); returns ``(counts, bad)``: ``join[t]`` the index in ``cand`` of t's
    swap or split, ``counts = [swaps_absorb, swaps_join, bridges, edge_splits]`` and
    ``bad`` flags the triangles of connected pieces left as more than one node (an
    absorbed triangle was some cycle's only way out): the caller retries without
    absorbing there.
    """
    # (three kernels called from here, not one kernel calling them: the ones
    # ``plan_merges`` calls on a big mesh, loaded by ``load_kernels``' small one)
    ends = np.empty((cross.shape[0], 2), np.int64)
    counts = _kruskal_joins_into(twin, cyc, n_cyc, unc, cand, ckind, no_absorb, status, swap_he, join, uf)
    _pieces_into(twin, cyc, n_cyc, unc, cross, pu, ends)
    return _bridges_into(tri, twin, is_con, cyc, n_cyc, unc, flip_bridges, status, slot, uf, pu, cross, ends, counts)


#: candidates ahead whose twin (``PLAN_AHEAD2``), then whose triangles' rows
#: (``PLAN_AHEAD1``) :func:`_kruskal_joins_into` asks for
PLAN_AHEAD1, PLAN_AHEAD2 = 8, 16


@njit(cache=True, nogil=True)
def _kruskal_joins_into(twin, cyc, n_cyc, unc, cand, ckind, no_absorb, status, swap_he, join, uf):
    """Stage A of :func:`_plan_merges_into`: the judged joins ``cand`` taken best first
    where they join two nodes of the union-find ``uf`` (reset here). Returns
    ``counts = [swaps_absorb, swaps_join, 0, edge_splits]``."""
    for x in range(uf.shape[0]):
        uf[x] = x
    n_abs = 0
    n_join = 0
    n_edge = 0
    n = cand.shape[0]
    for i in range(n):
        if i + PLAN_AHEAD2 < n:  # (the candidates are scattered: their rows asked for ahead)
            prefetch_row(twin, cand[i + PLAN_AHEAD2])
        if i + PLAN_AHEAD1 < n:
            a = cand[i + PLAN_AHEAD1]
            b = twin[a] // 3
            prefetch_row(swap_he, a // 3)
            prefetch_row(swap_he, b)
            prefetch_row(cyc, a // 3)
            prefetch_row(cyc, b)
        h = cand[i]
        g = twin[h]
        t = h // 3
        u = g // 3
        if swap_he[t] >= 0 or swap_he[u] >= 0 or (cyc[u] < 0 and no_absorb[u]):
            continue
        nu = _node(cyc, n_cyc, unc, u)
        rt = _find(uf, cyc[t])
        ru = _find(uf, nu)
        if rt == ru:
            continue
        uf[rt] = ru
        swap_he[t] = h
        swap_he[u] = g
        join[t] = i
        join[u] = i
        status[t] = SWAP if ckind[i] == 1 else EDGE
        status[u] = status[t]
        if ckind[i] == 1:
            if cyc[u] < 0:
                n_abs += 1
            else:
                n_join += 1
        else:
            n_edge += 1
    return np.array([n_abs, n_join, 0, n_edge], np.int64)


@njit(cache=True, nogil=True)
def _pieces_into(twin, cyc, n_cyc, unc, cross, pu, ends):
    """The pieces of :func:`_plan_merges_into`: the union-find ``pu`` (reset here) of
    the node graph over the crossing half-edges ``cross``, whatever their order, and
    ``ends[i]``: the nodes of ``cross[i]``'s two triangles. Reads only ``cross``, so it
    runs beside :func:`_kruskal_joins_into`."""
    for x in range(pu.shape[0]):
        pu[x] = x
    for i in range(cross.shape[0]):
        h = cross[i]
        nt = _node(cyc, n_cyc, unc, h // 3)
        nu = _node(cyc, n_cyc, unc, twin[h] // 3)
        ends[i, 0] = nt
        ends[i, 1] = nu
        a = _find(pu, nt)
        b = _find(pu, nu)
        if a != b:
            pu[a] = b


@njit(cache=True, nogil=True)
def _bridges_into(tri, twin, is_con, cyc, n_cyc, unc, flip_bridges, status, slot, uf, pu, cross, ends, counts):
    """Stages B-F of :func:`_plan_merges_into` after :func:`_kruskal_joins_into`
    (``uf``, ``counts``) and :func:`_pieces_into` (``pu``, ``ends``); ``cross`` is
    overwritten. Returns ``(counts, bad)``."""
    m = tri.shape[0]
    n_cross = cross.shape[0]
    n_merge = 0
    # pieces (``pu``: components of the node graph over the crossing edges, whatever
    # their order), and the crossing edges (one half each) whose nodes Kruskal left
    # apart: union-find sets only grow, so the stages below can join no others, and
    # they take these in ascending order, as a pass over all of them would (a stage's
    # pass over every crossing edge cost more than the plan's Kruskal). None left:
    # one node per piece already
    n_apart = 0
    for i in range(n_cross):
        if _find(uf, ends[i, 0]) != _find(uf, ends[i, 1]):
            h = cross[i]
            cross[n_apart] = min(h, twin[h])  # (the lower half; n_apart <= i: read already)
            n_apart += 1
    if n_apart == 0:
        return counts, np.zeros(m, np.bool_)
    cross[:n_apart].sort()
    for stage in range(4):  # (a triangle is split iff its status says so, from here on)
        for i in range(n_apart):
            h = cross[i]
            g = twin[h]
            con = is_con[h]
            if (stage == 3) != con:
                continue
            t = h // 3
            u = g // 3
            if status[t] >= SWAP or status[u] >= SWAP:
                continue
            st = status[t] == SPLIT and cyc[t] < 0
            su = status[u] == SPLIT and cyc[u] < 0
            if stage == 0 and not (st and su):
                continue
            if stage == 1 and not (st != su):
                continue
            if stage == 2 and (st or su):
                continue
            nt = _node(cyc, n_cyc, unc, t)
            nu = _node(cyc, n_cyc, unc, u)
            rt = _find(uf, nt)
            ru = _find(uf, nu)
            if rt == ru:
                continue
            uf[rt] = ru
            kind = MID if (con or not flip_bridges) else FLIP
            slot[h] = kind
            slot[g] = kind
            status[t] = SPLIT
            status[u] = SPLIT
            n_merge += 1
    # one node per piece?
    n_nodes = uf.shape[0]
    piece_node = np.full(n_nodes, -1, np.int64)
    piece_bad = np.zeros(n_nodes, np.bool_)
    ok = True
    for node in range(n_nodes):
        p = _find(pu, node)
        r = _find(uf, node)
        if piece_node[p] < 0:
            piece_node[p] = r
        elif piece_node[p] != r:
            ok = False
            piece_bad[p] = True
    bad = np.zeros(m, np.bool_)
    if not ok:  # absorbed triangles next to another node: they cut it off
        n_bad = 0
        for t in range(m):
            if cyc[t] >= 0 or status[t] < SWAP or not piece_bad[_find(pu, _node(cyc, n_cyc, unc, t))]:
                continue
            rt = _find(uf, _node(cyc, n_cyc, unc, t))
            for k in range(3):
                g = twin[3 * t + k]
                if g < 0:
                    continue
                u = g // 3
                nu = _node(cyc, n_cyc, unc, u)
                if _find(uf, nu) != rt:
                    bad[t] = True
                    n_bad += 1
                    break
        if n_bad == 0:  # should not happen: give up absorbing in those pieces
            for t in range(m):
                bad[t] = piece_bad[_find(pu, _node(cyc, n_cyc, unc, t))]
    counts[2] = n_merge
    return counts, bad


@njit(cache=True, nogil=True)
def _row(out, link, parent, partner, kind, pos, x, y, z, bits, par, prt, kd):
    """Write output row ``pos``: corners, link bits, parent, partner, kind."""
    out[pos, 0] = x
    out[pos, 1] = y
    out[pos, 2] = z
    link[pos] = bits
    parent[pos] = par
    partner[pos] = prt
    kind[pos] = kd


@njit(cache=True, nogil=True)
def _swap_links(cov_1, cov_2, bit_1, bit_2, bit_diag):
    """Link bits of a swapped row: its two outer edges where they are cover edges, the
    diagonal where fewer than two are (the cycle crosses to the row's partner)."""
    bits = 0
    if cov_1:
        bits |= bit_1
    if cov_2:
        bits |= bit_2
    if not (cov_1 and cov_2):
        bits |= bit_diag
    return bits


@njit(cache=True)
def emit(tri, twin, is_cov, status, slot, swap_he, split_rows, n_points, changed):
    """The new output triangles, with the two edges the cycle crosses in each.

    Only triangles a join changes get rows here: a triangle kept whole (status
    ``PASS``) is its input row, with the links of its cover edges, and is read from
    the input where needed (*virtual row* ``t``; the new rows are virtual rows
    ``m + i``, see :func:`walk_links`): at 1.5 M triangles ~99 % of the rows are
    never copied before the final gather.

    ``changed``: the triangles whose status is not ``PASS``, ascending (the passes go
    over these, ~2 % of the rows, not all m). ``split_rows``: the split triangles
    (status ``SPLIT``), ascending; the incenter of
    ``split_rows[i]`` is vertex ``n_points + i`` (counted along the rows; a bridge's
    other end found by binary search: where a numbering of every row was a cumulative
    sum over all of them); midpoints follow, in order of first emission.
    Each output row gets ``link``: bit j set if the cycle crosses its edge j (from
    vertex j to j + 1). Row kinds: 0 incenter sector, 1 flip (bridge), 2 midpoint
    (bridge, or an edge split without incenters), 3 input triangle kept whole, 4
    swapped pair (flip without Steiner point). ``partner`` is the other triangle a
    join replaced (the twin across the swapped, split or bridged edge; -1 for kept
    triangles and plain sectors): with ``parent`` the row's parents. ``mid_t[j]`` is
    the triangle t whose split made midpoint j (-1 for a bridge's midpoint): the
    caller places those Steiner points.

    Returns ``(out, link, parent, partner, kind, mid_a, mid_b, mid_t)`` of the new rows.
    """
    m = tri.shape[0]
    n_split = 0
    n_midh = 0
    n_edge = 0  # two rows each
    n_pass = m - changed.shape[0]
    for t in changed:  # (one pass: a bridge's midpoint slots are a split triangle's)
        st = status[t]
        if st == EDGE:
            n_edge += 1
        elif st == SPLIT:
            n_split += 1
            for h in range(3 * t, 3 * t + 3):
                if slot[h] == MID:
                    n_midh += 1
    total = m - n_pass + 2 * n_split + n_midh + n_edge
    # the bridges' midpoint slots, ascending, and each one's midpoint (its pair's: the
    # first of the two emitted makes it); a few, found by binary search (a per-half-edge
    # map was 24 B per input triangle, filled, ~9k page faults at 1.5 M)
    mid_hs = np.empty(n_midh, np.int64)
    mid_of = np.full(n_midh, -1, np.int64)
    if n_midh:
        i = 0
        for t in split_rows:
            for h in range(3 * t, 3 * t + 3):
                if slot[h] == MID:
                    mid_hs[i] = h
                    i += 1
    n_midh += n_edge  # one midpoint per pair
    out = np.empty((total, 3), np.int64)
    link = np.zeros(total, np.uint8)
    parent = np.empty(total, np.int64)
    partner = np.full(total, -1, np.int64)
    kind = np.empty(total, np.int8)
    mid_a = np.empty(n_midh // 2, np.int64)
    mid_b = np.empty(n_midh // 2, np.int64)
    mid_t = np.full(n_midh // 2, -1, np.int64)
    n_mid = 0
    n_all = n_points + n_split
    pos = 0
    n_inc = 0
    for t in changed:
        st = status[t]
        if st == SWAP or st == EDGE:
            h = swap_he[t]
            g = twin[h]
            if g < h:
                continue  # emitted with its partner
            _, u, a, b, c, d = quad_corners(tri, twin, h)
            k = h - 3 * t
            kg = g - 3 * u
        if st == SWAP:
            # (a, d, c): edges ad (u's), dc (diagonal), ca (t's)
            bits = _swap_links(is_cov[3 * u + (kg + 1) % 3], is_cov[3 * t + (k + 2) % 3], 1, 4, 2)
            _row(out, link, parent, partner, kind, pos, a, d, c, bits, t, u, 4)
            # (d, b, c): edges db (u's), bc (t's), cd (diagonal)
            bits = _swap_links(is_cov[3 * u + (kg + 2) % 3], is_cov[3 * t + (k + 1) % 3], 1, 2, 4)
            _row(out, link, parent, partner, kind, pos + 1, d, b, c, bits, u, t, 4)
            pos += 2
        elif st == EDGE:
            mv = n_all + n_mid
            mid_a[n_mid] = a
            mid_b[n_mid] = b
            mid_t[n_mid] = t
            n_mid += 1
            # t1 (a, M, c), t2 (M, b, c), u1 (b, M, d), u2 (M, a, d); cross links
            # t1-u2 (aM) and t2-u1 (Mb) are edge 0 of all four; outer edges where
            # covered, else the sibling (t1-t2, u1-u2)
            ct = is_cov[3 * t + (k + 2) % 3]
            _row(out, link, parent, partner, kind, pos, a, mv, c, 1 | (4 if ct else 2), t, u, 2)
            ct = is_cov[3 * t + (k + 1) % 3]
            _row(out, link, parent, partner, kind, pos + 1, mv, b, c, 1 | (2 if ct else 4), t, u, 2)
            cu = is_cov[3 * u + (kg + 2) % 3]
            _row(out, link, parent, partner, kind, pos + 2, b, mv, d, 1 | (4 if cu else 2), u, t, 2)
            cu = is_cov[3 * u + (kg + 1) % 3]
            _row(out, link, parent, partner, kind, pos + 3, mv, a, d, 1 | (2 if cu else 4), u, t, 2)
            pos += 4
        else:
            inc = n_points + n_inc  # (t ascending: the split rows before t, counted)
            n_inc += 1
            for k in range(3):
                h = 3 * t + k
                a = tri[t, k]
                b = tri[t, (k + 1) % 3]
                hp = 3 * t + (k + 2) % 3
                hn = 3 * t + (k + 1) % 3
                ring_prev = not (is_cov[hp] and is_cov[h])
                ring_next = not (is_cov[h] and is_cov[hn])
                s = slot[h]
                if s == PLAIN:
                    bits = (1 if ring_prev else 0) | (2 if is_cov[h] else 0) | (4 if ring_next else 0)
                    _row(out, link, parent, partner, kind, pos, inc, a, b, bits, t, -1, 0)
                    pos += 1
                elif s == FLIP:
                    u = twin[h] // 3
                    _row(out, link, parent, partner, kind, pos, inc, a, n_points + lower_bound(split_rows, u), 3, t, u,
                         1)
                    pos += 1
                else:
                    g = twin[h]
                    ih = lower_bound(mid_hs, h)
                    if mid_of[ih] < 0:
                        mid_of[ih] = n_all + n_mid
                        mid_of[lower_bound(mid_hs, g)] = n_all + n_mid
                        mid_a[n_mid] = a
                        mid_b[n_mid] = b
                        n_mid += 1
                    mv = mid_of[ih]
                    _row(out, link, parent, partner, kind, pos, inc, a, mv, 3, t, g // 3, 2)
                    _row(out, link, parent, partner, kind, pos + 1, inc, mv, b, 6, t, g // 3, 2)
                    pos += 2
    return out[:pos], link[:pos], parent[:pos], partner[:pos], kind[:pos], mid_a[:n_mid], mid_b[:n_mid], mid_t[:n_mid]


def new_row_twins(out, tri, twin_in, status, n_points, changed):
    """Half-edge twins where the output differs from the input.

    Virtual rows (see :func:`emit`): ``t < m`` is input triangle t kept whole (its
    half-edges are the input's ``3 t + j``), ``m + i`` is new row ``out[i]``. A kept
    triangle's twin is the input's where the other side is kept too. Matched here by
    their end points (sorted keys), over the non-kept triangles only: the new rows'
    half-edges and the kept half-edges facing a non-kept triangle (~1 % of a Triangle
    mesh). Returns ``(tw_new, changed, face_tw, bad)``: ``tw_new[3 i + j]`` the virtual
    twin of new row i's edge j (-1 on the boundary); ``changed`` the non-kept input
    triangles, ascending, and ``face_tw[3 r + k]`` the virtual twin of the kept
    half-edge facing half-edge k of ``changed[r]`` (:func:`_faced` reads them);
    ``bad`` -1 or a virtual half-edge whose edge is used twice in one direction or by
    three rows. What ``hammesh.halfedge.half_edge_twins`` gives on the whole output,
    at a fraction of the passes. ``changed``: the triangles whose status is not
    ``PASS``, ascending (the caller's, returned as it is).

    The keys are sorted with their index packed below them (a plain sort of distinct
    int64s: the stable argsort it replaced, 0.018 s at 1.5 M, was most of this), or
    argsorted (stable) where key and index need more than 62 bits; by numpy between
    the two compiled halves (:func:`_row_twin_keys`, :func:`_match_row_twins`):
    numpy's sort of the ~200 k keys at 1.5 M triangles (vectorised, AVX-512 / AVX2)
    took 1-2 ms where the compiled ``ndarray.sort`` took 15-30 ms. Distinct values
    sort one way only, so the matching is the same.
    """
    face_tw, tw_new, rest, keys, packed, ib, facing = _row_twin_keys_split(out, tri, twin_in, status, n_points,
                                                                           changed)
    if ib >= 0:
        packed.sort()  # (in place: the index is the low bits)
        srt = packed & ((np.int64(1) << ib) - 1)
        by_key = packed >> ib  # (the keys in sorted order: the matching reads them in a row)
    else:
        srt = np.argsort(keys, kind="stable")
        by_key = keys[srt]
    bad = _match_row_twins(face_tw, tw_new, rest, by_key, srt, facing)
    return tw_new, changed, face_tw, bad


#: changed triangles from which :func:`_row_twin_keys_split` reads the kept half-edges
#: facing them in two parts side by side (a random read each: ~5 ms of one core at 1.5 M)
TWIN_KEYS_TWO_MIN = 20_000


def _row_twin_keys_split(out, tri, twin_in, status, n_points, changed):
    """:func:`_row_twin_keys` (the same arrays), the changed triangles' half in two parts
    side by side from ``TWIN_KEYS_TWO_MIN`` of them on (where :func:`threads.cores`
    allows): each writes its entries after the new rows' (the second from a place its
    part cannot reach), the second's then moved down to follow the first's."""
    k, n_ch = out.shape[0], changed.shape[0]
    if n_ch < TWIN_KEYS_TWO_MIN or threads.cores() < 2:
        return _row_twin_keys(out, tri, twin_in, status, n_points, changed)
    face_tw = np.full(3 * n_ch, -1, np.int64)
    tw_new = np.empty(3 * k, np.int64)
    rest, keys, facing = (np.empty(3 * k + 3 * n_ch, np.int64) for _ in range(3))
    half = n_ch // 2
    first = partial(_twin_keys_into, out, tri, twin_in, status, n_points, changed, 0, half, 0, rest, keys, facing)
    second = partial(_twin_keys_into, out, tri, twin_in, status, n_points, changed, half, n_ch, 3 * k + 3 * half,
                     rest, keys, facing)
    n1, n2 = run_all([first, second])
    for a in (rest, keys, facing):  # (overlapping ranges: numpy copies through a buffer)
        a[n1:n1 + n2] = a[3 * k + 3 * half: 3 * k + 3 * half + n2]
    n = n1 + n2
    rest, keys, facing = rest[:n], keys[:n], facing[:n]
    packed, ib = _packed_keys(keys, n_points)
    return face_tw, tw_new, rest, keys, packed, ib, facing


@njit(cache=True, nogil=True)
def _twin_keys_into(out, tri, twin_in, status, n_points, changed, r_lo, r_hi, at, rest, keys, facing):
    """:func:`_row_twin_keys`' entries of the changed triangles ``r_lo..r_hi`` from place
    ``at`` on (``r_lo`` 0: first the new rows', from place 0); returns the place after
    the last written."""
    m = tri.shape[0]
    k = out.shape[0]
    n = at
    if r_lo == 0:
        for i in range(k):
            for j in range(3):
                a = out[i, j]
                b = out[i, (j + 1) % 3]
                rest[n] = 3 * (m + i) + j
                keys[n] = min(a, b) * np.int64(n_points) + max(a, b)
                facing[n] = 3 * i + j if a < b else ~(3 * i + j)
                n += 1
    for r in range(r_lo, r_hi):
        u = changed[r]
        for j in range(3):
            g = twin_in[3 * u + j]
            if g >= 0 and status[g // 3] == PASS:
                x = g // 3
                a = tri[x, g - 3 * x]
                b = tri[x, (g - 3 * x + 1) % 3]
                rest[n] = g
                keys[n] = min(a, b) * np.int64(n_points) + max(a, b)
                facing[n] = 3 * (k + r) + j if a < b else ~(3 * (k + r) + j)
                n += 1
    return n - at if r_lo > 0 else n


@njit(cache=True, nogil=True)
def _packed_keys(keys, n_points):
    """:func:`_row_twin_keys`' packing: ``(packed, ib)``, or an empty array and -1."""
    n = keys.shape[0]
    ib = 1
    while (1 << ib) < n:
        ib += 1
    if n_points > 0 and (np.int64(n_points) * np.int64(n_points)) < (np.int64(1) << (62 - ib)):
        packed = np.empty(n, np.int64)
        for i in range(n):
            packed[i] = (keys[i] << ib) | i
        return packed, ib
    return np.empty(0, np.int64), -1


@njit(cache=True, nogil=True)
def _row_twin_keys(out, tri, twin_in, status, n_points, changed):
    """:func:`new_row_twins`' first half: ``(face_tw, tw_new, rest, keys, packed, ib,
    facing)``; ``rest`` the virtual half-edges to match, ``keys`` their undirected
    edge keys, ``packed`` the keys shifted by ``ib`` bits with their index below (``ib``
    -1 and ``packed`` empty where that needs more than 62 bits); ``facing[i]`` where
    ``rest[i]``'s twin is written: ``s`` = new row ``i'``'s edge ``j`` at ``3 i' + j`` of
    ``tw_new``, a kept half-edge facing half-edge ``j`` of ``changed[r]`` at ``3 k + 3 r +
    j`` (``face_tw[3 r + j]``: known here, not searched for in ``changed`` by the
    matching), ``~s`` where the edge runs from its larger end point (two that run the
    same way: an edge used twice in one direction)."""
    k = out.shape[0]
    n_ch = changed.shape[0]
    face_tw = np.full(3 * n_ch, -1, np.int64)
    tw_new = np.empty(3 * k, np.int64)
    rest = np.empty(3 * k + 3 * n_ch, np.int64)  # virtual half-edges to match
    keys = np.empty(3 * k + 3 * n_ch, np.int64)
    facing = np.empty(3 * k + 3 * n_ch, np.int64)
    n = _twin_keys_into(out, tri, twin_in, status, n_points, changed, 0, n_ch, 0, rest, keys, facing)
    rest = rest[:n]
    keys = keys[:n]
    facing = facing[:n]
    packed, ib = _packed_keys(keys, n_points)
    return face_tw, tw_new, rest, keys, packed, ib, facing


@njit(cache=True, nogil=True)
def _match_row_twins(face_tw, tw_new, rest, by_key, srt, facing):
    """:func:`new_row_twins`' second half: the half-edges ``rest`` in the order ``srt`` of
    their keys (``by_key``: the keys in that order, read in a row rather than through
    ``srt``), paired where two share a key (``tw_new``, ``face_tw`` filled at the places
    ``facing`` names, :func:`_row_twin_keys`); returns -1 or a virtual half-edge whose
    edge is used twice in one direction or by three rows."""
    k3 = tw_new.shape[0]
    n = rest.shape[0]
    i = 0
    while i < n:
        e = i + 1
        while e < n and by_key[e] == by_key[i]:
            e += 1
        if e - i == 1:
            s = facing[srt[i]]
            s = s if s >= 0 else ~s
            if s < k3:
                tw_new[s] = -1
        elif e - i == 2:
            h = rest[srt[i]]
            g = rest[srt[i + 1]]
            sh = facing[srt[i]]
            sg = facing[srt[i + 1]]
            if (sh >= 0) == (sg >= 0):
                return max(h, g)  # one edge twice in one direction
            for s, y in ((sh, g), (sg, h)):
                s = s if s >= 0 else ~s
                if s < k3:
                    tw_new[s] = y
                else:  # a kept half-edge: filed under the input half-edge it faces
                    face_tw[s - k3] = y
        else:
            return rest[srt[i + 2]]
        i = e
    return -1


@njit(cache=True, nogil=True)
def _faced(g, changed, face_tw):
    """Twin of the kept half-edge facing input half-edge ``g`` of a changed triangle."""
    return face_tw[3 * lower_bound(changed, g // 3) + g % 3]


class Walk(NamedTuple):
    """Result of :func:`walk_links`."""

    order: np.ndarray  # (k,) int64 virtual rows in cycle order
    lengths: np.ndarray  # (c,) int64 cycle lengths
    low: np.ndarray  # (c,) int64 each cycle's lowest parent (input triangle)
    bad: int  # -1, or the first virtual row found badly linked


#: rows below which :func:`walk_links` walks its first cycle from one end only
WALK_TWO_ENDS_MIN_ROWS = 400_000


def walk_links(status, is_cov, link_new, parent_new, twin_in, tw_new, changed, face_tw, ends=None) -> Walk:
    """Follow the links into cycles over the virtual rows, checking each row as the walk reaches it.

    Virtual rows as in :func:`new_row_twins` (kept input triangles, then the new
    rows). Returns a :class:`Walk`: virtual rows in cycle order, the cycle lengths,
    each cycle's lowest parent (input triangle) and ``bad`` = -1 or the first virtual
    row found whose links are not two, or that crosses an edge whose other side does
    not link back. Every row is reached exactly once (the outer loop starts a walk at
    each row not seen yet), so every row is checked, in the same pass that orders
    them.

    First every row's two links are looked up, one row range per core
    (:func:`_link_ends_into`, into ``ends``: ``(2 n_v,)`` int64 scratch, any contents,
    e.g. from ``hammesh.pages``; made here if None): that pass reads the input's twins,
    cover marks and statuses with no row waiting on another, so the walk itself then
    reads one pair of entries per row (a pointer chase through ~8 arrays was ~75 ns
    a row at 1.5 M rows, the table's ~4x less).

    From ``WALK_TWO_ENDS_MIN_ROWS`` rows (and two cores) the first cycle, usually
    all of the mesh, is walked from both ends at once: this thread forward from its
    first row, a second one backward, each stopping where the other has been
    (:func:`_walk_one_into`); the backward part, reversed, then follows the forward
    one (rows both reached, near the meeting place, counted once), which is the
    order one walk gives. Both walks check every row they reach. If either finds a
    bad row, the one-thread walk runs again to name the same row as always.
    """
    m = status.shape[0]
    n_v = m + link_new.shape[0]
    n_rows = link_new.shape[0] + int(np.count_nonzero(status == PASS))
    if ends is None:
        ends = fresh(2 * n_v, np.int64)
    run_all([
        partial(_link_ends_into, status, is_cov, link_new, twin_in, tw_new, changed, face_tw, lo, hi, ends)
        for lo, hi in row_ranges(n_v, threads.THREAD_MIN_ROWS)
    ])
    s0 = _first_start(status, n_v)
    if n_rows < WALK_TWO_ENDS_MIN_ROWS or threads.cores() < 2 or s0 < 0:
        return Walk(*_walk_all(ends, parent_new, m, status, n_rows))
    fwd = np.zeros(n_v, np.bool_)
    bwd = np.zeros(n_v, np.bool_)
    order = fresh(n_rows, np.int64)
    back = np.empty(n_rows, np.int64)
    args = (ends, parent_new, m, s0)
    # (this thread forward, one of the process's pool backward: no thread started)
    (n_f, lo_f, bad_f), (n_b, lo_b, bad_b) = run_all([
        partial(_walk_one_into, *args, True, fwd, bwd, order), partial(_walk_one_into, *args, False, bwd, fwd, back),
    ])
    if bad_f >= 0 or bad_b >= 0:
        return Walk(*_walk_all(ends, parent_new, m, status, n_rows))
    return Walk(*_walk_rest(ends, parent_new, m, status, order, n_f, min(lo_f, lo_b), back, n_b, fwd, bwd))


@njit(cache=True, nogil=True)
def swap_outcome_of(twin, is_cov, cyc, root, buf, starts, c, ca, cb, budget, wide, pos, plen, m_table, m_steps,
                    m_state):
    """``_join_kernels.swap_merge_outcome`` of the alternating cycle ``c`` of ``buf`` /
    ``starts`` (``alternating_cycles_into``'s output), its group the cycle's triangles,
    sorted, as the caller's ``np.unique`` makes it. Reads only, bar the calling
    thread's own walk memo (``m_*``, a ``_join_kernels.WalkMemo``): two threads test
    one task's cycles at once (``sparse._SwapTests``).
    """
    fl = buf[starts[c]:starts[c + 1]]
    tris = np.empty(2 * fl.shape[0], np.int64)
    for i in range(fl.shape[0]):
        tris[2 * i] = fl[i] // 3
        tris[2 * i + 1] = twin[fl[i]] // 3
    return swap_merge_outcome(twin, is_cov, cyc, root, fl, np.unique(tris), ca, cb, budget, wide, pos, plen, m_table,
                              m_steps, m_state)


def load_output_kernels() -> None:
    """Load (or compile) the kernels only big outputs reach: the walk from both ends and
    the gather of several runs (and the fans' kinds, the parents mapped back), on a fan of four new rows (two runs of it, one
    walked from both ends): ``hammesh.postprocess.load_kernels`` warms them on its
    small mesh, where those paths do not run."""
    k = 4
    r = np.arange(k)
    tw = np.stack([np.full(k, -1), 3 * ((r + 1) % k) + 2, 3 * ((r - 1) % k) + 1], axis=1).reshape(-1)
    status = np.zeros(0, np.int8)
    none = np.zeros(0, np.int64)
    link = np.full(k, 6, np.uint8)  # (each row crosses its two edges to the centre)
    marks = (np.zeros(k, np.bool_), np.zeros(k, np.bool_))
    ends = np.empty(2 * k, np.int64)
    _link_ends_into(status, np.zeros(0, np.bool_), link, none, tw, none, none, 0, k, ends)
    args = (ends, r.copy(), 0, 0)
    order, back = np.empty(k, np.int64), np.empty(k, np.int64)
    n_b, lo_b, _ = _walk_one_into(*args, False, marks[1], marks[0], back)
    n_f, lo_f, _ = _walk_one_into(*args, True, marks[0], marks[1], order)
    walk = _walk_rest(ends, r.copy(), 0, status, order, n_f, min(lo_f, lo_b), back, n_b, marks[0], marks[1])
    rows, lengths = np.empty(k, np.int64), np.empty(2, np.int64)
    _runs_in_order_into(walk[0], np.array([2, 2]), np.array([1, 0]), rows, lengths)
    # the cover swaps' tests on two threads (``sparse._alternating_merges``), on two
    # triangles whose third edges are joined
    twin = np.array([3, 4, 5, 0, 1, 2], np.int64)
    swap_outcome_of(twin, np.array([True, True, False, True, True, False]), np.zeros(2, np.int64),
                    np.zeros(1, np.int64), np.array([2, 5], np.int64), np.array([0, 2], np.int64), 0, 0, 0, 0, True,
                    none, none, *new_walk_memo(2, 8))
    blocked_rows_into(np.zeros(k, np.int8), np.zeros(k, np.bool_), np.zeros(k, np.int64), np.empty(k, np.bool_), 0, k)
    # the parents mapped back (meshes with fans; renumbered ones)
    map_through_into(r.copy(), r.copy(), 0, k)
    # the new rows' twin keys in two parts (``_row_twin_keys_split``, many changed rows)
    tri = np.array([[0, 1, 2], [2, 1, 3]], np.int64)
    kt = np.empty(12, np.int64)
    _twin_keys_into(tri[:1], tri, np.array([-1, 4, -1, -1, 1, -1], np.int64), np.zeros(2, np.int8), 4,
                    np.array([1], np.int64), 0, 1, 0, kt, kt.copy(), kt.copy())
    _packed_keys(np.arange(3, dtype=np.int64), 4)
    from hammesh.postprocess._improve_kernels import load_improve_kernels  # (only when loading)

    load_improve_kernels()


@njit(cache=True, nogil=True)
def _first_start(status, n_v):
    """The first virtual row a walk starts at (the first kept or new row), -1 if none."""
    m = status.shape[0]
    for s in range(n_v):
        if s >= m or status[s] == PASS:
            return s
    return -1


@njit(cache=True, nogil=True)
def _link_ends_into(status, is_cov, link_new, twin_in, tw_new, changed, face_tw, lo, hi, ends):
    """Each virtual row's two links, for rows ``lo..hi``.

    ``ends[2 x]``, ``ends[2 x + 1]`` = ``4 g + j`` for the edges ``j1 < j2`` of row x the
    cycle crosses and their virtual twins ``g``; both -1 unless there are exactly two,
    each linked back. A kept row's links are its cover edges (the input's twins, or
    where the other side changed the kept half-edge's twin, :func:`_faced`), a new
    row's its link bits. Rows are independent: threads fill disjoint ranges. (Written
    out in one loop: the same test as a helper returning a tuple, with its early
    exits, compiled ~5x slower, 70 ns a row at 1.5 M.)
    """
    m = status.shape[0]
    for x in range(lo, hi):
        n_links = 0
        e1 = e2 = -1
        for j in range(3):
            h = 3 * x + j
            if x < m:  # a kept triangle: links on its cover edges, the input's twins
                if not is_cov[h]:
                    continue
                g = twin_in[h]
                if g >= 0 and status[g // 3] != PASS:
                    g = _faced(g, changed, face_tw)
            else:
                if not (link_new[x - m] >> j) & 1:
                    continue
                g = tw_new[h - 3 * m]
            n_links += 1
            if g < 0:
                n_links = 3
                break
            y = g // 3
            back = is_cov[g] if y < m else (link_new[y - m] >> (g - 3 * y)) & 1
            if not back:
                n_links = 3
                break
            if e1 < 0:
                e1 = 4 * g + j
            else:
                e2 = 4 * g + j
        if n_links == 2:
            ends[2 * x] = e1
            ends[2 * x + 1] = e2
        else:
            ends[2 * x] = -1
            ends[2 * x + 1] = -1


@njit(cache=True, nogil=True)
def _walk_one_into(ends, parent_new, m, s, forward, mine, theirs, buf):
    """Walk the cycle through virtual row ``s`` into ``buf``, marking ``mine``.

    ``ends``: the rows' links (:func:`_link_ends_into`); ``m`` the input's triangles
    (virtual rows from ``m`` on are new rows, their parents ``parent_new``).
    ``forward``: leave ``s`` by its second link (as :func:`_walk_all`), else by its
    first. Stops before a row ``theirs`` marks (another walk of the same cycle from
    the other end has been there) or on returning to ``s``. Returns ``(count,
    lowest parent, bad)``.
    """
    n = 0
    x = s
    came = -1
    lo = m
    while True:
        mine[x] = True
        buf[n] = x
        n += 1
        lo = min(lo, x if x < m else parent_new[x - m])
        e1 = ends[2 * x]
        if e1 < 0:
            return n, lo, x
        e2 = ends[2 * x + 1]
        if x == s and came < 0:
            e = e2 if forward else e1
        else:
            e = e2 if (e1 & 3) == came else e1
        g = e >> 2
        y = g // 3
        came = g - 3 * y
        if y == s:
            return n, lo, -1
        if mine[y]:  # (before theirs: one walk's marks are both in the one-thread walk)
            return n, lo, y
        if theirs[y]:
            return n, lo, -1
        x = y


@njit(cache=True, nogil=True)
def _walk_all(ends, parent_new, m, status, n_rows):
    """:func:`walk_links` in one thread: ``(order, lengths, low, bad)``."""
    n_v = ends.shape[0] // 2
    seen = np.zeros(n_v, np.bool_)
    order = np.empty(n_rows, np.int64)
    return _walk_rest(ends, parent_new, m, status, order, 0, m, np.empty(0, np.int64), 0, seen, seen)


@njit(cache=True, nogil=True)
def _walk_rest(ends, parent_new, m, status, order, n_f, lo_first, back, n_b, seen, seen_b):
    """The walk's outer loop: ``order[:n_f]`` holds a first cycle walked forward (its
    lowest parent ``lo_first``; none if ``n_f`` is 0) and ``back[:n_b]`` the same
    cycle walked backward from the same row; the rows of ``back`` not in ``seen`` (the
    forward walk's marks) follow it, reversed. Then a walk from every row neither
    ``seen`` nor ``seen_b`` marks (kept rows of ``status`` ``PASS`` and new rows, from
    ``m`` on). Returns ``(order, lengths, low, bad)``."""
    n_v = ends.shape[0] // 2
    n_rows = order.shape[0]
    lengths = np.empty(n_rows, np.int64)
    low = np.empty(n_rows, np.int64)
    n_c = 0
    pos = n_f
    if n_f > 0:
        e = 1
        while e < n_b and not seen[back[e]]:
            e += 1
        for i in range(e - 1, 0, -1):
            order[pos] = back[i]
            pos += 1
        lengths[0] = pos
        low[0] = lo_first
        n_c = 1
    for s in range(n_v):
        if seen[s] or seen_b[s] or (s < m and status[s] != PASS):
            continue
        n, lo, bad = _walk_one_into(ends, parent_new, m, s, True, seen, seen, order[pos:])
        if bad >= 0:
            return order, lengths, low, bad
        lengths[n_c] = n
        low[n_c] = lo
        n_c += 1
        pos += n
    return order, lengths[:n_c], low[:n_c], -1


class CycleRows(NamedTuple):
    """Result of :func:`rows_in_cycle_order`: the output rows in cycle order."""

    out: np.ndarray  # (k, 3) int64 corners
    parent: np.ndarray  # (k,) int64 input triangle each row lies in
    partner: np.ndarray  # (k,) int64 the other triangle a join replaced, or -1
    kind: np.ndarray  # (k,) int8 (3: kept whole)
    pm: np.ndarray  # (k,) float64 the parents' smallest angle
    lengths: np.ndarray  # (c,) int64 run lengths in the new run order
    claim: np.ndarray  # (3 k,) int64 half-edge twins of the rows (-1 boundary)


def rows_in_cycle_order(
    order, lengths, run_order, tri, twin_in, status, out_new, parent_new, partner_new, kind_new, tw_new, changed,
    face_tw, amin, scratch=None, con=None, pinned=None,
) -> CycleRows:
    """The output rows, walked into ``order`` (:func:`walk_links`, virtual rows), taken across in one gather.

    Runs go in the order ``run_order``; every row's corners, parents, kind (3 for a
    kept triangle), its parents' smallest angle ``pm`` (``amin`` of ``parent``, and of
    ``partner`` if any) and its pairing claim (``claim[3 i + j]``: the twin of edge j
    of final row i, -1 on the boundary) are written in the same pass, over one row
    range per core (:func:`_row_positions_into`, then :func:`_gather_rows_into`: each
    row is written by one thread only). The big arrays come from ``hammesh.pages``
    (the reserve ``quality_mesh`` faulted while Triangle ran, if any). ``scratch``: an int64
    array of at least one entry per virtual row, any contents (e.g. :func:`walk_links`'
    ``ends``, done with), for the rows' final places (``scratch[t]``: where virtual row
    ``t`` went, afterwards); made here if None. ``con``
    (``(3 m,)`` bool, the input's pinned half-edges) and ``pinned`` (``(3 k,)`` bool):
    each kept row's pinned output edges written on the way (its input half-edge's
    ``con``, if inner), as ``_improve_kernels.pinned_output_edges`` finds them; the new
    rows' entries are left as they were.
    """
    m = tri.shape[0]
    k = order.shape[0]
    rows, new_len = order, lengths
    if lengths.shape[0] > 1:
        rows = np.empty(k, np.int64)
        new_len = np.empty(lengths.shape[0], np.int64)
        _runs_in_order_into(order, lengths, run_order, rows, new_len)
    spans = row_ranges(k, threads.THREAD_MIN_ROWS)
    n_v = m + out_new.shape[0]  # (entries of rows not output: never read)
    pos = fresh(n_v, np.int64) if scratch is None or scratch.shape[0] < n_v else scratch[:n_v]
    run_all([partial(_row_positions_into, rows, pos, lo, hi) for lo, hi in spans])
    res = CycleRows(
        fresh((k, 3), np.int64), fresh(k, np.int64), fresh(k, np.int64), fresh(k, np.int8), fresh(k, np.float64),
        new_len, fresh(3 * k, np.int64),
    )
    if con is None or pinned is None:
        con, pinned = np.zeros(0, np.bool_), np.zeros(0, np.bool_)
    run_all([
        partial(
            _gather_rows_into, rows, pos, tri, twin_in, status, out_new, parent_new, partner_new, kind_new, tw_new,
            changed, face_tw, amin, res.out, res.parent, res.partner, res.kind, res.pm, res.claim, con, pinned, lo, hi,
        )
        for lo, hi in spans
    ])
    return res


@njit(cache=True, nogil=True)
def kept_below(kind, parent, parent_min, bound, out):
    """Rows kept whole (``kind`` 3) whose parent's smallest angle is at most ``bound``,
    into ``out``; returns their count (``sparse.kept_radius_ratio``: one pass, no
    gathered copies of the 1.5 M rows)."""
    k = 0
    for i in range(kind.shape[0]):
        if kind[i] == 3 and parent_min[parent[i]] <= bound:
            out[k] = i
            k += 1
    return k


@njit(cache=True, nogil=True)
def _runs_in_order_into(order, lengths, run_order, rows, new_len):
    """``rows``: the runs of ``order`` (lengths ``lengths``) in the order ``run_order``."""
    c = lengths.shape[0]
    starts = np.empty(c, np.int64)
    s = 0
    for r in range(c):
        starts[r] = s
        s += lengths[r]
    p = 0
    for q in range(c):
        r = run_order[q]
        new_len[q] = lengths[r]
        for i in range(starts[r], starts[r] + lengths[r]):
            rows[p] = order[i]
            p += 1


@njit(cache=True, nogil=True)
def _row_positions_into(rows, pos, lo, hi):
    """``pos[rows[i]] = i`` for ``i`` in ``lo..hi`` (``rows`` holds each virtual row once)."""
    for i in range(lo, hi):
        pos[rows[i]] = i


#: places ahead whose row :func:`_gather_rows_into` asks for (a cache hint)
GATHER_AHEAD = 16


@njit(cache=True, nogil=True)
def _gather_rows_into(
    rows, pos, tri, twin_in, status, out_new, parent_new, partner_new, kind_new, tw_new, changed, face_tw, amin,
    out2, parent2, partner2, kind2, pm, claim, con, pinned, lo, hi,
):
    """Final rows ``lo..hi`` of :func:`rows_in_cycle_order` (``pos``: every row's final place;
    ``pinned`` empty: no pinned edges written). The rows in cycle order jump about the
    virtual rows: the row ``GATHER_AHEAD`` places on is asked for now (its triangle,
    twins and angle, or its new row; ``hammesh.prefetch``): at 1.5 M triangles, one
    thread, 0.057 -> 0.039 s, the same values (session 20)."""
    m = tri.shape[0]
    pin = pinned.shape[0] == claim.shape[0]
    for i in range(lo, hi):
        if i + GATHER_AHEAD < hi:
            y = rows[i + GATHER_AHEAD]
            if y < m:
                prefetch_row(tri, y)
                prefetch_row(twin_in, 3 * y)
                prefetch_row(amin, y)
            else:
                prefetch_row(out_new, y - m)
        x = rows[i]
        for j in range(3):
            h = 3 * x + j
            if x < m:
                g = twin_in[h]
                if pin:
                    pinned[3 * i + j] = con[h] and g >= 0
                if g >= 0 and status[g // 3] != PASS:
                    g = _faced(g, changed, face_tw)
            else:
                g = tw_new[h - 3 * m]
            claim[3 * i + j] = -1 if g < 0 else 3 * pos[g // 3] + g % 3
        if x < m:
            out2[i, 0] = tri[x, 0]
            out2[i, 1] = tri[x, 1]
            out2[i, 2] = tri[x, 2]
            parent2[i] = x
            partner2[i] = -1
            kind2[i] = 3
            pm[i] = amin[x]
            continue
        r = x - m
        out2[i, 0] = out_new[r, 0]
        out2[i, 1] = out_new[r, 1]
        out2[i, 2] = out_new[r, 2]
        p = parent_new[r]
        q = partner_new[r]
        parent2[i] = p
        partner2[i] = q
        kind2[i] = kind_new[r]
        a = amin[p]
        if q >= 0 and amin[q] < a:
            a = amin[q]
        pm[i] = a


@njit(cache=True, nogil=True)
def blocked_rows_into(status, is_fan, cyc, out, lo, hi):
    """Rows ``lo..hi`` no alternating cycle of the cover swaps may pass
    (``sparse._alternating_merges``): in a step of the plan, a fan or uncovered. One
    threaded pass instead of three numpy passes and their temporaries (5 ms at 1.5 M
    on the main thread)."""
    for t in range(lo, hi):
        out[t] = status[t] != PASS or is_fan[t] or cyc[t] < 0


@njit(cache=True, nogil=True)
def iota_into(a, lo, hi):
    """``a[i] = i`` for ``i`` in ``lo..hi`` (a numbering in an array the caller has, e.g.
    from the page reserve: ``np.arange`` would fault fresh pages)."""
    for i in range(lo, hi):
        a[i] = i


@njit(cache=True, nogil=True)
def map_through_into(a, table, lo, hi):
    """``a[i] = table[a[i]]`` for ``i`` in ``lo..hi``, in place (row numbers composed with
    a renumbering: one threaded pass, no fresh array to fault as ``table[a]`` makes)."""
    for i in range(lo, hi):
        a[i] = table[a[i]]


@njit(cache=True, nogil=True, inline="always")
def _holds(items, x):
    """Is ``x`` one of the few ``items``?"""
    for y in items:
        if y == x:
            return True
    return False


@njit(cache=True, nogil=True)
def union_polygon_into(tri, twin, pinned, members, poly, hes):
    """The counter-clockwise corners and outer half-edges of a group's union (``sparse._union_polygon``).

    ``members``: the group's triangles; ``poly``, ``hes``: room for ``len(members) + 2``
    entries each (or more). Returns the polygon's length, 0 where ``sparse._union_polygon``
    gives None: an edge inside the group is pinned, the union is not a disc with every
    corner on its boundary (a vertex starts two outer edges, or the outer edges are not
    ``len(members) + 2`` in one closed loop). The polygon starts at the first outer
    half-edge in the order of ``members`` and their edges (as the Python version's
    dictionary did): the same polygon, without a dictionary per group.
    """
    nm = members.shape[0]
    cap = poly.shape[0]
    n = 0
    for i in range(nm):
        for h in range(3 * members[i], 3 * members[i] + 3):
            if twin[h] >= 0 and _holds(members, twin[h] // 3):  # an edge inside the group
                if pinned[h]:
                    return 0
                continue
            a = tri[h // 3, h % 3]
            for j in range(n):
                if poly[j] == a:
                    return 0
            if n >= cap:
                return 0
            poly[n] = a  # (a -> b along h, gathered unordered first)
            hes[n] = h
            n += 1
    if n != nm + 2:
        return 0
    # chain them: the edge from a vertex v is the one whose start is v
    for i in range(n - 1):
        h = hes[i]
        x = h // 3
        b = tri[x, (h - 3 * x + 1) % 3]
        nxt = -1
        for j in range(i + 1, n):
            if poly[j] == b:
                nxt = j
                break
        if nxt < 0:
            return 0
        if nxt != i + 1:
            poly[i + 1], poly[nxt] = poly[nxt], poly[i + 1]
            hes[i + 1], hes[nxt] = hes[nxt], hes[i + 1]
    h = hes[n - 1]
    x = h // 3
    return n if tri[x, (h - 3 * x + 1) % 3] == poly[0] else 0


@njit(cache=True, nogil=True)
def ring_fan_point(pts, tri, members, poly, n, amin, keep, lo, hi, iters, need=0.0):
    """``place_fan`` over ``poly[:n]`` for a ring fan of ``members`` (``sparse._best_ring``).

    Starts: the members' centroids; the first compass step a quarter of the distance
    from the first centroid to the nearest corner. The lower bound is ``lo``, or with
    ``keep > 0`` the larger of ``lo`` and ``keep`` x the members' smallest ``amin``.
    Returns ``(x, y, slack, smallest angle, largest angle, the bound used)``; slack
    ``-inf`` without a search where no fan point can keep the smallest angle at the bound
    or at ``need`` (the caller's floor): half the polygon's smallest corner is below
    (``_join_kernels.half_smallest_corner``; most ring groups of 2-4 triangles at 1.5 M).
    """
    nm = members.shape[0]
    lo_g = lo
    if keep > 0.0:
        a = np.inf
        for i in range(nm):
            a = min(a, amin[members[i]])
        lo_g = max(lo, keep * a)
    if half_smallest_corner(pts, poly, n) < max(lo_g, need) * (1.0 - CORNER_BOUND_RTOL):
        return 0.0, 0.0, -np.inf, 0.0, np.pi, lo_g
    starts = np.empty((nm, 2))
    for i in range(nm):
        x = members[i]
        for d in range(2):
            starts[i, d] = (pts[tri[x, 0], d] + pts[tri[x, 1], d] + pts[tri[x, 2], d]) / 3.0
    d2 = np.inf
    for j in range(n):
        dx = pts[poly[j], 0] - starts[0, 0]
        dy = pts[poly[j], 1] - starts[0, 1]
        d2 = min(d2, dx * dx + dy * dy)
    x, y, sl, nmin, nmax = place_fan(pts, poly, n, starts, nm, lo_g, hi, 0.25 * np.sqrt(d2), iters)
    return x, y, sl, nmin, nmax, lo_g
