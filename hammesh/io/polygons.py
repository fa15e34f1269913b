"""Quads and polygons split into triangles, vectorized; each split is reported as a repair.

A quad is split along the diagonal that keeps both halves turning the way the quad
turns (in 3D: both halves' normals agree with the quad's Newell normal); a polygon of
``p`` corners is fanned from its first corner when every fan triangle agrees with the
polygon's orientation (convex polygons, the usual case), otherwise it is ear-clipped
in its own plane (a Python loop over those polygons only).  Every triangle keeps the
winding of its polygon.
"""

from __future__ import annotations

import numpy as np

__all__ = ["triangulate_cells"]


def _normal(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Newell normal (3D) or twice the signed area (2D, as ``(k, 1)``) of each polygon."""
    p = points[cells]  # (k, c, d)
    q = np.roll(p, -1, axis=1)
    if points.shape[1] == 2:
        return np.sum(p[..., 0] * q[..., 1] - q[..., 0] * p[..., 1], axis=1)[:, None]
    n = np.empty((len(cells), 3))
    n[:, 0] = np.sum((p[..., 1] - q[..., 1]) * (p[..., 2] + q[..., 2]), axis=1)
    n[:, 1] = np.sum((p[..., 2] - q[..., 2]) * (p[..., 0] + q[..., 0]), axis=1)
    n[:, 2] = np.sum((p[..., 0] - q[..., 0]) * (p[..., 1] + q[..., 1]), axis=1)
    return n


def _agrees(points: np.ndarray, tri: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Does each triangle turn the way ``normal`` (one row per triangle) says?"""
    a, b, c = (points[tri[:, i]] for i in range(3))
    if points.shape[1] == 2:
        cross = ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))[:, None]
    else:
        cross = np.cross(b - a, c - a)
    return np.sum(cross * normal, axis=1) > 0


def _ear_clip(points: np.ndarray, cell: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Ear clipping of one polygon in its plane; falls back to a fan if none is found."""
    if points.shape[1] == 3:
        axis = int(np.argmax(np.abs(normal)))
        keep = [i for i in range(3) if i != axis]
        xy = points[cell][:, keep]
        sign = 1.0 if normal[axis] > 0 else -1.0
        if axis == 1:
            sign = -sign
    else:
        xy = points[cell]
        sign = 1.0 if normal[0] > 0 else -1.0
    idx = list(range(len(cell)))
    out = []

    def turn(i: int, j: int, k: int) -> float:
        (ax, ay), (bx, by), (cx, cy) = xy[i], xy[j], xy[k]
        return sign * ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))

    guard = 0
    while len(idx) > 3 and guard < 4 * len(cell) ** 2:
        guard += 1
        n = len(idx)
        for t in range(n):
            i, j, k = idx[t - 1], idx[t], idx[(t + 1) % n]
            if turn(i, j, k) <= 0:
                continue
            if any(
                turn(i, j, m) > 0 and turn(j, k, m) > 0 and turn(k, i, m) > 0
                for m in idx
                if m not in (i, j, k)
            ):
                continue
            out.append((i, j, k))
            idx.pop(t)
            break
        else:
            break
    if len(idx) >= 3:
        out.extend((idx[0], idx[s], idx[s + 1]) for s in range(1, len(idx) - 1))
    return cell[np.array(out, dtype=np.int64)]


def triangulate_cells(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of ``k`` polygons of ``c >= 3`` corners each, in cell order.

    Parameters
    ----------
    points : (n, 2) or (n, 3) float64
    cells : (k, c) int64

    Returns
    -------
    triangles : (k * (c - 2), 3) int64
        Triangles of cell 0, then of cell 1, ...
    origin : (k * (c - 2),) int64
        The cell each triangle comes from.

    Examples
    --------
    >>> pts = np.array([[0., 0.], [1., 0.], [1., 1.], [0., 1.]])
    >>> triangulate_cells(pts, np.array([[0, 1, 2, 3]]))[0].tolist()
    [[0, 1, 2], [0, 2, 3]]
    """
    cells = np.asarray(cells, dtype=np.int64)
    k, c = cells.shape
    if c == 3:
        return cells.copy(), np.arange(k, dtype=np.int64)
    normal = _normal(points, cells)
    s = np.arange(1, c - 1)
    fan = np.stack([np.repeat(cells[:, :1], c - 2, axis=1), cells[:, s], cells[:, s + 1]], axis=2)
    good = _agrees(points, fan.reshape(-1, 3), np.repeat(normal, c - 2, axis=0)).reshape(k, c - 2).all(axis=1)
    if c == 4:  # the other diagonal
        alt = np.stack([cells[:, [1, 2, 3]], cells[:, [1, 3, 0]]], axis=1)
        alt_good = _agrees(points, alt.reshape(-1, 3), np.repeat(normal, 2, axis=0)).reshape(k, 2).all(axis=1)
        use = ~good & alt_good
        fan[use] = alt[use]
        good |= alt_good
    bad = np.flatnonzero(~good & (np.abs(normal).sum(axis=1) > 0))
    for i in bad.tolist():
        fan[i] = _ear_clip(points, cells[i], normal[i])
    return fan.reshape(-1, 3), np.repeat(np.arange(k, dtype=np.int64), c - 2)
