"""Per-point values of an input mesh carried to a post-processed mesh.

A post-processed mesh (:func:`hammesh.postprocess.hamiltonian`) keeps the input's
points first, at their indices, and adds Steiner points inside (or on an edge of) the
input triangle named by the ``parent`` of the output triangles around them.  The
input's point data (temperatures, displacements, labels: whatever a mesh file brought)
is kept at the input points and *interpolated* at the new ones, as Triangle
interpolates vertex attributes at the vertices it inserts: linearly, with the new
point's barycentric coordinates in its parent.  Integer data (labels, ids) take the
value of the parent's nearest corner instead, so a label stays a label.
"""

from __future__ import annotations

import numpy as np

__all__ = ["carry_point_data", "steiner_weights"]


def steiner_weights(
    input_points: np.ndarray,
    input_triangles: np.ndarray,
    points: np.ndarray,
    triangles: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Corners and barycentric weights of each new point in an input triangle.

    Every new point (index ``>= len(input_points)``) is a corner of some output rows;
    each row's ``parent`` input triangle is a candidate.  The candidate in which the
    point's smallest barycentric coordinate is largest wins (a point on an input edge
    lies in both triangles of the edge; a Thm 2.4 flip row names only the first of its
    two parents, which need not hold all of its corners, so rows of ``kind`` 1 count
    only when nothing else does).  Weights are clipped at 0 and renormalised: points a
    rounding step outside (snapped Steiner points) are not extrapolated.

    Parameters
    ----------
    input_points : (n0, d) float64
        ``d`` = 2, or 3 for a surface (its new points lie in their parents' planes).
    input_triangles : (m0, 3) int
    points : (n, d) float64
        The output's points; the first ``n0`` are the input's.
    triangles : (m, 3) int
    parent : (m,) int
        Input row of each output row (``-1``: none).
    kind : (m,) int, optional
        :data:`hammesh.mesh.KIND_NAMES` index of each row.

    Returns
    -------
    corners : (n - n0, 3) int64
        Input point indices of each new point's triangle (``-1`` if no row has a parent).
    weights : (n - n0, 3) float64
        Barycentric weights, summing to 1 (zeros where ``corners`` is -1).
    """
    n0 = len(input_points)
    new = len(points) - n0
    corners = np.full((max(new, 0), 3), -1, dtype=np.int64)
    weights = np.zeros((max(new, 0), 3), dtype=np.float64)
    if new <= 0:
        return corners, weights
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    par = np.asarray(parent, dtype=np.int64).reshape(-1)
    # (row, corner) incidences of new points whose row has a parent
    rows, slot = np.nonzero((tri >= n0) & (par >= 0)[:, None])
    if len(rows) == 0:
        return corners, weights
    vertex = tri[rows, slot] - n0
    owner = np.asarray(input_triangles, dtype=np.int64)[par[rows]]
    abc = np.asarray(input_points, dtype=np.float64)[owner]  # (k, 3, 2)
    p = np.asarray(points, dtype=np.float64)[vertex + n0]
    lam = _barycentric(abc, p)
    score = lam.min(axis=1)
    if kind is not None:  # flip rows last (see above)
        score = np.where(np.asarray(kind).reshape(-1)[rows] == 1, score - 4.0, score)
    # the best incidence of each new point: sort by (vertex, -score), take the first
    order = np.lexsort((-score, vertex))
    first = order[np.r_[True, vertex[order][1:] != vertex[order][:-1]]]
    vertex, owner, lam, score = vertex[first], owner[first], lam[first], score[first]
    # sparse mode places some Steiner points for their angles (docs/sparse.md), off
    # their rows' parents but inside the triangles around them: search the input
    # triangles around the best parent's corners, two rings wide, then everywhere
    tri0 = np.asarray(input_triangles, dtype=np.int64)
    pts0 = np.asarray(input_points, dtype=np.float64)
    outside = np.flatnonzero(score < -_INSIDE_TOLERANCE)
    if len(outside):
        ring = _VertexRing(tri0, n0)
        for _ in range(2):
            seeds = owner[outside]
            cand_point, cand_tri = ring.around(seeds)
            if len(cand_point) == 0:
                break
            p_c = np.asarray(points, dtype=np.float64)[vertex[outside][cand_point] + n0]
            lam_c = _barycentric(pts0[tri0[cand_tri]], p_c)
            sc = lam_c.min(axis=1)
            o = np.lexsort((-sc, cand_point))
            best = o[np.r_[True, cand_point[o][1:] != cand_point[o][:-1]]]
            at = outside[cand_point[best]]
            better = sc[best] > score[at]
            at, best = at[better], best[better]
            owner[at], lam[at], score[at] = tri0[cand_tri[best]], lam_c[best], sc[best]
            outside = np.flatnonzero(score < -_INSIDE_TOLERANCE)
            if len(outside) == 0:
                break
        if len(outside) and pts0.shape[1] == 2:  # (not seen in hammesh's constructions; matplotlib's)
            from matplotlib.tri import Triangulation

            finder = Triangulation(pts0[:, 0], pts0[:, 1], tri0).get_trifinder()
            p_o = np.asarray(points, dtype=np.float64)[vertex[outside] + n0]
            found = np.asarray(finder(p_o[:, 0], p_o[:, 1]), dtype=np.int64)
            hit = found >= 0
            at = outside[hit]
            owner[at] = tri0[found[hit]]
            lam[at] = _barycentric(pts0[owner[at]], p_o[hit])
    lam = np.clip(lam, 0.0, None)
    total = lam.sum(axis=1, keepdims=True)
    lam = np.where(total > 0, lam / np.where(total > 0, total, 1.0), 1.0 / 3.0)
    corners[vertex] = owner
    weights[vertex] = lam
    return corners, weights


#: A barycentric coordinate above ``-_INSIDE_TOLERANCE`` counts as inside (rounding).
_INSIDE_TOLERANCE = 1e-9


class _VertexRing:
    """Input triangles around the corners of given triangles (a CSR of corner -> rows)."""

    def __init__(self, triangles: np.ndarray, n: int) -> None:
        self.triangles = triangles
        flat = triangles.reshape(-1)
        self.rows = np.argsort(flat, kind="stable") // 3
        self.start = np.searchsorted(flat[np.argsort(flat, kind="stable")], np.arange(n + 1))

    def around(self, corners_of: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(which, row)`` pairs: input row ``row`` touches a corner of ``corners_of[which]``."""
        c = corners_of.reshape(-1)  # (k * 3,) corner vertices
        counts = self.start[c + 1] - self.start[c]
        which = np.repeat(np.repeat(np.arange(len(corners_of)), 3), counts)
        offsets = np.repeat(self.start[c] - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
        return which, self.rows[offsets]


def _barycentric(abc: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``(k, 3)`` barycentric coordinates of points ``p (k, d)`` in triangles ``abc (k, 3, d)``,
    ``d`` = 2, or 3 (a surface: of ``p``'s projection onto the triangle's plane); a
    degenerate triangle: equal thirds."""
    a, b, c = abc[:, 0], abc[:, 1], abc[:, 2]
    v0, v1, v2 = b - a, c - a, p - a
    if abc.shape[-1] == 2:
        den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
        safe = np.where(den != 0, den, 1.0)
        l1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / safe
        l2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / safe
    else:  # the normal equations of p - a = l1 v0 + l2 v1
        d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
        d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
        den = d00 * d11 - d01 * d01
        safe = np.where(den != 0, den, 1.0)
        l1 = (d11 * d20 - d01 * d21) / safe
        l2 = (d00 * d21 - d01 * d20) / safe
    lam = np.column_stack([1.0 - l1 - l2, l1, l2])
    return np.where((den != 0)[:, None], lam, 1.0 / 3.0)


def carry_point_data(
    point_data: dict[str, np.ndarray],
    input_points: np.ndarray,
    input_triangles: np.ndarray,
    points: np.ndarray,
    triangles: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The input's ``point_data`` on the output's points (see the module docstring).

    Parameters
    ----------
    point_data : dict of str to (n0,) or (n0, c) arrays
    input_points, input_triangles, points, triangles, parent, kind
        As in :func:`steiner_weights`.

    Returns
    -------
    dict of str to (n,) or (n, c) arrays
        Same names and dtypes; rows ``< n0`` are the input's values.  A new point that no
        row with a parent touches (none in hammesh's constructions) gets NaN (floats) or
        the dtype's minimum (integers).

    Examples
    --------
    >>> pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> out = np.vstack([pts, [[0.25, 0.25]]])
    >>> tri = np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3]])
    >>> carry_point_data({"t": np.array([0.0, 4.0, 8.0])}, pts, np.array([[0, 1, 2]]),
    ...                  out, tri, np.zeros(3, dtype=np.int64))["t"].tolist()
    [0.0, 4.0, 8.0, 3.0]
    """
    if not point_data:
        return {}
    n0 = len(input_points)
    corners, weights = steiner_weights(input_points, input_triangles, points, triangles, parent, kind)
    found = corners[:, 0] >= 0
    safe = np.where(corners >= 0, corners, 0)
    nearest = safe[np.arange(len(safe)), np.argmax(weights, axis=1)]
    carried: dict[str, np.ndarray] = {}
    for name, values in point_data.items():
        values = np.asarray(values)
        given = values[:n0]
        if values.dtype.kind in "biu":  # labels: the nearest corner's
            new = given[nearest]
            new[~found] = np.iinfo(values.dtype).min if values.dtype.kind != "b" else False
        else:
            w = weights.reshape(weights.shape + (1,) * (values.ndim - 1))
            new = (given[safe].astype(np.float64) * w).sum(axis=1).astype(values.dtype, copy=False)
            new[~found] = np.nan
        carried[name] = np.concatenate([given, new])
    return carried
