"""Sparse cycles as vertex colourings (``benchmarks/partition_colourings.py``, issue 14,
session 21): the cover and the colouring are two views of one thing, the repairs keep
every mixed triangle mixed and cover more, the rotations merge exactly the cycles they
count, the grown trees are induced trees, and sparse mode certifies what it makes from
the compact cover."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hammesh
from hammesh.halfedge import half_edges
from hammesh.postprocess import comb_cover as comb
from hammesh.postprocess.cycle_cover import cycle_cover, cycle_ids_by_halves

_bench = Path(__file__).parents[2] / "benchmarks"
sys.path.insert(0, str(_bench))  # (partition_colourings imports nothing of its siblings; bench_partition does)
_spec = importlib.util.spec_from_file_location("partition_colourings", _bench / "partition_colourings.py")
pc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(pc)
_spec2 = importlib.util.spec_from_file_location("partition_ceilings", _bench / "partition_ceilings.py")
ceil = importlib.util.module_from_spec(_spec2)
_spec2.loader.exec_module(ceil)


def _mesh(w: float = 2.0, hole: bool = True, area: float = 0.004):
    a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    holes = [np.c_[np.cos(a), np.sin(a)] * 0.25 + [w / 2, 0.5]] if hole else []
    dom = hammesh.Domain.from_polygon([[0, 0], [w, 0], [w, 1], [0, 1]], holes=holes)
    return hammesh.quality_mesh(dom, min_angle=30, max_area=area)


def _arrays(mesh):
    tri = np.ascontiguousarray(mesh.triangles, dtype=np.int64)
    return mesh.points, tri, half_edges(tri, mesh.n_points).twin


def _is_induced_tree(inside: np.ndarray, tri: np.ndarray) -> bool:
    """Connected, and one edge fewer than vertices (so no cycle), by a plain count."""
    e = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
    e = e[inside[e[:, 0]] & inside[e[:, 1]]]
    v = np.flatnonzero(inside)
    if len(e) != len(v) - 1:
        return False
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(inside)
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, comp = connected_components(g, directed=False)
    return len(np.unique(comp[v])) == 1


def _n_cycles(tri, twin, colour) -> int:
    return int(cycle_ids_by_halves(twin, pc.cover_of(tri, twin, colour))[1])


@settings(max_examples=8, deadline=None)
@given(w=st.floats(1.0, 3.0), hole=st.booleans())
def test_a_cover_and_its_colouring_are_one_thing(w: float, hole: bool) -> None:
    pts, tri, twin = _arrays(_mesh(w, hole, 0.01))
    cov = cycle_cover(tri, twin)
    bnd = pc.boundary_vertices(tri, twin, len(pts))
    colour, conflicts = pc.colour_of_cover(tri, twin, cov.is_cov, bnd)
    if conflicts == 0:  # (a cycle round the hole does not separate: no colouring then)
        assert (pc.cover_of(tri, twin, colour) == cov.is_cov).all()
        s = colour[tri].sum(axis=1)
        assert ((s == 0) | (s == 3)).sum() == cov.n_uncovered
    # and back: any colouring's cover gives it again (up to a swap)
    c = np.random.default_rng(int(w * 100)).integers(0, 2, len(pts)).astype(np.int8)
    c[bnd] = 0  # (the cover never crosses the boundary: its edges must be one colour)
    back, conflicts = pc.colour_of_cover(tri, twin, pc.cover_of(tri, twin, c))
    assert conflicts == 0
    assert (back == c).all() or (back == 1 - c).all()


def test_the_deferring_tree_is_an_induced_tree_that_covers_more() -> None:
    pts, tri, twin = _arrays(_mesh())
    bnd = pc.boundary_vertices(tri, twin, len(pts))
    plain, none = pc.deferring_tree(pts, tri, twin, max_defer=0)
    assert none == 0
    assert (plain == ceil.vertex_tree_cover(pts, tri, twin).inside).all()
    inside, deferrals = pc.deferring_tree(pts, tri, twin)
    assert deferrals > 0
    for t in (plain, inside):
        assert _is_induced_tree(t, tri) and not t[bnd].any()
    assert (inside[tri].sum(axis=1) == 0).sum() < (plain[tri].sum(axis=1) == 0).sum()
    assert _n_cycles(tri, twin, inside.astype(np.int8)) == 1


@pytest.mark.parametrize("lmax", [2, 16])
def test_small_loop_adds_cover_more_and_unmix_nothing(lmax: int) -> None:
    pts, tri, twin = _arrays(_mesh())
    c = pc.deferring_tree(pts, tri, twin)[0].astype(np.int8)
    before = c[tri].sum(axis=1)
    adds, leaves, made = pc.small_loop_adds(tri, twin, c, lmax)
    after = c[tri].sum(axis=1)
    assert adds > 0 and (after == 3).sum() == 0
    assert ((before == 1) | (before == 2) <= (after == 1) | (after == 2)).all()  # mixed stays mixed
    assert (after == 0).sum() <= (before == 0).sum() - adds
    assert not c[pc.boundary_vertices(tri, twin, len(pts))].any()
    # a leaf extends the tree; an island or a short loop adds one small cycle
    assert leaves <= adds
    assert _n_cycles(tri, twin, c) <= 1 + made


def test_rotations_merge_exactly_what_they_count() -> None:
    pts, tri, twin = _arrays(_mesh())
    c = pc.deferring_tree(pts, tri, twin)[0].astype(np.int8)
    pc.small_loop_adds(tri, twin, c, 16)
    mixed = np.isin(c[tri].sum(axis=1), (1, 2))
    n0 = _n_cycles(tri, twin, c)
    for rotate in (lambda x: pc.capped_rotations(tri, twin, x, 200), lambda x: pc.scale_rotations(pts, tri, twin, x, 6),
                   lambda x: pc.scale_rotations(pts, tri, twin, x, 0)):
        x = c.copy()
        merged = rotate(x)
        assert merged > 0
        assert (np.isin(x[tri].sum(axis=1), (1, 2)) == mixed).all()  # the same triangles covered
        assert _n_cycles(tri, twin, x) == n0 - merged


def test_the_seeded_cover_covers_what_the_matching_covers() -> None:
    pts, tri, twin = _arrays(_mesh())
    tree = pc.deferring_tree(pts, tri, twin, max_defer=0)[0].astype(np.int8)
    cov = pc.seeded_cover(pts, tri, twin, tree)
    assert cov.n_uncovered < 0.01 * len(tri) < (tree[tri].sum(axis=1) == 0).sum()
    assert cov.n_cycles > 1


@pytest.mark.parametrize("tree, fill", [("quadtree", "grow"), ("fishbone", "grow"), ("fishbone", "comb")])
def test_sparse_mode_certifies_the_compact_cover(monkeypatch, tree: str, fill: str) -> None:
    from hammesh.partition import partition
    from hammesh.postprocess import sparse as sp

    mesh = _mesh(area=0.002)
    monkeypatch.setattr(sp, "cycle_cover", pc.compact_cover)
    monkeypatch.setattr(pc, "TREE", tree)
    monkeypatch.setattr(pc, "FISH_FILL", fill)
    monkeypatch.setattr(pc, "LMAX", 4)
    h = hammesh.hamiltonian(mesh, mode="sparse")  # (verified inside: a VerificationError fails the test)
    assert pc.LAST["cycles"] >= 1
    assert h.n_triangles >= mesh.n_triangles
    p = partition(h, 8)
    assert p.connected and p.sizes.max() - p.sizes.min() <= 1


@pytest.mark.parametrize("straight", [True, False])
def test_the_vertex_fishbone_tree_is_an_induced_tree(monkeypatch, straight: bool) -> None:
    monkeypatch.setattr(comb, "STRAIGHT_SPINES", straight)
    pts, tri, twin = _arrays(_mesh(area=0.002))
    bnd = pc.boundary_vertices(tri, twin, len(pts))
    for axis in (0, 1):
        plain = pc.vertex_fishbone_tree(pts, tri, twin, axis, levels=2)
        deferring = pc.vertex_fishbone_tree(pc.turned(pts, 30.0), tri, twin, axis, penalty=5.0, max_defer=8, levels=2)
        for inside in (plain, deferring):
            assert _is_induced_tree(inside, tri) and not inside[bnd].any()
        unc = [(t[tri].sum(axis=1) == 0).sum() for t in (plain, deferring)]
        assert unc[1] < unc[0]


def _lattice(nx: int = 60, ny: int = 52, jitter: float = 0.0):
    """A triangular lattice's Delaunay triangles (CCW, the flat ones at its ragged
    sides dropped), its points moved by up to ``jitter`` edges."""
    from scipy.spatial import Delaunay

    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    pts = np.c_[(i + 0.5 * (j % 2)).ravel(), (j * np.sqrt(3) / 2).ravel()].astype(float)
    pts += np.random.default_rng(1).uniform(-jitter, jitter, pts.shape)
    tri = Delaunay(pts).simplices.astype(np.int64)
    p = pts[tri]
    u, v = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    tri[area < 0] = tri[area < 0][:, ::-1]
    tri = np.ascontiguousarray(tri[np.abs(area) > 0.3])
    return pts, tri, half_edges(tri, len(pts)).twin


@pytest.mark.parametrize("jitter", [0.0, 0.15])
def test_the_comb_fill_is_an_induced_tree_that_covers_more(jitter: float) -> None:
    # the deepest cells as combs (teeth across the parent's spine, outside rows between
    # them): still one induced tree (one cycle), and on a lattice-like mesh fewer
    # monochrome triangles than the breadth-first fill (rows that alternate leave none);
    # cells of a few hundred vertices at least (at 1 500 triangles, cells of ~40
    # vertices, the comb loses one frame in four)
    for pts, tri, twin in (_lattice(jitter=jitter), _arrays(_mesh(area=0.0005))):
        bnd = pc.boundary_vertices(tri, twin, len(pts))
        for axis in (0, 1):
            for angle in (0.0, 30.0):
                unc = []
                for fill in ("grow", "comb"):
                    inside = pc.vertex_fishbone_tree(pc.turned(pts, angle), tri, twin, axis, penalty=5.0, max_defer=8,
                                                     levels=2, fill=fill)
                    assert _is_induced_tree(inside, tri) and not inside[bnd].any()
                    assert _n_cycles(tri, twin, inside.astype(np.int8)) == 1
                    unc.append((inside[tri].sum(axis=1) == 0).sum())
                assert unc[1] < unc[0], (axis, angle, unc)


def test_the_comb_keys_sweep_away_from_the_spine() -> None:
    # a key grows with the whole steps from the spine line; along the spine it adds < 1
    rng = np.random.default_rng(5)
    pts = rng.uniform(0, 1, (200, 2))
    src, dst = rng.integers(0, 200, 400), rng.integers(0, 200, 400)
    deep = rng.random(400) < 0.7
    keys = comb.comb_keys(pts, src, dst, np.full(400, 7.0), deep, np.zeros(400, np.int64), np.array([0.5]), 0, 20.0,
                          0.5, 4.0)
    assert (keys[~deep] == 7.0).all()
    v = dst[deep]
    step = 0.5 * np.median(np.linalg.norm(pts[v] - pts[src[deep]], axis=1))
    assert np.array_equal(np.floor(keys[deep] - 20.0), np.floor(np.abs(pts[v, 1] - 0.5) / step))


def test_an_unknown_fill_is_an_option_error() -> None:
    pts, tri, twin = _arrays(_mesh(hole=False, area=0.02))
    with pytest.raises(hammesh.errors.InvalidOptionError):
        pc.vertex_fishbone_tree(pts, tri, twin, fill="zigzag")


def test_straight_spines_are_shortest_paths_through_their_band() -> None:
    # a band: the vertices of a strip of a grid mesh; its spine must be a path from
    # the band's first vertex along the line to its last, and induced (shortest)
    pts, tri, twin = _arrays(_mesh(hole=False, area=0.002))
    n = len(pts)
    ptr, idx, _, _ = pc.vertex_maps(tri, n)
    cand = np.abs(pts[:, 1] - 0.5) < 0.06
    lab = np.zeros(n, np.int64)
    o = np.flatnonzero(cand)
    o = o[np.argsort(pts[o, 0], kind="stable")].astype(np.int64)
    spine = comb.spine_paths(ptr, idx, cand, lab, o)
    sv = np.flatnonzero(spine)
    assert o[0] in sv and spine[cand].sum() < cand.sum()
    e = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
    e = e[spine[e[:, 0]] & spine[e[:, 1]]]
    deg = np.bincount(e.ravel(), minlength=n)[sv]
    assert len(e) == len(sv) - 1 and deg.max() <= 2  # a path (one piece: the band is connected)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 3), st.floats(-10, 10), st.floats(0.1, 5.0)), min_size=1, max_size=60))
def test_weighted_cell_medians_halve_the_weight(rows) -> None:
    cell = np.array([r[0] for r in rows])
    value = np.array([r[1] for r in rows])
    weight = np.array([r[2] for r in rows])
    med = comb.cell_medians(cell, value, 4, weight)
    for c in range(4):
        own = cell == c
        if not own.any():
            assert np.isnan(med[c])
            continue
        total = weight[own].sum()
        assert weight[own & (value < med[c])].sum() < 0.5 * total + 1e-9
        assert weight[own & (value <= med[c])].sum() >= 0.5 * total - 1e-9


def test_order_jumps_count_the_splices() -> None:
    pts, tri, twin = _arrays(_mesh(hole=False, area=0.002))
    m = len(tri)
    order = np.random.default_rng(3).permutation(m)  # any cycle order of the rows
    assert pc.order_jumps(pts, tri, order, pts, tri[order], big=10) == (0, 1)
    # two arcs swapped: one splice where they meet (and none at the cycle's wrap)
    half = m // 2
    spliced = np.r_[order[half:], order[:half][::-1]]
    jumps, largest = pc.order_jumps(pts, tri, order, pts, tri[spliced], big=10)
    assert jumps == 1 and largest > 10
    # an inserted new triangle (not an input one) is skipped
    assert pc.order_jumps(pts, tri, order, np.r_[pts, [[9.0, 9.0]]],
                          np.r_[tri[order][:5], [[len(pts), 0, 1]], tri[order][5:]], big=10)[0] == 0
