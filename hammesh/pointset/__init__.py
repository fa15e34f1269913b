"""Triangulations of point sets (paper §3, §4): Hamiltonian and sequential.

======================================================  ====================================
module                                                  what
======================================================  ====================================
:mod:`hammesh.pointset.hamiltonian`                     Thm 3.1 / Lemma 3.2: Hamiltonian
                                                        cycle (path if convex), O(n log n)
:mod:`hammesh.pointset.sequential`                      :func:`sequential_triangulation`:
                                                        construction, else exact search
:mod:`hammesh.pointset.sequential_few_interior`         Lemma 4.2: sequential triangulation
                                                        with at most two interior points
:mod:`hammesh.pointset.sequential_search`               exact search for small sets
:mod:`hammesh.pointset.no_sequential`                   Thm 4.1: sets with no sequential one
:mod:`hammesh.pointset.verify`                          the certificate of every output
:mod:`hammesh.pointset.validate`                        checked input, exact convex hull
======================================================  ====================================

>>> import numpy as np
>>> from hammesh import pointset
>>> pts = np.random.default_rng(0).random((100, 2))
>>> T = pointset.hamiltonian_triangulation(pts, seed=0)      # verified cycle order
>>> len(T) == 2 * 100 - len(pointset.convex_hull(pts).boundary) - 2
True
>>> pointset.sequential_triangulation(pointset.no_sequential_example(9)) is None
True
"""

from hammesh.pointset.sequential_few_interior import (
    NotConstructed,
    convex_sequential,
    few_interior_sequential,
    lemma42_plan,
)
from hammesh.pointset.sequential import sequential_triangulation
from hammesh.pointset.sequential_search import SEARCH_LIMIT, search_sequential
from hammesh.pointset.hamiltonian import hamiltonian_triangulation
from hammesh.pointset.no_sequential import no_sequential_example
from hammesh.pointset.validate import Hull, as_points, convex_hull
from hammesh.pointset.verify import verify_point_triangulation

__all__ = [
    "hamiltonian_triangulation",
    "sequential_triangulation",
    "no_sequential_example",
    "search_sequential",
    "convex_sequential",
    "few_interior_sequential",
    "lemma42_plan",
    "NotConstructed",
    "verify_point_triangulation",
    "convex_hull",
    "as_points",
    "Hull",
    "SEARCH_LIMIT",
]
