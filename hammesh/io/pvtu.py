"""Partitioned VTK (``.pvtu``): an index listing ``.vtu`` pieces, for meshes beyond RAM.

hammesh's parallel meshing (``hammesh mesh ... --partitioned -o DIR``) has every worker
write its tile's piece (:func:`write_piece`); the driver writes the index
(:func:`write_index`), pieces listed in the order the cycle first enters them. Each
piece stores its points with point data ``global_id`` (a point shared by two pieces
has one id) and its triangles in cycle order with cell data ``global_position``
(place in the whole output), ``parent``, ``kind``, the regional attributes and, when
the output has more than one cycle, ``cycle_id`` and ``cycle_position`` (with one
cycle they would be all zeros and ``global_position`` again: 16 of ~80 bytes per
row, not written; :data:`CYCLE_CELL_DATA`), ``part`` with ``--parts``. The index
lists exactly the arrays its pieces hold.

:func:`read` stitches the pieces back into one mesh in cycle order (``hammesh check
index.pvtu`` re-verifies it like any mesh file); :func:`write` writes any mesh as a
one-piece index (the registry's writer). The format is VTK's own (``PUnstructuredGrid``,
what ParaView opens); pieces are ``.vtu`` files with raw appended binary arrays
(``header_type="UInt64"``, what ParaView and meshio read), written and read here
directly; pieces written by other tools are read by meshio.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io import vtu
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions

__all__ = ["read", "write", "write_piece", "write_raw_chunks", "write_index", "read_pieces", "PIECE_CELL_DATA",
           "CYCLE_CELL_DATA", "VTK_TRIANGLE"]

#: cell data of every piece (name -> VTK type)
PIECE_CELL_DATA = {"global_position": "Int64", "parent": "Int64", "kind": "Int64"}
#: cell data of the pieces of an output with more than one cycle
CYCLE_CELL_DATA = {"cycle_id": "Int64", "cycle_position": "Int64"}


#: VTK cell type of a triangle
VTK_TRIANGLE = 5


def write_piece(path: str | os.PathLike[str], point_ids: np.ndarray, points: np.ndarray, triangles: np.ndarray,
                position: np.ndarray, cycle_id: np.ndarray | None, cycle_position: np.ndarray | None,
                parent: np.ndarray, kind: np.ndarray, attributes: np.ndarray, part: np.ndarray | None = None,
                local: bool = False) -> None:
    """Write one piece: ``triangles`` in global point ids (``local``: indices into
    ``point_ids``/``points`` already), rows in cycle order.

    ``cycle_id`` / ``cycle_position`` None: not written (an output of one cycle).

    ``part`` (optional): a ``part`` cell array (``--parts``). Written as raw appended
    binary (:func:`hammesh.io.vtu.write_raw`) into ``NAME.part`` and renamed: never a half-written piece.
    """
    path = Path(path)
    point_ids = np.asarray(point_ids, dtype=np.int64)
    points = np.asarray(points)
    triangles = np.asarray(triangles, dtype=np.int64)
    if local:
        if len(triangles) and (triangles.min() < 0 or triangles.max() >= len(point_ids)):
            raise FileFormatError(f"{path}: a triangle uses a point the piece does not hold")
    else:
        order = np.argsort(point_ids, kind="stable")
        point_ids, points = point_ids[order], points[order]
        at = np.minimum(np.searchsorted(point_ids, triangles), max(len(point_ids) - 1, 0))
        if len(point_ids) and not np.array_equal(point_ids[at], triangles):
            raise FileFormatError(f"{path}: a triangle uses a point the piece does not hold")
        triangles = at
    local = triangles
    m = len(triangles)
    pts3 = np.zeros((len(points), 3))
    pts3[:, :2] = points
    arrays = [("PointData", "global_id", "Int64", point_ids, 1)]
    cell = {"global_position": position, "parent": parent, "kind": kind}
    if cycle_id is not None or cycle_position is not None:
        cell["cycle_id"], cell["cycle_position"] = cycle_id, cycle_position
    if part is not None:
        cell["part"] = part
    arrays += [("CellData", k, "Int64", np.asarray(v), 1) for k, v in cell.items()]
    attributes = np.asarray(attributes, dtype=np.float64).reshape(m, -1)
    arrays += [("CellData", f"attribute_{i}", "Float64", attributes[:, i], 1) for i in range(attributes.shape[1])]
    arrays += [("Points", "", "Float64", pts3, 3),
               ("Cells", "connectivity", "Int64", local, 1),
               ("Cells", "offsets", "Int64", 3 * np.arange(1, m + 1, dtype=np.int64), 1),
               ("Cells", "types", "UInt8", np.full(m, VTK_TRIANGLE, np.uint8), 1)]
    tmp = path.with_name(path.name + ".part")
    try:
        vtu.write_raw(tmp, arrays, len(points), m)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_raw_chunks(path: str | os.PathLike[str], arrays: list[tuple], n_points: int, n_cells: int) -> None:
    """:func:`hammesh.io.vtu.write_raw`'s file (the same bytes), each array written
    chunk by chunk: ``arrays`` holds ``(section, name, vtk_type, components, n_values,
    chunks)`` with ``chunks()`` yielding the array's values in order (``n_values`` in
    all, every component counted). A piece then goes from the tile's arrays to the
    file without a gathered copy of each (a fresh array is a page fault per 4 kB: the
    cost of the write step at millions of rows). Written into ``NAME.part`` and
    renamed: never a half-written file.
    """
    path = Path(path)
    sections: dict[str, list[str]] = {"PointData": [], "CellData": [], "Points": [], "Cells": []}
    offset = 0
    for section, name, vtk_type, ncomp, n_values, _ in arrays:
        attr = f' Name="{name}"' if name else ""
        comp = f' NumberOfComponents="{ncomp}"' if ncomp > 1 else ""
        sections[section].append(f'<DataArray type="{vtk_type}"{attr}{comp} format="appended" offset="{offset}"/>')
        offset += 8 + n_values * np.dtype(vtu.RAW_DTYPES[vtk_type]).itemsize
    head = ['<?xml version="1.0"?>',
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
            "<UnstructuredGrid>", f'<Piece NumberOfPoints="{n_points}" NumberOfCells="{n_cells}">']
    for section in ("PointData", "CellData", "Points", "Cells"):
        head += [f"<{section}>", *sections[section], f"</{section}>"]
    head += ["</Piece>", "</UnstructuredGrid>", '<AppendedData encoding="raw">']
    tmp = path.with_name(path.name + ".part")
    try:
        with open(tmp, "wb") as f:
            f.write("\n".join(head).encode() + b"\n_")
            for section, name, vtk_type, ncomp, n_values, chunks in arrays:
                dt = np.dtype(vtu.RAW_DTYPES[vtk_type]).newbyteorder("<")
                f.write(np.array([n_values * dt.itemsize], dtype="<u8").tobytes())
                done = 0
                for c in chunks():
                    c = np.ascontiguousarray(c, dtype=dt)
                    f.write(memoryview(c).cast("B"))
                    done += c.size
                if done != n_values:
                    raise ValueError(f"internal: {name or section} has {done} values, not {n_values}")
            f.write(b"\n</AppendedData>\n</VTKFile>\n")
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_index(path: str | os.PathLike[str], pieces: list[str], n_attributes: int = 0, *, cycles: bool = True,
                part: bool = False, types: dict[str, str] | None = None) -> None:
    """Write the ``.pvtu`` index listing ``pieces`` (file names relative to it), in order.

    Its cell data are the pieces': :data:`PIECE_CELL_DATA`, :data:`CYCLE_CELL_DATA`
    when ``cycles`` (more than one cycle), ``part`` when ``part``, ``n_attributes``
    regional attributes (a reader such as ParaView shows only the arrays listed here).
    ``types``: VTK type by array name where the pieces use another than these
    defaults (``global_id`` included), e.g. ``Int32`` (they must agree with the pieces).
    """
    types = types or {}
    path = Path(path)
    root = ET.Element("VTKFile", type="PUnstructuredGrid", version="1.0", byte_order="LittleEndian",
                      header_type="UInt64")
    grid = ET.SubElement(root, "PUnstructuredGrid", GhostLevel="0")
    pd = ET.SubElement(grid, "PPointData")
    ET.SubElement(pd, "PDataArray", type=types.get("global_id", "Int64"), Name="global_id")
    cd = ET.SubElement(grid, "PCellData")
    names = {**PIECE_CELL_DATA, **(CYCLE_CELL_DATA if cycles else {}), **({"part": "Int64"} if part else {})}
    for name, typ in names.items():
        ET.SubElement(cd, "PDataArray", type=types.get(name, typ), Name=name)
    for i in range(n_attributes):
        ET.SubElement(cd, "PDataArray", type="Float64", Name=f"attribute_{i}")
    pp = ET.SubElement(grid, "PPoints")
    ET.SubElement(pp, "PDataArray", type="Float64", NumberOfComponents="3")
    for src in pieces:
        ET.SubElement(grid, "Piece", Source=str(src))
    tmp = path.with_name(path.name + ".part")
    ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8")
    os.replace(tmp, path)


def read_pieces(path: str | os.PathLike[str]) -> list[Path]:
    """The piece files an index lists, in its order."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise FileFormatError(f"{path}: not a readable .pvtu index ({exc})") from None
    grid = root.find("PUnstructuredGrid")
    if root.tag != "VTKFile" or grid is None:
        raise FileFormatError(f"{path}: not a PUnstructuredGrid .pvtu index")
    out = [path.parent / p.get("Source", "") for p in grid.findall("Piece")]
    if not out:
        raise FileFormatError(f"{path}: the index lists no pieces")
    for p in out:
        if not p.is_file():
            raise FileFormatError(f"{path}: piece {p.name} is missing")
    return out


def _read_piece(piece: Path):
    """``(global_id, points (n, 2), triangles (local), global_position or None, attributes)``
    of one piece, or None if it has no triangles. hammesh's own raw pieces are read
    directly (:func:`_read_raw_vtu`), any other ``.vtu`` by meshio."""
    try:
        raw = vtu.read_raw(piece)
    except (OSError, ValueError, KeyError) as exc:
        raise FileFormatError(f"{piece}: {exc}") from None
    if raw is not None:
        types = raw.get(("Cells", "types"))
        conn = raw.get(("Cells", "connectivity"))
        if types is None or conn is None or ("Points", "points") not in raw:
            raise FileFormatError(f"{piece}: a raw .vtu without points or cells")
        if not (types == VTK_TRIANGLE).all() or len(conn) != 3 * len(types):
            raise FileFormatError(f"{piece}: hammesh pieces hold triangles only")
        if len(types) == 0:
            return None
        pts = raw[("Points", "points")]
        n = len(pts)
        gid = raw.get(("PointData", "global_id"), np.arange(n)).astype(np.int64)
        t = conn.astype(np.int64).reshape(-1, 3)
        if len(gid) != n or (t < 0).any() or (t >= n).any():
            raise FileFormatError(f"{piece}: a triangle uses a point the piece does not hold")
        gp = raw.get(("CellData", "global_position"))
        names = sorted(k[1] for k in raw if k[0] == "CellData" and k[1].startswith("attribute_"))
        attr = np.stack([raw[("CellData", k)] for k in names], 1) if names else np.zeros((len(t), 0))
        return gid, np.asarray(pts)[:, :2], t, None if gp is None else gp.astype(np.int64), attr
    import meshio

    try:
        m = meshio.read(str(piece), file_format="vtu")
    except Exception as exc:  # meshio raises many kinds
        raise FileFormatError(f"{piece}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    gid = np.asarray(m.point_data.get("global_id", np.arange(len(m.points))), dtype=np.int64)
    blocks = [i for i, c in enumerate(m.cells) if c.type == "triangle"]
    if not blocks:
        return None
    t = np.concatenate([m.cells[i].data for i in blocks]).astype(np.int64)
    gp = m.cell_data.get("global_position")
    names = sorted(k for k in m.cell_data if k.startswith("attribute_"))
    attr = (np.stack([np.concatenate([np.asarray(m.cell_data[k][i]) for i in blocks]) for k in names], 1)
            if names else np.zeros((len(t), 0)))
    return (gid, np.asarray(m.points)[:, :2], t,
            np.concatenate([np.asarray(gp[i]) for i in blocks]).astype(np.int64) if gp else None, attr)


def read(path: str | os.PathLike[str], *, dim: int | None = 2, strict: bool = False) -> Mesh:
    """Stitch an index's pieces into one mesh, triangles in cycle order.

    Points shared by pieces are one point (``global_id``); rows are ordered by
    ``global_position`` when every piece has it (hammesh's pieces), else piece by piece.
    """
    ids, xy, tris, pos, attrs = [], [], [], [], []
    for piece in read_pieces(path):
        got = _read_piece(piece)
        if got is None:
            continue
        gid, pts, t, gp, attr = got
        ids.append(gid)
        xy.append(pts)
        tris.append(gid[t])
        pos.append(gp)
        attrs.append(attr)
    if not tris:
        raise FileFormatError(f"{path}: the pieces hold no triangles")
    gids = np.concatenate(ids)
    n = int(gids.max()) + 1
    points = np.full((n, 2), np.nan)
    points[gids] = np.concatenate(xy)
    tri = np.concatenate(tris)
    width = min(a.shape[1] for a in attrs)
    attr = np.concatenate([a[:, :width] for a in attrs])
    if all(p is not None for p in pos):
        order = np.argsort(np.concatenate(pos), kind="stable")
        tri, attr = tri[order], attr[order]
    used = np.zeros(n, bool)
    used[tri.ravel()] = True
    if np.isnan(points[used]).any():
        raise FileFormatError(f"{path}: a triangle uses a point no piece holds")
    # points no triangle uses (ids of other runs' join points) get a harmless position
    points[~used] = 0.0
    return Mesh(points=points, triangles=tri, triangle_attributes=attr, info={"pieces": len(tris)})


def write(mesh: Mesh | HamiltonianMesh, path: str | os.PathLike[str]) -> None:
    """Write any mesh as a one-piece index (``NAME.pvtu`` + ``NAME.0.vtu`` beside it)."""
    path = Path(path)
    m = len(mesh.triangles)
    cid = cpos = None  # (one cycle, or none: global_position says it all)
    if isinstance(mesh, HamiltonianMesh):
        comps = np.asarray(mesh.components, np.int64)
        if len(comps) > 1:
            cid, cpos = np.repeat(np.arange(len(comps)), comps), cycle_positions(comps)
        parent, kind = mesh.parent, mesh.kind
    else:
        parent, kind = np.full(m, -1), np.zeros(m)
    piece = path.with_name(path.stem + ".0.vtu")
    write_piece(piece, np.arange(len(mesh.points)), mesh.points[:, :2], mesh.triangles, np.arange(m), cid, cpos,
                parent, kind, np.asarray(mesh.triangle_attributes).reshape(m, -1))
    write_index(path, [piece.name], np.asarray(mesh.triangle_attributes).reshape(m, -1).shape[1],
                cycles=cid is not None)
