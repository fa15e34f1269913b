"""Vertex markers of the tiles' output, as the serial path gives them (issue 15, session 16).

The serial path's markers are Triangle's, then the post-processing's: Triangle keeps
an input vertex's marker and gives an input vertex of marker 0 the marker of the
first segment (in input order) ending there with a nonzero one (``insertsegment`` in
triangle.c sets a zero vertex mark to the segment's), and every point it inserts on a
segment that segment's marker; other new points get 0; the Hamiltonian construction
gives a point it adds on a constrained edge that edge's marker
(:func:`hammesh.mesh.output_vertex_markers`), others 0.

The tiles' output has the same rule from two facts the workers know without the
whole mesh: the input vertices' markers (:func:`input_vertex_markers`, made once by
the driver, few), and the constrained edges each piece holds with their markers (a
point on a segment is an end of one of its pieces: a separator's crossing with a
segment, a subsegment's end, Triangle's or the construction's point on it). A point
shared by two pieces gets the same marker in both: the segment pieces meeting it on
either side carry one segment's marker. Separator and lattice points and incenters
are on no segment: 0, as the serial path's interior points.
"""

from __future__ import annotations

import numpy as np

__all__ = ["input_vertex_markers", "point_markers", "marked_inputs", "given_at"]


def input_vertex_markers(vertex_markers: np.ndarray, segments: np.ndarray, segment_markers: np.ndarray) -> np.ndarray:
    """Markers Triangle gives the input vertices: their own, or where that is 0 the
    first nonzero marker of a segment ending there, in input order.

    >>> input_vertex_markers(np.array([0, 3, 0, 0]), np.array([[0, 1], [1, 2], [2, 0]]), np.array([0, 7, 9])).tolist()
    [9, 3, 7, 0]
    """
    out = np.asarray(vertex_markers, dtype=np.int64).reshape(-1).copy()
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    mk = np.asarray(segment_markers, dtype=np.int64).reshape(-1)
    if len(mk) != len(seg) or not len(seg):
        return out
    ends = seg.T.ravel()  # (both ends of segment 0, 1, ... are at rows i and s + i)
    row = np.tile(np.arange(len(seg)), 2)
    value = np.tile(mk, 2)
    use = (value != 0) & (ends < len(out))
    ends, row, value = ends[use], row[use], value[use]
    order = np.argsort(row, kind="stable")  # input order; the first per vertex wins
    first, at = np.unique(ends[order], return_index=True)
    zero = out[first] == 0
    out[first[zero]] = value[order][at][zero]
    return out


def marked_inputs(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(ids, markers)`` of the input vertices with a nonzero marker (what a worker needs)."""
    markers = np.asarray(markers, dtype=np.int64).reshape(-1)
    ids = np.flatnonzero(markers)
    return ids, markers[ids]


def point_markers(n_points: int, segments: np.ndarray, segment_markers: np.ndarray,
                  given: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Marker of each of ``n_points`` points: a given one's (``given``: local indices
    and markers, the input vertices' of :func:`marked_inputs`), else the largest
    nonzero marker of a constrained edge ending at it, else 0.

    Parameters
    ----------
    segments : (s, 2) int64
        Constrained edges, indices of the points; ``segment_markers (s,)`` theirs.

    >>> point_markers(4, np.array([[0, 3], [1, 3]]), np.array([2, 6]), (np.array([2]), np.array([5]))).tolist()
    [2, 6, 5, 6]
    """
    out = np.zeros(int(n_points), np.int64)
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    mk = np.asarray(segment_markers, dtype=np.int64).reshape(-1)
    if len(mk) == len(seg) and len(seg):
        nz = mk != 0
        np.maximum.at(out, seg[nz].T.ravel(), np.tile(mk[nz], 2))
    where, values = (np.asarray(a, dtype=np.int64).reshape(-1) for a in given)
    out[where] = values
    return out


def given_at(point_ids: np.ndarray, sorted_prefix: int, marked: tuple[np.ndarray, np.ndarray]) -> tuple:
    """``marked`` (global ids, markers) as local indices into ``point_ids``, whose first
    ``sorted_prefix`` ids are sorted (a tile's vertices, where the input vertices are)
    and whose others are searched one by one (a piece's few join points); ids it does
    not hold are left out. No sort of the piece's millions of ids."""
    ids = np.asarray(point_ids, dtype=np.int64).reshape(-1)
    m_ids, m_val = (np.asarray(a, dtype=np.int64).reshape(-1) for a in marked)
    head = ids[:sorted_prefix]
    at = np.minimum(np.searchsorted(head, m_ids), max(len(head) - 1, 0))
    hit = (head[at] == m_ids) if len(head) else np.zeros(len(m_ids), bool)
    where, values = [at[hit]], [m_val[hit]]
    tail = ids[sorted_prefix:]
    if len(tail) and len(m_ids):
        for j in np.flatnonzero(np.isin(tail, m_ids[~hit])).tolist():
            where.append(np.array([sorted_prefix + j]))
            values.append(m_val[~hit][m_ids[~hit] == tail[j]][:1])
    return np.concatenate(where), np.concatenate(values)
