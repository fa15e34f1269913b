"""Picture of a polygon, its triangulation and the dual path (matplotlib, headless).

Like :mod:`hammesh.plot.cycle`: the Agg canvas without ``pyplot``, matplotlib imported
inside the function, the file written atomically (format from the suffix).
"""

from __future__ import annotations

import os

import numpy as np

from hammesh.io.atomic import atomic_path

__all__ = ["plot_polygon_path"]


def plot_polygon_path(
    polygon_points,
    points,
    triangles,
    path: str | os.PathLike[str],
    *,
    closed: bool = False,
    holes=(),
    title: str | None = None,
    dpi: int = 150,
) -> None:
    """Draw the polygon outline, the triangles and the dual path through their centroids.

    Parameters
    ----------
    polygon_points : (n, 2) float
        The polygon (drawn dark).
    points : (N, 2) float
        Vertices of the triangles (``N >= n``; Steiner points are marked).
    triangles : (m, 3) int
        In dual-path order (drawn grey; the path is coloured by position).
    path : path-like
        Output image; the suffix picks the format.
    closed : bool
        Close the path from the last triangle back to the first (a cycle).
    holes : sequence of (n_i, 2) float
        Hole rings, drawn like the outline; ``points`` then starts with the outline's
        and the holes' vertices, in order, before the Steiner points.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

    poly = np.asarray(polygon_points, dtype=np.float64)
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    fig = Figure(figsize=(8, 8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_axis_off()
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    edges = np.unique(np.sort(edges, axis=1), axis=0)
    ax.add_collection(LineCollection(pts[edges], colors="0.7", linewidths=0.6, zorder=1))
    rings = [poly] + [np.asarray(h, dtype=np.float64) for h in holes]
    for r in rings:
        closed_ring = np.vstack([r, r[:1]])
        ax.plot(closed_ring[:, 0], closed_ring[:, 1], color="0.1", linewidth=1.6, zorder=3)
    n_ring = sum(len(r) for r in rings)
    c = pts[tri].mean(axis=1)
    if closed and len(c) > 1:
        c = np.vstack([c, c[:1]])
    segs = np.stack([c[:-1], c[1:]], axis=1)
    if len(segs):
        lines = LineCollection(segs, array=np.arange(len(segs), dtype=float), cmap="turbo",
                               norm=Normalize(0, max(len(segs) - 1, 1)), linewidths=1.8, zorder=2)
        ax.add_collection(lines)
        fig.colorbar(lines, ax=ax, shrink=0.8, pad=0.02).set_label("position along dual path")
    if len(pts) > n_ring:
        s = pts[n_ring:]
        ax.plot(s[:, 0], s[:, 1], "o", color="crimson", markersize=4, zorder=4, label="Steiner")
        ax.legend(loc="upper right")
    ax.autoscale_view()
    ax.set_title(title or f"{len(tri)} triangles")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
