"""Some triangulation of a simple polygon (no Steiner points), and its dual adjacency.

Used as a scaffold by :mod:`~hammesh.polygon.visibility` (visibility walks through the
triangles) and :mod:`~hammesh.polygon.steiner` (Hertel--Mehlhorn starts from a
triangulation).  Triangle's constrained Delaunay triangulation (switch ``p``) is used:
it adds no vertices and eats the triangles outside the boundary.
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import MeshingError
from hammesh.polygon._polygon import polygon_edges
from hammesh.predicates import orient_rows as orient_many

__all__ = ["triangulate_polygon", "triangle_neighbors"]


def triangulate_polygon(points: np.ndarray) -> np.ndarray:
    """Triangulate the counter-clockwise simple polygon ``points`` without Steiner points.

    Parameters
    ----------
    points : (n, 2) float64
        A validated polygon (see :func:`~hammesh.polygon._polygon.as_polygon`).

    Returns
    -------
    (n - 2, 3) int64
        Counter-clockwise triangles (checked exactly).

    Raises
    ------
    MeshingError
        Triangle added vertices or returned a wrong number of triangles.
    """
    import triangle

    n = len(points)
    if n == 3:
        return np.array([[0, 1, 2]], dtype=np.int64)
    out = triangle.triangulate({"vertices": points, "segments": polygon_edges(n)}, "pQ")
    tri = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64)
    if len(out["vertices"]) != n or tri.shape != (n - 2, 3):
        raise MeshingError(
            f"Triangle returned {len(out['vertices'])} vertices and {len(tri)} triangles "
            f"for a {n}-gon (expected {n} and {n - 2})")
    s = orient_many(points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]])
    if np.any(s < 0):
        tri[s < 0] = tri[s < 0][:, ::-1]
    if np.any(s == 0):
        raise MeshingError("Triangle returned a degenerate triangle for a simple polygon")
    return tri


def triangle_neighbors(triangles: np.ndarray) -> np.ndarray:
    """``(m, 3) int64``: ``nb[t, k]`` is the triangle across edge ``(t[k], t[k+1])`` or -1.

    Raises
    ------
    ValueError
        An edge is shared by more than two triangles (the caller rephrases).
    """
    t = np.asarray(triangles, dtype=np.int64)
    m = len(t)
    a = t.reshape(-1)
    b = t[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo * (int(t.max(initial=0)) + 1) + hi
    order = np.argsort(key, kind="stable")
    k = key[order]
    nb = np.full(3 * m, -1, dtype=np.int64)
    same = np.flatnonzero(k[1:] == k[:-1])
    if same.size and np.any(np.diff(same) == 1):
        e = order[same[np.flatnonzero(np.diff(same) == 1)[0]]]
        raise ValueError(f"edge ({lo[e]}, {hi[e]}) is shared by more than two triangles")
    p, q = order[same], order[same + 1]
    nb[p] = q // 3
    nb[q] = p // 3
    return nb.reshape(m, 3)
