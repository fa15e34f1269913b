"""Read and write meshes through meshio (VTU, legacy VTK, Gmsh, XDMF, OBJ, PLY, STL, OFF).

Writing keeps the triangles' row order (for a :class:`~hammesh.mesh.HamiltonianMesh`
that order *is* the cycle) and, where the format can hold cell data (``.vtu``, ``.vtk``,
``.msh``, ``.xdmf``), stores the per-triangle fields of
:func:`hammesh.io.cell_data.triangle_cell_data`: ``cycle_position``, ``cycle_id``,
``parent``, ``kind`` and ``attribute_<i>``, and the points' markers (point data
``vertex_marker``, if any is nonzero).  The other formats get geometry and
connectivity only.  Constrained edges and regions are stored so that FEM codes find
them by name (:mod:`hammesh.io.tags`):

* ``.vtu .vtk .xdmf`` hold **triangles only** (``pyvista.read`` gets a pure triangle
  grid): the constrained edges are the cell data ``segment_edges`` / ``edge_marker``,
  and scikit-fem's ``skfem:b:marker_<k>`` / ``skfem:s:region_<a>`` fields name the
  boundaries and subdomains for ``skfem.MeshTri.load``.  A mesh whose segments are not
  all distinct triangle edges (invalid, but ``hammesh check`` must be able to report
  it) is written as before: ``line`` cells after the triangles with cell data
  ``segment_marker`` (``-1`` on triangles; the triangle fields ``-1`` or NaN on lines).
* ``.msh`` (Gmsh 4.1) has ``line`` elements per marker and named physical groups
  (``$PhysicalNames``: ``marker_<k>`` of dimension 1, ``region_<a>`` of dimension 2;
  see :func:`_gmsh_blocks`), and keeps the point numbering.

Format notes (meshio 5.3):

* Points are always written with ``z = 0``: OBJ and PLY fail on 2D points and the
  others pad themselves while printing a warning.
* ``.vtu`` is written by :mod:`hammesh.io.vtu` (the same file, compressed 3x
  faster); meshio reads it.
* ``.msh`` is written as Gmsh 4.1 binary (meshio's default for ``.msh`` is ANSYS);
  read as Gmsh first, then ANSYS.  Gmsh stores cell data as float64.
* Gmsh 4.1 tags entities, not elements, and meshio writes an entity (with its
  physical tag) only if some node is classified on it; its reader returns the points
  grouped by entity, in file order.  :func:`write` classifies node ``i`` on entity
  ``i`` (entities sorted by dimension, then tag) and every later node on the last one,
  so the file order is the point order and any Gmsh reader (``meshio``,
  ``skfem.MeshTri.load``) gets hammesh's numbering.  The classification says nothing
  about geometry (meshio and Gmsh do not use it).  Files written before stored each
  node's entity (point data ``gmsh_node_entity``); :func:`read` still restores their
  numbering.
* meshio prints warnings to ``sys.stderr`` (via rich): reading redirects them.
* ``.xdmf`` is written with its arrays inline (``data_format="XML"``) so the output is
  one file that can be replaced atomically (the HDF5 default writes a sibling ``.h5``),
  by meshio's ``XdmfWriter`` with the arrays formatted by :mod:`hammesh.io.xdmf_format`.
* ``.obj .off .stl`` are written by hammesh's own writers (:mod:`~hammesh.io.obj_format`,
  :mod:`~hammesh.io.off_format`, :mod:`~hammesh.io.stl_format`, through
  :mod:`hammesh.io.text_rows`): exact and 3-6x faster than meshio's line-by-line
  writers; ``.obj``/``.off`` write a point data ``color`` as vertex colours.
* ``.ply`` is written by :func:`hammesh.io.ply_format.write_ply` (binary): cells as
  int32 (PLY has no int64), and the data the cell-data formats hold (cycle fields,
  attributes, ``segment_edges``/``edge_marker``, vertex markers, point data) as vertex
  and face properties; meshio's writer drops cell data and vector point data.
* ``.stl`` is a triangle soup: reading merges equal points in order of first use, so
  unreferenced points are lost and point indices can change; each triangle's
  coordinates and the triangle order survive.
* Reading calls the per-format readers directly: ``meshio.read`` prints and calls
  ``sys.exit(1)`` when a file is unreadable.
* meshio's PLY and OFF readers loop forever on a file that ends inside its header
  (``readline`` at end of file returns ``""`` and they skip it as a blank line), so
  those headers are checked first.  A binary PLY whose face list is cut short is read
  silently by meshio; the face count of the header is checked afterwards.
* meshio's Gmsh reader trusts the file's counts: a flipped bit in a node tag makes it
  allocate ``max tag + 1`` entries (16 GiB for a tag of 2^31), a string-tag count of
  2^31 makes it read past the end of the file for minutes. ``.msh`` files are read in
  a child process (:func:`hammesh.meshing.isolate.run_isolated`, the result's arrays
  handed back without a copy) whose address space may grow by
  :data:`GMSH_MEMORY_BASE` + :data:`GMSH_MEMORY_PER_BYTE` x the file's size, stopped
  after :data:`GMSH_SECONDS_BASE` + :data:`GMSH_SECONDS_PER_MB` x its megabytes: such
  a file is refused (``FileFormatError``) in seconds, within bounded memory.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

from hammesh.errors import FileFormatError, InvalidMeshError, NotPlanarError
from hammesh.io.atomic import atomic_path
from hammesh.io.paths import require_file
from hammesh.io import tags, vtu
from hammesh.io.raw import RawMesh
from hammesh.io.text_rows import header_token
from hammesh.io.cell_data import ATTRIBUTE_PREFIX, CYCLE_FIELDS, join_components, split_components, triangle_cell_data
from hammesh.io.validate import validate_mesh
from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["read", "to_mesh", "write", "as_meshio", "point_colors", "ply_data", "SUFFIXES", "CELL_DATA_SUFFIXES", "SEGMENT_MARKER"]

#: suffix -> (meshio format names tried when reading, format written, writer kwargs)
_FORMATS: dict[str, tuple[tuple[str, ...], str, dict[str, Any]]] = {
    ".vtu": (("vtu",), "vtu", {}),
    ".vtk": (("vtk",), "vtk", {}),
    ".msh": (("gmsh", "ansys"), "gmsh", {"binary": True}),  # "gmsh" = 4.1
    ".xdmf": (("xdmf",), "xdmf", {"data_format": "XML"}),
    ".obj": (("obj",), "obj", {}),
    ".ply": (("ply",), "ply", {}),
    ".stl": (("stl",), "stl", {}),
    ".off": (("off",), "off", {}),
    ".vtp": ((), "vtp", {}),  # hammesh.io.vtk_xml reads and writes it (meshio has no .vtp)
}

#: Suffixes handled by this module.
SUFFIXES: tuple[str, ...] = tuple(_FORMATS)

#: Suffixes whose files store the per-triangle cell data.
CELL_DATA_SUFFIXES: frozenset[str] = frozenset({".vtu", ".vtk", ".msh", ".xdmf", ".vtp"})

#: Cell data holding each constrained edge's boundary marker (-1 on triangles).
SEGMENT_MARKER = "segment_marker"

#: Gmsh point data: each node's entity (row of the sorted entity list), see :func:`read`.
NODE_ENTITY = "gmsh_node_entity"

_GMSH_TAGS = ("gmsh:physical", "gmsh:geometrical")
#: A Gmsh file's own tags, carried as these attribute columns (``gmsh:`` names are
#: Gmsh's; a ``.msh`` output derives its own from the first column).
_GMSH_COLUMNS = {"gmsh:physical": "physical", "gmsh:geometrical": "geometrical"}
#: Components a Gmsh data field may have (other vectors are written as ``v[j]`` scalars).
_GMSH_COMPONENTS = (1, 3, 9)

_ATTRIBUTE_RE = re.compile(rf"^{ATTRIBUTE_PREFIX}(\d+)$")


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in _FORMATS:
        raise FileFormatError(
            f"{path}: unknown suffix {suffix!r} for meshio (supported: {', '.join(SUFFIXES)})"
        )
    return suffix


def write(mesh: Mesh | HamiltonianMesh, path: str | os.PathLike[str]) -> None:
    """Write ``mesh`` to ``path`` atomically, the format chosen by the suffix.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
        Validated first (:func:`hammesh.io.validate.validate_mesh`).
    path : path-like
        One of :data:`SUFFIXES` (case-insensitive).

    Notes
    -----
    ``.vtu .vtk .xdmf``: cells ``[("triangle", triangles)]`` with the edge and
    ``skfem:`` fields (:mod:`hammesh.io.tags`); ``[("triangle", triangles), ("line",
    segments)]`` if the segments are not all distinct triangle edges.  ``.msh``:
    triangle blocks (runs of equal physical tag, concatenated in row order) then one
    line block per marker, markers ascending.

    Raises
    ------
    InvalidMeshError
        The mesh is not writable (non-finite point, index out of range...).
    FileFormatError
        Unknown suffix.
    """
    import meshio

    path = Path(path)
    suffix = _suffix(path)
    validate_mesh(mesh)
    _, file_format, kwargs = _FORMATS[suffix]
    if suffix == ".ply":  # hammesh's writer: meshio's drops cell data and vector point data
        from hammesh.io.ply_format import write_ply

        points, triangles, point_data, cell_data = ply_data(mesh)
        with atomic_path(path) as tmp:
            write_ply(tmp, points, triangles, point_data=point_data, cell_data=cell_data)
        return
    out = _as_meshio(mesh, suffix, path)
    with atomic_path(path) as tmp:
        if suffix == ".vtu":  # meshio's .vtu writer spends most of its time in zlib
            vtu.write(tmp, out)
        elif suffix == ".vtp":  # (meshio has no .vtp writer)
            from hammesh.io.vtk_xml import write_vtp

            write_vtp(tmp, out)
        elif suffix in _TEXT_WRITERS:  # meshio's text writers format a line per Python call
            _write_text(suffix, tmp, mesh, out)
        else:
            if suffix == ".vtk":  # (legacy VTK names are one word: VTK's own %XX encoding)
                out.point_data = {header_token(k): v for k, v in out.point_data.items()}
                out.cell_data = {header_token(k): v for k, v in out.cell_data.items()}
            meshio.write(tmp, out, file_format=file_format, **kwargs)



#: Suffixes written by hammesh's own vectorised text writers (:mod:`hammesh.io.text_rows`).
_TEXT_WRITERS = frozenset({".obj", ".off", ".stl", ".xdmf"})


def point_colors(mesh: Mesh | HamiltonianMesh) -> np.ndarray | None:
    """The point data ``color`` of ``mesh`` if it is one row of 3 or 4 numbers a point
    (what ``.obj`` and ``.off`` files hold and :func:`write` writes there), else None."""
    colors = getattr(mesh, "point_data", {}).get("color")
    if colors is None:
        return None
    colors = np.asarray(colors)
    ok = colors.ndim == 2 and colors.shape[0] == len(mesh.points) and colors.shape[1] in (3, 4)
    return colors if ok and colors.dtype.kind in "biuf" else None


def ply_data(mesh: Mesh | HamiltonianMesh) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """``(points (n, 3), triangles, point data, cell data)`` that :func:`write` writes to
    ``.ply``: the cycle fields and attributes (:func:`~hammesh.io.cell_data.triangle_cell_data`),
    the constrained edges as ``segment_edges``/``edge_marker`` (:mod:`hammesh.io.tags`),
    the vertex markers and the mesh's point data."""
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    cell_data = triangle_cell_data(mesh)
    slots = tags.segment_slots(triangles, np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2))
    if slots is not None and len(slots.slot):
        cell_data[tags.SEGMENT_EDGES], cell_data[tags.EDGE_MARKER] = tags.edge_fields(mesh, slots)
    return _points3(mesh), triangles, _written_point_data(mesh, {}), cell_data


def _points3(mesh: Mesh | HamiltonianMesh) -> np.ndarray:
    """The points as ``(n, 3)`` float64: 3D surfaces as they are, planar meshes with z = 0."""
    points = np.asarray(mesh.points, dtype=np.float64)
    return points if points.shape[1] == 3 else np.column_stack([points, np.zeros(len(points))])


def _written_point_data(mesh: Mesh | HamiltonianMesh, point_data: dict[str, np.ndarray],
                        components: tuple[int, ...] | None = None) -> dict[str, np.ndarray]:
    """``point_data`` (a format's own fields) with the vertex markers (if any is nonzero)
    and the mesh's point data (``components``: vectors of other sizes split, as Gmsh needs)."""
    vertex_markers = np.asarray(getattr(mesh, "vertex_markers", np.zeros(0)), dtype=np.int64)
    if vertex_markers.shape == (len(mesh.points),) and vertex_markers.any():
        point_data[tags.VERTEX_MARKER] = vertex_markers
    carried = dict(getattr(mesh, "point_data", {}))  # the input's
    if components is not None:
        carried = split_components(carried, components)
    for name, values in carried.items():
        point_data.setdefault(name, np.asarray(values))
    return point_data


def _write_text(suffix: str, tmp: Path, mesh: Mesh | HamiltonianMesh, out: Any) -> None:
    """Write ``out`` (the ``meshio.Mesh`` of ``mesh``) with hammesh's own text writers."""
    triangles = out.cells[0].data
    if suffix == ".obj":
        from hammesh.io.obj_format import write_obj

        write_obj(tmp, out.points, triangles, colors=point_colors(mesh))
    elif suffix == ".off":
        from hammesh.io.off_format import write_off

        write_off(tmp, out.points, triangles, colors=point_colors(mesh))
    elif suffix == ".stl":
        from hammesh.io.stl_format import write_stl

        write_stl(tmp, out.points, triangles)
    else:
        from hammesh.io.xdmf_format import write_xdmf

        write_xdmf(tmp, out)


def as_meshio(mesh: Mesh | HamiltonianMesh, suffix: str = ".vtu") -> Any:
    """The ``meshio.Mesh`` that :func:`write` writes to a file of suffix ``suffix``.

    ``".vtu"`` (also ``.vtk .xdmf``): triangles only, the edge, ``skfem:`` and cycle
    fields as cell data; ``".msh"``: Gmsh blocks with physical tags and names; the
    formats without cell data: points and triangles.  Points get ``z = 0``.

    Raises
    ------
    InvalidMeshError
        The mesh is not writable.
    FileFormatError
        Unknown suffix.
    """
    path = Path(f"mesh{suffix}")
    suffix = _suffix(path)
    validate_mesh(mesh)
    return _as_meshio(mesh, suffix, path)


def _as_meshio(mesh: Mesh | HamiltonianMesh, suffix: str, path: Path) -> Any:
    import meshio

    if suffix == ".ply":  # (what write_ply writes)
        points3, triangles, point_data, cell_data = ply_data(mesh)
        return meshio.Mesh(points3, [("triangle", triangles.astype(np.int32))], point_data=point_data,
                           cell_data={k: [v] for k, v in cell_data.items()})
    points3 = _points3(mesh)  # (3D surfaces, hammesh.surface, as they are)
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    cells: list[tuple[str, np.ndarray]] = [("triangle", triangles)]
    cell_data: dict[str, list[np.ndarray]] = {}
    point_data: dict[str, np.ndarray] = {}
    field_data: dict[str, np.ndarray] = {}
    if suffix in CELL_DATA_SUFFIXES:
        if suffix == ".msh":
            cells, cell_data, point_data, field_data = _gmsh_blocks(mesh, triangles, path)
        else:
            cells, cell_data = _vtk_cells(mesh, triangles)
        point_data = _written_point_data(mesh, point_data, _GMSH_COMPONENTS if suffix == ".msh" else None)
    return meshio.Mesh(points3, cells, point_data=point_data, cell_data=cell_data, field_data=field_data)


def _vtk_cells(
    mesh: Mesh | HamiltonianMesh, triangles: np.ndarray
) -> tuple[list[tuple[str, np.ndarray]], dict[str, list[np.ndarray]]]:
    """Cells and cell data of a ``.vtu .vtk .xdmf`` file (see :func:`write`)."""
    data = triangle_cell_data(mesh)
    segments = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    slots = tags.segment_slots(triangles, segments)
    if slots is None:  # not storable per triangle: explicit line cells
        markers = _segment_markers(mesh)
        cell_data = _with_line_block({k: [v] for k, v in data.items()}, len(triangles), markers)
        return [("triangle", triangles), ("line", segments)], cell_data
    if len(segments):
        flags, edge_marker = tags.edge_fields(mesh, slots)
        data[tags.SEGMENT_EDGES] = flags
        data[tags.EDGE_MARKER] = edge_marker
    data.update(tags.skfem_cell_data(mesh, slots))
    return [("triangle", triangles)], {k: [v] for k, v in data.items()}


def _segment_markers(mesh: Mesh | HamiltonianMesh) -> np.ndarray:
    """``(s,) int64`` markers of ``mesh.segments`` (zeros if their count is off)."""
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    if len(markers) != len(mesh.segments):
        markers = np.zeros(len(mesh.segments), dtype=np.int64)
    return markers


def _fill(like: np.ndarray, count: int) -> np.ndarray:
    """``count`` filler values of ``like``'s kind: -1 for integers, NaN for floats."""
    shape = (count, *np.shape(like)[1:])  # (a vector field's filler is a vector)
    if np.issubdtype(like.dtype, np.integer):
        return np.full(shape, -1, dtype=like.dtype)
    return np.full(shape, np.nan, dtype=np.float64)


def _with_line_block(
    triangle_data: dict[str, list[np.ndarray]], m: int, markers: np.ndarray
) -> dict[str, list[np.ndarray]]:
    """Cell data for the blocks ``[triangles (m), lines]``: one entry per block and field."""
    data = {k: [v[0], _fill(v[0], len(markers))] for k, v in triangle_data.items()}
    data[SEGMENT_MARKER] = [np.full(m, -1, dtype=np.int64), markers]
    return data


def _triangle_physical(mesh: Mesh | HamiltonianMesh) -> tuple[np.ndarray, dict[int, str]]:
    """Gmsh physical tag of each triangle and the names of the tags.

    The first regional attribute if it is integral (and fits an int32), else its rank
    among the distinct values plus 1; named ``region_<a>`` (:func:`hammesh.io.tags.region_name`).
    Without attributes: tag 1, unnamed.
    """
    m = len(mesh.triangles)
    regions = tags.region_values(mesh)
    if regions is None or np.isnan(regions).any():
        return np.ones(m, dtype=np.int64), {}
    values, rank = np.unique(regions, return_inverse=True)
    if np.all(values == np.round(values)) and np.all(np.abs(values) < 2**31):
        physical = regions.astype(np.int64)
        names = {int(v): tags.region_name(v) for v in values}
    else:
        physical = rank.reshape(-1).astype(np.int64) + 1
        names = {i + 1: tags.region_name(v) for i, v in enumerate(values)}
    return physical, names


def _runs(values: np.ndarray) -> list[np.ndarray]:
    """Index arrays of the maximal runs of equal consecutive ``values``."""
    cuts = np.flatnonzero(np.diff(values)) + 1
    return np.split(np.arange(len(values)), cuts)


def _gmsh_blocks(
    mesh: Mesh | HamiltonianMesh, triangles: np.ndarray, path: Path
) -> tuple[list[tuple[str, np.ndarray]], dict[str, list[np.ndarray]], dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Cells, cell data, point data and field data (physical names) of a Gmsh 4.1 file.

    Gmsh 4.1 gives physical tags to entities, not elements, so the triangles are
    split into maximal runs of equal physical tag (one entity each, in row order:
    concatenated they are the triangles unchanged) and the segments are grouped by
    marker (one entity each, markers ascending, file order kept inside a group).
    Physical names (``field_data``): ``marker_<k>`` (dimension 1) and ``region_<a>``
    (dimension 2), which meshio turns into ``cell_sets`` and ``skfem.MeshTri.load``
    into named boundaries and subdomains.

    Each entity needs a node (see the module notes): with more entities than points
    (tiny meshes) the segments and then the triangles are merged into one entity, the
    physical tag of its first cell (names dropped); ``segment_marker`` and
    ``attribute_<i>`` stay exact.
    """
    n, m = len(mesh.points), len(triangles)
    segments = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    markers = _segment_markers(mesh)
    if len(markers) and (markers.min() < -(2**31) or markers.max() >= 2**31):
        bad = int(markers[np.argmax(np.abs(markers))])
        raise InvalidMeshError(f"{path}: segment marker {bad} does not fit Gmsh's 32-bit physical tags")
    physical, region_names = _triangle_physical(mesh)
    order = np.argsort(markers, kind="stable")
    marker_names = {int(k): tags.boundary_name(k) for k in np.unique(markers)}
    tri_runs = _runs(physical)
    line_groups = [order[g] for g in _runs(markers[order])] if len(order) else []
    # (the segments first: their markers stay exact in ``segment_marker``, which hammesh's
    # and meshio's readers take; the triangles' tags are what a solver's materials are
    # read from. Before session 19 the triangles went first: tester18 r06)
    if len(tri_runs) + len(line_groups) > n and line_groups:
        line_groups, marker_names = [order], {}
    if len(tri_runs) + len(line_groups) > n:
        tri_runs, region_names = [np.arange(m)], {}

    # (Gmsh's own tags are re-derived here from the first attribute: not written twice)
    tri_data = split_components({k: v for k, v in triangle_cell_data(mesh).items() if k not in _GMSH_TAGS},
                                _GMSH_COMPONENTS)
    with_lines = bool(line_groups)
    keys = [*tri_data, *([SEGMENT_MARKER] if with_lines else []), *_GMSH_TAGS]
    cells: list[tuple[str, np.ndarray]] = []
    data: dict[str, list[np.ndarray]] = {k: [] for k in keys}
    for tag, rows in enumerate(tri_runs, start=1):
        cells.append(("triangle", triangles[rows]))
        for k, v in tri_data.items():
            data[k].append(v[rows])
        if with_lines:
            data[SEGMENT_MARKER].append(np.full(len(rows), -1, dtype=np.int64))
        data["gmsh:physical"].append(np.full(len(rows), physical[rows[0]], dtype=np.int64))
        data["gmsh:geometrical"].append(np.full(len(rows), tag, dtype=np.int64))
    for tag, rows in enumerate(line_groups, start=1):
        cells.append(("line", segments[rows]))
        for k, v in tri_data.items():
            data[k].append(_fill(v, len(rows)))
        data[SEGMENT_MARKER].append(markers[rows])
        data["gmsh:physical"].append(np.full(len(rows), markers[rows[0]], dtype=np.int64))
        data["gmsh:geometrical"].append(np.full(len(rows), tag, dtype=np.int64))

    # node i on entity i (entities in meshio's sorted order: curves, then surfaces by
    # tag), later nodes on the last entity: the file keeps the point order
    entities = [(1, t) for t in range(1, len(line_groups) + 1)]
    entities += [(2, t) for t in range(1, len(tri_runs) + 1)]
    dim_tags = np.empty((n, 2), dtype=np.int64)
    dim_tags[: len(entities)] = entities
    dim_tags[len(entities):] = entities[-1]
    field_data = {name: np.array([tag, 1]) for tag, name in marker_names.items()}
    field_data.update({name: np.array([tag, 2]) for tag, name in region_names.items()})
    return cells, data, {"gmsh:dim_tags": dim_tags}, field_data


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    detail = text[0] if text else ""
    return f"{type(exc).__name__}: {detail}" if detail else type(exc).__name__


#: What a ``.msh`` read may add to its child's address space: a base (meshio, numpy's
#: work arrays) plus this many times the file's size (a binary node is 32 bytes on
#: disk and ~40 in memory; tag maps of a densely numbered file add 8 per tag).
GMSH_MEMORY_BASE = 1 << 30
GMSH_MEMORY_PER_BYTE = 32
#: Seconds a ``.msh`` read may take: a base plus this many per megabyte (meshio reads
#: ~50 MB/s of binary Gmsh on this project's VM: a 40x margin).
GMSH_SECONDS_BASE = 10.0
GMSH_SECONDS_PER_MB = 0.5


def _guarded_gmsh_read(path: Path, formats: tuple[str, ...]) -> Any:
    """:func:`_meshio_read` of a ``.msh`` file in a child process with a memory and a time
    budget scaled to the file's size (see the module docstring)."""
    from hammesh.errors import MeshingError
    from hammesh.meshing.isolate import run_isolated

    size = path.stat().st_size
    budget = GMSH_MEMORY_BASE + GMSH_MEMORY_PER_BYTE * size
    seconds = GMSH_SECONDS_BASE + GMSH_SECONDS_PER_MB * size / 1e6
    try:
        return run_isolated(_budgeted_meshio_read, (path, formats, budget), name="meshio's Gmsh reader", timeout=round(seconds, 1))
    except MeshingError as exc:  # (stopped, or out of the budget: the file's counts, not the machine)
        raise FileFormatError(f"{path}: {exc} (corrupt counts?)") from None


def _budgeted_meshio_read(path: Path, formats: tuple[str, ...], budget: int) -> Any:
    """:func:`_meshio_read` with this process's address space capped at its size now plus
    ``budget`` bytes (run in :func:`_guarded_gmsh_read`'s child: the cap dies with it)."""
    from hammesh.meshing.isolate import limit_memory

    limit_memory(extra=budget)
    return _meshio_read(path, formats)  # (a MemoryError there is one of its "cannot read" causes)


def _meshio_read(path: Path, formats: tuple[str, ...]) -> Any:
    import meshio

    errors = []
    for fmt in formats:
        reader = getattr(meshio, fmt).read
        said = io.StringIO()
        try:  # meshio prints its warnings (rich, to sys.stderr): a library stays quiet
            with np.errstate(all="ignore"), contextlib.redirect_stderr(said):
                got = reader(str(path))
        except Exception as exc:  # meshio raises anything on a bad file
            errors.append(f"as {fmt}: {_first_line(exc)}")
            continue
        # meshio skips the cells it has no type for (a warning, nothing more): their
        # triangles and segments would be lost in silence (.vtu: hammesh's reader takes them)
        skipped = re.search(r"cells that meshio cannot handle \(([^)]*)\)", said.getvalue())
        if skipped is None:
            return got
        errors.append(f"as {fmt}: meshio skips its cells of {skipped.group(1)}")
    raise FileFormatError(f"{path}: cannot read ({'; '.join(errors)})")


#: Legacy VTK datasets that are grids given by their dimensions, not cells.
_GRID_DATASETS = ("STRUCTURED_POINTS", "STRUCTURED_GRID", "RECTILINEAR_GRID")


def _read_raw(path: Path, suffix: str) -> Any:
    """The file's points and cells: hammesh's own OBJ, OFF, legacy VTK and VTK XML readers, else meshio."""
    if suffix == ".obj":
        from hammesh.io.obj_format import read_obj

        return read_obj(path)
    if suffix == ".off":
        from hammesh.io.off_format import read_off

        return read_off(path)
    if suffix == ".ply":  # (meshio's fails on VTK's face colours, reads ASCII line by line)
        from hammesh.io.ply_format import read_ply

        return read_ply(path)
    if suffix == ".vtp":  # (meshio has no .vtp reader)
        from hammesh.io.vtk_xml import read_vtk_xml

        return read_vtk_xml(path)
    if suffix == ".vtu":
        try:  # meshio's reader is the faster (0.40 vs 0.56 s CPU at 1.6M triangles) ...
            return _meshio_read(path, _FORMATS[suffix][0])
        except FileFormatError:  # ... but refuses files VTK reads: LZ4, a compressor named on
            from hammesh.io.vtk_xml import read_vtk_xml  # ASCII arrays; ours says what is wrong

            return read_vtk_xml(path)
    if suffix == ".vtk":
        from hammesh.io.vtk_legacy import DATASETS, dataset_type, read_legacy

        dataset = dataset_type(path)
        if dataset in DATASETS:
            return read_legacy(path)
        if dataset in _GRID_DATASETS:  # (meshio fails on them with a TypeError)
            raise FileFormatError(
                f"{path}: a {dataset} dataset (a structured grid, not a cell list): hammesh reads "
                f"{' and '.join(DATASETS)}; e.g. pyvista: "
                "pv.read(path).cast_to_unstructured_grid().save('grid.vtu')"
            )
    if suffix == ".msh" and sys.platform.startswith("linux"):  # (its counts: see the module docstring)
        return _guarded_gmsh_read(path, _FORMATS[suffix][0])
    return _meshio_read(path, _FORMATS[suffix][0])


def read(path: str | os.PathLike[str], *, dim: int | None = 2, strict: bool = False) -> Mesh:
    """Read a triangle mesh with meshio (OBJ, OFF and legacy VTK: hammesh's readers).

    Triangles keep their file order (all cell blocks, concatenated); quads and polygons
    are split into triangles in place (:func:`hammesh.io.polygons.triangulate_cells`);
    ``line`` blocks become ``segments`` and their cell data ``segment_marker`` (else
    ``gmsh:physical``, else 0) ``segment_markers``; ``vertex`` cells are ignored; other
    cell types (volumes, second-order cells) are refused.  Cell data ``attribute_<i>``
    (as written by :func:`write`) becomes ``triangle_attributes``; the cycle fields are
    not part of a :class:`Mesh` (read them with ``meshio`` directly).  What was changed
    to accept the file is listed in ``mesh.info["repairs"]``.

    Parameters
    ----------
    path : path-like
        One of :data:`SUFFIXES` (case-insensitive).
    dim : {2, 3, None}
        2: a planar mesh (``z`` dropped if constant, refused with
        :class:`~hammesh.errors.NotPlanarError` if it varies); 3: ``(n, 3)`` points
        (planar files get ``z = 0``); None: 2 if planar, else 3.
    strict : bool
        Refuse (:class:`~hammesh.errors.FileFormatError`) a file that would need a repair.

    Returns
    -------
    Mesh

    Raises
    ------
    FileFormatError
        Missing, empty, truncated or malformed file; no triangles; index out of range.
        The message names the file.
    """
    path = Path(path)
    suffix = _suffix(path)
    require_file(path)
    try:
        raw = _read_raw(path, suffix)
        return to_mesh(raw, path, dim=dim, strict=strict)
    except FileFormatError:
        raise
    except MemoryError:
        raise FileFormatError(f"{path}: sizes beyond this machine's memory (corrupt counts?)") from None
    except Exception as exc:  # malformed content that meshio accepted
        raise FileFormatError(f"{path}: malformed mesh ({_first_line(exc)})") from None


_IGNORED_CELLS = frozenset({"vertex"})
_POLYGON_CELLS = frozenset({"quad", "polygon"})


def _drop_zero_area(points: np.ndarray, triangles: np.ndarray, origin: list[tuple[int, np.ndarray]], path: Path,
                    strict: bool, repairs: list[str]) -> tuple[np.ndarray, list[tuple[int, np.ndarray]]]:
    """A planar mesh file's triangles without those of zero area (exact test), as VTK
    keeps them but no Hamiltonian mesh can (a zero angle): they hold no area, so the
    domain is the same; the repair is reported (refused with ``strict``). Points spanning
    less than ``MIN_EXTENT`` are refused first: there the exact test itself underflows
    and would call triangles of positive area flat."""
    from hammesh.domain.validate import check_extent
    from hammesh.predicates import orient_rows

    check_extent(points, FileFormatError, str(path))
    p = points[triangles]
    flat = orient_rows(np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1]),
                       np.ascontiguousarray(p[:, 2])) == 0
    if not flat.any():
        return triangles, origin
    k = int(flat.sum())
    if k == len(triangles):
        raise FileFormatError(f"{path}: every triangle has zero area: no planar mesh")
    what = f"dropped {k} zero-area triangle{'s' if k != 1 else ''} (no area: the domain is unchanged)"
    if strict:
        raise FileFormatError(f"{path}: needs repairs, refused (strict): {what}")
    repairs.append(what)
    keep = ~flat
    ends = np.cumsum([len(rows) for _, rows in origin])
    kept_origin = [(b, rows[keep[end - len(rows):end]]) for (b, rows), end in zip(origin, ends.tolist())]
    return np.ascontiguousarray(triangles[keep]), kept_origin


def _planar(points: np.ndarray, path: Path, dim: int | None, repairs: list[str]) -> np.ndarray:
    """Points with the ``dim`` asked for (see :func:`read`)."""
    if points.shape[1] == 2:
        return points if dim != 3 else np.column_stack([points, np.zeros(len(points))])
    if dim == 3:
        return points
    z = points[:, 2]
    if not len(z) or np.all(z == z[0]):  # (no points: nothing varies; "no triangles" follows)
        if len(z) and z[0] != 0:
            repairs.append(f"all points at z = {z[0]:.17g}: read as a planar mesh (written at z = 0)")
        return points[:, :2]
    if dim is None:
        return points
    lo, hi = float(z.min()), float(z.max())
    raise NotPlanarError(
        f"{path}: mesh is not planar (z varies from {lo:.6g} to {hi:.6g}); "
        "3D surfaces are for 'hammesh strip' and 'hammesh surface'"
    )


def to_mesh(raw: Any, path: Path, *, dim: int | None = 2, strict: bool = False) -> Mesh:
    """A :class:`Mesh` from a ``meshio.Mesh`` or :class:`~hammesh.io.raw.RawMesh` (see :func:`read`)."""
    repairs: list[str] = []
    points = np.asarray(raw.points, dtype=np.float64)
    if points.size == 0:  # (an empty STL solid: meshio gives points of shape (0,))
        raise FileFormatError(f"{path}: no points, no triangles")
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise FileFormatError(f"{path}: points have shape {points.shape}, expected (n, 2) or (n, 3)")
    if not np.isfinite(points).all():
        raise FileFormatError(f"{path}: non-finite point coordinates")
    points = _planar(points, path, dim, repairs)
    to_original = _gmsh_node_order(raw)
    if to_original is not None:
        restored = np.empty_like(points)
        restored[to_original] = points
        points = restored
    points = np.ascontiguousarray(points)
    n = len(points)

    tri_blocks, seg_blocks, tri_origin, seg_block_ids = [], [], [], []
    split: dict[str, list[int]] = {}
    refused: list[str] = []
    for b, block in enumerate(raw.cells):
        kind = block.type
        data = np.asarray(block.data, dtype=np.int64)
        if to_original is not None and data.size:
            data = to_original[data]
        if data.ndim != 2:
            raise FileFormatError(f"{path}: {kind} cells of mixed size")
        if data.size and (data.min() < 0 or data.max() >= n):
            bad = int(data.max() if data.max() >= n else data.min())
            raise FileFormatError(f"{path}: {kind} vertex index {bad} out of range [0, {n})")
        if kind == "triangle":
            tri_blocks.append(data.reshape(-1, 3))
            tri_origin.append((b, np.arange(len(data), dtype=np.int64)))
        elif kind in _POLYGON_CELLS or (kind.startswith("polygon") and data.shape[1] >= 3):
            from hammesh.io.polygons import triangulate_cells

            tris, origin = triangulate_cells(points, data)
            tri_blocks.append(tris)
            tri_origin.append((b, origin))
            count = split.setdefault(f"{data.shape[1]}", [0, 0])
            count[0] += len(data)
            count[1] += len(tris)
        elif kind == "line":
            seg_blocks.append(data.reshape(-1, 2))
            seg_block_ids.append(b)
        elif kind not in _IGNORED_CELLS:
            refused.append(kind)
    if refused:
        raise FileFormatError(
            f"{path}: has {refused[0]} cells; hammesh reads triangles, quads, polygons and lines"
        )
    for corners, (cells, tris) in split.items():
        what = "quad" if corners == "4" else f"{corners}-gon"
        repairs.append(f"triangulated {cells} {what}{'s' if cells != 1 else ''} ({tris} triangles)")
    if strict and repairs:
        raise FileFormatError(f"{path}: needs repairs, refused (strict): {'; '.join(repairs)}")
    if not tri_blocks or sum(len(t) for t in tri_blocks) == 0:
        raise FileFormatError(f"{path}: no triangles")
    triangles = np.concatenate(tri_blocks)
    if points.shape[1] == 2:
        triangles, tri_origin = _drop_zero_area(points, triangles, tri_origin, path, strict, repairs)
    segments = np.concatenate(seg_blocks) if seg_blocks else np.zeros((0, 2), np.int64)

    # hammesh's readers: what the file said beside its cells (a meshio.Mesh's .info is its own)
    read_info = dict(raw.info) if isinstance(raw, RawMesh) else {}
    not_carried: list[str] = list(read_info.pop("not_carried", []))
    attributes, names = _attribute_columns(raw.cell_data, tri_origin, len(triangles), not_carried)
    point_data = _point_data(raw.point_data, to_original, n, not_carried)

    markers, marker_key = np.zeros(len(segments), dtype=np.int64), None
    for key in (SEGMENT_MARKER, "gmsh:physical"):
        column = _block_column(raw.cell_data.get(key), seg_block_ids, len(segments))
        if column is not None and np.all(column == np.round(column)):
            markers, marker_key = column.astype(np.int64), key
            break
    if seg_blocks:
        markers, marker_key = _line_cell_data(raw.cell_data, seg_block_ids, markers, marker_key, not_carried)
    if not seg_blocks:
        from_fields = _edge_field_segments(raw.cell_data, tri_origin, triangles)
        if from_fields is not None:
            segments, markers = from_fields

    info: dict[str, Any] = {"repairs": repairs} if repairs else {}
    info.update(read_info)
    if not_carried:
        info["not_carried"] = not_carried
    if "cycle_position" in raw.cell_data:  # a Hamiltonian mesh's own fields: `hammesh check` compares them
        fields = {k: _origin_values(raw.cell_data[k], tri_origin, len(triangles)) for k in CYCLE_FIELDS
                  if k in raw.cell_data}
        info["cycle_fields"] = {k: v for k, v in fields.items() if v is not None and v.ndim == 1}
    return Mesh(
        points=points,
        triangles=np.ascontiguousarray(triangles),
        segments=np.ascontiguousarray(segments),
        segment_markers=markers,
        triangle_attributes=attributes,
        info=info,
        vertex_markers=_vertex_markers(raw.point_data, to_original, n),
        attribute_names=names,
        point_data=point_data,
    )


#: Cell data that hammesh writes about its own output (re-derived on every write, so
#: never read back as the user's data); ``attribute_<i>`` are read as attributes.
_OWN_CELL_DATA = frozenset({SEGMENT_MARKER, tags.SEGMENT_EDGES, tags.EDGE_MARKER})
#: The cycle's own fields: skipped only in a Hamiltonian mesh hammesh wrote (it has
#: ``cycle_position``); in anyone else's file a field named ``kind`` or ``part`` is data.
_CYCLE_CELL_DATA = frozenset(CYCLE_FIELDS)
#: Point data hammesh writes about its own output (``vertex_marker`` is read as markers).
_OWN_POINT_DATA = frozenset({tags.VERTEX_MARKER, NODE_ENTITY, "gmsh:dim_tags"})


def _relabels(a: np.ndarray, b: np.ndarray) -> bool:
    """True if ``a`` and ``b`` partition the rows alike (each a one-to-one relabelling of the other)."""
    if a.shape != b.shape:
        return False
    pairs = np.unique(np.stack([a, b], axis=1), axis=0)
    return len(pairs) == len(np.unique(a)) == len(np.unique(b))


def _attribute_columns(
    cell_data: Any, origin: list[tuple[int, np.ndarray]], m: int, not_carried: list[str]
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Every numeric per-triangle cell data array as ``triangle_attributes`` columns.

    ``attribute_<i>`` (hammesh's and Triangle's unnamed attributes) come first, in
    order; then every other field in file order under its own name (a field of ``c``
    components gives columns ``name[0]`` ... ``name[c-1]``).  hammesh's own output
    fields (:data:`_OWN_CELL_DATA`, ``skfem:``, and :data:`_CYCLE_CELL_DATA` in a
    Hamiltonian mesh it wrote) are skipped, and so are Gmsh's tags in
    a Hamiltonian mesh or attribute-carrying file hammesh wrote (it derives them); in any
    other Gmsh file the physical and elementary tags are kept as the columns
    ``physical`` and ``geometrical`` (:data:`_GMSH_COLUMNS`); ``physical``, first, is
    written back as the physical tags of a ``.msh`` output (:func:`_triangle_physical`).
    A field that is not numbers is listed in ``not_carried``.
    """
    numbered: dict[int, np.ndarray] = {}
    named: list[tuple[str, np.ndarray]] = []
    # hammesh's .msh files: the entity tags are runs of rows, and the physical tags
    # repeat the first attribute when there is one
    hamiltonian = "cycle_position" in cell_data
    ours = hamiltonian or any(_ATTRIBUTE_RE.match(k) for k in cell_data)
    for key, per_block in cell_data.items():
        if (key in _OWN_CELL_DATA or (hamiltonian and key in _CYCLE_CELL_DATA) or key.startswith("skfem:")
                or (ours and key in _GMSH_TAGS)):
            continue
        values = _origin_values(per_block, origin, m)
        if values is None:
            not_carried.append(f"cell data {key!r} (not one number or vector per triangle)")
            continue
        match = _ATTRIBUTE_RE.match(key)
        key = _GMSH_COLUMNS.get(key, key)
        if match is not None and values.ndim == 1:
            numbered[int(match.group(1))] = values
        elif values.ndim == 1:
            named.append((key, values))
        else:
            named += [(f"{key}[{j}]", values[:, j]) for j in range(values.shape[1])]
    # Gmsh's tags carry information only if they vary and are no relabelling of another
    # column (a hammesh .msh derives them from the first column, or writes 1 without
    # attributes; a Gmsh file with one entity per physical group repeats the physical tags)
    others = [v for name, v in named if name not in _GMSH_COLUMNS.values()] + list(numbered.values())
    physical = [v for name, v in named if name == "physical"]
    named = [(name, v) for name, v in named if name not in _GMSH_COLUMNS.values() or not (
        np.all(v == v[0]) or any(np.array_equal(v, o) for o in others)
        or (name == "geometrical" and any(_relabels(v, o) for o in others + physical)))]
    keys = sorted(numbered)
    if keys != list(range(len(keys))):  # a gap: keep them all, by name
        named = [(f"{ATTRIBUTE_PREFIX}{k}", numbered[k]) for k in keys] + named
        keys = []
    columns = [numbered[k] for k in keys] + [v for _, v in named]
    if not columns:
        return np.zeros((m, 0), dtype=np.float64), ()
    names = tuple(f"{ATTRIBUTE_PREFIX}{k}" for k in keys) + tuple(name for name, _ in named)
    return np.column_stack(columns).astype(np.float64), names if named else ()


def _origin_values(per_block: Any, origin: list[tuple[int, np.ndarray]], m: int) -> np.ndarray | None:
    """``(m,)`` or ``(m, c)`` float64 values of the triangle-making blocks (a split
    polygon's value repeated); None if not numbers or not one row per cell."""
    if per_block is None or not origin:
        return None
    try:
        parts = []
        for b, rows in origin:
            block = np.asarray(per_block[b])
            if block.dtype.kind not in "biuf" or block.ndim == 0:
                return None
            parts.append(block.reshape(len(block), -1)[rows].astype(np.float64))
        values = np.concatenate(parts)
    except (IndexError, ValueError, TypeError):
        return None
    if len(values) != m or values.shape[1] == 0:
        return None
    return values[:, 0] if values.shape[1] == 1 else values


def _point_data(point_data: Any, to_original: np.ndarray | None, n: int, not_carried: list[str]) -> dict[str, np.ndarray]:
    """The file's point data (in point order) other than hammesh's own fields."""
    data: dict[str, np.ndarray] = {}
    for key, values in (point_data or {}).items():
        if key in _OWN_POINT_DATA:
            continue
        arr = np.asarray(values)
        if arr.dtype.kind not in "biuf" or arr.ndim == 0 or len(arr) != n:
            not_carried.append(f"point data {key!r} (not one number or vector per point)")
            continue
        arr = arr.reshape(n, -1) if arr.ndim > 2 else arr
        if to_original is not None:
            restored = np.empty_like(arr)
            restored[to_original] = arr
            arr = restored
        data[key] = arr
    return join_components(data)


def _vertex_markers(point_data: Any, to_original: np.ndarray | None, n: int) -> np.ndarray:
    """Point data ``vertex_marker`` in point order, zeros if missing or not integral."""
    values = point_data.get(tags.VERTEX_MARKER) if point_data else None
    if values is None:
        return np.zeros(n, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    if len(values) != n or not np.all(values == np.round(values)):
        return np.zeros(n, dtype=np.int64)
    if to_original is not None:
        restored = np.empty_like(values)
        restored[to_original] = values
        values = restored
    return values.astype(np.int64)


def _edge_field_segments(
    cell_data: Any, origin: list[tuple[int, np.ndarray]], triangles: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """Segments stored as the cell data ``segment_edges`` / ``edge_marker``
    (:mod:`hammesh.io.tags`); None if absent or malformed, or if the triangles are not
    the file's cells one for one (a split polygon)."""
    flags_blocks = cell_data.get(tags.SEGMENT_EDGES)
    marker_blocks = cell_data.get(tags.EDGE_MARKER)
    if flags_blocks is None or marker_blocks is None:
        return None
    try:
        flags = np.concatenate([np.asarray(flags_blocks[b]).reshape(-1)[rows] for b, rows in origin])
        marks = np.concatenate([np.asarray(marker_blocks[b]).reshape(-1, 3)[rows] for b, rows in origin])
    except (IndexError, ValueError, TypeError):
        return None
    if len(flags) != len(triangles) or len(marks) != len(triangles):
        return None
    if any(len(rows) != len(np.asarray(flags_blocks[b]).reshape(-1)) for b, rows in origin):
        return None
    flags = flags.astype(np.float64)
    marks = marks.astype(np.float64)
    if not (np.all(flags == np.round(flags)) and np.all(marks == np.round(marks))):
        return None
    return tags.segments_from_edge_fields(triangles, flags.astype(np.int64), marks.astype(np.int64))


def _line_cell_data(cell_data: Any, seg_block_ids: list[int], markers: np.ndarray, marker_key: str | None,
                    not_carried: list[str]) -> tuple[np.ndarray, str | None]:
    """The line cells' other fields: the first whole-numbered one becomes the segment
    markers when no ``segment_marker`` or Gmsh physical tag gave them (a VTK file's
    boundary-condition ids on its lines: they reach the output as ``edge_marker``); any
    other field with a nonzero value on a line is listed in ``not_carried`` (one marker per
    segment is what a planar straight-line graph holds). Zeros carry nothing."""
    n = len(markers)
    for key, per_block in cell_data.items():
        if key == marker_key or key in _OWN_CELL_DATA or key in _CYCLE_CELL_DATA or key.startswith(("gmsh:", "skfem:")):
            continue
        column = _block_column(per_block, seg_block_ids, n)
        if column is None or not np.any(column != 0):
            continue
        whole = bool(np.all(np.isfinite(column)) and np.all(column == np.round(column))
                     and np.abs(column).max() <= np.iinfo(np.int32).max)
        if marker_key is None and whole:
            markers, marker_key = column.astype(np.int64), key
        else:
            why = f"a segment holds one marker: {marker_key!r} gave them" if marker_key else "not whole numbers"
            not_carried.append(f"cell data {key!r} on {n} line cells ({why})")
    return markers, marker_key


def _block_column(per_block: Any, block_ids: list[int], length: int) -> np.ndarray | None:
    """Cell data ``per_block`` of the blocks ``block_ids``, concatenated, as float64;
    None if missing, malformed or not ``length`` long."""
    if per_block is None or not block_ids:
        return None
    try:
        parts = [np.asarray(per_block[b], dtype=np.float64).reshape(-1) for b in block_ids]
    except (IndexError, ValueError, TypeError):
        return None
    column = np.concatenate(parts)
    return column if len(column) == length else None


def _gmsh_node_order(raw: Any) -> np.ndarray | None:
    """For a Gmsh file written by :func:`write`: file position -> original point index.

    meshio's Gmsh reader returns the nodes in file order, grouped by entity, and drops
    the node tags.  :func:`write` stores each node's entity (its row in the sorted
    entity list) as point data in tag order; meshio's writer groups the nodes by that
    row, ascending index inside a group, so a stable sort of the rows is the file
    order.  None (keep the file order) for any other file.
    """
    codes = raw.point_data.get(NODE_ENTITY)
    dim_tags = raw.point_data.get("gmsh:dim_tags")
    n = len(raw.points)
    if codes is None or dim_tags is None:
        return None
    codes = np.asarray(codes, dtype=np.float64).reshape(-1)
    dim_tags = np.asarray(dim_tags)
    if len(codes) != n or dim_tags.shape != (n, 2) or np.any(codes != np.round(codes)):
        return None
    codes = codes.astype(np.int64)
    to_original = np.argsort(codes, kind="stable")
    _, file_codes = np.unique(dim_tags, axis=0, return_inverse=True)
    if not np.array_equal(file_codes.reshape(-1), codes[to_original]):
        return None
    return to_original
