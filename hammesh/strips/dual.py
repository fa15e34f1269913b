"""Checked input for the strip encoders: a triangle mesh and its dual graph.

Any triangle mesh is accepted, planar ``(n, 2)`` or a surface in space ``(n, 3)``, and
need not be a manifold: non-manifold edges, flipped neighbours, non-orientable pieces,
zero-area and double-sided triangles are all drawn (:mod:`hammesh.strips.defects`).
Each triangle's winding (the order of its row) is kept, and the strips reproduce it.
Two triangles are dual neighbours when they are the only two on an edge and use it in
opposite directions (a *proper* edge); every other edge cuts the dual.  On a clean mesh
the pairing comes with one ``int32`` record per triangle from the packed kernel
(:func:`hammesh.strips._dual_kernels.mesh_records`); otherwise from
:func:`hammesh.strips.defects.proper_pairing`.  Rows repeating a vertex index draw
nothing in OpenGL: they are dropped (``rows`` lists the kept ones) and counted.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import cached_property
from typing import Optional, Union

import numpy as np
from hammesh import params
from hammesh.errors import InvalidMeshError
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.strips import _dual_kernels
from hammesh.strips.defects import ZERO_AREA_RTOL, MeshDefects, mesh_defects, proper_pairing
from hammesh.halfedge import mesh_arrays

__all__ = ["DualMesh", "dual_mesh", "oriented_key", "CENSUS_BESIDE_PAIRING"]

#: Triangles from which :func:`dual_mesh` runs the face census (repeated vertices, zero
#: areas) on a second thread beside the pairing; below, a thread costs more than it saves.
CENSUS_BESIDE_PAIRING = 50_000

MeshLike = Union[Mesh, HamiltonianMesh]


@dataclass(frozen=True, eq=False)
class DualMesh:
    """A validated triangle mesh with its half-edge pairing and dual components.

    Attributes
    ----------
    points : (n, 2) or (n, 3) float64
    triangles : (m, 3) int64
        As given (row order and winding kept), less the rows repeating a vertex.
    twin : (3 m,) int64
        ``twin[h]`` is the half-edge opposite ``h = 3 t + k`` (from ``triangles[t, k]``
        to ``triangles[t, (k + 1) % 3]``) across a proper edge, or -1 (boundary or cut).
    component : (m,) int64
        Connected piece of the dual graph each triangle belongs to, numbered by least
        triangle (computed on first use).
    n_components : int
    records : (m, 8) int32 (int64 for a mesh too large for int32) or None
        ``(v0, v1, v2, twin0, twin1, twin2, scratch, pad)`` per triangle
        (:func:`hammesh.strips._dual_kernels.mesh_records`): what the greedy cover reads,
        one half cache line per triangle; the greedy pass keeps its free degrees in the
        scratch column.  ``None`` only for a DualMesh built by hand:
        :meth:`cover_records` then builds them.
    defects : MeshDefects
        What was found (:mod:`hammesh.strips.defects`).
    rows : (m,) int64 or None
        Input row of each triangle when rows repeating a vertex were dropped
        (``None``: all rows kept).
    """

    points: np.ndarray
    triangles: np.ndarray
    twin: np.ndarray
    records: Optional[np.ndarray] = field(default=None, repr=False)
    defects: MeshDefects = field(default_factory=MeshDefects)
    rows: Optional[np.ndarray] = field(default=None, repr=False)

    @cached_property
    def _components(self) -> tuple[np.ndarray, int]:
        label, n_comp = _dual_kernels.dual_components(self.twin, len(self.triangles))
        return label, int(n_comp)

    @property
    def component(self) -> np.ndarray:
        return self._components[0]

    @property
    def n_components(self) -> int:
        return self._components[1]

    def cover_records(self) -> np.ndarray:
        """:attr:`records`, or new ones from ``triangles`` and ``twin`` (a DualMesh built by hand)."""
        if self.records is not None:
            return self.records
        m = len(self.triangles)
        n = int(self.triangles.max()) + 1 if m else 0
        rec = np.empty((m, _dual_kernels.REC_WIDTH), _dual_kernels.records_dtype(m, n))
        _dual_kernels.records_from_twin(self.triangles, np.ascontiguousarray(self.twin, dtype=np.int64), rec)
        return rec

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[0])

    @property
    def neighbor_triangles(self) -> np.ndarray:
        """``(m, 3) int64``: the triangle across each edge ``k`` of each row, or -1."""
        tw = self.twin.reshape(-1, 3)
        return np.where(tw >= 0, tw // 3, -1)


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
        Naming the item: shapes, empty mesh, non-finite point, index out of range, no
        triangle left after dropping those that repeat a vertex.

    Examples
    --------
    >>> import numpy as np
    >>> from hammesh.mesh import Mesh
    >>> d = dual_mesh(Mesh(np.array([[0., 0], [1, 0], [1, 1], [0, 1]]), np.array([[0, 1, 2], [0, 2, 3]])))
    >>> d.neighbor_triangles.tolist(), d.n_components
    ([[-1, -1, 1], [0, -1, -1]], 1)
    """
    params.instance("mesh", mesh, (Mesh, HamiltonianMesh), "a hammesh.Mesh (e.g. hammesh.Mesh(points, triangles))")
    pts, tri = mesh_arrays(mesh.points, mesh.triangles, dims=(2, 3))
    n = len(pts)
    flags = np.empty(len(tri), np.int8)
    paired = False
    if len(tri) >= CENSUS_BESIDE_PAIRING:
        # the face census gathers the points at random (~10% of a large encoding): it
        # runs on a second thread (nogil) while this one pairs the rows as if none
        # repeated a vertex, which is redone below in the rare case that some do
        with ThreadPoolExecutor(1) as pool:
            census = pool.submit(_dual_kernels.face_flags, pts, tri, ZERO_AREA_RTOL, flags)
            packed = _dual_kernels.mesh_records(tri, n)
            n_rep, n_zero = census.result()
        paired = True
    else:
        n_rep, n_zero = _dual_kernels.face_flags(pts, tri, ZERO_AREA_RTOL, flags)
    rows = None
    if n_rep:
        rows = np.flatnonzero(flags != _dual_kernels.FACE_REPEATED)
        if len(rows) == 0:
            raise InvalidMeshError(f"all {len(tri)} triangles repeat a vertex: nothing to draw")
        tri = np.ascontiguousarray(tri[rows])
        paired = False
    if not paired:
        packed = _dual_kernels.mesh_records(tri, n)
    if packed is not None:  # every edge proper or boundary: only pillows can be double-sided
        pillows = int(_dual_kernels.count_pillows(packed[0]))
        found = MeshDefects(repeated_vertex=int(n_rep), zero_area=int(n_zero), double_sided=pillows // 2)
        return DualMesh(pts, tri, packed[1], packed[0], found, rows)
    pairing = proper_pairing(tri, n)
    found = mesh_defects(pts, tri, pairing, repeated=int(n_rep), zero_area=int(n_zero))
    rec = np.empty((len(tri), _dual_kernels.REC_WIDTH), _dual_kernels.records_dtype(len(tri), n))
    _dual_kernels.records_from_twin(tri, pairing.twin, rec)
    return DualMesh(pts, tri, pairing.twin, rec, found, rows)


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
