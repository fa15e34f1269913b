"""Recover the cycle runs of a Hamiltonian mesh read from a file.

A file written by hammesh stores each connected piece's cycle as one consecutive run
of triangles; formats without cell data (.obj, .ply, ...) keep only that order. The
runs are therefore the pieces themselves: this module finds the pieces (connected
components of the dual graph) and checks they are stored as consecutive runs.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from hammesh.errors import InvalidMeshError, VerificationError
from hammesh.verify import _kernels

__all__ = ["infer_runs", "infer_runs_and_pairing"]


def infer_runs(triangles: np.ndarray, n_points: int) -> np.ndarray:
    """Run lengths of the cycles of a mesh stored piece after piece.

    Parameters
    ----------
    triangles : (m, 3) int64, in file order
    n_points : int

    Returns
    -------
    (c,) int64
        Length of each run; one run per connected piece.

    Raises
    ------
    VerificationError
        A piece is split over several runs (its triangles are not consecutive:
        ``check="cycle"``), or the mesh is not edge-manifold: an edge shared by more than
        two triangles or by two in one direction (``check="overlap"``).
    InvalidMeshError
        A triangle references a vertex outside ``0..n_points - 1``.
    """
    return infer_runs_and_pairing(triangles, n_points)[0]


def infer_runs_and_pairing(triangles: np.ndarray, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`infer_runs` and the half-edge pairing it found on the way.

    The pairing is the certificate's own (``_kernels.half_edge_twins``): ``hammesh
    check`` hands it on to the cycle checks and the overlap test instead of pairing
    the half-edges twice more.
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    m = len(tri)
    if m == 0:
        raise VerificationError("the mesh has no triangles", check="input")
    if tri.min() < 0 or tri.max() >= n_points:
        raise InvalidMeshError(f"triangles reference vertices outside 0..{n_points - 1}")
    twin, bad = _kernels.half_edge_twins(tri, int(n_points))  # the certificate's own
    if bad >= 0:
        t, k = divmod(int(bad), 3)
        raise VerificationError(
            f"edge ({tri[t, k]}, {tri[t, (k + 1) % 3]}) of triangle {t} is shared by more than two "
            "triangles or by two triangles in the same direction (non-manifold edge or overlap)", check="overlap"
        )
    h = np.flatnonzero(twin >= 0)
    graph = coo_matrix((np.ones(len(h), dtype=np.int8), (h // 3, twin[h] // 3)), shape=(m, m))
    n_pieces, label = connected_components(graph, directed=False)
    change = np.flatnonzero(np.diff(label) != 0) + 1
    starts = np.r_[0, change]
    if len(starts) != n_pieces:
        _, first_seen = np.unique(label[starts], return_index=True)
        repeat = np.setdiff1d(np.arange(len(starts)), first_seen)
        first_repeat = int(starts[repeat.min()])
        raise VerificationError(
            f"connected piece of triangle {first_repeat} is not stored as one consecutive "
            "run of triangles (each piece must be one cycle)", check="cycle"
        )
    return np.diff(np.r_[starts, m]).astype(np.int64), twin
