"""Partitioned VTK (``.pvtu``): an index listing ``.vtu`` pieces, for meshes beyond RAM.

hammesh's parallel meshing (``hammesh mesh ... --partitioned -o DIR``) has every worker
write its tile's piece (:func:`write_piece`); the driver writes the index
(:func:`write_index`), pieces listed in the order the cycle first enters them. Each
piece stores its points with point data ``global_id`` (a point shared by two pieces
has one id) and its triangles in cycle order with cell data ``global_position``
(place in the whole output), ``cycle_id``, ``cycle_position``, ``parent``, ``kind``
and the regional attributes.

:func:`read` stitches the pieces back into one mesh in cycle order (``hammesh check
index.pvtu`` re-verifies it like any mesh file); :func:`write` writes any mesh as a
one-piece index (the registry's writer). The format is VTK's own (``PUnstructuredGrid``,
what ParaView opens); pieces are written by meshio.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions

__all__ = ["read", "write", "write_piece", "write_index", "read_pieces", "PIECE_CELL_DATA"]

#: cell data of every piece (name -> VTK type)
PIECE_CELL_DATA = {"global_position": "Int64", "cycle_id": "Int64", "cycle_position": "Int64",
                   "parent": "Int64", "kind": "Int64"}


def write_piece(path: str | os.PathLike[str], point_ids: np.ndarray, points: np.ndarray, triangles: np.ndarray,
                position: np.ndarray, cycle_id: np.ndarray, cycle_position: np.ndarray, parent: np.ndarray,
                kind: np.ndarray, attributes: np.ndarray) -> None:
    """Write one piece: ``triangles`` in global point ids, rows in cycle order."""
    import meshio

    path = Path(path)
    order = np.argsort(point_ids, kind="stable")
    point_ids, points = np.asarray(point_ids)[order], np.asarray(points)[order]
    local = np.minimum(np.searchsorted(point_ids, triangles), max(len(point_ids) - 1, 0))
    if len(point_ids) and not np.array_equal(point_ids[local], triangles):
        raise FileFormatError(f"{path}: a triangle uses a point the piece does not hold")
    pts3 = np.zeros((len(points), 3))
    pts3[:, :2] = points
    cell = {"global_position": position, "cycle_id": cycle_id, "cycle_position": cycle_position,
            "parent": parent, "kind": kind}
    cell_data = {k: [np.asarray(v, dtype=np.int64)] for k, v in cell.items()}
    attributes = np.asarray(attributes, dtype=np.float64).reshape(len(triangles), -1)
    for i in range(attributes.shape[1]):
        cell_data[f"attribute_{i}"] = [np.ascontiguousarray(attributes[:, i])]
    m = meshio.Mesh(pts3, [("triangle", local.astype(np.int64))], point_data={"global_id": np.asarray(point_ids, np.int64)},
                    cell_data=cell_data)
    tmp = path.with_name(path.name + ".part")
    # uncompressed binary: a worker's write costs a memory copy, not zlib (~4x faster)
    meshio.write(str(tmp), m, file_format="vtu", compression=None)
    os.replace(tmp, path)


def write_index(path: str | os.PathLike[str], pieces: list[str], n_attributes: int = 0) -> None:
    """Write the ``.pvtu`` index listing ``pieces`` (file names relative to it), in order."""
    path = Path(path)
    root = ET.Element("VTKFile", type="PUnstructuredGrid", version="1.0", byte_order="LittleEndian",
                      header_type="UInt64")
    grid = ET.SubElement(root, "PUnstructuredGrid", GhostLevel="0")
    pd = ET.SubElement(grid, "PPointData")
    ET.SubElement(pd, "PDataArray", type="Int64", Name="global_id")
    cd = ET.SubElement(grid, "PCellData")
    for name, typ in PIECE_CELL_DATA.items():
        ET.SubElement(cd, "PDataArray", type=typ, Name=name)
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


def read(path: str | os.PathLike[str], *, dim: int | None = 2, strict: bool = False) -> Mesh:
    """Stitch an index's pieces into one mesh, triangles in cycle order.

    Points shared by pieces are one point (``global_id``); rows are ordered by
    ``global_position`` when every piece has it (hammesh's pieces), else piece by piece.
    """
    import meshio

    ids, xy, tris, pos, attrs = [], [], [], [], []
    for piece in read_pieces(path):
        try:
            m = meshio.read(str(piece), file_format="vtu")
        except Exception as exc:  # meshio raises many kinds
            raise FileFormatError(f"{piece}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
        gid = np.asarray(m.point_data.get("global_id", np.arange(len(m.points))), dtype=np.int64)
        blocks = [i for i, c in enumerate(m.cells) if c.type == "triangle"]
        if not blocks:
            continue
        t = np.concatenate([m.cells[i].data for i in blocks]).astype(np.int64)
        ids.append(gid)
        xy.append(np.asarray(m.points)[:, :2])
        tris.append(gid[t])
        gp = m.cell_data.get("global_position")
        pos.append(np.concatenate([np.asarray(gp[i]) for i in blocks]).astype(np.int64) if gp else None)
        names = sorted(k for k in m.cell_data if k.startswith("attribute_"))
        attrs.append(np.stack([np.concatenate([np.asarray(m.cell_data[k][i]) for i in blocks]) for k in names], 1)
                     if names else np.zeros((len(t), 0)))
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
    if isinstance(mesh, HamiltonianMesh):
        comps = np.asarray(mesh.components, np.int64)
        cid = np.repeat(np.arange(len(comps)), comps)
        cpos, parent, kind = cycle_positions(comps), mesh.parent, mesh.kind
    else:
        cid = np.zeros(m, np.int64)
        cpos, parent, kind = np.arange(m), np.full(m, -1), np.zeros(m)
    piece = path.with_name(path.stem + ".0.vtu")
    write_piece(piece, np.arange(len(mesh.points)), mesh.points[:, :2], mesh.triangles, np.arange(m), cid, cpos,
                parent, kind, np.asarray(mesh.triangle_attributes).reshape(m, -1))
    write_index(path, [piece.name], np.asarray(mesh.triangle_attributes).reshape(m, -1).shape[1])
