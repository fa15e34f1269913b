"""Validation of a simple polygon given as an ``(n, 2)`` vertex array.

Every public function of :mod:`hammesh.polygon` starts here.  The checks reuse
:func:`hammesh.domain.validate_domain` on the closed chain of edges, so messages follow
its conventions; "edge ``k``" joins vertices ``k`` and ``k + 1`` (mod ``n``) of the
input order.  The algorithms then work on a counter-clockwise copy; ``order`` maps its
indices back to the caller's.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from hammesh.domain.validate import point_array, validate_domain
from hammesh.errors import InvalidDomainError

__all__ = ["Polygon", "as_polygon", "polygon_edges", "edge_wording"]


@dataclass(frozen=True, eq=False)
class Polygon:
    """A validated simple polygon.

    Attributes
    ----------
    points : (n, 2) float64
        The vertices in counter-clockwise order.
    order : (n,) int64
        ``points[k]`` is the caller's vertex ``order[k]``.
    area : float
        Area (> 0).
    """

    points: np.ndarray
    order: np.ndarray
    area: float

    @property
    def n(self) -> int:
        return int(self.points.shape[0])

    def to_input(self, triangles: np.ndarray) -> np.ndarray:
        """Map ``(m, 3)`` internal vertex indices to the caller's indices."""
        return self.order[np.asarray(triangles, dtype=np.int64)]


def polygon_edges(n: int) -> np.ndarray:
    """The ``(n, 2) int64`` edges ``(k, k + 1 mod n)`` of an ``n``-gon."""
    k = np.arange(n, dtype=np.int64)
    return np.stack([k, (k + 1) % n], axis=1)


def edge_wording(message: str) -> str:
    """A domain validator's message in polygon words (segment -> edge)."""
    return re.sub(r"\bsegment(s?)\b", r"edge\1", message)


def as_polygon(points) -> Polygon:
    """Validate ``points`` as a simple polygon and return its counter-clockwise form.

    Parameters
    ----------
    points : (n, 2) array_like of float
        Vertices in order around the polygon, clockwise or counter-clockwise, without
        repeating the first vertex at the end.

    Raises
    ------
    InvalidDomainError
        Wrong shape, non-finite coordinates, fewer than 3 vertices, repeated vertices,
        zero area (all vertices collinear), crossing or touching edges, or an edge
        passing through another vertex.  The message names the items.

    Examples
    --------
    >>> as_polygon([[0, 0], [0, 1], [1, 0]]).order.tolist()   # clockwise input
    [2, 1, 0]
    >>> as_polygon([[0, 0], [1, 1], [1, 0], [0, 1]])
    Traceback (most recent call last):
    ...
    hammesh.errors.InvalidDomainError: not a simple polygon: edges 0 and 2 cross at (0.5, 0.5)
    """
    pts = point_array(points, "polygon points", rows="n")
    n = len(pts)
    if n < 3:
        raise InvalidDomainError(f"a polygon needs at least 3 vertices, got {n}")
    edges = polygon_edges(n)
    domain = SimpleNamespace(
        vertices=pts, segments=edges, holes=np.zeros((0, 2)), regions=np.zeros((0, 4)),
        segment_markers=np.zeros(n, np.int64), vertex_markers=np.zeros(n, np.int64))
    try:
        validate_domain(domain)
    except InvalidDomainError as exc:
        msg = str(exc)
        if "collinear" in msg and "vertices are collinear" in msg:
            raise InvalidDomainError(f"polygon has zero area: {msg}") from None
        if "duplicates" in msg:
            raise InvalidDomainError(f"polygon has repeated vertices: {msg}") from None
        raise InvalidDomainError(f"not a simple polygon: {edge_wording(msg)}") from None
    x, y = pts[:, 0], pts[:, 1]
    twice = float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    if twice == 0.0:  # pragma: no cover - a simple polygon has positive area
        raise InvalidDomainError("polygon has zero area")
    order = np.arange(n, dtype=np.int64)
    if twice < 0:
        order = order[::-1].copy()
    return Polygon(points=pts[order], order=order, area=abs(twice) / 2.0)
