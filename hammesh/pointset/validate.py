"""Checked input of the point-set algorithms, and their convex hull.

Duplicates are an error, not merged: a triangulation of a point set has every input
point as a vertex, so a repeated point has no valid place; the message names both
indices so the caller can drop one (``np.unique(points, axis=0)``) knowingly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.domain.validate import point_array
from hammesh.errors import InvalidDomainError
from hammesh.pointset._kernels import all_collinear, hull_boundary

__all__ = ["as_points", "Hull", "convex_hull", "MAX_COORDINATE", "MIN_EXTENT"]

#: Largest coordinate magnitude: differences squared stay finite in float64.
MAX_COORDINATE = 1e150
#: Smallest extent (largest coordinate difference) of a point set: products of two
#: differences stay normal float64 numbers.
MIN_EXTENT = 1e-150


def as_points(points: np.ndarray) -> np.ndarray:
    """``points`` as a contiguous ``(n, 2) float64`` array of distinct, finite points.

    Raises
    ------
    InvalidDomainError
        Wrong shape, fewer than 3 points, a non-finite coordinate, a duplicate point
        (both indices named) or all points on one line.
    """
    pts = point_array(points, "points", rows="n")
    n = len(pts)
    if n < 3:
        raise InvalidDomainError(f"a triangulation needs at least 3 points, got {n}")
    finite = np.isfinite(pts).all(axis=1)
    if not finite.all():
        i = int(np.argmin(finite))
        raise InvalidDomainError(f"point {i} {pts[i].tolist()} is not finite")
    big = float(np.abs(pts).max())
    if big > MAX_COORDINATE:  # orientation products would overflow float64 (issue 12 #9)
        raise InvalidDomainError(
            f"coordinates reach {big:.3g}: orientation tests overflow float64 beyond "
            f"{MAX_COORDINATE:.0e}; scale the points (the triangulation does not change)"
        )
    extent = float((pts.max(axis=0) - pts.min(axis=0)).max())
    if 0 < extent < MIN_EXTENT:  # orientation products underflow (reported as "collinear" before)
        raise InvalidDomainError(
            f"the points span only {extent:.3g}: orientation tests underflow float64 below "
            f"{MIN_EXTENT:.0e}; scale the points (the triangulation does not change)"
        )
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    s = pts[order]
    same = (s[1:] == s[:-1]).all(axis=1)
    if same.any():
        k = int(np.argmax(same))
        i, j = sorted((int(order[k]), int(order[k + 1])))
        raise InvalidDomainError(
            f"points {i} and {j} are duplicates {pts[i].tolist()}; remove one "
            "(e.g. np.unique(points, axis=0))"
        )
    if all_collinear(pts, int(order[0]), int(order[-1])):
        raise InvalidDomainError(f"all {n} points lie on one line; there is no triangle")
    return pts


@dataclass(frozen=True)
class Hull:
    """Convex hull of a point set.

    Attributes
    ----------
    boundary : (h,) int64
        Every point on the hull boundary (corners and points on hull edges), CCW,
        starting at the lexicographically smallest point.
    corner : (h,) bool
        True for strictly convex corners.
    order : (n,) int64
        The lexicographic order of all points (x, then y).
    """

    boundary: np.ndarray
    corner: np.ndarray
    order: np.ndarray

    @property
    def corners(self) -> np.ndarray:
        return self.boundary[self.corner]

    @property
    def h(self) -> int:
        return int(len(self.boundary))


def convex_hull(pts: np.ndarray) -> Hull:
    """Hull of points already checked by :func:`as_points` (exact predicates)."""
    order = np.lexsort((pts[:, 1], pts[:, 0])).astype(np.int64)
    boundary, corner = hull_boundary(pts, order)
    return Hull(boundary=boundary, corner=corner, order=order)
