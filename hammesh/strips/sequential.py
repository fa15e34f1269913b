"""Sequential triangulations (paper §4, Thm 4.3): is there a strip whose turns all alternate?

A triangulation is *sequential* if its dual has a Hamiltonian path along which no three
consecutively crossed edges share a vertex: all turns alternate left and right, so the
mesh is one GL strip of ``m + 2`` indices (plus at most one for the first triangle's
parity) with no swap.  Thm 4.3 decides it in O(n): a Hamiltonian path visits any fixed
triangle ``t0``; the six orders of ``t0``'s vertices each force the whole strip (successor
and predecessor triangles are determined by the alternation), and a sliding window finds
``m`` consecutive distinct triangles in the forced chain if there are any.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import permutations

import numpy as np

from hammesh.strips._sequential_kernels import sequential_chain
from hammesh.strips.dual import DualMesh, MeshLike, dual_mesh

__all__ = ["SequentialOrder", "sequential_order"]


@dataclass(frozen=True, eq=False)
class SequentialOrder:
    """An alternating Hamiltonian path.

    Attributes
    ----------
    order : (m,) int64
        Triangle ids in path order.
    vertices : (m + 2,) int64
        Triangle ``i`` of the path has vertices ``vertices[i:i + 3]``.
    """

    order: np.ndarray
    vertices: np.ndarray


def sequential_order(mesh: MeshLike | DualMesh) -> SequentialOrder | None:
    """The alternating Hamiltonian path of a sequential triangulation, or ``None`` (Thm 4.3).

    Parameters
    ----------
    mesh : Mesh, HamiltonianMesh or DualMesh
        Planar or a surface; validated by :func:`hammesh.strips.dual.dual_mesh`.

    Returns
    -------
    SequentialOrder or None
        ``None`` if no Hamiltonian path of the dual alternates its turns (always for a
        mesh of several pieces).  O(m) time: six forced chains of at most ``2 m - 1``
        triangles.

    Examples
    --------
    A fan of three triangles is sequential, a fan of four is not (its middle edges all
    meet at the centre).

    >>> import numpy as np
    >>> from hammesh.mesh import Mesh
    >>> pts = np.array([[0., 0], [1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0]])
    >>> fan = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])
    >>> sequential_order(Mesh(pts, fan[:3])).order.tolist()
    [2, 1, 0]
    >>> sequential_order(Mesh(pts, fan)) is None
    True
    """
    d = mesh if isinstance(mesh, DualMesh) else dual_mesh(mesh)
    if d.n_components != 1:
        return None
    tri = d.triangles
    t0 = 0
    for a, b, c in permutations(tri[t0].tolist()):
        order, verts = sequential_chain(tri, d.twin, t0, a, b, c)
        if len(order):
            return SequentialOrder(order=order, vertices=verts)
    return None
