"""Wavefront OBJ reading: ``v`` and ``f`` records, relative (negative) indices, any polygon.

meshio's OBJ reader subtracts one from every index, so a relative index (``f -3 -2 -1``:
the last three vertices defined so far, as the OBJ specification allows) becomes a
wrong vertex, and it drops faces of mixed size.  This reader follows the specification:
``v x y z [w]`` (``w`` ignored), ``f`` with ``i``, ``i/t``, ``i//n`` or ``i/t/n``
tokens, positive indices one-based, negative ones relative to the vertices read so far;
``l`` polylines become segments; every other record (``vt vn g o s usemtl mtllib``...)
is skipped.  Writing stays with meshio.

Reference: Wavefront OBJ specification, "Referencing vertex data" (B1-B8).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.raw import CellBlock, RawMesh, polygon_blocks

__all__ = ["read_obj"]


def _index(token: str, n_defined: int, path: Path, lineno: int) -> int:
    head = token.split("/", 1)[0]
    try:
        i = int(head)
    except ValueError:
        raise FileFormatError(f"{path}:{lineno}: vertex index is not an integer: {head!r}") from None
    if i > 0:
        return i - 1
    if i < 0 and -i <= n_defined:
        return n_defined + i
    raise FileFormatError(f"{path}:{lineno}: vertex index {i} refers to no vertex ({n_defined} defined so far)")


def read_obj(path: str | Path) -> RawMesh:
    """Points and cells of an OBJ file (see the module docstring).

    Raises
    ------
    FileFormatError
        Not text, a malformed ``v`` or ``f`` record, an index that refers to no vertex.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8", errors="strict")
    except UnicodeDecodeError:
        raise FileFormatError(f"{path}: not a text OBJ file") from None
    coords: list[list[str]] = []
    faces: list[list[int]] = []
    lines: list[list[int]] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        tokens = line.split("#", 1)[0].split()
        if not tokens:
            continue
        key = tokens[0]
        if key == "v":
            if len(tokens) < 4:
                raise FileFormatError(f"{path}:{lineno}: a vertex needs x y z, got {line.strip()!r}")
            coords.append(tokens[1:4])
        elif key == "f":
            if len(tokens) < 4:
                raise FileFormatError(f"{path}:{lineno}: a face needs at least 3 vertices")
            faces.append([_index(t, len(coords), path, lineno) for t in tokens[1:]])
        elif key == "l":
            ids = [_index(t, len(coords), path, lineno) for t in tokens[1:]]
            lines.extend([a, b] for a, b in zip(ids, ids[1:]))
    try:
        points = np.array(coords, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        raise FileFormatError(f"{path}: a vertex coordinate is not a number") from None
    sizes = np.array([len(f) for f in faces], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    connectivity = np.fromiter((i for f in faces for i in f), dtype=np.int64, count=int(offsets[-1]))
    blocks = polygon_blocks(offsets, connectivity)
    if lines:
        blocks.append(CellBlock("line", np.array(lines, dtype=np.int64)))
    return RawMesh(points, blocks)
