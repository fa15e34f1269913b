"""PLY reading (ASCII, binary little- and big-endian), every property kept; vectorised.

meshio 5's PLY reader fails on the files VTK and pyvista write with face colours
(``property uchar red`` after the face's index list, binary: ``TypeError: object of
type 'numpy.int8' has no len()``) and reads ASCII files line by line in Python (6 s
for 1 M triangles).  This reader follows the PLY format as Greg Turk described it:

* the header: ``format``, ``element NAME COUNT``, ``property TYPE NAME``, ``property
  list COUNT_TYPE ITEM_TYPE NAME`` (types ``char uchar short ushort int uint float
  double`` and their ``int8`` ... ``float64`` names), ``comment``/``obj_info`` skipped;
* ``vertex``: ``x y z`` the points, every other scalar property point data under its
  name (``nx``, ``red``, ``u``...);
* ``face``: the list ``vertex_indices`` (or ``vertex_index``) the polygons, every other
  scalar property cell data under its name;
* ``edge``: ``vertex1 vertex2`` segments;
* other elements and other list properties: listed as not carried (never dropped in silence).

Vectors: properties ``v_0 .. v_{c-1}`` are one ``(n, c)`` array ``v`` when a header line
``comment hammesh vectors v:c`` says so (as :func:`write_ply` writes them: brackets in
vertex property names break meshio's ASCII reader); properties named ``v[0]``,
``v[1]``, ... are one vector ``v`` too.

:func:`write_ply` writes every numeric point and cell datum as a vertex or face property
(meshio 5's writer drops cell data and vector point data): ``int64`` as ``int`` when it
fits, else ``double`` (exact below 2**53); binary little-endian, or ASCII (exact) when
there are face properties, which meshio 5's binary reader cannot read.

Binary records are walked by a numba kernel (each property's position in each record:
lists make records of different sizes) and the values gathered by numpy; ASCII files
are tokenised by :mod:`hammesh.io.text_records` (one record per line).

Reference: Greg Turk, "The PLY Polygon File Format" (1994),
https://paulbourke.net/dataformats/ply/.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from urllib.parse import unquote

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.cell_data import join_components
from hammesh.io.text_rows import header_token, write_rows

#: characters of a data name that are not kept in a PLY property name (see _ply_columns)
_PLY_UNSAFE = re.compile(r"[^A-Za-z0-9_]")
from hammesh.io.raw import CellBlock, RawMesh, polygon_block_rows, polygon_blocks

__all__ = ["read_ply", "write_ply", "PLY_TYPES"]

#: numpy type code of each PLY type name.
PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_MAX_HEADER = 1 << 20
_FACE_LISTS = ("vertex_indices", "vertex_index")


@dataclass(frozen=True)
class _Property:
    name: str
    dtype: np.dtype  # the item type
    count: np.dtype | None = None  # a list's count type, None for a scalar


@dataclass(frozen=True)
class _Element:
    name: str
    rows: int
    properties: tuple[_Property, ...]


class _Bad(Exception):
    """A defect of the file (read_ply adds the file's name)."""


def read_ply(path: str | Path) -> RawMesh:
    """Points, polygon and line cells, point and cell data of a PLY file.

    Raises
    ------
    FileFormatError
        No PLY header, an unknown type or format, a count beyond the file's data, an
        index that is not an integer.
    """
    path = Path(path)
    data = path.read_bytes()
    try:
        fmt, elements, body = _header(data)
        values = (_read_ascii if fmt == "ascii" else _read_binary)(data, body, elements, fmt)
        return _mesh(elements, values, _header_vectors(data), _header_names(data))
    except _Bad as exc:
        raise FileFormatError(f"{path}: {exc}") from None


def _header(data: bytes) -> tuple[str, list[_Element], int]:
    end = data.find(b"end_header", 0, _MAX_HEADER)
    if not data.startswith(b"ply") or end < 0:
        raise _Bad("not a PLY file or truncated header (no end_header)")
    body = data.find(b"\n", end)
    body = len(data) if body < 0 else body + 1
    fmt = None
    elements: list[_Element] = []
    props: list[_Property] = []
    for raw in data[:end].decode("latin-1").splitlines()[1:]:
        words = raw.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) >= 2:
            fmt = words[1]
        elif words[0] == "element" and len(words) == 3:
            if elements:
                elements[-1] = _Element(elements[-1].name, elements[-1].rows, tuple(props))
            props = []
            try:
                rows = int(words[2])
            except ValueError:
                raise _Bad(f"element {words[1]!r}: count {words[2]!r} is not an integer") from None
            if rows < 0:
                raise _Bad(f"element {words[1]!r}: negative count {rows}")
            elements.append(_Element(words[1], rows, ()))
        elif words[0] == "property" and elements:
            if len(words) == 5 and words[1] == "list":
                props.append(_Property(words[4], _type(words[3]), _type(words[2])))
            elif len(words) == 3:
                props.append(_Property(words[2], _type(words[1])))
            else:
                raise _Bad(f"malformed property line {raw.strip()!r}")
        else:
            raise _Bad(f"unknown header line {raw.strip()!r}")
    if elements:
        elements[-1] = _Element(elements[-1].name, elements[-1].rows, tuple(props))
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise _Bad(f"unknown format {fmt!r}")
    return fmt, elements, body


def _type(name: str) -> np.dtype:
    try:
        return np.dtype(PLY_TYPES[name])
    except KeyError:
        raise _Bad(f"unknown property type {name!r}") from None


def _read_binary(data: bytes, body: int, elements: list[_Element], fmt: str) -> dict[str, dict[str, object]]:
    """Every element's properties: scalars ``(rows,)``, lists ``(counts, items)``."""
    from hammesh.io._kernels import ply_record_positions_into

    order = "<" if fmt == "binary_little_endian" else ">"
    buf = np.frombuffer(data, dtype=np.uint8)
    out: dict[str, dict[str, object]] = {}
    pos = body
    for el in elements:
        sizes = np.array([p.dtype.itemsize for p in el.properties], np.int64)
        counts = np.array([p.count.itemsize if p.count is not None else 0 for p in el.properties], np.int64)
        signed = np.array([p.count is not None and p.count.kind == "i" for p in el.properties], np.bool_)
        smallest = int(np.where(counts > 0, counts, sizes).sum())  # a record's bytes with empty lists
        if el.rows * smallest > len(data) - pos:  # (before any allocation: counts may be corrupt)
            raise _Bad(f"element {el.name!r}: {el.rows} records do not fit the file (truncated?)")
        at = np.empty((el.rows, len(el.properties)), np.int64)
        items = np.empty((el.rows, len(el.properties)), np.int64)
        pos = ply_record_positions_into(buf, pos, sizes, counts, signed, order == ">", at, items)
        if pos < 0:
            raise _Bad(f"element {el.name!r}: {el.rows} records do not fit the file (truncated?)")
        props: dict[str, object] = {}
        uniform = _uniform_records(data, at, items, el, order)
        if uniform is not None:  # every record the same layout (the usual case): a view
            out[el.name] = uniform
            continue
        for j, p in enumerate(el.properties):
            dt = p.dtype.newbyteorder(order)
            if p.count is None:
                props[p.name] = _gather(buf, at[:, j], 1, dt).reshape(-1)
            else:
                n = items[:, j]
                first = np.repeat(at[:, j] + p.count.itemsize - (np.cumsum(n) - n) * p.dtype.itemsize, n)
                starts = first + np.arange(int(n.sum())) * p.dtype.itemsize
                props[p.name] = (n, _gather(buf, starts, 1, dt).reshape(-1))
        out[el.name] = props
    return out


def _uniform_records(data: bytes, at: np.ndarray, items: np.ndarray, el: _Element,
                     order: str) -> dict[str, object] | None:
    """The element's properties through one structured dtype, if every record has the
    same list lengths (then the records are equal in size); else None."""
    if not el.rows or (items != items[0]).any():
        return None
    fields = []
    for j, p in enumerate(el.properties):
        if p.count is not None:
            fields.append((f"count {j}", p.count.newbyteorder(order)))
            fields.append((f"items {j}", p.dtype.newbyteorder(order), (int(items[0, j]),)))
        else:
            fields.append((f"value {j}", p.dtype.newbyteorder(order)))
    table = np.frombuffer(data, dtype=np.dtype(fields), count=el.rows, offset=int(at[0, 0]))
    props: dict[str, object] = {}
    for j, p in enumerate(el.properties):
        if p.count is None:
            props[p.name] = table[f"value {j}"].astype(p.dtype)
        else:
            props[p.name] = (items[:, j].copy(), table[f"items {j}"].astype(p.dtype).reshape(-1))
    return props


def _gather(buf: np.ndarray, starts: np.ndarray, width: int, dt: np.dtype) -> np.ndarray:
    """``width`` values of type ``dt`` at every byte position in ``starts``."""
    size = dt.itemsize * width
    raw = buf[starts[:, None] + np.arange(size)] if len(starts) else np.zeros((0, size), np.uint8)
    return np.ascontiguousarray(raw).view(dt).astype(dt.newbyteorder("="))


def _read_ascii(data: bytes, body: int, elements: list[_Element], fmt: str) -> dict[str, dict[str, object]]:
    """As :func:`_read_binary`, one record per line (values parsed as float64, then cast)."""
    from hammesh.io._kernels import ply_value_positions_into
    from hammesh.io.text_records import BadRecord, as_bytes, field_counts, parse_floats, text_lines

    buf = as_bytes(data)
    lines = text_lines(buf[body:], b"\n")  # (no comments in a PLY body)
    starts, ends = lines.starts + body, lines.ends + body
    out: dict[str, dict[str, object]] = {}
    row = 0
    for el in elements:
        if row + el.rows > len(starts):
            raise _Bad(f"element {el.name!r}: declares {el.rows} records, the file has {len(starts) - row} lines left")
        s, e = starts[row:row + el.rows], ends[row:row + el.rows]
        n = field_counts(buf, s, e)
        try:
            values = parse_floats(buf, s, e, n)
        except BadRecord as exc:
            raise _Bad(f"element {el.name!r}, record {exc.row}: a value is not a number") from None
        lists = np.array([p.count is not None for p in el.properties], np.bool_)
        at = np.empty((el.rows, len(el.properties)), np.int64)
        items = np.empty((el.rows, len(el.properties)), np.int64)
        bad = ply_value_positions_into(values, np.cumsum(n) - n, n, lists, at, items)
        if bad >= 0:
            raise _Bad(f"element {el.name!r}, record {bad}: the fields do not match the properties")
        props: dict[str, object] = {}
        for j, p in enumerate(el.properties):
            if p.count is None:
                props[p.name] = _cast(values[at[:, j]], p.dtype, el.name, p.name)
            else:
                k = items[:, j]
                idx = np.repeat(at[:, j] + 1 - (np.cumsum(k) - k), k) + np.arange(int(k.sum()))
                props[p.name] = (k, _cast(values[idx], p.dtype, el.name, p.name))
        out[el.name] = props
        row += el.rows
    return out


def _cast(values: np.ndarray, dt: np.dtype, element: str, name: str) -> np.ndarray:
    if dt.kind == "f":
        return values.astype(dt)
    if not np.all(values == np.round(values)):
        raise _Bad(f"element {element!r}, property {name!r}: a value is not an integer")
    return values.astype(dt)


def _mesh(elements: list[_Element], values: dict[str, dict[str, object]], vectors: dict[str, int],
          names: dict[str, dict[str, str]]) -> RawMesh:
    vertex = values.get("vertex", {})
    if not all(k in vertex for k in "xyz"):
        raise _Bad("no vertex element with properties x y z")
    points = np.column_stack([np.asarray(vertex[k], np.float64) for k in "xyz"])
    not_carried: list[str] = []
    point_data = {}
    for name, v in vertex.items():
        if name in ("x", "y", "z"):
            continue
        if isinstance(v, tuple):
            not_carried.append(f"vertex list property {name!r}")
        else:
            point_data[name] = v
    renamed = names.get("vertex", {})
    point_data = {renamed.get(k, k): v for k, v in _joined_vectors(point_data, vectors).items()}
    blocks: list[CellBlock] = []
    cell_data: dict[str, list[np.ndarray]] = {}
    face = values.get("face", {})
    key = next((k for k in _FACE_LISTS if k in face), None)
    if key is not None:
        sizes, flat = face[key]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        blocks = polygon_blocks(offsets, flat.astype(np.int64))
        rows = polygon_block_rows(offsets)
        scalars = {}
        for name, v in face.items():
            if name == key:
                continue
            if isinstance(v, tuple):
                not_carried.append(f"face list property {name!r}")
            else:
                scalars[name] = v
        for name, v in join_components(_joined_vectors(scalars, vectors)).items():
            cell_data[names.get("face", {}).get(name, name)] = [v[r] for r in rows]
    edge = values.get("edge", {})
    if "vertex1" in edge and "vertex2" in edge:
        blocks.append(CellBlock("line", np.column_stack([edge["vertex1"], edge["vertex2"]]).astype(np.int64)))
        for name in cell_data:
            cell_data[name].append(np.full(len(edge["vertex1"]), np.nan))
    for el in elements:
        if el.name not in ("vertex", "face", "edge") and el.rows:
            not_carried.append(f"element {el.name!r} ({el.rows} records)")
    return RawMesh(points, blocks, cell_data=cell_data, point_data=point_data,
                   info={"not_carried": not_carried} if not_carried else {})


#: PLY type name of each numpy type written (PLY has no 64-bit integers).
_WRITE_TYPES = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int", "u4": "uint",
                "f4": "float", "f8": "double", "b1": "uchar"}


def _ply_columns(data: dict[str, np.ndarray], rows: int, taken: set[str],
                 element: str) -> tuple[list[tuple[str, np.ndarray]], list[str], list[str]]:
    """``(property name, column)`` of every numeric array of ``data`` (a vector ``v`` as
    ``v_0``, ``v_1``...; 64-bit integers as ``int`` if they fit, else ``double``), the
    vectors as ``v:c`` for the header's ``comment hammesh vectors`` line, and
    ``"element token name"`` (``text_rows.header_token``'s encoding) for each ``comment
    hammesh name`` line of a name that is not its property's."""
    out, vectors, renamed = [], [], []
    for name, values in data.items():
        values = np.asarray(values)
        if values.dtype.kind not in "biuf" or len(values) != rows:
            continue
        values = values.reshape(rows, -1)
        c = values.shape[1]
        # a property name meshio's reader takes (numpy's genfromtxt drops any other
        # character); the exact name goes in a ``comment hammesh name`` line
        token = _PLY_UNSAFE.sub("_", str(name)) or "_"
        names = lambda t: [t] if c == 1 else [f"{t}_{j}" for j in range(c)]  # noqa: E731
        while token in taken or taken.intersection(names(token)):  # (x y z, another field's)
            token = f"input_{token}"
        taken.update([token, *names(token)])
        if values.dtype.itemsize == 8 and values.dtype.kind in "iu":
            small = not values.size or (values.min() >= -2**31 and values.max() < 2**31)
            values = values.astype(np.int32 if small else np.float64)
        elif values.dtype.kind == "b":
            values = values.astype(np.uint8)
        out += [(label, values[:, j]) for j, label in enumerate(names(token))]
        if c > 1:
            vectors.append(f"{token}:{c}")
        if token != name:
            renamed.append(f"{element} {token} {header_token(name)}")
    return out, vectors, renamed


def _joined_vectors(data: dict[str, np.ndarray], vectors: dict[str, int]) -> dict[str, np.ndarray]:
    """The components ``v_0 .. v_{c-1}`` of each vector ``v: c`` of the header's
    ``comment hammesh vectors`` line as one ``(rows, c)`` array ``v`` (in ``v_0``'s place)."""
    out: dict[str, np.ndarray] = {}
    for name, values in data.items():
        base, _, j = name.rpartition("_")
        c = vectors.get(base, 0)
        parts = [data.get(f"{base}_{i}") for i in range(c)]
        if j == "0" and c and all(p is not None and np.ndim(p) == 1 for p in parts):
            out[base] = np.column_stack(parts)
        elif not (c and j.isdigit() and int(j) < c and base in out):
            out[name] = values
    return out


def _header_vectors(data: bytes) -> dict[str, int]:
    """``{name: components}`` from ``comment hammesh vectors v:3 w:2`` header lines."""
    out: dict[str, int] = {}
    end = data.find(b"end_header", 0, _MAX_HEADER)
    for raw in data[:max(end, 0)].decode("latin-1").splitlines():
        words = raw.split()
        if words[:3] == ["comment", "hammesh", "vectors"]:
            for word in words[3:]:
                name, _, c = word.rpartition(":")
                if name and c.isdigit() and int(c) > 1:
                    out[name] = int(c)
    return out


def _header_names(data: bytes) -> dict[str, dict[str, str]]:
    """``{element: {property name: data name}}`` from ``comment hammesh name ELEMENT TOKEN
    NAME`` header lines (``NAME`` in ``text_rows.header_token``'s %XX encoding)."""
    out: dict[str, dict[str, str]] = {}
    end = data.find(b"end_header", 0, _MAX_HEADER)
    for raw in data[:max(end, 0)].decode("latin-1").splitlines():
        words = raw.split()
        if words[:3] == ["comment", "hammesh", "name"] and len(words) == 6:
            out.setdefault(words[3], {})[words[4]] = unquote(words[5])
    return out


def _records(columns: list[tuple[str, np.ndarray]], rows: int) -> np.ndarray:
    """The columns as packed little-endian records (one per row)."""
    dtype = np.dtype([(f"f{j}", c.dtype.newbyteorder("<")) for j, (_, c) in enumerate(columns)])
    out = np.empty(rows, dtype=dtype)
    for j, (_, c) in enumerate(columns):
        out[f"f{j}"] = c
    return out


def write_ply(path: str | Path, points: np.ndarray, triangles: np.ndarray, *,
              point_data: dict[str, np.ndarray] | None = None,
              cell_data: dict[str, np.ndarray] | None = None) -> None:
    """Write ``points (n, 3)``, ``triangles (m, 3)`` and their data as PLY.

    ``point_data`` / ``cell_data``: arrays ``(n,)``/``(n, c)`` and ``(m,)``/``(m, c)``
    written as vertex and face properties (see the module docstring; :func:`read_ply`
    reads them back).  Binary little-endian, or ASCII when there are face properties:
    meshio 5's binary reader fails on those (its ASCII reader takes them); ASCII values
    are exact (:mod:`hammesh.io.text_rows`).  The caller validates the mesh and makes
    the write atomic (:func:`hammesh.io.write`).
    """
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    n, m = len(points), len(triangles)
    vertex = [("x", points[:, 0]), ("y", points[:, 1]), ("z", points[:, 2])]
    vertex_props, vertex_vectors, vertex_names = _ply_columns(point_data or {}, n, {"x", "y", "z"}, "vertex")
    vertex += vertex_props
    face_props, face_vectors, face_names = _ply_columns(cell_data or {}, m, {"vertex_indices"}, "face")
    binary = not face_props
    head = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0", "comment written by hammesh"]
    if vertex_vectors or face_vectors:
        head.append(f"comment hammesh vectors {' '.join(vertex_vectors + face_vectors)}")
    head += [f"comment hammesh name {pair}" for pair in vertex_names + face_names]
    head.append(f"element vertex {n}")
    head += [f"property {_WRITE_TYPES[c.dtype.str[1:]]} {name}" for name, c in vertex]
    head += [f"element face {m}", "property list uchar int vertex_indices"]
    head += [f"property {_WRITE_TYPES[c.dtype.str[1:]]} {name}" for name, c in face_props]
    head.append("end_header\n")
    if binary:
        face = [("", np.full(m, 3, np.uint8)), *[("", triangles[:, k].astype(np.int32)) for k in range(3)]]
        with open(path, "wb") as f:
            f.write("\n".join(head).encode("ascii"))
            f.write(_records(vertex, n).tobytes())
            f.write(_records(face, m).tobytes())
        return
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write("\n".join(head))
        write_rows(f, [c for _, c in vertex])
        write_rows(f, [*triangles.T, *(c for _, c in face_props)], prefix="3 ")
