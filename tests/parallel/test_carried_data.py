"""What the parallel path carries or says it does not (vertex attributes), and the
names a ``.pvtu`` gives triangle attributes and point data (issue 15)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.cli import main
from hammesh.io import pvtu, unwritten_data

# a square with one attribute per vertex (Triangle's .poly: "n 2 k b")
POLY = """4 2 1 0
1 0 0 10
2 1 0 20
3 1 1 30
4 0 1 40
4 0
1 1 2
2 2 3
3 3 4
4 4 1
0
"""


@pytest.fixture
def poly(tmp_path):
    p = tmp_path / "sq.poly"
    p.write_text(POLY)
    return p


def test_domain_reads_the_vertex_attributes(poly):
    dom = hammesh.read_domain(poly)
    assert np.shape(dom.vertex_attributes) == (4, 1)


@pytest.mark.parametrize("extra", [["--tiles", "2", "-o", "one.vtu"], ["--tiles", "2", "--partitioned", "-o", "dir"]])
def test_parallel_path_notes_the_vertex_attributes_it_does_not_carry(poly, tmp_path, capsys, extra):
    extra = [str(tmp_path / x) if x in ("one.vtu", "dir") else x for x in extra]
    rep = tmp_path / "r.json"
    assert main(["mesh", str(poly), "-q", "30", "-a", "2e-3", *extra, "--report", str(rep)]) == 0
    out = capsys.readouterr().out
    notes = [line for line in out.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1 and "vertex attributes (1 per vertex)" in notes[0]
    assert notes[0][len("note: "):] in json.loads(rep.read_text())["not_carried"]


def test_no_note_without_vertex_attributes(tmp_path, capsys):
    p = tmp_path / "plain.poly"
    p.write_text(POLY.replace("4 2 1 0", "4 2 0 0").replace(" 10\n", "\n").replace(" 20\n", "\n")
                 .replace(" 30\n", "\n").replace(" 40\n", "\n"))
    assert main(["mesh", str(p), "-q", "30", "-a", "2e-3", "--tiles", "2", "--partitioned",
                 "-o", str(tmp_path / "d")]) == 0
    assert [line for line in capsys.readouterr().out.splitlines()
            if line.startswith("note:")] == []


def _mesh(rng, names, k, vector_point_data):
    m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30,
                             max_area=0.05 + 0.05 * rng.random(), isolate=False)
    attrs = rng.random((m.n_triangles, k))
    pd = {"temperature": rng.random(m.n_points), "id": rng.integers(0, 9, m.n_points)}
    if vector_point_data:
        pd["velocity"] = rng.random((m.n_points, 2))
    return hammesh.Mesh(points=m.points, triangles=m.triangles, triangle_attributes=attrs, attribute_names=names,
                        point_data=pd)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**31), named=st.booleans(), vector=st.booleans())
def test_pvtu_names_attributes_and_point_data_as_the_vtu_writer(tmp_path_factory, seed, named, vector):
    rng = np.random.default_rng(seed)
    names = ("density", "v[0]", "v[1]") if named else ()
    mesh = _mesh(rng, names, 3, vector)
    d = tmp_path_factory.mktemp("pvtu")
    assert unwritten_data(mesh, d / "m.pvtu") == []  # nothing the file cannot hold
    hammesh.write(mesh, d / "m.pvtu")
    hammesh.write(mesh, d / "m.vtu")
    import meshio

    from hammesh.io.cell_data import triangle_cell_data

    piece = meshio.read(pvtu.read_pieces(d / "m.pvtu")[0])  # (another reader)
    whole = meshio.read(d / "m.vtu")
    own = {"global_position", "parent", "kind", "cycle_id", "cycle_position", "part"}
    named = set(triangle_cell_data(mesh))  # the serial writer's names of the attributes
    assert named == {k for k in piece.cell_data if k not in own} and named <= set(whole.cell_data)
    for k in named:
        assert np.allclose(piece.cell_data[k][0], whole.cell_data[k][0])
    order = np.argsort(piece.point_data["global_id"])
    assert set(piece.point_data) == {"global_id", *mesh.point_data} and set(mesh.point_data) <= set(whole.point_data)
    for k in mesh.point_data:
        assert np.allclose(piece.point_data[k][order], whole.point_data[k])
    back = hammesh.read_mesh(d / "m.pvtu")
    assert np.array_equal(back.triangles, mesh.triangles)
    assert np.array_equal(back.triangle_attributes, mesh.triangle_attributes)
    assert tuple(back.attribute_names) == names
    assert set(back.point_data) == set(mesh.point_data)
    for k, v in mesh.point_data.items():
        assert np.array_equal(back.point_data[k], v)


def test_pvtu_escapes_names(tmp_path):
    mesh = _mesh(np.random.default_rng(1), ('a "q" <b> & c',), 1, False)
    hammesh.write(mesh, tmp_path / "m.pvtu")
    back = hammesh.read_mesh(tmp_path / "m.pvtu")
    assert tuple(back.attribute_names) == ('a "q" <b> & c',)


def _marker_rule_holds(h, domain, serial_inputs):
    """The serial path's rule, checked without the code under test: input vertices keep
    the markers the serial run gives them; a point on a constrained edge has that
    edge's (nonzero) marker; any other point 0."""
    n = len(domain.vertices)
    vm = np.asarray(h.vertex_markers)
    assert vm.shape == (len(h.points),)
    assert np.array_equal(vm[:n], serial_inputs)
    on_edge = {}
    for (a, b), mk in zip(np.asarray(h.segments).tolist(), np.asarray(h.segment_markers).tolist()):
        for v in (a, b):
            if mk:
                on_edge.setdefault(v, set()).add(mk)
    for i in range(n, len(vm)):
        if i in on_edge:
            assert vm[i] in on_edge[i], (i, vm[i], on_edge[i])
        else:
            assert vm[i] == 0, (i, vm[i])


@pytest.fixture
def marked(tmp_path):
    p = tmp_path / "marked.poly"  # (no attributes; boundary markers on, vertex 2's marker 5, side 3's 7)
    p.write_text(POLY.replace("4 2 1 0", "4 2 0 1").replace("1 0 0 10", "1 0 0 0").replace("2 1 0 20", "2 1 0 5")
                 .replace("3 1 1 30", "3 1 1 0").replace("4 0 1 40", "4 0 1 0").replace("4 0\n", "4 1\n")
                 .replace("1 1 2\n", "1 1 2 1\n").replace("2 2 3\n", "2 2 3 1\n").replace("3 3 4\n", "3 3 4 7\n")
                 .replace("4 4 1\n", "4 4 1 0\n"))
    return p


def test_parallel_path_carries_the_vertex_markers(marked, tmp_path, capsys):
    dom = hammesh.read_domain(marked)
    assert dom.vertex_markers.tolist() == [0, 5, 0, 0]
    assert dom.segment_markers.tolist() == [1, 1, 7, 0]
    serial = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=2e-3))
    # Triangle's: a zero-marked vertex takes its first nonzero segment's marker
    assert serial.vertex_markers[:4].tolist() == [1, 5, 1, 7]
    h = hammesh.parallel.parallel_hamiltonian(dom, min_angle=30, max_area=2e-3, tiles=3)
    _marker_rule_holds(h, dom, serial.vertex_markers[:4])
    assert set(np.unique(h.vertex_markers)) == set(np.unique(serial.vertex_markers)) == {0, 1, 5, 7}
    # the command: no note, the markers in the file
    out = tmp_path / "m.vtu"
    assert main(["mesh", str(marked), "-q", "30", "-a", "2e-3", "--tiles", "2", "-o", str(out)]) == 0
    assert not [line for line in capsys.readouterr().out.splitlines()
                if line.startswith("note: ")]
    back = hammesh.read_mesh(out)
    assert back.vertex_markers[:4].tolist() == [1, 5, 1, 7]
    assert set(np.unique(back.vertex_markers)) == {0, 1, 5, 7}


def test_partitioned_pieces_carry_the_vertex_markers(marked, tmp_path, capsys):
    dom = hammesh.read_domain(marked)
    serial = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=2e-3))
    d = tmp_path / "d"
    assert main(["mesh", str(marked), "-q", "30", "-a", "2e-3", "--tiles", "3", "--partitioned", "-o", str(d)]) == 0
    assert not [line for line in capsys.readouterr().out.splitlines()
                if line.startswith("note: ")]
    assert 'Name="vertex_marker"' in (d / "mesh.pvtu").read_text()
    back = hammesh.read_mesh(d / "mesh.pvtu")  # (stitched: a point shared by pieces is one point)
    assert "vertex_marker" not in back.point_data
    one = hammesh.parallel.parallel_hamiltonian(dom, min_angle=30, max_area=2e-3, tiles=3)
    # the same points as the one-file path, the same markers (each piece wrote its own)
    assert np.array_equal(back.points[back.triangles], one.points[one.triangles])
    used = np.unique(back.triangles)
    assert np.array_equal(back.vertex_markers[used], one.vertex_markers[used])
    _marker_rule_holds(one, dom, serial.vertex_markers[:4])
    # every piece agrees on the points it shares with another
    seen = {}
    for piece in sorted(d.glob("piece_*.vtu")):
        m = hammesh.read_mesh(piece)
        gid = m.point_data["global_id"].astype(np.int64)
        for g, v in zip(gid.tolist(), m.vertex_markers.tolist()):
            assert seen.setdefault(g, v) == v


def test_markers_rule_of_triangle():
    from hammesh.parallel.markers import given_at, input_vertex_markers, point_markers

    # vertex 0: first nonzero segment (in input order) ending there; 1 keeps its own
    got = input_vertex_markers(np.array([0, 3, 0, 0]), np.array([[2, 0], [0, 1], [1, 2]]), np.array([0, 9, 7]))
    assert got.tolist() == [9, 3, 7, 0]
    # points 0..3; edges (0, 3) marker 2, (1, 3) marker 6 (the larger wins at 3); point 2 given 5
    pm = point_markers(4, np.array([[0, 3], [1, 3]]), np.array([2, 6]), (np.array([2]), np.array([5])))
    assert pm.tolist() == [2, 6, 5, 6]
    # global ids to a piece's indices: a sorted head (the tile's vertices), then join points
    where, values = given_at(np.array([3, 7, 9, 100, 101, 7000]), 3, (np.array([7, 8, 7000]), np.array([1, 2, 3])))
    assert sorted(zip(where.tolist(), values.tolist())) == [(1, 1), (5, 3)]
