"""Half-edge topology kernels (numba) the constructions run on their input.

Pairing of half-edges (``h = 3 t + k`` runs from ``tri[t, k]`` to ``tri[t, (k+1) % 3]``),
counter-clockwise orientation of the rows, one half-edge per vertex and rotations
around a vertex (constrained edges, neighbours). The certificates never call these:
they pair half-edges with their own code (``hammesh.verify._kernels``), so one bug
here cannot make a construction and its certificate wrong the same way.

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
from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh import threads
from hammesh.predicates import ERRBOUND, orient_points
from hammesh.prefetch import prefetch_row
from hammesh.pages import fresh
from hammesh.threads import row_ranges, run_all

#: rows ahead whose points / neighbours' rows / old rows a pass over scattered reads
#: asks for (:func:`_orient_ccw_into`, :func:`_twins_from_neighbors_into`, ...)
PREFETCH_ROWS = 16
#: :func:`_orient_ccw_into`: rows ahead whose cell key's table entry is asked for (and
#: rows behind whose key is counted, its histogram entry asked for meanwhile)
KEY_AHEAD_ROWS = 8

__all__ = [
    "Oriented",
    "input_ranges",
    "orient_ccw",
    "twins_from_neighbors",
    "half_edge_twins",
    "half_edge_twins_packed",
    "half_edge_twins_reference",
    "vertex_half_edges",
    "mark_segments",
    "mark_segments_into",
    "vertex_neighbors",
    "neighbor_rows_into",
    "twins_in_rows_into",
    "twins_agree",
]


class Oriented(NamedTuple):
    """Result of :func:`orient_ccw`."""

    triangles: np.ndarray  # (m, 3) int64, every row counter-clockwise
    n_flipped: int  # rows that were reversed
    bad: int  # -1, or the first row with a repeated vertex or zero area
    min_angle: float  # radians, smallest angle of the counter-clockwise rows
    area: float  # their total area


def input_ranges(points, tri, indices=True):
    """What a mesh's checks read off its arrays, in one pass per row range (threads):
    ``(finite, lo, hi, least, most)``: whether every coordinate is finite, each
    column's smallest and largest value (``(d,)`` float64 lists: ``[]`` without
    points; meaningful only if finite) and the smallest and largest vertex index (0
    and -1 without triangles, or with ``indices=False``: not read, for a caller whose
    next pass over the rows checks them, :func:`orient_ccw`).

    Replaces numpy's six passes on the main thread (``isfinite().all()``, a minimum and
    a maximum of each column, ``tri.min()``, ``tri.max()``: ~12 ms at 1.5 M triangles,
    the other core idle)."""
    n, m = points.shape[0], (tri.shape[0] if indices else 0)
    k = len(row_ranges(max(n, tri.shape[0]), threads.THREAD_MIN_ROWS))
    parts = run_all([
        (lambda i=i: _input_ranges_of(points, tri, n * i // k, n * (i + 1) // k, m * i // k, m * (i + 1) // k))
        for i in range(k)
    ])
    finite = all(p[0] for p in parts)
    lo = [float(min(p[1][j] for p in parts)) for j in range(points.shape[1])] if n else []
    hi = [float(max(p[2][j] for p in parts)) for j in range(points.shape[1])] if n else []
    least = min(p[3] for p in parts) if m else 0
    most = max(p[4] for p in parts) if m else -1
    return finite, lo, hi, int(least), int(most)


@njit(cache=True, nogil=True, error_model="numpy")
def _input_ranges_of(points, tri, p_lo, p_hi, t_lo, t_hi):
    """:func:`input_ranges` of points ``p_lo..p_hi`` and rows ``t_lo..t_hi``."""
    d = points.shape[1]
    lo = np.full(d, np.inf)
    hi = np.full(d, -np.inf)
    finite = True
    for j in range(d):  # (a column at a time: the loop keeps its bounds in registers)
        a = np.inf
        b = -np.inf
        for i in range(p_lo, p_hi):
            x = points[i, j]
            finite &= x - x == 0.0  # (NaN for NaN and the infinities)
            a = min(a, x)
            b = max(b, x)
        lo[j] = a
        hi[j] = b
    least = np.iinfo(np.int64).max
    most = np.iinfo(np.int64).min
    for t in range(t_lo, t_hi):
        for k in range(3):
            v = tri[t, k]
            least = min(least, v)
            most = max(most, v)
    return finite, lo, hi, least, most


def orient_ccw(points, tri, used=None, measure=True, cells=None):
    """Counter-clockwise rows of ``tri`` (rows with negative area reversed).

    Returns an :class:`Oriented`: ``bad`` is -1 or the first triangle with a repeated
    vertex, zero area or a vertex index out of range (such a row is read no further:
    the validation checks the indices here, ``input_ranges(indices=False)``, not in a
    pass of their own); the smallest angle (radians) and the total area of the
    counter-clockwise rows come from the same pass (a construction needs the angle for
    its bound; the certificate measures the input again with its own code).
    ``used`` (bool per point), if given, is set for every vertex of a triangle.
    ``measure=False``: neither angles, area nor ``used`` (NaN angle and area), for a
    construction that needs none of them (Thm 2.4's: 0.03 s fewer at 1.5 M triangles).
    ``cells`` (``(grid, keys)``: a ``locality.CellGrid`` and the ``locality.CellKeys``
    to fill, over the same row ranges): the cell key of every triangle's centroid and
    each range's histogram, from the corners this pass reads anyway (sparse mode's
    renumbering, ``hammesh.halfedge.locality``: 0.05 s CPU of scattered reads saved at
    1.5 M triangles).

    The first pass writes nothing: when no row needs reversing (Triangle's output,
    most files) ``triangles`` is ``tri`` itself, not a copy (36 MB of fresh memory
    fewer at 1.5 M triangles); a second pass writes the copy otherwise. Callers must
    not write into the result.
    """
    if not measure:
        used = np.zeros(0, np.bool_)  # (the kernel's sign: measure nothing)
    elif used is None:
        used = np.zeros(points.shape[0], np.bool_)
    spans = row_ranges(tri.shape[0], threads.THREAD_MIN_ROWS)
    no_out = np.empty((0, 3), tri.dtype)
    no_key = np.zeros((len(spans), 0), np.int64)
    if cells is None:
        x0 = y0 = scale = 0.0
        bits, table, key, count = 1, no_key[0], no_key[0], no_key
    else:
        (x0, y0, scale, bits, table), (key, count, cell_spans) = cells
        if list(cell_spans) != spans:
            raise ValueError("orient_ccw: the cell keys' row ranges are not this pass's")
    parts = run_all([
        (lambda r=r, lo=lo, hi=hi: _orient_ccw_into(
            points, tri, no_out, used, lo, hi, x0, y0, scale, bits, table, key, count[r]))
        for r, (lo, hi) in enumerate(spans)
    ])
    n_flipped = sum(p[0] for p in parts)
    out = tri
    if n_flipped:  # (the keys and counts are done: not again)
        out = np.empty_like(tri)
        run_all([
            (lambda lo=lo, hi=hi: _orient_ccw_into(
                points, tri, out, used, lo, hi, 0.0, 0.0, 0.0, 1, no_key[0], no_key[0], no_key[0]))
            for lo, hi in spans
        ])
    bads = [p[1] for p in parts if p[1] >= 0]
    s2 = min(p[2] for p in parts)
    min_angle = float(np.arcsin(np.sqrt(min(max(s2, 0.0), 1.0)))) if measure else math.nan
    total = math.fsum(p[3] for p in parts) if measure else math.nan
    return Oriented(out, n_flipped, (min(bads) if bads else -1), min_angle, total)


@njit(cache=True, nogil=True, error_model="numpy")
def _orient_ccw_into(points, tri, out, used, lo, hi, x0, y0, scale, bits, table, key, count):
    """Rows ``lo..hi``: flips, the first bad row, smallest sin^2, area; ``out`` (if not
    empty) gets the counter-clockwise rows; ``used`` empty: no angle, area or used;
    ``key`` (if not empty) each row's cell key (:func:`cell_key`), ``count`` their
    histogram over this range. The rows' points lie scattered (the input's numbering):
    those of the row ``PREFETCH_ROWS`` on are asked for now (``hammesh.prefetch``; at
    1.5 M triangles, one thread, 0.059 -> 0.044 s). So are the cell keys' table entry
    (of the row ``KEY_AHEAD_ROWS`` on, whose points have arrived) and histogram entry
    (counted ``KEY_AHEAD_ROWS`` rows later): both tables are 2 MB at 1.5 M triangles
    and the rows' cells random in the input's order (one thread, best of 11: 37.5 ->
    33.8 ms; the same keys and counts)."""
    write = out.shape[0] == tri.shape[0]
    measure = used.shape[0] == points.shape[0]
    keyed = key.shape[0] == tri.shape[0]
    n_flipped = 0
    bad = -1
    best_s2 = np.inf
    total = 0.0
    n = points.shape[0]
    top = (1 << bits) - 1
    for t in range(lo, hi):
        if keyed:
            if t - KEY_AHEAD_ROWS >= lo:  # (a row with an index out of range has none)
                kk = key[t - KEY_AHEAD_ROWS]
                if kk >= 0:
                    count[kk] += 1
            ahead = t + KEY_AHEAD_ROWS
            if ahead < hi:  # (only an address: the centroid in any order of the corners)
                p, q, r = tri[ahead, 0], tri[ahead, 1], tri[ahead, 2]
                if min(p, min(q, r)) >= 0 and max(p, max(q, r)) < n:
                    ix = min(max(int(((points[p, 0] + points[q, 0] + points[r, 0]) / 3.0 - x0) * scale), 0), top)
                    iy = min(max(int(((points[p, 1] + points[q, 1] + points[r, 1]) / 3.0 - y0) * scale), 0), top)
                    prefetch_row(table, (ix << bits) | iy)
        if t + PREFETCH_ROWS < hi:
            for k in range(3):
                v = tri[t + PREFETCH_ROWS, k]
                if v >= 0 and v < n:
                    prefetch_row(points, v)
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        if min(a, min(b, c)) < 0 or max(a, max(b, c)) >= n:
            if bad < 0:
                bad = t
            if keyed:
                key[t] = -1
            continue
        left = (points[b, 0] - points[a, 0]) * (points[c, 1] - points[a, 1])
        right = (points[b, 1] - points[a, 1]) * (points[c, 0] - points[a, 0])
        cr = left - right
        if abs(cr) <= ERRBOUND * (abs(left) + abs(right)):
            # the rounded sign is in doubt (a sliver): decide it exactly, as the certificate
            # does; a float 0 here refused a valid counter-clockwise triangle of Triangle's
            cr = float(orient_points(points, a, b, c))
        if (a == b or b == c or c == a or cr == 0.0) and bad < 0:
            bad = t
        if cr < 0.0:
            a, c = c, a
            n_flipped += 1
        if write:
            out[t, 0] = a
            out[t, 1] = b
            out[t, 2] = c
        if keyed:
            k = cell_key(points, a, b, c, x0, y0, scale, bits, table)
            key[t] = k
            prefetch_row(count, k)  # (counted KEY_AHEAD_ROWS rows on)
        if measure:
            used[a] = True
            used[b] = True
            used[c] = True
            cr2, s2 = _area_sin2(points, a, b, c)
            total += 0.5 * cr2
            if s2 < best_s2:
                best_s2 = s2
    if keyed:  # (the last rows' keys)
        for t in range(max(lo, hi - KEY_AHEAD_ROWS), hi):
            kk = key[t]
            if kk >= 0:
                count[kk] += 1
    return n_flipped, bad, best_s2, total



@njit(cache=True, inline="always", error_model="numpy")
def _area_sin2(points, p0, p1, p2):
    """``(cross, sin^2 of the smallest angle)`` of one triangle (cross: twice the area).

    The smallest angle lies opposite the shortest side and is at most 60 degrees, so
    its sine squared ``cross^2 / (|e|^2 |f|^2)`` over the two other sides is well
    conditioned; their product is the largest of the three products of squared
    sides (taken with ``max``: a branch on which side is shortest is one the
    processor cannot predict).
    """
    ax = points[p1, 0] - points[p0, 0]
    ay = points[p1, 1] - points[p0, 1]
    bx = points[p2, 0] - points[p1, 0]
    by = points[p2, 1] - points[p1, 1]
    cx = points[p0, 0] - points[p2, 0]
    cy = points[p0, 1] - points[p2, 1]
    cr = ax * by - ay * bx
    la = ax * ax + ay * ay
    lb = bx * bx + by * by
    lc = cx * cx + cy * cy
    return cr, cr * cr / max(la * lb, max(lb * lc, lc * la))


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
    twin = fresh(3 * tri.shape[0], np.int64, -1)  # (small pages: see hammesh.pages)
    spans = row_ranges(tri.shape[0], threads.THREAD_MIN_ROWS)
    parts = run_all([(lambda lo=lo, hi=hi: _twins_from_neighbors_into(tri, nbr, twin, lo, hi)) for lo, hi in spans])
    bads = [b for b, _, _ in parts if b >= 0]
    if bads:
        return twin, min(bads)
    # each match fills one half-edge whose neighbour is higher and one, in that row,
    # whose neighbour is lower (a distinct one per match): as many matches as
    # half-edges naming a lower neighbour means every one of those was matched
    # (no second pass over the rows); else find the first that was not
    if sum(p[1] for p in parts) == sum(p[2] for p in parts):
        return twin, -1
    bads = [b for b in run_all([
        (lambda lo=lo, hi=hi: _unmatched_neighbor(tri, nbr, twin, lo, hi)) for lo, hi in spans
    ]) if b >= 0]
    return twin, (min(bads) if bads else -1)


@njit(cache=True, nogil=True)
def _twins_from_neighbors_into(tri, nbr, twin, lo, hi):
    # two random reads per pair (u's row of tri and of nbr): u's half-edge is the one
    # holding b -> a whose neighbour is t; it cannot be matched already (only t's
    # row names it, and t's edges differ: a row with a repeated vertex is refused).
    # A third of Triangle's neighbours lie far away in memory: the rows of the
    # neighbours PREFETCH_ROWS rows ahead are asked for now (0.14 -> 0.10 s at 1.5 M
    # triangles, one thread), so that several misses are under way at once
    m = tri.shape[0]
    n_match = 0
    n_lower = 0
    for t in range(lo, hi):
        ahead = t + PREFETCH_ROWS
        if ahead < hi:
            for k in range(3):
                u = nbr[ahead, k]
                if ahead < u < m:
                    prefetch_row(tri, u)
                    prefetch_row(nbr, u)
        if tri[t, 0] == tri[t, 1] or tri[t, 1] == tri[t, 2] or tri[t, 2] == tri[t, 0]:
            return 3 * t, n_match, n_lower
        for k in range(3):
            u = nbr[t, k]
            if u < t:  # boundary (-1), or matched from u (counted: twins_from_neighbors)
                if u < -1:
                    return 3 * t + k, n_match, n_lower
                if u >= 0:
                    n_lower += 1
                continue
            h = 3 * t + k
            if u >= m:
                return h, n_match, n_lower
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            found = -1
            for j in range(3):
                if tri[u, j] == b and tri[u, (j + 1) % 3] == a:
                    found = 3 * u + j
            if found < 0 or nbr[u, found - 3 * u] != t:
                return h, n_match, n_lower
            twin[h] = found
            twin[found] = h
            n_match += 1
    return -1, n_match, n_lower


@njit(cache=True, nogil=True)
def _unmatched_neighbor(tri, nbr, twin, lo, hi):
    for t in range(lo, hi):
        for k in range(3):
            u = nbr[t, k]
            if 0 <= u < t and twin[3 * t + k] < 0:  # u does not name t back
                return 3 * t + k
    return -1


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
        if half_edge_twins_packed(tri, n_points, twin, np.empty(3 * m, np.int64)):
            return twin, -1
    return half_edge_twins_reference(tri, n_points)


@njit(cache=True, nogil=True)
def bucket_half_edges_into(tri, start, mark, keys):
    """Counting sort of the half-edges ``h = 3 t + k`` of ``tri`` by their lesser vertex.

    Key of a half-edge ``a -> b``: ``max(a, b) << 33 | (a > b) << 32 | h``. Afterwards
    bucket ``v`` is ``keys[start[v - 1]:start[v]]`` (``start[-1]`` read as 0: each
    ``start[v]`` is the end of bucket ``v``) and ``mark`` (one per vertex, any integer
    dtype) is -1, ready for a pairing pass that marks the first half of each edge
    (:func:`half_edge_twins_packed`; the strip encoder's records,
    ``hammesh.strips._halves_kernels.pair_records_into``). ``start``: ``(n_points + 1,)``,
    ``mark``: ``(n_points,)``, ``keys``: ``(3 m,)`` int64; needs ``3 m < 2**32``.
    """
    m = tri.shape[0]
    n_points = mark.shape[0]
    for v in range(n_points + 1):
        start[v] = 0
    for t in range(m):
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        start[min(a, b) + 1] += 1
        start[min(b, c) + 1] += 1
        start[min(c, a) + 1] += 1
    for v in range(n_points):
        start[v + 1] += start[v]
        mark[v] = -1
    for t in range(m):  # afterwards start[v] is the end of bucket v (start[v + 1] before)
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            f = start[lo]
            keys[f] = (np.int64(max(a, b)) << 33) | (np.int64(a > b) << 32) | (3 * t + k)
            start[lo] = f + 1


@njit(cache=True)
def half_edge_twins_packed(tri, n_points, twin, keys):
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
    start = np.empty(n_points + 1, np.int64)
    mark = np.empty(n_points, np.int64)
    bucket_half_edges_into(tri, start, mark, keys)
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
def half_edge_twins_reference(tri, n_points):
    """:func:`half_edge_twins` without packing (any size; names the bad half-edge)."""
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
    segment s is an edge of the mesh (:func:`mark_segments_into`).
    """
    is_con = np.zeros(twin.shape[0], np.bool_)
    return is_con, mark_segments_into(tri, twin, vh, segments, is_con)


@njit(cache=True)
def mark_segments_into(tri, twin, vh, segments, is_con):
    """:func:`mark_segments` into ``is_con`` (``(3m,)`` bool, False on entry: a caller's
    buffer); returns ``found``.

    O(degree) per segment by rotation around its first vertex; segments not found
    that way (a vertex where two fans only touch) are looked up in one pass over all
    half-edges (no typed dict: it would compile numba's dictionary with the kernel,
    about 10 s on a fresh checkout).
    """
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
    if n_missing:  # rare (few segments): a scan of the missing ones per half-edge near them
        ends = np.empty((n_missing, 3), np.int64)  # lower vertex, upper vertex, segment
        near = np.zeros(vh.shape[0], np.bool_)
        i = 0
        for s in range(segments.shape[0]):
            if not found[s]:
                a = segments[s, 0]
                b = segments[s, 1]
                ends[i, 0] = min(a, b)
                ends[i, 1] = max(a, b)
                ends[i, 2] = s
                near[min(a, b)] = True
                i += 1
        for h in range(twin.shape[0]):
            t = h // 3
            k = h - 3 * t
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            lo = min(a, b)
            if near[lo]:
                hi = max(a, b)
                for i in range(n_missing):
                    if ends[i, 0] == lo and ends[i, 1] == hi:
                        is_con[h] = True
                        found[ends[i, 2]] = True
    return found


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



# --- locality: triangles (and vertices) renumbered along a space-filling curve ---


@njit(cache=True, nogil=True, inline="always")
def _hilbert_key(x, y, bits):
    """Position of cell ``(x, y)`` (each ``< 2**bits``) along the Hilbert curve of that
    grid (the iterative ``xy2d`` of Hamilton, *Compact Hilbert indices*, 2006, in the
    form of Wikipedia's "Hilbert curve": each level rotates the quadrant's frame)."""
    d = 0
    s = 1 << (bits - 1)
    while s > 0:
        rx = 1 if (x & s) > 0 else 0
        ry = 1 if (y & s) > 0 else 0
        d += s * s * ((3 * rx) ^ ry)
        if ry == 0:  # rotate the quadrant so that the curve enters and leaves it alike
            if rx == 1:
                x = s - 1 - x
                y = s - 1 - y
            x, y = y, x
        x &= s - 1
        y &= s - 1
        s >>= 1
    return d


@njit(cache=True, nogil=True)
def hilbert_table_into(bits, table, lo, hi):
    """``table[x << bits | y]``: the Hilbert key of cell ``(x, y)``, for ``x`` in ``lo..hi``.

    A table, not a key per triangle: the key's levels form a chain of dependent
    steps (0.11 s at 1.5 M triangles against 0.025 s for the lookup and 0.008 s for
    the table of 512 x 512 cells)."""
    for x in range(lo, hi):
        for y in range(1 << bits):
            table[(x << bits) | y] = _hilbert_key(x, y, bits)


@njit(cache=True, nogil=True, inline="always")
def cell_key(points, a, b, c, x0, y0, scale, bits, table):
    """The Hilbert key (``table``) of the grid cell holding the centroid of triangle
    ``a b c`` (``scale`` cells per unit from ``(x0, y0)``, ``2**bits`` a side)."""
    top = (1 << bits) - 1
    cx = (points[a, 0] + points[b, 0] + points[c, 0]) / 3.0
    cy = (points[a, 1] + points[b, 1] + points[c, 1]) / 3.0
    ix = min(max(int((cx - x0) * scale), 0), top)
    iy = min(max(int((cy - y0) * scale), 0), top)
    return table[(ix << bits) | iy]


@njit(cache=True, nogil=True)
def cell_keys_into(points, tri, x0, y0, scale, bits, table, key, count, lo, hi):
    """Rows ``lo..hi``: ``key[t]``, the cell key of triangle ``t`` (:func:`cell_key`), and
    ``count[k]`` += 1 for each (this range's own histogram)."""
    for t in range(lo, hi):
        k = cell_key(points, tri[t, 0], tri[t, 1], tri[t, 2], x0, y0, scale, bits, table)
        key[t] = k
        count[k] += 1


@njit(cache=True, nogil=True)
def first_slots_in_place(count):
    """``count[r, k]`` (row range ``r``'s triangles of key ``k``) becomes the first slot
    of that range's triangles of key ``k`` in a counting sort: all keys below ``k``,
    then the ranges before ``r`` inside ``k`` (keys in order, ranges in order inside a
    key). One pass over the histogram in place, where numpy's transpose, cumulative sum
    and copy made three fresh 4 MB arrays (512 x 512 keys, two ranges: ~20 ms of the
    main thread alone, the other core idle, at 1.5 M triangles)."""
    s = 0
    for k in range(count.shape[1]):
        for r in range(count.shape[0]):
            c = count[r, k]
            count[r, k] = s
            s += c


@njit(cache=True, nogil=True)
def scatter_by_key_into(key, place, order, lo, hi):
    """Rows ``lo..hi`` of a counting sort: ``order[place[key[t]]++] = t``, and ``key[t]``
    overwritten by that place (the inverse: the keys are not needed after it);
    ``place``: this range's own first slot of each key, so the sort is stable."""
    for t in range(lo, hi):
        k = key[t]
        i = place[k]
        place[k] = i + 1
        order[i] = t
        key[t] = i


@njit(cache=True, nogil=True)
def renumber_vertices_into(tri, order, n_points, vertex_new, vertex_order, tri_new, leaving):
    """Vertices numbered by first use along the new rows (``tri[order]``), then the
    unused ones in their old order: ``vertex_order[j]`` is old vertex of new ``j``,
    ``vertex_new`` the inverse (zero on entry: a page reserve's fresh memory, no fill
    of its own on the main thread; it holds ``j + 1`` while the rows are read, and the
    pass over the vertices for the unused ones leaves ``j``); ``tri_new`` the new rows
    in new numbers. One serial pass (each first use takes the next number).
    ``leaving`` (``(n_points,)``, any contents on entry, or empty: not asked): a
    half-edge of the new rows leaving each new vertex, the one of its first use (what
    :func:`vertex_half_edges` finds, without its pass over the rows), -1 for an unused
    one. The old row ``PREFETCH_ROWS`` rows ahead is asked for now (``order`` jumps
    across the old rows: 0.037 -> 0.028 s at 1.5 M triangles, one thread, the same
    numbers)."""
    nxt = 0
    ask = leaving.shape[0] > 0
    m = order.shape[0]
    for i in range(m):
        if i + PREFETCH_ROWS < m:
            prefetch_row(tri, order[i + PREFETCH_ROWS])
        t = order[i]
        for k in range(3):
            v = tri[t, k]
            j = vertex_new[v] - 1
            if j < 0:
                j = nxt
                vertex_new[v] = j + 1
                vertex_order[j] = v
                nxt += 1
                if ask:
                    leaving[j] = 3 * i + k
            tri_new[i, k] = j
    if ask:
        for j in range(nxt, n_points):
            leaving[j] = -1
    for v in range(n_points):
        j = vertex_new[v] - 1
        if j < 0:
            j = nxt
            vertex_order[nxt] = v
            nxt += 1
        vertex_new[v] = j


@njit(cache=True, nogil=True)
def renumber_half_edges_into(twin, marks, order, inverse, twin_new, marks_new, lo, hi):
    """New rows ``lo..hi``: the twins in the new numbering (-1 stays) and the per
    half-edge ``marks`` carried along (none if ``marks`` is empty)."""
    carry = marks.shape[0] == twin.shape[0]
    for i in range(lo, hi):
        t = order[i]
        for k in range(3):
            g = twin[3 * t + k]
            twin_new[3 * i + k] = -1 if g < 0 else 3 * inverse[g // 3] + g % 3
            if carry:
                marks_new[3 * i + k] = marks[3 * t + k]


@njit(cache=True, nogil=True)
def neighbor_rows_into(nbr, order, inverse, rows, lo, hi):
    """New rows ``lo..hi`` (new row ``i`` is old row ``order[i]``): ``rows[3 i + k]``, the
    new number of the triangle that the old neighbour array ``nbr`` names across edge
    ``k`` (-1 stays). Returns False if a neighbour is out of range (below -1 or not a
    row): the array is not to be trusted.

    The first pass of ``locality.renumber_from_neighbors``' matching: the only one with
    scattered reads (``nbr``'s old rows and ``inverse``), the reads
    :func:`renumber_half_edges_into` makes of the old twins; the rows of the
    neighbours PREFETCH_ROWS rows ahead are asked for now, as in
    :func:`_twins_from_neighbors_into`. No branch on the values read: a branch that
    mispredicts stalls the misses under way (measured 0.065 against 0.048 s at 1.5 M
    triangles, one thread)."""
    m = nbr.shape[0]
    ok = True
    for i in range(lo, hi):
        ahead = i + PREFETCH_ROWS
        if ahead < hi:
            prefetch_row(nbr, order[ahead])
        t = order[i]
        for k in range(3):
            u = nbr[t, k]
            ok &= (u >= -1) & (u < m)
            r = inverse[min(max(u, 0), m - 1)]
            rows[3 * i + k] = r if u >= 0 else -1
    return ok


@njit(cache=True, nogil=True)
def twins_in_rows_into(tri, twin, lo, hi):
    """Rows ``lo..hi``, in place: ``twin[h]`` holds the row across ``h``
    (:func:`neighbor_rows_into`; -1 stays) and becomes the half-edge of that row that
    runs ``h``'s edge the other way. Returns False if that row holds no such half-edge.
    Reads only nearby rows on a renumbered mesh (``hammesh.halfedge.locality``)."""
    ok = True
    for i in range(lo, hi):
        for k in range(3):
            h = 3 * i + k
            u = twin[h]
            if u < 0:
                continue
            a = tri[i, k]
            b = tri[i, (k + 1) % 3]
            r0 = tri[u, 0]
            r1 = tri[u, 1]
            r2 = tri[u, 2]
            m0 = (r0 == b) & (r1 == a)
            m1 = (r1 == b) & (r2 == a)
            m2 = (r2 == b) & (r0 == a)
            ok &= m0 | m1 | m2
            twin[h] = 3 * u + np.int64(m1) + 2 * np.int64(m2)
    return ok


@njit(cache=True, nogil=True)
def twins_agree(twin, lo, hi):
    """Whether every half-edge of rows ``lo..hi`` with a twin is its twin's twin (each
    claimed neighbour names the row back)."""
    ok = True
    for h in range(3 * lo, 3 * hi):
        g = twin[h]
        if g >= 0:
            ok &= twin[g] == h
    return ok


@njit(cache=True, nogil=True)
def gather_points_into(points, vertex_order, out, lo, hi):
    """``out[j] = points[vertex_order[j]]`` for ``j`` in ``lo..hi``."""
    for j in range(lo, hi):
        v = vertex_order[j]
        for d in range(points.shape[1]):
            out[j, d] = points[v, d]


@njit(cache=True, nogil=True)
def restore_vertices_into(rows, vertex_order, n_points, lo, hi):
    """Rows ``lo..hi`` of an output in place: vertex numbers below ``n_points`` back to
    the old numbering (``vertex_order``); later ones (Steiner points) stay."""
    for i in range(lo, hi):
        for k in range(3):
            v = rows[i, k]
            if v < n_points:
                rows[i, k] = vertex_order[v]
