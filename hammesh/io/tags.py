"""Named boundary and region sets, and the per-triangle fields that carry them.

A finite-element code wants the constrained edges of a mesh as *named facet sets* (one
per segment marker: Dirichlet here, Neumann there) and the regional attributes as
*named element sets* (one material per region).  The names are the same everywhere
hammesh hands a mesh on (:func:`hammesh.fem.to_skfem`, the Gmsh physical names of
``.msh`` files, the ``skfem:`` cell data of ``.vtu .vtk .xdmf`` files):

* ``marker_<k>``: the constrained edges of segment marker ``k`` (``marker_1``,
  ``marker_-3``);
* ``region_<a>``: the triangles whose first regional attribute is ``a`` (``region_2``
  for 2.0, ``region_0.25``).

The VTK-family files (``.vtu .vtk``) and ``.xdmf`` hold triangles only (a reader such
as ``pyvista.read`` then gets a pure triangle grid); their constrained edges travel as
two per-triangle fields (:func:`edge_fields`):

* ``segment_edges`` ``(m,) int64``: bit ``k`` set if edge ``k`` of the triangle (from
  corner ``k`` to corner ``k + 1``) is a constrained edge, stored on one side only (the
  triangle in which the segment runs from its first point to its second, else the
  other); bit ``k + 3`` set too if the segment runs the other way (corner ``k + 1`` to
  ``k``: a boundary segment given clockwise), so directions survive;
* ``edge_marker`` ``(m, 3) int64``: that edge's segment marker, 0 elsewhere.

scikit-fem's own encoding (``skfem:b:<name>``: per triangle, bit ``j`` set if facet
``j`` of the triangle, corners sorted, facets ``(0 1) (1 2) (0 2)``, is in the set;
``skfem:s:<name>``: 1 on the set's triangles; see ``skfem.Mesh._encode_cell_data``)
is written beside them so that ``skfem.MeshTri.load`` finds the sets by name
(:func:`skfem_cell_data`).  A mesh with more than :data:`MAX_NAMED_SETS` distinct
markers (or regions) gets no ``skfem:`` fields of that kind.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = [
    "BOUNDARY_PREFIX",
    "REGION_PREFIX",
    "SEGMENT_EDGES",
    "EDGE_MARKER",
    "VERTEX_MARKER",
    "MAX_NAMED_SETS",
    "boundary_name",
    "region_name",
    "region_values",
    "EdgeSlots",
    "segment_slots",
    "edge_fields",
    "segments_from_edge_fields",
    "skfem_cell_data",
]

BOUNDARY_PREFIX = "marker_"
REGION_PREFIX = "region_"
#: Cell data: bit ``k`` set if edge ``k`` of the triangle is a constrained edge.
SEGMENT_EDGES = "segment_edges"
#: Cell data ``(m, 3)``: the segment marker of each constrained edge slot (0 elsewhere).
EDGE_MARKER = "edge_marker"
#: Point data: the points' boundary markers.
VERTEX_MARKER = "vertex_marker"
#: At most this many ``skfem:b:`` (and ``skfem:s:``) fields are written per file.
MAX_NAMED_SETS = 64

# skfem's facet j of a triangle with sorted corners s0 < s1 < s2 is (0 1), (1 2), (0 2):
# indexed by the sum of the two corners' ranks (1, 3, 2)
_SKFEM_FACET_OF_RANK_SUM = np.array([-1, 0, 2, 1], dtype=np.int64)


def boundary_name(marker: int) -> str:
    """Name of the facet set of segment marker ``marker``.

    >>> boundary_name(3), boundary_name(-1)
    ('marker_3', 'marker_-1')
    """
    return f"{BOUNDARY_PREFIX}{int(marker)}"


def region_name(value: float) -> str:
    """Name of the element set of regional attribute ``value`` (integral values
    without a decimal point).

    >>> region_name(2.0), region_name(0.25)
    ('region_2', 'region_0.25')
    """
    value = float(value)
    text = str(int(value)) if value.is_integer() else repr(value)
    return f"{REGION_PREFIX}{text}"


def region_values(mesh: Mesh | HamiltonianMesh) -> np.ndarray | None:
    """The first regional attribute of each triangle ``(m,) float64``, or None if the
    mesh has no attributes."""
    attrs = np.asarray(mesh.triangle_attributes, dtype=np.float64)
    m = len(mesh.triangles)
    if attrs.ndim != 2 or attrs.shape[0] != m or attrs.shape[1] == 0 or m == 0:
        return None
    return np.ascontiguousarray(attrs[:, 0])


class EdgeSlots(NamedTuple):
    """Where each segment lies in the triangle array: slot ``3 t + k`` is edge ``k`` of
    triangle ``t`` (from corner ``k`` to corner ``k + 1``)."""

    #: ``(s,) int64``: the slot of the triangle in which the segment runs first point
    #: -> second point (else the one in which it runs backwards).
    slot: np.ndarray
    #: ``(s,) int64``: the slot on the other side, -1 on the mesh boundary.
    other: np.ndarray


def segment_slots(triangles: np.ndarray, segments: np.ndarray) -> EdgeSlots | None:
    """Locate every segment among the triangles' edges (vectorized, ``O(m + s log s)``).

    Returns None if some segment is not an edge of the triangles, an edge is given
    twice (either direction), or an edge is shared by more than two triangles: such a
    mesh is written with explicit ``line`` cells instead (:mod:`hammesh.io.meshio_format`).
    """
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    if len(seg) == 0:
        return EdgeSlots(np.zeros(0, np.int64), np.zeros(0, np.int64))
    if len(tri) == 0:
        return None
    span = int(max(tri.max(), seg.max())) + 1
    a = tri.reshape(-1)
    skeys = np.minimum(seg[:, 0], seg[:, 1]) * span + np.maximum(seg[:, 0], seg[:, 1])
    by_key = np.argsort(skeys)
    sorted_skeys = skeys[by_key]
    if np.any(sorted_skeys[1:] == sorted_skeys[:-1]):
        return None
    # the segments are few (boundary and constraints): keep the edges whose two ends are
    # segment ends and look those up among the segments, instead of sorting all 3 m
    # edges (the 1.5 M-triangle write: 0.84 -> 0.05 s)
    on_segment = np.zeros(span, dtype=bool)
    on_segment[seg.reshape(-1)] = True
    ends = on_segment[tri]
    slots = np.flatnonzero((ends & ends[:, [1, 2, 0]]).reshape(-1))  # ascending
    u, v = a[slots], tri[slots // 3, (slots % 3 + 1) % 3]
    keys = np.minimum(u, v) * span + np.maximum(u, v)
    at = np.minimum(np.searchsorted(sorted_skeys, keys), len(seg) - 1)
    hit = sorted_skeys[at] == keys
    hit_slots = slots[hit]  # ascending
    at = at[hit]
    seg_of = by_key[at]
    count = np.bincount(seg_of, minlength=len(seg))
    if np.any(count == 0) or np.any(count > 2):
        return None
    grouped = hit_slots[np.argsort(seg_of, kind="stable")]  # per segment, its slots ascending
    lo = np.cumsum(count) - count
    first = grouped[lo]
    second = np.where(count == 2, grouped[np.minimum(lo + 1, len(grouped) - 1)], -1)
    # the slot in which the segment runs forwards
    forwards = a[first] == seg[:, 0]
    slot = np.where(forwards | (second < 0), first, second)
    other = np.where(slot == first, second, first)
    return EdgeSlots(slot, other)


def edge_fields(mesh: Mesh | HamiltonianMesh, slots: EdgeSlots | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """``(segment_edges (m,) int64, edge_marker (m, 3) int64)`` of ``mesh``'s segments
    (see the module docstring), or None if they cannot be stored per triangle
    (:func:`segment_slots`; ``slots``: its result, if the caller has it)."""
    m = len(mesh.triangles)
    if slots is None:
        slots = segment_slots(mesh.triangles, mesh.segments)
    if slots is None:
        return None
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    if len(markers) != len(slots.slot):
        markers = np.zeros(len(slots.slot), dtype=np.int64)
    bits = np.zeros(3 * m, dtype=np.int64)
    bits[slots.slot] = 1
    tri = np.asarray(mesh.triangles, dtype=np.int64).reshape(-1)
    seg = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    backwards = np.zeros(3 * m, dtype=np.int64)
    backwards[slots.slot] = tri[slots.slot] != seg[:, 0]
    flags = bits.reshape(m, 3) @ np.array([1, 2, 4], dtype=np.int64)
    flags += backwards.reshape(m, 3) @ np.array([8, 16, 32], dtype=np.int64)
    edge_marker = np.zeros(3 * m, dtype=np.int64)
    edge_marker[slots.slot] = markers
    return flags, edge_marker.reshape(m, 3)


def segments_from_edge_fields(
    triangles: np.ndarray, flags: np.ndarray, edge_marker: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`edge_fields`: ``(segments (s, 2), markers (s,))`` in slot order
    (triangle by triangle, edges 0 1 2), each in its own direction."""
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    flags = np.asarray(flags, dtype=np.int64).reshape(-1)
    marks = np.asarray(edge_marker, dtype=np.int64).reshape(-1, 3)
    bits = ((flags[:, None] >> np.arange(3)) & 1).astype(bool)
    t, k = np.nonzero(bits)
    backwards = ((flags[t] >> (k + 3)) & 1).astype(bool)
    segments = np.column_stack([tri[t, k], tri[t, (k + 1) % 3]])
    segments[backwards] = segments[backwards][:, ::-1]
    return segments, marks[t, k]


def _skfem_facet(triangles: np.ndarray, slot: np.ndarray) -> np.ndarray:
    """skfem's local facet index (0, 1, 2) of each edge slot ``3 t + k``."""
    tri = np.asarray(triangles, dtype=np.int64)
    t, k = np.divmod(slot, 3)
    rows = tri[t]
    rank = (rows[:, None, :] < rows[:, :, None]).sum(axis=2)  # rank of each corner in its row
    rank_sum = rank[np.arange(len(t)), k] + rank[np.arange(len(t)), (k + 1) % 3]
    return _SKFEM_FACET_OF_RANK_SUM[rank_sum]


def skfem_cell_data(mesh: Mesh | HamiltonianMesh, slots: EdgeSlots | None = None) -> dict[str, np.ndarray]:
    """scikit-fem's named-set cell data (``skfem:b:marker_<k>``, ``skfem:s:region_<a>``),
    each ``(m,) int64``, for ``skfem.MeshTri.load`` (see the module docstring).

    An interior constrained edge is put in its set from the triangle in which the
    segment runs forwards (its left side for a counter-clockwise mesh); empty if the
    segments cannot be located (:func:`segment_slots`).
    """
    m = len(mesh.triangles)
    data: dict[str, np.ndarray] = {}
    if slots is None:
        slots = segment_slots(mesh.triangles, mesh.segments)
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    if slots is not None and len(slots.slot) and len(markers) == len(slots.slot):
        values = np.unique(markers)
        if len(values) <= MAX_NAMED_SETS:
            t = slots.slot // 3
            bit = np.left_shift(1, _skfem_facet(mesh.triangles, slots.slot))
            for value in values.tolist():
                mask = np.zeros(m, dtype=np.int64)
                sel = markers == value
                np.bitwise_or.at(mask, t[sel], bit[sel])
                data[f"skfem:b:{boundary_name(value)}"] = mask
    regions = region_values(mesh)
    if regions is not None:
        values = np.unique(regions[~np.isnan(regions)])
        if len(values) <= MAX_NAMED_SETS:
            for value in values.tolist():
                data[f"skfem:s:{region_name(value)}"] = (regions == value).astype(np.int64)
    return data
