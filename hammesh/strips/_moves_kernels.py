"""Compiled local moves that shorten a dual path cover's buffer (join, rotate, tunnel).

The cover is a set of undirected links ``lk[t] = (a, b)`` (path neighbours, -1 at an
end), a label per path (``pid``), the path size per label and the other end of each
end triangle (``oth``).  The buffer's length is
    sum over paths (n + 2 + end term) + I + (S - 1) restarts,
where I counts links between two interior triangles with the same pivot (a swap) and
the end term of a path of n >= 3 triangles is 1 when both ends start with a swap.
A pivot depends only on the triangle's own links, so a move that changes the links of
a few triangles C changes I only on links touching C: every move is costed in O(1),
applied tentatively and undone unless the total drops.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._cover_kernels import PathCover
from hammesh.strips._numba import NEXT_CORNER, carve, kernel, loop_helper
from hammesh.strips._path_kernels import slot_of, vertex_between

__all__ = ["improve_cover"]


@loop_helper
def write_path_from(link, t, prev, buf, n0):
    """Write the path from ``t`` away from its neighbour ``prev`` (-1: ``t`` is an end) into ``buf[n0:]``.

    Returns the offset after the last triangle written.
    """
    n = n0
    while t >= 0:
        buf[n] = t
        n += 1
        a = link[t, 0]
        nxt = a if a != prev else link[t, 1]
        prev = t
        t = nxt
    return n


@loop_helper
def linked_pivot(tri, lk, le, t):
    """Pivot of an interior triangle (vertex shared by its two path edges), -1 at an end.

    ``le[t, j]`` is the local edge of ``t`` towards its path neighbour ``lk[t, j]``.
    """
    if lk[t, 0] < 0 or lk[t, 1] < 0:
        return -1
    k0 = le[t, 0]
    k1 = le[t, 1]
    k = k1 if k1 == NEXT_CORNER[k0] else k0  # an index select (no data-dependent branch)
    return tri[t, k]


@loop_helper
def swaps_near(tri, lk, le, C, nC):
    """Swaps (links between interior triangles with equal pivots) on links touching ``C[:nC]``."""
    s = 0
    for i in range(nC):
        c = C[i]
        pc = linked_pivot(tri, lk, le, c)
        if pc < 0:
            continue
        for j in range(2):
            u = lk[c, j]
            if u < 0:
                continue
            inside = False
            for i2 in range(nC):
                if C[i2] == u:
                    inside = True
            if inside and u < c:
                continue  # counted from u
            if linked_pivot(tri, lk, le, u) == pc:
                s += 1
    return s


@loop_helper
def end_starts_with_swap(tri, lk, le, a):
    """Starting at end ``a`` costs a swap after the first triangle (path of >= 3)."""
    j = 0 if lk[a, 0] >= 0 else 1
    return 1 if tri[a, le[a, j]] == linked_pivot(tri, lk, le, lk[a, j]) else 0


@loop_helper
def path_end_cost(tri, lk, le, a, b, n):
    if n < 3:
        return 0
    return min(end_starts_with_swap(tri, lk, le, a), end_starts_with_swap(tri, lk, le, b))


@loop_helper
def relink(lk, le, nb, t, old, new):
    j = 0 if lk[t, 0] == old else 1
    lk[t, j] = new
    k = slot_of(nb, t, new)
    le[t, j] = k if new >= 0 else -1  # (-1 would find a boundary edge)


@loop_helper
def is_linked(lk, t, u):
    return lk[t, 0] == u or lk[t, 1] == u


@loop_helper
def renumber_positions(lk, pid, ps, t, prev, label, p, d, n):
    """Give ``label`` and positions ``p, p + d, ...`` to ``n`` triangles from ``t``, walking away from ``prev``."""
    for _ in range(n):
        pid[t] = label
        ps[t] = p
        p += d
        a = lk[t, 0]
        nxt = a if a != prev else lk[t, 1]
        prev = t
        t = nxt


@loop_helper
def outward_step(lk, ps, t, excl):
    """Step of the positions leaving path end ``t`` outwards (``excl``: a link to ignore)."""
    for j in range(2):
        u = lk[t, j]
        if u >= 0 and u != excl:
            return ps[t] - ps[u]
    return 1


@loop_helper
def lies_toward(ps, x, u, t):
    """Does ``x``'s path neighbour ``u`` lie on the side of ``t`` (same path)?"""
    return (ps[u] - ps[x] > 0) == (ps[t] - ps[x] > 0)


@loop_helper
def rotate_positions(lk, pid, ps, x, e, label, dxy, nseg, n):
    """Positions after a rotation ``f .. x y .. e`` -> ``f .. x e .. y`` (links already changed).

    ``dxy`` was the step from ``x`` towards ``y`` and ``nseg`` the triangles ``y .. e``;
    renumbers the shorter of ``e .. y`` and ``x .. f``.
    """
    if nseg <= n - nseg:
        renumber_positions(lk, pid, ps, e, x, label, ps[x] + dxy, dxy, nseg)
    else:
        renumber_positions(lk, pid, ps, x, e, label, ps[e] + dxy, dxy, n - nseg)


@loop_helper
def link_ends(lk, le, nb, a, b):
    """Link path ends ``a`` and ``b`` (tentatively: :func:`unlink_ends` undoes it)."""
    relink(lk, le, nb, a, -1, b)
    relink(lk, le, nb, b, -1, a)


@loop_helper
def unlink_ends(lk, le, nb, a, b):
    """Undo :func:`link_ends`."""
    relink(lk, le, nb, a, b, -1)
    relink(lk, le, nb, b, a, -1)


@loop_helper
def commit_join(lk, pid, ps, pend, size, oth, a, b, ra, rb, na, nbb, fa, fb):
    """Book a join of end ``a`` (path ``ra``, ``na`` triangles, other end ``fa``) to end ``b`` (``rb``, ``nbb``, ``fb``).

    The links are already made; the smaller path is renumbered into the larger's
    positions and label, the label left empty gets size 0.
    """
    if na < nbb:
        d = outward_step(lk, ps, b, a)
        renumber_positions(lk, pid, ps, a, b, rb, ps[b] + d, d, na)
        keep = rb
        gone = ra
    else:
        d = outward_step(lk, ps, a, b)
        renumber_positions(lk, pid, ps, b, a, ra, ps[a] + d, d, nbb)
        keep = ra
        gone = rb
    pend[keep] = fa
    size[keep] = na + nbb
    size[gone] = 0
    oth[fa] = fb
    oth[fb] = fa


@loop_helper
def mark_ends_near(nb, lk, dirty, c):
    """Ends whose moves may read the links of ``c``: its dual neighbours, those of its path
    neighbours and of theirs (pivots two links away enter a move's cost)."""
    if c < 0:
        return
    for k in range(3):
        if nb[c, k] >= 0:
            dirty[nb[c, k]] = True
    dirty[c] = True
    for j in range(2):
        u = lk[c, j]
        if u < 0:
            continue
        dirty[u] = True
        for k in range(3):
            if nb[u, k] >= 0:
                dirty[nb[u, k]] = True
        for j2 in range(2):
            u2 = lk[u, j2]
            if u2 < 0 or u2 == c:
                continue
            for k in range(3):
                if nb[u2, k] >= 0:
                    dirty[nb[u2, k]] = True


@loop_helper
def tunnel_swaps_lower_bound(tri, lk, le, nb, e, x, side, nP):
    """Swaps on the links a tunnel creates: ``(p, e)``, ``(e, x)`` and ``(x, z)``, ``z = lk[x, side]``.

    Read before the move (``p`` is ``e``'s path neighbour, if any): a lower bound of
    the move's new cost, which also counts end terms (>= 0) and no other link (``w``
    becomes an end).
    """
    z = lk[x, side]
    pnx = vertex_between(tri, x, slot_of(nb, x, e), le[x, side])  # x's pivot between e and z
    n = 1 if linked_pivot(tri, lk, le, z) == pnx else 0
    if nP >= 2:
        j = 0 if lk[e, 0] >= 0 else 1
        pne = vertex_between(tri, e, le[e, j], slot_of(nb, e, x))  # e's pivot between p and x
        n += 1 if pne == pnx else 0
        n += 1 if linked_pivot(tri, lk, le, lk[e, j]) == pne else 0
    return n


@loop_helper
def has_third_path_end(nb, lk, pid, w, x, rp, rq):
    """Has ``w`` (losing its link to ``x`` in a tunnel) a neighbouring end of a path other than ``rp``, ``rq``?

    The candidates a tunnel's third join tries, read before the move: the move only
    changes the links of ``e`` (label ``rp``), ``x`` (interior before and after) and ``w``.
    """
    for k in range(3):
        v = nb[w, k]
        if v < 0 or v == x or is_linked(lk, w, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0):
            continue
        if pid[v] != rp and pid[v] != rq:
            return True
    return False


def improve_cover(tri, twin, order, starts, max_passes, visit, skip_hopeless_tunnels=True):
    """Lower the buffer length of a dual path cover by local moves at the path ends.

    Moves around each path end ``e`` (path ``f .. e``), each kept only when the total
    (indices plus one restart per path) strictly drops, each costed in O(1):

    * join: ``e`` next to another path's end: one path;
    * rotate: ``e`` next to ``x`` inside its own path: ``f .. x y .. e`` becomes
      ``f .. x e .. y`` (Posa's rotation), kept if it saves swaps or if the new end ``y``
      then joins another path;
    * tunnel: ``e`` next to ``x`` inside another path ``.. w x z ..``: ``e`` takes ``x``
      and the side of ``z``; the side of ``w`` is left over (and may join a third path).

    Every triangle keeps its position along its path (consecutive integers, any
    offset, either direction), so which neighbour of ``x`` lies towards ``e`` (rotate)
    and the ends and sizes of both sides of ``x`` (tunnel) are O(1); a committed move
    renumbers the part it re-attaches (the smaller part of a join, the shorter side of
    a rotation, the side a tunnel takes).  Path ends are considered in the order of
    ``visit`` (a permutation of the triangles).  Returns ``(order, starts)`` of the new
    cover (``order`` a view into the work buffer).

    ``skip_hopeless_tunnels`` (default) skips a tunnel before evaluating it when the
    swaps it would create already cost what it could save and the leftover end has no
    third path to join: exact (the same cover; a test compares both), ~60% of the
    tunnels.

    The work arrays (7 m + 1 int64, 7 m int32 and 2 m bool) are three numpy buffers
    carved once here (:func:`~hammesh.strips._numba.carve`): numpy asks for transparent
    huge pages on big ones, and first-touch page faults of a dozen separately allocated
    arrays had cost ~1/3 of the moves' time at 100k triangles.  (Positions stay int64: a committed move continues them from a
    neighbour's, so they may drift outside ``[0, m)``; an int32 work buffer measured no
    faster.)
    """
    m = tri.shape[0]
    # positions int64 (they may drift outside [0, m)); neighbours, links and their local
    # edges, which every move reads, in half the bytes where they fit
    pid, oth, size, ps, pend, out, st = carve(np.int64, m, m, m, m, m, m, m + 1)
    nb, lk, le = carve(np.int32 if 3 * m < 2**31 else np.int64, (m, 3), (m, 2), (m, 2))
    dirty, seen = carve(np.bool_, m, m)
    S2 = _improve_cover_into(
        tri, twin, order, starts, max_passes, visit, skip_hopeless_tunnels,
        nb, lk, le, pid, oth, size, ps, pend, out, st, dirty, seen,
    )
    if S2 < 0:
        return PathCover(order.copy(), starts.copy())
    return PathCover(out, st[: S2 + 1].copy())


@kernel
def _improve_cover_into(
    tri, twin, order, starts, max_passes, visit, skip_hopeless_tunnels,
    nb, lk, le, pid, oth, size, ps, pend, out, st, dirty, seen,
):
    # ps: positions, consecutive integers along each path; pend: one end of each path
    # label; dirty: ends to (re)consider, all at first, then near changes
    m = tri.shape[0]
    nb[:] = -1
    lk[:] = -1
    le[:] = -1
    oth[:] = -1
    size[:] = 0
    dirty[:] = True
    for t in range(m):
        for k in range(3):
            h = twin[3 * t + k]
            if h >= 0:
                nb[t, k] = h // 3
    S = starts.shape[0] - 1
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        pend[s] = order[a]
        for i in range(a, b):
            t = order[i]
            pid[t] = s
            ps[t] = i
            if i > a:
                lk[t, 0] = order[i - 1]
                le[t, 0] = slot_of(nb, t, order[i - 1])
            if i + 1 < b:
                lk[t, 1] = order[i + 1]
                le[t, 1] = slot_of(nb, t, order[i + 1])
        size[s] = b - a
        oth[order[a]] = order[b - 1]
        oth[order[b - 1]] = order[a]
    C = np.empty(8, np.int64)
    T = np.empty(12, np.int64)  # triangles whose links or path ends a committed move changed
    changed = False
    for _ in range(max_passes):
        improved = False
        for ie in range(m):
            e = visit[ie]
            if not dirty[e] or (lk[e, 0] >= 0 and lk[e, 1] >= 0):
                continue
            dirty[e] = False
            nT = 0
            rp = pid[e]
            f = oth[e]
            nP = size[rp]
            done = False
            # join
            for k in range(3):
                v = nb[e, k]
                if v < 0 or is_linked(lk, e, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0) or pid[v] == rp:
                    continue
                rv = pid[v]
                g = oth[v]
                nQ = size[rv]
                C[0] = e
                C[1] = v
                before = swaps_near(tri, lk, le, C, 2) + path_end_cost(tri, lk, le, e, f, nP)
                before += path_end_cost(tri, lk, le, v, g, nQ)
                link_ends(lk, le, nb, e, v)
                after = swaps_near(tri, lk, le, C, 2) + path_end_cost(tri, lk, le, f, g, nP + nQ)
                if after - before - 3 < 0:
                    commit_join(lk, pid, ps, pend, size, oth, e, v, rp, rv, nP, nQ, f, g)
                    T[0] = e
                    T[1] = v
                    T[2] = f
                    T[3] = g
                    nT = 4
                    done = True
                    break
                unlink_ends(lk, le, nb, e, v)
            if done:
                for i in range(nT):
                    mark_ends_near(nb, lk, dirty, T[i])
                improved = True
                continue
            for k in range(3):
                x = nb[e, k]
                if x < 0 or is_linked(lk, e, x):
                    continue
                if pid[x] == rp:
                    # rotate: y is x's neighbour on e's side
                    if lk[x, 0] < 0 or lk[x, 1] < 0:
                        y = lk[x, 0] if lk[x, 0] >= 0 else lk[x, 1]  # x == f
                    else:
                        y = lk[x, 0] if lies_toward(ps, x, lk[x, 0], e) else lk[x, 1]
                    dxy = 1 if ps[e] > ps[x] else -1
                    nseg = abs(ps[e] - ps[x])  # triangles y .. e
                    C[0] = x
                    C[1] = y
                    C[2] = e
                    before = swaps_near(tri, lk, le, C, 3) + path_end_cost(tri, lk, le, e, f, nP)
                    relink(lk, le, nb, x, y, e)
                    relink(lk, le, nb, y, x, -1)
                    relink(lk, le, nb, e, -1, x)
                    after = swaps_near(tri, lk, le, C, 3) + path_end_cost(tri, lk, le, y, f, nP)
                    if after < before:
                        rotate_positions(lk, pid, ps, x, e, rp, dxy, nseg, nP)
                        pend[rp] = f
                        oth[y] = f
                        oth[f] = y
                        T[0] = x
                        T[1] = y
                        T[2] = e
                        T[3] = f
                        nT = 4
                        done = True
                        break
                    # the new end y joins another path
                    for k2 in range(3):
                        v = nb[y, k2]
                        if v < 0 or is_linked(lk, y, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0) or pid[v] == rp:
                            continue
                        rv = pid[v]
                        g = oth[v]
                        nQ = size[rv]
                        C[3] = v
                        bj = swaps_near(tri, lk, le, C[1:], 1) + swaps_near(tri, lk, le, C[3:], 1)
                        bj += path_end_cost(tri, lk, le, v, g, nQ) + path_end_cost(tri, lk, le, y, f, nP)
                        link_ends(lk, le, nb, y, v)
                        C[4] = y
                        aj = swaps_near(tri, lk, le, C[3:], 2) + path_end_cost(tri, lk, le, f, g, nP + nQ)
                        # bj counted y's and v's links apart; no link joined them before
                        total = (after - before) + (aj - bj) - 3
                        if total < 0:
                            rotate_positions(lk, pid, ps, x, e, rp, dxy, nseg, nP)
                            commit_join(lk, pid, ps, pend, size, oth, y, v, rp, rv, nP, nQ, f, g)
                            T[0] = x
                            T[1] = y
                            T[2] = e
                            T[3] = f
                            T[4] = v
                            T[5] = g
                            nT = 6
                            done = True
                            break
                        unlink_ends(lk, le, nb, y, v)
                    if done:
                        break
                    relink(lk, le, nb, e, x, -1)
                    relink(lk, le, nb, y, -1, x)
                    relink(lk, le, nb, x, e, y)
                elif lk[x, 0] >= 0 and lk[x, 1] >= 0:
                    # tunnel into x's path
                    rq = pid[x]
                    nQ = size[rq]
                    a0 = pend[rq]
                    if lies_toward(ps, x, lk[x, 0], a0):
                        end0 = a0
                        end1 = oth[a0]
                    else:
                        end1 = a0
                        end0 = oth[a0]
                    n0 = abs(ps[end0] - ps[x])
                    n1 = abs(ps[end1] - ps[x])
                    for side in range(2):
                        w = lk[x, 1 - side]
                        endB = end0 if side == 0 else end1
                        nB = n0 if side == 0 else n1
                        endA = end1 if side == 0 else end0
                        nA = n1 if side == 0 else n0
                        C[0] = e
                        C[1] = x
                        C[2] = w
                        before = swaps_near(tri, lk, le, C, 3) + path_end_cost(tri, lk, le, e, f, nP)
                        before += path_end_cost(tri, lk, le, end0, end1, nQ)
                        if skip_hopeless_tunnels and before <= tunnel_swaps_lower_bound(tri, lk, le, nb, e, x, side, nP) and not has_third_path_end(
                            nb, lk, pid, w, x, rp, rq
                        ):
                            # the swaps the move creates already cost what it could save
                            # (end terms are >= 0), and w has no third path to join: skip
                            # what evaluating the move would find (most tunnels end here)
                            continue
                        relink(lk, le, nb, e, -1, x)
                        relink(lk, le, nb, x, w, e)
                        relink(lk, le, nb, w, x, -1)
                        nP2 = nP + 1 + nB
                        after = swaps_near(tri, lk, le, C, 3) + path_end_cost(tri, lk, le, f, endB, nP2)
                        after += path_end_cost(tri, lk, le, w, endA, nA)
                        ok = after < before
                        rv = -1
                        g = -1
                        nR = 0
                        if not ok:
                            # the leftover's new end w joins a third path
                            for k2 in range(3):
                                v = nb[w, k2]
                                if v < 0 or is_linked(lk, w, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0):
                                    continue
                                if pid[v] == rp or pid[v] == rq:
                                    continue
                                rv = pid[v]
                                g = oth[v]
                                nR = size[rv]
                                C[3] = w
                                C[4] = v
                                bj = swaps_near(tri, lk, le, C[3:], 2) + path_end_cost(tri, lk, le, v, g, nR)
                                bj += path_end_cost(tri, lk, le, w, endA, nA)
                                link_ends(lk, le, nb, w, v)
                                aj = swaps_near(tri, lk, le, C[3:], 2) + path_end_cost(tri, lk, le, endA, g, nA + nR)
                                if (after - before) + (aj - bj) - 3 < 0:
                                    ok = True
                                    break
                                unlink_ends(lk, le, nb, w, v)
                                rv = -1
                        if ok:
                            # labels: x and B join P (label rp); A keeps rq
                            d = outward_step(lk, ps, e, x)
                            renumber_positions(lk, pid, ps, x, e, rp, ps[e] + d, d, nB + 1)
                            pend[rp] = f
                            size[rp] = nP2
                            oth[f] = endB
                            oth[endB] = f
                            if rv < 0:
                                size[rq] = nA
                                pend[rq] = w
                                oth[w] = endA
                                oth[endA] = w
                            else:
                                commit_join(lk, pid, ps, pend, size, oth, w, v, rq, rv, nA, nR, endA, g)
                            T[0] = e
                            T[1] = x
                            T[2] = w
                            T[3] = f
                            T[4] = endA
                            T[5] = endB
                            T[6] = v if rv >= 0 else -1
                            T[7] = g
                            nT = 8
                            done = True
                            break
                        relink(lk, le, nb, w, -1, x)
                        relink(lk, le, nb, x, e, w)
                        relink(lk, le, nb, e, x, -1)
                    if done:
                        break
            if done:
                for i in range(nT):
                    mark_ends_near(nb, lk, dirty, T[i])
                improved = True
        if not improved:
            break
        changed = True
    if not changed:
        return -1
    seen[:] = False
    L = 0
    S2 = 0
    st[0] = 0
    for i in range(m):
        t = order[i]
        if seen[t] or (lk[t, 0] >= 0 and lk[t, 1] >= 0):
            continue
        n = write_path_from(lk, t, -1, out, L)
        for i2 in range(L, n):
            seen[out[i2]] = True
        L = n
        S2 += 1
        st[S2] = L
    return S2
