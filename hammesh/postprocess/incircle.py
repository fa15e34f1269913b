"""Theorem 2.4: a Hamiltonian cycle mesh from any triangulation, by incenters and flips.

Arkin, Held, Mitchell, Skiena, *Hamiltonian Triangulations for Fast Rendering*, Thm 2.4
and the paragraph on conformal meshes after it:

1. put a Steiner point at the incenter of every input triangle and join it to the
   triangle's corners (each triangle becomes three);
2. take a spanning tree of the dual graph and flip every input edge the tree
   crosses: the two incenters become joined (the flip is always legal, Fig. 9);
3. the triangles, walked around the tree, form one Hamiltonian cycle; the minimum
   angle is at least half the input's.

Constrained edges are never flipped. The tree is a minimum spanning forest in which
constrained dual edges cost more (``_kernels.spanning_forest``), so it crosses a
constrained edge only where a closed chain of them separates two regions: exactly
``regions - pieces`` crossings, one per separated region. A crossed constrained edge
keeps its place and gets its midpoint instead of a flip (the paper's conformal
variant); its two input triangles become four triangles around the midpoint.

The cycle is a successor permutation on output triangles (see ``_successors``):
every output triangle is owned by a *slot*, the half-edge ``h = 3 t + k`` of the input
triangle ``t``. Sweeping counter-clockwise around the incenter of ``t``, slot ``h``
holds ``(I_t, a, b)`` if its edge ``ab`` is not in the tree, ``(I_t, a, I_u)`` if it is
flipped (``u`` across), and ``(I_t, a, M)`` plus ``(I_t, M, b)`` if it is split at ``M``.
"""

from __future__ import annotations

import numpy as np

from hammesh import _kernels
from hammesh.errors import VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions
from hammesh.postprocess.conform import split_segments
from hammesh.verify.input_mesh import HalfEdges

__all__ = ["incircle_hamiltonian", "incenters"]

def incenters(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Incenters of triangles.

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64

    Returns
    -------
    (m, 2) float64
        ``(|BC| A + |CA| B + |AB| C) / (|BC| + |CA| + |AB|)`` for each triangle ABC.
    """
    return _kernels.incenters(
        np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(triangles, dtype=np.int64)
    )


def incircle_hamiltonian(
    mesh: Mesh, he: HalfEdges, is_con: np.ndarray
) -> tuple[HamiltonianMesh, np.ndarray]:
    """Build the Thm 2.4 Hamiltonian cycle mesh (unverified; see ``hammesh.hamiltonian``).

    Parameters
    ----------
    mesh : Mesh
        Counter-clockwise, validated (``hammesh.verify.input_mesh.prepare_mesh``).
    he : HalfEdges
        Its half-edge adjacency.
    is_con : (3 m,) bool
        Half-edges on constrained edges.

    Returns
    -------
    HamiltonianMesh
        With ``report`` holding the construction counts only.
    claim : (3 m_out,) int64
        The output's half-edge twins as the construction implies them; the
        certificate checks this claim instead of recomputing the pairing.
    """
    pts = mesh.points
    n, m = mesh.n_points, mesh.n_triangles
    # the walk runs in the tree search's numbering (locality): incenter n + i is that
    # of input triangle order[i]
    tri, code, order, firsts = _kernels.spanning_forest(mesh.triangles, he.twin, is_con)
    out, parent, kind, lengths, mid_a, mid_b, claim = _kernels.emit_cycles(tri, code, firsts, n)
    parent = order[parent]
    if len(out) != 3 * m + 2 * len(mid_a):
        raise VerificationError(
            f"internal error: the tree walk emitted {len(out)} of "
            f"{3 * m + 2 * len(mid_a)} triangles"
        )
    q = len(mid_a)
    points = np.empty((n + m + q, 2))
    points[:n] = pts
    _kernels.incenters(pts, tri, out=points[n : n + m])
    points[n + m :] = 0.5 * (pts[mid_a] + pts[mid_b])

    segs, markers = split_segments(mesh.segments, mesh.segment_markers, mid_a, mid_b, n + m, len(points))
    position = cycle_positions(lengths)
    report = {
        "triangles": int(len(out)),
        "vertices": int(len(points)),
        "input_triangles": int(m),
        "input_vertices": int(n),
        "steiner_points": int(m + q),
        "incenters": int(m),
        "midpoints": int(q),
        "flips": int(np.count_nonzero((code & 3) == _kernels.TREE_BIT) // 2),
        "components": [int(x) for x in lengths],
    }
    h = HamiltonianMesh(
        points=points,
        triangles=out,
        segments=segs,
        segment_markers=markers,
        components=lengths,
        position=position,
        parent=parent,
        kind=kind,
        triangle_attributes=mesh.triangle_attributes[parent],
        report=report,
    )
    return h, claim
