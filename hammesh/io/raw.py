"""The cells of a mesh file as read, before they become a :class:`~hammesh.mesh.Mesh`.

Readers that hammesh implements itself (OBJ with relative indices, legacy VTK
``POLYDATA``) return a :class:`RawMesh` shaped like a ``meshio.Mesh`` (``points``,
``cells`` blocks with ``type`` and ``data``, ``cell_data``, ``point_data``), so one
conversion (:func:`hammesh.io.meshio_format.to_mesh`) serves every format.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["CellBlock", "RawMesh", "polygon_blocks", "polygon_block_rows"]


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
