"""Quality meshing with Shewchuk's Triangle (PyPI ``triangle``)."""

from __future__ import annotations

from typing import Callable

import numpy as np
import triangle  # imported here, not in the forked child (which then imports nothing)

from hammesh.domain import Domain
from hammesh.errors import InvalidDomainError
from hammesh.meshing import options
from hammesh.meshing.options import MeshOptions, format_number
from hammesh.mesh import Mesh

#: An ``np.empty``-like allocator: ``alloc(shape, dtype) -> ndarray``.
Allocator = Callable[..., np.ndarray]

__all__ = ["triangle_switches", "mesh_with_triangle", "refines", "Allocator"]


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
    elif refines(opts):
        sw += "S" + str(options.STEINER_BUDGET)
    return sw + "n"


def refines(opts: MeshOptions) -> bool:
    """Whether Triangle adds points for quality (``-q``, ``-D``), which a thin part of the
    domain can make unbounded (an area bound alone is estimated by ``check_sizes``)."""
    return opts.min_angle is not None or opts.conforming_delaunay


def mesh_with_triangle(domain: Domain, opts: MeshOptions, *, alloc: Allocator = np.empty) -> Mesh:
    """Mesh a validated domain with Triangle (call through ``quality_mesh``).

    ``alloc`` makes the big output arrays (``np.empty``-like; ``run_isolated`` passes
    one whose arrays reach the parent process without a copy). Triangle's own int32
    arrays are converted into them in one pass each.
    """
    data: dict[str, np.ndarray] = {"vertices": np.array(domain.vertices, dtype=np.float64)}
    # Triangle keeps the input's point markers and gives a point it inserts on a
    # segment (and an input point of marker 0 on one) the segment's marker
    data["vertex_markers"] = np.array(domain.vertex_markers, dtype=np.int32)[:, None]
    attributes = getattr(domain, "vertex_attributes", None)
    if attributes is not None and attributes.shape[1]:  # Triangle interpolates them
        data["vertex_attributes"] = np.array(attributes, dtype=np.float64)
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
    added = len(out.get("vertices", ())) - len(data["vertices"])
    if opts.max_steiner is None and refines(opts) and added >= options.STEINER_BUDGET:
        quality = f"min angle {format_number(opts.min_angle)}" if opts.min_angle is not None else "conforming Delaunay"
        raise InvalidDomainError(
            f"the domain needs more than {options.STEINER_BUDGET:,} added points to reach {quality} (a part far "
            "thinner than the whole, or a vertex far from the rest); mesh it in pieces, or give max_steiner "
            "(--max-steiner) to accept a mesh that stops short of the angle"
        )
    raw_tri = out.get("triangles", np.zeros((0, 3), dtype=np.int32)).reshape(-1, 3)
    m = len(raw_tri)
    tri = alloc((m, 3), np.int64)
    tri[...] = raw_tri
    nbr = alloc((m, 3), np.int64)
    raw_nbr = out.get("neighbors")
    if raw_nbr is not None and len(raw_nbr) == m:
        # Triangle's neighbour k is opposite vertex k; ours is across edge (k, k+1)
        nbr[:, 0] = raw_nbr[:, 2]
        nbr[:, 1] = raw_nbr[:, 0]
        nbr[:, 2] = raw_nbr[:, 1]
    else:
        nbr.fill(-1)
    raw_pts = np.asarray(out["vertices"], dtype=np.float64)
    points = alloc(raw_pts.shape, np.float64)
    points[...] = raw_pts
    raw_vm = out.get("vertex_markers")
    vmarks = np.zeros(len(points), np.int64)
    if raw_vm is not None and np.size(raw_vm) == len(points):
        vmarks = alloc(len(points), np.int64)  # (in the shared file: no copy to it later)
        vmarks[...] = np.reshape(raw_vm, -1)
    attrs = np.asarray(out.get("triangle_attributes", np.zeros((m, 0))), dtype=np.float64)
    point_data = {}
    if "vertex_attributes" in data:
        raw_va = np.asarray(out["vertex_attributes"], dtype=np.float64).reshape(len(points), -1)
        point_data = {f"attribute_{j}": np.ascontiguousarray(raw_va[:, j]) for j in range(raw_va.shape[1])}
    return Mesh(
        points=points,
        triangles=tri,
        segments=np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2),
        segment_markers=np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1),
        triangle_attributes=attrs.reshape(m, -1) if m else np.zeros((0, 0)),
        neighbors=nbr,
        vertex_markers=vmarks,
        point_data=point_data,
    )
