"""Pictures of meshes and of their Hamiltonian cycles (matplotlib, headless).

Only :class:`matplotlib.figure.Figure` with the Agg canvas is used, never ``pyplot``,
so plotting touches no global state: it works without a display and from several
threads at once.  matplotlib is imported inside the functions.  Files are written
atomically; the format follows the suffix (``.png``, ``.pdf``, ``.svg``...).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from hammesh.io.atomic import atomic_path
from hammesh.io.validate import validate_mesh
from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["plot_cycle", "plot_mesh", "cycle_segments", "unique_edges", "LARGE_MESH"]

#: Above this many triangles the grey mesh edges are skipped in :func:`plot_cycle` and
#: every collection is rasterized, so a picture still takes seconds.
LARGE_MESH = 200_000

_EDGE_GREY = "0.82"
_CONSTRAINED = "0.12"
_CMAP = "turbo"


def unique_edges(triangles: np.ndarray) -> np.ndarray:
    """The ``(e, 2)`` distinct undirected edges of ``(m, 3)`` triangles, sorted."""
    t = np.asarray(triangles, dtype=np.int64)
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    edges.sort(axis=1)
    return np.unique(edges, axis=0)


def cycle_segments(mesh: HamiltonianMesh) -> np.ndarray:
    """The cycle as ``(m, 2, 2)`` segments between consecutive triangle centroids.

    Segment ``t`` joins the centroid of row ``t`` to that of the next row of its cycle;
    the last row of each run of :attr:`~HamiltonianMesh.components` joins back to the
    run's first row, so each cycle is closed.
    """
    points = np.asarray(mesh.points, dtype=np.float64)
    centroids = points[np.asarray(mesh.triangles)].mean(axis=1)
    m = len(centroids)
    components = np.asarray(mesh.components, dtype=np.int64)
    ends = np.cumsum(components)
    starts = ends - components
    nxt = np.arange(1, m + 1)
    nxt[ends - 1] = starts
    return np.stack([centroids, centroids[nxt]], axis=1)


def _new_axes(mesh: Mesh | HamiltonianMesh, figsize: tuple[float, float]) -> tuple[Any, Any]:
    from matplotlib.figure import Figure
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_axis_off()
    points = np.asarray(mesh.points, dtype=np.float64)
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.02 * max(float((hi - lo).max()), 1e-12)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    return fig, ax


def _figsize(points: np.ndarray) -> tuple[float, float]:
    span = np.ptp(np.asarray(points, dtype=np.float64), axis=0)
    w, h = max(float(span[0]), 1e-12), max(float(span[1]), 1e-12)
    ratio = min(max(h / w, 0.25), 4.0)
    return (8.0, max(8.0 * ratio, 3.0)) if ratio <= 1 else (max(8.0 / ratio, 3.0) + 1.5, 8.0)


def _edge_width(n_triangles: int, base: float) -> float:
    return float(np.clip(base * 30.0 / np.sqrt(max(n_triangles, 1)), 0.05, base))


def _add_edges(ax: Any, points: np.ndarray, edges: np.ndarray, **kwargs: Any) -> Any:
    from matplotlib.collections import LineCollection

    if len(edges) == 0:
        return None
    lines = LineCollection(points[np.asarray(edges, dtype=np.int64)], **kwargs)
    ax.add_collection(lines)
    return lines


def _title(kind: str, n_triangles: int, extra: str, title: str | None) -> str:
    line = f"{n_triangles:,} triangles{extra}"
    return f"{title}\n{line}" if title else f"{kind}: {line}"


def _save(fig: Any, path: str | os.PathLike[str], dpi: int) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")


def plot_cycle(
    mesh: HamiltonianMesh,
    path: str | os.PathLike[str],
    *,
    title: str | None = None,
    dpi: int = 150,
) -> None:
    """Draw ``mesh`` and its Hamiltonian cycle(s) to an image file.

    The mesh edges are thin light grey, the constrained edges (``mesh.segments``)
    thicker and dark; the cycle is one path through consecutive triangle centroids
    (each run of ``components`` closed), coloured by ``position`` along its cycle,
    with a colorbar.  Meshes with more than :data:`LARGE_MESH` triangles are drawn
    without the grey edges, rasterized.

    Parameters
    ----------
    mesh : HamiltonianMesh
    path : path-like
        Output file; the suffix picks the format (``.png``, ``.pdf``, ``.svg``...).
    title : str, optional
        First title line; the second gives the triangle and cycle counts.
    dpi : int
        Resolution of raster output.

    Raises
    ------
    InvalidMeshError
        The mesh has a non-finite point, an index out of range or inconsistent cycles.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    validate_mesh(mesh)
    points = np.asarray(mesh.points, dtype=np.float64)
    m = mesh.n_triangles
    large = m > LARGE_MESH
    fig, ax = _new_axes(mesh, _figsize(points))

    if not large:
        _add_edges(ax, points, unique_edges(mesh.triangles),
                   colors=_EDGE_GREY, linewidths=_edge_width(m, 0.6), zorder=1)
    _add_edges(ax, points, mesh.segments, colors=_CONSTRAINED,
               linewidths=_edge_width(m, 1.6) + 0.3, zorder=3, rasterized=large)

    position = np.asarray(mesh.position, dtype=np.float64)
    vmax = max(float(np.max(mesh.components)) - 1.0, 1.0)
    path_lines = LineCollection(
        cycle_segments(mesh),
        array=position,
        cmap=_CMAP,
        norm=Normalize(0.0, vmax),
        linewidths=_edge_width(m, 1.4),
        capstyle="round",
        joinstyle="round",
        zorder=2,
        rasterized=large,
    )
    ax.add_collection(path_lines)
    colorbar = fig.colorbar(path_lines, ax=ax, shrink=0.8, pad=0.02)
    colorbar.set_label("position along cycle")

    c = len(mesh.components)
    ax.set_title(_title("Hamiltonian cycle", m, f", {c} cycle{'s' if c != 1 else ''}", title))
    _save(fig, path, dpi)


def plot_mesh(
    mesh: Mesh | HamiltonianMesh,
    path: str | os.PathLike[str],
    *,
    title: str | None = None,
    dpi: int = 150,
) -> None:
    """Draw a triangle mesh (edges grey, constrained edges dark) to an image file.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
    path : path-like
        Output file; the suffix picks the format.
    title : str, optional
        First title line; the second gives the triangle count.
    dpi : int
        Resolution of raster output.

    Raises
    ------
    InvalidMeshError
        The mesh has a non-finite point or an index out of range.
    """
    validate_mesh(mesh)
    points = np.asarray(mesh.points, dtype=np.float64)
    m = mesh.n_triangles
    large = m > LARGE_MESH
    fig, ax = _new_axes(mesh, _figsize(points))
    _add_edges(ax, points, unique_edges(mesh.triangles), colors="0.45",
               linewidths=_edge_width(m, 0.8), zorder=1, rasterized=large)
    _add_edges(ax, points, mesh.segments, colors=_CONSTRAINED,
               linewidths=_edge_width(m, 1.6) + 0.3, zorder=2, rasterized=large)
    ax.set_title(_title("Mesh", m, f", {mesh.n_points:,} points", title))
    _save(fig, path, dpi)
