"""Compiled sequential loops of the strip encoders (numba, ``cache=True``).

Everything that cannot be vectorized lives here: joining strips by degenerate
stitching (a running parity), decoding generalized strips (two registers), growing
greedy dual paths, and the forced chains of the sequential test.  Kernels take and
return plain int64/bool arrays and never raise; callers check their inputs.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["stitch", "decode_generalized", "greedy_paths", "sequential_chain"]


@njit(cache=True)
def _variant_length(n_enc, ntri, swap1, odd):
    if odd and ntri >= 3:
        return n_enc - 1 if swap1 else n_enc + 1
    return n_enc


@njit(cache=True)
def stitch(enc, enc_starts, ntri, swap1):
    """Join GL strips into one by degenerate stitching, fixing each start's parity.

    ``enc[enc_starts[s]:enc_starts[s + 1]]`` is strip ``s`` encoded to start at an even
    position: ``x, p, q, [p], w1, ...`` (``[p]`` present iff ``swap1[s]``).  Strips are
    joined by repeating the previous strip's last index and the next strip's first
    (two degenerate triangles each way).  A strip that then starts at an odd position
    is sent as ``x, q, p, [q], w1, ...`` instead: same triangles, same windings, and the
    swap before ``w1`` toggles (so the join always costs exactly two indices).
    """
    S = enc_starts.shape[0] - 1
    total = 0
    for s in range(S):
        if s > 0:
            total += 2
        total += _variant_length(enc_starts[s + 1] - enc_starts[s], ntri[s], swap1[s], total % 2 == 1)
    out = np.empty(total, np.int64)
    pos = 0
    for s in range(S):
        a = enc_starts[s]
        b = enc_starts[s + 1]
        if s > 0:
            out[pos] = out[pos - 1]
            out[pos + 1] = enc[a]
            pos += 2
        rest = a
        if pos % 2 == 1:
            if ntri[s] == 1:
                # one triangle x p q sent as x q p at an odd position: winding (q, x, p)
                out[pos] = enc[a]
                out[pos + 1] = enc[a + 2]
                out[pos + 2] = enc[a + 1]
                pos += 3
                rest = b
            else:
                p = enc[a + 1]
                q = enc[a + 2]
                out[pos] = enc[a]
                out[pos + 1] = q
                out[pos + 2] = p
                pos += 3
                rest = a + 3
                if ntri[s] >= 3:
                    if swap1[s]:
                        rest = a + 4
                    else:
                        out[pos] = q
                        pos += 1
        for i in range(rest, b):
            out[pos] = enc[i]
            pos += 1
    return out


@njit(cache=True)
def decode_generalized(vertices, vertex_starts, swaps, tri_starts):
    """Oriented triangles of generalized strips (two registers, IRIS GL ``swaptmesh``).

    Strip ``s`` has vertices ``vertices[vertex_starts[s]:vertex_starts[s + 1]]`` (its
    triangle count plus two) and one swap bit per triangle.  The registers start as
    the first two vertices; for each further vertex ``v``: if its bit is set the
    registers swap, the triangle is ``(r0, r1, v)`` on even parity and ``(r1, r0, v)``
    on odd parity (parity flips per triangle and per swap), then ``r0, r1 = r1, v``.
    """
    T = swaps.shape[0]
    out = np.empty((T, 3), np.int64)
    S = tri_starts.shape[0] - 1
    for s in range(S):
        va = vertex_starts[s]
        ta = tri_starts[s]
        k = tri_starts[s + 1] - ta
        r0 = vertices[va]
        r1 = vertices[va + 1]
        parity = 0
        for j in range(k):
            v = vertices[va + 2 + j]
            if swaps[ta + j]:
                tmp = r0
                r0 = r1
                r1 = tmp
                parity ^= 1
            if parity == 0:
                out[ta + j, 0] = r0
                out[ta + j, 1] = r1
            else:
                out[ta + j, 0] = r1
                out[ta + j, 1] = r0
            out[ta + j, 2] = v
            r0 = r1
            r1 = v
            parity ^= 1
    return out


@njit(cache=True)
def _across(tri, twin, t, b, c):
    """Triangle across edge {b, c} of triangle t and its third vertex, or (-1, -1)."""
    for k in range(3):
        x = tri[t, k]
        y = tri[t, (k + 1) % 3]
        if (x == b and y == c) or (x == c and y == b):
            h = twin[3 * t + k]
            if h < 0:
                return -1, -1
            u = h // 3
            return u, tri[u, (h - 3 * u + 2) % 3]
    return -1, -1


@njit(cache=True)
def sequential_chain(tri, twin, t0, a, b, c):
    """Forced alternating strip through triangle ``t0`` read as vertices ``a, b, c``.

    In a strip whose turns alternate, triangle ``i`` is ``{v_i, v_(i+1), v_(i+2)}``, so
    ``(a, b, c)`` fixes the successor (across ``{b, c}``) and the predecessor (across
    ``{a, b}``) and so on (Thm 4.3).  Both directions are followed until the boundary or
    a repeated triangle, at most ``m - 1`` steps each.  A sliding window then looks for
    ``m`` consecutive distinct triangles.

    Returns ``(order, vertices)``: the ``m`` triangles and ``m + 2`` vertices of such a
    window, or two empty arrays.
    """
    m = tri.shape[0]
    seen = np.zeros(m, np.bool_)
    # successors
    succ_t = np.empty(m, np.int64)
    succ_v = np.empty(m, np.int64)
    ns = 0
    seen[t0] = True
    t = t0
    x = b
    y = c
    while ns < m - 1:
        u, z = _across(tri, twin, t, x, y)
        if u < 0 or seen[u]:
            break
        seen[u] = True
        succ_t[ns] = u
        succ_v[ns] = z
        ns += 1
        t = u
        x = y
        y = z
    for i in range(ns):
        seen[succ_t[i]] = False
    # predecessors
    pred_t = np.empty(m, np.int64)
    pred_v = np.empty(m, np.int64)
    npr = 0
    t = t0
    x = a
    y = b
    while npr < m - 1:
        u, z = _across(tri, twin, t, x, y)
        if u < 0 or seen[u]:
            break
        seen[u] = True
        pred_t[npr] = u
        pred_v[npr] = z
        npr += 1
        t = u
        y = x
        x = z
    # chain: pred (reversed), t0, succ ; vertices: pred_v reversed, a, b, c, succ_v
    L = npr + 1 + ns
    chain = np.empty(L, np.int64)
    verts = np.empty(L + 2, np.int64)
    for i in range(npr):
        chain[i] = pred_t[npr - 1 - i]
        verts[i] = pred_v[npr - 1 - i]
    chain[npr] = t0
    verts[npr] = a
    verts[npr + 1] = b
    verts[npr + 2] = c
    for i in range(ns):
        chain[npr + 1 + i] = succ_t[i]
        verts[npr + 3 + i] = succ_v[i]
    empty = np.empty(0, np.int64)
    if L < m:
        return empty, empty
    count = np.zeros(m, np.int64)
    distinct = 0
    for i in range(L):
        if count[chain[i]] == 0:
            distinct += 1
        count[chain[i]] += 1
        if i >= m:
            j = chain[i - m]
            count[j] -= 1
            if count[j] == 0:
                distinct -= 1
        if i >= m - 1 and distinct == m:
            s = i - m + 1
            return chain[s : s + m].copy(), verts[s : s + m + 2].copy()
    return empty, empty


@njit(cache=True)
def _visit(t, nb, visited, deg, bucket, top):
    visited[t] = True
    for k in range(3):
        u = nb[t, k]
        if u >= 0 and not visited[u]:
            deg[u] -= 1
            d = deg[u]
            bucket[d, top[d]] = u
            top[d] += 1


@njit(cache=True)
def _grow(cur, entry, prev_pivot, tri, twin, nb, visited, deg, bucket, top, out, w_swap):
    """Extend a path from ``cur`` (entered through local edge ``entry``, -1: none).

    Each step takes the unvisited neighbour with the least ``2 * remaining degree +
    w_swap * swap`` (few remaining neighbours first, so no triangle is stranded; then
    the alternating turn).  Returns ``(count, first_exit, first_pivot)``: triangles
    appended to ``out``, the local edge of ``cur`` left by, the pivot at ``cur``.
    """
    n = 0
    first_exit = -1
    first_pivot = -1
    while True:
        best = -1
        best_score = 1 << 30
        best_pivot = -1
        for k in range(3):
            if k == entry:
                continue
            u = nb[cur, k]
            if u < 0 or visited[u]:
                continue
            if entry < 0:
                pivot = tri[cur, k]
            elif k == (entry + 1) % 3:
                pivot = tri[cur, k]
            else:
                pivot = tri[cur, entry]
            swap = 1 if (prev_pivot >= 0 and pivot == prev_pivot) else 0
            score = 2 * deg[u] + w_swap * swap
            if score < best_score:
                best_score = score
                best = k
                best_pivot = pivot
        if best < 0:
            break
        if n == 0:
            first_exit = best
            first_pivot = best_pivot
        h = twin[3 * cur + best]
        u = h // 3
        _visit(u, nb, visited, deg, bucket, top)
        out[n] = u
        n += 1
        prev_pivot = best_pivot
        entry = h - 3 * u
        cur = u
    return n, first_exit, first_pivot


@njit(cache=True)
def greedy_paths(tri, twin, w_swap, seed_order):
    """Partition the dual graph into paths, greedily (O(m)).

    Seeds are taken with the fewest unvisited neighbours (a bucket queue, most recent
    first, so new paths start along the previous ones; ties at the start broken by
    ``seed_order``, last first); each path is grown forward from
    its seed, then backward through the seed's remaining edges, turn-aware.

    Returns ``(order, starts)`` as in :mod:`hammesh.strips.paths`.
    """
    m = tri.shape[0]
    nb = np.full((m, 3), -1, np.int64)
    deg = np.zeros(m, np.int64)
    for t in range(m):
        for k in range(3):
            h = twin[3 * t + k]
            if h >= 0:
                nb[t, k] = h // 3
                deg[t] += 1
    visited = np.zeros(m, np.bool_)
    bucket = np.empty((4, m), np.int64)
    top = np.zeros(4, np.int64)
    for i in range(m):
        t = seed_order[i]
        d = deg[t]
        bucket[d, top[d]] = t
        top[d] += 1
    order = np.empty(m, np.int64)
    starts = np.empty(m + 1, np.int64)
    fwd = np.empty(m, np.int64)
    bwd = np.empty(m, np.int64)
    L = 0
    S = 0
    starts[0] = 0
    while True:
        seed = -1
        for d in range(4):
            while top[d] > 0:
                top[d] -= 1
                t = bucket[d, top[d]]
                if not visited[t] and deg[t] == d:
                    seed = t
                    break
            if seed >= 0:
                break
        if seed < 0:
            break
        _visit(seed, nb, visited, deg, bucket, top)
        nf, kf, _ = _grow(seed, -1, -1, tri, twin, nb, visited, deg, bucket, top, fwd, w_swap)
        nbk = 0
        if nf > 0:
            # the triangle after the seed: its pivot is what the seed's turn must avoid
            p1 = -1
            if nf >= 2:
                u = fwd[0]
                # entry of fwd[0] and exit towards fwd[1]
                ein = twin[3 * seed + kf] - 3 * u
                eout = -1
                for k in range(3):
                    if nb[u, k] == fwd[1]:
                        eout = k
                if eout == (ein + 1) % 3:
                    p1 = tri[u, eout]
                else:
                    p1 = tri[u, ein]
            nbk, _, _ = _grow(seed, kf, p1, tri, twin, nb, visited, deg, bucket, top, bwd, w_swap)
        for i in range(nbk):
            order[L] = bwd[nbk - 1 - i]
            L += 1
        order[L] = seed
        L += 1
        for i in range(nf):
            order[L] = fwd[i]
            L += 1
        S += 1
        starts[S] = L
    return order, starts[: S + 1].copy()


# --- improving a path cover: merge adjacent path ends, rotate ends (Posa) -------------


@njit(cache=True)
def _walk(link, t, prev, buf, n0):
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


@njit(cache=True)
def _local_edge(nb, t, u):
    for k in range(3):
        if nb[t, k] == u:
            return k
    return -1


@njit(cache=True)
def _seq_cost(tri, nb, seq, a, b):
    """Indices of one GL strip drawing the dual path ``seq[a:b]``: ``n + 2 + swaps``, best direction."""
    n = b - a
    if n <= 2:
        return n + 2
    interior = 0
    prev_pivot = -1
    p1 = -1
    pl = -1
    for i in range(a + 1, b - 1):
        t = seq[i]
        kin = _local_edge(nb, t, seq[i - 1])
        kout = _local_edge(nb, t, seq[i + 1])
        if kout == (kin + 1) % 3:
            p = tri[t, kout]
        else:
            p = tri[t, kin]
        if i == a + 1:
            p1 = p
        elif p == prev_pivot:
            interior += 1
        pl = p
        prev_pivot = p
    # the first triangle's pivot is the tail of its exit half-edge; take the better end
    f = 1 if tri[seq[a], _local_edge(nb, seq[a], seq[a + 1])] == p1 else 0
    r = 1 if tri[seq[b - 1], _local_edge(nb, seq[b - 1], seq[b - 2])] == pl else 0
    return n + 2 + interior + min(f, r)


@njit(cache=True)
def _relink(link, pid, seq, a, b, label):
    for i in range(a, b):
        t = seq[i]
        link[t, 0] = seq[i - 1] if i > a else -1
        link[t, 1] = seq[i + 1] if i + 1 < b else -1
        pid[t] = label


@njit(cache=True)
def _is_end(link, t):
    return link[t, 0] < 0 or link[t, 1] < 0


@njit(cache=True)
def _try_join(tri, nb, link, pid, cost, buf, a, b, label, budget):
    """Join the path ``buf[a:b]`` (its end ``buf[b-1]``) to a neighbouring path end if the total drops.

    ``budget``: cost of the paths involved so far (``buf[a:b]`` and what it replaced);
    the joined path is written after ``b``.  Returns the improved total or -1.
    """
    y = buf[b - 1]
    for k in range(3):
        v = nb[y, k]
        if v < 0 or not _is_end(link, v):
            continue
        rv = pid[v]
        if rv == label or rv == pid[y]:
            continue
        nv = _walk(link, v, -1, buf, b)
        c = _seq_cost(tri, nb, buf, a, nv)
        if c < budget + cost[rv] + 1:
            _relink(link, pid, buf, a, nv, label)
            cost[rv] = 0
            cost[label] = c
            return c
    return -1


@njit(cache=True)
def improve_paths(tri, twin, order, starts, max_passes):
    """Lower the cost (indices plus one restart per path) of a dual path cover.

    Moves around each path end ``e``, each kept only when the total strictly drops:

    * join: ``e`` next to another path's end: one path (saves a start and a restart,
      may add swaps at the joint);
    * rotate: ``e`` next to ``x`` inside its own path: ``.. x y .. e`` becomes
      ``.. x e .. y`` (Posa's rotation), kept if it saves swaps or the new end ``y``
      joins another path;
    * tunnel: ``e`` next to ``x`` inside another path ``.. w x z ..``: ``e`` takes ``x``
      and one side of it, the other side is left (and may join a third path).

    Returns ``(order, starts)`` of the improved cover.
    """
    m = tri.shape[0]
    nb = np.full((m, 3), -1, np.int64)
    for t in range(m):
        for k in range(3):
            h = twin[3 * t + k]
            if h >= 0:
                nb[t, k] = h // 3
    link = np.full((m, 2), -1, np.int64)
    pid = np.zeros(m, np.int64)
    cost = np.zeros(m, np.int64)
    S = starts.shape[0] - 1
    for s in range(S):
        _relink(link, pid, order, starts[s], starts[s + 1], s)
        cost[s] = _seq_cost(tri, nb, order, starts[s], starts[s + 1])
    buf = np.empty(3 * m, np.int64)
    seq = np.empty(m, np.int64)
    for _ in range(max_passes):
        improved = False
        for e in range(m):
            if not _is_end(link, e):
                continue
            rp = pid[e]
            n = _walk(link, e, -1, buf, 0)
            for i in range(n):
                seq[i] = buf[n - 1 - i]  # P, ending at e
            # join
            for i in range(n):
                buf[i] = seq[i]
            if _try_join(tri, nb, link, pid, cost, buf, 0, n, rp, cost[rp]) >= 0:
                improved = True
                continue
            done = False
            for k in range(3):
                x = nb[e, k]
                if x < 0 or x == link[e, 0] or x == link[e, 1]:
                    continue
                if pid[x] == rp:
                    # rotate
                    j = -1
                    for i in range(n):
                        if seq[i] == x:
                            j = i
                    for i in range(j + 1):
                        buf[i] = seq[i]
                    for i in range(j + 1, n):
                        buf[i] = seq[n - 1 - (i - j - 1)]
                    c = _seq_cost(tri, nb, buf, 0, n)
                    if c < cost[rp]:
                        _relink(link, pid, buf, 0, n, rp)
                        cost[rp] = c
                        done = True
                        break
                    if _try_join(tri, nb, link, pid, cost, buf, 0, n, rp, cost[rp]) >= 0:
                        done = True
                        break
                elif not _is_end(link, x):
                    # tunnel: P + x + one side of x; the other side is left over
                    rq = pid[x]
                    for side in range(2):
                        for i in range(n):
                            buf[i] = seq[i]
                        buf[n] = x
                        nt = _walk(link, link[x, side], x, buf, n + 1)
                        # leftover, starting next to x
                        nl = _walk(link, link[x, 1 - side], x, buf, nt)
                        # reverse it so that its new end is last
                        for i in range((nl - nt) // 2):
                            tmp = buf[nt + i]
                            buf[nt + i] = buf[nl - 1 - i]
                            buf[nl - 1 - i] = tmp
                        old = cost[rp] + cost[rq] + 1
                        c1 = _seq_cost(tri, nb, buf, 0, nt)
                        c2 = _seq_cost(tri, nb, buf, nt, nl)
                        if c1 + c2 + 1 < old:
                            _relink(link, pid, buf, 0, nt, rp)
                            _relink(link, pid, buf, nt, nl, rq)
                            cost[rp] = c1
                            cost[rq] = c2
                            done = True
                            break
                        # the leftover's new end joins a third path
                        for i in range(nl - nt):
                            buf[nl + i] = buf[nt + i]
                        # relink only if the join succeeds: test on copies of the labels
                        y = buf[nl + (nl - nt) - 1]
                        ok = False
                        for k2 in range(3):
                            v = nb[y, k2]
                            if v < 0 or not _is_end(link, v):
                                continue
                            rv = pid[v]
                            if rv == rp or rv == rq:
                                continue
                            nv = _walk(link, v, -1, buf, nl + (nl - nt))
                            c3 = _seq_cost(tri, nb, buf, nl, nv)
                            if c1 + c3 < old + cost[rv] + 1:
                                _relink(link, pid, buf, 0, nt, rp)
                                _relink(link, pid, buf, nl, nv, rq)
                                cost[rp] = c1
                                cost[rq] = c3
                                cost[rv] = 0
                                ok = True
                                break
                        if ok:
                            done = True
                            break
                    if done:
                        break
            if done:
                improved = True
        if not improved:
            break
    out = np.empty(m, np.int64)
    st = np.empty(m + 1, np.int64)
    seen = np.zeros(m, np.bool_)
    L = 0
    S2 = 0
    st[0] = 0
    for i in range(S):
        for j in range(starts[i], starts[i + 1]):
            t = order[j]
            if seen[t] or not _is_end(link, t):
                continue
            n = _walk(link, t, -1, out, L)
            for i2 in range(L, n):
                seen[out[i2]] = True
            L = n
            S2 += 1
            st[S2] = L
    return out, st[: S2 + 1].copy()
