"""``--partitioned -o DIR``: never into a non-empty DIR without ``--force``, never a stray
or half-written file; ``--parts`` with the parallel path; the raw pieces (issue 15)."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.cli import main
from hammesh.errors import FileFormatError, OutputError
from hammesh.io import pvtu
from hammesh.parallel import partitioned as P
from hammesh.parallel.tile_mesh import locate_in_triangles
from tests.helpers import dual_pieces

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")
ARGS = ["mesh", DEMO, "-q", "30", "-a", "4e-3"]


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    return err


def test_non_empty_directory_is_refused_and_left_as_it_was(tmp_path, capsys):
    out = tmp_path / "parts"
    out.mkdir()
    (out / "piece_0009.vtu").write_text("an earlier run's piece")
    assert main([*ARGS, "--tiles", "2", "--partitioned", "-o", str(out)]) == 2
    assert "not empty" in _one_line_error(capsys)
    assert sorted(p.name for p in out.iterdir()) == ["piece_0009.vtu"]
    assert (out / "piece_0009.vtu").read_text() == "an earlier run's piece"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["parts"]  # no temp directory beside it


def test_force_replaces_the_content_no_stale_piece_survives(tmp_path, capsys):
    out = tmp_path / "parts"
    out.mkdir()
    for name in ("piece_0000.vtu", "piece_0007.vtu", "mesh.pvtu"):
        (out / name).write_text("old")
    assert main([*ARGS, "--tiles", "3", "--partitioned", "--force", "-o", str(out)]) == 0
    capsys.readouterr()
    names = sorted(p.name for p in out.iterdir())
    assert names == ["mesh.pvtu", "piece_0000.vtu", "piece_0001.vtu", "piece_0002.vtu"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["parts"]
    assert main(["check", str(out / "mesh.pvtu")]) == 0


@pytest.mark.parametrize("other", ["notes.txt", "sub/data.bin", "piece_0001.vtu.bak"])
def test_force_never_removes_what_is_not_an_earlier_output(tmp_path, capsys, other: str):
    """tester18 r10: --force replaced a whole directory tree, the user's files included."""
    out = tmp_path / "results"
    (out / other).parent.mkdir(parents=True, exist_ok=True)
    (out / other).write_text("the user's")
    (out / "piece_0000.vtu").write_text("old")
    assert main([*ARGS, "--tiles", "2", "--partitioned", "--force", "-o", str(out)]) == 2
    assert "not an earlier partitioned output" in _one_line_error(capsys)
    assert (out / other).read_text() == "the user's" and (out / "piece_0000.vtu").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]


def test_force_refuses_the_current_directory_before_any_work(tmp_path, capsys, monkeypatch):
    (tmp_path / "piece_0000.vtu").write_text("old")
    monkeypatch.chdir(tmp_path)
    assert main([*ARGS, "--tiles", "2", "--partitioned", "--force", "-o", "."]) == 2
    assert "current directory" in _one_line_error(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["piece_0000.vtu"]


def test_an_empty_directory_is_used_without_force(tmp_path, capsys):
    out = tmp_path / "empty"
    out.mkdir()
    assert main([*ARGS, "--tiles", "2", "--partitioned", "-o", str(out)]) == 0
    assert (out / "mesh.pvtu").is_file()
    assert "note:" not in capsys.readouterr().out  # (the constrained edges are in the pieces: tester18 r08)


def test_directory_holding_the_input_is_refused_even_with_force(tmp_path, capsys):
    src = tmp_path / "demo.poly"
    src.write_bytes(Path(DEMO).read_bytes())
    assert main(["mesh", str(src), "-q", "30", "-a", "4e-3", "--tiles", "2", "--partitioned", "--force",
                 "-o", str(tmp_path)]) == 2
    assert "input" in _one_line_error(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo.poly"]


def test_a_failing_run_leaves_nothing_behind(tmp_path, monkeypatch):
    calls = []
    real = P._finish_and_write

    def failing(outcome, args, path, components, parts, *more):
        calls.append(path)
        if len(calls) == 2:  # the first piece is written, the second fails
            raise OSError("disk full")
        return real(outcome, args, path, components, parts, *more)

    monkeypatch.setattr(P, "_finish_and_write", failing)
    out = tmp_path / "a" / "b" / "parts"
    with pytest.raises(OSError, match="disk full"):
        P.write_partitioned(hammesh.read_domain(DEMO), out, min_angle=30, max_area=4e-3, tiles=3)
    assert len(calls) == 2 and Path(calls[0]).parent.name.endswith(".partial")
    assert list(tmp_path.iterdir()) == []  # neither the pieces, the temp dir nor the parents it made


def test_parts_with_partitioned_are_connected_balanced_stretches(tmp_path, capsys, monkeypatch):
    from hammesh.parallel import partitioned as P

    monkeypatch.setattr(P, "SPILL_SHARE", 0.0)  # (no tile fits: every Hamiltonian mesh goes to a file)
    out = tmp_path / "parts"
    rep = tmp_path / "r.json"
    assert main([*ARGS, "--tiles", "3", "--partitioned", "--parts", "5", "-o", str(out), "--report", str(rep)]) == 0
    assert "5 parts" in capsys.readouterr().out
    part, pos = [], []
    for piece in pvtu.read_pieces(out / "mesh.pvtu"):
        m = meshio.read(piece)
        part.append(m.cell_data["part"][0])
        pos.append(m.cell_data["global_position"][0])
    part = np.concatenate(part)[np.argsort(np.concatenate(pos))]
    sizes = np.bincount(part, minlength=5)
    assert len(sizes) == 5 and sizes.max() - sizes.min() <= 1
    assert (np.diff(part) >= 0).all()  # one stretch of the (one) cycle each
    mesh = hammesh.read_mesh(out / "mesh.pvtu")  # rows in cycle order
    for k in range(5):
        assert dual_pieces(mesh.triangles[part == k]) == 1
    import json

    rep = json.loads(rep.read_text())
    assert rep["partition"]["k"] == 5
    assert rep["parallel"]["spilled"]  # 3 tiles on one worker: the Hamiltonian meshes went to files, now gone


def test_parts_with_tiles_in_one_file(tmp_path, capsys):
    out = tmp_path / "w.vtu"
    assert main([*ARGS, "--tiles", "2", "--parts", "3", "-o", str(out)]) == 0
    capsys.readouterr()
    part = meshio.read(out).cell_data["part"][0]
    assert sorted(np.unique(part).tolist()) == [0, 1, 2]
    assert main(["check", str(out)]) == 0


@pytest.mark.parametrize("argv, what", [
    (["--tiles", "2", "--partitioned", "--renumber", "rcm"], "--renumber"),
    (["--tiles", "2", "--force"], "--force"),
    (["--tiles", "2", "--parts", "0"], "parts"),
])
def test_parallel_options_that_cannot_work_exit_2(tmp_path, capsys, argv, what):
    assert main([*ARGS, *argv, "-o", str(tmp_path / "o")]) == 2
    assert what in _one_line_error(capsys)
    assert list(tmp_path.iterdir()) == []


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(1, 40), min_size=1, max_size=5), st.integers(1, 60))
def test_stretch_parts_balance_and_contiguity(lengths, k):
    comps = np.array(lengths, np.int64)
    k = min(k, int(comps.sum()))
    part = P.stretch_parts(np.arange(comps.sum()), comps, k)
    assert part.min() >= 0 and part.max() < k
    starts = np.concatenate([[0], np.cumsum(comps)[:-1]])
    if k >= len(comps):
        assert len(np.unique(part)) == k  # every part used
        per = P.parts_per_cycle(comps, k)
        for s, n, kr in zip(starts, comps, per):
            mine = part[s:s + n]
            assert (np.diff(mine) >= 0).all() and len(np.unique(mine)) == kr  # stretches of this cycle only
            sizes = np.bincount(mine - mine.min())
            assert sizes.max() - sizes.min() <= 1
    else:  # whole cycles
        for s, n in zip(starts, comps):
            assert len(np.unique(part[s:s + n])) == 1


def test_raw_piece_round_trip_and_truncation(tmp_path):
    rng = np.random.default_rng(3)
    ids = rng.permutation(500)[:200]
    pts = rng.random((200, 2))
    tri = ids[rng.integers(0, 200, (300, 3))]
    path = tmp_path / "p.vtu"
    pvtu.write_piece(path, ids, pts, tri, np.arange(300), np.zeros(300), np.arange(300), np.full(300, -1),
                     np.full(300, 3), rng.random((300, 1)))
    m = meshio.read(path)  # another reader agrees
    gid = m.point_data["global_id"]
    assert np.array_equal(gid[m.cells[0].data], tri)
    assert np.allclose(m.points[np.argsort(gid), :2], pts[np.argsort(ids)])
    g, xy, t, gp, attr = pvtu._read_piece(path)[:5]
    assert np.array_equal(g[t], tri) and np.array_equal(gp, np.arange(300))
    assert np.allclose(attr[:, 0], m.cell_data["attribute_0"][0])
    assert not list(tmp_path.glob("*.part"))
    path.write_bytes(path.read_bytes()[:-2000] + b"\n</AppendedData>\n</VTKFile>\n")
    with pytest.raises(FileFormatError):
        pvtu._read_piece(path)


def test_check_target_names_a_file(tmp_path):
    f = tmp_path / "x"
    f.write_text("")
    with pytest.raises(OutputError, match="this is a file"):
        P.check_target(f)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_locate_in_triangles_finds_the_holder(seed):
    rng = np.random.default_rng(seed)
    p = rng.random((30, 2))
    from scipy.spatial import Delaunay

    t = Delaunay(p).simplices
    tri_idx = rng.integers(0, len(t), 10)
    w = rng.dirichlet([1, 1, 1], 10)
    q = (p[t[tri_idx]] * w[:, :, None]).sum(1)
    where = locate_in_triangles(p, t, q)
    a, b, c = (p[t[where, i]] for i in range(3))
    # the found triangle holds the point (barycentric coordinates >= 0 up to rounding)
    d = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    l1 = ((b[:, 0] - q[:, 0]) * (c[:, 1] - q[:, 1]) - (b[:, 1] - q[:, 1]) * (c[:, 0] - q[:, 0])) / d
    l2 = ((c[:, 0] - q[:, 0]) * (a[:, 1] - q[:, 1]) - (c[:, 1] - q[:, 1]) * (a[:, 0] - q[:, 0])) / d
    assert (np.minimum(np.minimum(l1, l2), 1 - l1 - l2) >= -1e-9).all()
    assert (locate_in_triangles(p, t, np.array([[5.0, 5.0]])) == -1).all()


@pytest.mark.parametrize("estimate, workers, tiles", [
    (1e5, 2, 2), (1.9e6, 2, 2), (2e6, 2, 4), (3e6, 2, 4), (4.7e6, 2, 4), (4.8e6, 2, 6), (5.5e6, 2, 6),
    (5.6e6, 2, 8), (6.1e6, 2, 8), (7.5e6, 2, 8), (6.1e6, 1, 2), (1e8, 2, 34), (3e6, 8, 8), (8e6, 8, 16),
    (2e7, 8, 24), (2.3e7, 8, 32),
])
def test_default_tiles_are_a_multiple_of_the_workers(estimate, workers, tiles):
    from hammesh.parallel.run import TRIANGLES_PER_TILE, default_tiles

    got = default_tiles(estimate, workers)
    assert got == tiles and got % workers == 0
    assert estimate / got <= 1.2 * TRIANGLES_PER_TILE or got == workers


def test_spill_only_when_the_held_tiles_exceed_the_workers_memory(monkeypatch):
    from hammesh.parallel import partitioned as P

    class Cluster:  # (a running cluster's scheduler_info: 4 GB per worker)
        def scheduler_info(self):
            return {"workers": {a: {"memory_limit": 4e9} for a in "ab"}}

    c = Cluster()
    assert not P.spill_wanted(c, 2, 2, 1e9)  # one tile per worker: nothing waits
    assert not P.spill_wanted(c, 2, 4, 6e6)  # 2 x 1.5M x 400 B = 1.2 GB <= 2 GB
    assert P.spill_wanted(c, 2, 64, 1e8)  # 32 x 1.56M x 400 B = 20 GB
    monkeypatch.setattr(P, "SPILL_SHARE", 0.1)
    assert P.spill_wanted(c, 2, 4, 6e6)  # 1.2 GB > 0.4 GB


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.integers(0, 40))
def test_label_pieces_matches_scipy_components(seed, n_cut):
    """The flood fill of the regional attributes against scipy's components of the
    dual graph with the segment edges removed."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from hammesh.parallel._kernels import label_pieces_into

    rng = np.random.default_rng(seed)
    m_ = hammesh.quality_mesh(hammesh.Domain(vertices=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
                                             segments=np.array([[0, 1], [1, 2], [2, 3], [3, 0]])),
                              max_area=0.01 + 0.02 * rng.random(), isolate=False)
    tri, n = m_.triangles, len(m_.points)
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    cut = np.unique(edges, axis=0)[rng.permutation(len(np.unique(edges, axis=0)))[:n_cut]]
    keys = np.unique(cut @ np.array([n, 1]))
    on = np.zeros(n, bool)
    on[cut.ravel()] = True
    # neighbours across edge (s, s + 1), as mesh_tile stores them
    key_of = {}
    for t in range(len(tri)):
        for s in range(3):
            a, b = sorted((tri[t, s], tri[t, (s + 1) % 3]))
            key_of.setdefault((a, b), []).append((t, s))
    nbr = np.full((len(tri), 3), -1, np.int64)
    r, c = [], []
    for (a, b), sides in key_of.items():
        if len(sides) == 2:
            (t, s), (u, q) = sides
            nbr[t, s], nbr[u, q] = u, t
            if a * n + b not in set(keys.tolist()):
                r.append(t)
                c.append(u)
    label = np.empty(len(tri), np.int64)
    seeds = np.empty(len(tri), np.int64)
    count = label_pieces_into(tri.astype(np.int64), nbr, keys.astype(np.int64), on, label, seeds)
    # each piece's seed is its lowest triangle, in label order
    assert np.array_equal(seeds[:count], [np.flatnonzero(label == i)[0] for i in range(count)])
    k, ref = connected_components(coo_matrix((np.ones(len(r)), (r, c)), shape=(len(tri), len(tri))), directed=False)
    assert count == k
    # the same partition of the triangles (labels may differ by a renaming)
    pairs = np.unique(np.stack([label, ref], 1), axis=0)
    assert len(pairs) == k


def _index_cell_names(index: Path) -> list[str]:
    import xml.etree.ElementTree as ET

    grid = ET.parse(index).getroot().find("PUnstructuredGrid")
    return sorted(a.get("Name") for a in grid.find("PCellData"))


@pytest.mark.parametrize("pieces_domain, parts", [(False, None), (False, 3), (True, None)])
def test_index_lists_exactly_the_pieces_cell_data(tmp_path, capsys, pieces_domain, parts):
    """One cycle: no ``cycle_id``/``cycle_position`` (all zeros and ``global_position``
    again); several cycles: both, right; ``part`` listed in the index when written
    (ParaView shows only the arrays the index lists)."""
    from tests.parallel.test_tiles import _pieces_domain

    out = tmp_path / "o"
    if pieces_domain:  # (two plates: two cycles)
        P.write_partitioned(_pieces_domain(), out, min_angle=28, max_area=4e-3, tiles=3, parts=parts)
    else:
        argv = [*ARGS, "--tiles", "2", "--partitioned", "-o", str(out)]
        assert main([*argv, *(["--parts", str(parts)] if parts else [])]) == 0
        capsys.readouterr()
    listed = _index_cell_names(out / "mesh.pvtu")
    pos, cid, cpos = [], [], []
    for piece in pvtu.read_pieces(out / "mesh.pvtu"):
        m = meshio.read(piece)
        assert sorted(m.cell_data) == listed
        pos.append(m.cell_data["global_position"][0])
        if pieces_domain:
            cid.append(m.cell_data["cycle_id"][0])
            cpos.append(m.cell_data["cycle_position"][0])
    assert ("cycle_id" in listed) == ("cycle_position" in listed) == pieces_domain
    assert ("part" in listed) == (parts is not None)
    mesh = hammesh.read_mesh(out / "mesh.pvtu")
    assert main(["check", str(out / "mesh.pvtu")]) == 0
    if pieces_domain:  # the columns say which cycle and where in it, from the rows' order
        order = np.argsort(np.concatenate(pos))
        cid, cpos = np.concatenate(cid)[order], np.concatenate(cpos)[order]
        comps = np.bincount(cid)
        assert len(comps) == 2 == dual_pieces(mesh.triangles)
        assert np.array_equal(cpos, np.concatenate([np.arange(n) for n in comps]))
        for k in range(2):
            assert dual_pieces(mesh.triangles[cid == k]) == 1


def test_one_file_index_of_one_cycle_has_no_cycle_columns(tmp_path):
    h = hammesh.hamiltonian(hammesh.quality_mesh(hammesh.read_domain(DEMO), min_angle=30, max_area=4e-3,
                                                 isolate=False), mode="incircle")
    assert len(h.components) == 1
    pvtu.write(h, tmp_path / "one.pvtu")
    m = meshio.read(tmp_path / "one.0.vtu")
    assert "cycle_id" not in m.cell_data and "cycle_position" not in m.cell_data
    assert sorted(m.cell_data) == _index_cell_names(tmp_path / "one.pvtu")
    back = hammesh.read_mesh(tmp_path / "one.pvtu")
    assert np.array_equal(back.triangles, h.triangles)


def _edges(mesh, directed: bool = True) -> list[tuple[int, int, int]]:
    """The constrained edges with their markers, as a sorted list (a multiset)."""
    seg = np.asarray(mesh.segments, np.int64).reshape(-1, 2)
    seg = seg if directed else np.sort(seg, axis=1)
    return sorted(zip(seg[:, 0].tolist(), seg[:, 1].tolist(), np.asarray(mesh.segment_markers).tolist()))


@pytest.mark.parametrize("tiles, mode, pieces_domain", [(3, "sparse", False), (4, "incircle", False),
                                                        (5, "sparse", False), (3, "sparse", True)])
def test_partitioned_pieces_hold_the_constrained_edges(tmp_path, capsys, tiles, mode, pieces_domain):
    """tester18 r08: the pieces lost the constrained edges. Now every piece holds
    ``segment_edges`` / ``edge_marker`` (as the serial ``.vtu``), join rows included,
    and the stitched mesh gives back exactly the one-file run's segments (the union's:
    same edges, directions and markers, each once), which cover the domain's."""
    from tests.parallel.test_tiles import _pieces_domain

    out = tmp_path / "o"
    if pieces_domain:
        dom, args = _pieces_domain(), dict(min_angle=28, max_area=4e-3)
        rep = P.write_partitioned(dom, out, tiles=tiles, mode=mode, **args)
        assert "not_carried" not in rep
    else:
        dom, args = hammesh.read_domain(DEMO), dict(min_angle=30, max_area=4e-3)
        assert main([*ARGS, "--tiles", str(tiles), "--mode", mode, "--partitioned", "-o", str(out)]) == 0
        assert "note:" not in capsys.readouterr().out
    from hammesh.parallel.run import parallel_hamiltonian

    whole = parallel_hamiltonian(dom, tiles=tiles, mode=mode, **args)
    back = hammesh.read_mesh(out / "mesh.pvtu")
    assert np.array_equal(back.triangles, whole.triangles)
    assert len(back.segments) == len(whole.segments) > len(dom.segments)
    assert _edges(back) == _edges(whole)  # (directed, with markers: each edge once)
    # the constrained edges cover the domain's segments: as many pieces on each as its length
    p = back.points
    length = np.hypot(*(p[back.segments[:, 0]] - p[back.segments[:, 1]]).T).sum()
    v = np.asarray(dom.vertices)
    assert length == pytest.approx(np.hypot(*(v[dom.segments[:, 0]] - v[dom.segments[:, 1]]).T).sum(), rel=1e-12)
    listed = _index_cell_names(out / "mesh.pvtu")
    assert "segment_edges" in listed and "edge_marker" in listed
    for piece in pvtu.read_pieces(out / "mesh.pvtu"):  # (meshio reads the narrow types too)
        m = meshio.read(piece)
        assert m.cell_data["edge_marker"][0].shape == (len(m.cells[0].data), 3)
    capsys.readouterr()
    assert main(["check", str(out / "mesh.pvtu")]) == 0

