"""Compiled input side of the strip encoders: face checks, the proper-edge pairing,
orientability, dual components and the per-triangle records the cover reads.

Kernels take plain arrays, never raise, and return counts; callers check inputs and
turn counts into reports.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.halfedge import half_edge_twins_packed
from hammesh.strips._numba import kernel

__all__ = [
    "FACE_OK",
    "FACE_REPEATED",
    "FACE_ZERO_AREA",
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


@kernel
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
