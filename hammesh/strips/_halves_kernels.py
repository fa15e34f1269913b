"""Compiled steps of ``encode(fast=True)`` in two halves on two threads.

The mesh is cut by a plane through the median vertex (:mod:`hammesh.strips.halves`): a
row goes to the side of its least vertex index.  Each thread copies its half's rows in
the order of a grid of cells (:func:`vertex_cells_into`, :func:`row_cells_into`, :func:`rows_of_cells_into`), pairs their edges into triangle records
(:func:`pair_records_into`) and runs the one-pass greedy strips on them; an edge with
triangles on both sides is a boundary inside each half.  What the halves cannot see
alone, the edges they share, is settled afterwards from the half-edges each half left
unpaired (:func:`shared_edges`): a shared edge with one triangle on each side and
opposite directions is a proper dual edge the cover did not cross; anything else there
(a third triangle, the same direction twice) is a defect, and the caller then encodes
the whole mesh the ordinary way.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.halfedge import bucket_half_edges_into
from hammesh.strips._dual_kernels import REC_SCRATCH, REC_TWIN, REC_WIDTH
from hammesh.strips._numba import CORNERS, kernel, loop_helper, row

__all__ = ["vertex_cells_into", "row_cells_into", "rows_of_cells_into", "HalfPairing", "pair_records_into", "SharedEdges", "shared_edges", "edge_users"]


#: :func:`pair_records_into`'s result: proper edges paired (-1: an edge of this half is
#: used by three triangles or twice in one direction) and how many half-edges were left
#: unpaired (written to ``loose``).
HalfPairing = namedtuple("HalfPairing", ["pairs", "n_loose"])


@kernel
def pair_records_into(tri, start, mark, keys, rec, loose):
    """Triangle records of ``tri`` (:func:`hammesh.strips._dual_kernels.mesh_records`'s
    layout) with the proper edges paired, in one counting sort of the half-edges.

    Half-edges are bucketed by their lesser vertex; a key is ``other vertex << 33 |
    (origin is the upper vertex) << 32 | h``; inside a bucket a mark per other vertex
    pairs an edge's two halves in one read each (the buckets are
    :func:`hammesh.halfedge.bucket_half_edges_into`'s, as for
    :func:`hammesh.halfedge.half_edge_twins_packed`; here the
    records are written directly, with no ``int64`` pairing array, and the buckets are
    kept: afterwards bucket ``v`` is ``keys[start[v - 1]:start[v]]`` (``start[-1]`` read
    as 0) for :func:`edge_users`).  ``start``: ``(n_points + 1,)``, ``mark``:
    ``(n_points,)``, ``keys``: ``(3 m,)`` int64, ``rec``: ``(m, REC_WIDTH)``, ``loose``:
    ``(3 m, 2)`` int64 receives ``(lesser vertex, key)`` of each unpaired half-edge.
    Needs ``3 m < 2**32``.
    """
    m = tri.shape[0]
    n_points = mark.shape[0]
    bucket_half_edges_into(tri, start, mark, keys)
    for t in range(m):
        for k in range(3):
            rec[t, k] = tri[t, k]
            rec[t, REC_TWIN + k] = -1
        rec[t, REC_SCRATCH] = 0
        rec[t, REC_WIDTH - 1] = 0
    mask = (np.int64(1) << 32) - 1
    pairs = 0
    n_loose = 0
    s0 = 0
    for v in range(n_points):
        s1 = start[v]
        for j in range(s0, s1):
            kj = keys[row(j)]  # row(): no negative-index wraparound (see _cover_kernels)
            o = row(kj >> 33)
            p = mark[o]
            if p == -1:  # first half of edge (v, o)
                mark[o] = j
            elif p >= 0:  # second half: must run the other way
                kp = keys[row(p)]
                if ((kp ^ kj) >> 32) & 1 == 0:
                    return HalfPairing(-1, n_loose)
                hj = row(kj & mask)
                hp = row(kp & mask)
                rec[hj // CORNERS, REC_TWIN + hj % CORNERS] = hp
                rec[hp // CORNERS, REC_TWIN + hp % CORNERS] = hj
                mark[o] = -2
                pairs += 1
            else:  # a third triangle on the edge
                return HalfPairing(-1, n_loose)
        for j in range(s0, s1):
            o = row(keys[row(j)] >> 33)
            if mark[o] >= 0:  # alone on its edge in this half
                loose[n_loose, 0] = v
                loose[n_loose, 1] = keys[row(mark[o])]
                n_loose += 1
            mark[o] = -1
        s0 = s1
    return HalfPairing(pairs, n_loose)


@kernel
def edge_users(start, keys, lo, hi):
    """``(users, last key)`` of edge ``(lo, hi)``, ``lo < hi``, in buckets of :func:`pair_records_into`."""
    a = start[lo - 1] if lo > 0 else 0
    users = 0
    key = -1
    for j in range(a, start[lo]):
        if keys[j] >> 33 == hi:
            users += 1
            key = keys[j]
    return users, key


#: :func:`shared_edges`'s result: proper edges between the halves (each counted once) and
#: ``ok`` (False: an edge with triangles on both sides is not a proper edge).
SharedEdges = namedtuple("SharedEdges", ["proper", "ok"])


@kernel
def shared_edges(loose, n_loose, start, keys):
    """Check one half's unpaired half-edges against the other half's buckets.

    ``loose[:n_loose]``: ``(lesser vertex, key)`` of the half-edges this half left
    unpaired (:func:`pair_records_into`); ``start``, ``keys``: the other half's buckets.
    An unpaired edge is proper across the halves when the other half has exactly one
    half-edge on it, running the other way; none: a boundary edge; anything else: not
    proper (``ok`` False).  Run both ways, every proper edge between the halves is
    counted once from each side.
    """
    proper = 0
    for i in range(n_loose):
        lo = loose[i, 0]
        k = loose[i, 1]
        users, other = edge_users(start, keys, lo, k >> 33)
        if users == 0:
            continue
        if users > 1 or ((other ^ k) >> 32) & 1 == 0:
            return SharedEdges(proper, False)
        proper += 1
    return SharedEdges(proper, True)


@loop_helper
def _grid_step(q, k):
    """``int(q)`` clamped to ``[0, k)``, clamped as a float first (a difference of huge
    coordinates may be infinite, their quotient NaN)."""
    if not q >= 0.0:
        return 0
    if q >= k:
        return k - 1
    return int(q)


@kernel
def vertex_cells_into(pts, axis, other, cut, lo_a, lo_b, h, n0, n1, ny, label):
    """Cell of each vertex in a grid of square cells of side ``h``, sides of the cut first.

    Side 0 (``pts[:, axis] <= cut``) has ``n0`` columns from ``lo_a``, side 1 ``n1``
    columns from ``cut``, each of ``ny`` cells from ``lo_b`` along ``other``; columns run
    along ``axis`` and the cells of a column alternate direction (a serpentine), so
    consecutive labels are neighbouring cells.  Labels below ``n0 * ny`` are side 0.
    Points outside the grid (it is sized from a sample) go to the nearest cell.  Returns
    True when every coordinate is finite (every one is read here, so the input check
    costs no pass of its own: the sum of ``0 * x`` over the coordinates stays 0 unless
    one is infinite or NaN).
    """
    d = pts.shape[1]
    zero = 0.0
    for v in range(pts.shape[0]):
        for j in range(d):
            zero += 0.0 * pts[v, j]
        x = pts[v, axis]
        y = pts[v, other]
        if x <= cut:
            c = _grid_step((x - lo_a) / h, n0)
        else:
            c = n0 + _grid_step((x - cut) / h, n1)
        r = _grid_step((y - lo_b) / h, ny)
        if c % 2 == 1:
            r = ny - 1 - r
        label[v] = c * ny + r
    return zero == 0.0


@kernel
def row_cells_into(tri, label, row_label, counts):
    """``row_label[t]``: the cell label of row ``t``'s least vertex index, for every row of
    ``tri`` (the caller gives each thread a slice of the rows), and ``counts[c]`` (zeros
    given) raised by the rows of each cell ``c``; returns 0, or -1 if a row repeats a
    vertex, -2 if a row has a vertex index outside ``[0, len(label))`` (every index is
    checked before it is used, so the caller needs no range pass of its own).

    The least vertex decides, so rows over the same three vertices (the two sides of a
    double-sided face) land in one cell.  Why a pass of its own: each half's copy
    (:func:`rows_of_cells_into`) used to read all ``m`` input rows (24 bytes each) and
    look up their labels to find its own; on two threads, each labelling half of the rows
    once, the halves then scan ``m`` small labels instead (at 1M triangles that pass had
    been ~4.4 ms of a half's ~80 ms, half of it the same work done twice; session 15).
    The counts let the copy put each row in its place in one pass (session 16).
    """
    n = label.shape[0]
    for t in range(tri.shape[0]):
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        if (a < 0) | (a >= n) | (b < 0) | (b >= n) | (c < 0) | (c >= n):
            return -2
        if a == b or b == c or c == a:
            return -1
        cell = label[row(min(a, min(b, c)))]  # checked in range: row() (see _cover_kernels)
        row_label[t] = cell
        counts[row(cell)] += 1
    return 0


@kernel
def rows_of_cells_into(tri, row_label, first, last, offsets, half):
    """Copy the rows whose cell label (``row_label``, :func:`row_cells_into`) is in
    ``[first, last)`` into ``half``, cell after cell, in input order inside a cell.

    ``offsets[c - first]``: where cell ``c``'s rows start in ``half`` (the running sums of
    :func:`row_cells_into`'s counts; each is advanced past its cell's rows).  One pass: the
    counts were taken by the labelling (until session 16 a counting sort of its own here,
    two passes, ~1.3 ms more a half at 1M triangles).  Triangle's numbering is scattered;
    in cell order neighbouring triangles are near each other in memory, which the pairing
    and the greedy strips read at random (at 1M triangles the greedy strips ~20% faster).
    """
    for t in range(row_label.shape[0]):
        l = row_label[t]
        if first <= l < last:
            c = row(l - first)
            q = row(offsets[c])
            offsets[c] = q + 1
            half[q, 0] = tri[t, 0]
            half[q, 1] = tri[t, 1]
            half[q, 2] = tri[t, 2]
