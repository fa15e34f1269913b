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
from hammesh.io.cell_data import join_components, split_components
from hammesh.io.tags import EDGE_MARKER, SEGMENT_EDGES, VERTEX_MARKER, edge_fields, segments_from_edge_fields
from hammesh.mesh import HamiltonianMesh, Mesh, attribute_name, cycle_positions

__all__ = ["read", "write", "write_piece", "write_raw_chunks", "write_index", "read_pieces", "piece_cells", "index_counts", "PIECE_CELL_DATA",
           "CYCLE_CELL_DATA", "VTK_TRIANGLE", "named_attributes", "OWN_CELL_DATA"]

#: cell data of every piece (name -> VTK type)
PIECE_CELL_DATA = {"global_position": "Int64", "parent": "Int64", "kind": "Int64"}
#: cell data of the pieces of an output with more than one cycle
CYCLE_CELL_DATA = {"cycle_id": "Int64", "cycle_position": "Int64"}


#: VTK cell type of a triangle
VTK_TRIANGLE = 5
#: hammesh's own cell data in a piece (every other cell array is a triangle attribute)
#: the constrained edges, per triangle (:mod:`hammesh.io.tags`), when the mesh has any
EDGE_CELL_DATA = {SEGMENT_EDGES: ("Int64", 1), EDGE_MARKER: ("Int64", 3)}
OWN_CELL_DATA = frozenset({*PIECE_CELL_DATA, *CYCLE_CELL_DATA, "part", *EDGE_CELL_DATA})


def named_attributes(attributes: np.ndarray, names: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    """The columns of ``attributes (m, k)`` by the name the serial ``.vtu`` writer gives
    them (:func:`hammesh.io.cell_data.triangle_cell_data`): ``names[i]`` (a mesh file's
    field names, ``attribute_names``), else ``attribute_<i>``; columns ``v[0]``,
    ``v[1]``, ... are one ``(m, c)`` array ``v``.

    >>> sorted(named_attributes(np.zeros((2, 3)), ("rho", "v[0]", "v[1]")).items(), key=lambda x: x[0])[1][1].shape
    (2, 2)
    """
    m = len(attributes)
    attributes = np.asarray(attributes, dtype=np.float64).reshape(m, -1)
    return join_components({attribute_name(tuple(names), i): attributes[:, i] for i in range(attributes.shape[1])})


def _vtk_type(values: np.ndarray) -> str:
    return "Float64" if np.asarray(values).dtype.kind == "f" else "Int64"


def write_piece(path: str | os.PathLike[str], point_ids: np.ndarray, points: np.ndarray, triangles: np.ndarray,
                position: np.ndarray, cycle_id: np.ndarray | None, cycle_position: np.ndarray | None,
                parent: np.ndarray, kind: np.ndarray, attributes: np.ndarray, part: np.ndarray | None = None,
                local: bool = False, attribute_names: tuple[str, ...] = (),
                point_data: dict[str, np.ndarray] | None = None,
                edges: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """Write one piece: ``triangles`` in global point ids (``local``: indices into
    ``point_ids``/``points`` already), rows in cycle order.

    ``cycle_id`` / ``cycle_position`` None: not written (an output of one cycle).
    ``attributes (m, k)`` are named as the serial ``.vtu`` writer names them
    (:func:`named_attributes`: ``attribute_names``, else ``attribute_<i>``);
    ``point_data``: per-point arrays (the mesh's, in ``points``' order), written as point data.

    ``edges`` (optional): the constrained edges as ``(segment_edges (m,), edge_marker (m, 3))``
    of these rows (:func:`hammesh.io.tags.edge_fields`), written as the serial ``.vtu``
    writes them.

    ``part`` (optional): a ``part`` cell array (``--parts``). Written as raw appended
    binary (:func:`hammesh.io.vtu.write_raw`) into ``NAME.part`` and renamed: never a half-written piece.
    """
    path = Path(path)
    point_ids = np.asarray(point_ids, dtype=np.int64)
    points = np.asarray(points)
    triangles = np.asarray(triangles, dtype=np.int64)
    point_data = {k: np.asarray(v) for k, v in (point_data or {}).items()}
    if local:
        if len(triangles) and (triangles.min() < 0 or triangles.max() >= len(point_ids)):
            raise FileFormatError(f"{path}: a triangle uses a point the piece does not hold")
    else:
        order = np.argsort(point_ids, kind="stable")
        point_ids, points = point_ids[order], points[order]
        point_data = {k: v[order] for k, v in point_data.items()}
        at = np.minimum(np.searchsorted(point_ids, triangles), max(len(point_ids) - 1, 0))
        if len(point_ids) and not np.array_equal(point_ids[at], triangles):
            raise FileFormatError(f"{path}: a triangle uses a point the piece does not hold")
        triangles = at
    local = triangles
    m = len(triangles)
    pts3 = np.zeros((len(points), 3))
    pts3[:, :2] = points
    arrays = [("PointData", "global_id", "Int64", point_ids, 1)]
    arrays += [("PointData", _escape(k), _vtk_type(v), v, 1 if v.ndim == 1 else v.shape[1])
               for k, v in point_data.items()]
    cell = {"global_position": position, "parent": parent, "kind": kind}
    if cycle_id is not None or cycle_position is not None:
        cell["cycle_id"], cell["cycle_position"] = cycle_id, cycle_position
    if part is not None:
        cell["part"] = part
    arrays += [("CellData", k, "Int64", np.asarray(v), 1) for k, v in cell.items()]
    if edges is not None:
        arrays += [("CellData", SEGMENT_EDGES, "Int64", np.asarray(edges[0], np.int64), 1),
                   ("CellData", EDGE_MARKER, "Int64", np.asarray(edges[1], np.int64).reshape(m, 3), 3)]
    arrays += [("CellData", _escape(k), "Float64", v, 1 if v.ndim == 1 else v.shape[1])
               for k, v in named_attributes(attributes, attribute_names).items()]
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
                part: bool = False, types: dict[str, str] | None = None,
                cell_arrays: dict[str, tuple[str, int]] | None = None,
                point_arrays: dict[str, tuple[str, int]] | None = None, cells: list[int] | None = None) -> None:
    """Write the ``.pvtu`` index listing ``pieces`` (file names relative to it), in order.

    The index also records how many triangles each piece holds and their total
    (``NumberOfCells`` on each ``Piece`` and on ``PUnstructuredGrid``; VTK readers
    ignore them), so that :func:`read` notices a piece left out of the index or a piece
    file replaced: ``cells`` gives the counts, else they are read from the pieces'
    headers (hammesh's own pieces; a piece whose header cannot be read leaves them out).

    Its cell data are the pieces': :data:`PIECE_CELL_DATA`, :data:`CYCLE_CELL_DATA`
    when ``cycles`` (more than one cycle), ``part`` when ``part``, ``n_attributes``
    regional attributes (a reader such as ParaView shows only the arrays listed here).
    ``types``: VTK type by array name where the pieces use another than these
    defaults (``global_id`` included), e.g. ``Int32`` (they must agree with the pieces).
    ``cell_arrays`` / ``point_arrays``: the pieces' named attributes and point data,
    ``{name: (vtk type, components)}`` (``cell_arrays`` replaces ``n_attributes``).
    """
    types = types or {}
    path = Path(path)
    root = ET.Element("VTKFile", type="PUnstructuredGrid", version="1.0", byte_order="LittleEndian",
                      header_type="UInt64")
    if cells is None:
        cells = [piece_cells(path.parent / src) for src in pieces]
    counted = all(c is not None for c in cells) and len(cells) == len(pieces)
    grid = ET.SubElement(root, "PUnstructuredGrid", GhostLevel="0",
                         **({"NumberOfCells": str(sum(cells)), "NumberOfPieces": str(len(pieces))} if counted else {}))
    pd = ET.SubElement(grid, "PPointData")
    ET.SubElement(pd, "PDataArray", type=types.get("global_id", "Int64"), Name="global_id")
    for name, (typ, ncomp) in (point_arrays or {}).items():
        ET.SubElement(pd, "PDataArray", type=typ, Name=name, **({"NumberOfComponents": str(ncomp)} if ncomp > 1 else {}))
    cd = ET.SubElement(grid, "PCellData")
    names = {**PIECE_CELL_DATA, **(CYCLE_CELL_DATA if cycles else {}), **({"part": "Int64"} if part else {})}
    for name, typ in names.items():
        ET.SubElement(cd, "PDataArray", type=types.get(name, typ), Name=name)
    if cell_arrays is None:
        cell_arrays = {f"attribute_{i}": ("Float64", 1) for i in range(n_attributes)}
    for name, (typ, ncomp) in cell_arrays.items():
        ET.SubElement(cd, "PDataArray", type=typ, Name=name, **({"NumberOfComponents": str(ncomp)} if ncomp > 1 else {}))
    pp = ET.SubElement(grid, "PPoints")
    ET.SubElement(pp, "PDataArray", type="Float64", NumberOfComponents="3")
    for i, src in enumerate(pieces):
        ET.SubElement(grid, "Piece", Source=str(src), **({"NumberOfCells": str(cells[i])} if counted else {}))
    tmp = path.with_name(path.name + ".part")
    ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8")
    os.replace(tmp, path)


def piece_cells(piece: str | os.PathLike[str]) -> int | None:
    """The ``NumberOfCells`` a ``.vtu`` piece's header declares (its first ``Piece``
    element, within the first 64 KiB), or None if there is none to read."""
    import re

    try:
        with open(piece, "rb") as f:
            head = f.read(65536)
    except OSError:
        return None
    match = re.search(rb"<Piece\b[^>]*\bNumberOfCells=\"(\d+)\"", head)
    return None if match is None else int(match.group(1))


def index_counts(path: str | os.PathLike[str]) -> tuple[int | None, int | None, list[int | None]]:
    """What an index records of its pieces (:func:`write_index`): the total number of
    triangles, the number of pieces and each listed piece's count (None where absent)."""
    root = ET.parse(path).getroot()
    grid = root.find("PUnstructuredGrid")

    def count(element, name: str) -> int | None:
        value = None if element is None else element.get(name)
        return int(value) if value is not None and value.isdigit() else None

    return (count(grid, "NumberOfCells"), count(grid, "NumberOfPieces"),
            [count(p, "NumberOfCells") for p in ([] if grid is None else grid.findall("Piece"))])


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


def _columns(cell_data: dict[str, np.ndarray], m: int) -> tuple[np.ndarray, tuple[str, ...]]:
    """A piece's triangle attributes ``(m, k)`` and their names from its cell arrays
    other than hammesh's own (:data:`OWN_CELL_DATA`), in file order; an ``(m, c)``
    array ``v`` is the columns ``v[0]`` ... ``v[c-1]`` (as the serial readers take it)."""
    data = split_components({k: np.asarray(v) for k, v in cell_data.items() if k not in OWN_CELL_DATA}, (1,))
    names = tuple(data)
    attr = np.stack([np.asarray(data[k], np.float64).reshape(m) for k in names], 1) if names else np.zeros((m, 0))
    return attr, names


def _read_piece(piece: Path):
    """``(global_id, points (n, 2), triangles (local), global_position or None,
    attributes, attribute names, point data, hammesh's own cell fields)`` of one piece, or None if it has no
    triangles. hammesh's own raw pieces are read directly
    (:func:`hammesh.io.vtu.read_raw`), any other ``.vtu`` by meshio."""
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
        cells = {_unescape(k[1]): v for k, v in raw.items() if k[0] == "CellData"}
        pdata = {_unescape(k[1]): v for k, v in raw.items() if k[0] == "PointData" and k[1] != "global_id"}
        if any(len(v) != len(t) for v in cells.values()) or any(len(v) != n for v in pdata.values()):
            raise FileFormatError(f"{piece}: an array's length is not its piece's")
        attr, names = _columns(cells, len(t))
        own = {k: np.asarray(v) for k, v in cells.items() if k in OWN_CELL_DATA and k != "global_position"}
        return gid, np.asarray(pts)[:, :2], t, None if gp is None else gp.astype(np.int64), attr, names, pdata, own
    import meshio

    try:
        # (the format's reader raises; meshio.read(file_format=) prints and calls sys.exit(1))
        m = meshio.vtu.read(str(piece))
    except Exception as exc:  # meshio raises many kinds, also on files VTK reads (LZ4 pieces)
        from hammesh.io.vtk_xml import read_vtk_xml

        try:
            m = read_vtk_xml(piece)
        except FileFormatError:
            raise FileFormatError(
                f"{piece}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    gid = np.asarray(m.point_data.get("global_id", np.arange(len(m.points))), dtype=np.int64)
    blocks = [i for i, c in enumerate(m.cells) if c.type == "triangle"]
    if not blocks:
        return None
    t = np.concatenate([m.cells[i].data for i in blocks]).astype(np.int64)
    gp = m.cell_data.get("global_position")
    cells = {k: np.concatenate([np.asarray(v[i]) for i in blocks]) for k, v in m.cell_data.items()
             if np.asarray(v[blocks[0]]).dtype.kind in "biuf"}
    attr, names = _columns(cells, len(t))
    pdata = {k: np.asarray(v) for k, v in m.point_data.items() if k != "global_id" and np.asarray(v).dtype.kind in "biuf"}
    own = {k: v for k, v in cells.items() if k in OWN_CELL_DATA and k != "global_position"}
    return (gid, np.asarray(m.points)[:, :2], t,
            np.concatenate([np.asarray(gp[i]) for i in blocks]).astype(np.int64) if gp else None, attr, names, pdata,
            own)


def _escape(name: str) -> str:
    """An array's name as an XML attribute value (a mesh file's field names may hold ``"<&``)."""
    from xml.sax.saxutils import escape

    return escape(name, {'"': "&quot;"})


def _unescape(name: str) -> str:
    from xml.sax.saxutils import unescape

    return unescape(name, {"&quot;": '"'})


def read(path: str | os.PathLike[str], *, dim: int | None = 2, strict: bool = False) -> Mesh:
    """Stitch an index's pieces into one mesh, triangles in cycle order.

    Points shared by pieces are one point (``global_id``); rows are ordered by
    ``global_position`` when every piece has it (hammesh's pieces), else piece by piece.
    Cell arrays other than hammesh's own are the triangle attributes (by name:
    ``attribute_names`` unless all are ``attribute_<i>``), point arrays other than
    ``global_id`` the point data (those every piece holds).
    """
    ids, xy, tris, pos, attrs, names, pdata, owns = [], [], [], [], [], [], [], []
    pieces = read_pieces(path)
    total, n_pieces, listed = index_counts(path)
    if n_pieces is not None and n_pieces != len(pieces):
        raise FileFormatError(f"{path}: the index lists {len(pieces)} pieces; it was written with {n_pieces}")
    for i, piece in enumerate(pieces):
        got = _read_piece(piece)
        if listed[i] is not None and listed[i] != (0 if got is None else len(got[2])):
            raise FileFormatError(f"{piece}: holds {0 if got is None else len(got[2]):,} triangles; the index "
                                  f"says {listed[i]:,}")
        if got is None:
            continue
        gid, pts, t, gp, attr, nm, pd, own = got
        owns.append(own)
        ids.append(gid)
        xy.append(pts)
        tris.append(gid[t])
        pos.append(gp)
        attrs.append(attr)
        names.append(nm)
        pdata.append(pd)
    if not tris:
        raise FileFormatError(f"{path}: the pieces hold no triangles")
    gids = np.concatenate(ids)
    n = int(gids.max()) + 1
    points = np.full((n, 2), np.nan)
    xy_all = np.concatenate(xy)
    points[gids] = xy_all
    # a point several pieces hold (a separator's) must be the same point in each
    moved = np.flatnonzero((points[gids] != xy_all).any(axis=1) & ~np.isnan(xy_all).any(axis=1))
    if len(moved):
        raise FileFormatError(f"{path}: point {int(gids[moved[0]])} (global_id) lies at different places in "
                              "two pieces")
    tri = np.concatenate(tris)
    if total is not None and total != len(tri):
        raise FileFormatError(f"{path}: the pieces hold {len(tri):,} triangles; the index says {total:,}")
    width = min(a.shape[1] for a in attrs)
    attr = np.concatenate([a[:, :width] for a in attrs])
    attr_names = names[0][:width] if all(nm[:width] == names[0][:width] for nm in names) else ()
    if all(x == f"attribute_{i}" for i, x in enumerate(attr_names)):
        attr_names = ()
    if all(p is not None for p in pos):
        position = np.concatenate(pos)
        order = np.argsort(position, kind="stable")
        # (the rows' order is the cycle's: every position 0..m-1 exactly once)
        if not np.array_equal(position[order], np.arange(len(position))):
            gap = int(np.flatnonzero(position[order] != np.arange(len(position)))[0])
            raise FileFormatError(f"{path}: global_position does not number the {len(position):,} triangles "
                                  f"0..{len(position) - 1} (position {gap} is missing or repeated)")
        tri, attr = tri[order], attr[order]
    else:
        order = np.arange(len(tri))
    # the cycle's own fields every piece holds, in row order (`hammesh check` compares them)
    fields = {k: np.concatenate([np.asarray(o[k]).reshape(-1) for o in owns])[order]
              for k in owns[0] if k not in EDGE_CELL_DATA
              and all(k in o and np.size(o[k]) == len(t) for o, t in zip(owns, tris))}
    segments, seg_marks = np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
    if all(SEGMENT_EDGES in o and EDGE_MARKER in o for o in owns):  # the constrained edges, per triangle
        flags = np.concatenate([np.asarray(o[SEGMENT_EDGES], np.int64).reshape(-1) for o in owns])[order]
        marks = np.concatenate([np.asarray(o[EDGE_MARKER], np.int64).reshape(-1, 3) for o in owns])[order]
        if len(flags) != len(tri) or len(marks) != len(tri):
            raise FileFormatError(f"{path}: a piece's segment_edges or edge_marker is not one row per triangle")
        segments, seg_marks = segments_from_edge_fields(tri, flags, marks)
    used = np.zeros(n, bool)
    used[tri.ravel()] = True
    if np.isnan(points[used]).any():
        raise FileFormatError(f"{path}: a triangle uses a point no piece holds")
    point_data = {}
    for key in [k for k in pdata[0] if all(k in d for d in pdata)]:
        first = np.asarray(pdata[0][key])
        values = np.zeros((n, *first.shape[1:]), first.dtype)
        for gid, d in zip(ids, pdata):
            values[gid] = d[key]
        point_data[key] = values
    # points no triangle uses (ids of other runs' join points) get a harmless position
    points[~used] = 0.0
    # the points' markers (the parallel path's pieces, a whole mesh's index), as the
    # .vtu reader takes them: the mesh's vertex_markers, not point data
    marks = point_data.pop(VERTEX_MARKER, None)
    marks = np.zeros(0, np.int64) if marks is None or np.asarray(marks).dtype.kind not in "iu" else np.asarray(marks, np.int64)
    return Mesh(points=points, triangles=tri, triangle_attributes=attr, attribute_names=attr_names,
                point_data=point_data, vertex_markers=marks, segments=segments, segment_markers=seg_marks,
                info={"pieces": len(tris), **({"cycle_fields": fields} if fields else {})})


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
    names = tuple(getattr(mesh, "attribute_names", ()))
    attrs = np.asarray(mesh.triangle_attributes).reshape(m, -1)
    point_data = {k: np.asarray(v) for k, v in (getattr(mesh, "point_data", None) or {}).items()}
    # (as the serial .vtu writer: the points' markers as point data when any is nonzero)
    marks = np.asarray(getattr(mesh, "vertex_markers", None) if getattr(mesh, "vertex_markers", None) is not None
                       else np.zeros(0), dtype=np.int64)
    if marks.shape == (len(mesh.points),) and marks.any():
        point_data.setdefault(VERTEX_MARKER, marks)
    edges = edge_fields(mesh) if len(np.asarray(mesh.segments).reshape(-1, 2)) else None
    from hammesh.errors import OutputError
    from hammesh.io.atomic import atomic_paths

    # both files or neither, and a failure names the file (tester18 r11: "[Errno 27] File
    # too large" named nothing, and a failed index left the piece behind)
    with atomic_paths([piece, path]) as (piece_tmp, index_tmp):
        try:
            write_piece(piece_tmp, np.arange(len(mesh.points)), mesh.points[:, :2], mesh.triangles, np.arange(m), cid,
                        cpos, parent, kind, attrs, attribute_names=names, point_data=point_data, edges=edges)
        except OSError as exc:
            raise OutputError(f"{piece}: cannot write ({exc.strerror or exc})") from None
        write_index(index_tmp, [piece.name], cycles=cid is not None, cells=[m],
                    cell_arrays={**({} if edges is None else EDGE_CELL_DATA),
                                 **{k: ("Float64", 1 if v.ndim == 1 else v.shape[1])
                                    for k, v in named_attributes(attrs, names).items()}},
                    point_arrays={k: (_vtk_type(v), 1 if v.ndim == 1 else v.shape[1]) for k, v in point_data.items()})
