"""Compiled inner loops (numba) for the few steps numpy cannot vectorize.

Each kernel is O(m) over a plain int64/float64 array, returns plain arrays and
reports problems through a return code (never raises: the callers turn codes into
hammesh exceptions with a message). ``cache=True`` stores the machine code in
``__pycache__`` so only the very first run in an environment pays the compile time
(measured in ``benchmarks/bench_core.py``).

Large outputs are allocated by numpy in thin Python wrappers and filled by a
``_..._into`` kernel: numpy asks the kernel for transparent huge pages on big
arrays and numba's allocator does not, and first-touch page faults made fresh numba
arrays about 3x slower to fill on this project's machine (200 MB: 0.07 s vs 0.23 s).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hammesh._threads import row_ranges, run_all
from hammesh.predicates import orient_points

__all__ = [
    "orient_ccw",
    "twins_from_neighbors",
    "incenters",
    "boundary_half_edges",
    "half_edge_twins",
    "vertex_half_edges",
    "mark_segments",
    "vertex_neighbors",
    "emit_cycles",
    "emit_cycles_into",
    "split_slots",
    "spanning_forest",
    "first_cross_run_edge",
    "angle_area_stats",
    "certify_rows",
    "certify_row_range",
    "mark_used",
]


#: Rows per thread below which a row pass runs in one call (``hammesh._threads``).
THREAD_MIN_ROWS = 200_000


def index_dtype(n):
    """int32 for indices below ``n`` when they fit (half the memory traffic), else int64."""
    return np.int32 if n < 2**31 - 1 else np.int64


def orient_ccw(points, tri, used=None):
    """Counter-clockwise copy of ``tri`` (rows with negative area reversed).

    Returns ``(ccw, n_flipped, bad, (min_angle, total_area))``: ``bad`` is -1 or the
    first triangle with a repeated vertex or zero area; the smallest angle (radians)
    and the total area of the counter-clockwise rows come from the same pass, as
    ``angle_area_stats`` would compute them (the certificate needs them of its input).
    ``used`` (bool per point), if given, is set for every vertex of a triangle.
    """
    out = np.empty_like(tri)
    if used is None:
        used = np.zeros(points.shape[0], np.bool_)
    parts = run_all([
        (lambda lo=lo, hi=hi: _orient_ccw_into(points, tri, out, used, lo, hi))
        for lo, hi in row_ranges(tri.shape[0], THREAD_MIN_ROWS)
    ])
    bads = [p[1] for p in parts if p[1] >= 0]
    s2 = min(p[2] for p in parts)
    min_angle = float(np.arcsin(np.sqrt(min(max(s2, 0.0), 1.0))))
    total = math.fsum(p[3] for p in parts)
    return out, sum(p[0] for p in parts), (min(bads) if bads else -1), (min_angle, total)


@njit(cache=True, nogil=True, error_model="numpy")
def _orient_ccw_into(points, tri, out, used, lo, hi):
    n_flipped = 0
    bad = -1
    best_s2 = np.inf
    total = 0.0
    for t in range(lo, hi):
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        used[a] = True
        used[b] = True
        used[c] = True
        cr = (points[b, 0] - points[a, 0]) * (points[c, 1] - points[a, 1]) - (
            points[b, 1] - points[a, 1]
        ) * (points[c, 0] - points[a, 0])
        if (a == b or b == c or c == a or cr == 0.0) and bad < 0:
            bad = t
        if cr < 0.0:
            out[t, 0] = c
            out[t, 1] = b
            out[t, 2] = a
            n_flipped += 1
        else:
            out[t, 0] = a
            out[t, 1] = b
            out[t, 2] = c
        cr2, s2, _ = _measures(points, out[t, 0], out[t, 1], out[t, 2])  # as the certificate does
        total += 0.5 * cr2
        if s2 < best_s2:
            best_s2 = s2
    return n_flipped, bad, best_s2, total


def twins_from_neighbors(tri, nbr):
    """Half-edge twins from a neighbour array (``nbr[t, k]`` across edge ``(k, k+1)``).

    Returns ``(twin, bad)``; ``bad`` is -1, or a half-edge whose claimed neighbour
    does not hold the same edge reversed or does not name it back (then the
    neighbours are not to be trusted and the caller matches half-edges itself).
    Each pair is matched once, from its lower triangle (half the random reads of
    checking both sides), in threads over row ranges; a second pass checks that the
    higher side was matched. A half-edge is only ever matched by the triangle its
    own row names, so threads never write the same entry.
    """
    twin = np.full(3 * tri.shape[0], -1, np.int64)
    spans = row_ranges(tri.shape[0], THREAD_MIN_ROWS)
    for step in (_twins_from_neighbors_into, _unmatched_neighbor):
        bads = [b for b in run_all([
            (lambda lo=lo, hi=hi: step(tri, nbr, twin, lo, hi)) for lo, hi in spans
        ]) if b >= 0]
        if bads:
            return twin, min(bads)
    return twin, -1


@njit(cache=True, nogil=True)
def _twins_from_neighbors_into(tri, nbr, twin, lo, hi):
    m = tri.shape[0]
    for t in range(lo, hi):
        for k in range(3):
            u = nbr[t, k]
            if u < t:  # boundary, or matched from u (checked by _unmatched_neighbor)
                continue
            h = 3 * t + k
            if u >= m:
                return h
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            found = -1
            for j in range(3):
                if tri[u, j] == b and tri[u, (j + 1) % 3] == a:
                    found = 3 * u + j
            if found < 0 or nbr[u, found - 3 * u] != t or twin[found] >= 0 or u == t:
                return h
            twin[h] = found
            twin[found] = h
    return -1


@njit(cache=True, nogil=True)
def _unmatched_neighbor(tri, nbr, twin, lo, hi):
    for t in range(lo, hi):
        for k in range(3):
            u = nbr[t, k]
            if 0 <= u < t and twin[3 * t + k] < 0:  # u does not name t back
                return 3 * t + k
    return -1


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


@njit(cache=True, nogil=True)
def boundary_half_edges(tri, twin):
    """``(k, 2)`` directed boundary edges (half-edges without twin), in half-edge order."""
    nb = 0
    for h in range(twin.shape[0]):
        if twin[h] < 0:
            nb += 1
    out = np.empty((nb, 2), np.int64)
    i = 0
    for h in range(twin.shape[0]):
        if twin[h] < 0:
            t = h // 3
            k = h - 3 * t
            out[i, 0] = tri[t, k]
            out[i, 1] = tri[t, (k + 1) % 3]
            i += 1
    return out


@njit(cache=True)
def half_edge_twins(tri, n_points):
    """Match half-edges ``h = 3 t + k`` (from ``tri[t, k]`` to ``tri[t, (k+1) % 3]``).

    Half-edges are bucketed by their lower vertex (a counting sort) with the other
    vertex and the direction stored alongside, so an undirected edge's two halves meet
    in one contiguous bucket. Vertex, direction and half-edge are packed in one int64
    (one scattered write per half-edge instead of two); meshes too large to pack, and
    any mesh with a problem, go through the unpacked reference, which names the
    half-edge.

    Returns ``(twin, bad)``: ``twin[h]`` is the opposite half-edge or -1 (boundary);
    ``bad`` is -1, or a half-edge whose edge is used twice in one direction or by
    three triangles.
    """
    m = tri.shape[0]
    if 3 * m < (1 << 32) and n_points < (1 << 30):
        twin = np.empty(3 * m, np.int64)
        if _half_edge_twins_packed(tri, n_points, twin, np.empty(3 * m, np.int64)):
            return twin, -1
    return _half_edge_twins_reference(tri, n_points)


@njit(cache=True)
def _half_edge_twins_packed(tri, n_points, twin, keys):
    """:func:`half_edge_twins` with packed keys; False on any problem.

    Key: ``other vertex << 33 | (origin is the upper vertex) << 32 | h``, bucketed by
    the lower vertex. Inside a bucket a mark per other vertex pairs an edge's two
    halves in one read each (comparing every pair of a bucket costs a hard-to-predict
    branch per pair). ``twin`` and ``keys``: ``(3 m,)`` int64 outputs / scratch (a
    caller may hand in numpy-allocated ones); needs ``3 m < 2**32`` and
    ``n_points < 2**30``.
    """
    m = tri.shape[0]
    nh = 3 * m
    start = np.zeros(n_points + 1, np.int64)
    for t in range(m):
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        start[min(a, b) + 1] += 1
        start[min(b, c) + 1] += 1
        start[min(c, a) + 1] += 1
    mark = np.empty(n_points, np.int64)
    for v in range(n_points):
        start[v + 1] += start[v]
        mark[v] = -1
    for t in range(m):  # afterwards start[v] is the end of bucket v (start[v + 1] before)
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            f = start[lo]
            keys[f] = (max(a, b) << 33) | (np.int64(a > b) << 32) | (3 * t + k)
            start[lo] = f + 1
    for h in range(nh):
        twin[h] = -1
    mask = (1 << 32) - 1
    s0 = 0
    for v in range(n_points):
        s1 = start[v]
        for j in range(s0, s1):
            kj = keys[j]
            o = kj >> 33
            p = mark[o]
            if p == -1:  # first half of edge (v, o)
                mark[o] = j
            elif p >= 0:  # second half: must run the other way
                kp = keys[p]
                if ((kp ^ kj) >> 32) & 1 == 0:
                    return False
                hj = kj & mask
                hp = kp & mask
                twin[hj] = hp
                twin[hp] = hj
                mark[o] = -2
            else:  # a third triangle on the edge
                return False
        for j in range(s0, s1):
            mark[keys[j] >> 33] = -1
        s0 = s1
    return True


@njit(cache=True)
def _half_edge_twins_reference(tri, n_points):
    m = tri.shape[0]
    nh = 3 * m
    start = np.zeros(n_points + 1, np.int64)
    for t in range(m):
        for k in range(3):
            start[min(tri[t, k], tri[t, (k + 1) % 3]) + 1] += 1
    for v in range(n_points):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    heads = np.empty(nh, np.int64)
    other = np.empty(nh, np.int64)
    for t in range(m):
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            f = fill[lo]
            heads[f] = 3 * t + k
            other[f] = b - a
            fill[lo] = f + 1
    twin = np.full(nh, -1, np.int64)
    for v in range(n_points):
        s1 = start[v + 1]
        for j in range(start[v], s1):
            oj = other[j]
            for i in range(j + 1, s1):
                oi = other[i]
                if oi == oj:
                    return twin, heads[i]
                if oi == -oj:
                    if twin[heads[j]] >= 0 or twin[heads[i]] >= 0:
                        return twin, heads[i]
                    twin[heads[j]] = heads[i]
                    twin[heads[i]] = heads[j]
    return twin, -1


def vertex_half_edges(tri, n_points):
    """One half-edge leaving each vertex (-1 for an unused vertex)."""
    vh = np.full(int(n_points), -1, np.int64)
    _vertex_half_edges_into(tri, vh)
    return vh


@njit(cache=True, nogil=True)
def _vertex_half_edges_into(tri, vh):
    for t in range(tri.shape[0]):
        for k in range(3):
            vh[tri[t, k]] = 3 * t + k


@njit(cache=True)
def _around(tri, twin, vh, a, buf):
    """Triangles' half-edges leaving vertex ``a``, by rotation through the twins.

    Writes them into ``buf`` (grown by the caller if full) and returns their count, or
    -1 if ``buf`` is too small. Works for interior and boundary vertices.
    """
    h0 = vh[a]
    if h0 < 0:
        return 0
    cnt = 0
    h = h0
    while True:  # one way round: previous half-edge of the triangle, then its twin
        if cnt >= buf.shape[0]:
            return -1
        buf[cnt] = h
        cnt += 1
        t = h // 3
        p = 3 * t + (h - 3 * t + 2) % 3
        q = twin[p]
        if q < 0 or q == h0:
            break
        h = q
    if q < 0:  # boundary vertex: go the other way from h0
        g = twin[h0]
        while g >= 0:
            u = g // 3
            h = 3 * u + (g - 3 * u + 1) % 3
            if cnt >= buf.shape[0]:
                return -1
            buf[cnt] = h
            cnt += 1
            g = twin[h]
    return cnt


@njit(cache=True)
def mark_segments(tri, twin, vh, segments):
    """Flag the half-edges lying on constrained edges.

    Returns ``(is_con (3m,) bool, found (s,) bool)``: ``found[s]`` tells whether
    segment s is an edge of the mesh. O(degree) per segment by rotation around its
    first vertex; segments not found that way (a vertex where two fans only touch)
    are looked up in one pass over all half-edges.
    """
    is_con = np.zeros(twin.shape[0], np.bool_)
    found = np.zeros(segments.shape[0], np.bool_)
    buf = np.empty(64, np.int64)
    for s in range(segments.shape[0]):
        a = segments[s, 0]
        b = segments[s, 1]
        cnt = _around(tri, twin, vh, a, buf)
        while cnt < 0:
            buf = np.empty(2 * buf.shape[0], np.int64)
            cnt = _around(tri, twin, vh, a, buf)
        for i in range(cnt):
            h = buf[i]
            t = h // 3
            k = h - 3 * t
            if tri[t, (k + 1) % 3] == b:  # a -> b
                is_con[h] = True
                found[s] = True
                if twin[h] >= 0:
                    is_con[twin[h]] = True
            p = 3 * t + (k + 2) % 3
            if tri[t, (k + 2) % 3] == b:  # b -> a
                is_con[p] = True
                found[s] = True
                if twin[p] >= 0:
                    is_con[twin[p]] = True
    n_missing = 0
    for s in range(segments.shape[0]):
        if not found[s]:
            n_missing += 1
    if n_missing:
        n = vh.shape[0]
        want = dict()
        for s in range(segments.shape[0]):
            if not found[s]:
                a = segments[s, 0]
                b = segments[s, 1]
                want[min(a, b) * n + max(a, b)] = s
        for h in range(twin.shape[0]):
            t = h // 3
            k = h - 3 * t
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            key = min(a, b) * n + max(a, b)
            if key in want:
                is_con[h] = True
                found[want[key]] = True
    return is_con, found


@njit(cache=True)
def vertex_neighbors(tri, twin, vh, a):
    """Vertices joined to ``a`` by an edge (may repeat)."""
    buf = np.empty(64, np.int64)
    cnt = _around(tri, twin, vh, a, buf)
    while cnt < 0:
        buf = np.empty(2 * buf.shape[0], np.int64)
        cnt = _around(tri, twin, vh, a, buf)
    out = np.empty(2 * cnt, np.int64)
    for i in range(cnt):
        h = buf[i]
        t = h // 3
        k = h - 3 * t
        out[2 * i] = tri[t, (k + 1) % 3]
        out[2 * i + 1] = tri[t, (k + 2) % 3]
    return out


@njit(cache=True)
def _find(parent, x):
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

    On a large mesh (``points`` given, ``THREAD_MIN_ROWS`` rows per core) the search
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
    spans = row_ranges(m, THREAD_MIN_ROWS)
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
    return tri_r, code, order, firsts, np.sort(split)


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
            a = _find(uf, region[h // 3])
            b = _find(uf, region[g // 3])
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
        a = _find(uf, r)
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
    return mid_h, mid_id, tri[t, k].copy(), tri[t, (k + 1) % 3].copy()


#: State of a paused walk (``emit_cycles_into``): piece, slot, first free row, row of
#: the piece's start, the half-edge waiting for its link to the next row, first slot.
WALK_STATE = 6


def emit_cycles(tri, code, firsts, n_points, order=None):
    """Walk the Thm 2.4 cycles and emit the output triangles in cycle order (one call).

    See ``emit_cycles_into`` for the walk. Returns ``(out, parent, kind, lengths,
    mid_a, mid_b, out_twin)``: output triangles, the input triangle (``order[t]``) each lies
    in, its kind (0 incenter, 1 flip, 2 midpoint), the cycle lengths, the edge
    ``(mid_a[i], mid_b[i])`` split by midpoint ``n_points + m + i``, and the output's
    half-edge twins as the construction implies them (a *claim* the certificate checks,
    see ``certify_row_range``); the claim is empty if the walk did not emit every slot
    exactly once.
    """
    mid_h, mid_id, mid_a, mid_b = split_slots(tri, code)
    nh = code.shape[0]
    total = nh + len(mid_h)
    out = np.empty((total, 3), np.int64)
    parent = np.empty(total, np.int64)
    kind = np.empty(total, np.int8)
    claim = np.full(3 * total, UNLINKED, index_dtype(3 * total))
    prim = np.full(nh, -1, index_dtype(total))
    lengths = np.zeros(len(firsts), np.int64)
    y2 = np.full(len(mid_h), -1, np.int64)
    state = np.zeros(WALK_STATE, np.int64)
    order = np.arange(tri.shape[0], dtype=np.int64) if order is None else order
    done = emit_cycles_into(tri, code, firsts, order, int(n_points), mid_h, mid_id, out, parent, kind, claim,
                            prim, lengths, y2, state, total)
    pos = int(state[2])
    if done != 1 or pos != total:  # not a permutation: the caller reports it
        k = max(pos, 0)
        return out[:k], parent[:k], kind[:k], lengths, mid_a, mid_b, np.empty(0, np.int64)
    return out, parent, kind, lengths, mid_a, mid_b, claim


#: Claim entry not written (yet): the certificate skips it and counts the links.
UNLINKED = -2


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


@njit(cache=True)
def first_cross_run_edge(twin, run_lengths):
    """First half-edge whose twin lies in another run (cycle), or -1."""
    m = twin.shape[0] // 3
    run = np.empty(m, np.int64)
    t = 0
    for r in range(run_lengths.shape[0]):
        for _ in range(run_lengths[r]):
            run[t] = r
            t += 1
    for h in range(twin.shape[0]):
        g = twin[h]
        if g >= 0 and run[h // 3] != run[g // 3]:
            return h
    return -1


@njit(cache=True, inline="always", error_model="numpy")
def _measures(points, p0, p1, p2):
    """``(cross, sin^2 of the smallest angle, cos of the largest)`` of one triangle.

    ``cross`` is twice the signed area. The smallest angle is opposite the shortest
    side (at most 60 degrees: ``arcsin`` is well conditioned there), the largest
    opposite the longest side (cosine law).
    """
    ax = points[p1, 0] - points[p0, 0]  # side opposite vertex 2
    ay = points[p1, 1] - points[p0, 1]
    bx = points[p2, 0] - points[p1, 0]  # opposite vertex 0
    by = points[p2, 1] - points[p1, 1]
    cx = points[p0, 0] - points[p2, 0]  # opposite vertex 1
    cy = points[p0, 1] - points[p2, 1]
    cr = ax * by - ay * bx
    la = ax * ax + ay * ay
    lb = bx * bx + by * by
    lc = cx * cx + cy * cy
    if la <= lb and la <= lc:
        s2 = cr * cr / (lb * lc)
    elif lb <= lc:
        s2 = cr * cr / (la * lc)
    else:
        s2 = cr * cr / (la * lb)
    if la >= lb and la >= lc:
        c = (lb + lc - la) / (2.0 * np.sqrt(lb * lc))
    elif lb >= lc:
        c = (la + lc - lb) / (2.0 * np.sqrt(la * lc))
    else:
        c = (la + lb - lc) / (2.0 * np.sqrt(la * lb))
    return cr, s2, c


@njit(cache=True, nogil=True, error_model="numpy")
def _angle_area_range(points, tri, lo, hi):
    best_s2 = np.inf
    best_c = np.inf
    amin = -1
    amax = -1
    min_area = np.inf
    aarea = -1
    total = 0.0
    for t in range(lo, hi):
        p0 = tri[t, 0]
        p1 = tri[t, 1]
        p2 = tri[t, 2]
        cr, s2, c = _measures(points, p0, p1, p2)
        total += 0.5 * cr
        if 0.5 * cr < min_area:
            min_area = 0.5 * cr
            aarea = t
        if s2 < best_s2:
            best_s2 = s2
            amin = t
        if c < best_c:
            best_c = c
            amax = t
    return best_s2, amin, best_c, amax, min_area, aarea, total


@njit(cache=True, inline="always")
def _shared(tri, i, j):
    """How many vertices rows ``i`` and ``j`` have in common (2: they share an edge)."""
    shared = 0
    for a in range(3):
        for b in range(3):
            if tri[i, a] == tri[j, b]:
                shared += 1
    return shared


@njit(cache=True, nogil=True, error_model="numpy")
def certify_row_range(points, tri, runs, pair, lo, hi, used, cons_fail):
    """The certificate's per-row checks in one pass over a cycle-ordered mesh.

    ``runs`` are the cycle lengths (positive, summing to ``m``: checked by the
    caller); ``pair`` is a half-edge pairing to check (an empty array skips those
    checks). For each kind of failure the first row (or half-edge) is returned, -1
    if none: ``(bad_index, bad_consecutive, bad_pair, cross_run, min_angle, argmin,
    max_angle, argmax, min_area, argmin_area, total_area, bad_orientation, links,
    unpaired)``.

    * bad_index: a row with a vertex outside ``0..n-1`` (such rows are skipped);
    * bad_consecutive: a row sharing no edge (exactly two vertices) with the next row
      of its run (the last with the first), or the start of a run shorter than 3;
      if ``cons_fail`` has one entry per row, such rows are marked there instead (a
      caller that does not know the runs yet checks the marks later);
    * bad_pair: a half-edge whose partner is out of range or itself, or (checked
      from the higher half-edge of each pair) not paired back or not the same edge
      reversed;
    * cross_run: a half-edge paired with a half-edge of another run;
    * bad_orientation: a row that is not strictly counter-clockwise by the exact
      orientation predicate (a floating-point area can have the wrong sign on a
      nearly flat triangle; the filter decides almost every row at no extra cost);
    * links: pairs checked (each once, from its higher half-edge), unpaired: entries
      -1. The pairing covers every half-edge exactly when ``2 links + unpaired = 3 m``;
      entries ``UNLINKED`` are skipped (not written yet), which that count catches.

    Only rows ``lo <= i < hi`` are checked (they may cut runs anywhere), so that
    threads can share the work: the kernel releases the GIL. ``used[v]`` is set for
    every vertex of a checked row (threads may share ``used``: they only set it).
    """
    m = tri.shape[0]
    n = points.shape[0]
    check_pair = pair.shape[0] == 3 * m
    mark_cons = cons_fail.shape[0] == m
    bad_index = -1
    bad_orient = -1
    bad_consec = -1
    bad_pair = -1
    cross = -1
    links = 0
    unpaired = 0
    best_s2 = np.inf
    best_c = np.inf
    amin = -1
    amax = -1
    min_area = np.inf
    aarea = -1
    total = 0.0
    r_start = 0
    for r in range(runs.shape[0]):
        r_end = r_start + runs[r]
        if r_end <= lo or r_start >= hi:
            r_start = r_end
            continue
        if runs[r] < 3 and bad_consec < 0 and r_start >= lo:
            bad_consec = r_start
        for i in range(max(r_start, lo), min(r_end, hi)):
            p0 = tri[i, 0]
            p1 = tri[i, 1]
            p2 = tri[i, 2]
            if p0 < 0 or p1 < 0 or p2 < 0 or p0 >= n or p1 >= n or p2 >= n:
                if bad_index < 0:
                    bad_index = i
                continue
            used[p0] = True
            used[p1] = True
            used[p2] = True
            if bad_orient < 0 and orient_points(points, p0, p1, p2) <= 0:
                bad_orient = i
            j = i + 1 if i + 1 < r_end else r_start
            if _shared(tri, i, j) != 2:
                if mark_cons:
                    cons_fail[i] = True
                elif bad_consec < 0:
                    bad_consec = i
            cr, s2, c = _measures(points, p0, p1, p2)
            total += 0.5 * cr
            if 0.5 * cr < min_area:
                min_area = 0.5 * cr
                aarea = i
            if s2 < best_s2:
                best_s2 = s2
                amin = i
            if c < best_c:
                best_c = c
                amax = i
            if check_pair:
                for k in range(3):
                    h = 3 * i + k
                    g = pair[h]
                    if g == -1:
                        unpaired += 1
                        continue
                    if g == UNLINKED or g > h and g < 3 * m:
                        continue  # checked from g (or not written yet: counted)
                    if g < 0 or g >= 3 * m or g == h or pair[g] != h:
                        if bad_pair < 0:
                            bad_pair = h
                        continue
                    u = g // 3
                    jg = g - 3 * u
                    if tri[i, k] != tri[u, (jg + 1) % 3] or tri[i, (k + 1) % 3] != tri[u, jg]:
                        if bad_pair < 0:
                            bad_pair = h
                        continue
                    links += 1
                    if (u < r_start or u >= r_end) and cross < 0:
                        cross = h
        r_start = r_end
    min_ang = np.arcsin(np.sqrt(min(max(best_s2, 0.0), 1.0)))
    max_ang = np.arccos(min(max(best_c, -1.0), 1.0))
    return (bad_index, bad_consec, bad_pair, cross, min_ang, amin, max_ang, amax,
            min_area, aarea, total, bad_orient, links, unpaired)


@njit(cache=True, error_model="numpy")
def certify_rows(points, tri, runs, pair):
    """``certify_row_range`` over all rows."""
    used = np.zeros(points.shape[0], np.bool_)
    return certify_row_range(points, tri, runs, pair, 0, tri.shape[0], used, np.empty(0, np.bool_))


@njit(cache=True, nogil=True)
def runs_close(tri, runs):
    """First row that ends a run but shares no edge with the run's first row, or -1."""
    r_start = 0
    for r in range(runs.shape[0]):
        i = r_start + runs[r] - 1
        if _shared(tri, i, r_start) != 2:
            return i
        r_start += runs[r]
    return -1


@njit(cache=True, nogil=True)
def mark_used(tri, used):
    """Set ``used[v]`` for every vertex of ``tri``."""
    for t in range(tri.shape[0]):
        for k in range(3):
            used[tri[t, k]] = True


@njit(cache=True, nogil=True, error_model="numpy")
def angle_area_stats(points, tri):
    """One pass over the triangles.

    Returns ``(min_angle, argmin, max_angle, argmax, min_area, argmin_area, total_area)``
    with angles in radians and signed areas (positive = counter-clockwise).

    The smallest angle of a triangle is opposite its shortest side and is at most 60
    degrees, so it is found as ``arcsin`` of the smallest ``sin^2 = cross^2 / (|e|^2
    |f|^2)`` (well conditioned there); the largest, opposite the longest side, from
    the smallest cosine. One transcendental call per mesh, not per triangle.
    """
    s2, a, c, b, area, d, total = _angle_area_range(points, tri, 0, tri.shape[0])
    min_ang = np.arcsin(np.sqrt(min(max(s2, 0.0), 1.0)))
    max_ang = np.arccos(min(max(c, -1.0), 1.0))
    return min_ang, a, max_ang, b, area, d, total
