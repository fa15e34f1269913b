"""Legacy VTK ``POLYDATA`` and ``UNSTRUCTURED_GRID`` reading (ASCII and binary).

meshio 5 reads neither POLYDATA nor the version 5.1 layout that VTK 9.1+ (and so
pyvista's ``save``) writes.  Reads ``POINTS`` and the cell sections ``VERTICES LINES
POLYGONS TRIANGLE_STRIPS`` (POLYDATA) or ``CELLS`` + ``CELL_TYPES`` (UNSTRUCTURED_GRID:
vertices, lines, polylines, triangles, strips, polygons, pixels, quads; other cell types,
volumes and second-order cells, are named and left to the caller to refuse), in
both layouts: the classic one (``POLYGONS n size`` then ``n`` lists ``k i0 .. ik-1``)
and that of file version 5.1 (``POLYGONS n+1 size`` then ``OFFSETS`` and
``CONNECTIVITY`` arrays).  Binary data is big-endian, as the format says.  ``LINES``
become segments (a polyline: its consecutive pairs); triangle strips are decoded with
alternating winding (VTK's ``vtkTriangleStrip`` rule).  ``POINT_DATA`` and
``CELL_DATA`` arrays (``SCALARS``, ``VECTORS``, ``NORMALS``, ``TENSORS``,
``TEXTURE_COORDINATES``, ``COLOR_SCALARS``, ``GLOBAL_IDS``, ``PEDIGREE_IDS`` and
``FIELD`` arrays) are read as point and cell data (a strip's or polyline's value goes
to each of its triangles or segments), so a file's fields reach the output (never
lost); ``LOOKUP_TABLE`` definitions, ``METADATA`` and dataset-level ``FIELD`` data are
skipped.  Other datasets (structured grids) are left to meshio.

Reference: "VTK File Formats", legacy format, Dataset formats POLYDATA and UNSTRUCTURED_GRID
(https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html).
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.raw import CellBlock, RawMesh, blocks_of_kind, grid_blocks

__all__ = ["read_legacy", "dataset_type", "DATASETS"]

_TYPES = {
    "bit": ">u1", "unsigned_char": ">u1", "char": ">i1", "unsigned_short": ">u2", "short": ">i2",
    "unsigned_int": ">u4", "int": ">i4", "unsigned_long": ">u8", "long": ">i8",
    "float": ">f4", "double": ">f8", "vtktypeint64": ">i8", "vtktypeuint64": ">u8",
    "vtkidtype": ">i4", "vtktypeint8": ">i1", "vtktypeuint8": ">u1", "vtktypeint16": ">i2",
    "vtktypeuint16": ">u2", "vtktypeint32": ">i4", "vtktypeuint32": ">u4", "vtktypefloat32": ">f4",
    "vtktypefloat64": ">f8", "signed_char": ">i1",
}
# (``vtkIdType``: VTK's legacy writer and reader store it as a 4-byte int in binary
# files, whatever the build's id size: vtkDataWriter's "currently writing vtkIdType as int")
_SECTIONS = ("VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS")
#: The datasets :func:`read_legacy` reads.
DATASETS = ("POLYDATA", "UNSTRUCTURED_GRID")
#: POLYDATA sections, by how their cells become blocks (grid cell types: :mod:`hammesh.io.raw`).
_KIND_OF_SECTION = {"VERTICES": "vertex", "LINES": "line", "POLYGONS": "polygon", "TRIANGLE_STRIPS": "strip"}
_MAX_HEADER = 4096


def dataset_type(path: str | Path) -> str | None:
    """``"POLYDATA"``, ``"UNSTRUCTURED_GRID"``... of a legacy VTK file, or None."""
    with open(path, "rb") as f:
        head = f.read(_MAX_HEADER)
    for line in head.splitlines()[:6]:
        words = line.split()
        if len(words) >= 2 and words[0].upper() == b"DATASET":
            return words[1].decode("ascii", errors="replace").upper()
    return None


class _Reader:
    def __init__(self, path: Path) -> None:
        self.path = path
        self.buf = path.read_bytes()
        self.pos = 0
        self.binary = False

    def error(self, message: str) -> FileFormatError:
        return FileFormatError(f"{self.path}: {message}")

    def line(self) -> list[str] | None:
        """Next non-blank line's words (None at end of file)."""
        while self.pos < len(self.buf):
            end = self.buf.find(b"\n", self.pos)
            end = len(self.buf) if end < 0 else end
            raw = self.buf[self.pos:end]
            self.pos = end + 1
            try:  # (names are UTF-8 as VTK, meshio and pyvista write them; older files Latin-1)
                words = raw.decode("utf-8").split()
            except UnicodeDecodeError:
                words = raw.decode("latin-1").split()
            if words:
                return words
        return None

    def skip_to_blank_line(self) -> None:
        while self.pos < len(self.buf):
            end = self.buf.find(b"\n", self.pos)
            end = len(self.buf) if end < 0 else end
            blank = not self.buf[self.pos:end].strip()
            self.pos = end + 1
            if blank:
                return

    def count(self, token: str, what: str) -> int:
        try:
            n = int(token)
        except ValueError:
            raise self.error(f"{what} is not an integer: {token!r}") from None
        if n < 0:
            raise self.error(f"{what} is negative: {n}")
        return n

    def numbers(self, count: int, vtk_type: str, what: str) -> np.ndarray:
        dtype = _TYPES.get(vtk_type.lower())
        if dtype is None:
            raise self.error(f"unsupported data type {vtk_type!r} for {what}")
        if self.binary and vtk_type.lower() == "bit":
            # VTK packs bits eight to a byte, most significant first
            size = (count + 7) // 8
            if self.pos + size > len(self.buf):
                raise self.error(f"truncated {what} (declared {count} values)")
            packed = np.frombuffer(self.buf, dtype=np.uint8, count=size, offset=self.pos)
            self.pos += size
            if self.buf[self.pos:self.pos + 1] == b"\n":
                self.pos += 1
            return np.unpackbits(packed)[:count].astype(np.int64)
        if self.binary:
            size = np.dtype(dtype).itemsize * count
            if self.pos + size > len(self.buf):
                raise self.error(f"truncated {what} (declared {count} values)")
            arr = np.frombuffer(self.buf, dtype=dtype, count=count, offset=self.pos)
            self.pos += size
            if self.buf[self.pos:self.pos + 1] == b"\n":
                self.pos += 1
            return arr.astype(np.float64 if dtype[1] == "f" else np.int64)
        # ASCII: the values may span any number of lines
        values: list[str] = []
        while len(values) < count:
            words = self.line()
            if words is None:
                raise self.error(f"truncated {what} (declared {count} values, found {len(values)})")
            values.extend(words)
        if len(values) != count:
            raise self.error(f"{what}: {len(values)} values where {count} were declared")
        try:
            return np.array(values, dtype=np.float64 if dtype[1] == "f" else np.int64)
        except ValueError:
            raise self.error(f"{what}: a value is not a number") from None


def _cells_classic(r: _Reader, n: int, size: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    flat = r.numbers(size, "int", what)
    if n and size % n == 0 and size // n >= 2:  # all cells of one size: no walk
        c = size // n - 1
        rows = flat.reshape(n, c + 1)
        if (rows[:, 0] == c).all():
            return np.arange(n + 1, dtype=np.int64) * c, rows[:, 1:].reshape(-1)
    # sizes interleaved with indices: a kernel follows them (numba is loaded by the reader anyway)
    from hammesh.io._kernels import follow_cell_sizes_into

    starts = np.empty(n, dtype=np.int64)
    found = follow_cell_sizes_into(flat, starts)
    starts = starts[:found]
    if found and flat[starts[-1]] < 0:
        raise r.error(f"{what}: negative cell size")
    if found < n:
        raise r.error(f"{what}: {n} cells declared, data ends after {found}")
    sizes = flat[starts]
    end = int(starts[-1] + 1 + sizes[-1]) if n else 0
    if end != size:
        raise r.error(f"{what}: size {size} does not match the cells' lengths ({end})")
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    keep = np.repeat(starts + 1 - offsets[:-1], sizes) + np.arange(offsets[-1])
    return offsets, flat[keep]


def _cell_lists(r: _Reader, words: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """CSR ``offsets`` and ``connectivity`` of a ``POLYGONS``/``CELLS``... section (header
    ``words`` read), in either layout: classic or version 5.1 (``OFFSETS``, ``CONNECTIVITY``)."""
    key = words[0].upper()
    if len(words) < 3:
        raise r.error(f"{key} needs two counts")
    n = r.count(words[1], f"{key} count")
    size = r.count(words[2], f"{key} size")
    mark = r.pos
    nxt = r.line()
    if nxt is not None and nxt[0].upper() == "OFFSETS":  # file version 5.1
        offsets = r.numbers(n, nxt[1] if len(nxt) > 1 else "", f"{key} OFFSETS")
        conn_head = r.line()
        if conn_head is None or conn_head[0].upper() != "CONNECTIVITY":
            raise r.error(f"{key}: CONNECTIVITY expected after OFFSETS")
        conn = r.numbers(size, conn_head[1] if len(conn_head) > 1 else "", f"{key} CONNECTIVITY")
        if len(offsets) == 0 or offsets[0] != 0 or offsets[-1] != size or (np.diff(offsets) < 0).any():
            raise r.error(f"{key}: OFFSETS are not increasing from 0 to {size}")
        return offsets, conn
    r.pos = mark
    return _cells_classic(r, n, size, key)


def _grid_blocks(r: _Reader, offsets: np.ndarray, conn: np.ndarray,
                 types: np.ndarray) -> tuple[list[CellBlock], list[np.ndarray]]:
    """Blocks of an UNSTRUCTURED_GRID's cells (:func:`hammesh.io.raw.grid_blocks`), errors named."""
    try:
        return grid_blocks(offsets, conn, types)
    except ValueError as exc:
        raise r.error(f"CELL_TYPES: {exc}" if "cell types for" in str(exc) else str(exc)) from None


def read_legacy(path: str | Path) -> RawMesh:
    """Points, cells and point/cell data of a legacy VTK ``POLYDATA`` or ``UNSTRUCTURED_GRID`` file.

    Raises
    ------
    FileFormatError
        Not a legacy VTK file of one of :data:`DATASETS`, truncated or malformed data.
    """
    path = Path(path)
    r = _Reader(path)
    first = r.line()
    if not first or first[0] != "#" or "vtk" not in " ".join(first).lower():
        raise r.error("not a legacy VTK file (no '# vtk DataFile' line)")
    r.line()  # title
    mode = r.line()
    if not mode or mode[0].upper() not in ("ASCII", "BINARY"):
        raise r.error("expected ASCII or BINARY on line 3")
    r.binary = mode[0].upper() == "BINARY"
    ds = r.line()
    if not ds or len(ds) < 2 or ds[0].upper() != "DATASET" or ds[1].upper() not in DATASETS:
        raise r.error(f"not a {' or '.join(DATASETS)} dataset")
    grid = ds[1].upper() == "UNSTRUCTURED_GRID"
    points = None
    blocks: list[CellBlock] = []
    origins: list[np.ndarray] = []  # each block's cells' numbers in the file's cell order
    n_cells = 0
    grid_cells: tuple[np.ndarray, np.ndarray] | None = None  # CELLS, waiting for CELL_TYPES
    point_data: dict[str, np.ndarray] = {}
    cell_data_all: dict[str, np.ndarray] = {}
    target: dict[str, np.ndarray] | None = None  # the POINT_DATA or CELL_DATA section read now
    tuples = 0
    while True:
        words = r.line()
        if words is None:
            break
        key = words[0].upper()
        if key == "POINTS":
            if len(words) < 3:
                raise r.error("POINTS needs a count and a type")
            n = r.count(words[1], "number of points")
            points = r.numbers(3 * n, words[2], "POINTS").reshape(n, 3)
        elif not grid and key in _SECTIONS:
            offsets, conn = _cell_lists(r, words)
            got, rows = blocks_of_kind(_KIND_OF_SECTION[key], offsets, conn, n_cells)
            blocks.extend(got)
            origins.extend(rows)
            n_cells += len(offsets) - 1  # (5.1 files count the offsets, classic ones the cells)
        elif grid and key == "CELLS":
            grid_cells = _cell_lists(r, words)
        elif grid and key == "CELL_TYPES":
            if grid_cells is None:
                raise r.error("CELL_TYPES before CELLS")
            if len(words) < 2:
                raise r.error("CELL_TYPES needs a count")
            types = r.numbers(r.count(words[1], "CELL_TYPES count"), "int", "CELL_TYPES")
            blocks, origins = _grid_blocks(r, *grid_cells, types)
            n_cells = len(types)
        elif key == "METADATA":  # text up to a blank line (file versions >= 4.2)
            r.skip_to_blank_line()
        elif key in ("POINT_DATA", "CELL_DATA"):
            if len(words) < 2:
                raise r.error(f"{key} needs a count")
            tuples = r.count(words[1], f"{key} count")
            target = point_data if key == "POINT_DATA" else cell_data_all
        elif target is not None and key in _ARRAYS:
            _read_array(r, words, tuples, target)
        elif target is None and key == "FIELD":  # dataset-level data (e.g. TIME): not per point or cell
            _read_array(r, words, -1, {})
        else:
            raise r.error(f"unexpected section {words[0]!r}")
    if points is None:
        raise r.error("no POINTS section")
    if grid and grid_cells is not None and n_cells == 0 and len(grid_cells[0]) > 1:
        raise r.error("CELLS without CELL_TYPES")
    cell_data: dict[str, list[np.ndarray]] = {}
    for name, values in cell_data_all.items():
        if len(values) != n_cells:
            raise r.error(f"cell data {name!r} has {len(values)} values for {n_cells} cells")
        cell_data[name] = [values[o] for o in origins]
    for name, values in point_data.items():
        if len(values) != len(points):
            raise r.error(f"point data {name!r} has {len(values)} values for {len(points)} points")
    return RawMesh(points, blocks, cell_data=cell_data, point_data=point_data)


#: Attribute arrays of a POINT_DATA / CELL_DATA section (``LOOKUP_TABLE`` and
#: ``FIELD`` included: read or skipped by :func:`_read_array`).
_ARRAYS = ("SCALARS", "VECTORS", "NORMALS", "TENSORS", "TEXTURE_COORDINATES", "COLOR_SCALARS",
           "LOOKUP_TABLE", "GLOBAL_IDS", "PEDIGREE_IDS", "FIELD")


def _read_array(r: _Reader, words: list[str], tuples: int, into: dict[str, np.ndarray]) -> None:
    """Read one attribute array (its header ``words`` already read) into ``into``."""
    key = words[0].upper()

    def need(k: int) -> None:
        if len(words) < k:
            raise r.error(f"{key} needs {k - 1} fields after it, got {' '.join(words[1:])!r}")

    def put(name: str, values: np.ndarray, c: int) -> None:
        name = unquote(name)  # VTK writes a space in a name as %20 (vtkDataWriter::EncodeString)
        into[name] = values.reshape(tuples, c) if c > 1 else values.reshape(tuples)

    if key == "SCALARS":
        need(3)
        c = r.count(words[3], "SCALARS components") if len(words) > 3 else 1
        mark = r.pos
        nxt = r.line()
        if nxt is None or nxt[0].upper() != "LOOKUP_TABLE":
            r.pos = mark  # (the table line is optional in practice)
        put(words[1], r.numbers(tuples * c, words[2], f"SCALARS {words[1]}"), c)
    elif key in ("VECTORS", "NORMALS"):
        need(3)
        put(words[1], r.numbers(3 * tuples, words[2], f"{key} {words[1]}"), 3)
    elif key == "TENSORS":
        need(3)
        put(words[1], r.numbers(9 * tuples, words[2], f"TENSORS {words[1]}"), 9)
    elif key == "TEXTURE_COORDINATES":
        need(4)
        c = r.count(words[2], "texture dimension")
        put(words[1], r.numbers(c * tuples, words[3], f"TEXTURE_COORDINATES {words[1]}"), c)
    elif key in ("GLOBAL_IDS", "PEDIGREE_IDS"):
        need(3)
        put(words[1], r.numbers(tuples, words[2], f"{key} {words[1]}"), 1)
    elif key == "COLOR_SCALARS":  # binary: unsigned char; ASCII: floats in [0, 1]
        need(3)
        c = r.count(words[2], "COLOR_SCALARS components")
        put(words[1], r.numbers(c * tuples, "unsigned_char" if r.binary else "float", f"COLOR_SCALARS {words[1]}"), c)
    elif key == "LOOKUP_TABLE":  # a table's definition: RGBA per entry, not data of the mesh
        need(3)
        size = r.count(words[2], "LOOKUP_TABLE size")
        r.numbers(4 * size, "unsigned_char" if r.binary else "float", f"LOOKUP_TABLE {words[1]}")
    else:  # FIELD name count, then per array: name components tuples type, values
        need(3)
        for _ in range(r.count(words[2], "FIELD array count")):
            head = r.line()
            if head is not None and head[0].upper() == "METADATA":
                r.skip_to_blank_line()
                head = r.line()
            if head is None or len(head) < 4:
                raise r.error(f"FIELD {words[1]}: array header 'name components tuples type' expected")
            c = r.count(head[1], "FIELD array components")
            k = r.count(head[2], "FIELD array tuples")
            values = r.numbers(c * k, head[3], f"FIELD array {head[0]}")
            if k == tuples:
                put(head[0], values, c)
