"""Hamiltonian triangulations of simple polygons (Arkin et al., Theorem 2.1).

A triangulation of a polygon is *Hamiltonian* when its dual tree is a path, i.e. it
has exactly two ears.  Theorem 2.1 decides this by dynamic programming over the
visibility graph: with vertices numbered around the polygon, ``D[i, j]`` (for a chord
``(i, j)`` that is a visibility edge) is true when the sub-polygon ``i, i+1, ..., j``
has a Hamiltonian triangulation whose dual path ends at the triangle on ``(i, j)``::

    D[i, i+2] = (i, i+2) visible
    D[i, j]   = (D[i, j-1] and (i, j-1) visible) or (D[i+1, j] and (i+1, j) visible)

and the polygon is Hamiltonian iff ``D[i, j]`` and ``D[j, i]`` for some chord.  The
chords are processed in buckets of increasing ``j - i (mod n)``.

Complexity: ``O(n^2)`` for the visibility graph (:mod:`.visibility`), then ``O(|E|)``
for the dynamic program proper (plus ``O(n^2)`` bytes for the dense tables).
"""

from __future__ import annotations

import numba
import numpy as np

from hammesh.polygon._polygon import Polygon, as_polygon
from hammesh.polygon.verify import verify_polygon_triangulation
from hammesh.polygon.visibility import visibility_matrix

__all__ = ["hamiltonian_triangulation", "is_hamiltonian", "chords_by_gap", "path_table",
           "path_from_table"]


def hamiltonian_triangulation(points) -> np.ndarray | None:
    """A triangulation of a simple polygon whose dual graph is a path (Thm 2.1), or None.

    Parameters
    ----------
    points : (n, 2) array_like of float
        Simple polygon, clockwise or counter-clockwise.

    Returns
    -------
    (n - 2, 3) int64 or None
        Counter-clockwise triangles indexing ``points``, in dual-path order: consecutive
        rows share an edge, the first and last rows are the only two ears.  ``None``
        when the polygon has no Hamiltonian triangulation (then
        :func:`~hammesh.polygon.steiner_hamiltonian` adds Steiner points).

    Raises
    ------
    InvalidDomainError
        ``points`` is not a simple polygon.

    Examples
    --------
    >>> hamiltonian_triangulation([[0, 0], [1, 0], [1, 1], [0, 1]]).tolist()
    [[0, 2, 3], [0, 1, 2]]
    """
    poly = as_polygon(points)
    tri = _solve(poly)
    if tri is None:
        return None
    T = poly.to_input(tri)
    pts = np.asarray(points, dtype=np.float64)
    verify_polygon_triangulation([pts], pts, T, "path")
    return T


def is_hamiltonian(points) -> bool:
    """Whether a simple polygon has a Hamiltonian triangulation (the Thm 2.1 decision)."""
    poly = as_polygon(points)
    if poly.n <= 4:
        return True
    return _decide(poly)[0] >= 0


def chords_by_gap(vis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Directed visible chords ``(i, j)`` sorted by ``(j - i) mod n`` (bucket order)."""
    n = len(vis)
    i, j = np.nonzero(vis)
    gap = (j - i) % n
    order = np.argsort(gap, kind="stable")
    return i[order].astype(np.int64), j[order].astype(np.int64)


def _decide(poly: Polygon) -> tuple[int, int, np.ndarray]:
    vis = visibility_matrix(poly)
    ci, cj = chords_by_gap(vis)
    D = path_table(ci, cj, poly.n)
    i, j = _find_split(ci, cj, D)
    return i, j, D


def _solve(poly: Polygon) -> np.ndarray | None:
    n = poly.n
    if n == 3:
        return np.array([[0, 1, 2]], dtype=np.int64)
    i, j, D = _decide(poly)
    if i < 0:
        return None
    side_a = path_from_table(D, i, j, n)  # from chord (i, j) out to an ear, chain i..j
    side_b = path_from_table(D, j, i, n)  # chain j..i
    tri = np.concatenate([side_b[::-1], side_a])
    # the vertices of a triangle of a CCW polygon, in increasing index order, are CCW
    return np.sort(tri, axis=1)


@numba.njit(cache=True)
def path_table(ci, cj, n):
    """The Thm 2.1 table over chords ``ci, cj`` in :func:`chords_by_gap` order.

    ``D[i, j]``: 0 false, 1 true via (i, j-1), 2 true via (i+1, j), 3 true (ear); read
    back by :func:`path_from_table`.  Also used by :mod:`~hammesh.polygon.steiner` for
    pieces with straight angles.
    """
    D = np.zeros((n, n), np.uint8)
    for e in range(ci.shape[0]):
        i = ci[e]
        j = cj[e]
        gap = (j - i) % n
        if gap == 2:
            D[i, j] = 3
        elif gap > 2:
            if D[i, (j - 1) % n] != 0:
                D[i, j] = 1
            elif D[(i + 1) % n, j] != 0:
                D[i, j] = 2
    return D


@numba.njit(cache=True)
def _find_split(ci, cj, D):
    for e in range(ci.shape[0]):
        i = ci[e]
        j = cj[e]
        if D[i, j] != 0 and D[j, i] != 0:
            return i, j
    return -1, -1


def path_from_table(D: np.ndarray, i: int, j: int, n: int) -> np.ndarray:
    """Triangles of chain ``i..j`` from the one on chord ``(i, j)`` out to the ear."""
    out = []
    while True:
        how = D[i, j]
        if how == 3:
            out.append((i, (i + 1) % n, j))
            break
        if how == 1:
            out.append((i, (j - 1) % n, j))
            j = (j - 1) % n
        else:
            out.append((i, (i + 1) % n, j))
            i = (i + 1) % n
    return np.array(out, dtype=np.int64)
