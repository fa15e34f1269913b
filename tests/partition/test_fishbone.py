"""The fishbone hierarchy behind the incircle tree (``_fishbone_kernels``, issue 14 session 12)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.postprocess import _fishbone_kernels as fk
from hammesh.postprocess import _thm24_kernels as K
from tests.partition.test_forest import gear


def _cells(pts, tri, twin, angle: float, depth: int, joined: bool = True):
    """Each triangle's deepest cell and spine level, all centroids the sample."""
    m = len(tri)
    fl = fk.kd_lines(fk.sample_centroids(pts, tri, np.arange(m), angle), depth)
    qr = np.zeros((m, 4), np.int32)
    half = np.empty(m, np.int8)
    ca, sa = math.cos(angle), math.sin(angle)
    fk.descend_into(pts, tri, ca, sa, 0.0, np.zeros(1, bool), fl.lines, fl.fars, depth, K.FISH_SHIFT, qr, half, 0, m)
    if joined:
        fk.join_gaps_into(pts, tri, twin, ca, sa, 0.0, qr, K.FISH_SHIFT, fl.lines, depth, depth,
                          fk.rim_vertices(tri, twin, len(pts)))
    key = qr[:, 2] & ((1 << K.FISH_SHIFT) - 1)
    spine = qr[:, 2] >> K.FISH_SHIFT
    return fl, key, spine, half


def _pieces(twin, member: np.ndarray, label: np.ndarray) -> np.ndarray:
    """Per label value >= 0 among ``member`` triangles: dual-connected pieces (edges
    between members of the same label)."""
    m = len(member)
    h = np.flatnonzero(twin >= 0)
    a, b = h // 3, twin[h] // 3
    keep = member[a] & member[b] & (label[a] == label[b])
    g = coo_matrix((np.ones(int(keep.sum())), (a[keep], b[keep])), shape=(m, m))
    _, comp = connected_components(g, directed=False)
    out = np.zeros(int(label.max()) + 1, np.int64)
    for c in np.unique(label[member]):
        out[c] = len(np.unique(comp[member & (label == c)]))
    return out


@settings(max_examples=25, deadline=None)
@given(n=st.integers(64, 3000), depth=st.integers(1, 3), aspect=st.floats(0.2, 5.0), seed=st.integers(0, 2**31))
def test_kd_lines_split_every_cell_in_equal_quarters(n: int, depth: int, aspect: float, seed: int) -> None:
    """The regions (spine centroids counted on their side) of every level hold equal
    counts: each split halves its cell's count (the upper side ``ceil``), so at level
    ``l`` the counts differ by at most one per level."""
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2)) * [aspect, 1.0]
    fl = fk.kd_lines(xy, depth)
    reg = np.zeros(n, np.int64)
    for level in range(depth + 1):
        counts = np.bincount(reg, minlength=4**level)
        assert counts.max() - counts.min() <= level + 1 if level else counts[0] == n
        if level == depth:
            break
        oc = fk.level_offset(level) + reg
        across, along = (xy[:, 1], xy[:, 0]) if level % 2 == 0 else (xy[:, 0], xy[:, 1])
        s = (across >= fl.lines[oc]).astype(np.int64)
        f = (along >= fl.fars[2 * oc + s]).astype(np.int64)
        for c in range(4**level):  # the line is the count median of the cell
            own = reg == c
            assert int((own & (s == 1)).sum()) == (int(own.sum()) + 1) // 2
        reg = 4 * reg + 2 * s + f


def _plate(holes_at=((1.0, 0.5),), size=(2.0, 1.0), r=0.3, area=0.002):
    a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    circ = np.c_[np.cos(a), np.sin(a)] * r
    w, hgt = size
    dom = hammesh.Domain.from_polygon([[0, 0], [w, 0], [w, hgt], [0, hgt]], holes=[circ + c for c in holes_at])
    return hammesh.quality_mesh(dom, min_angle=30, max_area=area)


def test_descent_puts_triangles_in_their_cells_and_spines() -> None:
    """A triangle's spine level is the first level whose line (of its own cell) its
    turned bounding box straddles, and its cell the sides of its centroid; checked
    against numpy on a turned plate."""
    mesh = _plate()
    clean, he, _ = prepare_mesh(mesh)
    pts, tri, twin = clean.points, clean.triangles, he.twin
    angle, depth = 0.4, 3
    fl, key, spine, half = _cells(pts, tri, twin, angle, depth, joined=False)
    ca, sa = math.cos(angle), math.sin(angle)
    tp = np.c_[ca * pts[:, 0] + sa * pts[:, 1], ca * pts[:, 1] - sa * pts[:, 0]][tri]
    c, lo, hi = tp.mean(axis=1), tp.min(axis=1), tp.max(axis=1)
    reg = np.zeros(len(tri), np.int64)
    want = np.full(len(tri), depth)
    for level in range(depth):
        across = 1 if level % 2 == 0 else 0
        line = fl.lines[fk.level_offset(level) + reg]
        first = (want == depth) & (lo[:, across] <= line) & (line <= hi[:, across])
        want[first] = level
        s = (c[:, across] >= line).astype(np.int64)
        f = (c[:, 1 - across] >= fl.fars[2 * (fk.level_offset(level) + reg) + s]).astype(np.int64)
        reg = 4 * reg + 2 * s + f
    np.testing.assert_array_equal(key, reg)
    np.testing.assert_array_equal(spine, want)
    np.testing.assert_array_equal(half, reg >> (2 * depth - 1))
    assert 0 < half.sum() < len(tri)


def test_spine_is_joined_round_a_hole() -> None:
    """The top line of a 2 x 1 plate (along x at angle 0) crosses its central hole:
    its spine comes in two pieces; joined round the rim it is one, by triangles on
    the hole's rim."""
    mesh = _plate()
    clean, he, _ = prepare_mesh(mesh)
    pts, tri, twin = clean.points, clean.triangles, he.twin
    _, key, plain, _ = _cells(pts, tri, twin, 0.0, 2, joined=False)
    _, key2, joined, _ = _cells(pts, tri, twin, 0.0, 2)
    np.testing.assert_array_equal(key, key2)
    top = np.zeros(len(tri), np.int64)
    assert _pieces(twin, plain == 0, top)[0] == 2
    assert _pieces(twin, joined == 0, top)[0] == 1
    added = (joined == 0) & (plain != 0)
    c = pts[tri].mean(axis=1)
    assert added.any() and (np.hypot(*(c[added] - [1.0, 0.5]).T) < 0.4).all()
    assert ((joined == plain) | added).all()  # nothing else moves


def test_fish_angle_runs_the_top_line_between_the_plates_holes() -> None:
    """On bench_partition's 4 x 2 plate with two holes the top line is across the long
    side, between the holes (session 11: 1.38 x METIS's cut at k = 8, against 1.82
    along it through both holes); a square keeps its axes (either way round)."""
    mesh = _plate(holes_at=((1.0, 1.0), (3.0, 1.0)), size=(4.0, 2.0), r=0.4, area=0.004)
    assert fk.fish_angle(mesh.points, mesh.triangles, prepare_mesh(mesh)[1].twin) == math.pi / 2
    sq = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30,
                              max_area=3e-4)
    assert fk.fish_angle(sq.points, sq.triangles, prepare_mesh(sq)[1].twin) in (0.0, math.pi / 2)


def test_children_are_runs_of_the_cycle() -> None:
    """The point of the fishbone: every child hangs from its parent's spine by one
    edge, so the Thm 2.4 walk visits each cell whole. On a square every cell of the
    top two levels is one run of the cycle (``tree="fishbone"``) (round the cycle's end), its own
    spine included, and the cells' counts differ by at most 2 % of the mesh. The
    forest's classes are the ones listed by ``forest_classes``: its spines joined
    round no hole here, as the cells recomputed here."""
    sq = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30,
                              max_area=2e-4)
    clean, he, is_con = prepare_mesh(sq)
    pts, tri, twin = clean.points, clean.triangles, he.twin
    cl = K.forest_classes(tri, twin, is_con, pts)
    # the cells as the forest saw them (its own sample is every triangle here)
    m = len(tri)
    assert m <= fk.FISH_SAMPLE
    fr = cl.frame
    assert fr.depth >= 3
    _, key, spine, _ = _cells(pts, tri, twin, fr.angle, fr.depth)
    h = hammesh.hamiltonian(sq, mode="incircle", tree="fishbone")
    for level in (1, 2):
        lab = np.where(spine >= level, key >> (2 * (fr.depth - level)), -1)[h.parent]
        for cell in range(4**level):
            rows = lab == cell
            assert rows.any()
            assert np.count_nonzero(rows & ~np.roll(rows, 1)) == 1, (level, cell)
        sizes = np.bincount(lab[lab >= 0])
        assert sizes.max() - sizes.min() <= 0.02 * h.n_triangles


def test_tree_option_picks_the_walk_and_both_are_certified(tmp_path) -> None:
    """``tree`` changes only which spanning tree the incircle walk goes round: both
    cycles are certified, of the same triangles; ``hammesh mesh --parts`` walks the
    fishbone unless told otherwise; a wrong name is refused."""
    import meshio
    import pytest

    from hammesh.cli import main
    from hammesh.io import write
    from hammesh.errors import InvalidOptionError

    plate = _plate(holes_at=((0.6, 0.5), (1.4, 0.5)), r=0.2, area=0.004)
    quad = hammesh.hamiltonian(plate, mode="incircle")
    fish = hammesh.hamiltonian(plate, mode="incircle", tree="fishbone")
    assert quad.report["verified"] and fish.report["verified"]
    assert quad.n_triangles == fish.n_triangles
    assert sorted(quad.parent.tolist()) == sorted(fish.parent.tolist())
    assert not np.array_equal(quad.parent, fish.parent)  # another walk
    for h in (quad, fish):  # one cycle: consecutive rows share an edge, round the end
        a, b = np.sort(h.triangles, axis=1), np.sort(np.roll(h.triangles, -1, axis=0), axis=1)
        shared = (a[:, :, None] == b[:, None, :]).any(axis=2).sum(axis=1)
        assert (shared == 2).all()
    with pytest.raises(InvalidOptionError, match="tree"):
        hammesh.hamiltonian(plate, mode="incircle", tree="kd")
    src = tmp_path / "plate.vtu"
    write(plate, src)
    # sparse mode takes the fishbone as an opt-in (``sparse_cells``): not with --parts alone
    sp_fish = hammesh.hamiltonian(plate, mode="sparse", tree="fishbone")
    sp_quad = hammesh.hamiltonian(plate, mode="sparse")
    for extra, expected in ((["--tree", "fishbone"], sp_fish), ([], sp_quad)):
        out = tmp_path / f"sparse{len(extra)}.vtu"
        assert main(["mesh", str(src), "--parts", "4", "-o", str(out)] + extra) == 0
        np.testing.assert_array_equal(meshio.read(out).cell_data["parent"][0], expected.parent)
    for extra, expected in (([], fish), (["--tree", "quadtree"], quad)):
        out = tmp_path / f"out{len(extra)}.vtu"
        assert main(["mesh", str(src), "--mode", "incircle", "--parts", "4", "-o", str(out)] + extra) == 0
        np.testing.assert_array_equal(meshio.read(out).cell_data["parent"][0], expected.parent)


def _frame(mesh):
    clean, he, is_con = prepare_mesh(mesh)
    m = clean.n_triangles
    return clean, he, is_con, fk.ring_frame(clean.points, clean.triangles, he.twin,
                                           np.arange(0, m, max(1, m // fk.FISH_SAMPLE)))


def test_ring_frame_only_round_a_hole_that_holds_the_domain() -> None:
    """The gear wraps round its hole: the ring frame, centred in the hole, its rim the
    hole's vertices, its sector borders increasing inside the angle range, every
    point's radius its distance from the centre. The plate with two holes (the centroid
    between them), a square, and a 2:1 plate round a central hole (too long a domain:
    its widest ray is 3.5 of its narrowest) keep the plain frame."""
    clean, he, _, rf = _frame(gear(0.002))
    assert rf is not None
    assert np.hypot(*rf.centre) < 0.01 and abs(rf.r_in - 0.3) < 0.01
    hole = np.flatnonzero(rf.hole)
    assert len(hole) >= 48 and np.allclose(np.hypot(*clean.points[hole].T), 0.3)
    assert len(rf.cuts) == fk.SECTORS - 1 and (np.diff(rf.cuts) > 0).all()
    assert 0 < rf.cuts[0] and rf.cuts[-1] < rf.span
    np.testing.assert_allclose(rf.points[:, 0], np.hypot(*(clean.points - rf.centre).T))
    for mesh in (_plate(holes_at=((1.0, 1.0), (3.0, 1.0)), size=(4.0, 2.0), r=0.4, area=0.004),
                 _plate(area=0.001),
                 hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30,
                                      max_area=3e-4)):
        assert _frame(mesh)[3] is None


def test_a_triangle_across_the_seam_is_made_whole() -> None:
    """In the ring frame the angle coordinate jumps by ``span`` at the seam: a
    triangle across it gets its corners unwrapped, its centroid back in range, its
    box as narrow as it is."""
    span = 10.0
    pts = np.array([[1.0, 9.9], [1.2, 0.1], [1.1, 0.05]])
    tri = np.array([[0, 1, 2]])
    cx, cy, x0, x1, y0, y1 = fk.turned_box(pts, tri, 0, 1.0, 0.0, span)
    assert 0 <= cy < span and abs(cy - 0.0167) < 1e-3 and y1 - y0 < 0.3
    assert fk.turned_centroid(pts, tri, 0, 1.0, 0.0, span) == (cx, cy)
    assert fk.turned_box(pts, tri, 0, 1.0, 0.0, 0.0)[5] - fk.turned_box(pts, tri, 0, 1.0, 0.0, 0.0)[4] > 9


def test_gear_sectors_are_runs_and_the_forest_is_minimum(monkeypatch) -> None:
    """The ring frame's tree: the rim is one spine, eight sectors hang from it, each
    visited whole (one run of the cycle, its rows counted without the rim's), of
    nearly equal rows; the cycle is certified; Prim's two searches and the join still
    give a minimum spanning forest of the classes (networkx), the same on one thread
    and on two; and the k = 8 parts are the sectors."""
    import networkx as nx

    import hammesh.threads as row_threads

    mesh = gear(0.0006)
    clean, he, is_con, rf = _frame(mesh)
    assert rf is not None
    pts, tri, twin = clean.points, clean.triangles, he.twin
    m = len(tri)
    qr = np.empty((m, 3), K.index_dtype(m))
    fr = K.fishbone_frame(tri, twin, pts, qr)
    assert fr.span > 0 and fr.depth >= 3
    key = qr[:, 2] & ((1 << K.FISH_SHIFT) - 1)
    spine = qr[:, 2] >> K.FISH_SHIFT
    np.testing.assert_array_equal(spine == 0, rf.hole[tri].any(axis=1))  # the rim
    cell2 = key >> (2 * (fr.depth - 2))
    assert set(np.unique(cell2 & 1)) == {0}  # level 1 has no far halves
    sector = 2 * (cell2 >> 2) + ((cell2 >> 1) & 1)
    h = hammesh.hamiltonian(mesh, mode="incircle", tree="fishbone")
    assert h.report["verified"]
    lab = np.where(spine == 0, -1, sector)[h.parent]
    for s in range(fk.SECTORS):
        rows = lab == s
        assert np.count_nonzero(rows & ~np.roll(rows, 1)) == 1, s
    sizes = np.bincount(lab[lab >= 0])
    assert sizes.max() - sizes.min() <= 0.03 * h.n_triangles
    part = hammesh.partition(h, fk.SECTORS).part
    for p in range(fk.SECTORS):  # each part is mostly one sector
        own = lab[part == p]
        own = own[own >= 0]
        assert np.bincount(own).max() >= 0.9 * len(own)
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 10**9)  # one thread
    one = K.spanning_forest(tri, twin, is_con, pts)
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 20)  # both halves side by side
    two = K.spanning_forest(tri, twin, is_con, pts)
    assert all(np.array_equal(x, y) for x, y in zip(one, two))
    cl = K.forest_classes(tri, twin, is_con, pts)
    g = nx.Graph()
    for e in np.flatnonzero(twin > np.arange(3 * m)):
        assert cl.cls[e] == cl.cls[twin[e]]
        g.add_edge(e // 3, twin[e] // 3, w=int(cl.cls[e]))
    best = sum(d["w"] for _, _, d in nx.minimum_spanning_edges(g, weight="w", data=True))
    tw = (two.code >> 2) - 1
    tree = np.flatnonzero(((two.code & K.TREE_BIT) != 0) & (np.arange(3 * m) < tw))
    assert sum(g.edges[two.order[e // 3], two.order[tw[e] // 3]]["w"] for e in tree) == best


def test_ring_frame_cuts_the_gear_less_than_the_kd_frame() -> None:
    """What the ring frame is for (docs/partition.md): on the gear at k = 8 and 64 the
    cycle cuts fewer edges round the hole than the turned kd fishbone's."""
    from hammesh.partition import partition

    mesh = gear(0.0002)
    ring = hammesh.hamiltonian(mesh, mode="incircle", tree="fishbone")
    old = fk.RING_ASPECT
    try:
        fk.RING_ASPECT = 0.0  # no domain qualifies: the kd frame
        kd = hammesh.hamiltonian(mesh, mode="incircle", tree="fishbone")
    finally:
        fk.RING_ASPECT = old
    for k in (8, 64):
        assert partition(ring, k).edge_cut < partition(kd, k).edge_cut, k
