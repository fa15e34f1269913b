"""VTK XML PolyData (.vtp): every encoding VTK writes is read, bad files are refused.

Files are built by hand here (ascii, raw-appended, base64 in both layouts, big-endian,
compressed), so the reader is tested without pyvista; pyvista round trips run when it
is installed.
"""

from __future__ import annotations

import base64
import json
import subprocess
import sys
import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hammesh.errors import FileFormatError
from hammesh.io import read_mesh
from hammesh.io.vtk_xml import read_vtk_xml as read_vtp

# a unit square and an apex: one vertex cell, a polyline of 3 points (2 segments), a
# triangle polygon, a 4-point strip (2 triangles); VTK's cell order Verts, Lines, Polys, Strips
POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.5, 0]], dtype=np.float64)
SECTIONS = {
    "Verts": ([4], [1]),
    "Lines": ([0, 1, 2], [3]),
    "Polys": ([3, 2, 4], [3]),
    "Strips": ([0, 1, 3, 2], [4]),
}
CELL_IDS = np.array([10, 20, 30, 40], dtype=np.int32)  # one per cell, VTK order
HEIGHT = np.array([0.0, 1.0, 2.0, 1.0, 2.5], dtype=np.float32)


def _ascii_vtp() -> str:
    def arr(name, vtk_type, values, comps=1):
        text = " ".join(str(v) for v in np.asarray(values).reshape(-1).tolist())
        return (f'<DataArray type="{vtk_type}" Name="{name}" NumberOfComponents="{comps}" '
                f'format="ascii">\n{text}\n</DataArray>')

    cells = "".join(f"<{s}>{arr('connectivity', 'Int64', c)}{arr('offsets', 'Int64', o)}</{s}>"
                    for s, (c, o) in SECTIONS.items())
    return f"""<?xml version="1.0"?>
<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">
<PolyData>
<FieldData>{arr('TimeValue', 'Float64', [3.5])}</FieldData>
<Piece NumberOfPoints="5" NumberOfVerts="1" NumberOfLines="1" NumberOfStrips="1" NumberOfPolys="1">
<PointData>{arr('height', 'Float32', HEIGHT)}{arr('velocity', 'Float64', POINTS * 2, 3)}</PointData>
<CellData>{arr('cell_id', 'Int32', CELL_IDS)}
<DataArray type="String" Name="label" format="ascii">97 0 98 0 99 0 100 0</DataArray></CellData>
<Points>{arr('Points', 'Float64', POINTS, 3)}</Points>
{cells}
</Piece>
</PolyData>
</VTKFile>
"""


def _check_square(raw) -> None:
    """The blocks and data of the square, whatever its encoding."""
    by_type = {b.type: b.data.tolist() for b in raw.cells}
    assert by_type["line"] == [[0, 1], [1, 2]]
    tris = [t for b in raw.cells if b.type == "triangle" for t in b.data.tolist()]
    assert tris == [[3, 2, 4], [0, 1, 3], [3, 1, 2]]  # the polygon, then the strip (odd one swapped)
    ids = dict(zip((b.type for b in raw.cells), raw.cell_data["cell_id"]))
    assert ids["line"].tolist() == [20, 20] and np.concatenate(
        [v for b, v in zip(raw.cells, raw.cell_data["cell_id"]) if b.type == "triangle"]).tolist() == [30, 40, 40]
    np.testing.assert_array_equal(raw.points, POINTS)
    np.testing.assert_array_equal(raw.point_data["height"], HEIGHT)
    np.testing.assert_array_equal(raw.point_data["velocity"], POINTS * 2)


def test_ascii_file_written_by_hand(tmp_path):
    path = tmp_path / "sq.vtp"
    path.write_text(_ascii_vtp())
    raw = read_vtp(path)
    _check_square(raw)
    assert "label" not in raw.cell_data and "TimeValue" not in raw.cell_data  # String, FieldData: skipped


def test_ascii_file_through_read_mesh(tmp_path):
    path = tmp_path / "sq.vtp"
    path.write_text(_ascii_vtp())
    m = read_mesh(path)
    assert m.triangles.tolist() == [[3, 2, 4], [0, 1, 3], [3, 1, 2]]
    assert m.segments.tolist() == [[0, 1], [1, 2]]
    cid = m.triangle_attributes[:, m.attribute_names.index("cell_id")]
    assert cid.tolist() == [30, 40, 40]
    np.testing.assert_array_equal(m.point_data["velocity"], POINTS * 2)


# ---- binary files built with numpy -------------------------------------------------------------

class _Builder:
    """A .vtp of the square in one binary encoding (the layout of VTK's vtkXMLWriter)."""

    def __init__(self, fmt: str, order: str, header: str, compress: bool, joint: bool = False,
                 block: int = 16) -> None:
        self.fmt, self.order, self.header, self.compress, self.joint, self.block = (
            fmt, order, header, compress, joint, block)
        self.appended: list[bytes] = []
        self.at = 0

    def _blob(self, values: np.ndarray) -> tuple[bytes, bytes]:
        """(header, data) bytes of one array."""
        h = np.dtype("u4" if self.header == "UInt32" else "u8").newbyteorder(self.order)
        data = values.astype(values.dtype.newbyteorder(self.order)).tobytes()
        if not self.compress:
            return np.array([len(data)], h).tobytes(), data
        chunks = [data[i:i + self.block] for i in range(0, len(data), self.block)] or [b""]
        packed = [zlib.compress(c) for c in chunks]
        last = len(chunks[-1]) if len(chunks[-1]) < self.block else 0
        head = np.array([len(chunks), self.block, last, *map(len, packed)], h).tobytes()
        return head, b"".join(packed)

    def array(self, name: str, vtk_type: str, values, comps: int = 1) -> str:
        values = np.asarray(values, dtype={"Int64": "i8", "Int32": "i4", "Float32": "f4",
                                           "Float64": "f8", "UInt16": "u2", "Int8": "i1"}[vtk_type]).reshape(-1)
        head, data = self._blob(values)
        attrs = f'type="{vtk_type}" Name="{name}" NumberOfComponents="{comps}"'
        if self.fmt == "binary":
            text = base64.b64encode(head + data) if self.joint else base64.b64encode(head) + base64.b64encode(data)
            return f'<DataArray {attrs} format="binary">\n  {text.decode()}\n</DataArray>'
        blob = head + data
        if self.fmt == "appended-base64":
            blob = base64.b64encode(head + data) if self.joint else base64.b64encode(head) + base64.b64encode(data)
        tag = f'<DataArray {attrs} format="appended" offset="{self.at}"/>'
        self.appended.append(blob)
        self.at += len(blob)
        return tag

    def file(self) -> bytes:
        cells = "".join(f"<{s}>{self.array('connectivity', 'Int64', c)}{self.array('offsets', 'Int32', o)}</{s}>"
                        for s, (c, o) in SECTIONS.items())
        body = (f'<PointData>{self.array("height", "Float32", HEIGHT)}'
                f'{self.array("velocity", "Float64", POINTS * 2, 3)}</PointData>'
                f'<CellData>{self.array("cell_id", "Int32", CELL_IDS)}</CellData>'
                f'<Points>{self.array("Points", "Float64", POINTS, 3)}</Points>{cells}')
        order = "LittleEndian" if self.order == "<" else "BigEndian"
        comp = ' compressor="vtkZLibDataCompressor"' if self.compress else ""
        head = (f'<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" byte_order="{order}" '
                f'header_type="{self.header}"{comp}>\n<PolyData>\n<Piece NumberOfPoints="5" NumberOfVerts="1" '
                f'NumberOfLines="1" NumberOfStrips="1" NumberOfPolys="1">\n{body}\n</Piece>\n</PolyData>\n')
        if self.fmt == "binary":
            return (head + "</VTKFile>\n").encode()
        enc = "base64" if self.fmt == "appended-base64" else "raw"
        return (head.encode() + f'<AppendedData encoding="{enc}">\n   _'.encode() + b"".join(self.appended)
                + b"\n</AppendedData>\n</VTKFile>\n")


ENCODINGS = [
    (fmt, order, header, compress, joint)
    for fmt in ("binary", "appended-raw", "appended-base64")
    for order in ("<", ">")
    for header in ("UInt32", "UInt64")
    for compress in (False, True)
    for joint in ((False, True) if fmt != "appended-raw" else (False,))
]


@pytest.mark.parametrize("fmt,order,header,compress,joint", ENCODINGS)
def test_binary_encodings_built_with_numpy(tmp_path, fmt, order, header, compress, joint):
    path = tmp_path / "sq.vtp"
    path.write_bytes(_Builder(fmt, order, header, compress, joint).file())
    _check_square(read_vtp(path))


def test_multi_piece_file_offsets_indices_and_concatenates_data(tmp_path):
    one = _ascii_vtp()
    head, rest = one.split("<Piece", 1)
    piece = "<Piece" + rest.split("</Piece>", 1)[0] + "</Piece>"
    path = tmp_path / "two.vtp"
    path.write_text(head + piece + piece + "</PolyData></VTKFile>")
    raw = read_vtp(path)
    assert len(raw.points) == 10
    tris = np.concatenate([b.data for b in raw.cells if b.type == "triangle"])
    assert tris.tolist() == [[3, 2, 4], [0, 1, 3], [3, 1, 2], [8, 7, 9], [5, 6, 8], [8, 6, 7]]
    lines = np.concatenate([b.data for b in raw.cells if b.type == "line"])
    assert lines.tolist() == [[0, 1], [1, 2], [5, 6], [6, 7]]
    tri_ids = np.concatenate([v for b, v in zip(raw.cells, raw.cell_data["cell_id"]) if b.type == "triangle"])
    assert tri_ids.tolist() == [30, 40, 40, 30, 40, 40]
    assert raw.point_data["height"].shape == (10,) and raw.point_data["velocity"].shape == (10, 3)


def test_bit_and_small_integer_arrays(tmp_path):
    packed = np.packbits([1, 0, 1, 1]).tobytes()  # binary Bit arrays: eight to a byte, first bit high
    b64 = (base64.b64encode(np.array([len(packed)], "<u8").tobytes()) + base64.b64encode(packed)).decode()
    text = _ascii_vtp().replace(
        "</CellData>", '<DataArray type="Bit" Name="flag" format="ascii">1 0 1 1</DataArray>'
        f'<DataArray type="Bit" Name="packed" format="binary">{b64}</DataArray>'
        '<DataArray type="UInt16" Name="u" format="ascii">65535 0 1 2</DataArray></CellData>')
    path = tmp_path / "bits.vtp"
    path.write_text(text)
    raw = read_vtp(path)
    # cells: vertex (1), polyline (0: two segments), polygon (1), strip (1: two triangles)
    assert np.concatenate(raw.cell_data["flag"]).tolist() == [0, 0, 1, 1, 1]
    assert np.concatenate(raw.cell_data["packed"]).tolist() == [0, 0, 1, 1, 1]
    assert np.concatenate(raw.cell_data["u"]).tolist() == [0, 0, 1, 2, 2]


# ---- refusals -----------------------------------------------------------------------------------

@pytest.mark.parametrize("edit,message", [
    (lambda s: s.replace('NumberOfPoints="5"', 'NumberOfPoints="6"'), "Points: 15 values where 6 x 3"),
    (lambda s: s.replace(">3 2 4<", ">3 2 9<").replace("\n3 2 4\n", "\n3 2 9\n"), "index 9 out of range"),
    (lambda s: s.replace('NumberOfPolys="1"', 'NumberOfPolys="2"'), "Polys offsets: 1 values where 2"),
    (lambda s: s.replace("</Piece>", ""), "malformed XML"),
    (lambda s: s.replace('type="PolyData"', 'type="UnstructuredGrid"'), "not VTK PolyData"),
    (lambda s: s.replace('Name="cell_id" NumberOfComponents="1" format="ascii">\n10 20 30 40',
                         'Name="cell_id" NumberOfComponents="1" format="ascii">\n10 20 30'), "cell_id"),
    (lambda s: s.replace('header_type="UInt64"', 'header_type="UInt16"'), "header_type"),
    (lambda s: s.replace('header_type="UInt64"', 'compressor="vtkBZip2"'), "unknown compressor 'vtkBZip2'"),
    (lambda s: s.replace('type="Float32"', 'type="Float16"'), "unsupported type 'Float16'"),
    (lambda s: s.replace("0.5 1.5 0.0", "0.5 x 0.0"), "malformed .vtp data"),
])
def test_bad_files_name_the_problem(tmp_path, edit, message):
    path = tmp_path / "bad.vtp"
    text = edit(_ascii_vtp())
    assert text != _ascii_vtp()
    path.write_text(text)
    with pytest.raises(FileFormatError, match=message) as info:
        read_vtp(path)
    assert str(path) in str(info.value)


def test_truncated_raw_appended_data(tmp_path):
    blob = _Builder("appended-raw", "<", "UInt64", False).file()
    path = tmp_path / "cut.vtp"
    path.write_bytes(blob[: blob.index(b"_", blob.index(b"<AppendedData")) + 40])
    with pytest.raises(FileFormatError, match="truncated"):
        read_vtp(path)


def test_blocks_that_are_not_lz4_are_refused(tmp_path):
    # zlib blocks labelled LZ4: the decoder finds lengths or offsets past the buffers
    text = _Builder("binary", "<", "UInt32", True).file().replace(b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor")
    path = tmp_path / "lz4.vtp"
    path.write_bytes(text)
    with pytest.raises(FileFormatError, match="LZ4"):
        read_vtp(path)


def _lz4_length(n: int) -> bytes:
    """The extra length bytes of a nibble of 15: 255s, then the rest."""
    return bytes([255] * (n // 255) + [n % 255])


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.binary(min_size=0, max_size=300), st.integers(1, 70000), st.integers(4, 600)),
                min_size=0, max_size=6), st.binary(min_size=0, max_size=40))
def test_lz4_blocks_decode_as_their_sequences_say(sequences, last):
    """LZ4 blocks built from (literals, offset, match length) sequences, by the format's
    rules (https://github.com/lz4/lz4/blob/dev/doc/lz4_Block_format.md), decode to what
    replaying the sequences gives: long lengths (extra bytes), overlapping matches."""
    from hammesh.io._kernels import lz4_block_decode_into

    block, out = bytearray(), bytearray()
    for literals, offset, match in sequences:
        if not out and not literals:
            continue  # a match needs something behind it
        out += literals
        offset = 1 + (offset - 1) % min(len(out), 65535)
        lit_n, match_n = len(literals), match - 4
        block.append((min(lit_n, 15) << 4) | min(match_n, 15))
        block += _lz4_length(lit_n - 15) if lit_n >= 15 else b""
        block += literals + offset.to_bytes(2, "little")
        block += _lz4_length(match_n - 15) if match_n >= 15 else b""
        for _ in range(match):  # byte by byte: the copy may read what it writes
            out.append(out[-offset])
    block.append(min(len(last), 15) << 4)
    block += (_lz4_length(len(last) - 15) if len(last) >= 15 else b"") + last
    out += last
    dst = np.zeros(len(out), dtype=np.uint8)
    got = lz4_block_decode_into(np.frombuffer(bytes(block), dtype=np.uint8), dst)
    assert got == len(out)
    assert dst.tobytes() == bytes(out)
    # a block cut inside its last literals is malformed
    if last:
        assert lz4_block_decode_into(np.frombuffer(bytes(block[:-1]), dtype=np.uint8), dst) == -1


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data(), kind=st.sampled_from(["ascii", "binary", "appended-raw", "appended-base64"]))
def test_truncated_or_mutated_files_raise_file_format_error(tmp_path_factory, data, kind):
    """Any cut or byte change gives a RawMesh or FileFormatError: never another exception."""
    blob = (_ascii_vtp().encode() if kind == "ascii"
            else _Builder(kind, data.draw(st.sampled_from("<>")), "UInt32", data.draw(st.booleans())).file())
    blob = bytearray(blob)
    if data.draw(st.booleans(), label="truncate"):
        blob = blob[: data.draw(st.integers(0, len(blob) - 1), label="cut")]
    else:
        for _ in range(data.draw(st.integers(1, 4), label="mutations")):
            blob[data.draw(st.integers(0, len(blob) - 1))] = data.draw(st.integers(0, 255))
    path = tmp_path_factory.mktemp("fuzz") / "f.vtp"
    path.write_bytes(bytes(blob))
    try:
        raw = read_vtp(path)
    except FileFormatError as exc:
        assert str(path) in str(exc)
        return
    for block in raw.cells:
        assert block.data.dtype == np.int64 and block.data.ndim == 2


@pytest.mark.parametrize("cut", [0.3, 0.7])
def test_cli_truncated_file_exits_2_with_one_line(tmp_path, cut):
    blob = _Builder("appended-raw", "<", "UInt64", True).file()
    path = tmp_path / "cut.vtp"
    path.write_bytes(blob[: int(len(blob) * cut)])
    r = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(path), "-o", str(tmp_path / "o.vtu")],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert "cut.vtp" in r.stderr


# ---- the command line -----------------------------------------------------------------------------

def _grid_vtp(path, nx: int = 6, ny: int = 5) -> tuple[int, np.ndarray]:
    """A planar grid of quads as a raw-appended .vtp with a cell array; (quads, values)."""
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0))
    pts = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    a = (j * (nx + 1) + i).ravel()
    quads = np.column_stack([a, a + 1, a + nx + 2, a + nx + 1])
    values = np.arange(len(quads), dtype=np.float64) * 1.5
    blobs, tags, at = [], [], 0
    for section, name, arr in [("CellData", "pressure", values), ("Points", "Points", pts),
                               ("Polys", "connectivity", quads), ("Polys", "offsets", np.arange(1, len(quads) + 1) * 4)]:
        data = np.ascontiguousarray(arr, dtype="<f8" if arr.dtype.kind == "f" else "<i8").tobytes()
        vtk = "Float64" if arr.dtype.kind == "f" else "Int64"
        comps = arr.shape[1] if arr.ndim == 2 and section == "Points" else 1
        tags.append((section, f'<DataArray type="{vtk}" Name="{name}" NumberOfComponents="{comps}" '
                              f'format="appended" offset="{at}"/>'))
        blobs.append(np.array([len(data)], "<u8").tobytes() + data)
        at += len(blobs[-1])
    body = "".join(f"<{s}>{''.join(t for s2, t in tags if s2 == s)}</{s}>" for s in ("CellData", "Points", "Polys"))
    path.write_bytes(
        (f'<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64"><PolyData>'
         f'<Piece NumberOfPoints="{len(pts)}" NumberOfPolys="{len(quads)}">{body}</Piece></PolyData>'
         '<AppendedData encoding="raw">_').encode() + b"".join(blobs) + b"</AppendedData></VTKFile>")
    return len(quads), values


def test_cli_mesh_vtp_to_vtu_carries_a_cell_array(tmp_path):
    import meshio

    src = tmp_path / "grid.vtp"
    quads, values = _grid_vtp(src)
    out = tmp_path / "out.vtu"
    r = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(src), "-o", str(out),
                        "--report", str(tmp_path / "r.json")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    m = meshio.read(out)
    pressure = np.concatenate(m.cell_data["pressure"])
    assert len(pressure) >= 2 * quads  # each quad split in two (plus any Steiner triangles)
    known = pressure[~np.isnan(pressure)]
    assert set(known.tolist()) <= set(values.tolist())
    assert set(values.tolist()) <= set(known.tolist())  # every quad's value reached the output
    report = json.loads((tmp_path / "r.json").read_text())
    assert report  # written


def test_cli_strip_and_surface_read_a_3d_vtp(tmp_path):
    # a closed octahedron as a .vtp: 3D points, so read by dim=None/3 paths only
    pts = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)
    faces = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    src = tmp_path / "octa.vtp"
    b = _Builder("binary", "<", "UInt32", True)
    src.write_text(
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt32" '
        'compressor="vtkZLibDataCompressor"><PolyData><Piece NumberOfPoints="6" NumberOfPolys="8">'
        f'<Points>{b.array("Points", "Float64", pts, 3)}</Points>'
        f'<Polys>{b.array("connectivity", "Int64", faces)}{b.array("offsets", "Int64", np.arange(1, 9) * 3)}</Polys>'
        "</Piece></PolyData></VTKFile>")
    r = subprocess.run([sys.executable, "-m", "hammesh", "strip", str(src), "-o", str(tmp_path / "s.json")],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "s.json").read_text())
    assert len(doc["indices"]) >= 8 + 2  # one strip over the 8 faces needs at least 10 indices
    r = subprocess.run([sys.executable, "-m", "hammesh", "surface", str(src), "-o", str(tmp_path / "o.vtu")],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert read_mesh(tmp_path / "o.vtu", dim=3).n_triangles >= 8


# ---- pyvista round trips (optional extra) --------------------------------------------------------

def _vtk_triangles(poly) -> set[tuple[int, ...]]:
    """VTK's own triangulation of ``poly`` (vtkTriangleFilter), each triangle rotated to
    start at its smallest index: orientation kept."""
    tri = poly.triangulate()
    faces = tri.faces.reshape(-1, 4)[:, 1:]
    return {tuple(np.roll(f, -int(np.argmin(f))).tolist()) for f in faces}


@pytest.mark.parametrize("mode", ["binary-zlib", "binary", "ascii"])
def test_pyvista_round_trip_with_strips_lines_and_a_quad(tmp_path, mode):
    pv = pytest.importorskip("pyvista")
    pts = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0.5], [2, 1, 0], [0, 2, 0], [1, 2, 0]],
                   dtype=np.float64)
    poly = pv.PolyData(pts, faces=np.array([4, 3, 4, 7, 6]), lines=np.array([3, 0, 1, 2]),
                       strips=np.array([5, 0, 3, 1, 4, 2, 4, 2, 5, 4, 7]))
    poly.cell_data["material"] = np.arange(poly.n_cells, dtype=np.int32) + 100
    poly.point_data["temperature"] = np.linspace(0, 1, len(pts))
    path = tmp_path / "p.vtp"
    if mode == "ascii":
        poly.save(path, binary=False)
    elif mode == "binary":
        poly.save(path, compression=None)
    else:
        poly.save(path)
    raw = read_vtp(path)
    tris = np.concatenate([pv_block.data for pv_block in raw.cells if pv_block.type in ("triangle",)])
    ours = {tuple(np.roll(t, -int(np.argmin(t))).tolist()) for t in tris}
    quad = [b.data.tolist() for b in raw.cells if b.type == "quad"]
    assert quad == [[[3, 4, 7, 6]]]
    assert ours <= _vtk_triangles(poly)  # strips: same triangles, same winding as VTK's filter
    assert len(tris) == 3 + 2  # strip of 5 points: 3, strip of 4: 2
    # cell data: pyvista's cell order is lines, polys, strips
    got = {b.type: v.tolist() for b, v in zip(raw.cells, raw.cell_data["material"])}
    assert got["line"] == [100, 100] and got["quad"] == [101]
    assert got["triangle"] == [102, 102, 102, 103, 103]
    np.testing.assert_allclose(raw.point_data["temperature"], poly.point_data["temperature"])
    np.testing.assert_array_equal(raw.points, pts)


@pytest.mark.parametrize("compression", ["zlib", "lzma", None])
def test_pyvista_surface_reads_as_the_same_mesh(tmp_path, compression):
    pv = pytest.importorskip("pyvista")
    sphere = pv.Sphere(theta_resolution=16, phi_resolution=10)
    sphere.cell_data["area"] = sphere.compute_cell_sizes()["Area"]
    path = tmp_path / "s.vtp"
    sphere.save(path, compression=compression)
    m = read_mesh(path, dim=3)
    np.testing.assert_allclose(m.points, sphere.points, rtol=1e-7)
    np.testing.assert_array_equal(m.triangles, sphere.faces.reshape(-1, 4)[:, 1:])
    np.testing.assert_allclose(m.triangle_attributes[:, m.attribute_names.index("area")], sphere.cell_data["area"])


def test_vtk_multi_piece_file(tmp_path):
    pytest.importorskip("pyvista")
    import vtk

    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(12)
    sphere.SetPhiResolution(8)
    writer = vtk.vtkXMLPolyDataWriter()
    writer.SetInputConnection(sphere.GetOutputPort())
    writer.SetNumberOfPieces(3)
    writer.SetFileName(str(tmp_path / "pieces.vtp"))
    writer.Write()
    assert (tmp_path / "pieces.vtp").read_text(errors="replace").count("<Piece") == 3
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(tmp_path / "pieces.vtp"))
    reader.Update()
    ref = reader.GetOutput()
    raw = read_vtp(tmp_path / "pieces.vtp")
    pts = np.array([ref.GetPoint(i) for i in range(ref.GetNumberOfPoints())])
    np.testing.assert_allclose(raw.points, pts)
    tris = np.concatenate([b.data for b in raw.cells if b.type == "triangle"])
    ids = vtk.vtkIdList()
    ref_tris = []
    for c in range(ref.GetNumberOfCells()):
        ref.GetCellPoints(c, ids)
        ref_tris.append([ids.GetId(k) for k in range(ids.GetNumberOfIds())])
    assert tris.tolist() == ref_tris


# ---- writing ----------------------------------------------------------------------------------------

def test_written_vtp_reads_back_with_cycle_fields_and_vtk(tmp_path, hexagon):
    from hammesh.io import write

    path = tmp_path / "h.vtp"
    write(hexagon, path)
    raw = read_vtp(path)
    tris = np.concatenate([b.data for b in raw.cells])
    np.testing.assert_array_equal(tris, hexagon.triangles)
    np.testing.assert_array_equal(np.concatenate(raw.cell_data["cycle_position"]), np.arange(len(tris)))
    back = read_mesh(path)
    np.testing.assert_array_equal(back.triangles, hexagon.triangles)
    pv = pytest.importorskip("pyvista")
    theirs = pv.read(path)  # VTK reads what hammesh writes
    np.testing.assert_array_equal(theirs.faces.reshape(-1, 4)[:, 1:], hexagon.triangles)
    np.testing.assert_array_equal(theirs.cell_data["cycle_position"], np.arange(len(tris)))


def test_writer_puts_lines_first_and_keeps_each_cells_data(tmp_path):
    import meshio

    from hammesh.io.vtk_xml import write_vtp

    tri = np.array([[0, 1, 2], [0, 2, 3]])
    seg = np.array([[0, 1], [1, 2], [2, 3]])
    mesh = meshio.Mesh(POINTS[:4], [("triangle", tri), ("line", seg)],
                       cell_data={"v": [np.array([1.0, 2.0]), np.array([7.0, 8.0, 9.0])]})
    path = tmp_path / "mixed.vtp"
    write_vtp(path, mesh)
    raw = read_vtp(path)
    got = {b.type: (b.data.tolist(), v.tolist()) for b, v in zip(raw.cells, raw.cell_data["v"])}
    assert got == {"line": (seg.tolist(), [7.0, 8.0, 9.0]), "triangle": (tri.tolist(), [1.0, 2.0])}
