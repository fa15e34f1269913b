"""hammesh.io.meshio_format: round trips keep points, cycle order and cell data."""

from __future__ import annotations

import os

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from hammesh.errors import FileFormatError
from hammesh.io import meshio_format, read_mesh
from hammesh.io.cell_data import cycle_ids
from hammesh.mesh import Mesh

SUFFIXES = meshio_format.SUFFIXES
CELL_DATA = sorted(meshio_format.CELL_DATA_SUFFIXES)
# (.ply holds cell data too, by hammesh's own writer: tests/io/test_text_writers.py)
NO_CELL_DATA = sorted(set(SUFFIXES) - meshio_format.CELL_DATA_SUFFIXES - {".ply"})


def raw_read(path):
    """What another program sees: meshio's own reader (Gmsh for .msh; meshio has no .vtp
    reader: hammesh's, checked against VTK's in tests/io/test_vtp.py)."""
    if str(path).endswith(".vtp"):
        from hammesh.io.vtk_xml import read_vtk_xml as read_vtp

        return read_vtp(path)
    fmt = "gmsh" if str(path).endswith(".msh") else None
    return meshio.read(path, file_format=fmt)


def test_suffix_sets():
    assert set(SUFFIXES) == {".vtu", ".vtk", ".msh", ".xdmf", ".obj", ".ply", ".stl", ".off", ".vtp"}
    assert set(CELL_DATA) == {".vtu", ".vtk", ".msh", ".xdmf", ".vtp"}


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_round_trip_keeps_points_and_cycle_order(tmp_path, hmesh, suffix, assert_cycle_order):
    path = tmp_path / f"m{suffix}"
    meshio_format.write(hmesh, path)
    back = meshio_format.read(path)
    assert back.points.shape == hmesh.points.shape and back.points.dtype == np.float64
    np.testing.assert_allclose(back.points, hmesh.points, rtol=0, atol=1e-12)
    assert back.triangles.dtype == np.int64
    np.testing.assert_array_equal(back.triangles, hmesh.triangles)
    assert_cycle_order(back.triangles, hmesh.components)
    assert os.listdir(tmp_path) == [path.name]  # one file, no temp left, no .h5 sidecar


@pytest.mark.parametrize("suffix", CELL_DATA)
def test_cell_data_round_trips(tmp_path, hmesh, suffix):
    path = tmp_path / f"m{suffix}"
    meshio_format.write(hmesh, path)
    raw = raw_read(path)
    types = [b.type for b in raw.cells]
    tri = [i for i, t in enumerate(types) if t == "triangle"]
    assert tri == list(range(len(tri))) and set(types[len(tri):]) <= {"line"}  # triangles first
    data = {k: np.concatenate([np.asarray(v[i]) for i in tri]) for k, v in raw.cell_data.items()}
    expected = {
        "cycle_position": hmesh.position,
        "cycle_id": cycle_ids(hmesh.components),
        "parent": hmesh.parent,
        "kind": hmesh.kind,
    }
    for name, want in expected.items():
        got = data[name]
        assert got.shape == (hmesh.n_triangles,)
        np.testing.assert_array_equal(got.astype(np.int64), want, err_msg=name)
        if suffix != ".msh":  # Gmsh stores every field as float64
            assert np.issubdtype(got.dtype, np.integer), name
    for i in range(hmesh.triangle_attributes.shape[1]):
        np.testing.assert_array_equal(data[f"attribute_{i}"], hmesh.triangle_attributes[:, i])
    back = meshio_format.read(path)
    np.testing.assert_array_equal(back.triangle_attributes, hmesh.triangle_attributes)


def test_cycle_id_follows_component_runs(tmp_path, two_cycles):
    meshio_format.write(two_cycles, tmp_path / "m.vtu")
    ids = raw_read(tmp_path / "m.vtu").cell_data["cycle_id"][0]
    assert ids.tolist() == [0] * 6 + [1] * 4


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # meshio's STL binary-size probe
@pytest.mark.parametrize("suffix", NO_CELL_DATA)
def test_formats_without_cell_data_get_geometry_only(tmp_path, hexagon, suffix):
    meshio_format.write(hexagon, tmp_path / f"m{suffix}")
    raw = raw_read(tmp_path / f"m{suffix}")
    assert not {"cycle_position", "cycle_id", "parent", "kind"} & set(raw.cell_data)


def test_plain_mesh_has_no_cycle_fields(tmp_path, plain):
    meshio_format.write(plain, tmp_path / "m.vtu")
    names = set(raw_read(tmp_path / "m.vtu").cell_data)
    assert {n for n in names if not n.startswith("skfem:")} == {"attribute_0", "segment_edges", "edge_marker"}


def test_msh_is_gmsh_not_ansys(tmp_path, hexagon):
    meshio_format.write(hexagon, tmp_path / "m.msh")
    assert (tmp_path / "m.msh").read_bytes().startswith(b"$MeshFormat\n4.1 1")


def test_stl_is_a_soup_but_keeps_triangle_coordinates_in_order(tmp_path):
    points = np.array([[0.0, 0.0], [5.0, 5.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    triangles = np.array([[0, 2, 4], [0, 4, 3]])  # point 1 unused, first use order 0 2 4 3
    meshio_format.write(Mesh(points, triangles), tmp_path / "m.stl")
    back = meshio_format.read(tmp_path / "m.stl")
    assert back.n_points == 4
    np.testing.assert_array_equal(back.points[back.triangles], points[triangles])


def test_reader_drops_zero_z_and_rejects_varying_z(tmp_path):
    tri = [("triangle", np.array([[0, 1, 2]]))]
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    meshio.write(tmp_path / "flat.vtu", meshio.Mesh(flat, tri))
    assert meshio_format.read(tmp_path / "flat.vtu").points.shape == (3, 2)
    bent = flat.copy()
    bent[2, 2] = 0.5
    meshio.write(tmp_path / "bent.vtu", meshio.Mesh(bent, tri))
    with pytest.raises(FileFormatError, match=r"bent\.vtu.*not planar \(z varies"):
        meshio_format.read(tmp_path / "bent.vtu")


def test_reader_concatenates_blocks_splits_quads_keeps_lines_ignores_vertices(tmp_path):
    """Issue 12 defect 2: a quad is split in place (never dropped) and reported."""
    points = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]])
    cells = [
        ("triangle", np.array([[0, 1, 2]])),
        ("quad", np.array([[0, 1, 2, 3]])),
        ("line", np.array([[0, 1], [1, 4]])),
        ("vertex", np.array([[4]])),
        ("triangle", np.array([[0, 2, 3], [1, 4, 2]])),
    ]
    attribute = [np.array([1.0]), np.array([9.0]), np.zeros(2), np.zeros(1), np.array([2.0, 3.0])]
    meshio.write(tmp_path / "mixed.vtu", meshio.Mesh(points, cells, cell_data={"attribute_0": attribute}))
    back = meshio_format.read(tmp_path / "mixed.vtu")
    assert back.triangles.tolist() == [[0, 1, 2], [0, 1, 2], [0, 2, 3], [0, 2, 3], [1, 4, 2]]
    assert back.segments.tolist() == [[0, 1], [1, 4]]
    assert back.triangle_attributes[:, 0].tolist() == [1.0, 9.0, 9.0, 2.0, 3.0]
    assert back.info["repairs"] == ["triangulated 1 quad (2 triangles)"]
    with pytest.raises(FileFormatError, match="strict"):
        meshio_format.read(tmp_path / "mixed.vtu", strict=True)


def test_no_triangles_is_an_error(tmp_path):
    meshio.write(tmp_path / "lines.vtu", meshio.Mesh(np.zeros((2, 3)), [("line", np.array([[0, 1]]))]))
    with pytest.raises(FileFormatError, match=r"lines\.vtu: no triangles"):
        meshio_format.read(tmp_path / "lines.vtu")


def _garbage(kind: str, good: bytes) -> bytes:
    rng = np.random.default_rng(7)
    return {
        "empty": b"",
        "random": rng.bytes(4000),
        "text": b"this is not a mesh\n" * 5,
        "truncated": good[: len(good) // 2],
        "header_only": good[:60],
        "nul": b"\0" * 500,
    }[kind]


# A text format cut at a line end (.obj, ascii .stl) is a valid smaller mesh: not garbage.
GARBAGE = [
    (suffix, kind)
    for suffix in SUFFIXES
    for kind in ["empty", "random", "text", "truncated", "header_only", "nul"]
    if not (kind == "truncated" and suffix in (".obj", ".stl"))
]


@pytest.mark.parametrize(("suffix", "kind"), GARBAGE)
def test_garbage_raises_file_format_error_naming_the_file(tmp_path, hexagon, capfd, suffix, kind):
    good = tmp_path / f"good{suffix}"
    meshio_format.write(hexagon, good)
    bad = tmp_path / f"bad-{kind}{suffix}"
    bad.write_bytes(_garbage(kind, good.read_bytes()))
    capfd.readouterr()
    with pytest.raises(FileFormatError) as info:
        meshio_format.read(bad)
    assert capfd.readouterr() == ("", ""), "the reader printed something"
    message = str(info.value)
    assert str(bad) in message and "\n" not in message
    assert info.value.__cause__ is None
    assert info.value.__context__ is None or info.value.__suppress_context__


@pytest.mark.parametrize("cut", [1, 100, 200, 400, 800, -200, -50, -10])
def test_truncated_vtu(tmp_path, two_cycles, cut):
    good = tmp_path / "good.vtu"
    meshio_format.write(two_cycles, good)
    data = good.read_bytes()
    bad = tmp_path / "cut.vtu"
    bad.write_bytes(data[:cut])
    with pytest.raises(FileFormatError, match="cut.vtu"):
        meshio_format.read(bad)


def test_missing_file_and_unknown_suffix(tmp_path, hexagon):
    with pytest.raises(FileFormatError, match="nothing.vtu: no such file"):
        meshio_format.read(tmp_path / "nothing.vtu")
    with pytest.raises(FileFormatError, match="supported"):
        meshio_format.write(hexagon, tmp_path / "m.xyz")


def test_index_out_of_range_in_file(tmp_path):
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    meshio.write(tmp_path / "bad.vtu", meshio.Mesh(points, [("triangle", np.array([[0, 1, 7]]))]))
    with pytest.raises(FileFormatError, match=r"bad\.vtu.*index 7 out of range"):
        meshio_format.read(tmp_path / "bad.vtu")


def test_ply_face_count_checked(tmp_path, two_cycles):
    meshio_format.write(two_cycles, tmp_path / "m.ply")
    data = (tmp_path / "m.ply").read_bytes()
    (tmp_path / "cut.ply").write_bytes(data[: len(data) - 13 * 3])  # three binary faces short
    with pytest.raises(FileFormatError, match="cut.ply"):
        meshio_format.read(tmp_path / "cut.ply")


@st.composite
def delaunay_meshes(draw):
    n = draw(st.integers(3, 40))
    seed = draw(st.integers(0, 2**32 - 1))
    scale = draw(st.sampled_from([1e-6, 1.0, 1e3, 1e8]))
    rng = np.random.default_rng(seed)
    points = (rng.random((n, 2)) - 0.5) * scale + rng.normal(size=2) * scale
    triangles = Delaunay(points).simplices.astype(np.int64)
    # counter-clockwise, as hammesh stores them
    a, b, c = (points[triangles[:, i]] for i in range(3))
    cw = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    triangles[cw] = triangles[cw][:, [0, 2, 1]]
    triangles = triangles[rng.permutation(len(triangles))]
    attributes = rng.normal(size=(len(triangles), draw(st.integers(0, 2))))
    return Mesh(points, triangles, triangle_attributes=attributes)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mesh=delaunay_meshes())
def test_vtu_round_trip_property(tmp_path, mesh):
    path = tmp_path / "h.vtu"
    meshio_format.write(mesh, path)
    back = meshio_format.read(path)
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_array_equal(back.triangle_attributes, mesh.triangle_attributes)


# --- constrained edges: line cells after the triangles, with their markers ---------------


def undirected(segments, markers):
    seg = np.sort(np.asarray(segments, dtype=np.int64), axis=1)
    return sorted(zip(seg[:, 0].tolist(), seg[:, 1].tolist(), np.asarray(markers).tolist()))


@pytest.mark.parametrize("suffix", CELL_DATA)
def test_segments_and_markers_round_trip(tmp_path, hexagon, suffix):
    path = tmp_path / f"m{suffix}"
    meshio_format.write(hexagon, path)
    back = meshio_format.read(path)
    assert back.segments.dtype == np.int64 and back.segment_markers.dtype == np.int64
    # grouped by marker (.msh: one Gmsh entity per marker) or by triangle (edge fields)
    assert undirected(back.segments, back.segment_markers) == undirected(
        hexagon.segments, hexagon.segment_markers
    )
    np.testing.assert_array_equal(back.points, hexagon.points)
    np.testing.assert_array_equal(back.triangles, hexagon.triangles)
    np.testing.assert_array_equal(back.triangle_attributes, hexagon.triangle_attributes)


@pytest.mark.parametrize("suffix", [".vtu", ".vtk", ".xdmf"])
def test_vtk_family_keeps_segment_directions(tmp_path, hexagon, suffix):
    path = tmp_path / f"m{suffix}"
    meshio_format.write(hexagon, path)
    back = meshio_format.read(path)
    assert sorted(map(tuple, back.segments.tolist())) == sorted(map(tuple, hexagon.segments.tolist()))


@pytest.mark.parametrize("suffix", CELL_DATA)
def test_triangle_blocks_first_and_in_cycle_order(tmp_path, hexagon, suffix):
    meshio_format.write(hexagon, tmp_path / f"m{suffix}")
    raw = raw_read(tmp_path / f"m{suffix}")
    types = [b.type for b in raw.cells]
    k = types.count("triangle")
    assert types == ["triangle"] * k + ["line"] * (len(types) - k)
    if suffix != ".msh":  # the VTK family and XDMF: triangles only (pyvista gets a triangle grid)
        assert types == ["triangle"]
    triangles = np.concatenate([b.data for b in raw.cells[:k]])
    # the Gmsh file keeps the point numbering too
    np.testing.assert_array_equal(raw.points[:, :2], hexagon.points)
    np.testing.assert_array_equal(triangles, hexagon.triangles)


def test_msh_line_cells_get_fillers_and_triangles_no_marker(tmp_path, hexagon):
    meshio_format.write(hexagon, tmp_path / "m.msh")
    raw = raw_read(tmp_path / "m.msh")
    for name, per_block in raw.cell_data.items():
        if name.startswith("gmsh:"):
            continue
        for block, values in zip(raw.cells, per_block):
            values = np.asarray(values)
            assert len(values) == len(block.data), name
            if block.type == "triangle" and name == "segment_marker":
                assert (values == -1).all()
            elif block.type == "line" and name.startswith("attribute_"):
                assert np.isnan(values).all(), name
            elif block.type == "line" and name != "segment_marker":
                assert (values == -1).all(), name


def test_vtu_edge_fields_hold_the_markers_as_int64(tmp_path, hexagon):
    meshio_format.write(hexagon, tmp_path / "m.vtu")
    raw = raw_read(tmp_path / "m.vtu")
    flags, markers = raw.cell_data["segment_edges"][0], raw.cell_data["edge_marker"][0]
    assert flags.dtype == np.int64 and markers.dtype == np.int64 and markers.shape == (6, 3)
    assert (flags < 8).all()  # the hexagon's boundary runs counter-clockwise: no "backwards" bit
    t, k = np.nonzero((flags[:, None] >> np.arange(3)) & 1)
    tri = hexagon.triangles
    stored = {(int(tri[a, b]), int(tri[a, (b + 1) % 3])): int(markers[a, b]) for a, b in zip(t, k)}
    assert stored == {tuple(s): int(mk) for s, mk in zip(hexagon.segments.tolist(), hexagon.segment_markers)}
    assert (markers[(flags[:, None] >> np.arange(3)) & 1 == 0] == 0).all()


@pytest.mark.parametrize("suffix", [".vtu", ".vtk", ".xdmf"])
def test_segments_that_are_not_edges_fall_back_to_line_cells(tmp_path, hexagon, suffix):
    """An invalid mesh stays writable (``hammesh check`` reports it): as line cells."""
    bad = Mesh(hexagon.points, hexagon.triangles, segments=np.vstack([hexagon.segments, [[1, 4]]]),
               segment_markers=np.append(hexagon.segment_markers, 9))
    meshio_format.write(bad, tmp_path / f"m{suffix}")
    raw = raw_read(tmp_path / f"m{suffix}")
    assert [b.type for b in raw.cells] == ["triangle", "line"]
    np.testing.assert_array_equal(raw.cells[1].data, bad.segments)
    assert raw.cell_data["segment_marker"][1].tolist() == bad.segment_markers.tolist()
    back = meshio_format.read(tmp_path / f"m{suffix}")
    np.testing.assert_array_equal(back.segments, bad.segments)
    np.testing.assert_array_equal(back.segment_markers, bad.segment_markers)


@pytest.mark.parametrize("suffix", CELL_DATA)
def test_files_without_segments_hold_triangles_only(tmp_path, two_cycles, suffix):
    assert len(two_cycles.segments) == 0
    new = tmp_path / f"new{suffix}"
    meshio_format.write(two_cycles, new)
    raw = raw_read(new)
    assert {b.type for b in raw.cells} == {"triangle"}  # .msh: a block per run of region
    assert not {"segment_marker", "segment_edges", "edge_marker"} & set(raw.cell_data)
    assert "vertex_marker" not in raw.point_data  # all zero: not written
    back = meshio_format.read(new)
    assert back.segments.shape == (0, 2) and back.segment_markers.shape == (0,)
    np.testing.assert_array_equal(back.triangles, two_cycles.triangles)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # meshio's STL binary-size probe
@pytest.mark.parametrize("suffix", NO_CELL_DATA)
def test_formats_without_cell_data_stay_triangles_only(tmp_path, hexagon, suffix):
    meshio_format.write(hexagon, tmp_path / f"m{suffix}")
    raw = raw_read(tmp_path / f"m{suffix}")
    assert {b.type for b in raw.cells} == {"triangle"}
    assert len(meshio_format.read(tmp_path / f"m{suffix}").segments) == 0


def _regions_mesh():
    """Square fan, 8 triangles in cycle order, regions 3 3 7 7 7 3 3 3; boundary markers."""
    points, triangles = fan((0.0, 0.0), 8)
    boundary = np.column_stack([np.arange(1, 9), np.arange(1, 9) % 8 + 1])
    return Mesh(
        points, triangles, segments=boundary,
        segment_markers=np.array([4, 4, 2, 2, 2, 4, 0, -3]),
        triangle_attributes=np.array([[3.0], [3], [7], [7], [7], [3], [3], [3]]),
    )


def fan(center, k, radius=1.0):
    angles = 2 * np.pi * np.arange(k) / k
    points = np.vstack([center, np.column_stack([np.cos(angles), np.sin(angles)]) * radius])
    i = np.arange(1, k + 1)
    return points, np.column_stack([np.zeros(k, np.int64), i, i % k + 1])


def test_gmsh_physical_tags(tmp_path):
    mesh = _regions_mesh()
    meshio_format.write(mesh, tmp_path / "m.msh")
    raw = raw_read(tmp_path / "m.msh")
    types = [b.type for b in raw.cells]
    assert types == ["triangle"] * 3 + ["line"] * 4  # runs 3 3 | 7 7 7 | 3 3 3; markers -3 0 2 4
    physical = [np.unique(p).tolist() for p in raw.cell_data["gmsh:physical"]]
    assert physical == [[3], [7], [3], [-3], [0], [2], [4]]
    geometrical = [np.unique(g).tolist() for g in raw.cell_data["gmsh:geometrical"]]
    assert geometrical == [[1], [2], [3], [1], [2], [3], [4]]
    for phys, marker in zip(raw.cell_data["gmsh:physical"][3:],
                            raw.cell_data["segment_marker"][3:]):
        assert (phys == marker).all()
    assert raw.point_data["gmsh:dim_tags"].shape == (mesh.n_points, 2)
    back = meshio_format.read(tmp_path / "m.msh")
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_array_equal(back.triangle_attributes, mesh.triangle_attributes)
    assert undirected(back.segments, back.segment_markers) == undirected(mesh.segments, mesh.segment_markers)


def test_gmsh_triangles_without_integral_attribute_get_ranks_and_names(tmp_path, hexagon):
    attrs = np.array([[0.5], [0.5], [0.25], [0.25], [0.5], [0.5]])
    mesh = Mesh(hexagon.points, hexagon.triangles, hexagon.segments, np.ones(6, np.int64), attrs)
    meshio_format.write(mesh, tmp_path / "m.msh")  # 3 runs + 1 marker: 4 entities, 7 points
    raw = raw_read(tmp_path / "m.msh")
    assert [b.type for b in raw.cells].count("triangle") == 3  # runs 0.5 | 0.25 | 0.5
    physical = np.concatenate(raw.cell_data["gmsh:physical"][:3]).tolist()
    assert physical == [2, 2, 1, 1, 2, 2]  # rank + 1
    assert raw.field_data["region_0.25"].tolist() == [1, 2] and raw.field_data["region_0.5"].tolist() == [2, 2]
    back = meshio_format.read(tmp_path / "m.msh")
    np.testing.assert_array_equal(back.triangle_attributes, attrs)  # exact, from attribute_0


def test_gmsh_without_attributes_has_one_unnamed_triangle_group(tmp_path, hexagon):
    mesh = Mesh(hexagon.points, hexagon.triangles, hexagon.segments, hexagon.segment_markers)
    meshio_format.write(mesh, tmp_path / "m.msh")
    raw = raw_read(tmp_path / "m.msh")
    assert [b.type for b in raw.cells].count("triangle") == 1
    assert raw.cell_data["gmsh:physical"][0].tolist() == [1] * 6
    assert not [k for k in raw.field_data if k.startswith("region_")]


def test_gmsh_falls_back_to_merged_entities_when_nodes_are_too_few(tmp_path):
    # 4 points, 6 segments with 6 markers: 7 entities cannot each own a node
    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.3, 0.3]])
    triangles = np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3]])
    segments = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
    mesh = Mesh(points, triangles, segments=segments, segment_markers=np.arange(1, 7))
    meshio_format.write(mesh, tmp_path / "m.msh")
    raw = raw_read(tmp_path / "m.msh")
    assert [b.type for b in raw.cells] == ["triangle", "line"]
    back = meshio_format.read(tmp_path / "m.msh")
    np.testing.assert_array_equal(back.points, points)
    np.testing.assert_array_equal(back.triangles, triangles)
    np.testing.assert_array_equal(back.segments, segments)
    np.testing.assert_array_equal(back.segment_markers, np.arange(1, 7))  # exact, from segment_marker


def test_foreign_gmsh_file_markers_from_physical_tags(tmp_path):
    points = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    cells = [("triangle", np.array([[0, 1, 2], [0, 2, 3]])), ("line", np.array([[0, 1], [1, 2]]))]
    out = meshio.Mesh(
        points, cells,
        point_data={"gmsh:dim_tags": np.array([[1, 1], [2, 1], [2, 1], [2, 1]])},
        cell_data={"gmsh:physical": [np.array([1, 1]), np.array([8, 8])],
                   "gmsh:geometrical": [np.array([1, 1]), np.array([1, 1])]},
    )
    meshio.write(tmp_path / "f.msh", out, file_format="gmsh", binary=False)
    back = meshio_format.read(tmp_path / "f.msh")
    assert back.segment_markers.tolist() == [8, 8]
    assert undirected(back.segments, back.segment_markers) == [(0, 1, 8), (1, 2, 8)]


@pytest.mark.parametrize("geometrical, kept", [([7, 7, 9, 9], False), ([7, 8, 9, 9], True)])
def test_foreign_gmsh_elementary_tags_kept_only_when_they_say_more(tmp_path, geometrical, kept):
    # one elementary entity per physical group (Gmsh's usual file) repeats the physical
    # tags under other numbers: no column of its own; entities that split a group do
    points = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    out = meshio.Mesh(points, [("triangle", triangles)],
                      cell_data={"gmsh:physical": [np.array([1, 1, 2, 2])],
                                 "gmsh:geometrical": [np.array(geometrical)]})
    meshio.write(tmp_path / "f.msh", out, file_format="gmsh22", binary=False)
    back = meshio_format.read(tmp_path / "f.msh")
    names = list(back.attribute_names)
    assert "physical" in names
    assert ("geometrical" in names) == kept
    np.testing.assert_array_equal(back.triangle_attributes[:, names.index("physical")], [1, 1, 2, 2])


def test_reader_without_marker_data_gives_zero_markers(tmp_path):
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    cells = [("triangle", np.array([[0, 1, 2]])), ("line", np.array([[0, 1]]))]
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(points, cells))
    assert meshio_format.read(tmp_path / "m.vtu").segment_markers.tolist() == [0]


@st.composite
def meshes_with_segments(draw):
    mesh = draw(delaunay_meshes())
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    t = mesh.triangles
    edges = np.unique(np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
    chosen = edges[rng.random(len(edges)) < draw(st.floats(0.05, 1.0))]
    if len(chosen) == 0:
        chosen = edges[:1]
    chosen = chosen[rng.permutation(len(chosen))]
    markers = rng.integers(-2, draw(st.integers(1, 12)), size=len(chosen))
    attributes = mesh.triangle_attributes
    if attributes.shape[1] and draw(st.booleans()):  # integral region ids: split into runs
        attributes = np.column_stack([rng.integers(1, 4, len(t)), attributes[:, 1:]]).astype(float)
    return Mesh(mesh.points, t, segments=chosen, segment_markers=markers, triangle_attributes=attributes)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mesh=meshes_with_segments(), suffix=st.sampled_from(CELL_DATA))
def test_segments_round_trip_property(tmp_path, mesh, suffix):
    path = tmp_path / f"h{suffix}"
    meshio_format.write(mesh, path)
    back = meshio_format.read(path)
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_array_equal(back.triangle_attributes, mesh.triangle_attributes)
    assert undirected(back.segments, back.segment_markers) == undirected(mesh.segments, mesh.segment_markers)


def test_zero_area_triangles_are_dropped_with_their_data(tmp_path):
    # VTK keeps a zero-area triangle (collinear corners); no Hamiltonian mesh can: it is
    # dropped (the domain is unchanged), its cell data with it, and the repair reported
    pts = np.array([[0, 0], [1, 0], [2, 0], [0, 1], [1, 1]], float)
    tri = np.array([[0, 1, 3], [1, 2, 0], [1, 4, 3]])  # row 1: on the x axis
    path = tmp_path / "flat.vtu"
    meshio.Mesh(pts, [("triangle", tri)], cell_data={"mat": [np.array([5.0, 6.0, 7.0])]}).write(path)
    m = read_mesh(path)
    assert m.triangles.tolist() == [[0, 1, 3], [1, 4, 3]]
    assert m.triangle_attributes[:, m.attribute_names.index("mat")].tolist() == [5.0, 7.0]
    assert any("zero-area" in r for r in m.info["repairs"])
    with pytest.raises(FileFormatError, match="strict.*zero-area"):
        read_mesh(path, strict=True)
    meshio.Mesh(pts, [("triangle", tri[1:2])]).write(path)
    with pytest.raises(FileFormatError, match="every triangle has zero area"):
        read_mesh(path)
