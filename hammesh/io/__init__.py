"""Mesh file input and output.

One explicit registry, :data:`FORMATS`, maps a file suffix to its ``(reader, writer)``
pair; nothing registers itself on import.  Every writer validates the mesh first
(:class:`~hammesh.errors.InvalidMeshError`) and writes atomically; every reader raises
:class:`~hammesh.errors.FileFormatError` naming the file.

=========================================  ==========================================
suffixes                                   module
=========================================  ==========================================
``.vtu .vtk .msh .xdmf .obj .ply .stl .off``  :mod:`hammesh.io.meshio_format`
``.vtp``                                   :mod:`hammesh.io.vtk_xml` (through meshio_format)
``.ele .node``                             :mod:`hammesh.io.triangle_format`
=========================================  ==========================================

meshio_format reads through hammesh's own readers where meshio loses data or is slow
(``.obj``: :mod:`~hammesh.io.obj_format`, ``.off``: :mod:`~hammesh.io.off_format`,
``.ply``: :mod:`~hammesh.io.ply_format`, legacy ``.vtk``: :mod:`~hammesh.io.vtk_legacy`,
``.vtp`` and the ``.vtu`` files meshio refuses or reads in part:
:mod:`~hammesh.io.vtk_xml`), and through meshio for the rest.

:func:`read_mesh` is the one mesh-reading entry point of hammesh (``hammesh.strips``,
``hammesh.surface`` and the command line call it): ``dim=2`` planar meshes, ``dim=3``
surfaces, ``dim=None`` whichever the file holds.  Point lists (:func:`read_points`) and
simple polygons (:func:`read_polygon`: ``.poly``, GeoJSON, WKT, text) are read here too;
:func:`check_outputs` checks output paths before a command does any work.

Formats that hold cell data (``.vtu .vtk .msh .xdmf .ply``; ``.ele`` as attributes) store a
:class:`~hammesh.mesh.HamiltonianMesh`'s ``cycle_position``, ``cycle_id``, ``parent``
and ``kind`` per triangle; every format keeps the triangles' order, which is the cycle.
The same formats store the constrained edges and their markers (per-triangle cell data
in ``.vtu .vtk .xdmf``, which hold triangles only, and face properties in ``.ply``; ``line`` elements with named physical
groups in ``.msh``; the ``.poly`` next to a ``.ele``), the regions as named sets
(``marker_<k>``, ``region_<a>``: :mod:`hammesh.io.tags`, read by ``skfem.MeshTri.load``)
and the points' markers.

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

import dataclasses

import numpy as np

from hammesh import params
from hammesh.errors import FileFormatError
from hammesh.io import meshio_format, pvtu, triangle_format
from hammesh.io.paths import check_outputs
from hammesh.io.points_text import read_points
from hammesh.io.polygon_files import read_polygon
from hammesh.io.report import marker_range, write_report
from hammesh.mesh import HamiltonianMesh, Mesh, attribute_name

__all__ = [
    "FORMATS",
    "read_mesh",
    "read_points",
    "read_polygon",
    "write",
    "write_report",
    "check_outputs",
    "supported_suffixes",
    "DATA_SUFFIXES",
    "unwritten_data",
]

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
    ".vtp": (meshio_format.read, meshio_format.write),  # VTK XML PolyData: hammesh.io.vtk_xml
    ".ele": (triangle_format.read_ele, triangle_format.write),
    ".node": (triangle_format.read_ele, triangle_format.write),
    ".pvtu": (pvtu.read, pvtu.write),  # partitioned VTK: an index of .vtu pieces (issue 15)
}


#: Suffixes whose files hold the triangles' attributes and the points' data (the other
#: formats hold geometry).
DATA_SUFFIXES: frozenset[str] = frozenset({".vtu", ".vtk", ".vtp", ".msh", ".xdmf", ".ply", ".ele", ".node", ".pvtu"})


def unwritten_data(mesh: Mesh | HamiltonianMesh, path: str | os.PathLike[str]) -> list[str]:
    """What of ``mesh``'s own data a file ``path`` cannot hold, one line each.

    Every format keeps the triangles and their order; only :data:`DATA_SUFFIXES` keep
    the per-triangle attributes and the per-point data (a file read in brought them:
    ``attribute_names``, ``point_data``).  A command reports these lines instead of
    dropping the data in silence.

    >>> m = Mesh(np.zeros((3, 2)), np.array([[0, 1, 2]]), triangle_attributes=np.ones((1, 1)),
    ...          attribute_names=("region",))
    >>> unwritten_data(m, "out.obj"), unwritten_data(m, "out.vtu")
    (["cell data 'region' (.obj holds geometry only)"], [])
    """
    suffix = Path(path).suffix.lower()
    attrs = np.asarray(mesh.triangle_attributes)
    k = attrs.shape[1] if attrs.ndim == 2 else 0
    names = [attribute_name(tuple(getattr(mesh, "attribute_names", ())), j) for j in range(k)]
    names = list(dict.fromkeys(x.partition("[")[0] if x.endswith("]") else x for x in names))  # v[0], v[1]: v
    points = list(getattr(mesh, "point_data", {}))
    if getattr(mesh, "part", None) is not None:  # (a partitioned mesh's parts: the user asked for them)
        names.append("part")
    if suffix in DATA_SUFFIXES:
        return []
    if suffix in (".obj", ".off") and meshio_format.point_colors(mesh) is not None:
        points.remove("color")  # written as vertex colours
    lost = [f"cell data {x!r} ({suffix} holds geometry only)" for x in names] + [
        f"point data {x!r} ({suffix} holds geometry only)" for x in points]
    segments = np.asarray(getattr(mesh, "segments", np.zeros((0, 2)))).reshape(-1, 2)
    markers = np.asarray(getattr(mesh, "segment_markers", np.zeros(0))).reshape(-1)
    vmarks = getattr(mesh, "vertex_markers", None)
    if len(segments):  # (boundary conditions: a user must learn they are not in the file)
        marked = f" and their markers {marker_range(markers)}" if markers.size and markers.any() else ""
        lost.append(f"{len(segments):,} constrained edges (segments){marked} ({suffix} holds geometry only)")
    if vmarks is not None and np.asarray(vmarks).size and np.asarray(vmarks).any():
        lost.append(f"vertex markers {marker_range(np.asarray(vmarks))} ({suffix} holds geometry only)")
    return lost


def supported_suffixes() -> tuple[str, ...]:
    """The suffixes of :data:`FORMATS`, in registry order."""
    return tuple(FORMATS)


def _lookup(path: str | os.PathLike[str]) -> tuple[Reader, Writer]:
    if not isinstance(path, (str, os.PathLike)):
        raise params.invalid("path", path, "a file path (str or os.PathLike)")
    suffix = Path(path).suffix.lower()
    try:
        return FORMATS[suffix]
    except KeyError:
        shown = repr(suffix) if suffix else "no suffix"
        grid = _VTK_GRID_SUFFIXES.get(suffix)
        if grid is not None:  # VTK opens them; say how to make them a cell list
            raise FileFormatError(
                f"{path}: a VTK {grid} (a structured grid, not a cell list): hammesh reads .vtu/.vtp; "
                "e.g. pyvista: pv.read(path).cast_to_unstructured_grid().save('grid.vtu')"
            ) from None
        raise FileFormatError(
            f"{path}: unknown mesh format ({shown}); supported: {' '.join(FORMATS)}"
        ) from None


#: VTK XML structured datasets, which VTK opens and hammesh does not (no cell list).
_VTK_GRID_SUFFIXES = {".vti": "ImageData", ".vts": "StructuredGrid", ".vtr": "RectilinearGrid"}


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


def read_mesh(path: str | os.PathLike[str], *, dim: int | None = 2, strict: bool = False) -> Mesh:
    """Read a triangle mesh, the format chosen by the suffix.

    Triangles keep their file order, so a Hamiltonian mesh written by :func:`write`
    comes back in cycle order.  Quads and polygons are split into triangles and a
    constant ``z`` is dropped; each such repair is listed in ``mesh.info["repairs"]``.

    Parameters
    ----------
    path : path-like
    dim : {2, 3, None}
        2 (default): a planar mesh, ``points (n, 2)``
        (:class:`~hammesh.errors.NotPlanarError` if ``z`` varies); 3: ``points (n, 3)``
        (``z = 0`` added to planar files); None: whichever the file holds.
    strict : bool
        Refuse a file that needs a repair instead of repairing it.

    Raises
    ------
    FileFormatError
        Unknown suffix, missing, empty, truncated or malformed file.
    InvalidOptionError
        ``dim`` or ``strict`` out of their range.
    """
    reader, _ = _lookup(path)
    if dim is not None and (isinstance(dim, bool) or dim not in (2, 3)):
        raise params.invalid("dim", dim, "2, 3 or None")
    strict = params.flag("strict", strict)
    if reader is meshio_format.read:
        return meshio_format.read(path, dim=dim, strict=strict)
    mesh = reader(path)
    if dim == 3 and mesh.points.shape[1] == 2:
        points3 = np.column_stack([mesh.points, np.zeros(len(mesh.points))])
        mesh = dataclasses.replace(mesh, points=points3)
    return mesh
