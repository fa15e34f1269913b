"""Sequential triangulations of sets with few interior points (paper §4, Lemma 4.2).

Lemma 4.2: a set (in general position) with at most two points strictly inside its
convex hull has a sequential triangulation.  Implemented here: the convex-position
case of the proof, a zigzag strip ``p0, p1, p_{h-1}, p2, p_{h-2}, ...`` over the hull
points (every crossed edge is a chord, consecutive chords alternate ends).  Hull
edges with collinear points are handled when the zigzag stays non-degenerate (the
start is chosen among the strict corners); the result is certified by Thm 4.3.

Not implemented yet: the case analysis for one or two interior points (Figures
17-20); :func:`hammesh.pointset.sequential_triangulation` answers those sets by the
exact search when they are small enough.
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.predicates import orient_many
from hammesh.pointset.sequential_search import check_sequential
from hammesh.pointset.validate import as_points, convex_hull

__all__ = ["convex_sequential"]


def _zigzag(boundary: np.ndarray, start: int) -> np.ndarray:
    h = len(boundary)
    b = np.roll(boundary, -start)
    seq = [b[0], b[1]]
    left, right = 2, h - 1
    take_right = True
    while left <= right:
        if take_right:
            seq.append(b[right])
            right -= 1
        else:
            seq.append(b[left])
            left += 1
        take_right = not take_right
    return np.array([seq[k : k + 3] for k in range(len(seq) - 2)], dtype=np.int64)


def convex_sequential(points: np.ndarray) -> np.ndarray:
    """Sequential triangulation of a point set in convex position (Lemma 4.2, no interior point).

    Parameters
    ----------
    points : (n, 2) float64
        Every point on the hull boundary.

    Returns
    -------
    (n - 2, 3) int64
        Counter-clockwise triangles in strip order, certified (Thm 4.3).

    Raises
    ------
    InvalidOptionError
        A point is strictly inside the hull, or collinear hull points defeat every zigzag.

    Examples
    --------
    >>> import numpy as np
    >>> ang = np.linspace(0, 2 * np.pi, 7)[:-1]
    >>> convex_sequential(np.c_[np.cos(ang), np.sin(ang)]).shape
    (4, 3)
    """
    pts = as_points(points)
    hull = convex_hull(pts)
    if hull.h != len(pts):
        raise InvalidOptionError(
            f"{len(pts) - hull.h} points are inside the hull; convex_sequential needs convex position"
        )
    for start in np.flatnonzero(hull.corner):
        tri = _zigzag(hull.boundary, int(start))
        sign = orient_many(pts, tri)
        if (sign == 0).any():
            continue
        tri[sign < 0] = tri[sign < 0][:, ::-1]
        return check_sequential(pts, tri)
    raise InvalidOptionError("collinear hull points: no zigzag strip from a corner is non-degenerate")
