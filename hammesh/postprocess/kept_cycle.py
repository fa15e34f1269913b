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
from hammesh.errors import InvalidMeshError
from hammesh.mesh import KIND_NAMES, HamiltonianMesh, Mesh, cycle_positions
from hammesh.partition import cycle_runs, rows_share_an_edge

__all__ = ["kept_runs", "kept_cycle", "PREFIX_ROWS"]

#: rows tested first: a mesh in another order (Triangle's) is told apart on them
PREFIX_ROWS = 64

_INPUT_KIND = KIND_NAMES.index("input")


def kept_runs(triangles: np.ndarray) -> np.ndarray | None:
    """Run lengths if the rows walk closed dual cycles of three rows or more, else None.

    ``hammesh.partition.cycle_runs`` cuts the rows into runs and checks that each
    closes; a run of one or two rows is no cycle to keep (two rows meet across one edge
    only; the construction handles such pieces). Only the rows are read: whether the
    runs are the mesh's pieces is :func:`kept_cycle`'s question.
    """
    t = np.asarray(triangles)
    if len(t) == 0 or t.ndim != 2 or t.shape[1] != 3:
        return None
    # a cheap no for Triangle's order and most others, on every call: the runs that end
    # among the first rows must be closed cycles of three rows or more
    head = t[:PREFIX_ROWS]
    ends = np.flatnonzero(~rows_share_an_edge(head[:-1], head[1:]))
    starts = np.r_[0, ends[:-1] + 1]
    if (ends - starts < 2).any() or not rows_share_an_edge(head[ends], head[starts]).all():
        return None
    try:
        lengths = cycle_runs(t)
    except InvalidMeshError:  # (a run that does not close)
        return None
    return lengths if lengths.min() >= 3 else None


def kept_cycle(clean: Mesh, he: HalfEdges, lengths: np.ndarray | None = None) -> HamiltonianMesh | None:
    """``clean`` as a Hamiltonian mesh if its rows already walk one cycle per piece.

    Parameters
    ----------
    clean : Mesh
        Validated and counter-clockwise, rows in the caller's order
        (``hammesh.halfedge.prepare_mesh``).
    he : HalfEdges
        Its half-edges: a run of rows is a piece when no interior edge joins it to
        another run (two cycles in one piece would need joining).
    lengths : (c,) int64, optional
        :func:`kept_runs` of its rows, if the caller has them.

    Returns
    -------
    HamiltonianMesh or None
        Points, rows, segments and attributes unchanged, every triangle of kind
        ``"input"``, ``parent`` the identity; None when the rows are
        in no such order. Unverified (``hammesh.hamiltonian`` certifies it).
    """
    if lengths is None:
        lengths = kept_runs(clean.triangles)
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
        position=cycle_positions(lengths),
        parent=np.arange(m, dtype=np.int64),
        kind=np.full(m, _INPUT_KIND, dtype=np.int8),
        triangle_attributes=clean.triangle_attributes,
        report=report,
    )
