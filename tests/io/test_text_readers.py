"""The vectorised OBJ and OFF readers: every file hypothesis writes reads as a plain
line-by-line reading of the specification says (the oracle below, a Python loop), and
what the files carry beside the geometry (groups, materials, colours) is kept."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import FileFormatError
from hammesh.io import read_mesh
from hammesh.io.obj_format import read_obj
from hammesh.io.off_format import read_off


def _faces_of(raw) -> list[list[int]]:
    return [row.tolist() for block in raw.cells if block.type != "line" for row in block.data]


def _oracle_obj(text: str) -> tuple[np.ndarray, list[list[int]], list[int]]:
    """Points, faces and each face's ``g`` record number (-1 before any), line by line."""
    coords, faces, groups, group = [], [], [], -1
    for line in text.splitlines():
        tokens = line.split("#", 1)[0].split()
        if not tokens:
            continue
        if tokens[0] == "v":
            coords.append([float(t) for t in tokens[1:4]])
        elif tokens[0] == "g":
            group += 1
        elif tokens[0] == "f":
            ids = [int(t.split("/")[0]) for t in tokens[1:]]
            faces.append([i - 1 if i > 0 else len(coords) + i for i in ids])
            groups.append(group)
    return np.array(coords, dtype=np.float64).reshape(-1, 3), faces, groups


_number = st.floats(-1e6, 1e6, allow_nan=False).map(lambda x: repr(float(x)))


@st.composite
def obj_texts(draw) -> str:
    lines: list[str] = []
    n = 0
    for _ in range(draw(st.integers(1, 25))):
        kind = draw(st.sampled_from(["v", "v", "f", "g", "vt", "comment", "blank"]))
        if kind == "v" or n < 3:
            lines.append(" ".join(["v", *draw(st.lists(_number, min_size=3, max_size=3))]))
            n += 1
        elif kind == "f":
            k = draw(st.integers(3, 6))
            tokens = []
            for _ in range(k):
                i = draw(st.integers(1, n))
                index = str(i) if draw(st.booleans()) else str(i - 1 - n)  # relative: i - 1 - n
                tokens.append(index + draw(st.sampled_from(["", "/1", "//2", "/1/2"])))
            lines.append("f " + draw(st.sampled_from([" ", "\t", "  "])).join(tokens))
        elif kind == "g":
            lines.append("g part" + str(draw(st.integers(0, 3))))
        elif kind == "vt":
            lines.append("vt 0.5 0.5")
        elif kind == "comment":
            lines.append("# f 1 2 3")
        else:
            lines.append("   ")
    end = draw(st.sampled_from(["\n", "\r\n"]))
    return end.join(lines) + end


@settings(max_examples=150, deadline=None)
@given(obj_texts())
def test_obj_reads_as_the_specification_line_by_line(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("obj") / "m.obj"
    path.write_bytes(text.encode())
    points, faces, groups = _oracle_obj(text)
    raw = read_obj(path)
    np.testing.assert_array_equal(raw.points, points)
    assert _faces_of(raw) == faces  # (blocks are runs of equal size: file order kept)
    if "obj:group_ids" in raw.cell_data:
        assert [g for ids in raw.cell_data["obj:group_ids"] for g in ids.tolist()] == groups
    else:
        assert not any(line.split()[:1] == ["g"] for line in text.splitlines())


def test_obj_groups_materials_and_vertex_colours_are_carried(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nv 2 0 0 0 0 0\n"
                    "f 1 2 3\ng a\nusemtl steel\nf 1 3 4\ng b\nusemtl wood\nf 2 5 3\nusemtl steel\nf 1 2 4\n"
                    "l 1 2 5\n")
    m = read_mesh(path)
    col = {name: m.triangle_attributes[:, i] for i, name in enumerate(m.attribute_names)}
    assert col["obj:group_ids"].tolist() == [-1, 0, 1, 1]  # meshio's numbering of g records
    assert col["obj:material_ids"].tolist() == [-1, 0, 1, 0]
    assert m.info["obj:materials"] == ["steel", "wood"]
    np.testing.assert_array_equal(m.point_data["color"][:3], np.eye(3))
    assert sorted(map(tuple, np.sort(m.segments, axis=1).tolist())) == [(0, 1), (1, 4)]


def test_obj_extra_vertex_columns_on_some_lines_are_named_not_dropped(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    m = read_mesh(path)
    assert "vertex fields beyond x y z (on some v records only)" in m.info["not_carried"]



@st.composite
def off_texts(draw) -> tuple[str, np.ndarray, list[list[int]], np.ndarray | None]:
    nv = draw(st.integers(3, 12))
    points = np.array(draw(st.lists(st.lists(_number, min_size=3, max_size=3), min_size=nv, max_size=nv)),
                      dtype=np.float64)
    nf = draw(st.integers(1, 10))
    faces = [draw(st.lists(st.integers(0, nv - 1), min_size=3, max_size=6)) for _ in range(nf)]
    colours = np.array(draw(st.lists(st.lists(st.integers(0, 255), min_size=3, max_size=3),
                                     min_size=nf, max_size=nf))) if draw(st.booleans()) else None
    # the keyword on the counts' line, on its own line, or absent (Geomview: "recommended
    # but optional, as many existing files lack this keyword")
    head = draw(st.sampled_from([f"OFF {nv} {nf} 0\n", f"OFF\n# a comment\n{nv} {nf} 0\n", f"# a cube\n{nv} {nf} 0\n",
                                 f"{nv} {nf}\n"]))
    body = "".join(" ".join(repr(float(x)) for x in p) + "\n" for p in points)
    for i, f in enumerate(faces):
        body += f"{len(f)} " + " ".join(map(str, f))
        body += (" " + " ".join(map(str, colours[i]))) if colours is not None else ""
        body += "\n\n" if i % 3 == 0 else "\n"
    return head + body, points, faces, colours


@settings(max_examples=150, deadline=None)
@given(off_texts())
def test_off_reads_as_written_with_face_colours(tmp_path_factory, case):
    text, points, faces, colours = case
    path = tmp_path_factory.mktemp("off") / "m.off"
    path.write_text(text)
    raw = read_off(path)
    np.testing.assert_array_equal(raw.points, points)
    assert _faces_of(raw) == faces
    if colours is None:
        assert "color" not in raw.cell_data
    else:
        np.testing.assert_array_equal(np.concatenate(raw.cell_data["color"]), colours)


def test_coff_vertex_colours_and_face_colours_reach_the_output(tmp_path):
    import meshio

    from hammesh.cli import main

    path = tmp_path / "c.off"
    path.write_text("COFF\n4 2 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n1 1 0 0 0 1 1\n0 1 0 1 1 1 1\n"
                    "3 0 1 2 255 0 0\n3 0 2 3 0 255 0\n")
    m = read_mesh(path)
    np.testing.assert_array_equal(m.point_data["color"][:, :3], [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])
    out = tmp_path / "o.vtu"
    assert main(["mesh", str(path), "-o", str(out)]) == 0
    written = meshio.read(out)
    assert any(k.startswith("color") for k in written.cell_data) and "color" in written.point_data


@pytest.mark.parametrize("suffix, text, message", [
    (".obj", "v 0 0\nf 1 1 1\n", r"m\.obj:1: a vertex needs x y z"),
    (".obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", r"m\.obj:4: a face needs at least 3 vertices"),
    (".obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", r"m\.obj:4: vertex index is not an integer: 'x'"),
    (".obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", r"m\.obj:4: vertex index 0 refers to no vertex"),
    (".obj", "v 0 0 0\nv 1 0 zz\nv 0 1 0\nf 1 2 3\n", r"m\.obj:2: a field is not a number"),
    (".off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", r"m\.off:6: face declares 4 corners, lists 3"),
    (".off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n", r"m\.off:5: a field is not a number"),
    (".off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n", r"m\.off:6: vertex index -2 refers to no vertex"),
    (".off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n", r"m\.off:6: a face line is not 'k i0 .. ik-1'"),
    (".off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", r"declares 3 vertices and 2 faces"),
    (".off", "4OFF\n1 0 0\n0 0 0 0\n", r"4D and n-dimensional"),
    (".off", "3 1 x\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", r"not an OFF file \(no OFF keyword\)"),
])
def test_bad_records_are_named_with_their_line(tmp_path, suffix, text, message):
    path = tmp_path / f"m{suffix}"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=message):
        read_mesh(path)
