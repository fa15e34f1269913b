"""Sequential triangulations of simple polygons (Arkin et al., Theorem 4.4).

A triangulation is *sequential* when its dual has a Hamiltonian path along which no
three consecutively crossed edges share a vertex: the turns alternate left/right, so
the triangles form one strip (``glBegin(GL_TRIANGLE_STRIP)``) with no swap bits.

For a polygon the strip is fixed by its first vertex ``s`` and the side it leaves to:
the vertices come in zig-zag order ``s, s+1, s-1, s+2, s-2, ...`` (or ``s, s-1, s+1,
s-2, ...``), so the diagonals it needs are the chords ``(s-a, s+a)`` and
``(s-a, s+a+1)`` (resp. ``(s-a-1, s+a)``).  Theorem 4.4's votes: every visibility edge
votes for the one or two middle vertices of each of its two chains, with a type for
the side; ``s`` starts a sequential triangulation iff it received ``n - 3`` votes of
one type.

Complexity: the visibility graph (``O(n^2)``, :mod:`.visibility`) plus ``O(|E|)`` for
the votes and ``O(n)`` to build the strip.
"""

from __future__ import annotations

import numpy as np

from hammesh.polygon._polygon import Polygon, as_polygon
from hammesh.polygon.verify import verify_polygon_triangulation
from hammesh.polygon.visibility import visibility_matrix

__all__ = ["sequential_triangulation", "sequential_starts", "zigzag"]


def sequential_triangulation(points) -> np.ndarray | None:
    """A sequential (alternating-strip) triangulation of a simple polygon, or None (Thm 4.4).

    Parameters
    ----------
    points : (n, 2) array_like of float
        Simple polygon, clockwise or counter-clockwise.

    Returns
    -------
    (n - 2, 3) int64 or None
        Counter-clockwise triangles indexing ``points`` in strip order: consecutive
        rows share an edge and the turns alternate (no three consecutive shared edges
        meet at one vertex).  ``None`` if the polygon has no sequential triangulation.

    Raises
    ------
    InvalidDomainError
        ``points`` is not a simple polygon.

    Examples
    --------
    >>> sequential_triangulation([[0, 0], [1, 0], [2, 1], [1, 2], [0, 1]]).tolist()
    [[0, 1, 4], [1, 3, 4], [1, 2, 3]]
    """
    poly = as_polygon(points)
    starts = _starts(poly)
    if len(starts) == 0:
        return None
    s, direction = starts[0]
    T = poly.to_input(zigzag(poly.n, int(s), int(direction)))
    pts = np.asarray(points, dtype=np.float64)
    verify_polygon_triangulation([pts], pts, T, "path")
    return T


def sequential_starts(points) -> np.ndarray:
    """Every ``(start vertex, direction)`` of a sequential triangulation (Thm 4.4 votes).

    Returns
    -------
    (k, 2) int64
        Rows ``(s, d)`` in input indices: the strip starts at vertex ``s`` and next
        visits the following (``d = +1``) or preceding (``d = -1``) vertex of the input
        order.  Each sequential triangulation appears twice (once from each end).
    """
    poly = as_polygon(points)
    out = _starts(poly)
    if len(out) == 0:
        return out
    flip = poly.order[0] != 0  # internal order reversed
    s = poly.order[out[:, 0]]
    d = -out[:, 1] if flip else out[:, 1]
    res = np.stack([s, d], axis=1)
    return res[np.lexsort((-res[:, 1], res[:, 0]))]


def _starts(poly: Polygon) -> np.ndarray:
    """``(k, 2)`` internal ``(s, direction)`` whose strip uses only visible chords."""
    n = poly.n
    if n == 3:
        return np.array([[v, d] for v in range(3) for d in (1, -1)], dtype=np.int64)
    vis = visibility_matrix(poly)
    i, j = np.nonzero(vis)
    gap = (j - i) % n  # chord (i, j) with chain i, i+1, ..., j
    plus = np.bincount((i + gap // 2) % n, minlength=n)          # floor middle: s, s+1, ...
    minus = np.bincount((i + (gap + 1) // 2) % n, minlength=n)   # ceil middle: s, s-1, ...
    # an even chord's floor and ceil middles coincide, so it votes with both types
    rows = [(s, 1) for s in np.flatnonzero(plus == n - 3)]
    rows += [(s, -1) for s in np.flatnonzero(minus == n - 3)]
    rows.sort()
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def zigzag(n: int, start: int, direction: int) -> np.ndarray:
    """The strip triangles of the ``n``-gon starting at ``start`` (vertex indices CCW).

    Vertices are visited in the order ``start, start + d, start - d, start + 2d, ...``
    (mod ``n``); triangle ``k`` is visits ``k, k+1, k+2``, written counter-clockwise.
    """
    seq = np.empty(n, dtype=np.int64)
    seq[0] = start
    for k in range(1, n):
        step = (k + 1) // 2 if k % 2 else -(k // 2)
        seq[k] = (start + direction * step) % n
    tri = np.stack([seq[:-2], seq[1:-1], seq[2:]], axis=1)
    return np.sort(tri, axis=1)
