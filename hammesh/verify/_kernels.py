"""The certificate's own kernels (numba); no construction code runs here.

What the certificate knows about a mesh it finds with these kernels and the exact
predicates (``hammesh.predicates``): the row checks of a cycle-ordered output
(orientation, consecutive rows, the claimed pairing, angles and area), the
half-edge pairing of a mesh (its own bucket matching, written apart from the
construction's ``hammesh.halfedge._kernels.half_edge_twins``), boundaries and the
measures of the input. Results of several values are named tuples.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh.predicates import orient_points
from hammesh.prefetch import prefetch_row

__all__ = [
    "RowChecks",
    "AngleArea",
    "InputScan",
    "scan_input_into",
    "input_boundary_into",
    "match_small_bucket",
    "match_sorted_bucket",
    "bucket_has",
    "put_boundary_edge",
    "SMALL_BUCKET",
    "find_edges",
    "hull_chain",
    "sort_range",
    "sort_pairs_range",
    "lower_bound",
    "UNLINKED",
    "certify_row_range",
    "runs_close",
    "first_cross_run_edge",
    "boundary_half_edges",
    "half_edge_twins",
    "half_edge_twins_wide",
    "angle_area_stats",
    "mark_used",
    "digest_range",
    "points_digest",
]

#: Directed edge keys ``a * KEY_SHIFT + b`` (``hammesh.verify.reference.KEY_BASE``).
KEY_SHIFT = 1 << 32

#: Claim entry not written (yet): the certificate skips it and counts the links.
UNLINKED = -2


class RowChecks(NamedTuple):
    """Result of :func:`certify_row_range` (first failing row or half-edge, -1 if none)."""

    bad_index: int
    bad_consecutive: int
    bad_pair: int
    cross_run: int
    min_angle: float
    argmin: int
    max_angle: float
    argmax: int
    min_area: float
    argmin_area: int
    total_area: float
    bad_orientation: int
    links: int
    unpaired: int
    row_digest: int  # hash of the rows checked (their index and vertices)
    pair_digest: int  # hash of the pairing entries checked
    points_digest: int  # hash of the points when checking began (RowStream), else 0


class AngleArea(NamedTuple):
    """Result of :func:`angle_area_stats` (angles in radians, signed areas)."""

    min_angle: float
    argmin: int
    max_angle: float
    argmax: int
    min_area: float
    argmin_area: int
    total_area: float


@njit(cache=True, nogil=True, inline="always")
def _sift_down(a, lo, root, n):
    """Heap step of :func:`sort_range` (a max-heap in ``a[lo:lo + n]``)."""
    while True:
        child = 2 * root + 1
        if child >= n:
            return
        if child + 1 < n and a[lo + child] < a[lo + child + 1]:
            child += 1
        if a[lo + root] >= a[lo + child]:
            return
        a[lo + root], a[lo + child] = a[lo + child], a[lo + root]
        root = child


@njit(cache=True, nogil=True)
def sort_range(a, lo, hi):
    """Sort ``a[lo:hi]`` in place (heapsort, O(k log k)).

    For the buckets of high-degree vertices (most buckets are a few keys and take an
    insertion sort). numpy's sort inside a kernel would compile numba's generic
    quicksort with it, 30-40 s of a fresh checkout's compile time for the two key
    dtypes; this compiles in a fraction of that.
    """
    n = hi - lo
    for root in range(n // 2 - 1, -1, -1):
        _sift_down(a, lo, root, n)
    for end in range(n - 1, 0, -1):
        a[lo], a[lo + end] = a[lo + end], a[lo]
        _sift_down(a, lo, 0, end)


@njit(cache=True, nogil=True, inline="always")
def _pair_less(key, half, i, j):
    return key[i] < key[j] or (key[i] == key[j] and half[i] < half[j])


@njit(cache=True, nogil=True, inline="always")
def _sift_down_pairs(key, half, lo, root, n):
    """Heap step of :func:`sort_pairs_range` (a max-heap of pairs in ``[lo, lo + n)``)."""
    while True:
        child = 2 * root + 1
        if child >= n:
            return
        if child + 1 < n and _pair_less(key, half, lo + child, lo + child + 1):
            child += 1
        if not _pair_less(key, half, lo + root, lo + child):
            return
        key[lo + root], key[lo + child] = key[lo + child], key[lo + root]
        half[lo + root], half[lo + child] = half[lo + child], half[lo + root]
        root = child


@njit(cache=True, nogil=True)
def sort_pairs_range(key, half, lo, hi):
    """Sort the pairs ``(key, half)[lo:hi]`` in place, by key then half (heapsort)."""
    n = hi - lo
    for root in range(n // 2 - 1, -1, -1):
        _sift_down_pairs(key, half, lo, root, n)
    for end in range(n - 1, 0, -1):
        key[lo], key[lo + end] = key[lo + end], key[lo]
        half[lo], half[lo + end] = half[lo + end], half[lo]
        _sift_down_pairs(key, half, lo, 0, end)


@njit(cache=True, nogil=True, inline="always")
def lower_bound(a, x):
    """First index ``i`` with ``a[i] >= x`` in the sorted ``a`` (``len(a)`` if none)."""
    lo = 0
    hi = a.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def half_edge_twins(tri, n_points):
    """The certificate's own half-edge pairing (``h = 3 t + k`` from ``tri[t, k]``).

    Written apart from the constructions' pairing (``hammesh.halfedge``) and by another
    method, so that one bug cannot make both wrong the same way: half-edges are
    bucketed by their lower vertex (counting sort), each bucket is sorted by its other
    vertex, then direction, then half-edge (insertion sort: a bucket holds about half a
    vertex degree; a heapsort, :func:`sort_range`, for a high-degree vertex), and an edge's halves
    are then neighbours in their bucket. Vertex indices must lie in
    ``0..n_points-1`` (checked by the caller).

    Returns ``(twin, bad)``: ``twin[h]`` the opposite half-edge or -1 (boundary);
    ``bad`` -1, or the lowest half-edge of an edge used twice in one direction or by
    more than two triangles.
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
    for v in range(n_points):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    # one sort key per half-edge: (2 * other vertex + runs downward) << 32 | h, so that
    # an edge's halves are adjacent and a group's lowest half-edge comes first
    if nh >= (1 << 32) or n_points >= (1 << 30):
        return half_edge_twins_wide(tri, n_points, start, fill)
    mask = (1 << 32) - 1
    key = np.empty(nh, np.int64)
    for t in range(m):
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            i = fill[lo]
            fill[lo] = i + 1
            key[i] = ((2 * max(a, b) + (1 if a > b else 0)) << 32) | (3 * t + k)
    for v in range(n_points):
        s0 = start[v]
        s1 = start[v + 1]
        if s1 - s0 > 24:  # a high-degree vertex
            sort_range(key, s0, s1)
            continue
        for i in range(s0 + 1, s1):  # insertion sort
            kv = key[i]
            j = i
            while j > s0 and key[j - 1] > kv:
                key[j] = key[j - 1]
                j -= 1
            key[j] = kv
    twin = np.empty(nh, np.int64)
    twin.fill(-1)
    bad = -1
    for v in range(n_points):
        i = start[v]
        end = start[v + 1]
        while i < end:
            other = key[i] >> 33
            j = i + 1
            while j < end and key[j] >> 33 == other:
                j += 1
            hi_ = key[i] & mask
            if j - i == 2 and (key[i] >> 32) & 1 == 0 and (key[i + 1] >> 32) & 1 == 1:  # one each way
                hj = key[i + 1] & mask
                twin[hi_] = hj
                twin[hj] = hi_
            elif j - i >= 2:  # twice one way, or three or more triangles
                low = hi_
                for q in range(i + 1, j):
                    low = min(low, key[q] & mask)
                if bad < 0 or low < bad:
                    bad = low
            i = j
    return twin, bad


@njit(cache=True, nogil=True)
def half_edge_twins_wide(tri, n_points, start, fill):
    """:func:`half_edge_twins` for meshes too large for one int64 key per half-edge.

    ``start``: bucket starts (``n_points + 1``, counts of half-edges per lower vertex,
    cumulated); ``fill``: a copy of ``start[:-1]`` (consumed).
    """
    m = tri.shape[0]
    nh = 3 * m
    key = np.empty(nh, np.int64)  # 2 * other vertex + runs downward
    half = np.empty(nh, np.int64)
    for t in range(m):
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            i = fill[lo]
            fill[lo] = i + 1
            key[i] = 2 * max(a, b) + (1 if a > b else 0)
            half[i] = 3 * t + k
    for v in range(n_points):
        s0 = start[v]
        s1 = start[v + 1]
        sort_pairs_range(key, half, s0, s1)  # ties by h: the group's lowest first
    twin = np.empty(nh, np.int64)
    twin.fill(-1)
    bad = -1
    for v in range(n_points):
        i = start[v]
        end = start[v + 1]
        while i < end:
            j = i + 1
            while j < end and key[j] >> 1 == key[i] >> 1:
                j += 1
            if j - i == 2 and key[i] != key[i + 1]:
                twin[half[i]] = half[i + 1]
                twin[half[i + 1]] = half[i]
            elif j - i >= 2:
                low = half[i]
                for q in range(i, j):
                    low = min(low, half[q])
                if bad < 0 or low < bad:
                    bad = low
            i = j
    return twin, bad


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
    side (at most 60 degrees: ``arcsin`` is well conditioned there): its ``sin^2`` is
    ``cross^2`` over the product of the two longer sides' squares, the largest of the
    three products. The largest angle is opposite the longest side (cosine law): its
    numerator is the smallest of the three, its denominator the smallest product.
    Written with ``min``/``max`` rather than branches on which side is shortest (a
    branch per row the processor cannot predict: 30 % of the row checks' time).
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
    pab = la * lb
    pbc = lb * lc
    pca = lc * la
    s2 = cr * cr / max(pab, max(pbc, pca))
    num = min(lb + lc - la, min(lc + la - lb, la + lb - lc))
    c = num / (2.0 * np.sqrt(min(pab, min(pbc, pca))))
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


#: rows ahead whose points (and, scanning the input, bucket counts) a pass over rows
#: whose vertices lie scattered asks for now (``hammesh.prefetch``: a cache hint, no
#: value changes). At 1.5 M triangles, one thread: the row checks 0.061 -> 0.050 s,
#: the input's scan 0.025 -> 0.018, the bucket fill 0.026 -> 0.019 (session 20)
AHEAD_ROWS = 16


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
    d_rows = np.uint64(0)
    d_pairs = np.uint64(0)
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
            if i + AHEAD_ROWS < hi:
                for k in range(3):
                    v = tri[i + AHEAD_ROWS, k]
                    if v >= 0 and v < n:
                        prefetch_row(points, v)
            p0 = tri[i, 0]
            p1 = tri[i, 1]
            p2 = tri[i, 2]
            d_rows += _row_hash(i, p0, p1, p2)
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
                        d_pairs += _mix(h, -1)
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
                    d_pairs += _mix(h, g) + _mix(g, h)
                    if (u < r_start or u >= r_end) and cross < 0:
                        cross = h
        r_start = r_end
    min_ang = np.arcsin(np.sqrt(min(max(best_s2, 0.0), 1.0)))
    max_ang = np.arccos(min(max(best_c, -1.0), 1.0))
    return RowChecks(bad_index, bad_consec, bad_pair, cross, min_ang, amin, max_ang, amax,
                     min_area, aarea, total, bad_orient, links, unpaired, d_rows, d_pairs, 0)



#: the digests' mixing constants, unsigned: see :func:`_mix`
_MIX_A = np.uint64(0x1E3779B97F4A7C15)
_MIX_B = np.uint64(0x2545F4914F6CDD1D)
_MIX_C = np.uint64(0x3F58476D1CE4E5B9)
_MIX_SHIFT = np.uint64(29)


@njit(cache=True, inline="always")
def _mix(a, b):
    """A 64-bit hash of two integers (sums of them are order-free), as ``uint64``.

    Unsigned on purpose: numba emits signed integer ``+`` and ``*`` with LLVM's
    ``nsw`` flag (signed overflow is undefined behaviour), and a hash overflows on
    every call. From ``nsw`` LLVM may prove a signed ``x`` non-negative that in fact
    wrapped and turn ``x >> 29`` into a logical shift: it did so in
    ``certify_row_range`` for int32 claims (a sign-extended int32 plus a large
    constant "cannot" be negative), so its pair digest differed from
    :func:`digest_range`'s on the same claim. Unsigned arithmetic wraps by
    definition; the arguments are widened to int64 first (sign-extended), then
    reinterpreted, so an int32 and an int64 of the same value hash alike.
    """
    x = (np.uint64(np.int64(a)) * _MIX_A) ^ (np.uint64(np.int64(b)) + _MIX_B)
    x ^= x >> _MIX_SHIFT
    return x * _MIX_C


@njit(cache=True, inline="always")
def _row_hash(i, a, b, c):
    return _mix(i, _mix(a, _mix(b, c)))


@njit(cache=True, nogil=True)
def digest_range(tri, pair, lo, hi):
    """``(row digest, pair digest)`` of rows ``lo..hi`` as :func:`certify_row_range` sums them.

    The certificate compares the digests of the rows (and, for a claim that passed, of
    the pairing) which a :class:`~hammesh.verify.stream.RowStream` checked while they
    were written with those of the final arrays: a row or claim entry rewritten after
    its check is then caught. ``pair`` may be empty (no pair digest).
    """
    d_rows = np.uint64(0)
    d_pairs = np.uint64(0)
    with_pairs = pair.shape[0] == 3 * tri.shape[0]
    for i in range(lo, hi):
        d_rows += _row_hash(i, tri[i, 0], tri[i, 1], tri[i, 2])
        if with_pairs:
            for k in range(3):
                h = 3 * i + k
                d_pairs += _mix(h, pair[h])
    return d_rows, d_pairs


@njit(cache=True, nogil=True)
def points_digest(bits):
    """Digest of points given as their float64 bit patterns (``points.view(np.int64)``)."""
    d = np.uint64(0)
    for j in range(bits.shape[0]):
        d += _mix(j, bits[j])
    return d


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

    Returns an :class:`AngleArea`
    with angles in radians and signed areas (positive = counter-clockwise).

    The smallest angle of a triangle is opposite its shortest side and is at most 60
    degrees, so it is found as ``arcsin`` of the smallest ``sin^2 = cross^2 / (|e|^2
    |f|^2)`` (well conditioned there); the largest, opposite the longest side, from
    the smallest cosine. One transcendental call per mesh, not per triangle.
    """
    s2, a, c, b, area, d, total = _angle_area_range(points, tri, 0, tri.shape[0])
    min_ang = np.arcsin(np.sqrt(min(max(s2, 0.0), 1.0)))
    max_ang = np.arccos(min(max(c, -1.0), 1.0))
    return AngleArea(min_ang, a, max_ang, b, area, d, total)


class InputScan(NamedTuple):
    """Result of :func:`scan_input_into`."""

    bad_index: int  # -1, or the first row with a vertex outside 0..n-1
    bad: int  # -1, or the first row that is degenerate by the exact predicate
    n_flipped: int
    min_angle: float  # radians, over the rows in range
    total_area: float


@njit(cache=True, nogil=True, error_model="numpy")
def scan_input_into(points, tri, flip, used, start):
    """The certificate's one pass over an input's rows as the caller gave them.

    For each row: its indices are in range (else ``bad_index``, the row skipped), its
    orientation by the exact predicate (``hammesh.predicates``; sign 0 is ``bad``, a
    negative row is counter-clockwise reversed: ``flip[t]`` is set), its smallest
    angle and area (of the counter-clockwise row), ``used[v]`` for its vertices, and
    ``start[min(a, b) + 1] += 1`` for each edge ``ab``: the bucket sizes of
    :func:`input_boundary_into` (the same either way round). Nothing is copied: the
    pairing reads the rows again with ``flip``.
    """
    n = points.shape[0]
    bad_index = -1
    bad = -1
    n_flipped = 0
    best_s2 = np.inf
    total = 0.0
    m = tri.shape[0]
    for t in range(m):
        if t + AHEAD_ROWS < m:
            for k in range(3):
                v = tri[t + AHEAD_ROWS, k]
                if v >= 0 and v < n:
                    prefetch_row(points, v)
                    prefetch_row(start, v)
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        if a < 0 or b < 0 or c < 0 or a >= n or b >= n or c >= n:
            if bad_index < 0:
                bad_index = t
            continue
        used[a] = True
        used[b] = True
        used[c] = True
        start[min(a, b) + 1] += 1
        start[min(b, c) + 1] += 1
        start[min(c, a) + 1] += 1
        s = orient_points(points, a, b, c)
        if s == 0:
            if bad < 0:
                bad = t
            continue
        if s < 0:
            a, c = c, a
            flip[t] = True
            n_flipped += 1
        cr, s2, _ = _measures(points, a, b, c)
        total += 0.5 * cr
        if s2 < best_s2:
            best_s2 = s2
    return InputScan(bad_index, bad, n_flipped, np.arcsin(np.sqrt(min(max(best_s2, 0.0), 1.0))), total)


#: buckets of at most this many keys are matched by counting (:func:`match_small_bucket`)
SMALL_BUCKET = 24


@njit(cache=True, nogil=True)
def put_boundary_edge(out, nb, v, key):
    """Append bucket ``v``'s half-edge ``key`` as a directed edge key ``x * 2**32 + y``."""
    o = key >> 1
    if key & 1:  # runs from o down to v
        out[nb] = np.int64(o) * KEY_SHIFT + v
    else:
        out[nb] = np.int64(v) * KEY_SHIFT + o
    return nb + 1


@njit(cache=True, nogil=True)
def match_small_bucket(keys, s0, s1, v, out, nb):
    """Match the halves in ``keys[s0:s1]`` (vertex ``v``'s bucket) by counting.

    For each key: how often it occurs (once, or an edge is used twice in one
    direction) and how often its reverse ``key ^ 1`` does (at most once, or three
    triangles share the edge); one with no reverse is a boundary edge, appended to
    ``out``. Quadratic in the bucket, but without the unpredictable branches of a
    sort: at 1.5 M triangles (buckets of 0-18 keys) 34 ms where the insertion sort
    and scan took 45 (session 23). Returns ``(nb, ok)``.
    """
    ok = True
    for i in range(s0, s1):
        ki = keys[i]
        kp = ki ^ 1
        same = 0
        back = 0
        for j in range(s0, s1):
            same += keys[j] == ki
            back += keys[j] == kp
        if same != 1 or back > 1:
            ok = False
        elif back == 0:
            nb = put_boundary_edge(out, nb, v, ki)
    return nb, ok


@njit(cache=True, nogil=True)
def match_sorted_bucket(keys, s0, s1, v, out, nb):
    """Match the halves in the sorted ``keys[s0:s1]``: an edge's halves are neighbours.
    Returns ``(nb, ok)`` as :func:`match_small_bucket`."""
    ok = True
    i = s0
    while i < s1:
        o = keys[i] >> 1
        j = i + 1
        while j < s1 and keys[j] >> 1 == o:
            j += 1
        if j - i == 1:  # one half: a boundary edge
            nb = put_boundary_edge(out, nb, v, keys[i])
        elif j - i != 2 or keys[i] & 1 == keys[i + 1] & 1:
            ok = False
        i = j
    return nb, ok


@njit(cache=True, nogil=True)
def bucket_has(keys, s0, s1, hi):
    """Whether vertex ``v``'s bucket ``keys[s0:s1]`` holds a half of edge ``(v, hi)``."""
    for j in range(s0, s1):
        if keys[j] >> 1 == hi:
            return True
    return False


@njit(cache=True, nogil=True)
def input_boundary_into(tri, flip, start, keys, want, found):
    """The input's directed boundary edges, by the certificate's own bucket matching.

    Rows are read as :func:`scan_input_into` oriented them (``flip``), ``start`` holds
    its bucket sizes (``start[v + 1]``: edges whose lower vertex is ``v``) and is
    consumed. Each half-edge ``x -> y`` goes into the bucket of ``min(x, y)`` as the
    key ``2 max(x, y) + (x > y)`` (``keys``: ``3 m`` entries, int32 when ``2 n`` fits);
    in each bucket an edge's halves are matched (:func:`match_small_bucket`; a
    high-degree vertex's bucket is sorted, :func:`match_sorted_bucket`): one half
    alone is a boundary edge, one each way a pair, anything else an edge used twice in
    one direction or by three triangles.
    The halves' identities are not needed (no twin array): the boundary edge comes
    back from its bucket and key.

    Every vertex must be in ``0..n-1`` (the scan's ``bad_index`` is -1: the bucket fill
    asks for ``start`` rows ahead by the rows' vertices).

    ``want`` holds sorted undirected keys ``lo * n + hi`` (``n`` = ``start.shape[0] - 1``,
    ``lo < hi``: the constrained edges) and ``found[i]`` is set where the mesh has edge
    ``want[i]``: each is looked up in its lower vertex's bucket, so the
    constrained edges cost no pass over the rows of their own (:func:`find_edges`
    is that pass: 9 ms at 1.5 M triangles, session 23).

    Returns ``(boundary, ok)``: boundary edge keys ``x * 2**32 + y`` (unsorted) and
    False if some edge is used wrongly (then ``boundary`` is incomplete: the caller
    names the edge with :func:`half_edge_twins`).
    """
    m = tri.shape[0]
    nv = start.shape[0] - 1
    for v in range(nv):
        start[v + 1] += start[v]
    for t in range(m):  # afterwards start[v] is the end of bucket v
        if t + AHEAD_ROWS < m:
            for k in range(3):
                prefetch_row(start, tri[t + AHEAD_ROWS, k])  # (in range: the scan checked every row)
        if flip[t]:
            r0 = tri[t, 2]
            r2 = tri[t, 0]
        else:
            r0 = tri[t, 0]
            r2 = tri[t, 2]
        r1 = tri[t, 1]
        for k in range(3):
            if k == 0:
                x, y = r0, r1
            elif k == 1:
                x, y = r1, r2
            else:
                x, y = r2, r0
            if x < y:
                lo = x
                key = 2 * y
            else:
                lo = y
                key = 2 * x + 1
            i = start[lo]
            keys[i] = key
            start[lo] = i + 1
    nb = 0
    out = np.empty(3 * m, np.int64)  # only the pages written are touched
    ok = True
    s0 = 0
    w = 0  # the next wanted edge
    for v in range(nv):
        s1 = start[v]
        if s1 - s0 > SMALL_BUCKET:  # a high-degree vertex
            sort_range(keys, s0, s1)
            nb, fine = match_sorted_bucket(keys, s0, s1, v, out, nb)
        else:
            nb, fine = match_small_bucket(keys, s0, s1, v, out, nb)
        ok = ok and fine
        while w < want.shape[0] and want[w] // nv == v:  # (the constrained edges at v)
            found[w] = bucket_has(keys, s0, s1, want[w] - v * nv)
            w += 1
        s0 = s1
    return out[:nb].copy(), ok


@njit(cache=True, nogil=True)
def find_edges(tri, n_points, want):
    """Which undirected edges ``want`` (sorted keys ``lo * n_points + hi``) ``tri`` has.

    One pass over the half-edges; only those whose lower vertex is the lower vertex of
    a wanted edge are looked up (binary search), so the pass costs a read per half-edge.
    """
    found = np.zeros(want.shape[0], np.bool_)
    if want.shape[0] == 0:
        return found
    mark = np.zeros(n_points, np.bool_)
    for i in range(want.shape[0]):
        mark[want[i] // n_points] = True
    for t in range(tri.shape[0]):
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            if mark[lo]:
                key = lo * n_points + max(a, b)
                i = lower_bound(want, key)
                if i < want.shape[0] and want[i] == key:
                    found[i] = True
    return found


@njit(cache=True, nogil=True)
def hull_chain(points, order):
    """Convex hull boundary, counter-clockwise, collinear boundary points included.

    Andrew's monotone chain over ``order`` (the points sorted by x, then y) with the
    exact orientation predicate; a point is dropped only on a strict clockwise turn,
    so points on a hull edge stay. The points must be distinct and not all collinear.
    Written for the certificates, apart from the point-set constructions' hull.
    """
    n = order.shape[0]
    out = np.empty(2 * n, np.int64)
    k = 0
    for i in range(n):  # lower chain
        p = order[i]
        while k >= 2 and orient_points(points, out[k - 2], out[k - 1], p) < 0:
            k -= 1
        out[k] = p
        k += 1
    low = k + 1
    for i in range(n - 2, -1, -1):  # upper chain
        p = order[i]
        while k >= low and orient_points(points, out[k - 2], out[k - 1], p) < 0:
            k -= 1
        out[k] = p
        k += 1
    return out[: k - 1]
