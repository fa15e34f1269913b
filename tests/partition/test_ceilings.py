"""The ceilings of ``benchmarks/partition_ceilings.py`` (issue 14, session 15): each order
is a permutation whose stretches are what it claims, the projection keeps every
triangle in a part, and the vertex tree's cycle is one dual cycle round an induced tree."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hammesh
from hammesh.halfedge import half_edges
from hammesh.partition import dual_edges, edge_cut

_spec = importlib.util.spec_from_file_location(
    "partition_ceilings", Path(__file__).parents[2] / "benchmarks" / "partition_ceilings.py"
)
ceil = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ceil)


def _mesh(w: float = 2.0, hole: bool = True, area: float = 0.004):
    a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    holes = [np.c_[np.cos(a), np.sin(a)] * 0.25 + [w / 2, 0.5]] if hole else []
    dom = hammesh.Domain.from_polygon([[0, 0], [w, 0], [w, 1], [0, 1]], holes=holes)
    return hammesh.quality_mesh(dom, min_angle=30, max_area=area)


def test_walk_positions_are_the_rows_of_each_triangle() -> None:
    mesh = _mesh()
    h = hammesh.hamiltonian(mesh, mode="incircle")
    first, median = ceil.walk_positions(h.parent, mesh.n_triangles)
    assert (h.parent[first] == np.arange(mesh.n_triangles)).all()
    assert (h.parent[median] == np.arange(mesh.n_triangles)).all()
    assert (first <= median).all()
    # the first row of each triangle is the first one with that parent
    seen = np.full(mesh.n_triangles, -1)
    for i, p in enumerate(h.parent):
        if seen[p] < 0:
            seen[p] = i
    assert (seen == first).all()


def test_order_cut_counts_the_edges_between_stretches() -> None:
    mesh = _mesh(hole=False)
    m = mesh.n_triangles
    a, b = dual_edges(mesh.triangles, mesh.n_points)
    order = np.random.default_rng(1).permutation(m)
    cut, bad = ceil.order_cut(order, 4, a, b, shift=False)
    part = np.empty(m, np.int64)
    part[order] = np.searchsorted(np.arange(4) * m // 4, np.arange(m), side="right") - 1  # floor(j m / 4) on
    assert cut == int((part[a] != part[b]).sum()) == edge_cut(part, a, b)
    assert bad > 0  # random stretches are scattered
    assert ceil.order_cut(order, 1, a, b) == (0, 0)


def test_the_best_shift_is_what_partition_finds_on_a_cycle() -> None:
    mesh = _mesh()
    h = hammesh.hamiltonian(mesh, mode="sparse")
    a, b = dual_edges(h.triangles, h.n_points)
    order = np.arange(h.n_triangles)  # the rows are in cycle order
    for k in (3, 8):
        p = hammesh.partition(h, k)
        assert ceil.order_cut(order, k, a, b)[0] == p.edge_cut <= ceil.order_cut(order, k, a, b, shift=False)[0]
        # the best shift's cut, checked by trying every shift on the rows themselves
        m = h.n_triangles
        starts = np.arange(k) * m // k
        cuts = [int((p_[a] != p_[b]).sum()) for p_ in
                (np.searchsorted(starts, (np.arange(m) - s) % m, side="right") - 1 for s in range(m // k))]
        assert min(cuts) == p.edge_cut


def test_kd_order_stretches_are_its_halves() -> None:
    mesh = _mesh(w=2.0, hole=False)
    c = mesh.points[mesh.triangles].mean(axis=1)
    order = ceil.kd_order(c, leaf=8)
    m = len(c)
    assert np.array_equal(np.sort(order), np.arange(m))
    # k = 2 on a 2:1 box: the first half lies left of the second (split across x)
    half = m // 2
    assert c[order[:half], 0].max() <= c[order[half:], 0].min()
    a, b = dual_edges(mesh.triangles, mesh.n_points)
    cut, _ = ceil.order_cut(order, 4, a, b)  # (a centroid split may strand a triangle)
    assert cut < 0.25 * ceil.order_cut(np.random.default_rng(0).permutation(m), 4, a, b)[0]


def test_projected_parts_keep_every_triangle_and_smoothing_never_adds_cut() -> None:
    mesh = _mesh()
    m = mesh.n_triangles
    h = hammesh.hamiltonian(mesh, mode="incircle")
    row_part = hammesh.partition(h, 8).part
    nb = ceil.dual_neighbours(half_edges(mesh.triangles, mesh.n_points).twin)
    raw = ceil.projected_parts(h.parent, row_part, m, 8, nb, passes=0)
    smooth = ceil.projected_parts(h.parent, row_part, m, 8, nb)
    assert raw.shape == smooth.shape == (m,) and set(np.unique(smooth)) <= set(range(8))
    # each triangle's vote: the part of most of its rows
    for t in np.random.default_rng(0).choice(m, 20, replace=False):
        counts = np.bincount(row_part[h.parent == t], minlength=8)
        assert counts[raw[t]] == counts.max()
    a, b = dual_edges(mesh.triangles, mesh.n_points)
    # a move to the part of two of three neighbours trades >= 2 cut edges for <= 1
    assert edge_cut(smooth, a, b) <= edge_cut(raw, a, b)


def _check_vertex_tree(mesh, repair: int = 0) -> None:
    tri = mesh.triangles
    twin = half_edges(tri, mesh.n_points).twin
    vt = ceil.vertex_tree_cover(mesh.points, tri, twin, repair=repair)
    if repair:  # the repair only takes moves that cover more than they uncover
        assert len(vt.uncovered) <= len(ceil.vertex_tree_cover(mesh.points, tri, twin).uncovered)
    inside = vt.inside
    # no boundary vertex inside
    bh = np.flatnonzero(twin < 0)
    assert not inside[tri[bh // 3, bh % 3]].any()
    # the inside vertices induce a tree: connected, edges = vertices - 1, no triangle
    e = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
    e_in = e[inside[e].all(axis=1)]
    n_in = int(inside.sum())
    assert n_in > 0 and len(e_in) == n_in - 1
    import networkx as nx

    g = nx.Graph()
    g.add_nodes_from(np.flatnonzero(inside).tolist())
    g.add_edges_from(e_in.tolist())
    assert nx.is_connected(g)
    s = inside[tri].sum(axis=1)
    assert (s < 3).all()
    # the order is one closed dual cycle through exactly the mixed triangles
    covered = np.flatnonzero((s > 0) & (s < 3))
    assert np.array_equal(np.sort(vt.order), covered)
    assert np.array_equal(vt.uncovered, np.flatnonzero(s == 0))
    nb = ceil.dual_neighbours(twin)
    nxt = np.roll(vt.order, -1)
    assert (nb[vt.order] == nxt[:, None]).any(axis=1).all()


def test_vertex_tree_walks_one_cycle_round_an_induced_tree() -> None:
    _check_vertex_tree(_mesh())


def test_repaired_vertex_tree_is_still_one_cycle_round_an_induced_tree() -> None:
    mesh = _mesh()
    twin = half_edges(mesh.triangles, mesh.n_points).twin
    grown = ceil.vertex_tree_cover(mesh.points, mesh.triangles, twin)
    fixed = ceil.vertex_tree_cover(mesh.points, mesh.triangles, twin, repair=3)
    assert len(fixed.uncovered) < len(grown.uncovered)  # the swaps found something to cover
    _check_vertex_tree(mesh, repair=3)


@settings(max_examples=6, deadline=None)
@given(st.floats(0.8, 3.0), st.booleans(), st.integers(0, 2))
def test_vertex_tree_on_rectangles(w: float, hole: bool, repair: int) -> None:
    _check_vertex_tree(_mesh(w=w, hole=hole, area=0.01), repair)


@pytest.mark.slow
def test_bench_partition_prints_the_ceilings() -> None:
    pytest.importorskip("pymetis")  # a benchmark-only peer
    bench = Path(__file__).parents[2] / "benchmarks" / "bench_partition.py"
    proc = subprocess.run([sys.executable, str(bench), "--ceilings", "--target", "3000", "--domains", "gear"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = [r for r in proc.stdout.splitlines() if r.startswith("| gear |")]
    assert len(rows) == 2  # k = 8 and 64
    for r in rows:
        cells = [c.strip() for c in r.strip("|").split("|")]
        assert len(cells) == 11
        assert all(float(c.split()[0]) > 0 for c in cells[3:6])  # the three cycles' own ratios


# session 16: a ring of compact blocks


@settings(max_examples=20, deadline=None)
@given(st.integers(1, 40), st.integers(1, 40))
def test_gilbert_path_visits_every_cell_once_by_neighbouring_steps(w: int, h: int) -> None:
    p = ceil.gilbert_path(w, h)
    assert p.shape == (w * h, 2)
    assert (p >= 0).all() and (p[:, 0] < w).all() and (p[:, 1] < h).all()
    assert len(np.unique(p, axis=0)) == w * h
    step = np.abs(np.diff(p, axis=0))
    assert (step.max(axis=1) == 1).all()  # side by side, or one diagonal step at most
    diagonal = int((step.sum(axis=1) == 2).sum())
    assert diagonal <= (0 if w % 2 == 0 and h % 2 == 0 else 1)


def test_curve_order_runs_are_compact_and_blocks_follow_it() -> None:
    mesh = _mesh(w=2.0, hole=False)
    m = mesh.n_triangles
    c = mesh.points[mesh.triangles].mean(axis=1)
    order = ceil.curve_order(c, m // 2)
    assert np.array_equal(np.sort(order), np.arange(m))
    a, b = dual_edges(mesh.triangles, mesh.n_points)
    rand = ceil.order_cut(np.random.default_rng(0).permutation(m), 8, a, b)[0]
    assert ceil.order_cut(order, 8, a, b)[0] < 0.2 * rand
    # consecutive triangles along the curve are near each other (grid cells side by side)
    gap = np.linalg.norm(np.diff(c[order], axis=0), axis=1)
    assert np.median(gap) < 3 * np.sqrt(2.0 / m)
    nb = ceil.dual_neighbours(half_edges(mesh.triangles, mesh.n_points).twin)
    raw = ceil.curve_blocks(order, 100, nb, passes=0)
    pos = np.empty(m, np.int64)
    pos[order] = np.arange(m)
    assert np.array_equal(raw, pos // 100)
    block = ceil.curve_blocks(order, 100, nb)
    assert edge_cut(block, a, b) <= edge_cut(raw, a, b)


def test_sweep_blocks_walks_each_block_breadth_first_from_the_previous_one() -> None:
    mesh = _mesh()
    m = mesh.n_triangles
    nb = ceil.dual_neighbours(half_edges(mesh.triangles, mesh.n_points).twin)
    block = ceil.curve_blocks(ceil.curve_order(mesh.points[mesh.triangles].mean(axis=1), m // 2), 150, nb)
    order = ceil.sweep_blocks(block, nb)
    assert np.array_equal(np.sort(order), np.arange(m))
    assert (np.diff(block[order]) >= 0).all()  # block by block, in number order
    for i in range(1, int(block.max()) + 1):
        run = order[block[order] == i]
        if len(run) == 0:
            continue
        touches = (np.where(nb[run] >= 0, block[np.maximum(nb[run], 0)], -9) == i - 1).any(axis=1)
        if touches.any():
            # the seeds (next to the previous block) first, then each one next to an earlier one
            seeds = int(touches.sum())
            assert touches[:seeds].all()
            earlier = set(run[:seeds].tolist())
            for t in run[seeds:]:
                if any(u in earlier for u in nb[t] if u >= 0):
                    earlier.add(t)
            assert len(earlier) >= 0.9 * len(run)  # all but other pieces of the block


def test_block_cycles_and_the_ring_walk_each_block_once_along_its_own_cycle() -> None:
    mesh = _mesh()
    m = mesh.n_triangles
    nb = ceil.dual_neighbours(half_edges(mesh.triangles, mesh.n_points).twin)
    block = ceil.curve_blocks(ceil.curve_order(mesh.points[mesh.triangles].mean(axis=1), m // 2), 200, nb)
    bc = ceil.block_cycles(mesh.points, mesh.triangles, block)
    assert bc.triangles >= m and bc.steiner >= 0 and 0 < bc.min_angle < 60
    for i, o in enumerate(bc.orders):
        assert np.array_equal(np.sort(o), np.flatnonzero(block == i))
    order, spliced = ceil.ring_order(bc.orders, block, nb)
    assert np.array_equal(np.sort(order), np.arange(m))
    assert (np.diff(block[order]) >= 0).all()
    live = [i for i, o in enumerate(bc.orders) if len(o)]
    assert 0 <= spliced <= len(live)
    # a spliced block starts next to the previous block and ends next to the next one,
    # the two ends neighbours along its cycle (so the ring needs no Steiner point there)
    found = 0
    for j, i in enumerate(live):
        run = order[block[order] == i]
        first, last = run[0], run[-1]
        near = (lambda t, other: bool((nb[t] >= 0).any() and (block[nb[t][nb[t] >= 0]] == other).any()))
        if near(first, live[j - 1]) and near(last, live[(j + 1) % len(live)]):
            o = bc.orders[i]
            p = {int(t): n for n, t in enumerate(o)}
            assert (p[int(first)] - p[int(last)]) % len(o) in (1, len(o) - 1)
            found += 1
    assert found >= spliced


def test_cover_cycle_order_walks_one_cover_cycle() -> None:
    from hammesh.postprocess.cycle_cover import cycle_cover

    mesh = _mesh()
    twin = half_edges(mesh.triangles, mesh.n_points).twin
    cover = cycle_cover(mesh.triangles, twin, points=mesh.points)
    nb = ceil.dual_neighbours(twin)
    sizes = np.bincount(cover.cycle[cover.cycle >= 0])
    for which in (int(np.argmax(sizes)), int(np.argmin(sizes))):
        order = ceil.cover_cycle_order(twin, cover.is_cov, cover.cycle, which)
        assert np.array_equal(np.sort(order), np.flatnonzero(cover.cycle == which))
        nxt = np.roll(order, -1)
        assert (nb[order] == nxt[:, None]).any(axis=1).all()  # a closed dual cycle


@pytest.mark.slow
def test_bench_partition_prints_the_blocks() -> None:
    pytest.importorskip("pymetis")
    bench = Path(__file__).parents[2] / "benchmarks" / "bench_partition.py"
    proc = subprocess.run([sys.executable, str(bench), "--blocks", "512", "--target", "3000", "--domains", "gear"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = [r for r in proc.stdout.splitlines() if r.startswith("| gear |")]
    assert len(rows) == 2
    for r in rows:
        cells = [c.strip() for c in r.strip("|").split("|")]
        assert len(cells) == 7
        assert float(cells[3]) > 0 and float(cells[4].split()[0]) > 0
    assert "spliceable" in proc.stdout
