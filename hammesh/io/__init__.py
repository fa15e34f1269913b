"""Mesh file input and output.

One explicit registry, :data:`FORMATS`, maps a file suffix to its ``(reader, writer)``
pair; nothing registers itself on import.  Every writer validates the mesh first
(:class:`~hammesh.errors.InvalidMeshError`) and writes atomically; every reader raises
:class:`~hammesh.errors.FileFormatError` naming the file.

=========================================  ==========================================
suffixes                                   module
=========================================  ==========================================
``.vtu .vtk .msh .xdmf .obj .ply .stl .off``  :mod:`hammesh.io.meshio_format`
``.ele .node``                             :mod:`hammesh.io.triangle_format`
=========================================  ==========================================

Formats that hold cell data (``.vtu .vtk .msh .xdmf``; ``.ele`` as attributes) store a
:class:`~hammesh.mesh.HamiltonianMesh`'s ``cycle_position``, ``cycle_id``, ``parent``
and ``kind`` per triangle; every format keeps the triangles' order, which is the cycle.
The same formats store the constrained edges and their markers (``line`` cells with
``segment_marker``, Gmsh physical tags in ``.msh``; the ``.poly`` next to a ``.ele``).

Examples
--------
>>> import os, tempfile, numpy as np
>>> from hammesh.mesh import Mesh
>>> mesh = Mesh(np.array([[0., 0.], [1., 0.], [0., 1.]]), np.array([[0, 1, 2]]))
>>> path = os.path.join(tempfile.mkdtemp(), "one.vtu")
>>> write(mesh, path)
>>> read_mesh(path).triangles.tolist()
[[0, 1, 2]]
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from hammesh.errors import FileFormatError
from hammesh.io import meshio_format, triangle_format
from hammesh.io.report import write_report
from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["FORMATS", "read_mesh", "write", "write_report", "supported_suffixes"]

Reader = Callable[[str | os.PathLike[str]], Mesh]
Writer = Callable[[Mesh | HamiltonianMesh, str | os.PathLike[str]], None]

#: suffix -> (reader, writer).  Suffixes are matched case-insensitively.
FORMATS: dict[str, tuple[Reader, Writer]] = {
    ".vtu": (meshio_format.read, meshio_format.write),
    ".vtk": (meshio_format.read, meshio_format.write),
    ".msh": (meshio_format.read, meshio_format.write),
    ".xdmf": (meshio_format.read, meshio_format.write),
    ".obj": (meshio_format.read, meshio_format.write),
    ".ply": (meshio_format.read, meshio_format.write),
    ".stl": (meshio_format.read, meshio_format.write),
    ".off": (meshio_format.read, meshio_format.write),
    ".ele": (triangle_format.read_ele, triangle_format.write),
    ".node": (triangle_format.read_ele, triangle_format.write),
}


def supported_suffixes() -> tuple[str, ...]:
    """The suffixes of :data:`FORMATS`, in registry order."""
    return tuple(FORMATS)


def _lookup(path: str | os.PathLike[str]) -> tuple[Reader, Writer]:
    suffix = Path(path).suffix.lower()
    try:
        return FORMATS[suffix]
    except KeyError:
        shown = repr(suffix) if suffix else "no suffix"
        raise FileFormatError(
            f"{path}: unknown mesh format ({shown}); supported: {' '.join(FORMATS)}"
        ) from None


def write(mesh: Mesh | HamiltonianMesh, path: str | os.PathLike[str]) -> None:
    """Write ``mesh`` to ``path``, the format chosen by the suffix, atomically.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
    path : path-like
        Suffix in :data:`FORMATS`.  ``.ele``/``.node`` write the ``.node``, ``.poly``
        and ``.ele`` triple.

    Raises
    ------
    FileFormatError
        Unknown suffix (the message lists the supported ones).
    InvalidMeshError
        Non-finite point, index out of range, inconsistent cycle fields.
    """
    _, writer = _lookup(path)
    writer(mesh, path)


def read_mesh(path: str | os.PathLike[str]) -> Mesh:
    """Read a planar triangle mesh, the format chosen by the suffix.

    Triangles keep their file order, so a Hamiltonian mesh written by :func:`write`
    comes back in cycle order.

    Raises
    ------
    FileFormatError
        Unknown suffix, missing, empty, truncated or malformed file.
    """
    reader, _ = _lookup(path)
    return reader(path)
