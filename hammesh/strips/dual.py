"""Checked input for the strip encoders: a triangle mesh and its dual graph.

Any triangle mesh is accepted, planar ``(n, 2)`` or a surface in space ``(n, 3)``; each
triangle's winding (the order of its row) is kept, and the strips reproduce it.  Two
triangles are dual neighbours when they share an edge in opposite directions (the
half-edge pairing of :func:`hammesh.halfedge._kernels.half_edge_twins`; built together with
one ``int32`` record per triangle by :func:`hammesh.strips._kernels.mesh_records`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Optional, Union

import numpy as np
from hammesh.halfedge import _kernels
from hammesh.errors import InvalidMeshError
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.strips import _kernels as _strip_kernels
from hammesh.halfedge import mesh_arrays

__all__ = ["DualMesh", "dual_mesh", "oriented_key"]

MeshLike = Union[Mesh, HamiltonianMesh]


@dataclass(frozen=True, eq=False)
class DualMesh:
    """A validated triangle mesh with its half-edge pairing and dual components.

    Attributes
    ----------
    points : (n, 2) or (n, 3) float64
    triangles : (m, 3) int64
        As given (row order and winding kept).
    twin : (3 m,) int64
        ``twin[h]`` is the half-edge opposite ``h = 3 t + k`` (from ``triangles[t, k]``
        to ``triangles[t, (k + 1) % 3]``), or -1 on the boundary.
    component : (m,) int64
        Connected piece of the dual graph each triangle belongs to, numbered by least
        triangle (computed on first use).
    n_components : int
    records : (m, 8) int32 or None
        ``(v0, v1, v2, twin0, twin1, twin2, scratch, pad)`` per triangle
        (:func:`hammesh.strips._kernels.mesh_records`): what the greedy cover reads,
        one half cache line per triangle; the greedy pass keeps its free degrees in the
        scratch column.  ``None`` for a mesh too large for ``int32`` (or a DualMesh
        built by hand); the encoder then reads ``triangles`` and ``twin``.
    """

    points: np.ndarray
    triangles: np.ndarray
    twin: np.ndarray
    records: Optional[np.ndarray] = field(default=None, repr=False)

    @cached_property
    def _components(self) -> tuple[np.ndarray, int]:
        label, n_comp = _strip_kernels.dual_components(self.twin, len(self.triangles))
        return label, int(n_comp)

    @property
    def component(self) -> np.ndarray:
        return self._components[0]

    @property
    def n_components(self) -> int:
        return self._components[1]

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[0])

    @property
    def neighbor_triangles(self) -> np.ndarray:
        """``(m, 3) int64``: the triangle across each edge ``k`` of each row, or -1."""
        tw = self.twin.reshape(-1, 3)
        return np.where(tw >= 0, tw // 3, -1)


def _edge_problem(tri: np.ndarray, bad: int) -> str:
    t, k = divmod(int(bad), 3)
    a, b = int(tri[t, k]), int(tri[t, (k + 1) % 3])
    lo, hi = min(a, b), max(a, b)
    e0 = np.minimum(tri, np.roll(tri, -1, axis=1))
    e1 = np.maximum(tri, np.roll(tri, -1, axis=1))
    users = np.flatnonzero(((e0 == lo) & (e1 == hi)).any(axis=1))
    shown = ", ".join(str(int(u)) for u in users[:5]) + (", ..." if len(users) > 5 else "")
    if len(users) > 2:
        return (
            f"non-manifold edge ({a}, {b}): shared by {len(users)} triangles ({shown}); "
            "a strip can only cross an edge between two triangles"
        )
    return (
        f"edge ({a}, {b}) is used in the same direction by triangles {shown}: they are "
        "oriented inconsistently (or overlap); orient the mesh consistently first"
    )


def dual_mesh(mesh: MeshLike) -> DualMesh:
    """Check ``mesh`` and build its dual graph.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
        ``points (n, 2) or (n, 3)``, ``triangles (m, 3)`` integer, any consistent winding.

    Returns
    -------
    DualMesh

    Raises
    ------
    InvalidMeshError
        Naming the item: shapes, empty mesh, non-finite point, index out of range, a
        triangle with a repeated vertex or zero area, an edge shared by three or more
        triangles, two neighbours with inconsistent winding.

    Examples
    --------
    >>> import numpy as np
    >>> from hammesh.mesh import Mesh
    >>> d = dual_mesh(Mesh(np.array([[0., 0], [1, 0], [1, 1], [0, 1]]), np.array([[0, 1, 2], [0, 2, 3]])))
    >>> d.neighbor_triangles.tolist(), d.n_components
    ([[-1, -1, 1], [0, -1, -1]], 1)
    """
    pts, tri = mesh_arrays(mesh.points, mesh.triangles, dims=(2, 3))
    n = len(pts)
    t, kind = _strip_kernels.face_problem(pts, tri)
    if kind == 1:
        raise InvalidMeshError(f"triangle {t} {tri[t].tolist()} repeats a vertex (degenerate face)")
    if kind == 2:
        raise InvalidMeshError(f"triangle {t} {tri[t].tolist()} has zero area (degenerate face)")
    packed = _strip_kernels.mesh_records(tri, n)
    if packed is not None:
        return DualMesh(points=pts, triangles=tri, twin=packed[1], records=packed[0])
    # too large for int32 records, or a bad edge: the reference pairing names it
    twin, bad = _kernels.half_edge_twins(tri, n)
    if bad >= 0:
        raise InvalidMeshError(_edge_problem(tri, int(bad)))
    return DualMesh(points=pts, triangles=tri, twin=twin)


def oriented_key(triangles: np.ndarray) -> np.ndarray:
    """Oriented triangles as sorted canonical rows (each rotated to start at its least vertex).

    Two arrays of triangles are the same oriented triangles (as multisets) iff their keys
    are equal; a reversed triangle gets a different key.

    Parameters
    ----------
    triangles : (m, 3) int

    Returns
    -------
    (m, 3) int64, rows sorted lexicographically.

    Examples
    --------
    >>> oriented_key(np.array([[2, 0, 1], [5, 4, 3]])).tolist()
    [[0, 1, 2], [3, 5, 4]]
    """
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    r = np.argmin(tri, axis=1)
    rows = tri[np.arange(len(tri))[:, None], (r[:, None] + np.arange(3)) % 3]
    order = np.lexsort((rows[:, 2], rows[:, 1], rows[:, 0]))
    return rows[order]
