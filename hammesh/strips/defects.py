"""What a strip (or a surface cycle) may cross: the proper edges of any triangle soup, and the defects found.

Real-world surfaces are rarely clean 2-manifolds: pyvista's airplane has an edge shared by
three triangles, the Stanford bunny 132, the globe has zero-area triangles, parametric
Klein bottles, Boy surfaces and Möbius strips cannot be oriented, exported meshes carry
flipped triangles and double-sided faces.  A GL strip needs none of these properties:
two consecutive triangles of a strip share an edge, and the strip's implied winding
alternates, so they must use that edge in *opposite* directions for both to keep their
own winding.  We therefore call an edge *proper* when exactly two triangles use it, in
opposite directions, and the dual graph has exactly the proper edges.  Every other edge
is a cut: an edge with one, three or more triangles (boundary, non-manifold), or two
triangles whose windings disagree across it (a *flipped neighbour*; crossing it inside a
strip would cost two repeated indices, a restart costs three, and the encoder never has
to reverse a triangle).  Every triangle's row is kept as given.

The pairing (:func:`hammesh.strips._dual_kernels.proper_twins_into`: half-edges bucketed by
their lesser vertex, users gathered per bucket) is used only when the packed fast path
(:func:`hammesh.strips._dual_kernels.mesh_records`) meets a bad edge; on a clean mesh both
give the same pairing.

The defect counts (:class:`MeshDefects`) go into the strip's and the surface's report:

* ``repeated_vertex``: triangles with a repeated vertex index: nothing to draw (OpenGL
  skips them), dropped and listed;
* ``zero_area``: triangles of zero area (:data:`ZERO_AREA_RTOL`): collinear or
  coincident points, unresolvable slivers; a strip draws them as given, the surface
  construction (which needs an incenter) drops them;
* ``non_manifold_edges``: edges used by three or more triangles;
* ``flipped_neighbours``: edges used by exactly two triangles in the same direction;
* ``non_orientable_pieces``: pieces (joined across edges of exactly two triangles, either
  direction) whose triangles cannot all be re-oriented to agree (Klein bottle, Möbius
  strip), found as pieces whose orientation double cover is connected;
* ``double_sided``: vertex triples used by two triangles of opposite windings;
* ``duplicate``: further copies of a triangle with the same winding.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np

from hammesh.strips import _dual_kernels as _kernels

__all__ = [
    "MeshDefects",
    "EdgePairing",
    "proper_pairing",
    "repeated_vertex_rows",
    "zero_area_rows",
    "ZERO_AREA_RTOL",
    "orientation_pieces",
    "triangle_repeats",
    "mesh_defects",
    "defect_fields",
]


@dataclass(frozen=True)
class MeshDefects:
    """Counts of what makes a mesh other than a clean oriented 2-manifold (module docstring)."""

    repeated_vertex: int = 0
    zero_area: int = 0
    non_manifold_edges: int = 0
    flipped_neighbours: int = 0
    non_orientable_pieces: int = 0
    double_sided: int = 0
    duplicate: int = 0

    @property
    def any(self) -> bool:
        return any(v for v in asdict(self).values())

    def to_dict(self) -> dict[str, int]:
        return {k: int(v) for k, v in asdict(self).items()}


class EdgePairing(NamedTuple):
    """Result of :func:`proper_pairing`."""

    twin: np.ndarray  #: (3 m,) int64: the proper partner of each half-edge, or -1
    flipped: np.ndarray  #: (k, 2) int64: the two half-edges of each flipped-neighbour edge
    non_manifold_edges: int  #: edges used by three or more half-edges


def proper_pairing(triangles: np.ndarray, n_points: int) -> EdgePairing:
    """Pair the half-edges of proper edges (exactly two triangles, opposite directions).

    Half-edge ``h = 3 t + k`` goes from ``triangles[t, k]`` to ``triangles[t, (k + 1) % 3]``.
    Rows must not repeat a vertex (see :func:`repeated_vertex_rows`).

    Examples
    --------
    Two triangles agreeing across edge (0, 2), a third using (0, 2) as well: a
    non-manifold edge, nothing paired there.

    >>> t = np.array([[0, 1, 2], [0, 2, 3], [2, 0, 4]])
    >>> p = proper_pairing(t, 5)
    >>> int((p.twin >= 0).sum()), p.non_manifold_edges, len(p.flipped)
    (0, 1, 0)
    >>> p = proper_pairing(np.array([[0, 1, 2], [0, 2, 3]]), 4)
    >>> p.twin.tolist()
    [-1, -1, 3, 2, -1, -1]
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    twin = np.empty(3 * len(tri), np.int64)
    flipped = np.empty((3 * len(tri), 2), np.int64)
    n_flip, n_nm = _kernels.proper_twins_into(tri, int(n_points), twin, flipped)
    return EdgePairing(twin, flipped[:n_flip].copy(), int(n_nm))


def repeated_vertex_rows(triangles: np.ndarray) -> np.ndarray:
    """``(m,) bool``: rows with a repeated vertex index."""
    t = np.asarray(triangles)
    return (t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 2] == t[:, 0])


#: A triangle has *zero area* when twice its area is at most this times its longest side
#: squared (a relative height below ``1e-13``): collinear points, coincident points under
#: different indices, and slivers whose area floating point cannot resolve (the globe's
#: pole triangles: a 6e-8 base under a 1.4e9 height).  Equilateral triangles have 0.87.
ZERO_AREA_RTOL = 1e-13


def zero_area_rows(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``(m,) bool``: rows of zero area (:data:`ZERO_AREA_RTOL`; rows repeating a vertex too).

    Every index must be in ``[0, len(points))`` (checked by the callers, e.g. with
    :func:`hammesh.halfedge.mesh_arrays`): the compiled census reads the points unchecked.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    flags = np.empty(len(tri), np.int8)
    _kernels.face_flags(pts, tri, ZERO_AREA_RTOL, flags)
    return flags != _kernels.FACE_OK


def orientation_pieces(m: int, twin: np.ndarray, flipped: np.ndarray) -> tuple[int, int]:
    """``(pieces, non-orientable pieces)`` of the graph joining triangles across two-triangle edges.

    A proper edge asks both triangles to keep their relative orientation, a flipped one
    to change it; a piece can be oriented iff no triangle is reached with both signs
    (:func:`hammesh.strips._dual_kernels.orientation_count`, one search).
    """
    p, bad = _kernels.orientation_count(
        np.ascontiguousarray(twin, dtype=np.int64), np.ascontiguousarray(flipped, dtype=np.int64).reshape(-1, 2), int(m)
    )
    return int(p), int(bad)


def triangle_repeats(triangles: np.ndarray) -> tuple[int, int, np.ndarray]:
    """``(double_sided, duplicate, duplicate_rows)``: rows on the same three vertices.

    ``duplicate_rows`` marks every copy of an oriented triangle after its first row.
    """
    tri = np.asarray(triangles, dtype=np.int64)
    m = len(tri)
    dup_rows = np.zeros(m, dtype=bool)
    if m < 2:
        return 0, 0, dup_rows
    srt = np.sort(tri, axis=1)
    r = np.argmin(tri, axis=1)
    second = tri[np.arange(m), (r + 1) % 3]
    parity = (second == srt[:, 1]).astype(np.int64)  # 1: same cyclic order as sorted
    o = np.lexsort((np.arange(m), parity, srt[:, 2], srt[:, 1], srt[:, 0]))
    s, p = srt[o], parity[o]
    same_set = np.r_[False, (s[1:] == s[:-1]).all(axis=1)]
    same_oriented = same_set & np.r_[False, p[1:] == p[:-1]]
    dup_rows[o[same_oriented]] = True
    double = same_set & ~same_oriented  # the first of each parity change inside a vertex set
    return int(double.sum()), int(same_oriented.sum()), dup_rows


def mesh_defects(
    points: np.ndarray, triangles: np.ndarray, pairing: EdgePairing, *, repeated: int = 0, zero_area: int | None = None
) -> MeshDefects:
    """Count the defects of ``triangles`` (rows without repeated vertices) given their pairing."""
    tri = np.asarray(triangles, dtype=np.int64)
    if zero_area is None:
        zero_area = int(zero_area_rows(points, tri).sum())
    _, non_orientable = orientation_pieces(len(tri), pairing.twin, pairing.flipped)
    # a row and its copy (either winding) share three edges, so neither has a proper
    # neighbour other than the copy: only such rows are compared
    nb = np.where(pairing.twin >= 0, pairing.twin // 3, -1).reshape(-1, 3)
    cand = ((nb < 0) | (nb == nb.max(axis=1)[:, None])).all(axis=1)
    double, dup, _ = triangle_repeats(tri[cand])
    return MeshDefects(
        repeated_vertex=int(repeated),
        zero_area=int(zero_area),
        non_manifold_edges=int(pairing.non_manifold_edges),
        flipped_neighbours=int(len(pairing.flipped)),
        non_orientable_pieces=non_orientable,
        double_sided=double,
        duplicate=dup,
    )


def defect_fields(defects: MeshDefects | None, dropped: np.ndarray) -> dict:
    """``defect_<name>`` counts and ``dropped_rows`` for a strip document (none if not known).

    Flat keys, so that the ``.npz`` form stores each as a plain array.
    """
    if defects is None:
        return {}
    return {f"defect_{k}": v for k, v in defects.to_dict().items()} | {"dropped_rows": [int(r) for r in dropped]}
