"""Geomview OFF reading with faces of any size (meshio 5 reads triangles only).

``OFF`` (optionally followed by the counts on the same line), ``<vertices> <faces>
<edges>``, then one ``x y z`` line per vertex (extra columns, e.g. colours, ignored) and
one ``k i0 .. ik-1`` line per face (a colour after the indices ignored); ``#`` starts a
comment.  Faces of 4 or more corners are split by :func:`hammesh.io.meshio_format.to_mesh`.

Reference: Geomview, "OFF Files" (http://www.geomview.org/docs/html/OFF.html).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.raw import RawMesh, polygon_blocks

__all__ = ["read_off"]


def read_off(path: str | Path) -> RawMesh:
    """Points and polygon cells of an OFF file.

    Raises
    ------
    FileFormatError
        Not an OFF file, a count larger than the file, a malformed line, an index out
        of range.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise FileFormatError(f"{path}: not a text OFF file") from None
    rows = [(k, line.split("#", 1)[0].split()) for k, line in enumerate(text.splitlines(), start=1)]
    rows = [(k, t) for k, t in rows if t]
    if not rows or not rows[0][1][0].upper().endswith("OFF"):
        raise FileFormatError(f"{path}: not an OFF file (no OFF keyword)")
    head = rows[0][1][1:]
    body = rows[1:]
    if len(head) < 2:
        if not body:
            raise FileFormatError(f"{path}: truncated header (no counts)")
        head, body = body[0][1], body[1:]
    try:
        nv, nf = int(head[0]), int(head[1])
    except (ValueError, IndexError):
        raise FileFormatError(f"{path}: the counts line must be '<vertices> <faces> <edges>'") from None
    if nv < 0 or nf < 0 or nv + nf > len(body):
        raise FileFormatError(f"{path}: declares {nv} vertices and {nf} faces, the file has {len(body)} lines")
    try:
        points = np.array([t[:3] for _, t in body[:nv]], dtype=np.float64).reshape(nv, 3)
    except ValueError:
        raise FileFormatError(f"{path}: a vertex line is not 'x y z'") from None
    sizes = np.empty(nf, dtype=np.int64)
    conn: list[int] = []
    for i, (k, t) in enumerate(body[nv:nv + nf]):
        try:
            c = int(t[0])
            ids = [int(v) for v in t[1:1 + c]]
        except ValueError:
            raise FileFormatError(f"{path}:{k}: a face line is not 'k i0 .. ik-1'") from None
        if c < 1 or len(ids) != c:
            raise FileFormatError(f"{path}:{k}: face declares {c} corners, lists {len(ids)}")
        sizes[i] = c
        conn.extend(ids)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return RawMesh(points, polygon_blocks(offsets, np.array(conn, dtype=np.int64)))
