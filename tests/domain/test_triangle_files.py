"""Tests of hammesh.domain.triangle_files and read_domain."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import triangle

from hammesh.domain import READERS, Domain, read_domain, read_node, read_poly, write_poly
from hammesh.domain import triangle_files
from hammesh.errors import FileFormatError, InvalidDomainError

TRIANGLE_DATA = Path(os.path.dirname(triangle.__file__)) / "data"
BUNDLED = sorted(p.name for p in TRIANGLE_DATA.iterdir() if p.suffix in (".poly", ".node"))


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


SQUARE_POLY_1 = """\
# a unit square with a hole marker outside, 1-based
4 2 1 1   # 4 vertices, dim 2, 1 attribute, markers
1 0 0 0.5 7
2 1 0 0.5 7

3 1 1 0.5 7
4 0 1 0.5 7
4 1
1 1 2 3
2 2 3 3
3 3 4 3   # comment after a record
4 4 1 3
0
"""


# ----------------------------------------------------------------------------- bundled

@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_triangle_files_match_triangle_reader(name):
    path = TRIANGLE_DATA / name
    stem = name[: -len(path.suffix)]
    d = read_domain(path)
    if path.suffix == ".poly":
        ref = triangle.get_data(stem)
    else:  # the stem's .poly (if any) would override the vertices in get_data
        ref = triangle.data.loads(node=path.read_text())
    np.testing.assert_array_equal(d.vertices, ref["vertices"])
    if "vertex_markers" in ref:
        np.testing.assert_array_equal(d.vertex_markers, ref["vertex_markers"][:, 0])
    if path.suffix == ".poly":
        np.testing.assert_array_equal(d.segments, ref.get("segments", np.zeros((0, 2))))
        np.testing.assert_array_equal(d.segment_markers[:, None],
                                      ref.get("segment_markers", np.ones((len(d.segments), 1))))
        np.testing.assert_array_equal(d.holes, ref.get("holes", np.zeros((0, 2))))
        if "regions" in ref and stem != "la.1":
            # triangle.get_data assumes 4-field region lines; la.1.poly has 5 (checked below)
            np.testing.assert_array_equal(d.regions[:, :2], ref["regions"][:, :2])
    else:
        assert d.segments.shape == (0, 2)


def test_bundled_la_regions_single_value_is_attribute_and_area():
    # la.poly's region lines hold one value after x y (Triangle: both attribute and area)
    d = read_poly(TRIANGLE_DATA / "la.poly")
    np.testing.assert_array_equal(d.regions[:, 2], [0.05, 0.05, 0.2, 0.4, 0.8, 3])
    np.testing.assert_array_equal(d.regions[:, 3], d.regions[:, 2])
    # la.1.poly, written by Triangle from la.poly, spells the same regions out with
    # 5 fields (x y attribute area): Triangle itself read the single value as both
    r1 = read_poly(TRIANGLE_DATA / "la.1.poly").regions
    np.testing.assert_array_equal(r1, d.regions)


def test_bundled_poly_with_zero_vertices_uses_sibling_node():
    d = read_poly(TRIANGLE_DATA / "A.1.poly")
    np.testing.assert_array_equal(d.vertices, read_node(TRIANGLE_DATA / "A.1.node").vertices)
    assert len(d.segments) == 29


# ----------------------------------------------------------------------------- reading

def test_one_based_file_with_comments_attributes_markers(tmp_path):
    d = read_poly(write(tmp_path, "sq.poly", SQUARE_POLY_1))
    assert d.vertices.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]
    assert d.segments.tolist() == [[0, 1], [1, 2], [2, 3], [3, 0]]
    assert d.vertex_markers.tolist() == [7] * 4 and d.segment_markers.tolist() == [3] * 4
    assert d.holes.shape == (0, 2) and d.regions.shape == (0, 4)


def test_zero_based_file_gives_same_domain(tmp_path):
    text0 = """4 2 0 0
0 0 0
1 1 0
2 1 1
3 0 1
4 0
0 0 1
1 1 2
2 2 3
3 3 0
1
0 0.5 0.5
"""
    d = read_poly(write(tmp_path, "sq0.poly", text0))
    assert d.segments.tolist() == [[0, 1], [1, 2], [2, 3], [3, 0]]
    assert d.segment_markers.tolist() == [1, 1, 1, 1]  # no markers in file -> boundary
    assert d.vertex_markers.tolist() == [0, 0, 0, 0]
    assert d.holes.tolist() == [[0.5, 0.5]]


def test_regions_max_area_conventions(tmp_path):
    text = SQUARE_POLY_1.rstrip("\n") + """
4
1 0.1 0.1 5 0.25
2 0.2 0.2 6 -1
3 0.3 0.3 7 0
4 0.4 0.4 0.125
"""
    d = read_poly(write(tmp_path, "r.poly", text))
    np.testing.assert_array_equal(d.regions[:, :3], [[0.1, 0.1, 5], [0.2, 0.2, 6],
                                                     [0.3, 0.3, 7], [0.4, 0.4, 0.125]])
    assert d.regions[0, 3] == 0.25 and np.isnan(d.regions[1, 3]) and np.isnan(d.regions[2, 3])
    assert d.regions[3, 3] == 0.125


def test_header_fields_may_be_omitted_like_triangle(tmp_path):
    d = read_poly(write(tmp_path, "short.poly", "3\n1 0 0\n2 1 0\n3 0 1\n3\n1 1 2\n2 2 3\n3 3 1\n0\n"))
    assert d.segments.tolist() == [[0, 1], [1, 2], [2, 0]]


def test_node_file_has_no_segments(tmp_path):
    d = read_node(write(tmp_path, "pts.node", "# points\n4 2 0 1\n0 0 0 1\n1 2 0 1\n2 0 2 0\n3 1 1 0\n"))
    assert d.segments.shape == (0, 2) and d.vertex_markers.tolist() == [1, 1, 0, 0]


def test_poly_with_zero_vertices_reads_node_with_its_base(tmp_path):
    write(tmp_path, "m.node", "3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n")
    d = read_poly(write(tmp_path, "m.poly", "0 2 0 0\n3 0\n0 0 1\n1 1 2\n2 2 0\n0\n"))
    assert d.vertices.tolist() == [[0, 0], [1, 0], [0, 1]]
    assert d.segments.tolist() == [[0, 1], [1, 2], [2, 0]]


def test_poly_with_zero_vertices_and_missing_node(tmp_path):
    with pytest.raises(FileFormatError, match=r"lonely\.poly line 2: 0 vertices declared but lonely\.node"):
        read_poly(write(tmp_path, "lonely.poly", "# nothing\n0 2 0 0\n0 0\n0\n"))


def test_invalid_domain_in_file_names_file(tmp_path):
    text = "4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n2 0\n1 1 3\n2 2 4\n0\n"
    with pytest.raises(InvalidDomainError,
                       match=r"^x\.poly: segments 0 and 1 cross at \(0\.5, 0\.5\) \(indices zero-based"):
        read_poly(write(tmp_path, "x.poly", text), strict=True)
    with pytest.raises(InvalidDomainError, match=r"^d\.node: vertices 0 and 2 are duplicates"):
        read_node(write(tmp_path, "d.node", "3 2 0 0\n0 0 0\n1 1 0\n2 0 0\n"), strict=True)
    with pytest.raises(InvalidDomainError, match=r"^o\.poly: segment 0 references vertex 7"):
        read_poly(write(tmp_path, "o.poly", "3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n1 0\n0 0 7\n0\n"))


# ----------------------------------------------------------------------------- errors

@pytest.mark.parametrize("text, pattern", [
    ("3 2 0 0\n1 0 0\n2 1 0\n", r"f\.poly line 3: file ends early, expected vertex 3 of 3"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n", r"f\.poly line 4: file ends early, expected the segment header"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 0\n1 1 2\n", r"line 6: file ends early, expected the hole header"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n2 0\n1 1 2\n0\n", r"line 7: segment 2 of 2: expected 3 numbers, got 1"),
    ("3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n", r"f\.poly line 1: dimension must be 2, got 3"),
    ("3 2 0 0\n1 0 0\n2 1 zero\n3 0 1\n0 0\n0\n", r"f\.poly line 3: y coordinate must be a number, got 'zero'"),
    ("3 2 0 0\n1 0 0\n2 1 1_0\n3 0 1\n0 0\n0\n", r"line 3: y coordinate must be a number, got '1_0'"),
    ("3 2 0 1\n1 0 0\n2 1 0\n3 0 1\n0 0\n0\n", r"f\.poly line 2: vertex 1 of 3: expected 4 numbers, got 3"),
    ("3 2 0 0\n1 0 0 5\n2 1 0\n3 0 1\n0 0\n0\n", r"line 2: vertex 1 of 3: expected 3 numbers, got 4"),
    ("3 2 0 0\n1 0 0\n3 1 0\n2 0 1\n0 0\n0\n", r"line 3: vertex index 3 out of sequence, expected 2"),
    ("3 2 0 0\n2 0 0\n3 1 0\n4 0 1\n0 0\n0\n", r"line 2: the first vertex must be numbered 0 or 1, got 2"),
    ("3 2 0 2\n1 0 0 1 1\n2 1 0 1 1\n3 0 1 1 1\n", r"line 1: number of vertex boundary markers must be 0 or 1"),
    ("3 2 -1 0\n", r"line 1: number of attributes must be >= 0, got -1"),
    ("-3 2 0 0\n", r"line 1: number of vertices must be >= 0"),
    ("3 2 0 0 9\n", r"line 1: vertex header has 5 fields"),
    ("3.0 2 0 0\n", r"line 1: number of vertices must be an integer, got '3\.0'"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 2\n1 1 2 1\n0\n",
     r"line 5: number of segment boundary markers must be 0 or 1, got 2"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 0\n1 1 x\n0\n", r"line 6: segment endpoint must be an integer"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n2\n1 5 5\n", r"line 7: file ends early, expected hole 2 of 2"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n0\n1\n1 0.2 0.2\n", r"line 8: region 1 of 1: expected 4 or 5"),
    ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n0\n0\n7 7\n", r"line 8: unexpected data after the region section"),
    ("# only\n\n   # comments\n", r"f\.poly: file is empty"),
    ("", r"f\.poly: file is empty"),
])
def test_malformed_poly_names_file_and_line(tmp_path, text, pattern):
    with pytest.raises(FileFormatError, match=pattern):
        read_poly(write(tmp_path, "f.poly", text))


def test_malformed_node(tmp_path):
    with pytest.raises(FileFormatError, match=r"n\.node line 5: unexpected data after the vertex section"):
        read_node(write(tmp_path, "n.node", "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 2 3\n"))
    with pytest.raises(FileFormatError, match=r"n2\.node line 2: file ends early, expected vertex 2 of 4"):
        read_node(write(tmp_path, "n2.node", "4 2 0 0\n1 0 0\n"))


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(FileFormatError, match=r"nope\.poly: no such file"):
        read_poly(tmp_path / "nope.poly")
    with pytest.raises(FileFormatError, match=r"nope\.node: no such file"):
        read_domain(tmp_path / "nope.node")
    (tmp_path / "bin.node").write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(FileFormatError, match=r"bin\.node: not a text file"):
        read_node(tmp_path / "bin.node")
    with pytest.raises(FileFormatError, match=r"is a directory"):
        read_poly(tmp_path)


def test_read_domain_dispatch(tmp_path):
    assert set(READERS) == {".poly", ".node"}
    p = write(tmp_path, "UPPER.POLY", SQUARE_POLY_1)
    assert len(read_domain(p).segments) == 4
    with pytest.raises(FileFormatError,
                       match=r"mesh\.msh: unknown domain file suffix '\.msh' \(known: \.node, \.poly\)"):
        read_domain(tmp_path / "mesh.msh")
    with pytest.raises(FileFormatError, match=r"unknown domain file suffix ''"):
        read_domain(tmp_path / "noext")


# ----------------------------------------------------------------------------- writing

def test_write_poly_roundtrip_and_triangle_can_read_it(tmp_path):
    d = Domain([[0, 0], [1, 0], [1, 1], [0, 1], [0.1, 1 / 3], [0.3, 0.2], [0.2, 0.35]],
               [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 4]],
               holes=[[0.2, 0.3]], regions=[[0.9, 0.9, -2.5, np.nan], [0.5, 0.5, 1, 1e-3]],
               segment_markers=[1, 2, 3, 4, 0, 0, 0], vertex_markers=[9, 8, 7, 6, 5, 4, 3])
    path = tmp_path / "out.poly"
    write_poly(d, path)
    back = read_poly(path)
    for name in ("vertices", "segments", "holes", "regions", "segment_markers", "vertex_markers"):
        np.testing.assert_array_equal(getattr(back, name), getattr(d, name), err_msg=name)
    ref = triangle.data.loads(poly=path.read_text())
    np.testing.assert_array_equal(ref["vertices"], d.vertices)
    np.testing.assert_array_equal(ref["segments"], d.segments)
    assert [p.name for p in tmp_path.iterdir()] == ["out.poly"]  # no temp file left


def test_write_poly_is_atomic_on_failure(tmp_path, monkeypatch):
    path = tmp_path / "keep.poly"
    path.write_text("old content\n")
    d = Domain([[0, 0], [1, 0], [0, 1]])

    def boom(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(triangle_files.os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        write_poly(d, path)
    assert path.read_text() == "old content\n"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.poly"]


def test_write_poly_overwrites_and_rejects_non_domain(tmp_path):
    path = tmp_path / "o.poly"
    path.write_text("junk")
    write_poly(Domain([[0, 0], [1, 0], [0, 1]]), path)
    assert len(read_poly(path).vertices) == 3
    with pytest.raises(TypeError, match="needs a Domain"):
        write_poly({"vertices": [[0, 0]]}, path)


@pytest.mark.skipif(not os.path.exists("/dev/zero") or not hasattr(os, "mkfifo"), reason="POSIX devices and FIFOs")
@pytest.mark.parametrize("name", ["zero.poly", "zero.node", "fifo.poly"])
def test_a_device_or_a_pipe_is_refused_not_read_without_end(tmp_path, name):
    # (/dev/zero behind a .poly name was read until the memory cap: 2.5 GB, then killed)
    path = tmp_path / name
    if name.startswith("fifo"):
        os.mkfifo(path)  # (reading would block forever: no writer)
    else:
        path.symlink_to("/dev/zero")
    with pytest.raises(FileFormatError, match="not a regular file"):
        read_domain(path)
