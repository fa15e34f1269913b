"""Merging cover cycles by re-colouring a few mesh vertices (numba kernels).

A cycle cover of a triangle mesh's dual graph draws closed curves through the
triangles; each mesh edge is crossed (a cover edge) or not (the triangle's one
matching edge). In the plane the crossed edges are exactly those whose end points
lie on different sides of the curves: colour each vertex inside / outside and a
triangle is covered iff it is *bichromatic* (a triangle has then exactly one
monochromatic edge, its matching edge), uncovered iff monochromatic; the cycles are
the borders of the inside colour's components (Arkin, Held, Mitchell, Skiena,
*Hamiltonian triangulations for fast rendering*, 1996: a triangulation has a
Hamiltonian dual path iff its vertices split into such a tree and forest).

So flipping the colour of a set ``S`` of interior vertices gives another cover as
long as no triangle around ``S`` becomes monochromatic; it swaps the cover along
the dual cycle around ``S`` (an alternating cycle of the matching; a single vertex
of even degree with alternating spokes is ``_cover_kernels.rotate_candidates``'s
rotation). Nothing in the mesh changes. :func:`recolour_merges` looks, around every
small cycle (and uncovered triangle) that has no non-cover edge to another node whose
join keeps the local quality rule (``good``), for a set of up to three vertices
whose re-colouring leaves fewer nodes: that node then needs no join of its own (on
Triangle's ``la`` such nodes were the stars of single interior vertices, each joined
by a split that halves the corner at the star's centre). Everything here reads and
writes the cover in place; callers gate it by size (``cycle_cover.RECOLOUR_BELOW``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["recolour_merges", "vertex_colours"]


@njit(cache=True, nogil=True)
def _crossed(twin, is_cov, h):
    """Is the mesh edge of half-edge ``h`` crossed by the cover (a dual cover edge)?"""
    return twin[h] >= 0 and is_cov[h]


@njit(cache=True, nogil=True)
def vertex_colours(tri, twin, is_cov, vstart, vtri, col):
    """Colour the vertices (``col``: (n,) int8, filled) so that exactly the crossed
    edges join two colours, one breadth-first search per connected piece.

    ``vstart`` (n + 1,), ``vtri`` (3 m,): the triangles around each vertex (CSR).
    Returns False if no such colouring exists (the cover's curves do not separate,
    e.g. on a surface of higher genus): then nothing may be re-coloured.
    """
    n = col.shape[0]
    for v in range(n):
        col[v] = -1
    stack = np.empty(n, np.int64)
    for s in range(n):
        if col[s] >= 0 or vstart[s] == vstart[s + 1]:
            continue
        col[s] = 0
        stack[0] = s
        top = 1
        while top > 0:
            top -= 1
            v = stack[top]
            for i in range(vstart[v], vstart[v + 1]):
                t = vtri[i]
                for k in range(3):
                    if tri[t, k] != v:
                        continue
                    for e in (3 * t + k, 3 * t + (k + 2) % 3):  # the two edges of t at v
                        w = tri[t, (k + 1) % 3] if e == 3 * t + k else tri[t, (k + 2) % 3]
                        c = col[v] ^ (1 if _crossed(twin, is_cov, e) else 0)
                        if col[w] < 0:
                            col[w] = c
                            stack[top] = w
                            top += 1
    m = tri.shape[0]
    for t in range(m):
        for k in range(3):
            if (col[tri[t, k]] != col[tri[t, (k + 1) % 3]]) != _crossed(twin, is_cov, 3 * t + k):
                return False
    return True


@njit(cache=True, nogil=True)
def _exit(twin, is_cov, x, came):
    """The cover half-edge of ``x`` other than ``came`` (the one the walk entered by),
    or -1 if ``x`` does not have exactly two cover edges."""
    out = -1
    n_cov = 0
    for k in range(3):
        h = 3 * x + k
        if _crossed(twin, is_cov, h):
            n_cov += 1
            if h != came and out < 0:
                out = h
    return out if n_cov == 2 else -1


@njit(cache=True, nogil=True)
def _walk_stamp(twin, is_cov, t0, stamp, value, cyc, new_id, pos):
    """Walk the cover cycle through ``t0``, setting ``stamp`` to ``value`` (and, with
    ``new_id >= 0``, ``cyc`` to it and ``pos`` to the step count) on every triangle;
    returns its length, or -1 if some triangle on the way does not have exactly two
    cover edges."""
    x = t0
    came = -1  # the half-edge of x the walk entered by
    n = 0
    while True:
        stamp[x] = value
        if new_id >= 0:
            cyc[x] = new_id
            pos[x] = n
        n += 1
        out = _exit(twin, is_cov, x, came)
        if out < 0:
            return -1
        g = twin[out]
        x = g // 3
        came = g
        if x == t0:
            return n


@njit(cache=True, nogil=True)
def _walk_jump(twin, is_cov, t0, stamp, value, tsmark, mark, ts, nt, cyc, pos, plen):
    """Walk the *new* cover cycle through ``t0`` (a triangle around the re-coloured set,
    ``tsmark == mark``), stamping the set's triangles it passes with ``value``.

    Away from the set the cover is unchanged: a step out of it enters an old cycle
    (``cyc``, ``pos`` along it, ``plen`` its length) and follows it to the next of the
    set's triangles on it, found by position, not walked. Returns the new cycle's
    length, or -1 if a triangle of the set does not have exactly two cover edges.
    """
    x = t0
    came = -1
    n = 0
    while True:
        stamp[x] = value
        out = _exit(twin, is_cov, x, came)
        if out < 0:
            return -1
        came = twin[out]
        n += 1
        if tsmark[came // 3] != mark:  # (off the set: along the old cycle to its next triangle)
            came, arc = _jump(twin, tsmark, mark, ts, nt, cyc, pos, plen, x, came // 3)
            if came < 0:
                return -1
            n += arc
        x = came // 3
        if x == t0:
            return n


@njit(cache=True, nogil=True)
def _jump(twin, tsmark, mark, ts, nt, cyc, pos, plen, x, y):
    """From the set's triangle ``x`` into ``y`` off the set: the edge x-y is not at the
    set, so it was a cover edge and x was on y's old cycle; that cycle is followed (by
    position) to the next of the set's triangles ``ts[:nt]`` on it. Returns the
    half-edge of that triangle the walk enters by and the triangles passed on the way
    (-1, 0 if none is found)."""
    c = cyc[y]
    ln = plen[c]
    py = pos[y]
    d = 1 if (py - pos[x]) % ln == 1 else -1
    best = -1
    bd = ln + 1
    for q in range(nt):
        z = ts[q]
        if cyc[z] == c:
            dz = ((pos[z] - py) * d) % ln
            if 0 < dz < bd:
                bd = dz
                best = z
    if best < 0:
        return -1, 0
    pw = (pos[best] - d) % ln  # (the triangle before it: off the set, its edge unchanged)
    for k in range(3):
        h = 3 * best + k
        w = twin[h]
        if w >= 0 and tsmark[w // 3] != mark and cyc[w // 3] == c and pos[w // 3] == pw:
            return h, bd
    return -1, 0


@njit(cache=True, nogil=True)
def _has_good_edge(twin, is_cov, good, t0, stamp, value):
    """Has the cycle through ``t0`` (every triangle stamped ``value``) a good non-cover
    edge to a triangle that is not on it?"""
    x = t0
    came = -1
    while True:
        out = -1
        for k in range(3):
            h = 3 * x + k
            g = twin[h]
            if g < 0:
                continue
            if is_cov[h]:
                if h != came and out < 0:
                    out = h
            elif good[h] and stamp[g // 3] != value:
                return True
        came = twin[out]
        x = came // 3
        if x == t0:
            return False


@njit(cache=True, nogil=True)
def _try_set(tri, twin, is_cov, cyc, pos, plen, col, vstart, vtri, good, in_s, sv, ns, ts, saved, stamp, tsmark,
             starts, clock, shift, target, small):
    """Re-colour the ``ns`` vertices ``sv`` if that leaves every triangle around them
    covered and fewer nodes (cycles + uncovered triangles) among them, or, with
    ``shift`` (> 0), at most ``shift - 1`` more nodes, each with a good non-cover edge to
    another node, the node of triangle ``target`` among them and covered (the target
    itself moved, not a neighbour). A new cycle longer than ``small`` is taken to have
    a good edge (not walked: a check costs what the set's triangles do). Returns
    ``(nodes merged away, taken, clock, new cycles)``: not taken, the cover is as
    before; taken, ``starts[:new cycles]`` holds one triangle of each new cycle.
    """
    for i in range(ns):
        in_s[sv[i]] = True
    nt = 0
    ok = True
    for i in range(ns):
        v = sv[i]
        for j in range(vstart[v], vstart[v + 1]):
            t = vtri[j]
            seen = False
            for q in range(nt):
                if ts[q] == t:
                    seen = True
            if not seen:
                ts[nt] = t
                nt += 1
    # triangles left monochromatic (uncovered) around S: with ``shift`` at most as many
    # as before, else none
    n_mono = 0
    n_mono_old = 0
    for q in range(nt):
        t = ts[q]
        c0 = col[tri[t, 0]] ^ (1 if in_s[tri[t, 0]] else 0)
        c1 = col[tri[t, 1]] ^ (1 if in_s[tri[t, 1]] else 0)
        c2 = col[tri[t, 2]] ^ (1 if in_s[tri[t, 2]] else 0)
        if c0 == c1 and c1 == c2:
            n_mono += 1
        if cyc[t] < 0:
            n_mono_old += 1
    if n_mono > (n_mono_old if shift > 0 else 0):
        ok = False
    merged = 0
    taken = False
    n_start = 0
    if ok:
        # old nodes among the triangles around S; then the cover re-written there
        n_old = 0
        for q in range(nt):
            t = ts[q]
            if cyc[t] < 0:
                n_old += 1
            else:
                new = True
                for r in range(q):
                    if cyc[ts[r]] == cyc[t]:
                        new = False
                if new:
                    n_old += 1
        for q in range(nt):
            t = ts[q]
            for k in range(3):
                h = 3 * t + k
                saved[3 * q + k] = is_cov[h]
                a = col[tri[t, k]] ^ (1 if in_s[tri[t, k]] else 0)
                b = col[tri[t, (k + 1) % 3]] ^ (1 if in_s[tri[t, (k + 1) % 3]] else 0)
                is_cov[h] = twin[h] >= 0 and a != b
        # (an edge at a vertex of S has both its triangles around S: twins agree);
        # each new cycle through them walked with a stamp of its own
        first = clock + 1
        clock += 1
        for q in range(nt):
            tsmark[ts[q]] = first
        n_new = 0
        valid = True
        long_ok = True
        for q in range(nt):
            t = ts[q]
            if stamp[t] > first:
                continue
            if not (is_cov[3 * t] or is_cov[3 * t + 1] or is_cov[3 * t + 2]):
                n_new += 1  # (left uncovered: a node of its own)
                stamp[t] = clock + 1
                clock += 1
                continue
            clock += 1
            ln = _walk_jump(twin, is_cov, t, stamp, clock, tsmark, first, ts, nt, cyc, pos, plen)
            if ln < 0:
                valid = False
                break
            starts[n_start] = t
            n_start += 1
            n_new += 1
            if shift > 0 and ln <= small:
                # a short new cycle: stamped whole, then its edges read
                clock += 1
                _walk_stamp(twin, is_cov, t, stamp, clock, cyc, -1, pos)
                if not _has_good_edge(twin, is_cov, good, t, stamp, clock):
                    long_ok = False
        if valid and n_new < n_old:
            merged = n_old - n_new
            taken = True
        elif valid and shift > 0 and n_new <= n_old + shift - 1 and long_ok:
            taken = stamp[target] > first  # (walked: on a new cycle)
            for q in range(nt):
                t = ts[q]
                if not (is_cov[3 * t] or is_cov[3 * t + 1] or is_cov[3 * t + 2]):
                    if not ((good[3 * t] and twin[3 * t] >= 0) or (good[3 * t + 1] and twin[3 * t + 1] >= 0)
                            or (good[3 * t + 2] and twin[3 * t + 2] >= 0)):
                        taken = False
                        break
        if taken:
            for i in range(ns):
                col[sv[i]] ^= 1
        else:
            for q in range(nt):
                for k in range(3):
                    is_cov[3 * ts[q] + k] = saved[3 * q + k]
    for i in range(ns):
        in_s[sv[i]] = False
    return merged, taken, clock, n_start


@njit(cache=True, nogil=True)
def _is_target(twin, is_cov, cyc, good, members, nmem):
    """Has this node (its triangles ``members``) no non-cover edge to another node
    whose join keeps the rule (``good``)?"""
    for i in range(nmem):
        t = members[i]
        for k in range(3):
            h = 3 * t + k
            g = twin[h]
            if g < 0 or _crossed(twin, is_cov, h):
                continue
            if cyc[t] >= 0 and cyc[g // 3] == cyc[t]:
                continue
            if good[h]:
                return False
    return True


@njit(cache=True, nogil=True)
def recolour_merges(tri, twin, is_cov, cyc, n_cyc, good, placed, n_pts, max_nodes, max_set, max_cand, rounds,
                    max_shift=1, long_walk=4096):
    """Merge small cover nodes into others by re-colouring up to ``max_set`` vertices.

    Parameters: ``tri (m, 3)``, ``twin (3 m,)``, ``is_cov (3 m,) bool`` and ``cyc (m,)``
    (the cover; both rewritten in place, new cycles get ids from ``n_cyc`` on, so the
    caller renumbers), ``good (3 m,) bool`` (half-edges whose join keeps the local
    rule), ``n_pts`` vertices. A node (a cycle of at most ``max_nodes`` triangles or
    an uncovered triangle) with no good non-cover edge to another node is a target;
    the vertices of its triangles and their neighbours (interior ones, the first
    ``max_cand``) are tried in sets of 1, 2, ... ``max_set``, the first set that
    leaves fewer nodes is taken (:func:`_try_set`); ``rounds`` passes over the
    nodes. Returns the number of nodes merged away (0 if the cover has no vertex
    colouring, :func:`vertex_colours`), and the number of nodes moved instead (a set that
    moves the node, leaving as many nodes (or, up to ``max_shift``, ``max_shift - 1`` more),
    each with a good edge, where no set merges it: ``_try_set``'s ``shift``).
    """
    m = tri.shape[0]
    # triangles around each vertex (CSR) and the boundary's vertices
    vstart = np.zeros(n_pts + 1, np.int64)
    for t in range(m):
        for k in range(3):
            vstart[tri[t, k] + 1] += 1
    for v in range(n_pts):
        vstart[v + 1] += vstart[v]
    fill = vstart[:-1].copy()
    vtri = np.empty(3 * m, np.int64)
    bnd = np.zeros(n_pts, np.bool_)
    for t in range(m):
        for k in range(3):
            v = tri[t, k]
            vtri[fill[v]] = t
            fill[v] += 1
            if twin[3 * t + k] < 0:
                bnd[v] = True
                bnd[tri[t, (k + 1) % 3]] = True
    col = np.empty(n_pts, np.int8)
    if not vertex_colours(tri, twin, is_cov, vstart, vtri, col):
        return 0, 0
    in_s = np.zeros(n_pts, np.bool_)
    mark = np.zeros(n_pts, np.int64)
    stamp = np.zeros(m, np.int64)
    tsmark = np.zeros(m, np.int64)
    settled = np.zeros(m, np.bool_)
    # positions along the cycles (a check jumps along the unchanged arcs: _walk_jump)
    pos = np.full(m, -1, np.int64)
    plen = np.zeros(max(2 * n_cyc, 16), np.int64)
    clock = 1
    for t in range(m):
        if cyc[t] >= 0 and pos[t] < 0:
            plen[cyc[t]] = _walk_stamp(twin, is_cov, t, stamp, clock, cyc, cyc[t], pos)
    clock += 1
    visit = 0
    cands = np.empty(max_cand, np.int64)
    near = np.zeros((max_cand, max_cand), np.bool_)
    sv = np.empty(max(max_set, 1), np.int64)
    ts = np.empty(64 * max(max_set, 1), np.int64)
    starts = np.empty(ts.shape[0], np.int64)
    saved = np.empty(3 * ts.shape[0], np.bool_)
    members = np.empty(max_nodes, np.int64)
    next_id = n_cyc
    total = 0
    total_shifted = 0
    for _ in range(rounds):
        # members of each cycle at this round's start (CSR by id)
        n_ids = next_id
        cstart = np.zeros(n_ids + 1, np.int64)
        for t in range(m):
            if cyc[t] >= 0:
                cstart[cyc[t] + 1] += 1
        for c in range(n_ids):
            cstart[c + 1] += cstart[c]
        cfill = cstart[:-1].copy()
        ctri = np.empty(max(cstart[n_ids], 1), np.int64)
        for t in range(m):
            if cyc[t] >= 0:
                ctri[cfill[cyc[t]]] = t
                cfill[cyc[t]] += 1
        merged_round = 0
        shifted = 0
        for node in range(n_ids + m):
            if node < n_ids:
                nmem = cstart[node + 1] - cstart[node]
                if nmem == 0 or nmem > max_nodes or cyc[ctri[cstart[node]]] != node:
                    continue  # (empty, large, or merged in this round already)
                for i in range(nmem):
                    members[i] = ctri[cstart[node] + i]
            else:
                t = node - n_ids
                if cyc[t] >= 0:
                    continue
                nmem = 1
                members[0] = t
            if not _is_target(twin, is_cov, cyc, good, members, nmem):
                continue
            # a node a shift left (it has a placed join keeping the rule) is not
            # moved again unless it has none: no shift undoes another
            movable = True
            for i in range(nmem):
                if settled[members[i]]:
                    movable = _is_target(twin, is_cov, cyc, placed, members, nmem)
                    break
            # candidate vertices: the node's, then their neighbours (interior only)
            visit += 1
            nc = 0
            for ring in range(2):
                for i in range(nmem):
                    t = members[i]
                    for k in range(3):
                        v = tri[t, k]
                        if ring == 0:
                            if not bnd[v] and mark[v] != visit and nc < max_cand:
                                mark[v] = visit
                                cands[nc] = v
                                nc += 1
                            continue
                        for j in range(vstart[v], vstart[v + 1]):
                            s = vtri[j]
                            for kk in range(3):
                                w = tri[s, kk]
                                if not bnd[w] and mark[w] != visit and nc < max_cand:
                                    mark[w] = visit
                                    cands[nc] = w
                                    nc += 1
            # which candidates share a triangle (the sets tried are connected)
            for i in range(nc):
                for j in range(nc):
                    near[i, j] = False
                stamp_v = cands[i]
                for j2 in range(vstart[stamp_v], vstart[stamp_v + 1]):
                    t = vtri[j2]
                    for k in range(3):
                        w = tri[t, k]
                        if mark[w] == visit and w != stamp_v:
                            for j in range(nc):
                                if cands[j] == w:
                                    near[i, j] = True
            done = 0
            for shift in range(1 + max_shift):  # merges, then shifts (as many nodes / one more, none a target)
                if done or (shift > 0 and not movable):
                    break
                for size in range(1, max_set + 1):
                    if done:
                        break
                    # subsets of ``size`` candidates in lexicographic order
                    idx = np.arange(size)
                    if size > nc:
                        break
                    while True:
                        for i in range(size):
                            sv[i] = cands[idx[i]]
                        # (a set's triangles: at most 64 per vertex listed); connected
                        # sets only: apart, two re-colourings act one by one
                        fits = True
                        for i in range(size):
                            if vstart[sv[i] + 1] - vstart[sv[i]] > 64:
                                fits = False
                        if fits and size > 1:
                            links = 0
                            for i in range(size):
                                for j in range(i + 1, size):
                                    if near[idx[i], idx[j]]:
                                        links += 1
                            fits = links >= size - 1
                        if fits:
                            got, taken, clock, n_st = _try_set(
                                tri, twin, is_cov, cyc, pos, plen, col, vstart, vtri, placed, in_s, sv, size, ts, saved,
                                stamp, tsmark, starts, clock, shift, members[0], long_walk,
                            )
                            if taken:
                                # the new cycles through the set's triangles get fresh ids
                                # and positions (walked whole: only where one is taken)
                                for i in range(size):
                                    v = sv[i]
                                    for j in range(vstart[v], vstart[v + 1]):
                                        t = vtri[j]
                                        if not (is_cov[3 * t] or is_cov[3 * t + 1] or is_cov[3 * t + 2]):
                                            cyc[t] = -1  # (left uncovered by a shift)
                                            pos[t] = -1
                                clock += 1
                                for q in range(n_st):
                                    if next_id >= plen.shape[0]:
                                        grown = np.zeros(2 * plen.shape[0], np.int64)
                                        grown[: plen.shape[0]] = plen
                                        plen = grown
                                    plen[next_id] = _walk_stamp(twin, is_cov, starts[q], stamp, clock, cyc, next_id,
                                                                pos)
                                    next_id += 1
                                merged_round += got
                                if not got:
                                    shifted += 1
                                    for i in range(size):
                                        for j in range(vstart[sv[i]], vstart[sv[i] + 1]):
                                            settled[vtri[j]] = True
                                done = 1
                                break
                        # next subset
                        p = size - 1
                        while p >= 0 and idx[p] == nc - size + p:
                            p -= 1
                        if p < 0:
                            break
                        idx[p] += 1
                        for i in range(p + 1, size):
                            idx[i] = idx[i - 1] + 1
        total += merged_round
        total_shifted += shifted
        if merged_round == 0 and shifted == 0:
            break
    return total, total_shifted
