"""Wavefront OBJ reading: ``v``, ``f`` and ``l`` records, relative (negative) indices,
any polygon, groups, materials and vertex colours; vectorised.

meshio's OBJ reader subtracts one from every index, so a relative index (``f -3 -2 -1``:
the last three vertices defined so far, as the OBJ specification allows) becomes a
wrong vertex, and it drops faces of mixed size.  This reader follows the specification:

* ``v x y z [w]`` (``w`` ignored); ``v x y z r g b`` (the common colour extension) gives
  point data ``color``; other extra columns on every ``v`` line point data
  ``obj:vertex_fields``; extra columns on some lines only are listed as not carried;
* ``f`` with ``i``, ``i/t``, ``i//n`` or ``i/t/n`` tokens, positive indices one-based,
  negative ones relative to the vertices read so far; ``l`` polylines become segments;
* ``g`` records give cell data ``obj:group_ids`` (as meshio numbers them: each ``g``
  record a new id from 0, -1 before the first), ``usemtl`` records ``obj:material_ids``
  (one id per material name, in order of first use; -1 before the first), the names in
  ``info["obj:materials"]``;
* every other record (``vt vn o s mtllib``...) is skipped.

The lines, fields and indices are found by numba kernels and the coordinates parsed by
numpy's C parser (:mod:`hammesh.io.text_records`): 1 M faces in about half a second,
where a loop over the lines in Python took 5-7 s (as meshio's does).  :func:`write_obj`
writes ``v`` (with the point data ``color`` as ``v x y z r g b [a]``, which this reader
reads back) and one-based ``f`` records through :mod:`hammesh.io.text_rows`, coordinates
to 17 significant digits (exact); meshio's writer formats one line per Python call.

Reference: Wavefront OBJ specification, "Referencing vertex data" (B1-B8).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.raw import CellBlock, RawMesh, polygon_block_rows, polygon_blocks
from hammesh.io.text_rows import vertex_columns, write_rows
from hammesh.io.text_records import BadRecord, as_bytes, field_counts, first_word_codes, index_lists, parse_floats, text_lines

__all__ = ["read_obj", "write_obj", "RECORDS"]

#: The record keywords read; a line's code is 1 + its keyword's place here (0: skipped).
RECORDS = (b"v", b"f", b"l", b"g", b"usemtl")


def read_obj(path: str | Path) -> RawMesh:
    """Points, cells, cell and point data of an OBJ file (see the module docstring).

    Raises
    ------
    FileFormatError
        Not text, a malformed ``v`` or ``f`` record, an index that refers to no vertex.
    """
    path = Path(path)
    data = path.read_bytes()
    try:
        data.decode("utf-8", errors="strict")
    except UnicodeDecodeError:
        raise FileFormatError(f"{path}: not a text OBJ file") from None
    buf = as_bytes(data)
    lines = text_lines(buf, b"#")
    kinds, after = first_word_codes(buf, lines, RECORDS)
    row = None
    try:
        v = np.flatnonzero(kinds == 1)
        row = v
        counts = field_counts(buf, after[v], lines.ends[v], 3, "a vertex needs x y z")
        values = parse_floats(buf, after[v], lines.ends[v], counts)
        first = np.cumsum(counts) - counts
        points = values[first[:, None] + np.arange(3)]
        point_data, loose = _vertex_fields(values, first, counts)
        defined = np.cumsum(kinds == 1) - (kinds == 1)  # vertices read before each line
        f = np.flatnonzero(kinds == 2)
        row = f
        fcounts = field_counts(buf, after[f], lines.ends[f], 3, "a face needs at least 3 vertices")
        faces = index_lists(buf, after[f], lines.ends[f], fcounts, defined=defined[f])
        ln = np.flatnonzero(kinds == 3)
        row = ln
        lcounts = field_counts(buf, after[ln], lines.ends[ln])
        polylines = index_lists(buf, after[ln], lines.ends[ln], lcounts, defined=defined[ln])
    except BadRecord as exc:
        raise FileFormatError(f"{path}:{int(lines.numbers[row[exc.row]])}: {exc.what}") from None
    offsets = np.concatenate([[0], np.cumsum(faces.sizes)])
    blocks = polygon_blocks(offsets, faces.flat)
    face_rows = polygon_block_rows(offsets)
    segments, segment_of = _polyline_segments(polylines)
    if len(segments):
        blocks.append(CellBlock("line", segments))
    cell_data: dict[str, list[np.ndarray]] = {}
    info: dict[str, object] = {}
    for code, name in ((4, "obj:group_ids"), (5, "obj:material_ids")):
        marks = np.flatnonzero(kinds == code)
        if not len(marks):
            continue
        ids = np.arange(len(marks), dtype=np.int64)
        if code == 5:  # one id per material name (few records: a loop over them is cheap)
            names = [data[a:b].decode("utf-8").strip() for a, b in zip(after[marks].tolist(),
                                                                      lines.ends[marks].tolist())]
            unique = list(dict.fromkeys(names))
            ids = np.array([unique.index(x) for x in names], dtype=np.int64)
            info["obj:materials"] = unique
        of_face = _last_mark(marks, f, ids)
        cell_data[name] = [of_face[rows] for rows in face_rows]
        if len(segments):
            cell_data[name].append(_last_mark(marks, ln, ids)[segment_of])
    if loose:
        info["not_carried"] = [loose]
    return RawMesh(points, blocks, cell_data=cell_data, point_data=point_data, info=info)


def write_obj(path: str | Path, points: np.ndarray, triangles: np.ndarray, *,
              colors: np.ndarray | None = None, comment: str = "hammesh") -> None:
    """Write ``points (n, 3)`` and ``triangles (m, 3)`` (zero-based) as an OBJ file.

    ``colors (n, 3 | 4)``, if given, follow each vertex's coordinates.  The caller
    validates the mesh and makes the write atomic (:func:`hammesh.io.write`).
    """
    columns = vertex_columns(points, colors)
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write(f"# {comment}: {len(points)} vertices, {len(triangles)} triangles\n")
        write_rows(f, columns, prefix="v ")
        write_rows(f, list(np.asarray(triangles, dtype=np.int64).T + 1), prefix="f ")


def _vertex_fields(values: np.ndarray, first: np.ndarray, counts: np.ndarray) -> tuple[dict[str, np.ndarray], str]:
    """Point data from the columns after ``x y z`` (see the module docstring), and what
    could not be carried ("" if nothing)."""
    if not len(counts) or counts.max() == 3:
        return {}, ""
    c = int(counts[0])
    if (counts != c).any():
        return {}, "vertex fields beyond x y z (on some v records only)"
    if c == 4:  # the weight w: ignored, as the specification says for vertices
        return {}, ""
    extra = values[first[:, None] + np.arange(3, c)]
    return ({"color": extra} if c in (6, 7) else {"obj:vertex_fields": extra}), ""


def _polyline_segments(polylines) -> tuple[np.ndarray, np.ndarray]:
    """The consecutive pairs of every ``l`` record, and the record each pair came from."""
    sizes = polylines.sizes
    pairs = np.maximum(sizes - 1, 0)
    of = np.repeat(np.arange(len(sizes)), pairs)
    if not len(of):
        return np.zeros((0, 2), np.int64), of
    start = (np.cumsum(sizes) - sizes)[of] + (np.arange(len(of)) - (np.cumsum(pairs) - pairs)[of])
    return np.stack([polylines.flat[start], polylines.flat[start + 1]], axis=1), of


def _last_mark(marks: np.ndarray, rows: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """For each line row in ``rows``: ``ids`` of the last mark line before it (-1: none)."""
    at = np.searchsorted(marks, rows) - 1
    return np.where(at >= 0, ids[np.maximum(at, 0)], -1)
