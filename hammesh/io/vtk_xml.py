"""VTK XML files: PolyData (``.vtp``) and UnstructuredGrid (``.vtu``), as pyvista's ``save``,
ParaView and VTK's XML writers write them.

meshio 5 neither reads nor writes ``.vtp``, and refuses ``.vtu`` files that VTK reads
(``compressor="vtkLZ4DataCompressor"``: ``KeyError``; any compressor named on an ASCII
file: ``AssertionError``).  :func:`write_vtp` writes hammesh's output (triangles as
``Polys``, segments as ``Lines``) compressed like :mod:`hammesh.io.vtu` (which writes
``.vtu``).  :func:`read_vtk_xml` reads every encoding VTK's XML writers write:

* ``<DataArray format="ascii">``: whitespace-separated values;
* ``format="binary"``: base64 of a header and the bytes, the header ``UInt32`` or
  ``UInt64`` (``header_type``).  Uncompressed: one item, the byte count.  Compressed
  (``compressor="vtkZLibDataCompressor"``, ``vtkLZMADataCompressor``;
  ``vtkLZ4DataCompressor``, decoded by hammesh's own kernel: no ``lz4`` package needed):
  ``[blocks, block size, last block size, compressed size of each block]`` then the
  compressed blocks.  VTK encodes the header and the data separately (two base64 runs,
  the first padded); one run over both is read too;
* ``format="appended"``: the same header and data at ``offset`` in ``<AppendedData>``,
  ``encoding="raw"`` (bytes after the ``_`` mark) or ``"base64"``;
* ``byte_order`` ``LittleEndian`` or ``BigEndian``; types ``Int8`` ... ``UInt64``,
  ``Float32``, ``Float64`` and ``Bit`` (binary: eight to a byte, first value in the
  most significant bit).

Cells: PolyData's ``Verts``, ``Lines``, ``Polys`` and ``Strips`` (``connectivity`` and
``offsets``, the offsets being each cell's end), in that order, which is VTK's cell
numbering for cell data; an UnstructuredGrid's ``Cells`` (``connectivity``, ``offsets``,
``types``: :func:`hammesh.io.raw.grid_blocks`, pixels and quads included, volume cells
named for the refusal).  Polygons become triangle, quad and polygon blocks, strips
triangles with VTK's alternating winding, polylines their segments, vertices nothing
(:func:`hammesh.io.raw.blocks_of_kind`, shared with the legacy reader); each cell's data
follows its triangles and segments.  Pieces are concatenated (their point indices
offset by the points before them); point and cell data arrays present in every piece
(``NumberOfComponents`` kept) are read, ``String`` arrays and ``FieldData`` skipped.

Learned from meshio 5.3's ``meshio/vtu/_vtu.py`` (``VtuReader``: the block header of
compressed arrays, a raw ``<AppendedData>`` split off before the XML is parsed); written
anew for PolyData and grids, big-endian files, either base64 layout and bounds checked before any
read.  Reference: "VTK File Formats", *Serial XML file formats*
(https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html).
"""

from __future__ import annotations

import base64
import binascii
import lzma
import os
import xml.etree.ElementTree as ET
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from hammesh import threads as row_threads
from hammesh.errors import FileFormatError
from hammesh.io.raw import CellBlock, RawMesh, blocks_of_kind, grid_blocks
from hammesh.io.vtu import write_data_array, write_data_sections

__all__ = ["read_vtk_xml", "write_vtp", "COMPRESSORS", "VTK_TYPES", "DATASETS"]

#: numpy type code of each VTK XML ``type`` (``Bit``: unpacked to one byte per value).
VTK_TYPES: dict[str, str] = {
    "Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "Int32": "i4", "UInt32": "u4",
    "Int64": "i8", "UInt64": "u8", "Float32": "f4", "Float64": "f8", "Bit": "u1",
}
#: The ``compressor`` values read.
COMPRESSORS = ("vtkZLibDataCompressor", "vtkLZMADataCompressor", "vtkLZ4DataCompressor")

#: VTK's cell order in a piece, and how each section's cells become blocks.
_SECTIONS = {"Verts": "vertex", "Lines": "line", "Polys": "polygon", "Strips": "strip"}
_HEADER_TYPES = {"UInt32": "u4", "UInt64": "u8"}
#: The XML dataset types read, by file suffix.
DATASETS = {".vtp": "PolyData", ".vtu": "UnstructuredGrid"}


class _Bad(Exception):
    """A defect of the file, said in words (read_vtk_xml adds the file's name)."""


@dataclass(frozen=True)
class _Encoding:
    """What every binary array of one file shares."""

    order: str  # "<" or ">"
    header: np.dtype  # UInt32 or UInt64 in the file's byte order
    compressor: str | None
    appended: memoryview | None  # bytes after AppendedData's "_" mark (base64: up to its end tag)
    appended_base64: bool


def read_vtk_xml(path: str | Path) -> RawMesh:
    """Points, cells and point/cell data of a VTK XML PolyData (``.vtp``) or
    UnstructuredGrid (``.vtu``) file.

    Parameters
    ----------
    path : path-like
        A ``.vtp`` or ``.vtu`` file in any encoding VTK writes (see the module notes); the
        suffix says which dataset type it must hold.

    Returns
    -------
    RawMesh
        ``points (n, 3)``; triangle/quad/polygon blocks (polygons and strips), ``line``
        blocks (polylines); cell data per block, point data ``(n,)`` or ``(n, c)``.

    Raises
    ------
    FileFormatError
        Malformed XML, not the suffix's dataset type, an unknown type or compressor, truncated or
        undecodable data, counts that disagree, an index out of range.  The message
        names the file.
    """
    path = Path(path)
    try:
        return _read(path.read_bytes(), DATASETS.get(path.suffix.lower(), "PolyData"))
    except _Bad as exc:
        raise FileFormatError(f"{path}: {exc}") from None
    except ET.ParseError as exc:
        raise FileFormatError(f"{path}: malformed XML ({exc})") from None
    except MemoryError:
        raise FileFormatError(f"{path}: sizes beyond this machine's memory (corrupt counts?)") from None
    except (ValueError, TypeError, IndexError, OverflowError, binascii.Error, zlib.error, lzma.LZMAError) as exc:
        detail = str(exc).strip().splitlines()
        raise FileFormatError(
            f"{path}: malformed {path.suffix} data ({type(exc).__name__}: {detail[0] if detail else ''})") from None


def write_vtp(path: str | os.PathLike[str], mesh: Any, threads: int | None = None) -> None:
    """Write ``mesh`` (a ``meshio.Mesh`` of ``triangle`` and ``line`` blocks) as a compressed
    ``.vtp``: the arrays as :func:`hammesh.io.vtu.write` writes them (zlib blocks, base64),
    the triangles as ``Polys``, the lines as ``Lines``.  VTK numbers lines before polygons,
    so the cell data is reordered the same way: each cell keeps its values.

    Raises
    ------
    ValueError
        A cell type other than ``triangle``/``line`` (hammesh writes no other).
    """
    kinds = {"line": "Lines", "triangle": "Polys"}
    for block in mesh.cells:
        if block.type not in kinds:
            raise ValueError(f"hammesh.io.vtk_xml: cell type {block.type!r} is not supported")
    order = [i for kind in ("line", "triangle") for i, b in enumerate(mesh.cells) if b.type == kind]
    sections = {}
    for kind, section in kinds.items():
        cells = [np.asarray(b.data, dtype=np.int64) for b in mesh.cells if b.type == kind]
        if cells:
            sections[section] = np.concatenate(cells)
    cell_data = {name: np.concatenate([np.asarray(per_block[i]) for i in order])
                 for name, per_block in mesh.cell_data.items()}
    counts = {s: len(sections.get(s, ())) for s in ("Lines", "Polys")}
    workers = max(1, threads or row_threads.cores())
    with ThreadPoolExecutor(workers) as pool, open(path, "wb") as fh:
        fh.write(b'<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
                 b'header_type="UInt32" compressor="vtkZLibDataCompressor">\n'
                 b"<!--This file was created by hammesh-->\n<PolyData>\n")
        fh.write(f'<Piece NumberOfPoints="{len(mesh.points)}" NumberOfVerts="0" NumberOfLines="{counts["Lines"]}" '
                 f'NumberOfStrips="0" NumberOfPolys="{counts["Polys"]}">\n'.encode())
        fh.write(b"<Points>\n")
        write_data_array(fh, pool, workers, "Points", np.asarray(mesh.points, dtype=np.float64))
        fh.write(b"</Points>\n")
        for section, cells in sections.items():
            fh.write(f"<{section}>\n".encode())
            write_data_array(fh, pool, workers, "connectivity", cells.reshape(-1))
            write_data_array(fh, pool, workers, "offsets", np.arange(1, len(cells) + 1, dtype=np.int64) * cells.shape[1])
            fh.write(f"</{section}>\n".encode())
        write_data_sections(fh, pool, workers, mesh.point_data, cell_data)
        fh.write(b"</Piece>\n</PolyData>\n</VTKFile>\n")


def _read(raw: bytes, dataset: str) -> RawMesh:
    xml, appended, encoding = _split_appended(raw)
    root = ET.fromstring(xml)
    if root.tag != "VTKFile":
        raise _Bad(f"not a VTK XML file (root element <{root.tag}>)")
    if root.get("type") != dataset:
        suffix = {v: k for k, v in DATASETS.items()}[dataset]
        raise _Bad(f"not VTK {dataset} (type={root.get('type')!r}); {suffix} holds {dataset}")
    enc = _encoding(root, appended, encoding)
    grid = root.find(dataset)
    if grid is None:
        raise _Bad(f"no <{dataset}> element")
    pieces = grid.findall("Piece")
    if not pieces:
        raise _Bad(f"no <Piece> in <{dataset}>")
    points, blocks, origins = [], [], []
    point_arrays: list[dict[str, np.ndarray]] = []
    cell_arrays: list[dict[str, np.ndarray]] = []
    n_points = n_cells = 0
    for number, piece in enumerate(pieces):
        where = f"piece {number}" if len(pieces) > 1 else "piece"
        pts, got, rows, cells = _piece(piece, enc, n_points, n_cells, where)
        points.append(pts)
        blocks += got
        origins += rows
        point_arrays.append(_attributes(piece.find("PointData"), len(pts), enc, f"{where} PointData"))
        cell_arrays.append(_attributes(piece.find("CellData"), cells, enc, f"{where} CellData"))
        n_points += len(pts)
        n_cells += cells
    cell_data = {name: [_rows(values, o) for o in origins] for name, values in _joined(cell_arrays).items()}
    return RawMesh(np.concatenate(points), blocks, cell_data=cell_data, point_data=_joined(point_arrays))


def _split_appended(raw: bytes) -> tuple[bytes, memoryview | None, str]:
    """The XML part of the file (closed again after the ``<AppendedData ...>`` tag), a view
    of the appended data after its ``_`` mark (base64: up to the end tag) and its encoding.

    Raw appended data is not XML: it is cut off before parsing (as meshio does)."""
    at = raw.find(b"<AppendedData")
    if at < 0:
        return raw, None, "raw"
    close = raw.find(b">", at)
    if close < 0:
        raise _Bad("truncated <AppendedData> tag")
    tag = raw[at:close + 1]
    encoding = ET.fromstring(tag[:-2] + b"/>" if tag.endswith(b"/>") else tag[:-1] + b"/>").get("encoding", "raw")
    if encoding not in ("raw", "base64"):
        raise _Bad(f"unknown AppendedData encoding {encoding!r}")
    if tag.endswith(b"/>"):
        return raw[:close + 1] + b"</VTKFile>", None, encoding
    mark = raw.find(b"_", close)
    if mark < 0 or raw[close + 1:mark].strip():
        raise _Bad("<AppendedData> does not start with its '_' mark")
    end = raw.rfind(b"</AppendedData>") if encoding == "base64" else -1
    # a view, not a copy: the appended data is most of the file
    data = memoryview(raw)[mark + 1:end if end > mark else len(raw)]
    return raw[:close + 1] + b"</AppendedData></VTKFile>", data, encoding


def _encoding(root: ET.Element, appended: memoryview | None, encoding: str) -> _Encoding:
    order = {"LittleEndian": "<", "BigEndian": ">", None: "<"}.get(root.get("byte_order"))
    if order is None:
        raise _Bad(f"unknown byte_order {root.get('byte_order')!r}")
    header = _HEADER_TYPES.get(root.get("header_type", "UInt32"))
    if header is None:
        raise _Bad(f"unknown header_type {root.get('header_type')!r} (UInt32 or UInt64)")
    compressor = root.get("compressor") or None
    if compressor is not None and compressor not in COMPRESSORS:
        raise _Bad(f"unknown compressor {compressor!r} (read: {', '.join(COMPRESSORS)})")
    return _Encoding(order, np.dtype(header).newbyteorder(order), compressor, appended, encoding == "base64")


def _count(element: ET.Element, name: str, default: str | None = None) -> int:
    text = element.get(name, default)
    if text is None:
        raise _Bad(f"<{element.tag}> has no {name}")
    try:
        n = int(text)
    except ValueError:
        raise _Bad(f"{name}={text!r} is not an integer") from None
    if n < 0:
        raise _Bad(f"{name}={n} is negative")
    return n


def _piece(piece: ET.Element, enc: _Encoding, point_base: int, cell_base: int,
           where: str) -> tuple[np.ndarray, list[CellBlock], list[np.ndarray], int]:
    """One piece's points, blocks (indices offset by ``point_base``), each block's cell
    numbers (from ``cell_base``, VTK's order) and its number of cells."""
    n = _count(piece, "NumberOfPoints")
    holder = piece.find("Points")
    array = holder.find("DataArray") if holder is not None else None
    if array is None:
        if n:
            raise _Bad(f"{where}: {n} points declared, no <Points> array")
        points = np.zeros((0, 3))
    else:
        points = _values(array, n, enc, f"{where} Points")
        if points.ndim != 2 or points.shape[1] != 3:
            raise _Bad(f"{where}: Points have {points.shape[1] if points.ndim == 2 else 1} components, not 3")
        points = points.astype(np.float64)
    if piece.find("Cells") is not None or piece.get("NumberOfCells") is not None:  # UnstructuredGrid
        return (points, *_grid_piece(piece, enc, n, point_base, cell_base, where))
    blocks: list[CellBlock] = []
    origins: list[np.ndarray] = []
    first = cell_base
    for section, kind in _SECTIONS.items():
        cells = _count(piece, f"NumberOf{section}", "0")
        holder = piece.find(section)
        if holder is None:
            if cells:
                raise _Bad(f"{where}: {cells} {section} declared, no <{section}> element")
            continue
        arrays = {a.get("Name"): a for a in holder.findall("DataArray")}
        if cells == 0 and not arrays:
            continue
        if "offsets" not in arrays or "connectivity" not in arrays:
            raise _Bad(f"{where} {section}: needs DataArrays 'connectivity' and 'offsets'")
        offsets, conn = _cell_arrays(arrays, cells, n, enc, f"{where} {section}")
        got, rows = blocks_of_kind(kind, offsets, conn + point_base if point_base else conn, first)
        blocks += got
        origins += rows
        first += cells
    return points, blocks, origins, first - cell_base


def _cell_arrays(arrays: dict[str | None, ET.Element], cells: int, n: int, enc: _Encoding,
                 what: str) -> tuple[np.ndarray, np.ndarray]:
    """CSR ``offsets`` (from 0) and ``connectivity`` of ``cells`` cells over ``n`` points, checked."""
    ends = _values(arrays["offsets"], cells, enc, f"{what} offsets")
    offsets = np.concatenate([[0], ends.astype(np.int64)])
    conn = _values(arrays["connectivity"], None, enc, f"{what} connectivity").astype(np.int64)
    if ends.ndim != 1 or (np.diff(offsets) < 0).any() or offsets[-1] != len(conn):
        raise _Bad(f"{what}: offsets are not increasing up to the {len(conn)} connectivity entries")
    if len(conn) and (conn.min() < 0 or conn.max() >= n):
        bad = int(conn.max() if conn.max() >= n else conn.min())
        raise _Bad(f"{what}: point index {bad} out of range [0, {n})")
    return offsets, conn


def _grid_piece(piece: ET.Element, enc: _Encoding, n: int, point_base: int, cell_base: int,
                where: str) -> tuple[list[CellBlock], list[np.ndarray], int]:
    """An UnstructuredGrid piece's blocks, their cell numbers and its number of cells."""
    cells = _count(piece, "NumberOfCells")
    holder = piece.find("Cells")
    if holder is None:
        if cells:
            raise _Bad(f"{where}: {cells} cells declared, no <Cells> element")
        return [], [], 0
    arrays = {a.get("Name"): a for a in holder.findall("DataArray")}
    if not {"connectivity", "offsets", "types"} <= arrays.keys():
        raise _Bad(f"{where} Cells: needs DataArrays 'connectivity', 'offsets' and 'types'")
    offsets, conn = _cell_arrays(arrays, cells, n, enc, f"{where} Cells")
    types = _values(arrays["types"], cells, enc, f"{where} Cells types").astype(np.int64).reshape(-1)
    try:
        blocks, rows = grid_blocks(offsets, conn + point_base if point_base else conn, types)
    except ValueError as exc:
        raise _Bad(f"{where} Cells: {exc}") from None
    return blocks, [cell_base + r for r in rows], cells


def _attributes(holder: ET.Element | None, tuples: int, enc: _Encoding, where: str) -> dict[str, np.ndarray]:
    """The numeric arrays of a ``PointData``/``CellData`` element, ``tuples`` rows each."""
    out: dict[str, np.ndarray] = {}
    for i, array in enumerate(holder.findall("DataArray") if holder is not None else []):
        if array.get("type") == "String":  # not numbers: not mesh data hammesh carries
            continue
        name = array.get("Name") or f"array_{i}"
        out[name] = _values(array, tuples, enc, f"{where} {name!r}")
    return out


def _rows(values: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``values[rows]``: a view where the rows are consecutive (one block of one kind: the
    usual file), not a copy."""
    if len(rows) and rows[-1] - rows[0] == len(rows) - 1 and (len(rows) < 2 or (np.diff(rows) == 1).all()):
        return values[rows[0]:rows[-1] + 1]
    return values[rows]


def _joined(per_piece: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Arrays present, with the same components, in every piece, concatenated."""
    if len(per_piece) == 1:
        return per_piece[0]
    first = per_piece[0]
    names = [k for k in first if all(k in p and p[k].shape[1:] == first[k].shape[1:] for p in per_piece)]
    return {k: np.concatenate([p[k] for p in per_piece]) for k in names}


def _values(array: ET.Element, tuples: int | None, enc: _Encoding, what: str) -> np.ndarray:
    """A DataArray's values, native byte order, ``(tuples,)`` or ``(tuples, components)``
    (``tuples`` None: any number)."""
    vtk_type = array.get("type")
    code = VTK_TYPES.get(vtk_type or "")
    if code is None:
        raise _Bad(f"{what}: unsupported type {vtk_type!r}")
    components = _count(array, "NumberOfComponents", "1")
    if components == 0:
        raise _Bad(f"{what}: NumberOfComponents is 0")
    fmt = array.get("format", "ascii")
    if fmt == "ascii":
        text = (array.text or "") + "".join(child.tail or "" for child in array)  # (after InformationKey)
        values = np.array(text.split(), dtype=np.dtype(code))
    else:
        if fmt == "binary":
            text = ((array.text or "") + "".join(c.tail or "" for c in array)).encode("ascii")
            text = text.translate(None, b" \t\r\n\f\v")  # (base64 ignores no whitespace here)
            payload = _base64_payload(text, enc, what)
        elif fmt == "appended":
            if enc.appended is None:
                raise _Bad(f"{what}: format='appended' but the file has no <AppendedData>")
            offset = _count(array, "offset")
            payload = (_base64_payload(enc.appended[offset:], enc, what) if enc.appended_base64
                       else _raw_payload(enc.appended, offset, enc, what))
        else:
            raise _Bad(f"{what}: unknown format {fmt!r}")
        if vtk_type == "Bit":
            values = np.unpackbits(np.frombuffer(payload, np.uint8))
            values = values[:tuples * components] if tuples is not None else values
        else:
            dtype = np.dtype(code).newbyteorder(enc.order)
            if len(payload) % dtype.itemsize:
                raise _Bad(f"{what}: {len(payload)} bytes is not a whole number of {vtk_type} values")
            values = np.frombuffer(payload, dtype).astype(np.dtype(code))
    if tuples is not None and len(values) != tuples * components:
        raise _Bad(f"{what}: {len(values)} values where {tuples} x {components} were declared")
    if len(values) % components:
        raise _Bad(f"{what}: {len(values)} values are not tuples of {components}")
    return values.reshape(-1, components) if components > 1 else values


def _header_items(data: bytes, count: int, enc: _Encoding, what: str) -> list[int]:
    size = count * enc.header.itemsize
    if len(data) < size:
        raise _Bad(f"{what}: truncated (block header cut short)")
    return [int(v) for v in np.frombuffer(data, enc.header, count)]


def _b64(text: bytes, start: int, chars: int, what: str) -> bytes:
    chunk = text[start:start + chars]
    if len(chunk) < chars:
        raise _Bad(f"{what}: truncated base64 data")
    return base64.b64decode(chunk, validate=True)


def _chars(nbytes: int) -> int:
    """Base64 characters of ``nbytes`` bytes (padded)."""
    return -(-nbytes // 3) * 4


def _base64_payload(text: bytes, enc: _Encoding, what: str) -> bytes:
    """The bytes of a base64 array: header and data encoded apart (VTK) or together."""
    item = enc.header.itemsize
    if enc.compressor is None:
        head_items = 1
    else:  # the first three items (a whole number of base64 quanta) give the block count
        head_items = 3 + _header_items(_b64(text, 0, _chars(3 * item), what), 1, enc, what)[0]
    head_bytes = head_items * item
    if head_bytes % 3 and text[_chars(head_bytes) - 1:_chars(head_bytes)] == b"=":  # apart
        header = _header_items(_b64(text, 0, _chars(head_bytes), what), head_items, enc, what)
        size = _data_bytes(header, enc, what)
        data = _b64(text, _chars(head_bytes), _chars(size), what)[:size]
    else:  # one base64 run (or a header of whole quanta, where the two layouts agree)
        header = _header_items(_b64(text, 0, _chars(head_bytes), what), head_items, enc, what)
        size = _data_bytes(header, enc, what)
        data = _b64(text, 0, _chars(head_bytes + size), what)[head_bytes:head_bytes + size]
    if len(data) != size:
        raise _Bad(f"{what}: truncated data ({len(data)} of {size} bytes)")
    return _uncompressed(header, data, enc, what)


def _raw_payload(buf: memoryview, offset: int, enc: _Encoding, what: str) -> bytes:
    """The bytes of a raw appended array at ``offset``."""
    item = enc.header.itemsize
    head_items = 1 if enc.compressor is None else 3 + _header_items(buf[offset:], 1, enc, what)[0]
    header = _header_items(buf[offset:offset + head_items * item], head_items, enc, what)
    size = _data_bytes(header, enc, what)
    start = offset + head_items * item
    data = buf[start:start + size]
    if len(data) != size:
        raise _Bad(f"{what}: truncated appended data ({len(data)} of {size} bytes)")
    return _uncompressed(header, data, enc, what)


def _data_bytes(header: list[int], enc: _Encoding, what: str) -> int:
    """Bytes after the header: the byte count, or the compressed blocks' sizes summed."""
    return header[0] if enc.compressor is None else sum(header[3:])


def _uncompressed(header: list[int], data: bytes, enc: _Encoding, what: str) -> bytes:
    """``data`` itself, or its blocks decompressed (header ``[blocks, block size, last
    block size, compressed sizes]``; a last size of 0 means a full block)."""
    if enc.compressor is None:
        return data
    blocks, block_size, last = header[0], header[1], header[2]
    decompress = _decompressor(enc.compressor, what)
    sizes = header[3:]
    starts = np.concatenate([[0], np.cumsum(sizes, dtype=np.int64)]).tolist()

    def block(i: int) -> bytes:
        expected = last if i == blocks - 1 and last else block_size
        chunk = decompress(data[starts[i]:starts[i + 1]], max(expected, 1))  # (0 would mean: no limit)
        if len(chunk) != expected:
            raise _Bad(f"{what}: compressed block {i} holds {len(chunk)} bytes, not {expected}")
        return chunk

    workers = min(row_threads.cores(), len(sizes) // 8)
    if workers < 2:
        return b"".join(block(i) for i in range(len(sizes)))
    # zlib, lzma and the LZ4 kernel release the GIL: big arrays decompress on every core
    with ThreadPoolExecutor(workers) as pool:
        return b"".join(pool.map(block, range(len(sizes))))


def _lz4_decompress(decode, block: bytes, size: int) -> bytes:
    """One LZ4 block of at most ``size`` bytes, decoded by ``decode``
    (:func:`hammesh.io._kernels.lz4_block_decode_into`)."""
    out = np.empty(size, dtype=np.uint8)
    got = decode(np.frombuffer(block, dtype=np.uint8), out)
    if got < 0:
        raise _Bad("malformed LZ4 block")
    return out[:got].tobytes()


def _decompressor(compressor: str, what: str):
    """``f(block, size) -> bytes`` for ``compressor`` (at most ``size`` bytes out)."""
    if compressor == "vtkZLibDataCompressor":
        return lambda block, size: zlib.decompressobj().decompress(block, size)
    if compressor == "vtkLZMADataCompressor":  # VTK writes .xz streams (lzma_easy_buffer_encode)
        return lambda block, size: lzma.LZMADecompressor().decompress(block, size)
    # imported once here, on the reading thread (numba: loaded only for LZ4 files), not
    # in each block's call on the decompressing threads
    from hammesh.io._kernels import lz4_block_decode_into

    return partial(_lz4_decompress, lz4_block_decode_into)
