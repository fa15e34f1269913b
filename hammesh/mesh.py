"""The two plain-data mesh types of hammesh.

Both are frozen dataclasses of numpy arrays; algorithms are free functions that take
and return them (or plain arrays).  Conventions, everywhere in hammesh:

* ``points``: ``(n, 2) float64``.
* ``triangles``: ``(m, 3) int64``, zero-based, counter-clockwise.
* ``neighbors``: ``(m, 3) int64``; ``neighbors[t, k]`` is the triangle across edge
  ``(triangles[t, k], triangles[t, (k + 1) % 3])``, or ``-1`` on the boundary.
* ``segments``: ``(s, 2) int64`` constrained edges; each is an edge of ``triangles``.
* ``vertex_markers``: ``(n,) int64`` boundary markers of the points (Triangle's
  convention: a point on a constrained edge whose own marker is 0 takes the edge's).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from hammesh.errors import InvalidMeshError

__all__ = ["Mesh", "HamiltonianMesh", "KIND_NAMES", "cycle_positions", "triangle_neighbors",
           "output_vertex_markers", "attribute_name"]

#: Meaning of :attr:`HamiltonianMesh.kind`: how each output triangle was made.
#: 0: an input triangle's side joined to its incenter; 1: a flipped triangle
#: (two incenters, one input vertex); 2: a triangle at an edge midpoint (a split
#: constrained edge; in ``mode="sparse"`` also a free edge split to join two cycles);
#: 3: an input triangle kept whole, 4: one of two input triangles whose shared edge
#: was flipped without Steiner point (3 and 4 only in ``mode="sparse"``).
KIND_NAMES: tuple[str, ...] = ("incenter", "flip", "midpoint", "input", "swap")


def _coerce(obj: Any, name: str) -> None:
    """Store ``obj.name`` as a numpy array (lists accepted), or raise
    :class:`~hammesh.errors.InvalidMeshError` if it is not numbers.  Shapes and index
    ranges are checked by the algorithms and writers that use the field (they name the
    item at fault)."""
    value = getattr(obj, name)
    if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
        return
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise InvalidMeshError(f"{name} must be an array of numbers ({exc})") from None
    if arr.size and arr.dtype.kind not in "biuf":
        raise InvalidMeshError(f"{name} must be an array of numbers, got dtype {arr.dtype}")
    object.__setattr__(obj, name, arr)


def _empty_i(shape: tuple[int, ...]) -> np.ndarray:
    return np.zeros(shape, dtype=np.int64)


def attribute_name(names: tuple[str, ...], i: int) -> str:
    """Name of column ``i`` of ``triangle_attributes``: ``names[i]`` if given, else
    ``attribute_<i>`` (Triangle's regional attributes have no names).

    >>> attribute_name(("region",), 0), attribute_name((), 1)
    ('region', 'attribute_1')
    """
    return names[i] if i < len(names) and names[i] else f"attribute_{i}"


def _fit_names(obj: Any) -> None:
    """``obj.attribute_names`` as a tuple of str, one per attribute column or empty."""
    names = tuple(str(x) for x in (obj.attribute_names or ()))
    k = obj.triangle_attributes.shape[1] if np.ndim(obj.triangle_attributes) == 2 else 0
    object.__setattr__(obj, "attribute_names", names if len(names) == k else ())


def _fit_point_data(obj: Any) -> None:
    """``obj.point_data`` as a dict of numeric arrays with one row per point; anything
    else raises :class:`~hammesh.errors.InvalidMeshError` (a caller's bug, never
    silently dropped)."""
    data = obj.point_data
    if data is None:
        object.__setattr__(obj, "point_data", {})
        return
    if not isinstance(data, dict):
        raise InvalidMeshError(f"point_data must be a dict of arrays, got {type(data).__name__}")
    n = len(obj.points)
    fitted = {}
    for name, values in data.items():
        arr = np.asarray(values)
        if arr.ndim not in (1, 2) or len(arr) != n or arr.dtype.kind not in "biuf":
            raise InvalidMeshError(
                f"point_data[{name!r}] must be numbers with one row per point ({n}), got shape "
                f"{arr.shape} dtype {arr.dtype}"
            )
        fitted[str(name)] = arr
    object.__setattr__(obj, "point_data", fitted)


@dataclass(frozen=True, eq=False)
class Mesh:
    """A planar triangle mesh with constrained edges.

    Attributes
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64, counter-clockwise
    segments : (s, 2) int64
        Constrained edges (input segments, subdivided by the mesher). Never flipped.
    segment_markers : (s,) int64
        Boundary marker of each constrained edge (Triangle's convention; 0 if unknown).
    triangle_attributes : (m, k) float64
        Regional attributes (``k`` may be 0).
    neighbors : (m, 3) int64 or None
        See the module docstring; ``None`` means "compute when needed"
        (:func:`triangle_neighbors`).
    info : dict
        Provenance: backend, switches, meshing seconds (``quality_mesh`` fills it).
        ``info["rows_local"] = True`` says the rows are already numbered so that
        neighbours lie near each other in memory (``hammesh.parallel``'s lattice
        tiles): sparse mode then skips its renumbering for locality
        (:func:`hammesh.postprocess.sparse.renumbers`).
    vertex_markers : (n,) int64
        Boundary marker of each point (Triangle's ``pointmarkers``; zeros if unknown).
    attribute_names : tuple of str
        Name of each ``triangle_attributes`` column (a mesh file's cell data names);
        empty: ``attribute_<i>`` (:func:`attribute_name`).
    point_data : dict of str to (n,) or (n, c) arrays
        Per-point values read from a mesh file (other than ``vertex_marker``), carried
        to the output: input points keep theirs, new points are interpolated
        (:func:`hammesh.point_data.carry_point_data`).
    """

    points: np.ndarray
    triangles: np.ndarray
    segments: np.ndarray = field(default_factory=lambda: _empty_i((0, 2)))
    segment_markers: np.ndarray = field(default_factory=lambda: _empty_i((0,)))
    triangle_attributes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    neighbors: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)
    vertex_markers: np.ndarray = field(default_factory=lambda: _empty_i((0,)))
    attribute_names: tuple[str, ...] = ()
    point_data: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("points", "triangles", "segments", "segment_markers", "triangle_attributes",
                     "vertex_markers"):
            _coerce(self, name)
        if self.neighbors is not None:
            _coerce(self, "neighbors")
        if not isinstance(self.info, dict):
            raise InvalidMeshError(f"info must be a dict, got {type(self.info).__name__}")
        m = len(self.triangles)
        attrs = self.triangle_attributes
        if attrs.ndim == 1 and len(attrs) == m and m:  # (one column given flat)
            object.__setattr__(self, "triangle_attributes", attrs.reshape(m, 1))
        elif attrs.size == 0 or (attrs.ndim == 2 and attrs.shape[0] == m == 0):
            object.__setattr__(self, "triangle_attributes", np.zeros((m, 0), dtype=np.float64))
        elif attrs.ndim != 2 or attrs.shape[0] != m:  # (given data is never dropped in silence)
            raise InvalidMeshError(f"triangle_attributes has shape {attrs.shape}: must be (m, k) with one row "
                                   f"per triangle (m = {m})")
        if self.segment_markers.size == 0:
            object.__setattr__(self, "segment_markers", np.zeros(len(self.segments), dtype=np.int64))
        elif len(self.segment_markers) != len(self.segments):
            raise InvalidMeshError(f"{len(self.segment_markers)} segment_markers for {len(self.segments)} segments")
        _fit_vertex_markers(self)
        _fit_names(self)
        _fit_point_data(self)

    @property
    def n_points(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[0])


def _fit_vertex_markers(obj: Any) -> None:
    """``obj.vertex_markers`` as ``(n,) int64``: zeros if missing (empty); the error if of
    another length (given data is never dropped in silence)."""
    n = len(obj.points)
    markers = obj.vertex_markers
    if markers is None or np.size(markers) == 0:
        object.__setattr__(obj, "vertex_markers", np.zeros(n, dtype=np.int64))
    elif np.shape(markers) != (n,):
        raise InvalidMeshError(f"vertex_markers has shape {np.shape(markers)}: must be one per point (n = {n})")
    elif markers.dtype != np.int64:
        object.__setattr__(obj, "vertex_markers", np.asarray(markers).astype(np.int64))


@dataclass(frozen=True, eq=False)
class HamiltonianMesh:
    """A triangle mesh whose triangles are stored in Hamiltonian-cycle order.

    The triangles form ``len(components)`` cycles, stored as consecutive runs of
    rows: run ``c`` has ``components[c]`` triangles, consecutive rows of a run share
    an edge and so do its last and first rows.

    Attributes
    ----------
    points : (n, 2) float64
        The input mesh's points first (same indices), then the Steiner points.
    triangles : (m, 3) int64, counter-clockwise, in cycle order.
    segments : (s, 2) int64
        Constrained edges of the output (input segments, split at inserted midpoints).
    segment_markers : (s,) int64
    components : (c,) int64
        Run lengths of the cycles; they sum to ``m``.
    position : (m,) int64
        Position of each triangle inside its cycle (0 at each run's start).
    parent : (m,) int64
        Input triangle each output triangle lies in (a flip triangle: the first of its two).
    kind : (m,) int8
        Index into :data:`KIND_NAMES`.
    triangle_attributes : (m, k) float64
        Regional attributes inherited from ``parent``.
    report : dict
        Counts, angles, timings and the verification verdict (see ``docs/report.md``).
    vertex_markers : (n,) int64
        The input's point markers at their indices; a Steiner point on a constrained
        edge gets the edge's marker, any other Steiner point 0
        (:func:`output_vertex_markers`).
    attribute_names : tuple of str
        Names of the ``triangle_attributes`` columns (see :class:`Mesh`).
    point_data : dict of str to (n,) or (n, c) arrays
        The input's per-point values; Steiner points interpolated (see :class:`Mesh`).
    neighbors : (m, 3) int64
        Computed on first use (:func:`triangle_neighbors`), then kept.
    """

    points: np.ndarray
    triangles: np.ndarray
    segments: np.ndarray
    segment_markers: np.ndarray
    components: np.ndarray
    position: np.ndarray
    parent: np.ndarray
    kind: np.ndarray
    triangle_attributes: np.ndarray
    report: dict[str, Any] = field(default_factory=dict)
    vertex_markers: np.ndarray | None = None
    attribute_names: tuple[str, ...] = ()
    point_data: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.vertex_markers is not None:
            _coerce(self, "vertex_markers")
        _fit_vertex_markers(self)
        _fit_names(self)
        _fit_point_data(self)

    @property
    def n_points(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[0])

    @cached_property
    def neighbors(self) -> np.ndarray:
        """``(m, 3) int64``: ``neighbors[t, k]`` is the triangle across edge
        ``(triangles[t, k], triangles[t, (k + 1) % 3])``, -1 on the boundary (and across a
        constrained edge only if it is on the boundary).  Computed on first use."""
        return triangle_neighbors(self.triangles, self.n_points)

    @classmethod
    def from_order(cls, points: np.ndarray, triangles: np.ndarray, report: dict[str, Any] | None = None) -> HamiltonianMesh:
        """One run of triangles in dual-path order, as made by a point-set or polygon
        construction (no parent mesh: ``parent = -1``, ``kind = 0``)."""
        points = np.asarray(points, dtype=np.float64)
        triangles = np.asarray(triangles, dtype=np.int64)
        m = len(triangles)
        return cls(
            points=points,
            triangles=triangles,
            segments=np.zeros((0, 2), dtype=np.int64),
            segment_markers=np.zeros(0, dtype=np.int64),
            components=np.array([m], dtype=np.int64),
            position=np.arange(m, dtype=np.int64),
            parent=np.full(m, -1, dtype=np.int64),
            kind=np.zeros(m, dtype=np.int8),
            triangle_attributes=np.zeros((m, 0)),
            report=dict(report or {}),
        )

    def as_mesh(self) -> Mesh:
        """The output as a plain :class:`Mesh` (cycle order kept, cycle metadata dropped)."""
        return Mesh(
            points=self.points,
            triangles=self.triangles,
            segments=self.segments,
            segment_markers=self.segment_markers,
            triangle_attributes=self.triangle_attributes,
            vertex_markers=self.vertex_markers,
            attribute_names=self.attribute_names,
            point_data=self.point_data,
        )


def cycle_positions(components: np.ndarray) -> np.ndarray:
    """Position of every row inside its cycle, for run lengths ``components``.

    >>> cycle_positions(np.array([3, 2])).tolist()
    [0, 1, 2, 0, 1]
    """
    runs = np.asarray(components, dtype=np.int64)
    if len(runs) == 1:
        return np.arange(int(runs[0]), dtype=np.int64)
    return np.arange(int(runs.sum()), dtype=np.int64) - np.repeat(np.cumsum(runs) - runs, runs)


def triangle_neighbors(triangles: np.ndarray, n_points: int | None = None) -> np.ndarray:
    """The neighbour array of a consistently oriented, edge-manifold triangle array.

    Parameters
    ----------
    triangles : (m, 3) int
    n_points : int, optional
        Number of points (default: ``triangles.max() + 1``).

    Returns
    -------
    (m, 3) int64
        ``[t, k]``: the triangle across edge ``(triangles[t, k], triangles[t, (k+1) % 3])``,
        -1 on the boundary (see the module docstring).

    Raises
    ------
    InvalidMeshError
        An edge is shared by three triangles or by two in the same direction.

    Examples
    --------
    >>> triangle_neighbors(np.array([[0, 1, 2], [2, 1, 3]])).tolist()
    [[-1, 1, -1], [0, -1, -1]]
    """
    from hammesh.halfedge import half_edges  # halfedge imports this module

    tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    if n_points is None:
        n_points = int(tri.max()) + 1 if tri.size else 0
    twin = half_edges(tri, int(n_points)).twin
    return np.where(twin >= 0, twin // 3, -1).reshape(-1, 3)


def output_vertex_markers(
    input_markers: np.ndarray, n_points: int, segments: np.ndarray, segment_markers: np.ndarray
) -> np.ndarray:
    """Point markers of a post-processed mesh whose first points are the input's.

    The input's ``input_markers`` stay at their indices; a new point that is an end of
    a constrained edge (a split edge's midpoint) gets that edge's marker, as Triangle
    marks the points it inserts on a segment; other new points get 0.

    >>> output_vertex_markers(np.array([1, 1]), 4, np.array([[0, 2], [2, 1]]), np.array([7, 7])).tolist()
    [1, 1, 7, 0]
    """
    markers = np.zeros(int(n_points), dtype=np.int64)
    given = np.asarray(input_markers, dtype=np.int64).reshape(-1)[: int(n_points)]
    markers[: len(given)] = given
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    mk = np.asarray(segment_markers, dtype=np.int64).reshape(-1)
    if len(mk) == len(seg):
        for end in (0, 1):
            new = seg[:, end] >= len(given)
            markers[seg[new, end]] = mk[new]
    return markers
