"""Quality meshing with Triangle through ``meshpy`` (second backend)."""

from __future__ import annotations

import numpy as np

from hammesh.domain import Domain
from hammesh.errors import InvalidOptionError
from hammesh.meshing.options import MeshOptions
from hammesh.mesh import Mesh
from hammesh.meshing.triangle_backend import Allocator

__all__ = ["mesh_with_meshpy", "MESHPY_MIN_AREA"]

#: meshpy prints max_volume with ``%.20f``; smaller areas become 0 and meshpy then
#: exits the whole process.
MESHPY_MIN_AREA = 1e-15


def _into(alloc: Allocator, a: np.ndarray) -> np.ndarray:
    out = alloc(a.shape, a.dtype)
    out[...] = a
    return out


def mesh_with_meshpy(domain: Domain, opts: MeshOptions, *, alloc: Allocator = np.empty) -> Mesh:
    """Mesh a validated domain with meshpy (call through ``quality_mesh``).

    ``alloc`` (``np.empty``-like) makes the triangle and point arrays.
    """
    import meshpy.triangle as mt

    if opts.max_area is not None and opts.max_area < MESHPY_MIN_AREA:
        raise InvalidOptionError(
            f"max_area={opts.max_area!r} is below the meshpy backend's limit "
            f"{MESHPY_MIN_AREA:g} (use backend='triangle')"
        )
    if opts.conforming_delaunay or opts.max_steiner is not None:
        raise InvalidOptionError(
            "conforming_delaunay and max_steiner are not supported by the meshpy "
            "backend (use backend='triangle')"
        )
    info = mt.MeshInfo()
    info.set_points(np.array(domain.vertices, dtype=np.float64),
                    point_markers=np.asarray(domain.vertex_markers, dtype=np.int64).tolist())
    if len(domain.segments):
        info.set_facets(
            np.asarray(domain.segments, dtype=np.int64).tolist(),
            facet_markers=np.asarray(domain.segment_markers, dtype=np.int64).tolist(),
        )
    if len(domain.holes):
        info.set_holes(np.asarray(domain.holes, dtype=np.float64).tolist())
    has_regions = len(domain.regions) > 0
    regional_area = has_regions and bool(np.isfinite(domain.regions[:, 3]).any())
    if has_regions:
        info.regions.resize(len(domain.regions))
        for i, (x, y, attr, area) in enumerate(np.asarray(domain.regions).tolist()):
            info.regions[i] = [x, y, attr, area if np.isfinite(area) else -1.0]
    out = mt.build(
        info,
        min_angle=opts.min_angle,
        quality_meshing=opts.min_angle is not None,
        max_volume=opts.max_area,
        attributes=has_regions,
        volume_constraints=regional_area,
        generate_neighbor_lists=True,
    )
    tri = _into(alloc, np.asarray(out.elements, dtype=np.int64).reshape(-1, 3))
    nbr = np.asarray(out.neighbors, dtype=np.int64).reshape(-1, 3)
    nbr = np.ascontiguousarray(nbr[:, [2, 0, 1]]) if len(nbr) == len(tri) else None
    attrs = (
        np.asarray(out.element_attributes, dtype=np.float64).reshape(len(tri), -1)
        if has_regions
        else np.zeros((len(tri), 0))
    )
    return Mesh(
        points=_into(alloc, np.asarray(out.points, dtype=np.float64).reshape(-1, 2)),
        triangles=tri,
        segments=np.asarray(out.facets, dtype=np.int64).reshape(-1, 2),
        segment_markers=np.asarray(out.facet_markers, dtype=np.int64).reshape(-1),
        triangle_attributes=attrs,
        neighbors=nbr,
        vertex_markers=np.asarray(out.point_markers, dtype=np.int64).reshape(-1),
    )
