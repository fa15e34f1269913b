"""The input domain: a planar straight-line graph (PSLG) as plain numpy arrays.

A :class:`Domain` is what Triangle's ``-p`` switch consumes: vertices, constrained
segments, hole points and regional attributes / area limits.  It is checked on
construction (:func:`~hammesh.domain.validate.check_fields`), and what Triangle would
repair itself (duplicate vertices, T-junctions, overlapping or crossing segments) is
repaired and recorded in ``Domain.repairs``
(:func:`~hammesh.domain.repair.repair_graph`), or refused with ``strict=True``.  Its
arrays are read-only copies, so an invalid Domain can never exist.
"""

from __future__ import annotations

from dataclasses import InitVar, dataclass, field

import numpy as np

from hammesh.domain.repair import Repair, drop_outside_holes, refuse_points_on_segments, repair_graph
from hammesh.domain.validate import check_fields, point_array, refuse_complex
from hammesh.errors import InvalidDomainError

__all__ = ["Domain"]


def _empty(ncols, dtype):
    return lambda: np.zeros((0, ncols), dtype)


@dataclass(frozen=True, eq=False)
class Domain:
    """A validated planar straight-line graph.

    Parameters
    ----------
    vertices : (n, 2) float64
        Vertex coordinates, zero-based indices into this array are used by ``segments``.
    segments : (s, 2) int64, optional
        Constrained edges (vertex index pairs).  Empty: Triangle meshes the convex hull.
    holes : (h, 2) float64, optional
        One point strictly inside each hole.
    regions : (r, 4) float64, optional
        Columns x, y, attribute, max_area; max_area NaN means no regional area limit.
    segment_markers : (s,) int64, optional
        Boundary markers of the segments; default ones (Triangle's "boundary").
    vertex_markers : (n,) int64, optional
        Boundary markers of the vertices; default zeros.
    vertex_attributes : (n, k) float64, optional
        Triangle's vertex attributes (a ``.node`` file's columns after x and y): the
        mesher interpolates them at the points it inserts; the mesh has them as
        ``point_data["attribute_<j>"]``.  Default ``(n, 0)``.  A vertex a repair adds
        (a crossing) gets them interpolated along a crossing segment.

    strict : bool, optional
        Refuse (raise) instead of repairing duplicate vertices, zero-length or repeated
        segments, vertices inside segments, overlapping or crossing segments.

    Attributes
    ----------
    repairs : tuple of Repair
        What was repaired (:mod:`hammesh.domain.repair`), empty if nothing; the stored
        arrays are those of the repaired graph (kept vertices at their index, minus
        dropped duplicates before them; new crossing vertices appended).
        ``dataclasses.replace`` re-checks the stored, already repaired arrays: the
        copy's ``repairs`` is empty.

    Any array-like (nested lists) is accepted and copied to the dtypes above; the
    stored arrays are read-only.  Raises :class:`~hammesh.errors.InvalidDomainError`
    if the graph is invalid (see :func:`~hammesh.domain.validate.check_fields`) or,
    with ``strict``, defective.

    Examples
    --------
    >>> d = Domain([[0, 0], [1, 0], [0, 1]], [[0, 1], [1, 2], [2, 0]])
    >>> d.segments.dtype, d.segment_markers.tolist()
    (dtype('int64'), [1, 1, 1])
    >>> t = Domain([[0, 0], [2, 0], [0, 2], [1, 0]], [[0, 1], [1, 2], [2, 0]])
    >>> [r.kind for r in t.repairs], t.segments.tolist()
    (['vertex_on_segment'], [[0, 3], [3, 1], [1, 2], [2, 0]])
    """

    vertices: np.ndarray
    segments: np.ndarray = field(default_factory=_empty(2, np.int64))
    holes: np.ndarray = field(default_factory=_empty(2, np.float64))
    regions: np.ndarray = field(default_factory=_empty(4, np.float64))
    segment_markers: np.ndarray | None = None
    vertex_markers: np.ndarray | None = None
    vertex_attributes: np.ndarray | None = None
    strict: InitVar[bool] = False
    repairs: tuple[Repair, ...] = field(default=(), init=False)

    def __post_init__(self, strict: bool = False):
        vertices = _as_float(self.vertices, "vertices", 2)
        segments = _as_int(self.segments, "segments", 2)
        holes = _as_float(self.holes, "holes", 2)
        regions = _as_float(self.regions, "regions", 4)
        if self.segment_markers is None:
            segment_markers = np.ones(len(segments), np.int64)
        else:
            segment_markers = _as_int(self.segment_markers, "segment_markers", None)
        if self.vertex_markers is None:
            vertex_markers = np.zeros(len(vertices), np.int64)
        else:
            vertex_markers = _as_int(self.vertex_markers, "vertex_markers", None)
        for name, marks in (("segment_markers", segment_markers), ("vertex_markers", vertex_markers)):
            if len(marks) and (marks.min() < -2**31 or marks.max() >= 2**31):  # issue 12 #4
                raise InvalidDomainError(f"{name}: {int(marks[np.argmax(np.abs(marks))])} does not fit "
                                         "the 32-bit markers of Triangle and Gmsh")
        attributes = _vertex_attributes(self.vertex_attributes, len(vertices))
        values = dict(vertices=vertices, segments=segments, holes=holes, regions=regions,
                      segment_markers=segment_markers, vertex_markers=vertex_markers,
                      vertex_attributes=attributes)
        for name, value in values.items():
            object.__setattr__(self, name, value)
        check_fields(self)
        graph = repair_graph(vertices, segments, segment_markers, vertex_markers,
                             strict=bool(strict))
        if graph.repairs and attributes.shape[1]:
            attributes = carry_vertex_attributes(vertices, segments, attributes, graph.vertices)
        holes, dropped = drop_outside_holes(graph.vertices, holes, bool(strict))
        refuse_points_on_segments(graph.vertices, graph.segments, holes, regions)
        values.update(vertices=graph.vertices, segments=graph.segments,
                      segment_markers=graph.segment_markers, vertex_markers=graph.vertex_markers,
                      vertex_attributes=attributes, holes=holes)
        for name, value in values.items():
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "repairs", tuple(graph.repairs) + dropped)

    def __repr__(self) -> str:
        fixed = f", {len(self.repairs)} repairs" if self.repairs else ""
        return (f"Domain({len(self.vertices)} vertices, {len(self.segments)} segments, "
                f"{len(self.holes)} holes, {len(self.regions)} regions{fixed})")

    @classmethod
    def from_polygon(cls, outer, holes=(), *, internal_segments=None, ring_markers=None,
                     internal_markers=None, strict: bool = False) -> "Domain":
        """Build a domain from an outer ring, hole rings and internal polylines.

        Parameters
        ----------
        outer : (k, 2) array-like
            Outer boundary ring, either orientation, not closed (a repeated first
            point at the end is dropped).
        holes : sequence of (k_i, 2) array-like
            Hole rings, same conventions; each must lie inside ``outer`` and not inside
            another hole.  A hole point strictly inside each ring is computed.
        internal_segments : sequence of (m_j, 2) array-like, optional
            Open polylines of constrained segments (cracks, internal loops).  A point
            exactly equal to an existing vertex reuses it, so a polyline may start on
            the boundary, and repeating its first point closes it into a loop.
        ring_markers : sequence, optional
            One entry per ring, the outer ring first, then the holes: an int (the
            marker of every side of the ring) or a sequence of ``k_i`` ints (side ``j``
            runs from ring point ``j`` to ``j + 1``).  Default: 1 everywhere.  A ring
            point gets the marker of the side leaving it.
        internal_markers : sequence, optional
            One entry per internal polyline: an int or one int per segment.  Default 0
            (new polyline points get vertex marker 0, so Triangle gives the points
            it meshes on a polyline the polyline's marker).
        strict : bool
            Refuse instead of repairing internal polylines that cross, overlap or
            touch (see :class:`Domain`). The rings themselves are never repaired: they
            must be simple and disjoint.

        Returns
        -------
        Domain
            Vertices in order outer ring, hole rings, new polyline points; segments in
            order ring sides (ring by ring), then polyline segments.

        Raises
        ------
        InvalidDomainError
            A marker entry that is neither an int nor one int per side.

        Examples
        --------
        >>> d = Domain.from_polygon([[0, 0], [4, 0], [4, 4], [0, 4]],
        ...                         [[[1, 1], [2, 1], [2, 2], [1, 2]]])
        >>> bool(1 < d.holes[0, 0] < 2 and 1 < d.holes[0, 1] < 2)
        True
        >>> d = Domain.from_polygon([[0, 0], [4, 0], [4, 4], [0, 4]], ring_markers=[[1, 2, 2, 2]])
        >>> d.segment_markers.tolist(), d.vertex_markers.tolist()
        ([1, 2, 2, 2], [1, 2, 2, 2])
        """
        rings = [_ring(outer, "outer ring")]
        rings += [_ring(h, f"hole ring {i}") for i, h in enumerate(holes)]
        vertices, segments, starts = [], [], []
        for ring in rings:
            base = sum(len(r) for r in vertices)
            k = len(ring)
            starts.append(base)
            vertices.append(ring)
            idx = base + np.arange(k)
            segments.append(np.stack([idx, np.roll(idx, -1)], axis=1))
        nb = sum(len(r) for r in vertices)
        ring_sides = _side_markers(ring_markers, [len(r) for r in rings], "ring_markers", 1)
        vmarks = [np.concatenate(ring_sides)]  # a ring point: the side leaving it
        smarks = [np.concatenate(ring_sides)]
        # the rings must be simple and disjoint (hole points, nesting): never repaired
        repair_graph(np.concatenate(vertices), np.concatenate(segments), smarks[0], vmarks[0],
                     strict=True)

        if internal_segments is None and internal_markers is not None:
            raise InvalidDomainError("internal_markers given without internal_segments")
        if internal_segments is not None:
            internal_segments = list(internal_segments)
            lookup = {}
            for i, p in enumerate(np.concatenate(vertices)):
                lookup.setdefault((float(p[0]), float(p[1])), i)
            extra = []
            for j, line in enumerate(internal_segments):
                pts = point_array(line, f"internal polyline {j}")
                if len(pts) < 2:
                    raise InvalidDomainError(
                        f"internal polyline {j} needs at least 2 points, got {len(pts)}")
                idx = []
                for p in pts:
                    key = (float(p[0]), float(p[1]))
                    if key not in lookup:
                        lookup[key] = nb + len(extra)
                        extra.append(p)
                    idx.append(lookup[key])
                idx = np.asarray(idx, np.int64)
                segments.append(np.stack([idx[:-1], idx[1:]], axis=1))
                smarks.append(np.zeros(len(idx) - 1, np.int64))
            counts = [len(sm) for sm in smarks[1:]]
            smarks[1:] = _side_markers(internal_markers, counts, "internal_markers", 0)
            if extra:
                vertices.append(np.asarray(extra, np.float64))
                vmarks.append(np.zeros(len(extra), np.int64))

        kw = dict(vertices=np.concatenate(vertices), segments=np.concatenate(segments),
                  segment_markers=np.concatenate(smarks), vertex_markers=np.concatenate(vmarks))
        graph = cls(**kw, strict=strict)  # checks rings and polylines before Triangle runs
        _check_nesting(rings)
        hole_points = [_interior_point(r) for r in rings[1:]]
        return cls(**kw, holes=np.asarray(hole_points, np.float64).reshape(-1, 2),
                   strict=strict) if hole_points else graph


# ----------------------------------------------------------------------------- conversion

def _vertex_attributes(value, n: int) -> np.ndarray:
    """``(n, k) float64`` vertex attributes (``(n, 0)`` for None)."""
    if value is None:
        return np.zeros((n, 0), np.float64)
    refuse_complex(value, "vertex_attributes")
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidDomainError(f"vertex_attributes must be numbers ({exc})") from None
    if arr.ndim == 1 and len(arr) == n:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != n:
        raise InvalidDomainError(f"vertex_attributes must have shape ({n}, k), got {arr.shape}")
    return arr  # (data, not geometry: NaN is carried as NaN, as Triangle does)


def carry_vertex_attributes(vertices: np.ndarray, segments: np.ndarray, attributes: np.ndarray,
                            repaired: np.ndarray) -> np.ndarray:
    """Vertex attributes of a repaired graph's vertices.

    A kept vertex has its own (a merged duplicate: the first's); a crossing vertex the
    repair added gets them interpolated linearly along the original segment it lies
    nearest to (it lies on two of them; Triangle would interpolate the same way along
    the segment it splits).

    >>> carry_vertex_attributes(np.array([[0., 0], [2, 0], [1, -1], [1, 1]]),
    ...                         np.array([[0, 1], [2, 3]]), np.array([[0.], [4], [0], [0]]),
    ...                         np.array([[0., 0], [2, 0], [1, -1], [1, 1], [1, 0]])).ravel().tolist()
    [0.0, 4.0, 0.0, 0.0, 2.0]
    """
    lookup: dict[tuple[float, float], int] = {}
    for i, p in enumerate(np.asarray(vertices).tolist()):
        lookup.setdefault((p[0], p[1]), i)
    out = np.empty((len(repaired), attributes.shape[1]), np.float64)
    new = []
    for i, p in enumerate(np.asarray(repaired).tolist()):
        j = lookup.get((p[0], p[1]))
        if j is None:
            new.append(i)
        else:
            out[i] = attributes[j]
    if new:
        a, b = vertices[segments[:, 0]], vertices[segments[:, 1]]
        d = b - a
        length2 = np.maximum((d * d).sum(axis=1), np.finfo(float).tiny)
        for i in new:  # (crossings: few)
            t = np.clip(((repaired[i] - a) * d).sum(axis=1) / length2, 0.0, 1.0)
            gap = np.hypot(*(a + t[:, None] * d - repaired[i]).T)
            k = int(np.argmin(gap))
            out[i] = (1 - t[k]) * attributes[segments[k, 0]] + t[k] * attributes[segments[k, 1]]
    return out


def _side_markers(markers, sides, name, default):
    """One ``(sides[i],) int64`` array per ring / polyline from ``markers`` (see
    :meth:`Domain.from_polygon`): None gives ``default``; an entry is an int or one int
    per side."""
    if markers is None:
        return [np.full(k, default, np.int64) for k in sides]
    if isinstance(markers, (str, bytes)) or not hasattr(markers, "__len__"):
        raise InvalidDomainError(f"{name} must be a sequence with one entry per "
                                 f"{'ring' if name == 'ring_markers' else 'polyline'}, got {markers!r}")
    markers = list(markers)
    if len(markers) != len(sides):
        raise InvalidDomainError(f"{name} has {len(markers)} entries, expected {len(sides)}")
    out = []
    for i, (entry, k) in enumerate(zip(markers, sides)):
        if np.isscalar(entry) or (isinstance(entry, np.ndarray) and entry.ndim == 0):
            arr = _as_int([entry], f"{name}[{i}]", None)
            arr = np.full(k, arr[0], np.int64)
        else:
            arr = _as_int(entry, f"{name}[{i}]", None)
            if arr.shape != (k,):
                raise InvalidDomainError(
                    f"{name}[{i}] has shape {np.shape(entry)}, expected an int or {k} ints (one per side)")
        out.append(arr)
    return out


def _as_float(value, name, ncols):
    if value is None:  # "none of these" (holes=None, regions=None)
        return np.zeros((0, ncols), np.float64)
    refuse_complex(value, name)
    try:
        arr = np.array(value, dtype=np.float64)  # always a copy
    except (TypeError, ValueError) as exc:
        raise InvalidDomainError(f"{name} cannot be converted to float64: {exc}") from None
    if arr.size == 0:
        arr = arr.reshape(0, ncols)
    return arr


def _as_int(value, name, ncols):
    if value is None:
        return np.zeros((0, ncols) if ncols else (0,), np.int64)
    try:
        arr = np.array(value)
    except (TypeError, ValueError) as exc:
        raise InvalidDomainError(f"{name} cannot be converted to int64: {exc}") from None
    if arr.size == 0:
        return np.zeros((0, ncols) if ncols else (0,), np.int64)
    if arr.dtype.kind in "iu":
        if arr.dtype.kind == "u" and arr.max() > np.iinfo(np.int64).max:
            raise InvalidDomainError(f"{name} has a value too large for int64")
        return arr.astype(np.int64)
    if arr.dtype.kind == "f":
        bad = ~np.isfinite(arr) | (arr != np.round(arr))
        if bad.any():
            pos = tuple(int(x) for x in np.argwhere(bad)[0])
            raise InvalidDomainError(
                f"{name}{list(pos)} is {float(arr[pos])!r}, not an integer")
        return arr.astype(np.int64)
    raise InvalidDomainError(f"{name} must hold integers, got dtype {arr.dtype}")


def _ring(value, what):
    ring = point_array(value, what)
    if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    if len(ring) < 3:
        raise InvalidDomainError(f"{what} needs at least 3 distinct points, got {len(ring)}")
    return ring


# ----------------------------------------------------------------------------- geometry

def _point_in_ring(points, ring):
    """Even-odd test; ``points (m, 2)``; points on the ring give an arbitrary answer."""
    points = np.atleast_2d(points)
    x, y = points[:, 0:1], points[:, 1:2]
    a, b = ring, np.roll(ring, -1, axis=0)
    ax, ay, bx, by = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    straddle = (ay > y) != (by > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xcross = ax + (y - ay) * (bx - ax) / (by - ay)
    return (straddle & (x < xcross)).sum(axis=1) % 2 == 1


def _check_nesting(rings):
    """Each hole ring inside the outer ring and not inside another hole ring.

    The rings are already known not to cross or touch, so one vertex per ring decides.
    """
    outer, holes = rings[0], rings[1:]
    if not holes:
        return
    probes = np.array([h[0] for h in holes])
    inside = _point_in_ring(probes, outer)
    if not inside.all():
        i = int(np.flatnonzero(~inside)[0])
        raise InvalidDomainError(f"hole ring {i} is not inside the outer ring")
    for j, ring in enumerate(holes):
        nested = _point_in_ring(probes, ring)
        nested[j] = False
        if nested.any():
            i = int(np.flatnonzero(nested)[0])
            raise InvalidDomainError(f"hole ring {i} lies inside hole ring {j}")


def _interior_point(ring):
    """A point strictly inside a simple polygon: centroid of its largest triangle."""
    import triangle

    k = len(ring)
    idx = np.arange(k)
    tri = triangle.triangulate(
        {"vertices": ring, "segments": np.stack([idx, np.roll(idx, -1)], axis=1)}, "pQ")
    t = tri["vertices"][tri["triangles"]]
    area = np.abs((t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1])
                  - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0]))
    return t[np.argmax(area)].mean(axis=0)
