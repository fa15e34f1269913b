"""Read and write meshes through meshio (VTU, legacy VTK, Gmsh, XDMF, OBJ, PLY, STL, OFF).

Writing keeps the triangles' row order (for a :class:`~hammesh.mesh.HamiltonianMesh`
that order *is* the cycle) and, where the format can hold cell data (``.vtu``, ``.vtk``,
``.msh``, ``.xdmf``), stores the per-triangle fields of
:func:`hammesh.io.cell_data.triangle_cell_data`: ``cycle_position``, ``cycle_id``,
``parent``, ``kind`` and ``attribute_<i>``.  The other formats get geometry and
connectivity only.

Format notes (meshio 5.3):

* Points are always written with ``z = 0``: OBJ and PLY fail on 2D points and the
  others pad themselves while printing a warning.
* ``.msh`` is written as Gmsh 4.1 binary (meshio's default for ``.msh`` is ANSYS);
  read as Gmsh first, then ANSYS.  Gmsh stores cell data as float64.
* ``.xdmf`` is written with its arrays inline (``data_format="XML"``) so the output is
  one file that can be replaced atomically (the HDF5 default writes a sibling ``.h5``).
* ``.ply`` cells are written as int32 (PLY has no int64).
* ``.stl`` is a triangle soup: reading merges equal points in order of first use, so
  unreferenced points are lost and point indices can change; each triangle's
  coordinates and the triangle order survive.
* Reading calls the per-format readers directly: ``meshio.read`` prints and calls
  ``sys.exit(1)`` when a file is unreadable.
* meshio's PLY and OFF readers loop forever on a file that ends inside its header
  (``readline`` at end of file returns ``""`` and they skip it as a blank line), so
  those headers are checked first.  A binary PLY whose face list is cut short is read
  silently by meshio; the face count of the header is checked afterwards.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.atomic import atomic_path
from hammesh.io.cell_data import ATTRIBUTE_PREFIX, triangle_cell_data
from hammesh.io.validate import validate_mesh
from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["read", "write", "SUFFIXES", "CELL_DATA_SUFFIXES"]

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
}

#: Suffixes handled by this module.
SUFFIXES: tuple[str, ...] = tuple(_FORMATS)

#: Suffixes whose files store the per-triangle cell data.
CELL_DATA_SUFFIXES: frozenset[str] = frozenset({".vtu", ".vtk", ".msh", ".xdmf"})

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

    points = np.asarray(mesh.points, dtype=np.float64)
    points3 = np.column_stack([points, np.zeros(len(points))])
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    if suffix == ".ply":
        triangles = triangles.astype(np.int32)
    segments = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    cells: list[tuple[str, np.ndarray]] = [("triangle", triangles)]
    cell_data: dict[str, list[np.ndarray]] = {}
    point_data: dict[str, np.ndarray] = {}
    if suffix in CELL_DATA_SUFFIXES:
        cell_data = {k: [v] for k, v in triangle_cell_data(mesh).items()}
        if len(segments):
            markers = _segment_markers(mesh)
            if suffix == ".msh":
                cells, cell_data, point_data = _gmsh_blocks(mesh, triangles, segments, markers)
            else:
                cells.append(("line", segments))
                cell_data = _with_line_block(cell_data, markers)
    out = meshio.Mesh(points3, cells, point_data=point_data, cell_data=cell_data)
    with atomic_path(path) as tmp:
        meshio.write(tmp, out, file_format=file_format, **kwargs)


def _segment_markers(mesh: Mesh | HamiltonianMesh) -> np.ndarray:
    """``(s,) int64`` markers of ``mesh.segments`` (zeros if their count is off)."""
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    if len(markers) != len(mesh.segments):
        markers = np.zeros(len(mesh.segments), dtype=np.int64)
    return markers


def _fill(like: np.ndarray, count: int) -> np.ndarray:
    """``count`` filler values of ``like``'s kind: -1 for integers, NaN for floats."""
    if np.issubdtype(like.dtype, np.integer):
        return np.full(count, -1, dtype=like.dtype)
    return np.full(count, np.nan, dtype=np.float64)


def _with_line_block(
    triangle_data: dict[str, list[np.ndarray]], markers: np.ndarray
) -> dict[str, list[np.ndarray]]:
    """Cell data for the blocks ``[triangles, lines]``: each field gets one entry per block."""
    m = len(next(iter(triangle_data.values()))[0]) if triangle_data else None
    data = {k: [v[0], _fill(v[0], len(markers))] for k, v in triangle_data.items()}
    if m is None:  # a plain mesh without attributes: no triangle field to size from
        return {SEGMENT_MARKER: [None, markers]}  # replaced by the caller's count below
    data[SEGMENT_MARKER] = [np.full(m, -1, dtype=np.int64), markers]
    return data
def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    detail = text[0] if text else ""
    return f"{type(exc).__name__}: {detail}" if detail else type(exc).__name__


def _meshio_read(path: Path, formats: tuple[str, ...]) -> Any:
    import meshio

    errors = []
    for fmt in formats:
        reader = getattr(meshio, fmt).read
        try:
            with np.errstate(all="ignore"):
                return reader(str(path))
        except Exception as exc:  # meshio raises anything on a bad file
            errors.append(f"as {fmt}: {_first_line(exc)}")
    raise FileFormatError(f"{path}: cannot read ({'; '.join(errors)})")


_MAX_HEADER_BYTES = 1 << 20


def _check_header(path: Path, suffix: str) -> int | None:
    """Reject PLY/OFF files that end inside their header; return PLY's face count."""
    if suffix not in (".ply", ".off"):
        return None
    with open(path, "rb") as f:
        head = f.read(_MAX_HEADER_BYTES)
    lines = [line.strip() for line in head.splitlines()]
    if suffix == ".off":
        significant = [ln for ln in lines[1:] if ln and not ln.startswith(b"#")]
        if not lines or lines[0] != b"OFF" or not significant:
            raise FileFormatError(f"{path}: not an OFF file or truncated header")
        return None
    if not lines or lines[0] != b"ply" or b"end_header" not in lines:
        raise FileFormatError(f"{path}: not a PLY file or truncated header (no end_header)")
    faces = 0
    for line in lines[: lines.index(b"end_header")]:
        match = re.fullmatch(rb"element\s+face\s+(\d+)", line)
        if match:
            faces = int(match.group(1))
    return faces


def read(path: str | os.PathLike[str]) -> Mesh:
    """Read a planar triangle mesh with meshio.

    Triangles keep their file order (all ``triangle`` blocks, concatenated); ``line``
    blocks become ``segments``; other cell types are ignored.  A ``z`` coordinate that
    is zero everywhere is dropped.  Cell data ``attribute_<i>`` (as written by
    :func:`write`) becomes ``triangle_attributes``; the cycle fields are not part of a
    :class:`Mesh` (read them with ``meshio`` directly).

    Parameters
    ----------
    path : path-like
        One of :data:`SUFFIXES` (case-insensitive).

    Returns
    -------
    Mesh

    Raises
    ------
    FileFormatError
        Missing, empty, truncated or malformed file; no triangles; ``z`` not zero
        everywhere; index out of range.  The message names the file.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: file not found")
    expected_faces = _check_header(path, suffix)
    raw = _meshio_read(path, _FORMATS[suffix][0])
    if expected_faces is not None:
        got = sum(len(block.data) for block in raw.cells)
        if got != expected_faces:
            raise FileFormatError(
                f"{path}: truncated (header declares {expected_faces} faces, found {got})"
            )
    try:
        return _to_mesh(raw, path)
    except FileFormatError:
        raise
    except Exception as exc:  # malformed content that meshio accepted
        raise FileFormatError(f"{path}: malformed mesh ({_first_line(exc)})") from None


def _to_mesh(raw: Any, path: Path) -> Mesh:
    points = np.asarray(raw.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise FileFormatError(f"{path}: points have shape {points.shape}, expected (n, 2) or (n, 3)")
    if points.shape[1] == 3:
        if np.any(points[:, 2] != 0):
            raise FileFormatError(f"{path}: mesh is not planar (z varies)")
        points = points[:, :2]
    points = np.ascontiguousarray(points)
    if not np.isfinite(points).all():
        raise FileFormatError(f"{path}: non-finite point coordinates")

    tri_blocks, seg_blocks, tri_block_ids = [], [], []
    for b, block in enumerate(raw.cells):
        if block.type == "triangle":
            tri_blocks.append(np.asarray(block.data, dtype=np.int64).reshape(-1, 3))
            tri_block_ids.append(b)
        elif block.type == "line":
            seg_blocks.append(np.asarray(block.data, dtype=np.int64).reshape(-1, 2))
    if not tri_blocks or sum(len(t) for t in tri_blocks) == 0:
        raise FileFormatError(f"{path}: no triangles")
    triangles = np.concatenate(tri_blocks)
    segments = np.concatenate(seg_blocks) if seg_blocks else np.zeros((0, 2), np.int64)
    n = len(points)
    for name, arr in (("triangle", triangles), ("line", segments)):
        if arr.size and (arr.min() < 0 or arr.max() >= n):
            bad = int(arr.max() if arr.max() >= n else arr.min())
            raise FileFormatError(
                f"{path}: {name} vertex index {bad} out of range [0, {n})"
            )

    columns: dict[int, np.ndarray] = {}
    for key, per_block in raw.cell_data.items():
        match = _ATTRIBUTE_RE.match(key)
        if match is None:
            continue
        try:
            parts = [np.asarray(per_block[b], dtype=np.float64).reshape(-1) for b in tri_block_ids]
        except (IndexError, ValueError, TypeError):
            continue
        column = np.concatenate(parts)
        if len(column) == len(triangles):
            columns[int(match.group(1))] = column
    keys = sorted(columns)
    if keys and keys == list(range(len(keys))):
        attributes = np.column_stack([columns[k] for k in keys])
    else:
        attributes = np.zeros((len(triangles), 0), dtype=np.float64)

    return Mesh(
        points=points,
        triangles=np.ascontiguousarray(triangles),
        segments=np.ascontiguousarray(segments),
        triangle_attributes=attributes,
    )
