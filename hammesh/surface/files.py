"""Reading and writing triangle surfaces (3D points) with meshio, atomically."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.mesh import HamiltonianMesh

__all__ = ["read_surface", "write_surface", "SURFACE_SUFFIXES"]

#: suffix -> meshio format name
SURFACE_SUFFIXES = {".obj": "obj", ".ply": "ply", ".stl": "stl", ".off": "off", ".vtu": "vtu", ".vtk": "vtk"}


def _format(path: Path) -> str:
    fmt = SURFACE_SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise FileFormatError(f"{path}: unknown surface format; supported: {' '.join(SURFACE_SUFFIXES)}")
    return fmt


def read_surface(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(points (n, 3) float64, triangles (m, 3) int64)`` of a surface file.

    Exactly coincident points are merged (STL stores every triangle's corners
    separately); unused points are kept. Only ``triangle`` cells are read.

    Raises
    ------
    FileFormatError
        Missing, unreadable, of an unknown format, without triangles, or with quad or
        polygon faces (they would be left out: triangulate first).
    """
    import meshio

    path = Path(path)
    fmt = _format(path)
    if not path.exists():
        raise FileFormatError(f"{path}: no such file")
    try:
        with warnings.catch_warnings():  # meshio's STL sniffing warns on ASCII files
            warnings.simplefilter("ignore")
            mesh = meshio.read(path, file_format=fmt)
    except Exception as exc:  # noqa: BLE001 - meshio raises many kinds
        raise FileFormatError(f"{path}: cannot read as {fmt}: {exc}") from None
    faces = [c.type for c in mesh.cells if c.type in ("quad", "polygon") or c.type.startswith("polygon")]
    if faces:
        raise FileFormatError(f"{path}: has {faces[0]} cells; triangulate the surface first")
    blocks = [c.data for c in mesh.cells if c.type == "triangle"]
    if not blocks or sum(len(b) for b in blocks) == 0:
        raise FileFormatError(f"{path}: no triangle cells")
    pts = np.asarray(mesh.points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise FileFormatError(f"{path}: points have shape {pts.shape}")
    if pts.shape[1] == 2:
        pts = np.c_[pts, np.zeros(len(pts))]
    tri = np.concatenate(blocks).astype(np.int64)
    uniq, first, inv = np.unique(pts, axis=0, return_index=True, return_inverse=True)
    if len(uniq) < len(pts):  # weld duplicates, keeping first-occurrence order
        order = np.argsort(first)
        rank = np.empty(len(order), np.int64)
        rank[order] = np.arange(len(order))
        tri = rank[inv.reshape(-1)][tri]
        pts = pts[np.sort(first)]
    return np.ascontiguousarray(pts), np.ascontiguousarray(tri)


def write_surface(h: HamiltonianMesh, path: str | os.PathLike[str]) -> None:
    """Write a Hamiltonian surface in cycle order, atomically (:func:`hammesh.io.write`).

    ``.vtu .vtk`` also carry cell data ``cycle_id``, ``cycle_position``, ``parent`` and
    ``kind``; ``.obj .ply .stl .off`` hold geometry and order only (``.stl`` repeats
    each triangle's corners).
    """
    from hammesh.io import write

    _format(Path(path))
    write(h, path)
