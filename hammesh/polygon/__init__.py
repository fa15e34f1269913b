"""Hamiltonian and sequential triangulations of simple polygons (paper Sections 2, 4, 5).

::

    from hammesh import polygon
    T = polygon.hamiltonian_triangulation(points)        # Thm 2.1, or None
    S = polygon.sequential_triangulation(points)         # Thm 4.4, or None
    Q, T = polygon.steiner_hamiltonian(points, "cycle")  # Thm 2.3 ("path" too, holes=)
    T = polygon.hamiltonian_triangulation_holes(points, holes)  # Thm 2.2, small, or None
    paths = polygon.path_partition(points, triangles)    # Lemma 5.1

``points`` is an ``(n, 2)`` simple polygon, clockwise or counter-clockwise; returned
triangles index the input order and are counter-clockwise.  Invalid polygons raise
:class:`~hammesh.errors.InvalidDomainError` naming the problem.
"""

from hammesh.polygon._polygon import as_polygon as validate_polygon
from hammesh.polygon.path_partition import path_partition
from hammesh.polygon.hamiltonian import hamiltonian_triangulation, is_hamiltonian
from hammesh.polygon.hamiltonian_holes import hamiltonian_triangulation_holes
from hammesh.polygon.steiner import (
    DECOMPOSITIONS,
    KINDS,
    SteinerResult,
    convex_decomposition,
    steiner_hamiltonian,
    steiner_hamiltonian_result,
)
from hammesh.polygon.sequential import sequential_starts, sequential_triangulation
from hammesh.polygon.visibility import visibility_graph

__all__ = [
    "hamiltonian_triangulation",
    "is_hamiltonian",
    "hamiltonian_triangulation_holes",
    "sequential_triangulation",
    "sequential_starts",
    "steiner_hamiltonian",
    "steiner_hamiltonian_result",
    "SteinerResult",
    "KINDS",
    "DECOMPOSITIONS",
    "convex_decomposition",
    "path_partition",
    "visibility_graph",
    "validate_polygon",
]
