"""Compiled loops (numba) of the dual cycle cover (``cycle_cover.py``).

Serial, nopython, ``cache=True``; O(m) over plain arrays (the augmenting searches are
bounded by a budget), problems reported by return values, never raised. Small
helpers are left to LLVM's inliner, not numba's ``inline="always"``, which types
and compiles every call site anew (the cover's first compile: ~29 s CPU with
``_chain_end``, ``_third`` and ``_log`` so inlined, ~23 s without, the same speed;
docs/sparse.md, Cold start). Half-edge
``h = 3 t + k`` runs from ``tri[t, k]`` to ``tri[t, (k + 1) % 3]``; ``twin[h]`` is the
opposite half-edge or -1.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hammesh.postprocess._join_kernels import EDGE_GOOD, EDGE_NOT_GOOD, EDGE_UNKNOWN, corners_rule_out, edge_meets_rule
from hammesh.postprocess._thm24_kernels import edge_class as _edge_class
from hammesh.postprocess._thm24_kernels import find_root as _find


@njit(cache=True, nogil=True)
def neighbors(twin, m):
    """``nb[t, k]`` (int32): the triangle across side k of t, -1 on the boundary."""
    nb = np.full((m, 3), -1, np.int32)
    for t in range(m):
        for k in range(3):
            g = twin[3 * t + k]
            if g >= 0:
                nb[t, k] = g // 3
    return nb


@njit(cache=True, nogil=True)
def _lca(x, y, fa, mate, parent, stamp, s):
    while True:
        if x >= 0:
            x = _find(fa, x)
            if stamp[x] == s:
                return x
            stamp[x] = s
            x = parent[mate[x]] if mate[x] >= 0 else -1
        x, y = y, x


@njit(cache=True, nogil=True)
def _no_guide():
    """The ``guide`` of a breadth-first search (``_augment``): empty arrays."""
    return np.empty((0, 3), np.int64), np.empty((0, 2)), np.empty(0), np.empty(0), np.empty(0)


@njit(cache=True, nogil=True)
def _push(queue, tail, w, guide, g):
    """Push the even vertex ``w`` of a guided search (``_augment``; ``guide =
    (tri, points, goal, keys, cost)``, ``keys`` as long as ``queue``, ``cost`` one
    per triangle) into the binary heap ``queue[:tail]``, keyed as A* keys it: ``g``
    (the tree path's cost to ``w``, kept in ``cost[w]``) plus the distance from
    ``w``'s centroid to the goal ``goal[:d]`` times ``goal[d]`` (steps per unit
    length; ``goal[d + 1]``: the cost of a chain's triangle, ``_augment``).
    Returns the new heap size."""
    tri, pts, goal, keys, cost = guide
    d = 0.0
    for j in range(pts.shape[1]):
        c = (pts[tri[w, 0], j] + pts[tri[w, 1], j] + pts[tri[w, 2], j]) / 3.0 - goal[j]
        d += c * c
    cost[w] = g
    d = g + goal[pts.shape[1]] * np.sqrt(d)
    i = tail
    while i > 0:
        p = (i - 1) // 2
        if keys[p] <= d:
            break
        keys[i] = keys[p]
        queue[i] = queue[p]
        i = p
    keys[i] = d
    queue[i] = w
    return tail + 1


@njit(cache=True, nogil=True)
def _pop(queue, tail, guide):
    """The least-key vertex of ``_push``'s heap ``queue[:tail]`` and the new size."""
    keys = guide[3]
    v = queue[0]
    tail -= 1
    d = keys[tail]
    w = queue[tail]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= tail:
            break
        if c + 1 < tail and keys[c + 1] < keys[c]:
            c += 1
        if keys[c] >= d:
            break
        keys[i] = keys[c]
        queue[i] = queue[c]
        i = c
    if tail > 0:
        keys[i] = d
        queue[i] = w
    return v, tail


@njit(cache=True, nogil=True)
def _blossom(v, w, a, fa, mate, parent, label, queue, tail):
    while _find(fa, v) != a:
        parent[v] = w
        w = mate[v]
        if label[w] == 1:  # odd vertex inside the blossom becomes even
            label[w] = 0
            queue[tail] = w
            tail += 1
        if fa[v] == v:
            fa[v] = a
        if fa[w] == w:
            fa[w] = a
        v = parent[w]
    return tail


#: Kinds of augmenting search (``_augment``'s ``mode``).
PLAIN = 0  # along dual edges between degree-3 triangles
CHAIN = 1  # also through chains of degree-2 triangles (left uncovered when used)
DROP = 2  # PLAIN, or drop one interior degree-3 triangle (left uncovered)
OBSERVE = 3  # PLAIN, noting where a DROP search of the same start would stop (``seen``)


@njit(cache=True, nogil=True)
def _chain_end(nb, active, alive, v, k):
    """The degree-3 triangle reached from ``v`` across its side ``k`` through a chain
    of degree-2 triangles (``(end, chain length)``; the neighbour itself, length 0,
    if it has degree 3; end -1 if the chain dead-ends or comes back)."""
    w = nb[v, k]
    if w < 0 or not alive[w]:
        return -1, 0
    prev = v
    cur = w
    ln = 0
    while not active[cur]:
        nxt = -1
        for j in range(3):
            z = nb[cur, j]
            if z >= 0 and alive[z] and z != prev:
                nxt = z
        prev = cur
        cur = nxt
        ln += 1
        if cur < 0 or cur == w:
            return -1, 0
    if cur == v:
        return -1, 0
    return cur, ln


@njit(cache=True, nogil=True)
def _third(nb, u, a, b):
    """The neighbour of ``u`` other than ``a`` and ``b`` (-1 unless exactly one)."""
    z = -1
    for k in range(3):
        x = nb[u, k]
        if x != a and x != b:
            if z >= 0 or x < 0:
                return -1
            z = x
    return z


@njit(cache=True, nogil=True)
def _log(log, nlog, i, mate, active, alive):
    """Record triangle ``i``'s state before a change (``log`` rows ``(i, mate, active,
    alive)``; ``nlog[0]`` rows used, past the end: no longer undoable)."""
    n = nlog[0]
    if n < log.shape[0]:
        log[n, 0] = i
        log[n, 1] = mate[i]
        log[n, 2] = active[i]
        log[n, 3] = alive[i]
    nlog[0] = n + 1


@njit(cache=True, nogil=True)
def _undo(log, nlog, mate, active, alive):
    """Restore the states recorded by ``_log``, newest first; False if it overflowed."""
    n = nlog[0]
    if n > log.shape[0]:
        return False
    for j in range(n - 1, -1, -1):
        i = log[j, 0]
        mate[i] = log[j, 1]
        active[i] = log[j, 2] != 0
        alive[i] = log[j, 3] != 0
    nlog[0] = 0
    return True


@njit(cache=True, nogil=True)
def _drop(u, nb, active, alive, mate, log, nlog):
    """Leave the degree-3 triangle ``u`` uncovered: it leaves the graph and its three
    neighbours (all of degree 3) drop to degree 2, so none of them needs a matching
    edge any more; the partner of a neighbour matched elsewhere is freed and
    returned (-1 if none). Changes are logged (``_log``) when ``log`` has rows."""
    keep = log.shape[0] > 0
    if keep:
        _log(log, nlog, u, mate, active, alive)
    alive[u] = False
    active[u] = False
    mate[u] = -1
    freed = -1
    for k in range(3):
        x = nb[u, k]
        y = mate[x]
        if keep:
            _log(log, nlog, x, mate, active, alive)
            if y >= 0 and y != u:
                _log(log, nlog, y, mate, active, alive)
        active[x] = False
        if y >= 0:
            mate[x] = -1
            if y != u:
                mate[y] = -1
                freed = y
    return freed


@njit(cache=True, nogil=True)
def _augment(r, nb, active, alive, mate, parent, fa, label, stamp, s0, touched, queue, budget, mode, take, log,
             nlog, seen, guide, mark=None):
    """Edmonds' blossom search for an augmenting path from the free vertex ``r``.

    Blossoms are contracted with a union-find over bases (``fa``); the arrays are
    global (size m) but only the vertices this search touches are set and reset, so a
    search costs about what it explores: ``label`` (int8) must start -1 everywhere,
    ``parent`` and ``fa`` may start empty (never read before a search sets them).
    It gives up after ``budget`` touched vertices (``touched`` and ``queue`` hold
    ``budget + 8``).

    ``mode``: ``PLAIN`` searches the dual edges between degree-3 (``active``)
    triangles; ``CHAIN`` also steps through chains of degree-2 (``alive``, not
    active) triangles to the degree-3 triangle at their far end (``_chain_end``,
    found on the way: no chain graph is built); ``DROP`` searches like ``PLAIN``
    and also stops at an odd (matched) vertex ``u`` reached from ``v`` whose third
    neighbour ``z`` (neither ``v`` nor ``u``'s mate) is free: the path to ``v`` is
    flipped (``r`` matched, ``v`` free) and ``u`` dropped (``_drop``: ``v``, ``u``'s
    mate and ``z`` drop to degree 2 and need no partner), so one interior triangle
    is left uncovered instead of a chain of boundary triangles. With ``take >= 0``
    the search stops at ``u == take`` even if ``z`` is matched (its partner is
    freed). ``OBSERVE`` searches like ``PLAIN`` and notes in ``seen`` (4 int64) where
    ``DROP`` from the same state would have stopped: ``seen[0]`` the first ``u`` with
    a free ``z``, ``seen[2]`` the first with a matched one (the ``extra`` below), each
    -1 if none, and ``seen[1]``, ``seen[3]`` the vertices touched when the expansion
    that met it began (a ``DROP`` search of a smaller budget meets it iff less).
    The two searches explore alike up to where ``DROP`` stops, so a failed
    ``OBSERVE`` search answers the ``DROP`` search that would follow it
    (``_drop_matching``) without exploring the same triangles again.

    ``guide`` (``_no_guide()``: none) makes the search best-first (A*) instead of
    breadth-first: the even vertex of least tree cost plus distance to a goal point
    is expanded next (``_push``; a step costs 1, a chain's triangle ``goal[d + 1]``).
    Edmonds' search is correct in any expansion order; a search that must cross the
    mesh to the free triangle near the goal (``CHAIN`` searches between distant
    parity defects) then explores a band along the way instead of a disc.

    ``mark`` ((m,) bool, optional): set on every triangle the search may have read
    (those it touched and their neighbours): ``drop_defects`` checks a speculative
    run against it.

    Returns ``(found, next lca stamp, extra)``: ``found`` the far end of the path
    applied (the dropped triangle after a drop, now not ``alive``) or -1; ``extra``
    after a drop the partner freed (or -1); after a failed ``DROP`` search the first
    odd vertex that ``take`` could drop (or -1). Every change is recorded in ``log``
    (``_log``; an empty ``log``: not recorded).
    """
    n_t = 0
    head = 0
    tail = 0
    label[r] = 0
    fa[r] = r  # the union-find is set up as triangles are touched (fa may start empty)
    touched[n_t] = r
    n_t += 1
    guided = guide[3].shape[0] > 0
    chain_cost = guide[2][guide[1].shape[1] + 1] if guided else 0.0
    # (breadth-first, the queue is written here: helpers taking the guide's arrays
    # cost a call with reference counts per vertex, +70 % on the defects' searches)
    if guided:
        tail = _push(queue, tail, r, guide, 0.0)
    else:
        queue[tail] = r
        tail += 1
    found = -1
    drop = False
    extra = -1
    s = s0
    if mode == OBSERVE:
        seen[0] = -1
        seen[2] = -1
    while head < tail and found < 0 and n_t < budget:
        if guided:
            v, tail = _pop(queue, tail, guide)  # (head stays 0)
            gv = guide[4][v] + 1.0  # (A*: a step costs 1, a chain's triangle chain_cost)
        else:
            v = queue[head]
            head += 1
            gv = 0.0
        n_v = n_t
        for k in range(3):
            if mode == CHAIN:
                u, ln = _chain_end(nb, active, alive, v, k)
            else:
                u, ln = nb[v, k], 0
            if u < 0 or not active[u]:
                continue
            if label[u] < 0:
                parent[u] = v
                label[u] = 1
                fa[u] = u
                touched[n_t] = u
                n_t += 1
                if mate[u] < 0:
                    found = u
                    break
                w = mate[u]
                if mode == DROP:
                    z = _third(nb, u, v, w)
                    if z >= 0 and z != r and active[z]:
                        if mate[z] < 0 or u == take:
                            found = u
                            drop = True
                            break
                        if extra < 0 and mate[z] != u:
                            extra = u
                elif mode == OBSERVE:
                    z = _third(nb, u, v, w)
                    if z >= 0 and z != r and active[z]:
                        if mate[z] < 0:
                            if seen[0] < 0:
                                seen[0] = u
                                seen[1] = n_v
                        elif seen[2] < 0 and mate[z] != u:
                            seen[2] = u
                            seen[3] = n_v
                label[w] = 0
                fa[w] = w
                touched[n_t] = w
                n_t += 1
                if guided:
                    tail = _push(queue, tail, w, guide, gv + chain_cost * ln)
                else:
                    queue[tail] = w
                    tail += 1
            elif label[u] == 0 and _find(fa, v) != _find(fa, u):
                s += 1
                a = _lca(u, v, fa, mate, parent, stamp, s)
                nt = _blossom(u, v, a, fa, mate, parent, label, queue, tail)
                nt = _blossom(v, u, a, fa, mate, parent, label, queue, nt)
                if guided:  # the vertices made even were appended past the heap: push them
                    for i in range(tail, nt):
                        tail = _push(queue, tail, queue[i], guide, gv)  # (i == tail: writes at <= i)
                else:
                    tail = nt
    if found >= 0:
        v = found
        keep = log.shape[0] > 0
        while v >= 0:
            pv = parent[v]
            nv = mate[pv]
            if keep:
                _log(log, nlog, v, mate, active, alive)
                _log(log, nlog, pv, mate, active, alive)
            mate[v] = pv
            mate[pv] = v
            v = nv
        extra = _drop(found, nb, active, alive, mate, log, nlog) if drop else -1
    for i in range(n_t):
        x = touched[i]
        label[x] = -1
        parent[x] = -1
        fa[x] = x
    if mark is not None:  # (a search reads the triangles it touches and their neighbours)
        for i in range(n_t):
            x = touched[i]
            mark[x] = True
            for k in range(3):
                y = nb[x, k]
                if y >= 0:
                    mark[y] = True
    return found, s, extra


@njit(cache=True, nogil=True)
def peel(nb, m):
    """Leave out triangles that cannot lie on a cycle (at most one neighbour left)."""
    deg = np.zeros(m, np.int8)  # dual degree, 0-3
    for t in range(m):
        for k in range(3):
            if nb[t, k] >= 0:
                deg[t] += 1
    return _peel_degrees(nb, deg), deg


@njit(cache=True, nogil=True)
def neighbors_degrees_into(twin, nb, deg, lo, hi):
    """``neighbors_into`` and each row's dual degree ``deg[t]`` (int8, 0-3), rows lo..hi:
    :func:`peel_active`'s start, made on the neighbours' threads."""
    for t in range(lo, hi):
        d = 0
        for k in range(3):
            g = twin[3 * t + k]
            if g >= 0:
                nb[t, k] = g // 3
                d += 1
            else:
                nb[t, k] = -1
        deg[t] = d


@njit(cache=True, nogil=True)
def peel_active(nb, deg):
    """:func:`peel` from the degrees ``deg`` (``neighbors_degrees_into``; lowered in
    place as it peels): ``(alive, active)``, active the rows alive at degree 3."""
    alive = _peel_degrees(nb, deg)
    active = np.empty(nb.shape[0], np.bool_)
    for t in range(nb.shape[0]):
        active[t] = alive[t] and deg[t] == 3
    return alive, active


@njit(cache=True, nogil=True)
def _peel_degrees(nb, deg):
    m = nb.shape[0]
    alive = np.ones(m, np.bool_)
    stack = np.empty(m + 1, np.int64)
    top = 0
    for t in range(m):
        if deg[t] <= 1:
            stack[top] = t
            top += 1
    while top > 0:
        top -= 1
        t = stack[top]
        if not alive[t]:
            continue
        alive[t] = False
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and alive[u]:
                deg[u] -= 1
                if deg[u] == 1:
                    stack[top] = u
                    top += 1
    return alive


@njit(cache=True, nogil=True)
def _bfs_order(nb, side, half):
    """Triangles with ``side[t] == half`` in breadth-first order over the dual edges
    between them (each piece in turn)."""
    m = nb.shape[0]
    n = 0
    for t in range(m):
        if side[t] == half:
            n += 1
    order = np.empty(n, np.int32)
    seen = np.zeros(m, np.bool_)
    head = 0
    tail = 0
    for s in range(m):
        if side[s] != half or seen[s]:  # (the other half's pages of seen never touched)
            continue
        seen[s] = True
        order[tail] = s
        tail += 1
        while head < tail:
            t = order[head]
            head += 1
            for k in range(3):
                u = nb[t, k]
                if u >= 0 and not seen[u] and side[u] == half:
                    seen[u] = True
                    order[tail] = u
                    tail += 1
    return order


@njit(cache=True, nogil=True)
def _greedy_matching(nb, active, m, rule, good, order, online, parent, fa, label, stamp, queue, mate):
    """Karp-Sipser: match the degree-3 triangles among themselves, forced pairs first.

    Where a triangle has a choice, its partner is one across a good edge if any
    (matched edges are where the cover's cycles can later be joined: sparse mode
    prefers the edges whose join keeps the local quality rule), then the one with the
    fewest free candidates of its own. ``good`` (int8, one entry per half-edge:
    ``_join_kernels.EDGE_UNKNOWN``, ``EDGE_NOT_GOOD``, ``EDGE_GOOD``) holds what is
    known; an edge not judged yet is judged by ``rule`` (``_join_kernels.EdgeRule``:
    ``edge_meets_rule`` of its lower half-edge, as ``good_half_edges_into`` judges it)
    when first asked, and both halves noted. Only the edges between a triangle and two
    or three free neighbours are asked (with one the partner is forced): about a
    third of a big mesh's edges (docs/sparse.md, session 17). Two halves may share
    ``good``: an edge across the split is never asked.

    Free choices are taken in ``order`` (breadth-first, ``_bfs_order``): the greedy
    then sweeps a front, and a triangle it strands (no free neighbour left) has free
    triangles just ahead; an augmenting search of at most ``online`` triangles from
    it, made at once, finds one a few steps away (measured at 1.5 M triangles: 9,980
    triangles left free in Triangle's numbering without these searches, about 20 with).
    ``active``: the triangles to match (alive, of degree 3; with cells, not the
    pinned ones; of one half when two threads match one half each: ``order`` lists
    the triangles this call may touch); ``mate`` is completed in place. Returns the
    next lca stamp.
    """
    n = order.shape[0]
    # (the rule's arrays taken out once: ``edge_meets_rule`` called from this loop, not
    # through a helper taking the rule, which doubled the judging's cost)
    pts, tri, twin, pinned, amin = rule.pts, rule.tri, rule.twin, rule.pinned, rule.amin
    keep, cos_hi, swaps, edge_splits = rule.keep, rule.cos_hi, rule.swaps, rule.edge_splits
    corners = rule.corners  # (the necessary test first, off the corner angles: no point read)
    by_corners = corners.shape[0] > 0
    stack = np.empty(4 * n + 16, np.int32)  # a triangle is pushed once, then once per neighbour matched
    touched = np.empty(online + 16, np.int32)
    nolog = np.empty((0, 4), np.int64)
    nonlog = np.zeros(1, np.int64)
    noguide = _no_guide()
    s = 0
    hdeg = np.zeros(m, np.int8)  # free candidates, 0-3
    for i in range(n):
        t = order[i]
        if active[t] and mate[t] < 0:
            for k in range(3):
                u = nb[t, k]
                if u >= 0 and active[u] and mate[u] < 0:
                    hdeg[t] += 1
    top = 0
    for i in range(n):
        t = order[i]
        if active[t] and hdeg[t] == 1:
            stack[top] = t
            top += 1
    scan = 0
    while True:
        if top > 0:
            top -= 1
            t = stack[top]
            if mate[t] >= 0:
                continue
        else:
            while scan < n and not (active[order[scan]] and mate[order[scan]] < 0 and hdeg[order[scan]] > 0):
                scan += 1
            if scan >= n:
                break
            t = order[scan]
        # partner: a good edge first, then the fewest free candidates of its own
        best = -1
        best_good = False
        n_free = 0
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and active[u] and mate[u] < 0:
                n_free += 1
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and active[u] and mate[u] < 0:
                gk = False
                if n_free > 1:
                    h = 3 * t + k
                    v = good[h]
                    if v == EDGE_UNKNOWN:
                        g = twin[h]
                        v = EDGE_NOT_GOOD
                        if g >= 0 and not (by_corners and corners_rule_out(corners, twin, h, amin, keep)) and \
                                edge_meets_rule(pts, tri, twin, pinned, min(h, g), amin, keep, cos_hi, swaps,
                                                edge_splits):
                            v = EDGE_GOOD
                        good[h] = v
                        if g >= 0:
                            good[g] = v
                    gk = v == EDGE_GOOD
                if best < 0 or (gk and not best_good) or (gk == best_good and hdeg[u] < hdeg[best]):
                    best = u
                    best_good = gk
        if best < 0:  # stranded: augment now, while free triangles are near
            hdeg[t] = 0
            if online <= 0:
                continue
            far, s, _x = _augment(t, nb, active, active, mate, parent, fa, label, stamp, s, touched, queue, online,
                                  PLAIN, -1, nolog, nonlog, nonlog, noguide)
            if far < 0:
                continue
            # t and the path's far end are newly matched (the path's inner triangles
            # stay matched): only the far end's free neighbours lose a candidate
            for k in range(3):
                w = nb[far, k]
                if w >= 0 and active[w] and mate[w] < 0:
                    hdeg[w] -= 1
                    stack[top] = w
                    top += 1
            continue
        mate[t] = best
        mate[best] = t
        for xi in range(2):
            x = t if xi == 0 else best
            for k in range(3):
                w = nb[x, k]
                if w >= 0 and active[w] and mate[w] < 0:
                    hdeg[w] -= 1
                    if hdeg[w] <= 1:
                        stack[top] = w
                        top += 1
    return s


@njit(cache=True, nogil=True)
def _record_writes(log, nlog, writes, n_w):
    """Append the triangles of ``log[:nlog]`` (``_log``) to ``writes[:n_w]`` (grown by
    doubling); returns ``(writes, n_w)``, ``n_w`` -1 once a log overflowed (unknown)."""
    n = nlog[0]
    if n_w < 0 or n > log.shape[0]:
        return writes, -1
    if n_w + n > writes.shape[0]:
        grown = np.empty(2 * (n_w + n) + 64, np.int64)
        grown[:n_w] = writes[:n_w]
        writes = grown
    for j in range(n):
        writes[n_w + j] = log[j, 0]
    return writes, n_w + n


@njit(cache=True, nogil=True)
def _drop_matching(nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue, plain_budget, budget,
                   rounds, frees, mark=None):
    """Fix free degree-3 triangles by leaving interior triangles uncovered (``DROP``).

    A degree-3 triangle the matching cannot pair (a parity defect: typically two
    triangles with a single degree-3 neighbour each, next to the boundary) costs
    either a chain of degree-2 triangles (``_chain_matching``: boundary triangles,
    whose incenter sectors are the sparse mode's worst angles) or one dropped
    interior triangle. From each free triangle an augmenting search of
    ``plain_budget`` triangles comes first, then a ``DROP`` search of ``budget``
    triangles, which pairs it along an augmenting path or drops the nearest triangle whose
    third neighbour is free (two defects fixed by one interior triangle), whichever
    it meets first; failing both, it drops the first triangle it can (the
    defect moves: the partner freed is searched from in turn, at most ``rounds``
    times). A sequence that ends with a triangle still free is undone (``_undo``):
    drops that fix nothing would only add uncovered triangles.

    ``mark`` ((m,) bool, optional): set on every triangle read (``_augment``'s
    ``mark``, and each free triangle looked at), for ``drop_defects``.
    Returns ``(next lca stamp, triangles dropped, writes, n_writes)``: the triangles
    whose state (``mate``, ``active``, ``alive``) the kept sequences changed are among
    ``writes[:n_writes]`` (``n_writes`` -1: not known, a log overflowed).
    """
    n_drop = 0
    log = np.empty(((2 * rounds + 4) * (max(budget, plain_budget) + 16) + 64, 4), np.int64)
    nlog = np.zeros(1, np.int64)
    writes = np.empty(64, np.int64)
    n_w = 0
    seen = np.empty(4, np.int64)
    noguide = _no_guide()
    for t in frees:  # the free triangles, in index order (the list only shrinks)
        if mark is not None:
            mark[t] = True
        if not active[t] or mate[t] >= 0:
            continue
        r = t  # a longer augmenting path first: it leaves nothing uncovered
        nlog[0] = 0
        f0, s, _x = _augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                             plain_budget, OBSERVE, -1, log, nlog, seen, noguide, mark)
        if f0 >= 0:
            writes, n_w = _record_writes(log, nlog, writes, n_w)
            continue
        nlog[0] = 0
        fixed = False
        drops = 0
        known = plain_budget >= budget  # the failed search answers the DROP search
        for it in range(rounds + 1):
            # a DROP search from r: pairs r along an augmenting path or stops at the
            # first drop; after a failed OBSERVE search of at least its budget from
            # the same state neither exists but the drop it saw, if any
            if known:
                found = -1
                extra = seen[2] if seen[2] >= 0 and seen[3] < budget else -1
                if seen[0] >= 0 and seen[1] < budget:  # the search stops there
                    found, s, extra = _augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched,
                                               queue, budget, DROP, -1, log, nlog, seen, noguide, mark)
            else:
                found, s, extra = _augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                                           budget, DROP, -1, log, nlog, seen, noguide, mark)
            if found < 0:
                if extra < 0 or it == rounds:
                    break
                found, s, extra = _augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched,
                                           queue, budget, DROP, extra, log, nlog, seen, noguide, mark)
                if found < 0:  # the same search again: it stops at the same triangle
                    break
            if not alive[found]:
                drops += 1
            if extra < 0:
                fixed = True
                break
            r = extra  # freed by the drop: an augmenting path first, then drop again
            f2, s, _x = _augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                                 budget, OBSERVE, -1, log, nlog, seen, noguide, mark)
            if f2 >= 0:
                fixed = True
                break
            known = True
        if fixed or not _undo(log, nlog, mate, active, alive):
            n_drop += drops
            writes, n_w = _record_writes(log, nlog, writes, n_w)
    return s, n_drop, writes, n_w


@njit(cache=True, nogil=True)
def _centroid_into(tri, pts, t, out):
    """``out``: the centroid of triangle ``t``."""
    for j in range(pts.shape[1]):
        out[j] = (pts[tri[t, 0], j] + pts[tri[t, 1], j] + pts[tri[t, 2], j]) / 3.0


@njit(cache=True, nogil=True)
def _nearest_free_centroid(t, frees, active, mate, tri, pts, goal, weight):
    """``goal[:d]``: the centroid of the free triangle of ``frees`` (other than ``t``)
    nearest to ``t``'s (a few dozen at most: a plain scan); ``goal[d]``: the inverse
    of ``t``'s mean edge length (A*'s steps per unit length, ``_push``)."""
    d = pts.shape[1]
    here = np.empty(d)
    there = np.empty(d)
    _centroid_into(tri, pts, t, here)
    per = 0.0
    for k in range(3):
        e = 0.0
        for j in range(d):
            e += (pts[tri[t, (k + 1) % 3], j] - pts[tri[t, k], j]) ** 2
        per += np.sqrt(e)
    goal[d] = 3.0 * weight / per if per > 0.0 else 0.0
    best = np.inf
    for u in frees:
        if u == t or not active[u] or mate[u] >= 0:
            continue
        _centroid_into(tri, pts, u, there)
        dd = 0.0
        for j in range(d):
            dd += (there[j] - here[j]) ** 2
        if dd < best:
            best = dd
            goal[:d] = there


@njit(cache=True, nogil=True)
def _chain_matching(nb, active, alive, mate, parent, fa, label, stamp, s, queue, frees, tri, pts, guide_weight,
                    chain_cost):
    """Augment through chains of degree-2 triangles; a chain used is left uncovered.

    A chain of degree-2 triangles between two degree-3 ones x, y may serve as a
    matching edge x-y at the price of leaving the chain uncovered: ``CHAIN``
    searches (unbounded) from the triangles still free find the chains as they go;
    none is made when fewer than two are free (an augmenting path joins two free
    triangles: the search from a lone one would explore the whole mesh to fail).
    Afterwards each pair matched across a chain drops its shortest chain between
    them. Returns the next lca stamp.

    Tried in session 10: growing the search from every free triangle at once
    (Edmonds' forest: a path closes where two trees meet, about half way) took
    0.064 / 0.145 s thread CPU at 1.5 M (Hilbert order / Triangle's) against 0.032 /
    0.108 s one root at a time, and its paths ran through chains (5 / 30 boundary
    triangles left uncovered, against none): not kept.

    With the points (``pts`` with a row per vertex of ``tri``; empty: breadth-first)
    each search is best-first towards the centroid of the free triangle nearest to
    its start (``_augment``'s ``guide``): these last defects lie far apart (corners,
    holes), and a breadth-first search from one explores a disc reaching the
    nearest other (150-630 k triangles at 1.5 M).
    """
    m = nb.shape[0]
    hit = False
    nonlog = np.zeros(1, np.int64)
    n = 0
    for t in frees:
        if active[t] and mate[t] < 0:
            n += 1
    # the paths' triangles (their flips logged): the only ones a chain can newly pair
    # (before this phase every partner is a neighbour); rows are written as used
    log = np.empty((m + 64 if n >= 2 else 0, 4), np.int64)
    nlog = np.zeros(1, np.int64)
    touched = np.empty(m + 16 if n >= 2 else 0, np.int32)  # a search touches a triangle once
    guided = n >= 2 and pts.shape[0] > 0
    keys = np.empty(m + 8 if guided else 0)  # the heap's keys, beside queue
    cost = np.empty(m if guided else 0)  # each even triangle's tree path cost (set as pushed)
    goal = np.zeros(pts.shape[1] + 2)
    goal[pts.shape[1] + 1] = chain_cost
    for t in frees:
        if n < 2:
            break
        if active[t] and mate[t] < 0:
            if guided:
                _nearest_free_centroid(t, frees, active, mate, tri, pts, goal, guide_weight)
            f, s, _x = _augment(t, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                                m + 8, CHAIN, -1, log, nlog, nonlog, (tri, pts, goal, keys, cost))
            if f >= 0:
                hit = True
                n -= 2
    if not hit:
        return s
    if nlog[0] <= log.shape[0]:  # the triangles of the paths, in index order, each once
        pairs = np.empty(nlog[0], np.int64)
        for j in range(nlog[0]):
            pairs[j] = log[j, 0]
        pairs = np.unique(pairs)
    else:  # (paths longer than the log: every triangle)
        pairs = np.arange(m)
    for x in pairs:  # matched across a chain: its triangles are left uncovered
        y = mate[x]
        if not active[x] or y < x:
            continue
        direct = False
        for k in range(3):
            if nb[x, k] == y:
                direct = True
        if direct:
            continue
        kk = -1
        best = 0
        for k in range(3):
            e, ln = _chain_end(nb, active, alive, x, k)
            if e == y and (kk < 0 or ln < best):
                kk = k
                best = ln
        prev = x
        cur = nb[x, kk]
        while cur != y:
            nxt = -1
            for j in range(3):
                z = nb[cur, j]
                if z >= 0 and alive[z] and z != prev:
                    nxt = z
            alive[cur] = False
            prev = cur
            cur = nxt
    return s


@njit(cache=True, nogil=True)
def cover_edges_into(nb, alive, mate, is_cov, cdeg, lo, hi):
    """The cover, rows lo..hi: ``is_cov`` on the alive-alive dual edges that are not
    matching edges, ``cdeg`` (int8) each triangle's count of them."""
    for t in range(lo, hi):
        c = 0
        for k in range(3):
            u = nb[t, k]
            on = alive[t] and u >= 0 and alive[u] and mate[t] != u
            is_cov[3 * t + k] = on
            c += on
        cdeg[t] = c


@njit(cache=True, nogil=True)
def _repair(nb, twin, is_cov, cdeg, alive, arc_limit, odd):
    """Drop the shortest cover arc between two free degree-3 triangles (among ``odd``)."""
    # repair: join two free degree-3 triangles by dropping the arc between them
    for t in odd:
        if not (alive[t] and cdeg[t] == 3):
            continue
        best_len = arc_limit + 1
        best_k = -1
        for k0 in range(3):
            prev = t
            cur = nb[t, k0]
            ln = 0
            while cur != t and cdeg[cur] == 2 and ln <= arc_limit:
                nxt = -1
                for k in range(3):
                    if is_cov[3 * cur + k] and nb[cur, k] != prev:
                        nxt = nb[cur, k]
                prev = cur
                cur = nxt
                ln += 1
            if cur != t and cur >= 0 and cdeg[cur] == 3 and ln < best_len:
                best_len = ln
                best_k = k0
        if best_k < 0:
            continue
        cur = nb[t, best_k]
        h = 3 * t + best_k
        is_cov[h] = False
        is_cov[twin[h]] = False
        cdeg[t] -= 1
        cdeg[cur] -= 1
        for _ in range(best_len):  # cur: an inner triangle of the arc, one cover edge left
            hh = -1
            for k in range(3):
                if is_cov[3 * cur + k]:
                    hh = 3 * cur + k
            nxt = twin[hh] // 3
            is_cov[hh] = False
            is_cov[twin[hh]] = False
            cdeg[cur] -= 1
            cdeg[nxt] -= 1
            alive[cur] = False
            cur = nxt



@njit(cache=True, nogil=True)
def _final_peel(nb, twin, is_cov, cdeg, alive, odd):
    """Peel what still has cover degree other than 2 (from ``odd``, the triangles
    that had it before the repair, which only gives such triangles degree 2 or kills
    them)."""
    m = cdeg.shape[0]
    stack = np.empty(m + 1, np.int64)
    # final peel: cover degree must be exactly 2
    top = 0
    for t in odd:
        if alive[t] and cdeg[t] != 2:
            stack[top] = t
            top += 1
    while top > 0:
        top -= 1
        t = stack[top]
        if not alive[t] or cdeg[t] == 2:
            continue
        alive[t] = False
        for k in range(3):
            h = 3 * t + k
            if is_cov[h]:
                u = nb[t, k]
                is_cov[h] = False
                is_cov[twin[h]] = False
                cdeg[u] -= 1
                if alive[u] and cdeg[u] != 2:
                    stack[top] = u
                    top += 1
        cdeg[t] = 0


@njit(cache=True, nogil=True)
def smooth_cells(nb, cell, quad, passes):
    """Move a triangle into the cell of two of its neighbours, so that few triangles
    have two dual edges across cell borders (each triangle has one matching edge,
    and only a matched edge may cross a border); a moved triangle takes the
    neighbour's quadtree coordinates ``quad`` too. In place, returns the moves."""
    m = cell.shape[0]
    moved = 0
    for _ in range(passes):
        changed = 0
        for t in range(m):
            c = cell[t]
            for k in range(3):
                u = nb[t, k]
                if u < 0 or cell[u] == c:
                    continue
                cnt = 0
                for j in range(3):
                    w = nb[t, j]
                    if w >= 0 and cell[w] == cell[u]:
                        cnt += 1
                if cnt >= 2:
                    cell[t] = cell[u]
                    quad[t] = quad[u]
                    changed += 1
                    break
        moved += changed
        if changed == 0:
            break
    return moved


@njit(cache=True, nogil=True)
def _pin_borders(nb, alive, deg, cell, mate, m):
    """Match the dual edges across cell borders (both triangles of degree 3, free):
    the cover's cycles then stay inside the cells. Returns the pairs pinned."""
    n = 0
    for t in range(m):
        if not (alive[t] and deg[t] == 3) or mate[t] >= 0:
            continue
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and alive[u] and deg[u] == 3 and mate[u] < 0 and cell[u] != cell[t]:
                mate[t] = u
                mate[u] = t
                n += 1
                break
    return n


@njit(cache=True, nogil=True)
def cut_cell_borders(nb, cell):
    """Remove from the dual graph (in place) the edges of triangles that could not
    keep their cycle inside their cell: a triangle with two or three dual edges
    across cell borders (a junction of cells; it has one matching edge), or with
    two neighbours only and one of them across a border (both its edges would be
    cover edges), and, as the peel does, every edge of a triangle left with one
    neighbour. A worklist, O(m): afterwards every border edge joins two triangles
    of degree 3 with one border edge each. A triangle cut off is left uncovered
    (peeled) and joined later (an absorbing swap, a fan or its incenter).
    Returns the number of edges cut."""
    m = nb.shape[0]
    n_cut = 0
    stack = np.empty(m + 6 * m + 8, np.int64)  # m, then two pushes per edge cut
    top = 0
    for t in range(m):
        stack[top] = t
        top += 1
    while top > 0:
        top -= 1
        t = stack[top]
        nbrd = 0
        d = 0
        for k in range(3):
            u = nb[t, k]
            if u >= 0:
                d += 1
                if cell[u] != cell[t]:
                    nbrd += 1
        if d == 0 or (d == 3 and nbrd <= 1) or (d == 2 and nbrd == 0):
            continue
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and (d == 1 or cell[u] != cell[t]):
                nb[t, k] = -1
                for j in range(3):
                    if nb[u, j] == t:
                        nb[u, j] = -1
                n_cut += 1
                stack[top] = u
                top += 1
        stack[top] = t  # left with one neighbour: peeled in turn
        top += 1
    return n_cut


@njit(cache=True, nogil=True)
def _cell_neighbors(nb, cell):
    """``nb`` without the dual edges across cell borders."""
    m = nb.shape[0]
    out = nb.copy()
    for t in range(m):
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and cell[u] != cell[t]:
                out[t, k] = -1
    return out


@njit(cache=True, nogil=True)
def neighbors_into(twin, nb, lo, hi):
    """``nb[t, k]``: the triangle across side k of t (-1 on the boundary), rows lo..hi."""
    for t in range(lo, hi):
        for k in range(3):
            g = twin[3 * t + k]
            nb[t, k] = g // 3 if g >= 0 else -1


@njit(cache=True, nogil=True)
def match_half(nb, active, side, half, rule, good, online, budget, mate, parent, fa, label, stamp):
    """Match the degree-3 triangles of one half (``side[t] == half``) among themselves.

    The greedy (``_greedy_matching``) sweeps the half breadth-first (with ``online``
    searches; ``online == 0``: in triangle order, as before session 6), then an
    augmenting search of ``budget`` triangles starts from each triangle still free.
    Everything stays inside the half: the two halves of a split share no triangle
    this writes, so they run on two threads side by side (the arrays are shared), and
    the result does not depend on the number of threads. The parity defects are left
    to ``finish_matching``: fixed inside the halves on two threads (tried) they cost
    more, as the defects left at the split then go to chains. Returns the next lca
    stamp.
    """
    m = nb.shape[0]
    act = np.zeros(m, np.bool_)
    for t in range(m):
        if side[t] == half:  # (zeros elsewhere: the other half's pages never written)
            act[t] = active[t]
    queue = np.empty(max(online, budget) + 16, np.int32)  # a search enqueues what it touches
    if online > 0:  # breadth-first even in a local row order (session 10, 1.5 M in
        # Hilbert order: sweeping rows left 13,152 cycles instead of 11,954 and cost
        # more in finish_matching than the breadth-first order saves)
        order = _bfs_order(nb, side, half)
    else:
        n = 0
        for t in range(m):
            if act[t]:
                n += 1
        order = np.empty(n, np.int32)
        n = 0
        for t in range(m):
            if act[t]:
                order[n] = t
                n += 1
    s = _greedy_matching(nb, act, m, rule, good, order, online, parent, fa, label, stamp, queue, mate)
    touched = np.empty(budget + 8, np.int32)
    nolog = np.empty((0, 4), np.int64)
    nonlog = np.zeros(1, np.int64)
    noguide = _no_guide()
    for i in range(order.shape[0]):
        t = order[i]
        if act[t] and mate[t] < 0:
            _f, s, _x = _augment(t, nb, act, act, mate, parent, fa, label, stamp, s, touched, queue, budget,
                                 PLAIN, -1, nolog, nonlog, nonlog, noguide)
    return s


@njit(cache=True, nogil=True)
def _augment_every_free(nb, active, alive, mate, parent, fa, label, stamp, s, queue, budget):
    """A plain search of at most ``budget`` triangles (``_augment``) from every active
    triangle still unmatched, in index order; returns the next lca stamp."""
    touched = np.empty(budget + 8, np.int32)
    nolog = np.empty((0, 4), np.int64)
    nonlog = np.zeros(1, np.int64)
    noguide = _no_guide()
    for t in range(nb.shape[0]):
        if active[t] and mate[t] < 0:
            _f, s, _x = _augment(t, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue, budget,
                                 PLAIN, -1, nolog, nonlog, nonlog, noguide)
    return s


@njit(cache=True, nogil=True)
def match_cells(nb, active, alive, deg, cell, rule, good, online, budget, mate, parent, fa, label, stamp):
    """The matching inside quadtree cells (``cycle_cover(..., cell_size=)``): every dual
    edge across a cell border is matched first (``_pin_borders``), so that the cover's
    cycles stay inside the cells; then the greedy and its searches run inside each cell
    (bounded by its size). Returns the next lca stamp."""
    m = nb.shape[0]
    _pin_borders(nb, alive, deg, cell, mate, m)
    nbc = _cell_neighbors(nb, cell)
    inner = active & (mate < 0)  # the pinned pairs stay out of the cell's searches
    one = np.zeros(m, np.int8)
    order = _bfs_order(nbc, one, 0) if online > 0 else np.arange(m).astype(np.int32)
    queue = np.empty(m + 8, np.int32)
    s = _greedy_matching(nbc, inner, m, rule, good, order, online, parent, fa, label, stamp, queue, mate)
    return _augment_every_free(nbc, inner, alive, mate, parent, fa, label, stamp, s, queue, budget)


@njit(cache=True, nogil=True)
def search_frees(nb, active, alive, mate, parent, fa, label, stamp, s, budget):
    """The first phase of ``finish_matching``: the triangles still free (index order)
    and a search of ``budget`` triangles over the whole graph from each (those left at
    the split between the halves, mostly: the join across it). Returns ``(frees,
    next lca stamp)``; ``frees`` lists them all, matched since or not."""
    m = nb.shape[0]
    n = 0
    for t in range(m):
        if active[t] and mate[t] < 0:
            n += 1
    frees = np.empty(n, np.int64)
    n = 0
    for t in range(m):
        if active[t] and mate[t] < 0:
            frees[n] = t
            n += 1
    queue = np.empty(budget + 16, np.int32)
    touched = np.empty(budget + 8, np.int32)
    nolog = np.empty((0, 4), np.int64)
    nonlog = np.zeros(1, np.int64)
    noguide = _no_guide()
    for t in frees:
        if mate[t] < 0:
            _f, s, _x = _augment(t, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue, budget,
                                 PLAIN, -1, nolog, nonlog, nonlog, noguide)
    return frees, s


@njit(cache=True, nogil=True)
def drop_defects(nb, active, alive, mate, parent, fa, label, stamp, s, plain_budget, drop_budget, drop_rounds,
                 frees, mark):
    """``_drop_matching`` from the free triangles ``frees`` (the second phase of
    ``finish_matching``); ``mark`` ((m,) bool, or empty: not kept) is set on every
    triangle read. Returns ``(next lca stamp, dropped, writes, n_writes)``.

    Two runs over two parts of the free list, side by side (``cycle_cover``: the
    second on a copy of ``mate``, ``active``, ``alive`` with its own search arrays),
    give the serial run's state exactly when the second read no triangle the first
    wrote (``writes_meet``): its writes are then copied over (``copy_writes``); else
    the second part runs again after the first."""
    big = max(plain_budget, drop_budget)
    touched = np.empty(big + 16, np.int32)
    queue = np.empty(big + 16, np.int32)
    if mark.shape[0] > 0:
        s, n_drop, writes, n_w = _drop_matching(nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                                                plain_budget, drop_budget, drop_rounds, frees, mark)
    else:
        s, n_drop, writes, n_w = _drop_matching(nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                                                plain_budget, drop_budget, drop_rounds, frees)
    return s, n_drop, writes, n_w


@njit(cache=True, nogil=True)
def writes_meet(mark, writes, n_w, other, n_other):
    """Whether the triangles ``writes[:n_w]`` (one run's writes) meet what another
    read (``mark``) or wrote (``other[:n_other]``): True if either count is -1."""
    if n_w < 0 or n_other < 0:
        return True
    for j in range(n_other):
        mark[other[j]] = True
    for j in range(n_w):
        if mark[writes[j]]:
            return True
    return False


@njit(cache=True, nogil=True)
def copy_writes(writes, n_w, mate, active, alive, mate_to, active_to, alive_to):
    """The state of the triangles ``writes[:n_w]`` copied into the ``_to`` arrays."""
    for j in range(n_w):
        t = writes[j]
        mate_to[t] = mate[t]
        active_to[t] = active[t]
        alive_to[t] = alive[t]


@njit(cache=True, nogil=True)
def copy_state_into(mate, active, alive, mate_to, active_to, alive_to, lo, hi):
    """``mate``, ``active``, ``alive`` rows lo..hi copied into the ``_to`` arrays."""
    for t in range(lo, hi):
        mate_to[t] = mate[t]
        active_to[t] = active[t]
        alive_to[t] = alive[t]


@njit(cache=True, nogil=True)
def chain_frees(nb, active, alive, mate, parent, fa, label, stamp, s, frees, tri, pts, guide_weight, chain_cost):
    """The last phase of ``finish_matching``: ``_chain_matching`` from ``frees``.
    Returns the number of triangles still free."""
    queue = np.empty(nb.shape[0] + 8, np.int32)
    _chain_matching(nb, active, alive, mate, parent, fa, label, stamp, s, queue, frees, tri, pts, guide_weight,
                    chain_cost)
    n_free = 0
    for t in frees:
        if active[t] and mate[t] < 0:
            n_free += 1
    return n_free


@njit(cache=True, nogil=True)
def finish_matching(nb, active, alive, mate, parent, fa, label, stamp, s, budget, plain_budget, drop_budget,
                    drop_rounds, tri, pts, guide_weight, chain_cost):
    """From the matchings of the halves (or cells) to the matching the cover complements.

    Searches of ``budget`` triangles over the whole graph from each triangle still
    free (``search_frees``); the parity defects (``_drop_matching``: searches of
    ``plain_budget``, then of ``drop_budget`` triangles, skipped if ``drop_rounds <
    0``), then chains (``_chain_matching``, best-first towards the nearest free
    triangle when ``pts``, the points of ``tri``, has rows). The free triangles are
    listed once (the phases only match them; a drop sequence that frees another
    either matches it or is undone). Then ``cover_edges_into`` (rows on threads) and
    ``settle_cover``. Serial; ``cycle_cover`` runs the drop phase in two parts side
    by side (``drop_defects``), with the same result.

    Returns ``(n_free_after_matching, n_dropped)``.
    """
    frees, s = search_frees(nb, active, alive, mate, parent, fa, label, stamp, s, budget)
    n_drop = 0
    if drop_rounds >= 0:
        s, n_drop, _w, _n = drop_defects(nb, active, alive, mate, parent, fa, label, stamp, s, plain_budget,
                                         drop_budget, drop_rounds, frees, np.zeros(0, np.bool_))
    n_free = chain_frees(nb, active, alive, mate, parent, fa, label, stamp, s, frees, tri, pts, guide_weight,
                         chain_cost)
    return n_free, n_drop


@njit(cache=True, nogil=True)
def settle_cover(nb, twin, is_cov, cdeg, alive, arc_limit):
    """After ``cover_edges_into``: a degree-3 triangle still free is repaired by dropping
    the shortest cover arc from it to another (``_repair``), and whatever still has
    cover degree other than 2 is peeled (``_final_peel``). Returns the uncovered count."""
    m = cdeg.shape[0]
    n = 0
    for t in range(m):
        if alive[t] and cdeg[t] != 2:
            n += 1
    odd = np.empty(n, np.int64)
    n = 0
    for t in range(m):
        if alive[t] and cdeg[t] != 2:
            odd[n] = t
            n += 1
    _repair(nb, twin, is_cov, cdeg, alive, arc_limit, odd)
    _final_peel(nb, twin, is_cov, cdeg, alive, odd)
    n_unc = 0
    for t in range(m):
        if cdeg[t] != 2:
            n_unc += 1
    return n_unc


@njit(cache=True, nogil=True)
def edge_classes(qa, qb, out):
    """``_thm24_kernels.edge_class`` of each pair of packed quadtree coordinates."""
    for i in range(qa.shape[0]):
        out[i] = _edge_class(qa[i], qb[i])


@njit(cache=True, nogil=True)
def _cover_next(twin, is_cov, cur, prev):
    """The triangle after ``cur`` on its cover cycle, come to from ``prev`` (-1: none)."""
    nxt = -1
    for k in range(3):
        h = 3 * cur + k
        if is_cov[h] and twin[h] // 3 != prev:
            nxt = twin[h] // 3
    return nxt


@njit(cache=True, nogil=True)
def cycle_ids(twin, is_cov, m):
    """Cycle id of each covered triangle (-1 if uncovered) and the number of cycles."""
    cyc = np.full(m, -1, np.int64)
    n = 0
    for s in range(m):
        if cyc[s] >= 0:
            continue
        first = -1
        for k in range(3):
            if is_cov[3 * s + k]:
                first = k
                break
        if first < 0:
            continue
        cyc[s] = n
        prev = s
        cur = twin[3 * s + first] // 3
        while cur != s:
            cyc[cur] = n
            prev, cur = cur, _cover_next(twin, is_cov, cur, prev)
            if cur < 0:
                break
        n += 1
    return cyc, n


@njit(cache=True, nogil=True)
def star_prefilter_into(tri, is_cov, vh, skip, lo, hi):
    """For ``rotate_stars``, rows lo..hi: ``vh[v]`` a half-edge leaving each vertex,
    ``skip[v]`` set where v cannot be rotated: it is the apex (the corner opposite
    the matched, non-cover edge) of some triangle, or a corner of an uncovered one.
    Elsewhere every triangle around v has its matched edge at v, so v's spokes
    alternate matched / cover. Two row ranges may run side by side: ``skip`` is only
    ever set, and any half-edge leaving v serves as ``vh[v]``."""
    for t in range(lo, hi):
        cov = is_cov[3 * t] or is_cov[3 * t + 1] or is_cov[3 * t + 2]
        for k in range(3):
            vh[tri[t, k]] = 3 * t + k
            if not cov:
                skip[tri[t, k]] = True
            elif not is_cov[3 * t + k]:
                skip[tri[t, (k + 2) % 3]] = True


@njit(cache=True, nogil=True, inline="always")
def _star_spokes(twin, is_cov, cyc, h0, cell, spokes):
    """The spokes around the vertex ``h0`` leaves (``spokes[:d]``, the half-edges of
    the edges at v, one per triangle around it), d if they alternate matched / cover
    around an interior vertex of even degree 4..30 whose triangles are covered (and
    in one cell if ``cell`` has m rows), else -1."""
    use_cell = cell.shape[0] == cyc.shape[0]
    d = 0
    h = h0
    while True:  # h leaves v in triangle t; spoke p = edge (w, v) of t
        t = h // 3
        p = 3 * t + (h - 3 * t + 2) % 3
        q = twin[p]
        if q < 0 or d >= 32 or cyc[t] < 0 or (use_cell and cell[t] != cell[h0 // 3]):
            return -1
        if d > 0 and is_cov[p] == is_cov[spokes[d - 1]]:
            return -1  # not alternating
        spokes[d] = p
        d += 1
        h = q
        if h == h0:
            break
    if d < 4 or d % 2 == 1:
        return -1
    return d


@njit(cache=True, nogil=True)
def star_candidates_into(twin, is_cov, cyc, vh, skip, cell, cand, lo, hi):
    """``cand[v]`` for vertices lo..hi: v not skipped (``star_prefilter_into``), its
    spokes alternate (``_star_spokes``) and its cover spokes lie on distinct cycles.
    Read-only but ``cand``: two vertex ranges run side by side. The rotations
    themselves (``rotate_candidates``) only ever remove candidates."""
    spokes = np.empty(32, np.int64)
    for v in range(lo, hi):
        cand[v] = False
        h0 = vh[v]
        if h0 < 0 or skip[v]:
            continue
        d = _star_spokes(twin, is_cov, cyc, h0, cell, spokes)
        if d < 0:
            continue
        ok = True
        for i in range(d):
            if is_cov[spokes[i]]:
                for j in range(i):
                    if is_cov[spokes[j]] and cyc[spokes[j] // 3] == cyc[spokes[i] // 3]:
                        ok = False
        cand[v] = ok


@njit(cache=True, nogil=True)
def rotate_candidates(twin, is_cov, cyc, n_cyc, vh, cand, cell):
    """Rotate the candidate vertices (``star_candidates_into``) in vertex order, each
    checked again against the rotations before it (alternation, distinct merged
    cycles); then renumber ``cyc``. Returns the number of cycles merged away."""
    table = np.empty(max(n_cyc, 1), np.int64)
    merged = rotate_candidates_table(twin, is_cov, cyc, n_cyc, vh, cand, cell, table)
    if merged > 0:
        renumber_cycles_into(cyc, table, 0, cyc.shape[0])
    return merged


@njit(cache=True, nogil=True)
def renumber_cycles_into(cyc, table, lo, hi):
    """``cyc[t] = table[cyc[t]]`` for the covered triangles of rows lo..hi."""
    for t in range(lo, hi):
        if cyc[t] >= 0:
            cyc[t] = table[cyc[t]]


@njit(cache=True, nogil=True)
def rotate_candidates_table(twin, is_cov, cyc, n_cyc, vh, cand, cell, table):
    """``rotate_candidates`` but the renumbering: ``table[c]`` (``n_cyc`` rows) is each
    old cycle id's new one (``renumber_cycles_into``: rows on threads), ``cyc`` is
    left as it was. Returns the number of cycles merged away."""
    uf = np.arange(max(n_cyc, 1))
    spokes = np.empty(32, np.int64)
    roots = np.empty(16, np.int64)
    merged = 0
    for v in range(cand.shape[0]):
        if not cand[v]:
            continue
        d = _star_spokes(twin, is_cov, cyc, vh[v], cell, spokes)
        if d < 0:
            continue
        nr = 0
        ok = True
        for i in range(d):
            if is_cov[spokes[i]]:
                r = _find(uf, cyc[spokes[i] // 3])
                for j in range(nr):
                    if roots[j] == r:
                        ok = False
                roots[nr] = r
                nr += 1
        if not ok:
            continue
        for i in range(d):
            p = spokes[i]
            c = not is_cov[p]
            is_cov[p] = c
            is_cov[twin[p]] = c
        for j in range(1, nr):
            uf[_find(uf, roots[j])] = _find(uf, roots[0])
        merged += nr - 1
    # cycle ids after the merges: the union-find roots, renumbered
    if merged > 0:
        new_id = np.full(max(n_cyc, 1), -1, np.int64)
        n_new = 0
        for c in range(n_cyc):
            r = _find(uf, c)
            if new_id[r] < 0:
                new_id[r] = n_new
                n_new += 1
        for c in range(n_cyc):  # each old id's new one: no find per row
            table[c] = new_id[_find(uf, c)]
    return merged


@njit(cache=True, nogil=True)
def rotate_stars(tri, twin, is_cov, cyc, n_cyc, n_points, cell):
    """Merge cover cycles for free by re-matching around vertices.

    Around an interior vertex of even degree 2k whose k spokes alternate matched /
    cover (the dual edges crossing the spokes), swapping the two roles keeps every
    triangle at cover degree 2 and the matching perfect; if the k cover spokes lie on
    k different cycles, the k cycles become one (remove one edge from each: k paths;
    the new spokes chain them around the vertex). No geometry changes.

    With cells (``cell`` (m,) int64; empty: none) only vertices whose triangles all
    lie in one cell are rotated: cycles are merged across cells by the joins, finest
    cells first.

    Modifies ``is_cov`` and ``cyc`` (renumbered 0..n_cyc - merged - 1) in place;
    returns the number of cycles merged away. One pass (on the 16k corpus and at
    1.5 M triangles a second merged no cycle). The three steps run on two threads
    from ``cycle_cover`` (``star_prefilter_into``, ``star_candidates_into``, then
    ``rotate_candidates``); this is them in one call.
    """
    vh = np.full(n_points, -1, np.int32)
    skip = np.zeros(n_points, np.bool_)
    cand = np.empty(n_points, np.bool_)
    star_prefilter_into(tri, is_cov, vh, skip, 0, tri.shape[0])
    star_candidates_into(twin, is_cov, cyc, vh, skip, cell, cand, 0, n_points)
    return rotate_candidates(twin, is_cov, cyc, n_cyc, vh, cand, cell)


@njit(cache=True, nogil=True)
def _cover_next_nb(nb, is_cov, cur, prev):
    """:func:`_cover_next` read off the neighbour rows (``nb``, int32: 12 bytes a row
    against the twins' 24, no division)."""
    nxt = -1
    for k in range(3):
        if is_cov[3 * cur + k] and nb[cur, k] != prev:
            nxt = nb[cur, k]
    return nxt


@njit(cache=True, nogil=True)
def cycle_segments_into(nb, is_cov, side, half, cyc, smin, send):
    """The cover cycles cut at the split into runs inside one half (``side == half``).

    Triangles are taken in index order; each one not yet on a run starts one and walks
    its cycle both ways while it stays in the half. ``cyc[t]``: the run's number (in
    this half, in order of the runs' first triangles), ``smin[i]`` its smallest
    triangle, ``send[i, 0:2]`` the triangles of the other half its two ends lead to
    (-1, -1: a whole cycle inside the half). ``nb``: the neighbour rows
    (``neighbors_into``). The two halves write disjoint triangles
    of ``cyc``: they run side by side, and ``link_segments`` joins the runs.
    Returns the number of runs.
    """
    m = cyc.shape[0]
    n = 0
    for s in range(m):
        if side[s] != half or cyc[s] >= 0:
            continue
        k1 = -1
        k2 = -1
        for k in range(3):
            if is_cov[3 * s + k]:
                if k1 < 0:
                    k1 = k
                else:
                    k2 = k
        if k1 < 0:
            continue
        cyc[s] = n
        lo = s
        send[n, 0] = -1
        send[n, 1] = -1
        for d in range(2):
            prev = s
            cur = nb[s, k1 if d == 0 else k2]
            while cur >= 0 and cur != s and side[cur] == half:
                cyc[cur] = n
                lo = min(lo, cur)
                prev, cur = cur, _cover_next_nb(nb, is_cov, cur, prev)
            if cur == s:  # closed inside the half
                break
            if cur < 0:  # a broken chain (a surface whose two cover edges lead to one
                break  # neighbour): ends there, as in ``cycle_ids``
            send[n, d] = cur
        smin[n] = lo
        n += 1
    return n


@njit(cache=True, nogil=True)
def link_segments(cyc, side, n0, smin0, send0, n1, smin1, send1):
    """Cycle id of each run of ``cycle_segments_into`` (runs of half 0 first, then of
    half 1): runs whose ends meet are one cycle, and cycles are numbered in order of
    their smallest triangle, as ``cycle_ids`` numbers them. Returns ``(ids, n)``."""
    total = n0 + n1
    uf = np.arange(max(total, 1))
    for i in range(total):
        for d in range(2):
            o = send0[i, d] if i < n0 else send1[i - n0, d]
            if o >= 0:
                j = cyc[o] + (n0 if side[o] == 1 else 0)
                a = _find(uf, i)
                b = _find(uf, j)
                if a != b:
                    uf[a] = b
    low = np.full(max(total, 1), -1, np.int64)  # each root: its cycle's smallest triangle
    for i in range(total):
        r = _find(uf, i)
        lo = smin0[i] if i < n0 else smin1[i - n0]
        if low[r] < 0 or lo < low[r]:
            low[r] = lo
    roots = np.empty(total, np.int64)
    n = 0
    for i in range(total):
        if uf[i] == i:
            roots[n] = i
            n += 1
    order = np.argsort(low[roots[:n]])
    rank = np.empty(max(total, 1), np.int64)
    for j in range(n):
        rank[roots[order[j]]] = j
    ids = np.empty(max(total, 1), np.int64)
    for i in range(total):
        ids[i] = rank[_find(uf, i)]
    return ids, n


@njit(cache=True, nogil=True)
def relabel_segments_into(cyc, side, n0, ids, lo, hi):
    """``cyc[t]``: from run number (per half) to cycle id, rows lo..hi."""
    for t in range(lo, hi):
        c = cyc[t]
        if c >= 0:
            cyc[t] = ids[c + (n0 if side[t] == 1 else 0)]
