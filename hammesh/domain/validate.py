"""Validation of a planar straight-line graph before it reaches Triangle.

Triangle (a C library) trusts its input: out-of-range indices, NaN or huge
coordinates make it loop or crash the interpreter with SIGSEGV.  :func:`check_fields`
checks those preconditions in numpy first and raises
:class:`~hammesh.errors.InvalidDomainError` with a one-line message naming the
offending field, index or point.

Geometric defects that Triangle itself repairs (duplicate vertices, a vertex inside a
segment, overlapping or crossing segments) are repaired, and reported, by
:mod:`hammesh.domain.repair` with exact predicates; :func:`validate_domain` refuses
them instead (strict). Both decide with a Shamos-Hoey sweep
(:mod:`hammesh.domain.intersections`): ``O((n + s) log(n + s))`` whatever the shape,
so a vertex of degree 10^4 or 2*10^4 long parallel segments take well under a
second (the old tolerance-based grid took 93 s and 122 s on those).
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidDomainError

__all__ = ["validate_domain", "check_fields", "point_array", "refuse_complex", "check_extent", "column_ranges", "holes_in_hull", "holes_inside_hull", "HULL_TOLERANCE", "MAX_ABS_COORDINATE", "MIN_EXTENT"]

#: Beyond this magnitude Triangle's floating-point predicates overflow.
MAX_ABS_COORDINATE = 1e30
#: Below this extent (largest coordinate difference) Triangle's and the certificate's
#: products underflow: a 1e-90 square fails in Triangle, a 1e-120 one in the certificate.
MIN_EXTENT = 1e-60
_XY = ("x coordinate", "y coordinate")


def column_ranges(points: np.ndarray) -> tuple[list[float], list[float]]:
    """Each coordinate's smallest and largest value of ``(n, d)`` points (``n > 0``), by
    1-D reductions over the column views: numpy's ``points.min(axis=0)`` over an
    ``(n, 2)`` array runs an inner loop of 2 per row, ~35x slower (82 ms against 2.3 ms
    for 0.77 M points, on the main thread of every ``hamiltonian()`` and ``hammesh
    check``)."""
    cols = np.asarray(points, dtype=np.float64).reshape(len(points), -1)
    return ([float(cols[:, j].min()) for j in range(cols.shape[1])],
            [float(cols[:, j].max()) for j in range(cols.shape[1])])


def check_extent(points: np.ndarray, error: type[Exception], what: str = "the mesh",
                 ranges: tuple[list[float], list[float]] | None = None) -> None:
    """Refuse points spanning less than :data:`MIN_EXTENT` (and more than nothing): their
    areas and angles underflow float64 in Triangle and in the certificate.

    ``error``: the exception class to raise (``InvalidDomainError``, ``InvalidMeshError``).
    ``ranges``: the points' :func:`column_ranges`, if the caller has them.
    """
    if len(points) == 0:
        return
    lo, hi = column_ranges(points) if ranges is None else ranges
    extent = max((b - a for a, b in zip(lo, hi)), default=0.0)
    if 0 < extent < MIN_EXTENT:
        raise error(f"{what} spans only {extent:.3g}: below {MIN_EXTENT:g} areas and angles underflow float64 "
                    "(rescale it; the mesh does not change)")


#: a hole point is given to Triangle unless it lies farther than this times the
#: input's extent outside the convex hull of the input's points (:func:`holes_in_hull`)
HULL_TOLERANCE = 1e-12


def holes_in_hull(vertices: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """The hole points (``(h, 2)``) that lie in the convex hull of ``vertices`` (or
    within :data:`HULL_TOLERANCE` of the extent outside it): the only ones Triangle may
    be given.

    Why (in a tile, where session 18 found it): a tile takes every domain hole whose point lies in its box
    (``tiles._make_tiles``), and the tile's own piece of the domain need not surround
    it. Triangle's ``carveholes`` skips a hole point outside the input's bounding box
    only, then ``locate``s it, which assumes a point inside the triangulation: from a
    hull triangle it may step across the hull into Triangle's outer "dummy" triangle,
    whose corners are NULL, and read them (SIGSEGV in ``preciselocate``, every run,
    any heap: one band input in ~5,000 examples of the random-domain test's generator,
    session 18; very likely the interpreter crash of sessions 16-17, the same call on
    input the guard does not flag). A point
    outside the hull is in no triangle Triangle makes, so dropping it changes nothing
    (49 such inputs of that generator: the same mesh without it in 42; in the other 7
    it was the only hole, and an empty hole array made the wrapper fail, hence
    callers leave the key out then).
    """
    h = np.asarray(holes, dtype=np.float64).reshape(-1, 2)
    return h[holes_inside_hull(vertices, h)]


def holes_inside_hull(vertices: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """``(h,) bool``: which hole points :func:`holes_in_hull` keeps."""
    h = np.asarray(holes, dtype=np.float64).reshape(-1, 2)
    v = np.asarray(vertices, dtype=np.float64)
    keep = np.ones(len(h), dtype=bool)
    if len(h) == 0 or len(v) < 3:
        return keep
    from scipy.spatial import ConvexHull
    from scipy.spatial import QhullError

    try:
        hull = ConvexHull(v)
    except QhullError:  # (all points on a line: Triangle fails on the input anyway)
        return keep
    extent = max(float(np.ptp(v, axis=0).max()), float(np.abs(v).max()))
    # (qhull's facets: unit outward normal n and offset c, n . x + c <= 0 inside)
    outside = h @ hull.equations[:, :2].T + hull.equations[:, 2]
    return (outside <= HULL_TOLERANCE * extent).all(axis=1)


def refuse_complex(value, what: str) -> None:
    """Refuse complex numbers, which numpy would cast to their real part (ComplexWarning).

    Raises
    ------
    InvalidDomainError
        Naming ``what``.
    """
    kind = value.dtype.kind if isinstance(value, np.ndarray) else None
    if kind is None and not isinstance(value, (str, bytes)):
        try:
            kind = np.asarray(value).dtype.kind
        except (TypeError, ValueError):  # (ragged: the caller's conversion names it)
            return
    if kind == "c":
        raise InvalidDomainError(f"{what} are complex numbers; give real x and y columns")


def point_array(value, what: str, rows: str = "k") -> np.ndarray:
    """``value`` as a new ``(k, 2) float64`` array, or an error naming ``what``.

    ``rows`` is how the message names the row count (``"n"`` for a point set).

    Raises
    ------
    InvalidDomainError
        Not numbers (complex numbers too), or not of shape ``(k, 2)``.
    """
    refuse_complex(value, what)
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidDomainError(f"{what} cannot be converted to float64: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidDomainError(f"{what} must have shape ({rows}, 2), got {arr.shape}")
    return arr


def validate_domain(domain) -> None:
    """Check that ``domain`` is a proper planar straight-line graph (strict: no repairs).

    :func:`check_fields`, then the geometric checks of
    :func:`~hammesh.domain.repair.repair_graph` with ``strict=True`` (exact predicates):
    no duplicate vertices, no zero-length or repeated segments, segments meeting only
    at shared endpoints, no vertex inside a segment.

    Parameters
    ----------
    domain : Domain or any object with the attributes
        ``vertices (n, 2) float64``, ``segments (s, 2) int64``, ``holes (h, 2) float64``,
        ``regions (r, 4) float64`` (x, y, attribute, max_area with NaN = no limit),
        ``segment_markers (s,) int64`` and ``vertex_markers (n,) int64``.

    Raises
    ------
    InvalidDomainError
        On the first problem found, in this order: field shapes and dtypes; non-finite
        or too large (> 1e30) coordinates; region max_area not NaN or > 0; fewer than 3
        vertices; segment indices out of range; duplicate vertices; all vertices
        collinear; zero-length or duplicate segments; crossing or collinearly
        overlapping segments, a segment through a vertex.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> bad = SimpleNamespace(vertices=np.zeros((3, 2)), segments=np.zeros((0, 2), np.int64),
    ...                       holes=np.zeros((0, 2)), regions=np.zeros((0, 4)),
    ...                       segment_markers=np.zeros(0, np.int64),
    ...                       vertex_markers=np.zeros(3, np.int64))
    >>> validate_domain(bad)
    Traceback (most recent call last):
    ...
    hammesh.errors.InvalidDomainError: vertices 0 and 1 are duplicates: both at (0.0, 0.0)
    """
    check_fields(domain)
    from hammesh.domain.repair import repair_graph

    repair_graph(domain.vertices, domain.segments, domain.segment_markers,
                 domain.vertex_markers, strict=True)


def check_fields(domain) -> None:
    """The preconditions no repair can meet: shapes, dtypes, finite coordinates,
    region areas, at least 3 vertices, segment indices in range.

    Raises
    ------
    InvalidDomainError
        Naming the field, row and value at fault.
    """
    vertices = _field(domain, "vertices", np.float64, 2)
    segments = _field(domain, "segments", np.int64, 2)
    holes = _field(domain, "holes", np.float64, 2)
    regions = _field(domain, "regions", np.float64, 4)
    segment_markers = _field(domain, "segment_markers", np.int64, None)
    vertex_markers = _field(domain, "vertex_markers", np.int64, None)
    n, s = len(vertices), len(segments)
    if segment_markers.shape != (s,):
        raise InvalidDomainError(
            f"segment_markers must have shape ({s},) (one per segment), got {segment_markers.shape}")
    if vertex_markers.shape != (n,):
        raise InvalidDomainError(
            f"vertex_markers must have shape ({n},) (one per vertex), got {vertex_markers.shape}")

    _check_points(vertices, "vertex", _XY)
    _check_points(holes, "hole", _XY)
    _check_points(regions[:, :3], "region", _XY + ("attribute",))
    _check_max_area(regions)

    if n < 3:
        raise InvalidDomainError(f"a domain needs at least 3 vertices, got {n}")
    check_extent(vertices, InvalidDomainError, "the domain")
    if s:
        _check_segment_indices(segments, n)


# ----------------------------------------------------------------------------- fields

def _field(domain, name, dtype, ncols):
    try:
        value = getattr(domain, name)
    except AttributeError:
        raise InvalidDomainError(f"domain has no field {name!r}") from None
    if not isinstance(value, np.ndarray):
        raise InvalidDomainError(f"{name} must be a numpy array, got {type(value).__name__}")
    if value.dtype != dtype:
        raise InvalidDomainError(f"{name} must have dtype {np.dtype(dtype)}, got {value.dtype}")
    if ncols is not None and (value.ndim != 2 or value.shape[1] != ncols):
        raise InvalidDomainError(f"{name} must have shape (k, {ncols}), got {value.shape}")
    if ncols is None and value.ndim != 1:
        raise InvalidDomainError(f"{name} must be one-dimensional, got shape {value.shape}")
    return value


def _fmt(x) -> str:
    return repr(float(x))


def _point(p) -> str:
    return f"({_fmt(p[0])}, {_fmt(p[1])})"


def _check_points(values, what, columns):
    if values.size == 0:
        return
    bad = ~np.isfinite(values)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InvalidDomainError(
            f"{what} {i} has a non-finite {columns[j]} ({_fmt(values[i, j])})")
    big = np.abs(values) > MAX_ABS_COORDINATE
    if big.any():
        i, j = np.argwhere(big)[0]
        raise InvalidDomainError(
            f"{what} {i} has {columns[j]} = {_fmt(values[i, j])} beyond +-{MAX_ABS_COORDINATE:g}; "
            "Triangle's predicates would overflow (rescale the domain)")


def _check_max_area(regions):
    area = regions[:, 3]
    bad = ~(np.isnan(area) | ((area > 0) & np.isfinite(area)))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidDomainError(
            f"region {i} has max_area {_fmt(area[i])}; it must be NaN (no limit) "
            "or a finite number > 0")


# ----------------------------------------------------------------------------- segments

def _check_segment_indices(segments, n):
    neg = segments < 0
    if neg.any():
        i, j = np.argwhere(neg)[0]
        raise InvalidDomainError(f"segment {i} references negative vertex index {segments[i, j]}")
    out = segments >= n
    if out.any():
        i, j = np.argwhere(out)[0]
        raise InvalidDomainError(
            f"segment {i} references vertex {segments[i, j]} but there are only {n} vertices")
