"""Geomview OFF reading with faces of any size and the colours OFF files carry; vectorised.

``[C][N][ST]OFF`` (optionally followed by the counts on the same line; a file without
the keyword, starting with its counts, is read as plain ``OFF``), ``<vertices>
<faces> <edges>``, then one ``x y z`` line per vertex and one ``k i0 .. ik-1`` line per
face; ``#`` starts a comment.  Faces of 4 or more corners are split by
:func:`hammesh.io.meshio_format.to_mesh`.  meshio 5 reads triangles only and drops
colours.

Data after the coordinates and the indices is kept, never dropped in silence:

* vertex columns after ``x y z`` (the same number on every vertex line): point data
  named by the header's prefixes in Geomview's order ``normal`` (``N``, 3), ``color``
  (``C``, 3 or 4), ``texture`` (``ST``, 2); columns the header does not explain (e.g.
  colours in a plain ``OFF``) are ``color`` if 3 or 4, else ``off:vertex_fields``;
* face columns after the indices (a colour: 3 or 4 numbers, or one colour-map index),
  the same number on every face line: cell data ``color``;
* columns on some lines only: listed as not carried.

Lines, fields and indices are found by numba kernels, numbers parsed by numpy's C
parser (:mod:`hammesh.io.text_records`): 1 M faces in well under a second, where a
loop over the lines in Python took 15 s (meshio's, triangles only, 2 s).
:func:`write_off` writes ``OFF`` (``COFF`` with the point data ``color``) through
:mod:`hammesh.io.text_rows`, coordinates to 17 significant digits (exact).

Reference: Geomview, "OFF Files" (http://www.geomview.org/docs/html/OFF.html).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.raw import RawMesh, polygon_block_rows, polygon_blocks
from hammesh.io.text_rows import vertex_columns, write_rows
from hammesh.io.text_records import BadRecord, as_bytes, field_counts, index_lists, parse_floats, text_lines

__all__ = ["read_off", "write_off"]

#: The header keyword: prefixes, then OFF.
_KEYWORD = re.compile(rb"(ST)?(C)?(N)?(4)?(n)?OFF", re.IGNORECASE)


def read_off(path: str | Path) -> RawMesh:
    """Points, polygon cells, point and cell data of an OFF file.

    Raises
    ------
    FileFormatError
        Not an OFF file, a count larger than the file, a malformed line, an index out
        of range.
    """
    path = Path(path)
    data = path.read_bytes()
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        raise FileFormatError(f"{path}: not a text OFF file") from None
    buf = as_bytes(data)
    lines = text_lines(buf, b"#")
    if not len(lines.starts):
        raise FileFormatError(f"{path}: not an OFF file (no OFF keyword)")
    head = data[lines.starts[0]:lines.ends[0]].split()
    keyword = _KEYWORD.fullmatch(head[0])
    headless = keyword is None and 2 <= len(head) <= 3 and all(t.isdigit() for t in head)
    if headless:  # Geomview: "recommended but optional, as many existing files lack this keyword"
        keyword, head = _KEYWORD.fullmatch(b"OFF"), [b"OFF", *head]
    if keyword is None:
        if not head[0].upper().endswith(b"OFF"):
            raise FileFormatError(f"{path}: not an OFF file (no OFF keyword)")
        raise FileFormatError(f"{path}: {head[0].decode(errors='replace')!r} files are not read "
                              "(OFF with the prefixes ST, C, N)")
    if keyword.group(4) or keyword.group(5):
        raise FileFormatError(f"{path}: {head[0].decode()!r}: 4D and n-dimensional OFF files are not read")
    body = 1
    counts_line = head[1:]
    if len(counts_line) < 2:
        if len(lines.starts) < 2:
            raise FileFormatError(f"{path}: truncated header (no counts)")
        counts_line = data[lines.starts[1]:lines.ends[1]].split()
        body = 2
    try:
        nv, nf = int(counts_line[0]), int(counts_line[1])
    except (ValueError, IndexError):
        raise FileFormatError(f"{path}: the counts line must be '<vertices> <faces> <edges>'") from None
    rows = len(lines.starts) - body
    if nv < 0 or nf < 0 or nv + nf > rows:
        raise FileFormatError(f"{path}: declares {nv} vertices and {nf} faces, the file has {rows} lines")
    v = np.arange(body, body + nv)
    f = np.arange(body + nv, body + nv + nf)
    starts, ends = lines.starts, lines.ends
    row = v
    try:
        vcounts = field_counts(buf, starts[v], ends[v], 3, "a vertex line is not 'x y z'")
        values = parse_floats(buf, starts[v], ends[v], vcounts)
        first = np.cumsum(vcounts) - vcounts
        points = values[first[:, None] + np.arange(3)]
        row = f
        fcounts = field_counts(buf, starts[f], ends[f])
        try:
            corners = index_lists(buf, starts[f], ends[f], np.minimum(fcounts, 1), take=np.ones(nf, np.int64)).flat
        except BadRecord as exc:
            raise BadRecord(exc.row, "a face line is not 'k i0 .. ik-1'") from None
        if len(corners) != nf or (corners < 1).any():
            bad = int(np.flatnonzero(fcounts < 1)[0]) if len(corners) != nf else int(np.flatnonzero(corners < 1)[0])
            raise BadRecord(bad, "a face line is not 'k i0 .. ik-1'")
        faces = index_lists(buf, starts[f], ends[f], fcounts, skip=1, take=corners)
        short = np.flatnonzero(faces.sizes != corners)
        if len(short):
            i = int(short[0])
            raise BadRecord(i, f"face declares {int(corners[i])} corners, lists {int(faces.sizes[i])}")
        extra = fcounts - 1 - corners
        face_values = parse_floats(buf, starts[f], ends[f], fcounts) if extra.any() else None
    except BadRecord as exc:
        raise FileFormatError(f"{path}:{int(lines.numbers[row[exc.row]])}: {exc.what}") from None
    offsets = np.concatenate([[0], np.cumsum(corners)])
    blocks = polygon_blocks(offsets, faces.flat)
    not_carried: list[str] = []
    point_data = _vertex_columns(keyword, values, first, vcounts, not_carried)
    cell_data: dict[str, list[np.ndarray]] = {}
    if face_values is not None:
        c = int(extra[0])
        if (extra != c).any():
            not_carried.append("face columns after the indices (on some face lines only)")
        else:
            at = (np.cumsum(fcounts) - fcounts + 1 + corners)[:, None] + np.arange(c)
            colours = face_values[at] if c > 1 else face_values[at[:, 0]]
            cell_data["color"] = [colours[rows] for rows in polygon_block_rows(offsets)]
    return RawMesh(points, blocks, cell_data=cell_data, point_data=point_data,
                   info={"not_carried": not_carried} if not_carried else {})


def write_off(path: str | Path, points: np.ndarray, triangles: np.ndarray, *,
              colors: np.ndarray | None = None) -> None:
    """Write ``points (n, 3)`` and ``triangles (m, 3)`` as an OFF (``COFF`` with ``colors (n, 3 | 4)``).

    The caller validates the mesh and makes the write atomic (:func:`hammesh.io.write`).
    """
    triangles = np.asarray(triangles, dtype=np.int64)
    columns = vertex_columns(points, colors)
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write(f"{'C' if colors is not None else ''}OFF\n{len(points)} {len(triangles)} 0\n")
        write_rows(f, columns)
        write_rows(f, list(triangles.T), prefix="3 ")


def _vertex_columns(keyword: re.Match, values: np.ndarray, first: np.ndarray, counts: np.ndarray,
                    not_carried: list[str]) -> dict[str, np.ndarray]:
    """Point data from the vertex columns after ``x y z`` (see the module docstring)."""
    if not len(counts) or counts.max() == 3:
        return {}
    c = int(counts[0])
    if (counts != c).any():
        not_carried.append("vertex columns after x y z (on some vertex lines only)")
        return {}
    columns = values[first[:, None] + np.arange(3, c)]
    named: list[tuple[str, int]] = []
    if keyword.group(3):
        named.append(("normal", 3))
    if keyword.group(2):
        named.append(("color", 4 if c - 3 - 3 * bool(keyword.group(3)) - 2 * bool(keyword.group(1)) == 4 else 3))
    if keyword.group(1):
        named.append(("texture", 2))
    if sum(w for _, w in named) == c - 3 and named:
        out, at = {}, 0
        for name, width in named:
            out[name] = columns[:, at:at + width]
            at += width
        return out
    return {"color": columns} if c - 3 in (3, 4) else {"off:vertex_fields": columns}
