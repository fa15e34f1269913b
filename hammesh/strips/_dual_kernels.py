"""Compiled input side of the strip encoders: face checks, the proper-edge pairing,
orientability, dual components and the per-triangle records the cover reads.

Kernels take plain arrays, never raise, and return counts; callers check inputs and
turn counts into reports.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.halfedge import half_edge_twins_packed
from hammesh.strips._numba import kernel, loop_helper, row

__all__ = [
    "FACE_OK",
    "FACE_REPEATED",
    "FACE_ZERO_AREA",
    "is_zero_area",
    "CENSUS_BLOCK",
    "clearly_nonzero_in_plane",
    "face_flags",
    "proper_twins_into",
    "orientation_count",
    "dual_components",
    "REC_TWIN",
    "REC_SCRATCH",
    "REC_WIDTH",
    "MeshRecords",
    "records_dtype",
    "mesh_records",
    "records_from_twin",
]

#: ``face_flags`` values.
FACE_OK, FACE_REPEATED, FACE_ZERO_AREA = 0, 1, 2


@loop_helper
def is_zero_area(pts, a, b, c, rtol):
    """Whether triangle ``(a, b, c)`` (distinct indices) has zero area.

    Twice the area is at most ``rtol`` times the longest side squared, the cross product
    taken at the vertex opposite the longest side (exact differences for a sliver's
    short side); the definition of :mod:`hammesh.strips.defects`.  Of equally long
    sides the one with the least sum of its two vertex indices counts as the longest,
    so the answer is the same bit for bit for every rotation of the row and for the
    reversed row (each side's vector is then negated, exactly).  A filter decides most
    rows with one cross product (see below; it assumes ``rtol >= 1e-14``, far above
    the rounding of a cross product); it changes no answer.
    """
    three = pts.shape[1] > 2
    # the sides as vectors: ab = b - a, bc = c - b, ca = a - c
    abx = pts[b, 0] - pts[a, 0]
    aby = pts[b, 1] - pts[a, 1]
    abz = (pts[b, 2] - pts[a, 2]) if three else 0.0
    bcx = pts[c, 0] - pts[b, 0]
    bcy = pts[c, 1] - pts[b, 1]
    bcz = (pts[c, 2] - pts[b, 2]) if three else 0.0
    cax = pts[a, 0] - pts[c, 0]
    cay = pts[a, 1] - pts[c, 1]
    caz = (pts[a, 2] - pts[c, 2]) if three else 0.0
    s_ab = abx * abx + aby * aby + abz * abz
    s_bc = bcx * bcx + bcy * bcy + bcz * bcz
    s_ca = cax * cax + cay * cay + caz * caz
    # a filter first: the cross product at any vertex is twice the area up to a few
    # ulps of the longest side squared, far below rtol (1e-13) times it; so twice that
    # bound exceeded at vertex b means the exact test below would say no too
    longest = max(s_ab, max(s_bc, s_ca))
    fx = aby * bcz - abz * bcy
    fy = abz * bcx - abx * bcz
    fz = abx * bcy - aby * bcx
    lim = 2.0 * rtol * longest
    if rtol >= 1e-14 and fx * fx + fy * fy + fz * fz > lim * lim:
        return False
    # the longest side; at its apex the side leaving it and the side arriving
    # (ab: apex c, bc then ca; bc: apex a, ca then ab; ca: apex b, ab then bc)
    best = s_ab
    key = a + b
    ux, uy, uz, vx, vy, vz = bcx, bcy, bcz, cax, cay, caz
    if s_bc > best or (s_bc == best and b + c < key):
        best = s_bc
        key = b + c
        ux, uy, uz, vx, vy, vz = cax, cay, caz, abx, aby, abz
    if s_ca > best or (s_ca == best and c + a < key):
        best = s_ca
        ux, uy, uz, vx, vy, vz = abx, aby, abz, bcx, bcy, bcz
    cx = uy * vz - uz * vy
    cy = uz * vx - ux * vz
    cz = ux * vy - uy * vx
    return best == 0.0 or np.sqrt(cx * cx + cy * cy + cz * cz) <= rtol * best


#: Rows a planar census reads at a time (:func:`face_flags`): their corners gathered into
#: columns, then one loop the compiler vectorizes over them.
CENSUS_BLOCK = 256


@loop_helper
def clearly_nonzero_in_plane(ax, ay, bx, by, cx, cy, n, rtol, out):
    """``out[j]``: whether :func:`is_zero_area`'s filter already says "not zero area" for
    the planar triangle ``j < n`` of these corner columns (twice its area above ``2 rtol``
    times its longest side squared; ``rtol >= 1e-14``).  No branch: the loop runs on
    vector registers (a half's census at 1M triangles 1.8-2.0 ms against 2.7-3.6 row by
    row, session 16)."""
    for j in range(n):
        ux = bx[j] - ax[j]
        uy = by[j] - ay[j]
        vx = cx[j] - bx[j]
        vy = cy[j] - by[j]
        wx = ax[j] - cx[j]
        wy = ay[j] - cy[j]
        cross = ux * vy - uy * vx
        lim = 2.0 * rtol * max(ux * ux + uy * uy, max(vx * vx + vy * vy, wx * wx + wy * wy))
        out[j] = cross * cross > lim * lim


@kernel
def face_flags(pts, tri, rtol, flags):
    """Fill ``flags[t]``: 1 repeated vertex, 2 zero area (:func:`is_zero_area`), 0
    otherwise; return both counts.  Every index of ``tri`` must be in range (the callers'
    rows are checked: :func:`hammesh.halfedge.mesh_arrays`, or the halves' rows copy):
    they index the points as ``np.uint64``, without numba's negative-index wraparound
    (:data:`~hammesh.strips._numba.row`; ~15% of the census at 1M triangles).

    Planar points (and ``rtol >= 1e-14``): :data:`CENSUS_BLOCK` rows at a time, their
    corners gathered into columns and :func:`clearly_nonzero_in_plane` run over them;
    only the rows it does not clear get the exact test.  The same flags (the filter is
    :func:`is_zero_area`'s own: it decides nothing the exact test would decide otherwise).
    """
    m = tri.shape[0]
    n_rep = 0
    n_zero = 0
    planar = pts.shape[1] == 2 and rtol >= 1e-14
    B = CENSUS_BLOCK if planar else 1
    col = np.empty((6, B))
    clear = np.zeros(B, np.bool_)
    for t0 in range(0, m, B):
        nb = min(B, m - t0)
        if planar:
            for j in range(nb):
                t = t0 + j
                a = row(tri[t, 0])
                b = row(tri[t, 1])
                c = row(tri[t, 2])
                col[0, j] = pts[a, 0]
                col[1, j] = pts[a, 1]
                col[2, j] = pts[b, 0]
                col[3, j] = pts[b, 1]
                col[4, j] = pts[c, 0]
                col[5, j] = pts[c, 1]
            clearly_nonzero_in_plane(col[0], col[1], col[2], col[3], col[4], col[5], nb, rtol, clear)
        for j in range(nb):
            t = t0 + j
            a = row(tri[t, 0])
            b = row(tri[t, 1])
            c = row(tri[t, 2])
            if (a == b) | (b == c) | (c == a):  # one branch, not three (rarely taken)
                flags[t] = FACE_REPEATED
                n_rep += 1
            elif clear[j]:
                flags[t] = FACE_OK
            elif is_zero_area(pts, a, b, c, rtol):
                flags[t] = FACE_ZERO_AREA
                n_zero += 1
            else:
                flags[t] = FACE_OK
    return n_rep, n_zero


@kernel
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


@kernel
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


@kernel
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


# --- one record per triangle -------------------------------------------------------------
#
# The greedy cover and the renumbering read a triangle's vertices, its three twins and
# its neighbours' free degrees in Triangle's scattered numbering: almost every step is a
# cache miss.  With ``int64`` rows and a separate ``int64`` pairing that is two misses
# per triangle (24 bytes of ``tri`` and 24 of ``twin``, 4.8 MB at 100k triangles); a
# 32-byte ``int32`` record ``(v0, v1, v2, twin0, twin1, twin2, scratch, pad)`` holds all
# of it in one half cache line (3.2 MB), ~30% less time for the greedy cover at 100k.
# Meshes too large for ``int32`` get ``int64`` records: the kernels are the same (numba
# compiles one specialisation per dtype).

#: Columns of a triangle record (:func:`mesh_records`).
REC_TWIN = 3
REC_SCRATCH = 6
REC_WIDTH = 8

#: :func:`mesh_records`'s result: the records and the ``int64`` half-edge pairing.
MeshRecords = namedtuple("MeshRecords", ["records", "twin"])


def records_dtype(m: int, n_points: int):
    """``int32`` when ``m`` triangles on ``n_points`` vertices fit (half the bytes), else ``int64``."""
    return np.int32 if 3 * m < 2**31 - 1 and n_points < 2**30 else np.int64


def mesh_records(tri, n_points):
    """Triangle records and the half-edge pairing (:class:`MeshRecords`), or ``None``.

    ``records[t] = (tri[t, 0], tri[t, 1], tri[t, 2], twin[3 t], twin[3 t + 1],
    twin[3 t + 2], scratch, 0)``; ``twin`` is
    :func:`hammesh.halfedge._kernels.half_edge_twins`'s pairing (its packed fast path),
    the records one sequential pass after it.  ``None`` when the packed pairing does not
    apply (``int64`` sizes) or an edge is used twice in one direction or by three
    triangles: the caller then pairs proper edges with :func:`proper_twins_into` and
    fills records with :func:`records_from_twin`.
    """
    m = tri.shape[0]
    if records_dtype(m, n_points) is not np.int32:
        return None
    twin = np.empty(3 * m, np.int64)
    if not half_edge_twins_packed(tri, n_points, twin, np.empty(3 * m, np.int64)):
        return None
    rec = np.empty((m, REC_WIDTH), np.int32)
    records_from_twin(tri, twin, rec)
    return MeshRecords(rec, twin)


@kernel
def count_pillows(rec):
    """Rows whose three edges all lead to one other triangle (a two-triangle closed piece)."""
    c = 0
    for t in range(rec.shape[0]):
        h = rec[t, REC_TWIN]
        if h >= 0:
            u = h // 3
            c += np.int64((rec[t, REC_TWIN + 1] // 3 == u) & (rec[t, REC_TWIN + 2] // 3 == u))
    return c


@kernel
def records_from_twin(tri, twin, rec):
    """Fill ``rec`` (``(m, REC_WIDTH)``, any integer dtype) from rows and their pairing."""
    for t in range(tri.shape[0]):
        for k in range(3):
            rec[t, k] = tri[t, k]
            rec[t, REC_TWIN + k] = twin[3 * t + k]
        rec[t, REC_SCRATCH] = 0
        rec[t, REC_WIDTH - 1] = 0
