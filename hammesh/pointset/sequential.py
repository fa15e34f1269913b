"""Sequential triangulations of point sets: the construction first, then the exact search.

:func:`sequential_triangulation` chooses between Lemma 4.2's construction
(:mod:`~hammesh.pointset.sequential_few_interior`) and the exact search of small sets
(:mod:`~hammesh.pointset.sequential_search`); it lives apart from both so that neither
imports the other's caller (the two modules used to import each other).
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.pointset.sequential_few_interior import NotConstructed, few_interior_sequential
from hammesh.pointset.sequential_search import SEARCH_LIMIT, search_sequential
from hammesh.pointset.validate import as_points

__all__ = ["sequential_triangulation"]


def sequential_triangulation(points: np.ndarray) -> np.ndarray | None:
    """A sequential triangulation (one alternating strip) of ``points``, or ``None``.

    At most two interior points: the construction of Lemma 4.2
    (:func:`hammesh.pointset.sequential_few_interior.few_interior_sequential`), any ``n``; in
    convex position it also decides exactly (``None`` is then a proof).  Otherwise,
    and for degenerate input the construction does not cover, the exact search
    (:func:`search_sequential`) for at most :data:`SEARCH_LIMIT` points.

    Returns
    -------
    (2 n - h - 2, 3) int64 or None
        Counter-clockwise triangles in strip order, certified by Thm 4.3; ``None`` when
        the set provably has none.

    Raises
    ------
    InvalidOptionError
        The set is too large to decide: more than :data:`SEARCH_LIMIT` points and
        neither Lemma 4.2 nor the convex-position test applies (the message says why).
    InvalidDomainError
        Invalid points (see :func:`hammesh.pointset.validate.as_points`).
    """
    pts = as_points(points)
    n = len(pts)
    try:
        return few_interior_sequential(pts)
    except NotConstructed as exc:
        if n <= SEARCH_LIMIT:
            return search_sequential(pts)
        why = str(exc)
    raise InvalidOptionError(
        f"cannot decide whether these {n} points have a sequential triangulation: {why}; "
        f"no construction is known and the exact search is limited to {SEARCH_LIMIT} points"
    )
