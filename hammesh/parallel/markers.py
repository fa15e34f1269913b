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

__all__ = ["input_vertex_markers", "point_markers", "marked_inputs"]


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


def point_markers(point_ids: np.ndarray, segments: np.ndarray, segment_markers: np.ndarray,
                  marked: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Marker of each point: an input vertex's own (``marked``: :func:`marked_inputs`),
    else the largest nonzero marker of a constrained edge ending at it, else 0.

    Parameters
    ----------
    point_ids : (n,) int64
        Global ids of the points (a piece's, or ``arange`` for the whole output).
    segments : (s, 2) int64
        Constrained edges, global ids; ``segment_markers (s,)`` theirs.
    """
    ids = np.asarray(point_ids, dtype=np.int64).reshape(-1)
    out = np.zeros(len(ids), np.int64)
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    mk = np.asarray(segment_markers, dtype=np.int64).reshape(-1)
    order = np.argsort(ids, kind="stable")
    sorted_ids = ids[order]

    def local(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        at = np.minimum(np.searchsorted(sorted_ids, g), max(len(ids) - 1, 0))
        hit = sorted_ids[at] == g if len(ids) else np.zeros(len(g), bool)
        return order[at[hit]], hit

    if len(mk) == len(seg) and len(seg):
        nz = mk != 0
        ends, value = seg[nz].T.ravel(), np.tile(mk[nz], 2)
        where, hit = local(ends)
        np.maximum.at(out, where, value[hit])
    m_ids, m_val = marked
    where, hit = local(np.asarray(m_ids, dtype=np.int64))
    out[where] = np.asarray(m_val, dtype=np.int64)[hit]
    return out
