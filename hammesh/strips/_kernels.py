"""Compiled sequential loops of the strip encoders (numba, ``cache=True``).

Everything that cannot be vectorized lives here: joining strips by degenerate
stitching (a running parity), decoding generalized strips (two registers), growing
greedy dual paths and improving the cover at its ends, the forced chains of the
sequential test, and the encoder's fast path from mesh arrays to a proven buffer
(face checks, dual components, turns, orientation, emission, the decode-and-compare
proof).  Kernels take and return plain int64/bool arrays and never raise; callers
check their inputs and turn error codes into messages.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hammesh.halfedge import _kernels as _core


def _leaf_probe(a):
    a[0] += 1
    return a[0]


def _leaf_decorator():
    """``njit(cache=True, _nrt=False)`` if this numba accepts and compiles it, else ``njit(cache=True)``.

    ``_nrt`` is a private numba option: a numba that rejects it (when decorating or when
    compiling) must not break the package, so a tiny probe is compiled (cached) first.
    """
    try:
        dec = njit(cache=True, _nrt=False)
        probe = dec(_leaf_probe)
        if probe(np.zeros(1, np.int64)) != 1:
            raise RuntimeError("probe gave a wrong result")
        return dec, True
    except Exception:  # noqa: BLE001 - any failure of the private option: plain njit
        return njit(cache=True), False


#: Helpers called inside the loops: they read and write the arrays they are given but
#: never allocate, so they are compiled without numba's reference counting (NRT);
#: otherwise every call increfs and decrefs each array argument, ~70 ns a call here,
#: which made the path-cover moves ten times slower than their arithmetic.  Falls back
#: to plain ``njit(cache=True)`` (same results, slower moves) where numba refuses it.
_leaf, LEAF_WITHOUT_NRT = _leaf_decorator()

__all__ = [
    "stitch",
    "decode_generalized",
    "greedy_paths",
    "improve_cover",
    "sequential_chain",
    "face_flags",
    "dual_components",
    "proper_twins_into",
    "orientation_count",
    "path_turns",
    "orient_paths",
    "emit_restart",
    "encode_restart",
    "permute_mesh",
    "check_draws",
    "mesh_records",
    "records_fit",
    "records_from_twin",
    "greedy_paths_records",
    "permute_records",
]


#: ``(k + 1) % 3`` as a table: an index select instead of a division or a branch.
_NEXT = np.array([1, 2, 0], np.int64)


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


@_leaf
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


@_leaf
def _visit(t, twin, deg, bucket, top):
    """Mark ``t`` visited (``deg[t] = -1``) and requeue its free neighbours one degree lower."""
    deg[t] = -1
    for k in range(3):
        h = twin[3 * t + k]
        if h < 0:
            continue
        u = h // 3
        if deg[u] >= 0:
            deg[u] -= 1
            d = deg[u]
            bucket[d, top[d]] = u
            top[d] += 1


@_leaf
def _grow(cur, entry, prev_pivot, tri, twin, deg, bucket, top, out, w_swap):
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
            h = twin[3 * cur + k]
            if h < 0:
                continue
            u = h // 3
            if deg[u] < 0:  # visited
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
        _visit(u, twin, deg, bucket, top)
        out[n] = u
        n += 1
        prev_pivot = best_pivot
        entry = h - 3 * u
        cur = u
    return n, first_exit, first_pivot


def greedy_paths(tri, twin, w_swap, seed_order):
    """Partition the dual graph into paths, greedily (O(m)).

    Seeds are taken with the fewest unvisited neighbours (a bucket queue, most recent
    first, so new paths start along the previous ones; ties at the start broken by
    ``seed_order``, last first); each path is grown forward from
    its seed, then backward through the seed's remaining edges, turn-aware.

    Returns ``(order, starts)`` as in :mod:`hammesh.strips.paths` (``order`` a view
    into the work buffer, one numpy allocation: see :func:`improve_cover`).
    """
    m = tri.shape[0]
    ws = np.empty(9 * m + 5, np.int64)
    S = _greedy_paths_into(tri, twin, w_swap, seed_order, ws)
    return ws[5 * m : 6 * m], ws[6 * m : 6 * m + S + 1].copy()


@njit(cache=True)
def _greedy_paths_into(tri, twin, w_swap, seed_order, ws):
    m = tri.shape[0]
    deg = ws[:m]  # free neighbours; -1 once visited
    bucket = ws[m : 5 * m].reshape((4, m))
    order = ws[5 * m : 6 * m]
    starts = ws[6 * m : 7 * m + 1]
    fwd = ws[7 * m + 1 : 8 * m + 1]
    bwd = ws[8 * m + 1 : 9 * m + 1]
    top = ws[9 * m + 1 : 9 * m + 5]
    top[:] = 0
    for t in range(m):
        deg[t] = (twin[3 * t] >= 0) + (twin[3 * t + 1] >= 0) + (twin[3 * t + 2] >= 0)
    for i in range(m):
        t = seed_order[i]
        d = deg[t]
        bucket[d, top[d]] = t
        top[d] += 1
    L = 0
    S = 0
    starts[0] = 0
    while True:
        seed = -1
        for d in range(4):
            while top[d] > 0:
                top[d] -= 1
                t = bucket[d, top[d]]
                if deg[t] == d:
                    seed = t
                    break
            if seed >= 0:
                break
        if seed < 0:
            break
        _visit(seed, twin, deg, bucket, top)
        nf, kf, _ = _grow(seed, -1, -1, tri, twin, deg, bucket, top, fwd, w_swap)
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
                    h = twin[3 * u + k]
                    if h >= 0 and h // 3 == fwd[1]:
                        eout = k
                if eout == (ein + 1) % 3:
                    p1 = tri[u, eout]
                else:
                    p1 = tri[u, ein]
            nbk, _, _ = _grow(seed, kf, p1, tri, twin, deg, bucket, top, bwd, w_swap)
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
    return S


# --- walking a path cover ---------------------------------------------------------------


@_leaf
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


@_leaf
def _local_edge(nb, t, u):
    """First ``k`` with ``nb[t, k] == u``, or -1.

    Branch-free: which edge leads to a path neighbour is a coin toss, and the
    mispredicted branches of the plain search had cost more than half of
    :func:`improve_cover`'s set-up.
    """
    e0 = np.int64(nb[t, 0] == u)
    e1 = np.int64(nb[t, 1] == u)
    e2 = np.int64(nb[t, 2] == u)
    return (1 - e0) * (e1 + (1 - e1) * (3 * e2 - 1))


# --- the encoder's fast path: input checks, dual components, turns, emission, proof ----


#: ``face_flags`` values.
FACE_OK, FACE_REPEATED, FACE_ZERO_AREA = 0, 1, 2


@njit(cache=True, nogil=True)
def face_flags(pts, tri, rtol, flags):
    """Fill ``flags[t]``: 1 repeated vertex, 2 zero area, 0 otherwise; return both counts.

    Zero area: twice the area is at most ``rtol`` times the longest side squared, the
    cross product taken at the vertex opposite the longest side (exact differences for
    a sliver's short side); the definition of :mod:`hammesh.strips.defects`.
    """
    m = tri.shape[0]
    d = pts.shape[1]
    n_rep = 0
    n_zero = 0
    e = np.empty((3, 3), np.float64)
    for t in range(m):
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        if a == b or b == c or c == a:
            flags[t] = FACE_REPEATED
            n_rep += 1
            continue
        best = 0.0
        kb = 0
        for k in range(3):
            p = tri[t, k]
            q = tri[t, (k + 1) % 3]
            s = 0.0
            for j in range(3):
                e[k, j] = (pts[q, j] - pts[p, j]) if j < d else 0.0
                s += e[k, j] * e[k, j]
            if s > best:
                best = s
                kb = k
        # edges at the apex (vertex kb + 2): -e[kb + 1] and e[kb + 2]
        u = e[(kb + 1) % 3]
        v = e[(kb + 2) % 3]
        cx = u[1] * v[2] - u[2] * v[1]
        cy = u[2] * v[0] - u[0] * v[2]
        cz = u[0] * v[1] - u[1] * v[0]
        if best == 0.0 or np.sqrt(cx * cx + cy * cy + cz * cz) <= rtol * best:
            flags[t] = FACE_ZERO_AREA
            n_zero += 1
        else:
            flags[t] = FACE_OK
    return n_rep, n_zero


@njit(cache=True, nogil=True)
def proper_twins_into(tri, n_points, twin, flipped):
    """Pair the halves of proper edges (two users, opposite directions); the rest get -1.

    Half-edges are bucketed by their lesser endpoint (a counting sort that also copies
    the other endpoint and the direction, so a bucket is read from contiguous memory);
    inside a bucket (a vertex's few edges) the users of each edge are gathered by the
    other endpoint.  ``flipped`` (``(3 m, 2)``) receives the half-edge pairs of edges
    used twice in one direction.  Returns ``(n_flipped, n_non_manifold)``.
    """
    m = tri.shape[0]
    H = 3 * m
    start = np.zeros(n_points + 1, np.int64)
    for t in range(m):
        for j in range(3):
            a = tri[t, j]
            b = tri[t, (j + 1) % 3]
            start[min(a, b) + 1] += 1
    for v in range(n_points):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    slot = np.empty(H, np.int64)
    other_end = np.empty(H, np.int64)
    forward = np.empty(H, np.bool_)  # the half-edge runs from the lesser endpoint
    for t in range(m):
        for j in range(3):
            a = tri[t, j]
            b = tri[t, (j + 1) % 3]
            lo = min(a, b)
            i = fill[lo]
            slot[i] = 3 * t + j
            other_end[i] = max(a, b)
            forward[i] = a < b
            fill[lo] = i + 1
            twin[3 * t + j] = -1
    done = np.zeros(H, np.bool_)
    n_flip = 0
    n_nm = 0
    for v in range(n_points):
        for i in range(start[v], start[v + 1]):
            if done[i]:
                continue
            hi = other_end[i]
            users = 1
            other = -1
            done[i] = True
            for j in range(i + 1, start[v + 1]):
                if not done[j] and other_end[j] == hi:
                    done[j] = True
                    users += 1
                    other = j
            if users == 2:
                if forward[other] != forward[i]:
                    twin[slot[i]] = slot[other]
                    twin[slot[other]] = slot[i]
                else:
                    flipped[n_flip, 0] = slot[i]
                    flipped[n_flip, 1] = slot[other]
                    n_flip += 1
            elif users >= 3:
                n_nm += 1
    return n_flip, n_nm


@njit(cache=True, nogil=True)
def orientation_count(twin, flipped, m):
    """``(pieces, non-orientable pieces)`` across proper and flipped edges (a signed search).

    A proper edge keeps the relative orientation, a flipped one reverses it; a piece
    that reaches a triangle with both signs cannot be oriented.
    """
    flip_of = np.full(3 * m, -1, np.int64)
    for i in range(flipped.shape[0]):
        flip_of[flipped[i, 0]] = flipped[i, 1]
        flip_of[flipped[i, 1]] = flipped[i, 0]
    label = np.full(m, -1, np.int64)
    sign = np.zeros(m, np.int8)
    stack = np.empty(m, np.int64)
    pieces = 0
    bad = 0
    for s in range(m):
        if label[s] >= 0:
            continue
        label[s] = pieces
        sign[s] = 1
        stack[0] = s
        top = 1
        conflict = False
        while top > 0:
            top -= 1
            t = stack[top]
            for k in range(3):
                h = 3 * t + k
                g = twin[h]
                want = sign[t]
                if g < 0:
                    g = flip_of[h]
                    want = -sign[t]
                if g < 0:
                    continue
                u = g // 3
                if label[u] < 0:
                    label[u] = pieces
                    sign[u] = want
                    stack[top] = u
                    top += 1
                elif sign[u] != want:
                    conflict = True
        if conflict:
            bad += 1
        pieces += 1
    return pieces, bad


@njit(cache=True)
def dual_components(twin, m):
    """Connected pieces of the dual graph, numbered by their least triangle (as scipy does)."""
    label = np.full(m, -1, np.int64)
    stack = np.empty(m, np.int64)
    c = 0
    for s in range(m):
        if label[s] >= 0:
            continue
        label[s] = c
        stack[0] = s
        top = 1
        while top > 0:
            top -= 1
            t = stack[top]
            for k in range(3):
                h = twin[3 * t + k]
                if h >= 0:
                    u = h // 3
                    if label[u] < 0:
                        label[u] = c
                        stack[top] = u
                        top += 1
        c += 1
    return label, c


@njit(cache=True)
def path_turns(tri, twin, order, starts):
    """Entry/exit edges, pivots, swaps and heads of flat dual paths (see ``paths.py``).

    Returns ``(first, last, entry, exit, new_vertex, pivot, swap, head, err, pos)``;
    ``err`` is 0, 1 (positions ``pos``, ``pos + 1`` share no edge) or 2 (the path
    turns back at ``pos``); on an error the arrays are incomplete.
    """
    L = order.shape[0]
    S = starts.shape[0] - 1
    first = np.zeros(L, np.bool_)
    last = np.zeros(L, np.bool_)
    entry = np.full(L, -1, np.int64)
    exit_ = np.full(L, -1, np.int64)
    new_vertex = np.full(L, -1, np.int64)
    pivot = np.full(L, -1, np.int64)
    swap = np.zeros(L, np.bool_)
    head = np.zeros((L, 3), np.int64)
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        first[a] = True
        last[b - 1] = True
        for i in range(a, b - 1):
            t = order[i]
            u = order[i + 1]
            k = -1
            for kk in range(3):
                h = twin[3 * t + kk]
                if h >= 0 and h // 3 == u:
                    k = kk
                    break
            if k < 0:
                return first, last, entry, exit_, new_vertex, pivot, swap, head, 1, i
            exit_[i] = k
            entry[i + 1] = twin[3 * t + k] - 3 * u
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        for i in range(a + 1, b - 1):
            if entry[i] == exit_[i]:
                return first, last, entry, exit_, new_vertex, pivot, swap, head, 2, i
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        t = order[a]
        if b - a == 1:
            head[a, 0] = tri[t, 0]
            head[a, 1] = tri[t, 1]
            head[a, 2] = tri[t, 2]
            continue
        k = exit_[a]
        pivot[a] = tri[t, k]
        head[a, 0] = tri[t, (k + 2) % 3]
        head[a, 1] = tri[t, k]
        head[a, 2] = tri[t, (k + 1) % 3]
        for i in range(a + 1, b):
            t = order[i]
            kin = entry[i]
            new_vertex[i] = tri[t, (kin + 2) % 3]
            if i < b - 1:
                kout = exit_[i]
                if kout == (kin + 1) % 3:
                    p = tri[t, kout]
                else:
                    p = tri[t, kin]
                pivot[i] = p
                swap[i] = p == pivot[i - 1]
    return first, last, entry, exit_, new_vertex, pivot, swap, head, 0, -1


@_leaf
def _edge_to(twin, t, u):
    """Local edge of ``t`` shared with ``u >= 0`` (first one), or -1 (branch-free, see :func:`_local_edge`)."""
    e0 = np.int64(twin[3 * t] // 3 == u)  # a boundary's -1 // 3 is -1: never u
    e1 = np.int64(twin[3 * t + 1] // 3 == u)
    e2 = np.int64(twin[3 * t + 2] // 3 == u)
    return (1 - e0) * (e1 + (1 - e1) * (3 * e2 - 1))


@_leaf
def _pivot_at(tri, twin, prev, t, nxt):
    """Vertex shared by the edges of ``t`` towards ``prev`` and ``nxt`` (direction free)."""
    kin = _edge_to(twin, t, prev)
    kout = _edge_to(twin, t, nxt)
    if kout == (kin + 1) % 3:
        return tri[t, kout]
    return tri[t, kin]


@njit(cache=True)
def orient_paths(tri, twin, order, starts):
    """Reverse each path whose first swap goes away that way.

    Interior pivots (so interior swaps) do not depend on the direction; only the swap
    after the first triangle does: it is needed when the second triangle's pivot is the
    tail of the first triangle's exit half-edge.  Paths must be valid dual paths.
    Returns ``(order, any_reversed)``.
    """
    out = order.copy()
    flipped = False
    S = starts.shape[0] - 1
    for s in range(S):
        a = starts[s]
        b = starts[s + 1] - 1
        if b - a < 2:
            continue
        t0 = order[a]
        sf = tri[t0, _edge_to(twin, t0, order[a + 1])] == _pivot_at(tri, twin, t0, order[a + 1], order[a + 2])
        if not sf:
            continue
        tb = order[b]
        sb = tri[tb, _edge_to(twin, tb, order[b - 1])] == _pivot_at(tri, twin, order[b - 2], order[b - 1], tb)
        if not sb:
            flipped = True
            for i in range(b - a + 1):
                out[a + i] = order[b - i]
    return out, flipped


@njit(cache=True)
def emit_restart(first, swap, head, pivot, new_vertex, starts, restart):
    """The GL buffer of analysed paths, each from an even position, joined by ``restart``.

    Returns ``(indices, max_index)``.
    """
    L = first.shape[0]
    S = starts.shape[0] - 1
    total = S - 1
    for i in range(L):
        if first[i]:
            total += 3
        else:
            total += 2 if swap[i] else 1
    out = np.empty(total, np.int64)
    pos = 0
    mx = -1
    for s in range(S):
        if s > 0:
            out[pos] = restart
            pos += 1
        a = starts[s]
        for j in range(3):
            v = head[a, j]
            out[pos] = v
            pos += 1
            if v > mx:
                mx = v
        for i in range(a + 1, starts[s + 1]):
            if swap[i]:
                out[pos] = pivot[i - 1]
                pos += 1
            v = new_vertex[i]
            out[pos] = v
            pos += 1
            if v > mx:
                mx = v
    return out, mx


@njit(cache=True)
def _same_rotation(a, b, c, x, y, z):
    # & and | rather than short-circuit `and` / `or`: no branches
    return ((a == x) & (b == y) & (c == z)) | ((a == y) & (b == z) & (c == x)) | ((a == z) & (b == x) & (c == y))


@njit(cache=True)
def check_draws(tri, indices, restart, use_restart, order):
    """Decode ``indices`` with OpenGL's strip rules and compare with a claimed draw order.

    The ``k``-th non-degenerate triangle drawn must be ``tri[order[k]]`` with the same
    winding (any rotation), and ``order`` must name every row exactly once: then the
    buffer draws exactly the mesh's oriented triangles.  Returns ``(status, k)``:
    0 ok; 1 draw ``k`` differs from the claim; 2 more draws than rows; 3 fewer (``k``
    draws); 4 ``order[k]`` out of range or repeated.
    """
    m = tri.shape[0]
    if order.shape[0] != m:
        return 4, min(order.shape[0], m)
    seen = np.zeros(m, np.bool_)
    for k in range(m):
        t = order[k]
        if t < 0 or t >= m or seen[t]:
            return 4, k
        seen[t] = True
    L = indices.shape[0]
    pos = 0  # position inside the current strip
    k = 0
    for i in range(L):
        v = indices[i]
        if use_restart and v == restart:
            pos = 0
            continue
        if pos >= 2:
            a = indices[i - 2]
            b = indices[i - 1]
            # selects instead of branches: a degenerate window (a swap, ~1 in 5) or the
            # window's parity would be mispredicted; the row read for a degenerate
            # window is ignored, the two early exits almost never taken
            drawn = (a != b) & (b != v) & (a != v)
            if drawn & (k >= m):
                return 2, k
            t = order[min(k, m - 1)]
            odd = pos % 2 == 1  # window starts at an odd position: drawn (b, a, v)
            x = b if odd else a
            y = a if odd else b
            if drawn & (_same_rotation(x, y, v, tri[t, 0], tri[t, 1], tri[t, 2]) == False):  # noqa: E712
                return 1, k
            k += np.int64(drawn)
        pos += 1
    if k != m:
        return 3, k
    return 0, -1


# --- improving a path cover with O(1) cost updates ---------------------------------------
#
# The cover is a set of undirected links ``lk[t] = (a, b)`` (path neighbours, -1 at an
# end), a label per path (``pid``), the path size per label and the other end of each
# end triangle (``oth``).  The buffer's length is
#     sum over paths (n + 2 + end term) + I + (S - 1) restarts,
# where I counts links between two interior triangles with the same pivot (a swap) and
# the end term of a path of n >= 3 triangles is 1 when both ends start with a swap.
# A pivot depends only on the triangle's own links, so a move that changes the links of
# a few triangles C changes I only on links touching C: every move is costed in O(1),
# applied tentatively and undone unless the total drops.


@_leaf
def _pivot(tri, lk, le, t):
    """Pivot of an interior triangle (vertex shared by its two path edges), -1 at an end.

    ``le[t, j]`` is the local edge of ``t`` towards its path neighbour ``lk[t, j]``.
    """
    if lk[t, 0] < 0 or lk[t, 1] < 0:
        return -1
    k0 = le[t, 0]
    k1 = le[t, 1]
    k = k1 if k1 == _NEXT[k0] else k0  # an index select (no data-dependent branch)
    return tri[t, k]


@_leaf
def _local_swaps(tri, lk, le, C, nC):
    """Swaps (links between interior triangles with equal pivots) on links touching ``C[:nC]``."""
    s = 0
    for i in range(nC):
        c = C[i]
        pc = _pivot(tri, lk, le, c)
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
            if _pivot(tri, lk, le, u) == pc:
                s += 1
    return s


@_leaf
def _end_flag(tri, lk, le, a):
    """Starting at end ``a`` costs a swap after the first triangle (path of >= 3)."""
    j = 0 if lk[a, 0] >= 0 else 1
    return 1 if tri[a, le[a, j]] == _pivot(tri, lk, le, lk[a, j]) else 0


@_leaf
def _end_term(tri, lk, le, a, b, n):
    if n < 3:
        return 0
    return min(_end_flag(tri, lk, le, a), _end_flag(tri, lk, le, b))


@_leaf
def _set_link(lk, le, nb, t, old, new):
    j = 0 if lk[t, 0] == old else 1
    lk[t, j] = new
    k = _local_edge(nb, t, new)
    le[t, j] = k if new >= 0 else -1  # (-1 would find a boundary edge)


@_leaf
def _in_links(lk, t, u):
    return lk[t, 0] == u or lk[t, 1] == u


@_leaf
def _renumber(lk, pid, ps, t, prev, label, p, d, n):
    """Give ``label`` and positions ``p, p + d, ...`` to ``n`` triangles from ``t``, walking away from ``prev``."""
    for _ in range(n):
        pid[t] = label
        ps[t] = p
        p += d
        a = lk[t, 0]
        nxt = a if a != prev else lk[t, 1]
        prev = t
        t = nxt


@_leaf
def _beyond(lk, ps, t, excl):
    """Step of the positions leaving path end ``t`` outwards (``excl``: a link to ignore)."""
    for j in range(2):
        u = lk[t, j]
        if u >= 0 and u != excl:
            return ps[t] - ps[u]
    return 1


@_leaf
def _toward(ps, x, u, t):
    """Does ``x``'s path neighbour ``u`` lie on the side of ``t`` (same path)?"""
    return (ps[u] - ps[x] > 0) == (ps[t] - ps[x] > 0)


@_leaf
def _rotate_positions(lk, pid, ps, x, e, label, dxy, nseg, n):
    """Positions after a rotation ``f .. x y .. e`` -> ``f .. x e .. y`` (links already changed).

    ``dxy`` was the step from ``x`` towards ``y`` and ``nseg`` the triangles ``y .. e``;
    renumbers the shorter of ``e .. y`` and ``x .. f``.
    """
    if nseg <= n - nseg:
        _renumber(lk, pid, ps, e, x, label, ps[x] + dxy, dxy, nseg)
    else:
        _renumber(lk, pid, ps, x, e, label, ps[e] + dxy, dxy, n - nseg)


@_leaf
def _mark(nb, lk, dirty, c):
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


@_leaf
def _shared(tri, t, k0, k1):
    """Vertex shared by the distinct local edges ``k0`` and ``k1`` of ``t`` (either order)."""
    return tri[t, k1 if k1 == _NEXT[k0] else k0]


@_leaf
def _tunnel_swaps(tri, lk, le, nb, e, x, side, nP):
    """Swaps on the links a tunnel creates: ``(p, e)``, ``(e, x)`` and ``(x, z)``, ``z = lk[x, side]``.

    Read before the move (``p`` is ``e``'s path neighbour, if any): a lower bound of
    the move's new cost, which also counts end terms (>= 0) and no other link (``w``
    becomes an end).
    """
    z = lk[x, side]
    pnx = _shared(tri, x, _local_edge(nb, x, e), le[x, side])  # x's pivot between e and z
    n = 1 if _pivot(tri, lk, le, z) == pnx else 0
    if nP >= 2:
        j = 0 if lk[e, 0] >= 0 else 1
        pne = _shared(tri, e, le[e, j], _local_edge(nb, e, x))  # e's pivot between p and x
        n += 1 if pne == pnx else 0
        n += 1 if _pivot(tri, lk, le, lk[e, j]) == pne else 0
    return n


@_leaf
def _third_end(nb, lk, pid, w, x, rp, rq):
    """Has ``w`` (losing its link to ``x`` in a tunnel) a neighbouring end of a path other than ``rp``, ``rq``?

    The candidates a tunnel's third join tries, read before the move: the move only
    changes the links of ``e`` (label ``rp``), ``x`` (interior before and after) and ``w``.
    """
    for k in range(3):
        v = nb[w, k]
        if v < 0 or v == x or _in_links(lk, w, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0):
            continue
        if pid[v] != rp and pid[v] != rq:
            return True
    return False


def improve_cover(tri, twin, order, starts, max_passes, visit):
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

    The work arrays (7 m + 1 int64 and 7 m int32) are numpy buffers sliced by the
    kernel: numpy asks for transparent huge pages on big ones, and first-touch page
    faults of a dozen separately allocated arrays had cost ~1/3 of the moves' time at
    100k triangles.  (Positions stay int64: a committed move continues them from a
    neighbour's, so they may drift outside ``[0, m)``; an int32 work buffer measured no
    faster.)
    """
    m = tri.shape[0]
    ws = np.empty(7 * m + 1, np.int64)
    # neighbours, links and their local edges: the arrays every move reads, half the bytes
    links = np.empty(7 * m, np.int32 if 3 * m < 2**31 else np.int64)
    flags = np.empty(2 * m, np.bool_)
    S2 = _improve_cover_into(tri, twin, order, starts, max_passes, visit, ws, links, flags)
    if S2 < 0:
        return order.copy(), starts.copy()
    return ws[5 * m : 6 * m], ws[6 * m : 6 * m + S2 + 1].copy()


@njit(cache=True)
def _improve_cover_into(tri, twin, order, starts, max_passes, visit, ws, links, flags):
    m = tri.shape[0]
    nb = links[: 3 * m].reshape((m, 3))
    lk = links[3 * m : 5 * m].reshape((m, 2))
    le = links[5 * m : 7 * m].reshape((m, 2))
    pid = ws[:m]
    oth = ws[m : 2 * m]
    size = ws[2 * m : 3 * m]
    ps = ws[3 * m : 4 * m]  # positions: consecutive integers along each path
    pend = ws[4 * m : 5 * m]  # one end of each path label
    out = ws[5 * m : 6 * m]
    st = ws[6 * m : 7 * m + 1]
    dirty = flags[:m]  # ends to (re)consider: all at first, then near changes
    seen = flags[m:]
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
                le[t, 0] = _local_edge(nb, t, order[i - 1])
            if i + 1 < b:
                lk[t, 1] = order[i + 1]
                le[t, 1] = _local_edge(nb, t, order[i + 1])
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
                if v < 0 or _in_links(lk, e, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0) or pid[v] == rp:
                    continue
                rv = pid[v]
                g = oth[v]
                nQ = size[rv]
                C[0] = e
                C[1] = v
                before = _local_swaps(tri, lk, le, C, 2) + _end_term(tri, lk, le, e, f, nP)
                before += _end_term(tri, lk, le, v, g, nQ)
                _set_link(lk, le, nb, e, -1, v)
                _set_link(lk, le, nb, v, -1, e)
                after = _local_swaps(tri, lk, le, C, 2) + _end_term(tri, lk, le, f, g, nP + nQ)
                if after - before - 3 < 0:
                    if nP < nQ:
                        d = _beyond(lk, ps, v, e)
                        _renumber(lk, pid, ps, e, v, rv, ps[v] + d, d, nP)
                        keep, gone = rv, rp
                    else:
                        d = _beyond(lk, ps, e, v)
                        _renumber(lk, pid, ps, v, e, rp, ps[e] + d, d, nQ)
                        keep, gone = rp, rv
                    pend[keep] = f
                    size[keep] = nP + nQ
                    size[gone] = 0
                    oth[f] = g
                    oth[g] = f
                    T[0] = e
                    T[1] = v
                    T[2] = f
                    T[3] = g
                    nT = 4
                    done = True
                    break
                _set_link(lk, le, nb, e, v, -1)
                _set_link(lk, le, nb, v, e, -1)
            if done:
                for i in range(nT):
                    _mark(nb, lk, dirty, T[i])
                improved = True
                continue
            for k in range(3):
                x = nb[e, k]
                if x < 0 or _in_links(lk, e, x):
                    continue
                if pid[x] == rp:
                    # rotate: y is x's neighbour on e's side
                    if lk[x, 0] < 0 or lk[x, 1] < 0:
                        y = lk[x, 0] if lk[x, 0] >= 0 else lk[x, 1]  # x == f
                    else:
                        y = lk[x, 0] if _toward(ps, x, lk[x, 0], e) else lk[x, 1]
                    dxy = 1 if ps[e] > ps[x] else -1
                    nseg = abs(ps[e] - ps[x])  # triangles y .. e
                    C[0] = x
                    C[1] = y
                    C[2] = e
                    before = _local_swaps(tri, lk, le, C, 3) + _end_term(tri, lk, le, e, f, nP)
                    _set_link(lk, le, nb, x, y, e)
                    _set_link(lk, le, nb, y, x, -1)
                    _set_link(lk, le, nb, e, -1, x)
                    after = _local_swaps(tri, lk, le, C, 3) + _end_term(tri, lk, le, y, f, nP)
                    if after < before:
                        _rotate_positions(lk, pid, ps, x, e, rp, dxy, nseg, nP)
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
                        if v < 0 or _in_links(lk, y, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0) or pid[v] == rp:
                            continue
                        rv = pid[v]
                        g = oth[v]
                        nQ = size[rv]
                        C[3] = v
                        bj = _local_swaps(tri, lk, le, C[1:], 1) + _local_swaps(tri, lk, le, C[3:], 1)
                        bj += _end_term(tri, lk, le, v, g, nQ) + _end_term(tri, lk, le, y, f, nP)
                        _set_link(lk, le, nb, y, -1, v)
                        _set_link(lk, le, nb, v, -1, y)
                        C[4] = y
                        aj = _local_swaps(tri, lk, le, C[3:], 2) + _end_term(tri, lk, le, f, g, nP + nQ)
                        # bj counted y's and v's links apart; no link joined them before
                        total = (after - before) + (aj - bj) - 3
                        if total < 0:
                            _rotate_positions(lk, pid, ps, x, e, rp, dxy, nseg, nP)
                            if nP < nQ:
                                d = _beyond(lk, ps, v, y)
                                _renumber(lk, pid, ps, y, v, rv, ps[v] + d, d, nP)
                                keep, gone = rv, rp
                            else:
                                d = _beyond(lk, ps, y, v)
                                _renumber(lk, pid, ps, v, y, rp, ps[y] + d, d, nQ)
                                keep, gone = rp, rv
                            pend[keep] = f
                            size[keep] = nP + nQ
                            size[gone] = 0
                            oth[f] = g
                            oth[g] = f
                            T[0] = x
                            T[1] = y
                            T[2] = e
                            T[3] = f
                            T[4] = v
                            T[5] = g
                            nT = 6
                            done = True
                            break
                        _set_link(lk, le, nb, y, v, -1)
                        _set_link(lk, le, nb, v, y, -1)
                    if done:
                        break
                    _set_link(lk, le, nb, e, x, -1)
                    _set_link(lk, le, nb, y, -1, x)
                    _set_link(lk, le, nb, x, e, y)
                elif lk[x, 0] >= 0 and lk[x, 1] >= 0:
                    # tunnel into x's path
                    rq = pid[x]
                    nQ = size[rq]
                    a0 = pend[rq]
                    if _toward(ps, x, lk[x, 0], a0):
                        end0 = a0
                        end1 = oth[a0]
                    else:
                        end1 = a0
                        end0 = oth[a0]
                    n0 = abs(ps[end0] - ps[x])
                    n1 = abs(ps[end1] - ps[x])
                    for side in range(2):
                        z = lk[x, side]
                        w = lk[x, 1 - side]
                        endB = end0 if side == 0 else end1
                        nB = n0 if side == 0 else n1
                        endA = end1 if side == 0 else end0
                        nA = n1 if side == 0 else n0
                        C[0] = e
                        C[1] = x
                        C[2] = w
                        before = _local_swaps(tri, lk, le, C, 3) + _end_term(tri, lk, le, e, f, nP)
                        before += _end_term(tri, lk, le, end0, end1, nQ)
                        if before <= _tunnel_swaps(tri, lk, le, nb, e, x, side, nP) and not _third_end(
                            nb, lk, pid, w, x, rp, rq
                        ):
                            # the swaps the move creates already cost what it could save
                            # (end terms are >= 0), and w has no third path to join: skip
                            # what evaluating the move would find (most tunnels end here)
                            continue
                        _set_link(lk, le, nb, e, -1, x)
                        _set_link(lk, le, nb, x, w, e)
                        _set_link(lk, le, nb, w, x, -1)
                        nP2 = nP + 1 + nB
                        after = _local_swaps(tri, lk, le, C, 3) + _end_term(tri, lk, le, f, endB, nP2)
                        after += _end_term(tri, lk, le, w, endA, nA)
                        ok = after < before
                        rv = -1
                        g = -1
                        nR = 0
                        if not ok:
                            # the leftover's new end w joins a third path
                            for k2 in range(3):
                                v = nb[w, k2]
                                if v < 0 or _in_links(lk, w, v) or (lk[v, 0] >= 0 and lk[v, 1] >= 0):
                                    continue
                                if pid[v] == rp or pid[v] == rq:
                                    continue
                                rv = pid[v]
                                g = oth[v]
                                nR = size[rv]
                                C[3] = w
                                C[4] = v
                                bj = _local_swaps(tri, lk, le, C[3:], 2) + _end_term(tri, lk, le, v, g, nR)
                                bj += _end_term(tri, lk, le, w, endA, nA)
                                _set_link(lk, le, nb, w, -1, v)
                                _set_link(lk, le, nb, v, -1, w)
                                aj = _local_swaps(tri, lk, le, C[3:], 2) + _end_term(tri, lk, le, endA, g, nA + nR)
                                if (after - before) + (aj - bj) - 3 < 0:
                                    ok = True
                                    break
                                _set_link(lk, le, nb, w, v, -1)
                                _set_link(lk, le, nb, v, w, -1)
                                rv = -1
                        if ok:
                            # labels: x and B join P (label rp); A keeps rq
                            d = _beyond(lk, ps, e, x)
                            _renumber(lk, pid, ps, x, e, rp, ps[e] + d, d, nB + 1)
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
                                if nA < nR:
                                    d = _beyond(lk, ps, v, w)
                                    _renumber(lk, pid, ps, w, v, rv, ps[v] + d, d, nA)
                                    keep, gone = rv, rq
                                else:
                                    d = _beyond(lk, ps, w, v)
                                    _renumber(lk, pid, ps, v, w, rq, ps[w] + d, d, nR)
                                    keep, gone = rq, rv
                                pend[keep] = endA
                                size[keep] = nA + nR
                                size[gone] = 0
                                oth[endA] = g
                                oth[g] = endA
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
                        _set_link(lk, le, nb, w, -1, x)
                        _set_link(lk, le, nb, x, e, w)
                        _set_link(lk, le, nb, e, x, -1)
                    if done:
                        break
            if done:
                for i in range(nT):
                    _mark(nb, lk, dirty, T[i])
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
        n = _walk(lk, t, -1, out, L)
        for i2 in range(L, n):
            seen[out[i2]] = True
        L = n
        S2 += 1
        st[S2] = L
    return S2


def encode_restart(tri, twin, order, starts, restart):
    """The restart-joined GL buffer of flat dual paths in one pass, no per-position arrays.

    The same turns as :func:`path_turns` + :func:`emit_restart` (head of each path:
    opposite vertex, then the exit half-edge's tail and head; then one new vertex per
    triangle, preceded by the previous pivot where two pivots coincide), computed on
    the fly: the encoder's fast path.  Returns ``(indices, n_swaps, max_index, err)``;
    ``err`` is 0, or 1 when a path is not a dual path (call :func:`path_turns` for
    the message).  The buffer is allocated by numpy at its bound ``2 L + 3 S`` and
    ``indices`` is its filled prefix (one pass instead of counting the swaps first).
    """
    out = np.empty(2 * order.shape[0] + 3 * (starts.shape[0] - 1), np.int64)
    n, n_swaps, mx, err = _encode_restart_into(tri, twin, order, starts, restart, out)
    if err:
        return out[:0], 0, -1, err
    return out[:n], n_swaps, mx, 0


@njit(cache=True)
def _encode_restart_into(tri, twin, order, starts, restart, out):
    S = starts.shape[0] - 1
    n_swaps = 0
    pos = 0
    mx = -1
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        if s > 0:
            out[pos] = restart
            pos += 1
        t = order[a]
        if b - a == 1:
            for j in range(3):
                out[pos] = tri[t, j]
                pos += 1
                mx = max(mx, tri[t, j])
            continue
        k = _edge_to(twin, t, order[a + 1])
        if k < 0:
            return 0, 0, -1, 1
        out[pos] = tri[t, (k + 2) % 3]
        out[pos + 1] = tri[t, k]
        out[pos + 2] = tri[t, (k + 1) % 3]
        pos += 3
        mx = max(mx, tri[t, 0], tri[t, 1], tri[t, 2])
        prev_pivot = tri[t, k]
        kprev = k
        for i in range(a + 1, b):
            t = order[i]
            kin = twin[3 * order[i - 1] + kprev] - 3 * t
            v = tri[t, (kin + 2) % 3]
            if i < b - 1:
                kout = _edge_to(twin, t, order[i + 1])
                if kout < 0 or kout == kin:
                    return 0, 0, -1, 1
                p = tri[t, kout if kout == _NEXT[kin] else kin]
                # a swap (two equal pivots) in ~1 of 5 positions: written always, kept
                # by advancing or not (a branch here is mispredicted at every swap)
                sw = np.int64(p == prev_pivot)
                out[pos] = prev_pivot
                pos += sw
                n_swaps += sw
                prev_pivot = p
                kprev = kout
            out[pos] = v
            pos += 1
            mx = max(mx, v)
    return pos, n_swaps, mx, 0


def permute_mesh(tri, twin, order):
    """The mesh renumbered so that triangle ``i`` is ``order[i]`` (a permutation).

    Returns ``(tri2, twin2, new_id)``: ``tri2[i] = tri[order[i]]`` (rows and windings
    kept), ``twin2`` the same pairing in the new numbering, ``new_id[t]`` the new
    number of triangle ``t``.  In path order, neighbours along the paths are
    neighbours in memory: the improvement moves and the emission then read mostly
    cached rows.  ``tri2`` and ``twin2`` are int32 where the values fit (half the
    bytes for every later pass to read), else int64.
    """
    m = tri.shape[0]
    small = 3 * m < 2**31 and (m == 0 or int(tri.max()) < 2**31)
    buf = np.empty(6 * m, np.int32 if small else np.int64)  # one buffer (huge pages when >= 4 MB)
    tri2 = buf[: 3 * m].reshape(m, 3)
    twin2 = buf[3 * m :]
    new_id = np.empty(m, np.int64)
    _permute_mesh_into(tri, twin, order, tri2, twin2, new_id)
    return tri2, twin2, new_id


@njit(cache=True)
def _permute_mesh_into(tri, twin, order, tri2, twin2, new_id):
    m = tri.shape[0]
    for i in range(m):
        new_id[order[i]] = i
    for i in range(m):
        t = order[i]
        for k in range(3):
            tri2[i, k] = tri[t, k]
            h = twin[3 * t + k]
            if h >= 0:
                u = h // 3
                twin2[3 * i + k] = 3 * new_id[u] + (h - 3 * u)
            else:
                twin2[3 * i + k] = -1


# --- one record per triangle: the encoder's fast path from the input's numbering ------
#
# The greedy cover and the renumbering read a triangle's vertices, its three twins and
# its neighbours' free degrees in Triangle's scattered numbering: almost every step is a
# cache miss.  With ``int64`` rows and a separate ``int64`` pairing that is two misses
# per triangle (24 bytes of ``tri`` and 24 of ``twin``, 4.8 MB at 100k triangles); a
# 32-byte ``int32`` record ``(v0, v1, v2, twin0, twin1, twin2, scratch, pad)`` holds all
# of it in one half cache line (3.2 MB), ~30% less time for the greedy cover at 100k.

#: Columns of a triangle record (:func:`mesh_records`).
REC_TWIN = 3
REC_SCRATCH = 6
REC_WIDTH = 8


def records_fit(m, n_points):
    """Can ``m`` triangles on ``n_points`` vertices be packed in ``int32`` records?"""
    return 3 * m < 2**31 - 1 and n_points < 2**30


def mesh_records(tri, n_points):
    """Triangle records and the half-edge pairing, ``(rec, twin)`` or ``None``.

    ``rec[t] = (tri[t, 0], tri[t, 1], tri[t, 2], twin[3 t], twin[3 t + 1], twin[3 t + 2],
    scratch, 0)`` as ``int32``; ``twin`` is :func:`hammesh.halfedge._kernels.half_edge_twins`'s
    pairing (its packed fast path), the records one sequential pass after it. ``None``
    when the mesh does not fit :func:`records_fit` or has an edge used twice in one
    direction or by three triangles: the caller then asks the reference kernel, which
    names the half-edge. All buffers are numpy's (huge pages, see :func:`improve_cover`).
    """
    m = tri.shape[0]
    if not records_fit(m, n_points):
        return None
    twin = np.empty(3 * m, np.int64)
    if not _core.half_edge_twins_packed(tri, n_points, twin, np.empty(3 * m, np.int64)):
        return None
    rec = np.empty((m, REC_WIDTH), np.int32)
    records_from_twin(tri, twin, rec)
    return rec, twin


@njit(cache=True)
def records_from_twin(tri, twin, rec):
    for t in range(tri.shape[0]):
        for k in range(3):
            rec[t, k] = tri[t, k]
            rec[t, REC_TWIN + k] = twin[3 * t + k]
        rec[t, 6] = 0
        rec[t, 7] = 0


@_leaf
def _visit_rec(t, rec, bucket, top):
    """:func:`_visit` on records: the free degree lives in the scratch column."""
    rec[t, REC_SCRATCH] = -1
    for k in range(3):
        h = rec[t, REC_TWIN + k]
        if h < 0:
            continue
        u = h // 3
        d = rec[u, REC_SCRATCH]
        if d >= 0:
            d -= 1
            rec[u, REC_SCRATCH] = d
            bucket[d, top[d]] = u
            top[d] += 1


@_leaf
def _grow_rec(cur, entry, prev_pivot, rec, bucket, top, out, w_swap):
    """:func:`_grow` on records (the same choices)."""
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
            h = rec[cur, REC_TWIN + k]
            if h < 0:
                continue
            u = h // 3
            du = rec[u, REC_SCRATCH]
            if du < 0:  # visited
                continue
            if entry < 0:
                pivot = rec[cur, k]
            elif k == (entry + 1) % 3:
                pivot = rec[cur, k]
            else:
                pivot = rec[cur, entry]
            swap = 1 if (prev_pivot >= 0 and pivot == prev_pivot) else 0
            score = 2 * du + w_swap * swap
            if score < best_score:
                best_score = score
                best = k
                best_pivot = pivot
        if best < 0:
            break
        if n == 0:
            first_exit = best
            first_pivot = best_pivot
        h = rec[cur, REC_TWIN + best]
        u = h // 3
        _visit_rec(u, rec, bucket, top)
        out[n] = u
        n += 1
        prev_pivot = best_pivot
        entry = h - 3 * u
        cur = u
    return n, first_exit, first_pivot


def greedy_paths_records(rec, w_swap, seed_order):
    """:func:`greedy_paths` on triangle records (:func:`mesh_records`): the same paths.

    Overwrites the records' scratch column (free degrees).  The work buffer is
    ``int32`` (half the bytes of the bucket queue); ``order`` is a view into it.
    """
    m = rec.shape[0]
    ws = np.empty(9 * m + 5, np.int32)
    S = _greedy_records_into(rec, w_swap, seed_order, ws)
    return ws[5 * m : 6 * m], ws[6 * m : 6 * m + S + 1].astype(np.int64)


@njit(cache=True)
def _greedy_records_into(rec, w_swap, seed_order, ws):
    m = rec.shape[0]
    bucket = ws[m : 5 * m].reshape((4, m))
    order = ws[5 * m : 6 * m]
    starts = ws[6 * m : 7 * m + 1]
    fwd = ws[7 * m + 1 : 8 * m + 1]
    bwd = ws[8 * m + 1 : 9 * m + 1]
    top = ws[9 * m + 1 : 9 * m + 5]
    top[:] = 0
    for t in range(m):
        rec[t, REC_SCRATCH] = (rec[t, 3] >= 0) + (rec[t, 4] >= 0) + (rec[t, 5] >= 0)
    for i in range(m):
        t = seed_order[i]
        d = rec[t, REC_SCRATCH]
        bucket[d, top[d]] = t
        top[d] += 1
    L = 0
    S = 0
    starts[0] = 0
    while True:
        seed = -1
        for d in range(4):
            while top[d] > 0:
                top[d] -= 1
                t = bucket[d, top[d]]
                if rec[t, REC_SCRATCH] == d:
                    seed = t
                    break
            if seed >= 0:
                break
        if seed < 0:
            break
        _visit_rec(seed, rec, bucket, top)
        nf, kf, _ = _grow_rec(seed, -1, -1, rec, bucket, top, fwd, w_swap)
        nbk = 0
        if nf > 0:
            # the triangle after the seed: its pivot is what the seed's turn must avoid
            p1 = -1
            if nf >= 2:
                u = fwd[0]
                ein = rec[seed, REC_TWIN + kf] - 3 * u
                eout = -1
                for k in range(3):
                    h = rec[u, REC_TWIN + k]
                    if h >= 0 and h // 3 == fwd[1]:
                        eout = k
                if eout == (ein + 1) % 3:
                    p1 = rec[u, eout]
                else:
                    p1 = rec[u, ein]
            nbk, _, _ = _grow_rec(seed, kf, p1, rec, bucket, top, bwd, w_swap)
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
    return S


def permute_records(rec, order):
    """:func:`permute_mesh` from triangle records (one record read per row): ``(tri2, twin2, new_id)``.

    ``tri2`` and ``twin2`` are ``int32`` (the records fit), ``new_id`` ``int64``.
    """
    m = rec.shape[0]
    buf = np.empty(6 * m, np.int32)
    tri2 = buf[: 3 * m].reshape(m, 3)
    twin2 = buf[3 * m :]
    new_id = np.empty(m, np.int64)
    _permute_records_into(rec, order, tri2, twin2, new_id)
    return tri2, twin2, new_id


@njit(cache=True)
def _permute_records_into(rec, order, tri2, twin2, new_id):
    m = rec.shape[0]
    for i in range(m):
        new_id[order[i]] = i
    for i in range(m):
        t = order[i]
        for k in range(3):
            tri2[i, k] = rec[t, k]
            h = rec[t, REC_TWIN + k]
            if h >= 0:
                u = h // 3
                twin2[3 * i + k] = 3 * new_id[u] + (h - 3 * u)
            else:
                twin2[3 * i + k] = -1
