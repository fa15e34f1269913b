"""Mesh one tile with Triangle, its boundary (separators included) kept unsplit."""

from __future__ import annotations

import numpy as np

from hammesh.errors import MeshingError
from hammesh.mesh import Mesh
from hammesh.meshing.options import format_number
from hammesh.parallel.tiles import Tile

__all__ = ["tile_switches", "mesh_tile", "region_attributes", "locate_in_triangles"]


def region_attributes(tile: Tile, points: np.ndarray, triangles: np.ndarray, neighbors: np.ndarray,
                      segments: np.ndarray) -> np.ndarray:
    """Regional attribute of every triangle, read off the coarse mesh once per region piece.

    Triangle spreads a region's attribute from its point up to the segments around it;
    a tile's part of a region need not hold the point, so the attribute comes from the
    coarse mesh (which Triangle gave the attributes). Region boundaries are segments, so
    the tile's triangles fall into pieces (dual components, never crossing a segment)
    that each lie in one region: one coarse point location per piece, not per
    triangle (locating all of them cost ~1 s per 750k triangles plus the locator).
    """
    from hammesh.parallel._kernels import label_pieces_into

    m, n = len(triangles), len(points)
    values = np.unique(tile.region_attribute)
    if len(values) == 1:  # the tile lies in one region (or in none)
        return np.full(m, values[0])
    seg_keys = np.unique(np.sort(segments, axis=1) @ np.array([n, 1], np.int64))
    on_seg = np.zeros(n, np.bool_)
    on_seg[segments.ravel()] = True
    label = np.empty(m, np.int64)
    label_pieces_into(np.ascontiguousarray(triangles, dtype=np.int64), np.ascontiguousarray(neighbors, dtype=np.int64),
                      seg_keys, on_seg, label)
    # a piece's seed is its lowest triangle, and seeds are taken in order: where the
    # running maximum of the labels steps up
    first = np.flatnonzero(np.diff(np.maximum.accumulate(label), prepend=-1) > 0)
    where = locate_in_triangles(tile.region_points, tile.region_triangles, points[triangles[first]].mean(axis=1))
    if (where < 0).any():
        raise MeshingError(f"tile {tile.index}: a triangle lies outside the coarse mesh (regions)")
    return tile.region_attribute[where][label]


def locate_in_triangles(p: np.ndarray, t: np.ndarray, q: np.ndarray, chunk: int = 64) -> np.ndarray:
    """For each query point, the triangle of ``(p, t)`` holding it most deeply (largest
    smallest barycentric coordinate), -1 if none holds it (tolerance 1e-9). Brute force
    over the triangles, ``chunk`` points at a time: meant for few queries."""
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    det = np.where(det == 0, np.inf, det)
    out = np.full(len(q), -1, np.int64)
    for i in range(0, len(q), chunk):
        x, y = q[i:i + chunk, 0:1], q[i:i + chunk, 1:2]
        l1 = ((b[:, 0] - x) * (c[:, 1] - y) - (b[:, 1] - y) * (c[:, 0] - x)) / det
        l2 = ((c[:, 0] - x) * (a[:, 1] - y) - (c[:, 1] - y) * (a[:, 0] - x)) / det
        depth = np.minimum(np.minimum(l1, l2), 1 - l1 - l2)
        best = depth.argmax(axis=1) if len(t) else np.zeros(len(x), np.int64)
        ok = depth[np.arange(len(x)), best] >= -1e-9 if len(t) else np.zeros(len(x), bool)
        out[i:i + chunk] = np.where(ok, best, -1)
    return out


def tile_switches(min_angle: float | None, max_area: float) -> str:
    """Triangle's switches for a tile: ``-Y`` keeps every boundary segment unsplit.

    ``-Y`` ("no Steiner point on the mesh boundary", Triangle's documentation; ``-YY``
    would also forbid them on interior segments, which the tile does not need): the
    separators are on the tile's boundary, so both tiles along one keep exactly its
    given subsegments. Internal user segments may still be split.
    """
    sw = "p"
    if min_angle is not None:
        sw += "q" + format_number(min_angle)
    return sw + "a" + format_number(max_area) + "YnQ"


def mesh_tile(tile: Tile, min_angle: float | None, max_area: float) -> Mesh:
    """Triangle mesh of one tile, in its local numbering.

    The tile's vertices keep their order (points ``[:len(tile.vertex_ids)]``); Steiner
    points follow. ``info["separator_subsegments"]`` counts the separator edges.
    """
    import triangle

    data = {
        "vertices": np.ascontiguousarray(tile.vertices, dtype=np.float64),
        "segments": np.ascontiguousarray(tile.segments, dtype=np.int32),
        "segment_markers": np.ascontiguousarray(tile.segment_markers, dtype=np.int32)[:, None],
    }
    if len(tile.holes):
        data["holes"] = np.ascontiguousarray(tile.holes, dtype=np.float64)
    out = triangle.triangulate(data, tile_switches(min_angle, max_area))
    tri = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(tri) == 0:
        raise MeshingError(f"Triangle produced no triangles for tile {tile.index}")
    raw_nbr = np.asarray(out["neighbors"], dtype=np.int64).reshape(-1, 3)
    nbr = np.stack([raw_nbr[:, 2], raw_nbr[:, 0], raw_nbr[:, 1]], axis=1)
    pts = np.asarray(out["vertices"], dtype=np.float64)
    if len(pts) < len(tile.vertices) or not np.array_equal(pts[: len(tile.vertices)], tile.vertices):
        raise MeshingError(f"Triangle did not keep tile {tile.index}'s vertices in order")
    segs = np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2)
    attrs = np.zeros((len(tri), 0))
    if len(tile.region_triangles):
        attrs = region_attributes(tile, pts, tri, nbr, segs)[:, None]
    return Mesh(
        points=pts,
        triangle_attributes=attrs,
        triangles=tri,
        segments=segs,
        segment_markers=np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1),
        neighbors=nbr,
        info={"backend": "triangle", "switches": tile_switches(min_angle, max_area), "tile": tile.index},
    )
