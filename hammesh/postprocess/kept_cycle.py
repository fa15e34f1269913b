"""A mesh whose rows already walk a Hamiltonian cycle of every piece, kept as it is.

``hammesh mesh out.vtu`` on hammesh's own output (or any mesh written in cycle order:
consecutive rows share an edge, each piece's last row shares one with its first) needs
no construction: sparse mode's cover, joins and Steiner points would only add triangles
and lower the angles it had kept (session 15: +0.66 % triangles, 156 below the parent
rule, on a 54 k-triangle plate run a second time). :func:`kept_cycle` recognises such
an order in O(m) and returns the mesh unchanged; ``hammesh.hamiltonian`` certifies it
as it certifies any construction (the certificate derives the dual itself).
"""

from __future__ import annotations

import numpy as np

from hammesh.halfedge import HalfEdges
from hammesh.mesh import KIND_NAMES, HamiltonianMesh, Mesh

__all__ = ["cycle_runs", "kept_cycle", "PREFIX_ROWS"]

#: rows tested first: a mesh in another order (Triangle's) is told apart on them
PREFIX_ROWS = 64

_INPUT_KIND = KIND_NAMES.index("input")


def _share_an_edge(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether rows ``a[i]`` and ``b[i]`` have exactly two corners in common."""
    common = (a[:, :, None] == b[:, None, :]).any(axis=2).sum(axis=1)
    return common == 2


def cycle_runs(triangles: np.ndarray) -> np.ndarray | None:
    """Lengths of the runs of rows that walk closed dual cycles, or None.

    The rows are cut where two consecutive rows share no edge; every run must close
    (its last row shares an edge with its first) and have three rows at least.
    Only the rows are read: whether the runs are the mesh's pieces is
    :func:`kept_cycle`'s question.
    """
    t = np.asarray(triangles)
    m = len(t)
    if m == 0 or t.ndim != 2 or t.shape[1] != 3:
        return None
    head = min(m, PREFIX_ROWS)
    if head > 1 and not _share_an_edge(t[: head - 1], t[1:head]).all():
        return None  # (a cheap no for Triangle's order and most others)
    steps = _share_an_edge(t[:-1], t[1:])
    starts = np.concatenate([[0], np.flatnonzero(~steps) + 1])
    ends = np.concatenate([starts[1:], [m]])
    lengths = ends - starts
    # (a dual cycle has three rows at least: two rows meet across one edge only, and a
    # lone triangle has no cycle to keep; the construction handles such pieces)
    if lengths.min() < 3 or not _share_an_edge(t[ends - 1], t[starts]).all():
        return None
    return lengths.astype(np.int64)


def kept_cycle(clean: Mesh, he: HalfEdges) -> HamiltonianMesh | None:
    """``clean`` as a Hamiltonian mesh if its rows already walk one cycle per piece.

    Parameters
    ----------
    clean : Mesh
        Validated and counter-clockwise, rows in the caller's order
        (``hammesh.halfedge.prepare_mesh``).
    he : HalfEdges
        Its half-edges: a run of rows is a piece when no interior edge joins it to
        another run (two cycles in one piece would need joining).

    Returns
    -------
    HamiltonianMesh or None
        Points, rows, segments and attributes unchanged, every triangle of kind
        ``"input"``, ``parent`` the identity; None when the rows are
        in no such order. Unverified (``hammesh.hamiltonian`` certifies it).
    """
    lengths = cycle_runs(clean.triangles)
    if lengths is None:
        return None
    m = len(clean.triangles)
    run = np.repeat(np.arange(len(lengths)), lengths)
    inner = np.flatnonzero(he.twin >= 0)
    if (run[inner // 3] != run[he.twin[inner] // 3]).any():
        return None
    n = len(clean.points)
    report = {
        "triangles": m, "vertices": n, "input_triangles": m, "input_vertices": n,
        "steiner_points": 0, "steiner_per_input_triangle": 0.0, "triangles_added": 0,
        "incenters": 0, "midpoints": 0, "merges": 0,
        "kept_input_cycle": True, "components": [int(x) for x in lengths],
    }
    return HamiltonianMesh(
        points=clean.points,
        triangles=clean.triangles,
        segments=clean.segments,
        segment_markers=clean.segment_markers,
        components=lengths,
        position=np.arange(m, dtype=np.int64) - np.repeat(np.cumsum(lengths) - lengths, lengths),
        parent=np.arange(m, dtype=np.int64),
        kind=np.full(m, _INPUT_KIND, dtype=np.int8),
        triangle_attributes=clean.triangle_attributes,
        report=report,
    )
