"""The cells of a mesh file as read, before they become a :class:`~hammesh.mesh.Mesh`.

Readers that hammesh implements itself (OBJ with relative indices, legacy VTK
``POLYDATA``, VTK XML ``.vtp``) return a :class:`RawMesh` shaped like a ``meshio.Mesh`` (``points``,
``cells`` blocks with ``type`` and ``data``, ``cell_data``, ``point_data``), so one
conversion (:func:`hammesh.io.meshio_format.to_mesh`) serves every format.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["CellBlock", "RawMesh", "polygon_blocks", "polygon_block_rows", "strip_triangles", "blocks_of_kind",
           "grid_blocks", "KIND_OF_VTK_TYPE", "OTHER_VTK_TYPES", "VTK_PIXEL"]

#: VTK cell types (``vtkCellType.h``) hammesh reads, by how their cells become blocks
#: (:func:`blocks_of_kind`): vertices, lines and polylines, triangles, strips, polygons,
#: pixels and quads.
KIND_OF_VTK_TYPE = {1: "vertex", 2: "vertex", 3: "line", 4: "line", 5: "polygon", 6: "strip", 7: "polygon",
                    8: "polygon", 9: "polygon"}
#: Names (meshio's) of the VTK cell types hammesh does not take, so that the refusal names them.
OTHER_VTK_TYPES = {10: "tetra", 11: "voxel", 12: "hexahedron", 13: "wedge", 14: "pyramid", 21: "line3",
                   22: "triangle6", 23: "quad8", 24: "tetra10", 25: "hexahedron20", 28: "quad9",
                   34: "triangle7", 68: "lagrange_curve", 69: "lagrange_triangle", 70: "lagrange_quadrilateral"}
#: A pixel's corners go row by row (0 1 3 2 is its boundary).
VTK_PIXEL = 8


@dataclass(frozen=True)
class CellBlock:
    """``data (k, c) int64`` cells of one ``type`` (``"triangle"``, ``"quad"``, ``"polygon"``, ``"line"``)."""

    type: str
    data: np.ndarray


@dataclass(frozen=True)
class RawMesh:
    points: np.ndarray
    cells: list[CellBlock]
    cell_data: dict[str, list[Any]] = field(default_factory=dict)
    point_data: dict[str, Any] = field(default_factory=dict)
    #: what the file said beside its cells (e.g. OBJ material names), and
    #: ``not_carried``: what the reader could not take; merged into ``Mesh.info``
    info: dict[str, Any] = field(default_factory=dict)


def polygon_blocks(offsets: np.ndarray, connectivity: np.ndarray) -> list[CellBlock]:
    """Blocks of consecutive polygons of equal size, from CSR ``offsets`` (k + 1) and
    ``connectivity``; file order kept.  Sizes 1 and 2 become ``vertex``/``line`` blocks."""
    sizes = np.diff(offsets)
    blocks: list[CellBlock] = []
    if len(sizes) == 0:
        return blocks
    cuts = np.flatnonzero(np.diff(sizes)) + 1
    starts = np.concatenate([[0], cuts])
    ends = np.concatenate([cuts, [len(sizes)]])
    names = {1: "vertex", 2: "line", 3: "triangle", 4: "quad"}
    for a, b in zip(starts.tolist(), ends.tolist()):
        c = int(sizes[a])
        if c == 0:
            continue
        data = connectivity[offsets[a]:offsets[b]].reshape(b - a, c)
        blocks.append(CellBlock(names.get(c, "polygon"), data.astype(np.int64)))
    return blocks


def polygon_block_rows(offsets: np.ndarray) -> list[np.ndarray]:
    """The polygon numbers (rows of ``offsets``) of each block :func:`polygon_blocks`
    makes, in the same order: how per-polygon data follows its polygons.

    >>> [r.tolist() for r in polygon_block_rows(np.array([0, 3, 6, 10]))]
    [[0, 1], [2]]
    """
    sizes = np.diff(offsets)
    if len(sizes) == 0:
        return []
    cuts = np.flatnonzero(np.diff(sizes)) + 1
    starts = np.concatenate([[0], cuts])
    ends = np.concatenate([cuts, [len(sizes)]])
    return [np.arange(a, b, dtype=np.int64) for a, b in zip(starts.tolist(), ends.tolist()) if sizes[a] != 0]


def strip_triangles(offsets: np.ndarray, conn: np.ndarray) -> np.ndarray:
    """``(t, 3) int64`` triangles of the triangle strips ``offsets`` (k + 1) / ``conn``, in
    order, with VTK's alternating winding (``vtkTriangleStrip``: every odd triangle has
    its first two corners swapped); strips of fewer than 3 points give none.

    >>> strip_triangles(np.array([0, 5]), np.array([0, 1, 2, 3, 4])).tolist()
    [[0, 1, 2], [2, 1, 3], [2, 3, 4]]
    """
    counts = np.maximum(np.diff(offsets) - 2, 0)
    strip_of = np.repeat(np.arange(len(counts)), counts)
    rank = np.arange(len(strip_of)) - (np.cumsum(counts) - counts)[strip_of]  # within its strip
    at = offsets[:-1][strip_of] + rank
    tris = np.stack([conn[at], conn[at + 1], conn[at + 2]], axis=1).astype(np.int64).reshape(-1, 3)
    odd = rank % 2 == 1
    tris[odd, 0], tris[odd, 1] = tris[odd, 1], tris[odd, 0].copy()
    return tris


def blocks_of_kind(kind: str, offsets: np.ndarray, conn: np.ndarray,
                   first: int) -> tuple[list[CellBlock], list[np.ndarray]]:
    """Cell blocks of ``offsets`` (k + 1) / ``conn`` cells all of one ``kind``, and each
    block's cells' numbers in the file (``first`` + row): how cell data follows its cells.

    ``kind``: ``"polygon"`` (:func:`polygon_blocks`), ``"strip"`` (triangles,
    :func:`strip_triangles`), ``"line"`` (a polyline: its consecutive pairs),
    ``"vertex"`` (no block); any other name is one block of that type (cells of one size,
    for the caller to refuse by name; ``ValueError`` if their sizes differ).
    """
    cells = len(offsets) - 1
    if kind == "polygon":
        return polygon_blocks(offsets, conn), [first + rows for rows in polygon_block_rows(offsets)]
    if kind == "strip":
        strip_of = np.repeat(np.arange(cells), np.maximum(np.diff(offsets) - 2, 0))
        if len(strip_of) == 0:  # (an empty block would stand for no cells of the file)
            return [], []
        return [CellBlock("triangle", strip_triangles(offsets, conn))], [first + strip_of]
    if kind == "line":
        pairs = np.maximum(np.diff(offsets) - 1, 0)
        pair_of = np.repeat(np.arange(cells), pairs)
        if len(pair_of) == 0:
            return [], []
        rank = np.arange(len(pair_of)) - (np.cumsum(pairs) - pairs)[pair_of]  # within its polyline
        at = offsets[:-1][pair_of] + rank
        return [CellBlock("line", np.stack([conn[at], conn[at + 1]], axis=1).astype(np.int64))], [first + pair_of]
    if kind == "vertex":
        return [], []
    sizes = np.diff(offsets)
    if (sizes != sizes[0]).any():
        raise ValueError(f"{kind} cells of different sizes")
    return [CellBlock(kind, conn.reshape(cells, int(sizes[0])))], [first + np.arange(cells)]


def grid_blocks(offsets: np.ndarray, conn: np.ndarray,
                types: np.ndarray) -> tuple[list[CellBlock], list[np.ndarray]]:
    """Blocks of an unstructured grid's cells (CSR ``offsets`` (k + 1), ``conn``, VTK
    ``types`` (k,)): one per run of cells of the same kind (file order), and each block's
    cell numbers; shared by the legacy and XML VTK readers.

    Raises
    ------
    ValueError
        ``types`` and ``offsets`` disagree in count, or cells of one unknown type differ in size.
    """
    if len(types) != len(offsets) - 1:
        raise ValueError(f"{len(types)} cell types for {len(offsets) - 1} cells")
    pixels = np.flatnonzero(types == VTK_PIXEL)
    if len(pixels):  # a pixel's corners go row by row: 0 1 3 2 is its boundary
        conn = conn.copy()
        third = offsets[pixels] + 2
        conn[third], conn[third + 1] = conn[third + 1], conn[third].copy()
    present, type_id = np.unique(types, return_inverse=True)
    kinds = [KIND_OF_VTK_TYPE.get(t) or OTHER_VTK_TYPES.get(t) or f"VTK cell type {t}" for t in present.tolist()]
    # runs of one kind (a triangle next to a quad: one run; each unknown type its own kind)
    kind_of_cell = np.unique(kinds, return_inverse=True)[1][type_id]
    cuts = np.flatnonzero(np.diff(kind_of_cell)) + 1
    starts = np.concatenate([[0], cuts]).tolist()
    ends = np.concatenate([cuts, [len(types)]]).tolist()
    blocks: list[CellBlock] = []
    origins: list[np.ndarray] = []
    for a, b in zip(starts, ends):
        got, rows = blocks_of_kind(kinds[type_id[a]], offsets[a:b + 1] - offsets[a], conn[offsets[a]:offsets[b]], a)
        blocks.extend(got)
        origins.extend(rows)
    return blocks, origins
