"""Reading and writing triangle surfaces (3D points) through :mod:`hammesh.io`, atomically."""

from __future__ import annotations

import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from hammesh.mesh import HamiltonianMesh

__all__ = ["read_surface", "weld_points", "weld_surface", "Welded", "write_surface", "SURFACE_SUFFIXES"]

#: Formats that hold a 3D surface (every mesh format of :mod:`hammesh.io` but Triangle's).
SURFACE_SUFFIXES: tuple[str, ...] = (".obj", ".ply", ".stl", ".off", ".vtu", ".vtk", ".msh", ".xdmf", ".vtp")

def read_surface(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(points (n, 3) float64, triangles (m, 3) int64)`` of a surface file.

    Read by :func:`hammesh.io.read_mesh` (``dim=3``: planar files get ``z = 0``; quads
    and polygons are split into triangles).  Exactly coincident points are then merged
    (STL stores every triangle's corners separately); unused points are kept.

    Raises
    ------
    FileFormatError
        Missing, unreadable, of an unknown format or without triangles.
    """
    from hammesh.errors import FileFormatError
    from hammesh.io import read_mesh

    if Path(path).suffix.lower() not in SURFACE_SUFFIXES:
        raise FileFormatError(f"{path}: unknown surface format; supported: {' '.join(SURFACE_SUFFIXES)}")
    mesh = read_mesh(path, dim=3)
    return weld_points(mesh.points, mesh.triangles)


class Welded(NamedTuple):
    """A surface with coincident points merged (:func:`weld_surface`)."""

    points: np.ndarray  #: (k, d) float64, first-occurrence order
    triangles: np.ndarray  #: (m, 3) int64 into ``points``
    source: np.ndarray  #: (k,) int64: the input point each kept point is


def weld_surface(pts: np.ndarray, tri: np.ndarray, point_data: dict[str, np.ndarray] | None = None) -> Welded:
    """Merge exactly coincident points that also carry equal ``point_data`` values.

    STL stores every triangle's corners separately: welding makes it one surface.  Two
    points at one place with different data (a texture seam: two UVs) stay two points,
    so no value is lost; first-occurrence order is kept, unused points too.
    """
    pts = np.ascontiguousarray(pts)
    tri = np.ascontiguousarray(tri)
    key = pts.reshape(len(pts), -1).astype(np.float64)
    if point_data:
        key = np.column_stack([key] + [np.asarray(v).reshape(len(pts), -1).astype(np.float64)
                                       for v in point_data.values()])
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    if len(first) == len(pts):
        return Welded(pts, tri, np.arange(len(pts), dtype=np.int64))
    order = np.argsort(first)
    rank = np.empty(len(order), np.int64)
    rank[order] = np.arange(len(order))
    source = np.sort(first).astype(np.int64)
    return Welded(np.ascontiguousarray(pts[source]), np.ascontiguousarray(rank[inv.reshape(-1)][tri]), source)


def weld_points(pts: np.ndarray, tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge exactly coincident points (first occurrence order kept); unused points kept."""
    welded = weld_surface(pts, tri)
    return welded.points, welded.triangles


def write_surface(h: HamiltonianMesh, path: str | os.PathLike[str]) -> None:
    """Write a Hamiltonian surface in cycle order, atomically (:func:`hammesh.io.write`).

    ``.vtu .vtk .msh .xdmf`` also carry cell data ``cycle_id``, ``cycle_position``,
    ``parent`` and ``kind``; ``.obj .ply .stl .off`` hold geometry and order only
    (``.stl`` repeats each triangle's corners); ``.ele``/``.node`` hold planar meshes only.
    """
    from hammesh.io import write

    write(h, path)
