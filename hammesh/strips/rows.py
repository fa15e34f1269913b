"""Row cover: dual paths that never cross a triangle's edge most parallel to a direction.

In a triangle a strip enters by one edge and leaves by another; the segment joining
their midpoints is parallel to the third edge (the midline), so a strip heads along the
edges it does *not* cross.  Each triangle here refuses to cross its edge most parallel
to an axis; two neighbours are linked when neither refuses their common edge.  Every
triangle then has at most two links, so the links are paths (and the odd cycle, opened
where it is met): rows running along the axis, as a structured grid's rows run, with
few swaps (two consecutive turns the same way need the strip to cross an edge nearly
parallel to its heading).  On q30 planar meshes (10k-12k triangles) the rows have
~0.11 swaps per triangle at ~13 triangles per row; the end moves
(:func:`~hammesh.strips._moves_kernels.improve_cover`) then join them into strips of
~25 triangles: 1.214-1.254 indices per triangle against the greedy cover's 1.270-1.282
and the swap-free chains' 1.264-1.268 (measured in ``docs/strips.md``, session 12).

Planar meshes only (the axes are those of the ``x, y`` plane); :data:`ROW_AXES` are the
directions tried (``encode`` keeps the shortest buffer).  Our construction; the midline
observation is elementary geometry.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._cover_kernels import PathCover
from hammesh.strips._row_kernels import link_paths_into, row_links_into

__all__ = ["ROW_AXES", "parallel_edges", "row_links", "row_path_cover"]

#: Directions (radians from the x axis) the row cover is tried along.
ROW_AXES = (0.0, np.pi / 2)


def parallel_edges(points: np.ndarray, triangles: np.ndarray, angle: float) -> np.ndarray:
    """``(m,)`` local index ``k`` of each triangle's edge ``(v_k, v_k+1)`` most parallel to ``angle``
    (numpy; :func:`row_path_cover` computes it and :func:`row_links` in one compiled kernel,
    :func:`~hammesh.strips._row_kernels.row_links_into`, and the tests compare the two).

    The measure is ``|sin|`` of the angle between edge and axis; a zero-length edge
    (coincident points) counts as parallel.
    """
    p = np.asarray(points, np.float64)[:, :2]
    tri = np.asarray(triangles)
    # coordinates whose differences overflow give inf / nan: any choice is a valid cover
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        e = p[np.roll(tri, -1, axis=1)] - p[tri]  # (m, 3, 2): edge k from v_k to v_k+1
        across = np.abs(e[..., 1] * np.cos(angle) - e[..., 0] * np.sin(angle))
        sine = np.nan_to_num(across / np.hypot(e[..., 0], e[..., 1]), nan=0.0)
    return np.argmin(sine, axis=1)


def row_links(twin: np.ndarray, refused: np.ndarray) -> np.ndarray:
    """``(m, 3)`` linked neighbour across each edge, -1 where either side refuses it.

    ``twin``: ``(3 m,)`` half-edge pairing (-1: no proper neighbour); ``refused``: each
    triangle's refused local edge (:func:`parallel_edges`).
    """
    m = len(refused)
    tw = np.asarray(twin, np.int64).reshape(m, 3)
    u, ku = tw // 3, tw % 3
    ok = (tw >= 0) & (np.arange(3) != refused[:, None])
    ok &= refused[np.where(ok, u, 0)] != ku
    return np.where(ok, u, -1)


def row_path_cover(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, angle: float) -> PathCover:
    """The rows along ``angle`` as a dual path cover (:class:`~hammesh.strips._cover_kernels.PathCover`:
    ``order (m,)``, ``starts (S + 1,)`` int64)."""
    p = np.asarray(points, np.float64)
    tri = np.asarray(triangles)
    m = len(tri)
    link = np.empty((m, 3), np.int64)
    row_links_into(p, tri, np.asarray(twin, np.int64).reshape(-1), np.cos(angle), np.sin(angle), np.empty(m, np.int64), link)
    order = np.empty(m, np.int64)
    starts = np.empty(m + 1, np.int64)
    S = link_paths_into(link, order, starts)
    return PathCover(order, starts[: S + 1].copy())
