"""Quality meshing with Shewchuk's Triangle (PyPI ``triangle``)."""

from __future__ import annotations

import numpy as np

from hammesh.domain import Domain
from hammesh.meshing.options import MeshOptions, format_number
from hammesh.mesh import Mesh

__all__ = ["triangle_switches", "mesh_with_triangle"]


def triangle_switches(domain: Domain, opts: MeshOptions) -> str:
    """Triangle's switch string for ``domain`` and ``opts`` (numbers positional)."""
    sw = "p" if len(domain.segments) else "pc"
    if opts.min_angle is not None:
        sw += "q" + format_number(opts.min_angle)
    if len(domain.regions):
        sw += "A"
        if np.isfinite(domain.regions[:, 3]).any():
            sw += "a"
    if opts.max_area is not None:
        sw += "a" + format_number(opts.max_area)
    if opts.conforming_delaunay:
        sw += "D"
    if opts.max_steiner is not None:
        sw += "S" + str(int(opts.max_steiner))
    return sw + "n"


def mesh_with_triangle(domain: Domain, opts: MeshOptions) -> Mesh:
    """Mesh a validated domain with Triangle (call through ``quality_mesh``)."""
    import triangle

    data: dict[str, np.ndarray] = {"vertices": np.array(domain.vertices, dtype=np.float64)}
    if len(domain.segments):
        data["segments"] = np.array(domain.segments, dtype=np.int32)
        data["segment_markers"] = np.array(domain.segment_markers, dtype=np.int32)[:, None]
    if len(domain.holes):
        data["holes"] = np.array(domain.holes, dtype=np.float64)
    if len(domain.regions):
        reg = np.array(domain.regions, dtype=np.float64)
        reg[~np.isfinite(reg[:, 3]), 3] = -1.0  # Triangle: negative = no regional limit
        data["regions"] = reg
    out = triangle.triangulate(data, triangle_switches(domain, opts))
    tri = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64)
    nbr = np.asarray(out.get("neighbors", np.full((len(tri), 3), -1)), dtype=np.int64)
    # Triangle's neighbour k is opposite vertex k; ours is across edge (k, k+1)
    # (C order: a column gather returns Fortran order, which every consumer would copy)
    nbr = np.ascontiguousarray(nbr[:, [2, 0, 1]]) if len(nbr) else np.zeros((0, 3), dtype=np.int64)
    attrs = np.asarray(out.get("triangle_attributes", np.zeros((len(tri), 0))), dtype=np.float64)
    return Mesh(
        points=np.asarray(out["vertices"], dtype=np.float64),
        triangles=tri,
        segments=np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2),
        segment_markers=np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1),
        triangle_attributes=attrs.reshape(len(tri), -1) if len(tri) else np.zeros((0, 0)),
        neighbors=nbr,
    )
