"""hammesh.io.triangle_format: Triangle's .node/.ele/.poly files."""

from __future__ import annotations

import os

import numpy as np
import pytest
import triangle
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from hammesh.errors import FileFormatError
from hammesh.io import triangle_format
from hammesh.io.cell_data import cycle_ids
from hammesh.mesh import Mesh


@pytest.mark.parametrize("suffix", [".ele", ".node"])
def test_round_trip(tmp_path, hmesh, suffix, assert_cycle_order):
    triangle_format.write(hmesh, tmp_path / f"m{suffix}")
    assert sorted(os.listdir(tmp_path)) == ["m.ele", "m.node", "m.poly"]
    back = triangle_format.read_ele(tmp_path / f"m{suffix}")
    np.testing.assert_array_equal(back.points, hmesh.points)
    np.testing.assert_array_equal(back.triangles, hmesh.triangles)
    assert_cycle_order(back.triangles, hmesh.components)
    np.testing.assert_array_equal(back.segments, hmesh.segments)
    np.testing.assert_array_equal(back.segment_markers, hmesh.segment_markers)
    np.testing.assert_array_equal(back.triangle_attributes, hmesh.triangle_attributes)


def test_ele_attributes_hold_the_cycle(tmp_path, two_cycles):
    triangle_format.write(two_cycles, tmp_path / "m.ele")
    text = (tmp_path / "m.ele").read_text()
    assert "# attributes: attribute_0 attribute_1 cycle_id cycle_position kind parent" in text
    lines = [ln.split("#")[0].split() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln]
    assert lines[0] == ["10", "3", "6"]
    rows = np.array(lines[1:], dtype=np.float64)
    assert rows[:, 0].tolist() == list(range(10))  # zero-based numbering
    np.testing.assert_array_equal(rows[:, 1:4], two_cycles.triangles)
    np.testing.assert_array_equal(rows[:, 4:6], two_cycles.triangle_attributes)
    np.testing.assert_array_equal(rows[:, 6], cycle_ids(two_cycles.components))
    np.testing.assert_array_equal(rows[:, 7], two_cycles.position)
    np.testing.assert_array_equal(rows[:, 8], two_cycles.kind)
    np.testing.assert_array_equal(rows[:, 9], two_cycles.parent)


def test_ele_keeps_a_partitioned_meshs_parts(tmp_path, two_cycles):
    import hammesh

    parted = hammesh.partitioned(two_cycles, 2)
    triangle_format.write(parted, tmp_path / "m.ele")
    text = (tmp_path / "m.ele").read_text()
    assert "cycle_position kind parent part\n" in text
    rows = np.array([ln.split() for ln in text.splitlines() if ln and not ln.startswith("#")][1:], dtype=np.float64)
    np.testing.assert_array_equal(rows[:, -1], parted.part)
    back = triangle_format.read_ele(tmp_path / "m.ele")  # hammesh's own columns are not attributes
    np.testing.assert_array_equal(back.triangle_attributes, two_cycles.triangle_attributes)
    assert hammesh.io.unwritten_data(parted, tmp_path / "m.ele") == []
    assert "cell data 'part' (.obj holds geometry only)" in hammesh.io.unwritten_data(parted, tmp_path / "m.obj")


def test_triangle_package_reads_our_files(tmp_path, hexagon):
    triangle_format.write(hexagon, tmp_path / "m.ele")
    data = triangle.load(str(tmp_path), "m")
    np.testing.assert_array_equal(data["vertices"], hexagon.points)
    np.testing.assert_array_equal(data["triangles"], hexagon.triangles)
    np.testing.assert_array_equal(data["segments"], hexagon.segments)


def test_plain_mesh_without_segments(tmp_path, hexagon):
    mesh = Mesh(hexagon.points, hexagon.triangles)
    triangle_format.write(mesh, tmp_path / "p.ele")
    back = triangle_format.read_ele(tmp_path / "p.ele")
    assert back.segments.shape == (0, 2) and back.triangle_attributes.shape == (6, 0)


def _write(tmp_path, name, node, ele, poly=None):
    (tmp_path / f"{name}.node").write_text(node)
    (tmp_path / f"{name}.ele").write_text(ele)
    if poly is not None:
        (tmp_path / f"{name}.poly").write_text(poly)
    return tmp_path / f"{name}.ele"


NODE_1 = """# one-based, with an attribute and boundary markers
4 2 1 1
1 0.0 0.0 7.0 1
2 1.0 0.0 7.0 1

3 1.0 1.0 7.0 0   # trailing comment
4 0.0 1.0 7.0 1
"""


def test_one_based_files_with_comments_and_markers(tmp_path):
    ele = "2 3 1\n1 1 2 3 0.5\n2 1 3 4 1.5 # second\n"
    poly = "0 2 0 1\n2 1\n1 1 2 5\n2 4 1 6\n0\n"
    back = triangle_format.read_ele(_write(tmp_path, "one", NODE_1, ele, poly))
    assert back.points.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]
    assert back.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert back.triangle_attributes.tolist() == [[0.5], [1.5]]
    assert back.segments.tolist() == [[0, 1], [3, 0]]
    assert back.segment_markers.tolist() == [5, 6]


def test_second_order_elements_keep_corners(tmp_path):
    node = "6 2\n" + "".join(f"{i} {x} {y}\n" for i, (x, y) in enumerate(
        [(0, 0), (2, 0), (0, 2), (1, 1), (0, 1), (1, 0)]))
    back = triangle_format.read_ele(_write(tmp_path, "q", node, "1 6 0\n0 0 1 2 3 4 5\n"))
    assert back.triangles.tolist() == [[0, 1, 2]]


NODE_0 = "3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n"


@pytest.mark.parametrize(
    ("node", "ele", "pattern"),
    [
        (NODE_0, "", r"bad\.ele: unexpected end of file"),
        (NODE_0, "1 3 0\n0 0 1 two\n", r"bad\.ele:2: vertex index is not an integer: 'two'"),
        (NODE_0, "hello world\n", r"bad\.ele:1: number of triangles is not an integer"),
        (NODE_0, "1 3 0\n0 0 1 3\n", r"bad\.ele:2: vertex index 3 out of range \[0, 3\)"),
        (NODE_0, "1 3 0\n0 0 -1 2\n", r"bad\.ele:2: vertex index -1 out of range"),
        (NODE_0, "2 3 0\n0 0 1 2\n", r"bad\.ele:1: declares 2 triangles, the file has only 1 more records"),
        (NODE_0, "1 3 1\n0 0 1 2\n", r"bad\.ele:2: expected 5 numbers"),
        (NODE_0, "0 3 0\n", r"bad\.ele:1: no triangles"),
        (NODE_0, "1 4 0\n0 0 1 2 0\n", r"bad\.ele:1: nodes per triangle is 4"),
        ("3 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n", "1 3 0\n0 0 1 2\n", r"bad\.node:1: dimension is 3"),
        ("3 2 0 0\n0 0 0\n1 1 zero\n2 0 1\n", "1 3 0\n0 0 1 2\n", r"bad\.node:3: y is not a number"),
        ("3 2 0 0\n0 0 0\n2 1 0\n3 0 1\n", "1 3 0\n0 0 1 2\n", r"bad\.node:3: vertex number 2, expected 1"),
        ("3 2 0 0\n5 0 0\n6 1 0\n7 0 1\n", "1 3 0\n0 0 1 2\n", r"bad\.node:2: first vertex number must be 0 or 1"),
        ("3 2 0 0\n0 0 0\n1 nan 0\n2 0 1\n", "1 3 0\n0 0 1 2\n", r"bad\.node:3: vertex 1 is not finite"),
        ("", "1 3 0\n0 0 1 2\n", r"bad\.node: unexpected end of file"),
    ],
)
def test_malformed_files_name_file_and_line(tmp_path, node, ele, pattern):
    with pytest.raises(FileFormatError, match=pattern):
        triangle_format.read_ele(_write(tmp_path, "bad", node, ele))


def test_bad_poly_is_reported(tmp_path):
    path = _write(tmp_path, "bad", NODE_0, "1 3 0\n0 0 1 2\n", "0 2 0 1\n1 1\n0 0 9 1\n0\n")
    with pytest.raises(FileFormatError, match=r"bad\.poly:3: vertex index 9 out of range"):
        triangle_format.read_ele(path)


def test_missing_node_or_ele(tmp_path):
    (tmp_path / "lonely.ele").write_text("1 3 0\n0 0 1 2\n")
    with pytest.raises(FileFormatError, match=r"lonely\.node: no such file \(needed by lonely\.ele\)"):
        triangle_format.read_ele(tmp_path / "lonely.ele")
    (tmp_path / "alone.node").write_text(NODE_0)
    with pytest.raises(FileFormatError, match=r"alone\.ele: no such file"):
        triangle_format.read_ele(tmp_path / "alone.node")


def test_binary_garbage(tmp_path):
    (tmp_path / "g.node").write_bytes(np.random.default_rng(3).bytes(500))
    (tmp_path / "g.ele").write_text("1 3 0\n0 0 1 2\n")
    with pytest.raises(FileFormatError, match=r"g\.node: not a text file"):
        triangle_format.read_ele(tmp_path / "g.ele")


def test_stem_with_dots(tmp_path, hexagon):
    triangle_format.write(hexagon, tmp_path / "plate.1.ele")
    assert sorted(os.listdir(tmp_path)) == ["plate.1.ele", "plate.1.node", "plate.1.poly"]
    assert triangle_format.read_ele(tmp_path / "plate.1.node").n_triangles == 6


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(3, 40), seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1e-9, 1.0, 1e7]),
       k=st.integers(0, 2))
def test_ele_round_trip_property(tmp_path, n, seed, scale, k):
    rng = np.random.default_rng(seed)
    points = (rng.random((n, 2)) - 0.5) * scale + np.pi * scale
    triangles = Delaunay(points).simplices.astype(np.int64)[::-1]
    attrs = rng.normal(size=(len(triangles), k)) * 1e5
    edges = triangles[:, :2][: rng.integers(0, len(triangles) + 1)]
    mesh = Mesh(points, triangles, segments=edges, segment_markers=rng.integers(0, 9, len(edges)),
                triangle_attributes=attrs)
    triangle_format.write(mesh, tmp_path / "h.ele")
    back = triangle_format.read_ele(tmp_path / "h.ele")
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_array_equal(back.triangle_attributes, mesh.triangle_attributes)
    np.testing.assert_array_equal(back.segments, mesh.segments)
    np.testing.assert_array_equal(back.segment_markers, mesh.segment_markers)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(3, 30), seed=st.integers(0, 2**32 - 1), base=st.sampled_from([0, 1]),
       k=st.integers(0, 2), marks=st.booleans())
def test_vectorised_and_row_readers_agree(tmp_path, n, seed, base, k, marks):
    """Triangle's files as people write them (comments, blank lines, trailing tokens, any
    base): the one-pass table read gives what the row-by-row reader gives."""
    rng = np.random.default_rng(seed)
    points = rng.random((n, 2)) * 10
    triangles = Delaunay(points).simplices
    attrs = rng.normal(size=(len(triangles), k))

    def noise() -> str:  # a comment or blank line now and then
        return rng.choice(["", "", "", "\n", "# note\n", "   \n"])

    node = f"{n} 2 0 {int(marks)}\n" + "".join(
        noise() + f"{i + base} {float(x)!r} {float(y)!r}" + (f" {i % 3}" if marks else "") + " # c\n"
        for i, (x, y) in enumerate(points))
    ele = f"{len(triangles)} 3 {k}\n" + "".join(
        noise() + f"{j + base} " + " ".join(str(v + base) for v in t) + "".join(f" {float(a)!r}" for a in row) + "\n"
        for j, (t, row) in enumerate(zip(triangles, attrs)))
    path = _write(tmp_path, "w", node, ele)
    fast = triangle_format.read_ele(path)
    original = triangle_format._Tokens.table
    try:
        triangle_format._Tokens.table = lambda self, count, width: None  # row by row only
        rows = triangle_format.read_ele(path)
    finally:
        triangle_format._Tokens.table = original
    for a, b in [(fast.points, rows.points), (fast.triangles, rows.triangles),
                 (fast.triangle_attributes, rows.triangle_attributes), (fast.vertex_markers, rows.vertex_markers)]:
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(fast.points, points)
    np.testing.assert_array_equal(fast.triangles, triangles)
