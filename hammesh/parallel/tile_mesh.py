"""Mesh one tile with Triangle, its boundary (separators included) kept unsplit."""

from __future__ import annotations

import numpy as np

from hammesh.errors import MeshingError
from hammesh.mesh import Mesh
from hammesh.meshing.options import format_number
from hammesh.parallel.tiles import Tile

__all__ = ["tile_switches", "mesh_tile", "region_attributes"]


def region_attributes(tile: Tile, points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Regional attribute of every triangle: that of the coarse triangle holding its centroid.

    Triangle spreads a region's attribute from its point up to the segments around it;
    a tile's part of a region need not hold the point, so the attribute is read off
    the coarse mesh (which Triangle gave the attributes) instead. Region boundaries
    are segments, so no tile triangle straddles two regions.
    """
    from matplotlib.tri import Triangulation

    rp = tile.region_points
    finder = Triangulation(rp[:, 0], rp[:, 1], tile.region_triangles).get_trifinder()
    c = points[triangles].mean(axis=1)
    where = np.asarray(finder(c[:, 0], c[:, 1]))
    if (where < 0).any():
        raise MeshingError(f"tile {tile.index}: a triangle lies outside the coarse mesh (regions)")
    return tile.region_attribute[where]


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
    attrs = np.zeros((len(tri), 0))
    if len(tile.region_triangles):
        attrs = region_attributes(tile, pts, tri)[:, None]
    return Mesh(
        points=pts,
        triangle_attributes=attrs,
        triangles=tri,
        segments=np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2),
        segment_markers=np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1),
        neighbors=nbr,
        info={"backend": "triangle", "switches": tile_switches(min_angle, max_area), "tile": tile.index},
    )
