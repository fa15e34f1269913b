"""VTK XML unstructured grids (``.vtu``) written by hammesh itself: compressed and raw.

* :func:`write`: a compressed ``.vtu`` (what ``hammesh.write`` writes for ``.vtu``);
* :func:`write_raw` / :func:`read_raw`: the raw-appended pieces of a partitioned output
  (:mod:`hammesh.io.pvtu`), a copy of the arrays to the file and back.

Compressed files.

meshio's ``.vtu`` writer compresses every array with ``zlib`` at its default level (6)
in one thread; on a hammesh mesh that is 75–85 % of the write (1.5 s of 1.8 s at 158k
triangles, about 15 s at 1.5M, several times the meshing itself).  This writer makes
the same file — same XML layout, ``vtkZLibDataCompressor``, ``UInt32`` block headers,
32 KiB blocks, the arrays and names meshio would write (indices as Int32 below 2**31
points, as VTK writes them) — but compresses at level 1 and
on every core (``zlib`` releases the GIL while it compresses).  Level 1 on hammesh's
arrays (indices, small integer fields, mostly-zero boundary fields) costs ~10–20 % more
bytes than level 6 and is 3–4× faster.

The file layout follows VTK's documentation of the XML formats ("VTK File Formats",
*Serial XML file formats*: ``<DataArray format="binary">`` with a compressed block
header) and meshio 5.3's ``meshio/vtu/_vtu.py``, which reads what this writes; meshio
still reads every ``.vtu`` (:mod:`hammesh.io.meshio_format`).

Only what hammesh writes is supported: ``triangle`` and ``line`` cells, point and cell
data of numeric dtypes (1-D or 2-D), no field data.
"""

from __future__ import annotations

import base64
import os
import re
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from hammesh import threads as row_threads
from hammesh.errors import FileFormatError

__all__ = ["write", "write_raw", "read_raw", "write_data_array", "write_data_sections", "xml_attribute", "VTK_CELL_TYPES", "BLOCK_BYTES", "LEVEL", "RAW_DTYPES"]

#: VTK cell type of each meshio cell type written here.
VTK_CELL_TYPES: dict[str, int] = {"line": 3, "triangle": 5}

#: Uncompressed bytes per compressed block (VTK's own default).
BLOCK_BYTES = 32768

#: zlib level: 1 is 3–4x faster than meshio's 6 on hammesh's arrays.
LEVEL = 1

#: numpy dtype of each VTK type of a raw piece (:func:`write_raw`, :func:`read_raw`)
RAW_DTYPES = {"Float64": "f8", "Int64": "i8", "UInt8": "u1", "Int32": "i4", "Float32": "f4", "UInt64": "u8", "Int8": "i1",
              "Int16": "i2"}

_VTK_TYPES = {
    np.dtype(np.int8): "Int8", np.dtype(np.int16): "Int16", np.dtype(np.int32): "Int32",
    np.dtype(np.int64): "Int64", np.dtype(np.uint8): "UInt8", np.dtype(np.uint16): "UInt16",
    np.dtype(np.uint32): "UInt32", np.dtype(np.uint64): "UInt64",
    np.dtype(np.float32): "Float32", np.dtype(np.float64): "Float64",
}


def write(path: str | os.PathLike[str], mesh: Any, threads: int | None = None) -> None:
    """Write ``mesh`` (a ``meshio.Mesh``) to ``path`` as a compressed ``.vtu``.

    Parameters
    ----------
    path : path-like
        The file written (the caller makes the write atomic).
    mesh : meshio.Mesh
        Points ``(n, 3)``, cell blocks of :data:`VTK_CELL_TYPES`, point and cell data.
    threads : int, optional
        Compression threads; all cores by default.

    Raises
    ------
    ValueError
        A cell type or dtype this writer does not know (a programming error: hammesh
        writes only triangles and lines with numeric data).
    """
    blocks = [(block.type, np.asarray(block.data)) for block in mesh.cells]
    for kind, _ in blocks:
        if kind not in VTK_CELL_TYPES:
            raise ValueError(f"hammesh.io.vtu: cell type {kind!r} is not supported")
    connectivity = np.concatenate([data.reshape(-1) for _, data in blocks]).astype(np.int64, copy=False)
    sizes = np.concatenate([np.full(len(data), data.shape[1], np.int64) for _, data in blocks])
    types = np.concatenate([np.full(len(data), VTK_CELL_TYPES[kind], np.uint8) for kind, data in blocks])
    n_cells = len(types)
    offsets = np.cumsum(sizes)
    if len(mesh.points) < 2**31 and (not len(offsets) or offsets[-1] < 2**31):
        # Int32 indices (as VTK writes them unless told otherwise): half the bytes to
        # compress, the largest array of the file (connectivity: 36 MB at 1.5 M triangles)
        connectivity, offsets = connectivity.astype(np.int32), offsets.astype(np.int32)
    # (one block, the usual case: no copy of the arrays, 12 MB each at 1.5 M triangles)
    cell_data = {name: np.asarray(arrays[0]) if len(arrays) == 1 else np.concatenate([np.asarray(a) for a in arrays])
                 for name, arrays in mesh.cell_data.items()}

    workers = max(1, threads or row_threads.cores())
    with ThreadPoolExecutor(workers) as pool, open(path, "wb") as fh:
        fh.write(b'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
                 b'byte_order="LittleEndian" header_type="UInt32" compressor="vtkZLibDataCompressor">\n'
                 b"<!--This file was created by hammesh-->\n<UnstructuredGrid>\n")
        fh.write(f'<Piece NumberOfPoints="{len(mesh.points)}" NumberOfCells="{n_cells}">\n'.encode())
        fh.write(b"<Points>\n")
        write_data_array(fh, pool, workers, "Points", np.asarray(mesh.points, dtype=np.float64))
        fh.write(b"</Points>\n<Cells>\n")
        write_data_array(fh, pool, workers, "connectivity", connectivity)
        write_data_array(fh, pool, workers, "offsets", offsets)
        write_data_array(fh, pool, workers, "types", types)
        fh.write(b"</Cells>\n")
        write_data_sections(fh, pool, workers, mesh.point_data, cell_data)
        fh.write(b"</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")


def write_data_sections(fh: BinaryIO, pool: ThreadPoolExecutor, workers: int, point_data: dict[str, Any],
                        cell_data: dict[str, np.ndarray]) -> None:
    """``<PointData>`` and ``<CellData>`` (each only if not empty), every array by
    :func:`write_data_array`; shared by the ``.vtu`` and ``.vtp`` writers."""
    for tag, data in (("PointData", point_data), ("CellData", cell_data)):
        if data:
            fh.write(f"<{tag}>\n".encode())
            for name, values in data.items():
                write_data_array(fh, pool, workers, name, np.asarray(values))
            fh.write(f"</{tag}>\n".encode())


def write_data_array(fh: BinaryIO, pool: ThreadPoolExecutor, workers: int, name: str, values: np.ndarray) -> None:
    """One ``<DataArray format="binary">``: a block header and the zlib blocks, base64."""
    values = np.ascontiguousarray(values)
    if values.dtype.byteorder == ">":
        values = values.astype(values.dtype.newbyteorder("<"))
    vtk_type = _VTK_TYPES.get(values.dtype.newbyteorder("="))
    if vtk_type is None:
        raise ValueError(f"hammesh.io.vtu: {name}: dtype {values.dtype} is not supported")
    components = f' NumberOfComponents="{values.shape[1]}"' if values.ndim == 2 else ""
    fh.write(f'<DataArray type="{vtk_type}" Name="{xml_attribute(name)}"{components} format="binary">\n'.encode())
    raw = memoryview(values.reshape(-1).view(np.uint8))
    chunks = [raw[i:i + BLOCK_BYTES] for i in range(0, len(raw), BLOCK_BYTES)] or [raw]
    # one task per group of blocks: a task per 32 KiB block would cost as much as its zlib
    per_task = -(-len(chunks) // (4 * workers))
    groups = [chunks[i:i + per_task] for i in range(0, len(chunks), per_task)]
    compressed = [c for group in pool.map(_compress_all, groups) for c in group]
    # header: number of blocks, block size, size of the last block, each compressed size
    header = np.array([len(chunks), BLOCK_BYTES, len(chunks[-1]), *map(len, compressed)], dtype=np.uint32)
    fh.write(base64.b64encode(header.tobytes()))
    fh.write(base64.b64encode(b"".join(compressed)))
    fh.write(b"\n</DataArray>\n")


def _compress_all(chunks: list[memoryview]) -> list[bytes]:
    return [zlib.compress(chunk, LEVEL) for chunk in chunks]


def xml_attribute(text: str) -> str:
    """``text`` quoted for an XML attribute value."""
    return text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")


def write_raw(path: Path, arrays: list[tuple[str, str, str, np.ndarray, int]], n_points: int, n_cells: int) -> None:
    """Write a ``.vtu`` whose arrays are raw little-endian bytes in ``<AppendedData encoding="raw">``.

    ``arrays``: ``(section, name, vtk_type, data, components)`` with section one of
    ``PointData``, ``CellData``, ``Points``, ``Cells``. Each block is an UInt64 byte count
    and the bytes (VTK's ``header_type="UInt64"``); the XML header gives the offsets. A
    worker's write is then a copy of its arrays to the file: no base64 or zlib (meshio's
    writer spent ~3 s per 750k-triangle piece on its text encoding).
    """
    sections: dict[str, list[str]] = {"PointData": [], "CellData": [], "Points": [], "Cells": []}
    blocks = []
    offset = 0
    for section, name, vtk_type, data, ncomp in arrays:
        data = np.ascontiguousarray(data, dtype=np.dtype(RAW_DTYPES[vtk_type]).newbyteorder("<"))
        attr = f' Name="{name}"' if name else ""
        comp = f' NumberOfComponents="{ncomp}"' if ncomp > 1 else ""
        sections[section].append(f'<DataArray type="{vtk_type}"{attr}{comp} format="appended" offset="{offset}"/>')
        blocks.append(data)
        offset += 8 + data.nbytes
    head = ['<?xml version="1.0"?>',
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
            "<UnstructuredGrid>", f'<Piece NumberOfPoints="{n_points}" NumberOfCells="{n_cells}">']
    for section in ("PointData", "CellData", "Points", "Cells"):
        head += [f"<{section}>", *sections[section], f"</{section}>"]
    head += ["</Piece>", "</UnstructuredGrid>", '<AppendedData encoding="raw">', "_"]
    with open(path, "wb") as f:
        f.write("\n".join(head[:-1]).encode() + b"\n_")
        for data in blocks:
            f.write(np.array([data.nbytes], dtype="<u8").tobytes())
            f.write(memoryview(data).cast("B"))
        f.write(b"\n</AppendedData>\n</VTKFile>\n")


def read_raw(path: Path) -> dict | None:
    """The arrays of a raw-appended ``.vtu`` as :func:`hammesh.io.pvtu.write_piece` writes it
    (``{name: array}``, ``"points"``, ``"connectivity"``, ``"types"``), or None for any
    other ``.vtu`` (read by meshio instead)."""
    raw = path.read_bytes()
    head_end = raw.find(b'<AppendedData encoding="raw">', 0, 1 << 20)
    if head_end < 0:
        return None
    text = raw[:head_end].decode("utf-8", "replace")
    if 'header_type="UInt64"' not in text or 'byte_order="LittleEndian"' not in text or "compressor" in text:
        return None
    start = raw.find(b"_", head_end)
    if start < 0:
        return None
    base = start + 1
    out = {}
    for m in re.finditer(r"<(PointData|CellData|Points|Cells)>(.*?)</\1>", text, re.S):
        for da in re.finditer(r"<DataArray ([^>]*)/>", m.group(2)):
            attrs = dict(re.findall(r'(\w+)="([^"]*)"', da.group(1)))
            if attrs.get("format") != "appended" or attrs.get("type") not in RAW_DTYPES:
                return None
            at = base + int(attrs["offset"])
            dt = np.dtype(RAW_DTYPES[attrs["type"]]).newbyteorder("<")
            nbytes = int(np.frombuffer(raw, "<u8", 1, at)[0]) if at + 8 <= len(raw) else -1
            if nbytes < 0 or at + 8 + nbytes > len(raw) or nbytes % dt.itemsize:
                raise FileFormatError(f"{path}: truncated (an array runs past the end of the file)")
            data = np.frombuffer(raw, dt, nbytes // dt.itemsize, at + 8)
            ncomp = int(attrs.get("NumberOfComponents", 1))
            data = data.reshape(-1, ncomp) if ncomp > 1 else data
            key = "points" if m.group(1) == "Points" else attrs.get("Name", "")
            out[(m.group(1), key)] = data
    return out
