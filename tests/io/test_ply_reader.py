"""hammesh's PLY reader: files built here from known arrays (ASCII, binary little- and
big-endian, ragged faces, properties before and after the index list) read back as
built; VTK's own files with face colours (meshio 5 fails on them) are read."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import FileFormatError
from hammesh.io import read_mesh
from hammesh.io.ply_format import read_ply

TYPES = {"uchar": "u1", "short": "i2", "int": "i4", "float": "f4", "double": "f8"}


def _ply(fmt: str, points, faces, vprops: dict, fprops_before: dict, fprops_after: dict,
         count_type: str = "uchar", index_type: str = "int") -> bytes:
    """A PLY file of ``points`` and ``faces`` (lists) with the given scalar properties."""
    head = ["ply", f"format {fmt} 1.0", "comment built by the test", f"element vertex {len(points)}",
            "property double x", "property double y", "property double z"]
    head += [f"property {t} {name}" for name, (t, _) in vprops.items()]
    head.append(f"element face {len(faces)}")
    head += [f"property {t} {name}" for name, (t, _) in fprops_before.items()]
    head.append(f"property list {count_type} {index_type} vertex_indices")
    head += [f"property {t} {name}" for name, (t, _) in fprops_after.items()]
    head.append("end_header")
    out = ("\n".join(head) + "\n").encode()
    order = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}[fmt]

    def val(t, v):
        if order is None:
            return repr(float(v)) if TYPES[t][0] == "f" else str(int(v))
        return np.array([v], dtype=order + TYPES[t]).tobytes()

    for i, p in enumerate(points):
        fields = [val("double", x) for x in p] + [val(t, vs[i]) for t, vs in vprops.values()]
        out += (" ".join(fields) + "\n").encode() if order is None else b"".join(fields)
    for i, f in enumerate(faces):
        fields = [val(t, vs[i]) for t, vs in fprops_before.values()]
        fields += [val(count_type, len(f))] + [val(index_type, j) for j in f]
        fields += [val(t, vs[i]) for t, vs in fprops_after.values()]
        out += (" ".join(fields) + "\n").encode() if order is None else b"".join(fields)
    return out


@st.composite
def ply_cases(draw):
    nv = draw(st.integers(3, 9))
    points = np.array(draw(st.lists(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=3, max_size=3),
                                    min_size=nv, max_size=nv)))
    nf = draw(st.integers(1, 8))
    ragged = draw(st.booleans())
    faces = [draw(st.lists(st.integers(0, nv - 1), min_size=3, max_size=5 if ragged else 3)) for _ in range(nf)]
    if not ragged:
        faces = [f[:3] for f in faces]

    def props(n, names):
        chosen = draw(st.lists(st.sampled_from(names), unique=True, max_size=3))
        return {name: (t, [draw(st.integers(0, 100)) for _ in range(n)])
                for name in chosen for t in [draw(st.sampled_from(list(TYPES)))]}

    fmt = draw(st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]))
    return (fmt, points, faces, props(nv, ["nx", "red", "u"]), props(nf, ["flags"]),
            props(nf, ["red", "green", "quality"]), draw(st.sampled_from(["uchar", "int"])))


@settings(max_examples=120, deadline=None)
@given(ply_cases())
def test_files_read_back_as_built(tmp_path_factory, case):
    fmt, points, faces, vprops, before, after, count_type = case
    path = tmp_path_factory.mktemp("ply") / "m.ply"
    path.write_bytes(_ply(fmt, points, faces, vprops, before, after, count_type))
    raw = read_ply(path)
    np.testing.assert_array_equal(raw.points, points)
    assert [row for b in raw.cells for row in b.data.tolist()] == faces
    for name, (_, values) in vprops.items():
        np.testing.assert_array_equal(raw.point_data[name], values)
    for name, (_, values) in {**before, **after}.items():
        np.testing.assert_array_equal(np.concatenate(raw.cell_data[name]), values)


@pytest.mark.parametrize("cut", [0.5, 0.9])
def test_truncated_binary_files_are_refused(tmp_path, cut):
    data = _ply("binary_little_endian", np.eye(3), [[0, 1, 2]] * 4, {}, {}, {"red": ("uchar", [1, 2, 3, 4])})
    path = tmp_path / "t.ply"
    path.write_bytes(data[: int(len(data) * cut)])
    with pytest.raises(FileFormatError, match="t.ply"):
        read_mesh(path, dim=3)


@pytest.mark.parametrize("text, message", [
    (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "no end_header"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n1\n", "unknown property type 'quad'"),
    (b"ply\nformat weird 1.0\nend_header\n", "unknown format 'weird'"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
     b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n4 0 0 0\n", "record 0"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
     b"end_header\n0 0 zz\n", "not a number"),
    (b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
     b"element face 0\nproperty list uchar int vertex_indices\nend_header\n", "no triangles"),
])
def test_bad_files_name_the_problem(tmp_path, text, message):
    path = tmp_path / "b.ply"
    path.write_bytes(text)
    with pytest.raises(FileFormatError, match=message):
        read_mesh(path, dim=3)


def test_other_elements_and_list_properties_are_listed_not_dropped(tmp_path):
    text = (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            b"element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n"
            b"element material 1\nproperty uchar red\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 6 0 0 1 0 0 1\n7\n")
    path = tmp_path / "o.ply"
    path.write_bytes(text)
    m = read_mesh(path)
    assert m.triangles.tolist() == [[0, 1, 2]]
    assert set(m.info["not_carried"]) >= {"face list property 'texcoord'", "element 'material' (1 records)"}


@pytest.mark.parametrize("binary", [True, False])
def test_vtk_files_with_face_colours(tmp_path, binary):
    pv = pytest.importorskip("pyvista")
    plane = pv.Plane(i_resolution=4, j_resolution=3).triangulate()
    rgb = (np.arange(plane.n_cells * 3).reshape(-1, 3) * 7 % 255).astype(np.uint8)
    plane.cell_data["RGB"] = rgb
    path = tmp_path / "c.ply"
    plane.save(path, texture="RGB", binary=binary)  # meshio 5: TypeError on the binary one
    m = read_mesh(path)
    cols = np.column_stack([m.triangle_attributes[:, m.attribute_names.index(c)] for c in ("red", "green", "blue")])
    np.testing.assert_array_equal(cols, rgb)
    np.testing.assert_array_equal(m.triangles, plane.faces.reshape(-1, 4)[:, 1:])


def test_an_empty_file_read_as_planar_says_no_triangles(tmp_path):
    # (it said "mesh is not planar (z varies from 0 to 0)")
    path = tmp_path / "e.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                     b"property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n")
    with pytest.raises(FileFormatError, match="no triangles"):
        read_mesh(path)
