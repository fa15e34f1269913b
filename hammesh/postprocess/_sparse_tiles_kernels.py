"""Kernels of ``hammesh.postprocess.sparse_tiles`` (numba): the joins between the
cells' cycles (Kruskal in class order, each join placed near the cycle's first) and
the walk of the joined cycle's links.

Conventions as in ``_sparse_cells_kernels``: small kernels named by what they do,
fill kernels (``_into``) behind the module's thin wrappers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["plan_tile_joins_into", "tighten_joins_into", "walk_links_into"]


@njit(cache=True, nogil=True, inline="always")
def _find(uf, x):
    while uf[x] != x:
        uf[x] = uf[uf[x]]
        x = uf[x]
    return x


@njit(cache=True, nogil=True, inline="always")
def _gap(p, a, n):
    """Cyclic distance of positions ``p`` and ``a`` on a cycle of ``n`` (0: no anchor)."""
    if a < 0:
        return 0
    d = abs(p - a)
    return min(d, n - d)


@njit(cache=True, nogil=True)
def plan_tile_joins_into(order, cls, pref, far, row_t, row_u, cyc_t, cyc_u, pos_t, pos_u, length, n_rows, rounds, take):
    """Kruskal over the candidate joins ``order`` (sorted by class, then preference):
    class by class, the joins between two cycles not yet one, each triangle in one
    join at most. Inside a class a join is placed near the position where its cycles
    were first joined (their *anchor*): candidates go by their distance from the
    anchors (plus ``pref``: a swap before a bridge at the same distance), after
    ``far`` (the two cells' distance in the fishbone's order, which outranks the
    rest: the halves of a cell joined where they meet in that order); one whose
    distance grew since it was ranked (an anchor set in this class) waits for the
    next of ``rounds`` passes, ranked again. So each cell's joins sit close together
    along its cycle and the cell stays nearly one run of the joined cycle.
    ``take`` (candidates,) bool: out. Returns the joins taken."""
    n_cyc = length.shape[0]
    scale = 4 * length.max() + 2 if n_cyc else 1
    uf = np.arange(n_cyc)
    anchor = np.full(n_cyc, -1, np.int64)
    used = np.zeros(n_rows, np.bool_)
    n = order.shape[0]
    taken = 0
    i = 0
    while i < n:
        j = i
        while j < n and cls[order[j]] == cls[order[i]]:
            j += 1
        pending = order[i:j].copy()
        for r in range(rounds):
            cost = np.empty(pending.shape[0], np.int64)
            for x in range(pending.shape[0]):
                c = pending[x]
                cost[x] = far[c] * scale + 2 * (_gap(pos_t[c], anchor[cyc_t[c]], length[cyc_t[c]])
                                                + _gap(pos_u[c], anchor[cyc_u[c]], length[cyc_u[c]])) + pref[c]
            ranked = np.argsort(cost, kind="mergesort")
            wait = np.empty(pending.shape[0], np.int64)
            k = 0
            for x in ranked:
                c = pending[x]
                if used[row_t[c]] or used[row_u[c]]:
                    continue
                a = _find(uf, cyc_t[c])
                b = _find(uf, cyc_u[c])
                if a == b:
                    continue
                now = far[c] * scale + 2 * (_gap(pos_t[c], anchor[cyc_t[c]], length[cyc_t[c]])
                                            + _gap(pos_u[c], anchor[cyc_u[c]], length[cyc_u[c]])) + pref[c]
                if r + 1 < rounds and now > cost[x]:
                    wait[k] = c
                    k += 1
                    continue
                uf[a] = b
                used[row_t[c]] = True
                used[row_u[c]] = True
                if anchor[cyc_t[c]] < 0:
                    anchor[cyc_t[c]] = pos_t[c]
                if anchor[cyc_u[c]] < 0:
                    anchor[cyc_u[c]] = pos_u[c]
                take[c] = True
                taken += 1
            pending = wait[:k].copy()
            if k == 0:
                break
        i = j
    return taken


@njit(cache=True, nogil=True)
def walk_links_into(twin, link, order, lengths):
    """Read the cycles off the rows' links: ``link`` (m, 3) bool marks the two
    half-edges of each row the cycle crosses, ``twin`` the rows' half-edge twins.
    Fills ``order`` (m,) with the rows cycle by cycle and ``lengths`` with the runs;
    returns the number of runs, or -1 - row where a link has no linked twin (a row
    with other than two links, a link on the boundary or one its neighbour does not
    return)."""
    m = link.shape[0]
    seen = np.zeros(m, np.bool_)
    n = 0
    runs = 0
    for s in range(m):
        if seen[s]:
            continue
        start = n
        came = -1
        cur = s
        while True:
            seen[cur] = True
            order[n] = cur
            n += 1
            nxt = -1
            count = 0
            for k in range(3):
                if link[cur, k]:
                    count += 1
                    g = twin[3 * cur + k]
                    if g < 0 or not link[g // 3, g % 3]:
                        return -1 - cur
                    if g // 3 != came and nxt < 0:
                        nxt = g // 3
            if count == 0 and n - start == 1:
                break  # (a piece of one triangle: a run of one)
            if count != 2:
                return -1 - cur
            if nxt == s or nxt < 0:
                break
            if seen[nxt]:
                return -1 - cur
            came = cur
            cur = nxt
        lengths[runs] = n - start
        runs += 1
    return runs


@njit(cache=True, nogil=True)
def _spread(cyc, e, alt, cur, inc_ptr, inc_edge, cyc_t, pos_t, pos_u, length):
    """Positions of cycle ``cyc``'s joins (edge ``e`` at candidate ``alt``) taken off
    its length: the cycle's triangles outside its longest arc between two joins."""
    lo, hi = inc_ptr[cyc], inc_ptr[cyc + 1]
    r = hi - lo
    if r <= 1:
        return 0
    p = np.empty(r, np.int64)
    for i in range(r):
        f = inc_edge[lo + i]
        c = alt if f == e else cur[f]
        p[i] = pos_t[c] if cyc_t[c] == cyc else pos_u[c]
    p.sort()
    gap = length[cyc] - p[r - 1] + p[0]
    for i in range(1, r):
        gap = max(gap, p[i] - p[i - 1])
    return length[cyc] - gap


@njit(cache=True, nogil=True)
def tighten_joins_into(cur, ends, inc_ptr, inc_edge, alt_ptr, alt, row_t, row_u, cyc_t, cyc_u, pos_t, pos_u, pref,
                       length, n_rows, sweeps):
    """Move each join of the plan (``cur[e]``: the candidate of tree edge ``e``, whose
    cycles are ``ends[e]``) to the candidate between the same two cycles
    (``alt[alt_ptr[e]:alt_ptr[e + 1]]``) that leaves the fewest triangles of the two
    cycles outside their longest arcs between joins (``_spread``; ``pref`` breaks
    ties: swaps first), each triangle in one join at most; ``sweeps`` passes over the
    edges. In place; returns the joins moved."""
    used = np.zeros(n_rows, np.bool_)
    for e in range(cur.shape[0]):
        used[row_t[cur[e]]] = True
        used[row_u[cur[e]]] = True
    moved = 0
    for _ in range(sweeps):
        changed = 0
        for e in range(cur.shape[0]):
            a, b = ends[e, 0], ends[e, 1]
            c0 = cur[e]
            best = c0
            best_cost = 2 * (_spread(a, e, c0, cur, inc_ptr, inc_edge, cyc_t, pos_t, pos_u, length)
                             + _spread(b, e, c0, cur, inc_ptr, inc_edge, cyc_t, pos_t, pos_u, length)) + pref[c0]
            for i in range(alt_ptr[e], alt_ptr[e + 1]):
                c = alt[i]
                if c == c0 or used[row_t[c]] or used[row_u[c]]:
                    continue
                cost = 2 * (_spread(a, e, c, cur, inc_ptr, inc_edge, cyc_t, pos_t, pos_u, length)
                            + _spread(b, e, c, cur, inc_ptr, inc_edge, cyc_t, pos_t, pos_u, length)) + pref[c]
                if cost < best_cost:
                    best, best_cost = c, cost
            if best != c0:
                used[row_t[c0]] = used[row_u[c0]] = False
                used[row_t[best]] = used[row_u[best]] = True
                cur[e] = best
                changed += 1
        moved += changed
        if changed == 0:
            break
    return moved
