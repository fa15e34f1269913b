"""The dual cycle cover: disjoint cycles, checked independently with networkx.

``oracle_check`` re-derives every property from the triangles alone, in plain
Python (the dual edges from a dictionary of vertex pairs, not from the half-edge
twins the cover was given), so a wrong twin array or a kernel bug cannot hide
itself: every cover half-edge lies on a real dual edge and is paired with its
opposite, each covered triangle has exactly two, the cover's components are single
cycles (hence disjoint), and ``cycle``/``n_cycles``/``n_uncovered`` say so.
"""

from __future__ import annotations

import threading

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh.postprocess._join_kernels import EDGE_NOT_GOOD, no_edge_rule
from hammesh.postprocess.cycle_cover import cycle_cover
from hammesh.halfedge import half_edges
from tests.helpers import bundled_domain, hull_area


def check_cover(tri: np.ndarray, n: int, online: int | None = None) -> tuple:
    twin = half_edges(tri, n).twin
    c = cycle_cover(tri, twin, online=online)
    cov = c.is_cov
    m = len(tri)
    # symmetric, never on the boundary
    assert not cov[twin < 0].any()
    np.testing.assert_array_equal(cov[twin[cov]], True)
    deg = cov.reshape(m, 3).sum(axis=1)
    assert set(np.unique(deg).tolist()) <= {0, 2}
    assert ((deg == 0) == (c.cycle < 0)).all()
    assert int((deg == 0).sum()) == c.n_uncovered
    g = nx.Graph()
    hs = np.flatnonzero(cov)
    g.add_edges_from(zip((hs // 3).tolist(), (twin[hs] // 3).tolist()))
    comps = list(nx.connected_components(g))
    assert len(comps) == c.n_cycles
    for comp in comps:  # each a cycle with one id
        assert len({int(c.cycle[t]) for t in comp}) == 1
        assert all(d == 2 for _, d in g.degree(comp))
    oracle_check(tri, c)
    return c


def oracle_check(tri: np.ndarray, c) -> None:
    """Brute-force re-check of a ``CycleCover`` from the triangles alone (no twins, no numba)."""
    m = len(tri)
    sides: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for t in range(m):
        for k in range(3):
            a, b = int(tri[t, k]), int(tri[t, (k + 1) % 3])
            sides.setdefault((min(a, b), max(a, b)), []).append((t, k))
    cov = np.asarray(c.is_cov).reshape(m, 3)
    adj: dict[int, list[int]] = {t: [] for t in range(m)}
    for pair, owners in sides.items():
        flags = [bool(cov[t, k]) for t, k in owners]
        if len(owners) != 2:
            assert not any(flags), f"cover half-edge on boundary edge {pair}"
            continue
        assert flags[0] == flags[1], f"cover edge {pair} marked on one side only"
        if flags[0]:
            (t, _), (u, _) = owners
            assert t != u
            adj[t].append(u)
            adj[u].append(t)
    for t in range(m):
        d = len(adj[t])
        assert d in (0, 2), f"triangle {t} has cover degree {d}"
        assert (d == 0) == (int(c.cycle[t]) < 0), f"triangle {t}: cycle id {int(c.cycle[t])}, degree {d}"
        n_nb = sum(len(sides[(min(a, b), max(a, b))]) - 1 for a, b in
                   ((tri[t, k], tri[t, (k + 1) % 3]) for k in range(3)))
        if n_nb <= 1:  # an ear (or a lone triangle) cannot lie on a cycle
            assert d == 0
    seen = np.zeros(m, bool)
    n_cyc = 0
    ids = set()
    for s in range(m):
        if seen[s] or not adj[s]:
            continue
        # walk the cycle through s: with degree 2 everywhere it must come back to s
        prev, cur, comp = s, adj[s][0], [s]
        seen[s] = True
        while cur != s:
            assert not seen[cur], f"triangle {cur} on two cycles"
            seen[cur] = True
            comp.append(cur)
            nxt = adj[cur][0] if adj[cur][0] != prev else adj[cur][1]
            prev, cur = cur, nxt
        assert len(comp) >= 3
        assert len({int(c.cycle[t]) for t in comp}) == 1, "one cycle, two ids"
        ids.add(int(c.cycle[comp[0]]))
        n_cyc += 1
    assert len(ids) == n_cyc == c.n_cycles
    assert int((~seen).sum()) == c.n_uncovered


@st.composite
def punched_delaunay(draw):
    """A Delaunay triangulation of random points with some triangles removed (holes, ears, bridges)."""
    seed = draw(st.integers(0, 2**31 - 1))
    n = draw(st.integers(4, 160))
    drop = draw(st.sampled_from([0.0, 0.05, 0.2, 0.4]))
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    tri = tri[rng.random(len(tri)) >= drop]
    # keep only vertices still used, renumbered (the cover takes any triangle list)
    used, tri = np.unique(tri, return_inverse=True)
    return pts[used], tri.reshape(-1, 3).astype(np.int64), rng


@given(
    case=punched_delaunay(), rotate=st.booleans(), use_good=st.booleans(), online=st.sampled_from([0, 4, 256]),
    drop=st.booleans(), split=st.booleans(),
)
def test_cover_matches_brute_force_oracle(
    case, rotate: bool, use_good: bool, online: int, drop: bool, split: bool
) -> None:
    pts, tri, rng = case
    if len(tri) == 0:
        return
    twin = half_edges(tri, len(pts)).twin
    good = None
    if use_good:  # any symmetric preference must leave the cover valid
        g = rng.random(3 * len(tri)) < 0.5
        inner = twin >= 0
        g[inner] = g[inner] & g[twin[inner]]
        good = g
    # with points (and online > 0) the two halves of the quadtree's top split are matched
    # apart, then joined across it
    c = cycle_cover(tri, twin, rotate=rotate, good=good, online=online, drop=drop, points=pts if split else None)
    oracle_check(tri, c)


@given(
    case=punched_delaunay(), rotate=st.booleans(), online=st.sampled_from([0, 4, 256]),
    keep=st.sampled_from([0.0, 0.5, 0.9, 1.0]), swaps=st.booleans(), splits=st.booleans(),
)
def test_edges_judged_as_asked_give_the_cover_of_edges_judged_ahead(
    case, rotate: bool, online: int, keep: float, swaps: bool, splits: bool
) -> None:
    # ``judge=True`` (sparse mode's matching) judges an edge only where the greedy
    # chooses across it, by the test the whole-mesh pass makes ``good`` by: the same
    # cover; also through the re-colouring (small meshes), which reads every edge
    from hammesh.postprocess import _join_kernels as J
    from hammesh.postprocess.cycle_cover import JoinRule
    from hammesh.postprocess.sparse import triangle_angles

    pts, tri, rng = case
    m = len(tri)
    if m == 0:
        return
    twin = half_edges(tri, len(pts)).twin
    pinned = rng.random(3 * m) < 0.1
    inner = twin >= 0
    pinned[inner] |= pinned[twin[inner]]
    amin, amax = triangle_angles(pts, tri)
    hi = float(amax.max()) + np.radians(5.0)
    good = np.zeros(3 * m, np.bool_)
    J.good_half_edges_into(pts, tri, twin, pinned, amin, keep, hi, swaps, splits, 0, 3 * m, good)
    rule = JoinRule(amin, keep, hi, pinned, swaps, splits)
    ahead = cycle_cover(tri, twin, rotate=rotate, good=good, online=online, points=pts, rule=rule)
    asked = cycle_cover(tri, twin, rotate=rotate, online=online, points=pts, rule=rule, judge=True)
    np.testing.assert_array_equal(ahead.is_cov, asked.is_cov)
    np.testing.assert_array_equal(ahead.cycle, asked.cycle)
    assert (ahead.n_cycles, ahead.n_uncovered, ahead.n_rotations) == (asked.n_cycles, asked.n_uncovered,
                                                                      asked.n_rotations)
    oracle_check(tri, asked)


@given(case=punched_delaunay(), rotate=st.booleans(), size=st.sampled_from([1, 4, 16, 64]))
def test_cell_confined_cover_matches_oracle(case, rotate: bool, size: int) -> None:
    # cycles confined to quadtree cells (edges cut at cell junctions, borders pinned
    # into the matching, searches inside the cells first): still valid cycles
    pts, tri, _ = case
    if len(tri) == 0:
        return
    twin = half_edges(tri, len(pts)).twin
    c = cycle_cover(tri, twin, rotate=rotate, points=pts, cell_size=size)
    oracle_check(tri, c)
    assert c.quad is not None and len(c.quad) == len(tri)


@given(case=punched_delaunay(), size=st.sampled_from([1, 4, 16, 64]))
def test_cut_cell_borders_leaves_only_pinnable_borders(case, size: int) -> None:
    # after the cut every dual edge across a cell border joins two triangles of
    # degree 3 with that one border edge each (so all borders can be matched), and
    # every edge cut was a border edge or one of a triangle left with one neighbour
    from hammesh.postprocess import _cover_kernels as ck
    from hammesh.postprocess.cycle_cover import _cells

    pts, tri, _ = case
    m = len(tri)
    if m == 0:
        return
    twin = half_edges(tri, len(pts)).twin
    _, cell = _cells(pts, tri, twin, m, size)
    nb0 = ck.neighbors(twin, m)
    nb = nb0.copy()
    ck.cut_cell_borders(nb, cell)
    assert ((nb == nb0) | (nb == -1)).all()
    for t in range(m):
        d = int((nb[t] >= 0).sum())
        assert d != 1
        border = [u for u in nb[t] if u >= 0 and cell[u] != cell[t]]
        if border:
            assert d == 3 and len(border) == 1
        for k in range(3):  # symmetric
            u = nb[t, k]
            if u >= 0:
                assert t in nb[u]


def test_cells_keep_cycles_inside() -> None:
    # confined to cells of ~256 triangles, far fewer cover edges cross a cell border
    # than in the unconfined cover (only where the matching had to search across)
    from hammesh.postprocess.cycle_cover import _cells

    dom = bundled_domain("face")
    mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 8000)
    tri = mesh.triangles
    m = len(tri)
    twin = half_edges(tri, mesh.n_points).twin
    _, cell = _cells(mesh.points, tri, twin, m, 256)

    def crossing(c) -> int:
        h = np.flatnonzero(c.is_cov)
        return int((cell[h // 3] != cell[twin[h] // 3]).sum() // 2)

    free = cycle_cover(tri, twin)
    inside = cycle_cover(tri, twin, points=mesh.points, cell_size=256)
    oracle_check(tri, inside)
    assert crossing(inside) * 4 < crossing(free)
    assert inside.n_uncovered <= 0.03 * m


def test_join_classes_are_quadtree_levels() -> None:
    # two triangles of one finest cell join before two across the top split
    from hammesh.postprocess.cycle_cover import join_classes

    low = (1 << 15) - 1
    quad = np.array([(5 << 15) | 7, (5 << 15) | 7, (low << 15) | 7, (0 << 15) | 7], np.int64)
    c = join_classes(quad, np.array([0, 2]), np.array([1, 3]))
    assert c[0] < c[1]


def test_oracle_catches_a_broken_cover() -> None:
    # the oracle must fail on a cover with a triangle of degree 3 or a one-sided edge
    pts, tri = icosphere(1)
    twin = half_edges(tri, len(pts)).twin
    c = cycle_cover(tri, twin)
    oracle_check(tri, c)
    bad = c.is_cov.copy()
    h = int(np.flatnonzero(bad)[0])
    bad[h] = False  # one side only
    with pytest.raises(AssertionError):
        oracle_check(tri, type(c)(bad, c.cycle, c.n_cycles, c.n_uncovered, c.n_unmatched))
    bad2 = c.is_cov.copy()
    h = int(np.flatnonzero(~bad2 & (twin >= 0))[0])
    bad2[h] = bad2[twin[h]] = True  # a matching edge put back: two triangles of degree 3
    with pytest.raises(AssertionError):
        oracle_check(tri, type(c)(bad2, c.cycle, c.n_cycles, c.n_uncovered, c.n_unmatched))


def icosphere(nsub: int) -> tuple[np.ndarray, np.ndarray]:
    from hammesh.surface.shapes import icosphere as ico

    return ico(nsub)


def test_fan_is_one_cycle() -> None:
    tri = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    c = check_cover(tri, 5)
    assert (c.n_cycles, c.n_uncovered) == (1, 0)


def test_ears_stay_uncovered() -> None:
    # a strip: every triangle has a boundary edge; the ends are ears
    tri = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    c = check_cover(tri, 5)
    assert c.n_cycles == 0 and c.n_uncovered == 3


@pytest.mark.parametrize("online", [0, 256])
def test_closed_surface_nearly_all_covered(online: int) -> None:
    pts, tri = icosphere(4)  # dual cubic and bridgeless: a perfect matching exists
    c = check_cover(tri, len(pts), online)
    assert c.n_uncovered == 0 and c.n_unmatched == 0


def test_breadth_first_greedy_leaves_fewer_free() -> None:
    # the sweep with online searches: on a 20k-triangle mesh far fewer degree-3
    # triangles are left for the searches afterwards than by Triangle's numbering
    from hammesh.postprocess import _cover_kernels as ck

    dom = bundled_domain("face")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 30000)
    tri = m.triangles
    nb = ck.neighbors(half_edges(tri, m.n_points).twin, len(tri))
    alive, deg = ck.peel(nb, len(tri))
    active = alive & (deg == 3)
    free = {}
    for online in (0, 256):
        k = len(tri)
        work = (np.empty(k, np.int64), np.empty(k, np.int64), np.full(k, -1, np.int8), np.zeros(k, np.int64),
                np.empty(k + 8, np.int64))
        order = ck._bfs_order(nb, np.zeros(k, np.int8), 0) if online else np.arange(k)
        mate = np.full(k, -1, np.int64)
        ck._greedy_matching(nb, active, k, no_edge_rule(), np.full(3 * k, EDGE_NOT_GOOD, np.int8), order, online,
                            *work, mate)
        paired = np.flatnonzero(mate >= 0)
        assert (mate[mate[paired]] == paired).all() and active[paired].all()
        assert all(mate[t] in nb[t] for t in paired)  # matched along dual edges only
        free[online] = int((active & (mate < 0)).sum())
    assert free[256] * 4 < max(free[0], 4)


@pytest.mark.parametrize("online", [0, 256])
@pytest.mark.parametrize("name", ["A", "face", "square_circle_hole"])
def test_quality_meshes_nearly_all_covered(name: str, online: int) -> None:
    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 3000)
    c = check_cover(m.triangles, m.n_points, online)
    assert c.n_uncovered <= 0.02 * m.n_triangles
    assert c.n_cycles <= 0.05 * m.n_triangles


@given(seed=st.integers(0, 10_000), n=st.integers(4, 300))
def test_random_delaunay(seed: int, n: int) -> None:
    pts = np.random.default_rng(seed).random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    check_cover(tri, n)


@pytest.mark.parametrize("seed", [18, 88, 162])
def test_matching_defects_are_repaired(seed: int) -> None:
    # Delaunay with random triangles removed: dual bridges, no perfect matching; the
    # repair (drop a cover arc between two free triangles) must leave valid cycles
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 60))
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    tri = tri[rng.random(len(tri)) > 0.2]
    c = check_cover(tri, n)
    assert c.n_unmatched > 0
    h = hammesh.hamiltonian(hammesh.Mesh(points=pts, triangles=tri), mode="sparse")
    assert h.report["verified"] and h.report["unmatched"] > 0


@pytest.mark.parametrize("name", ["face", "double_hex", "square_circle_hole"])
def test_drops_leave_fewer_boundary_triangles_uncovered(name: str) -> None:
    # parity defects fixed by longer augmenting searches, then by dropping interior
    # triangles, before chains of boundary triangles: fewer boundary triangles off
    # the cover, every dropped triangle an interior one (three neighbours), the
    # cover still valid
    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 6000)
    tri = m.triangles
    twin = half_edges(tri, m.n_points).twin
    boundary = (twin.reshape(-1, 3) < 0).any(axis=1)
    n_nb = (twin.reshape(-1, 3) >= 0).sum(axis=1)
    chains = cycle_cover(tri, twin, drop=False)
    drops = cycle_cover(tri, twin, drop=True)
    oracle_check(tri, drops)
    lost = {}
    for key, c in (("chains", chains), ("drops", drops)):
        lost[key] = int((boundary & (c.cycle < 0)).sum())
    assert chains.n_dropped == 0
    assert lost["drops"] < lost["chains"]
    assert int(((c := drops).cycle < 0)[n_nb == 3].sum()) >= c.n_dropped


def test_undo_restores_the_logged_state() -> None:
    # a drop sequence that fixes nothing is undone: every logged triangle gets back
    # its partner and flags, newest change first
    from hammesh.postprocess import _cover_kernels as ck

    rng = np.random.default_rng(5)
    m = 40
    mate = rng.integers(-1, m, m)
    active = rng.random(m) < 0.5
    alive = rng.random(m) < 0.5
    before = (mate.copy(), active.copy(), alive.copy())
    log = np.empty((64, 4), np.int64)
    nlog = np.zeros(1, np.int64)
    for i in rng.integers(0, m, 30):  # repeated triangles: the oldest record wins
        ck._log(log, nlog, i, mate, active, alive)
        mate[i], active[i], alive[i] = rng.integers(-1, m), not active[i], not alive[i]
    assert ck._undo(log, nlog, mate, active, alive)
    for a, b in zip((mate, active, alive), before):
        np.testing.assert_array_equal(a, b)
    nlog[0] = len(log) + 1  # overflowed: cannot be undone, nothing touched
    assert not ck._undo(log, nlog, mate, active, alive)


@pytest.mark.parametrize("judge", [False, True])
@pytest.mark.parametrize("local", [False, True])
def test_halves_on_two_threads_give_the_one_thread_cover(monkeypatch, local: bool, judge: bool) -> None:
    # the two halves of the split share nothing they write: matched side by side on
    # two threads or one after the other, the cover is the same (local: the rows
    # renumbered as sparse mode hands them over, cut at a quadrant border; judge: the
    # halves judge their edges as they ask, into one memo, as sparse mode's cover)
    from hammesh import threads
    from hammesh.halfedge import renumber_local
    from hammesh.postprocess import _join_kernels as J
    from hammesh.postprocess.cycle_cover import JoinRule
    from hammesh.postprocess.sparse import triangle_angles

    dom = bundled_domain("face")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 6000)
    tri, pts = m.triangles, m.points
    twin = half_edges(tri, m.n_points).twin
    if local:
        loc = renumber_local(pts, tri, twin)
        tri, pts, twin = loc.triangles, loc.points, loc.twin
    k = {}
    if judge:
        amin, amax = triangle_angles(pts, tri)
        rule = JoinRule(amin, 0.9, float(amax.max()) + np.radians(5.0), np.zeros(3 * len(tri), np.bool_))
        good = np.zeros(3 * len(tri), np.bool_)
        J.good_half_edges_into(pts, tri, twin, rule.pinned, amin, 0.9, rule.hi, True, True, 0, 3 * len(tri), good)
        ahead = cycle_cover(tri, twin, points=pts, online=256, local=local, good=good, rule=rule)
        k = {"rule": rule, "judge": True}
    one = cycle_cover(tri, twin, points=pts, online=256, local=local, **k)
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 500)
    two = cycle_cover(tri, twin, points=pts, online=256, local=local, **k)
    if judge:
        np.testing.assert_array_equal(ahead.is_cov, two.is_cov)
    oracle_check(tri, two)
    np.testing.assert_array_equal(one.is_cov, two.is_cov)
    np.testing.assert_array_equal(one.cycle, two.cycle)
    assert two.n_uncovered <= 0.01 * len(tri)


def _matching_start(name: str, divisor: int):
    """A bundled domain's q30 mesh at its hull area / ``divisor`` and what the matching
    starts from: ``(triangles, m, neighbours, alive, degree-3 alive, mate all -1)``."""
    from hammesh.postprocess import _cover_kernels as ck

    dom = bundled_domain(name)
    msh = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / divisor)
    tri = msh.triangles
    m = len(tri)
    nb = ck.neighbors(half_edges(tri, msh.n_points).twin, m)
    alive, deg = ck.peel(nb, m)
    return tri, m, nb, alive, alive & (deg == 3), np.full(m, -1, np.int64)


@pytest.mark.parametrize("name", ["face", "double_hex", "square_circle_hole", "A"])
def test_observed_search_answers_the_drop_search(name: str) -> None:
    # _drop_matching skips the DROP search after a failed OBSERVE search of at least
    # its budget: from the same state, DROP must stop at the first drop OBSERVE saw
    # (free third neighbour) within its budget, or fail with the first ``extra`` it
    # saw; checked from every defect the matching leaves, for two budgets each
    from hammesh.postprocess import _cover_kernels as ck

    tri, m, nb, alive, active, mate = _matching_start(name, 6000)
    parent, fa, label, stamp = np.empty(m, np.int64), np.empty(m, np.int64), np.full(m, -1, np.int8), np.zeros(m, np.int64)
    g = np.full(3 * m, EDGE_NOT_GOOD, np.int8)
    s = ck.match_half(nb, active, np.zeros(m, np.int8), 0, no_edge_rule(), g, 0, 2000, mate, parent, fa, label, stamp)
    touched, queue = np.empty(m + 16, np.int64), np.empty(m + 16, np.int64)
    log, nlog = np.empty((8 * m + 64, 4), np.int64), np.zeros(1, np.int64)
    seen, dummy = np.empty(4, np.int64), np.empty(4, np.int64)
    outcomes = set()
    for r in np.flatnonzero(active & (mate < 0)):
        for budget in (m, 40):
            nlog[0] = 0
            f, s, _ = ck._augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue, budget,
                                  ck.OBSERVE, -1, log, nlog, seen, ck._no_guide())
            if f >= 0:  # an augmenting path: applied; put the state back
                assert ck._undo(log, nlog, mate, active, alive)
                outcomes.add("path")
                continue
            assert nlog[0] == 0  # a failed search changes nothing
            for b in (budget, budget // 2):
                stop = seen[0] if seen[0] >= 0 and seen[1] < b else -1
                first = seen[2] if seen[2] >= 0 and seen[3] < b else -1
                found, s, extra = ck._augment(r, nb, active, alive, mate, parent, fa, label, stamp, s, touched, queue,
                                              b, ck.DROP, -1, log, nlog, dummy, ck._no_guide())
                assert found == stop
                if found < 0:
                    assert extra == first
                    outcomes.add("extra" if first >= 0 else "none")
                else:
                    assert not alive[found]  # dropped
                    outcomes.add("drop")
                assert ck._undo(log, nlog, mate, active, alive)
    assert "drop" in outcomes or "extra" in outcomes  # the comparison met a drop


@given(seed=st.integers(0, 10_000), n=st.integers(4, 400), p=st.floats(0.0, 1.0))
def test_cycle_ids_by_halves_match_the_serial_walk(seed: int, n: int, p: float) -> None:
    # runs of the cycles inside each half joined across the split: the same ids as
    # one walk in index order, whatever the halves (here random, so cycles cross the
    # split many times)
    from hammesh.postprocess import _cover_kernels as ck
    from hammesh.postprocess.cycle_cover import cycle_ids_by_halves

    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    twin = half_edges(tri, n).twin
    c = cycle_cover(tri, twin, rotate=False)
    side = (rng.random(len(tri)) < p).astype(np.int8)
    want, n_want = ck.cycle_ids(twin, c.is_cov, len(tri))
    got, n_got = cycle_ids_by_halves(twin, c.is_cov, side, [(0, len(tri) // 2), (len(tri) // 2, len(tri))])
    assert n_got == n_want == c.n_cycles
    np.testing.assert_array_equal(got, want)


@given(seed=st.integers(0, 10_000), n=st.integers(4, 400))
def test_rotations_from_candidates_match_the_serial_pass(seed: int, n: int) -> None:
    # the prefilter and the candidates on two row ranges each, then the rotations:
    # the same flips and cycle ids as the one-call pass (random Delaunay meshes:
    # nearly all of them have cycles to merge)
    from hammesh.postprocess import _cover_kernels as ck

    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    twin = half_edges(tri, n).twin
    c = cycle_cover(tri, twin, rotate=False)
    cell = np.zeros(0, np.int64)
    want_cov, want_cyc = c.is_cov.copy(), c.cycle.copy()
    want = ck.rotate_stars(tri, twin, want_cov, want_cyc, c.n_cycles, n, cell)
    got_cov, got_cyc = c.is_cov.copy(), c.cycle.copy()
    vh, skip, cand = np.full(n, -1, np.int64), np.zeros(n, np.bool_), np.empty(n, np.bool_)
    m = len(tri)
    for lo, hi in ((m // 3, m), (0, m // 3)):
        ck.star_prefilter_into(tri, got_cov, vh, skip, lo, hi)
    for lo, hi in ((0, n // 2), (n // 2, n)):
        ck.star_candidates_into(twin, got_cov, got_cyc, vh, skip, cell, cand, lo, hi)
    got = ck.rotate_candidates(twin, got_cov, got_cyc, c.n_cycles, vh, cand, cell)
    assert got == want
    np.testing.assert_array_equal(got_cov, want_cov)
    np.testing.assert_array_equal(got_cyc, want_cyc)


@pytest.mark.parametrize("side", [[0, 0, 0], [0, 1, 1], [1, 1, 0]])
def test_cycle_ids_by_halves_stop_at_a_broken_chain(side: list) -> None:
    """Two triangles glued along two edges (a surface soup can give that): both cover
    edges of one lead to the same neighbour, so the walk finds no next triangle. The
    runs end there as the serial walk does, instead of walking on from index -1 (into
    the last triangle, 2, which is on no cycle: that looped for ever)."""
    from hammesh.postprocess import _cover_kernels as k
    from hammesh.postprocess.cycle_cover import cycle_ids_by_halves

    twin = np.array([3, 4, -1, 0, 1, -1, -1, -1, -1], np.int64)
    is_cov = np.array([True, True, False, True, True, False, False, False, False])
    want, n_want = k.cycle_ids(twin, is_cov, 3)
    assert (n_want, list(want)) == (1, [0, 0, -1])
    got, n_got = cycle_ids_by_halves(twin, is_cov, np.array(side, np.int8), [(0, 2), (2, 3)])
    assert (n_got, list(got)) == (n_want, list(want))


def test_clock_times_the_steps_and_changes_nothing() -> None:
    # cycle_cover(..., clock=) records each step's wall and CPU seconds (bench_cover.py
    # --steps) and must leave the cover exactly as without it
    dom = bundled_domain("face")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 3000)
    twin = half_edges(m.triangles, m.n_points).twin
    clock: dict = {}
    a = cycle_cover(m.triangles, twin, points=m.points, online=256, clock=clock)
    b = cycle_cover(m.triangles, twin, points=m.points, online=256)
    np.testing.assert_array_equal(a.is_cov, b.is_cov)
    np.testing.assert_array_equal(a.cycle, b.cycle)
    assert {"neighbors", "peel", "match_halves", "finish_matching", "cycle_ids", "rotate"} <= set(clock)
    assert all(w >= 0 and c >= 0 for w, c in clock.values())


@pytest.mark.parametrize("name", ["face", "double_hex", "square_circle_hole", "A", "la"])
def test_chain_phase_pairs_what_unbounded_searches_pair(name: str) -> None:
    # the chain phase (_chain_matching) skips the search when fewer than two
    # triangles are free (no augmenting path can exist); otherwise it is one
    # unbounded CHAIN search from each free triangle: the same matching as those
    # searches made here, valid (partners mutual, across a dual edge or a chain of
    # degree-2 triangles), leaving fewer free (at most one: the meshes are connected)
    from hammesh.postprocess import _cover_kernels as ck

    tri, m, nb, alive, active, mate = _matching_start(name, 3000)
    # a greedy matching in a shuffled order, no searches: many triangles left free
    order = np.random.default_rng(5).permutation(np.flatnonzero(active))
    work = (np.empty(m, np.int64), np.empty(m, np.int64), np.full(m, -1, np.int8), np.zeros(m, np.int64))
    queue = np.empty(m + 16, np.int64)
    s = ck._greedy_matching(nb, active, m, no_edge_rule(), np.full(3 * m, EDGE_NOT_GOOD, np.int8), order, 0, *work,
                            queue, mate)
    frees = np.flatnonzero(active & (mate < 0))
    assert len(frees) >= 2
    one = mate.copy()
    touched = np.empty(m + 16, np.int64)
    nolog, nonlog = np.empty((0, 4), np.int64), np.zeros(1, np.int64)
    s1 = s
    for t in frees:
        if one[t] < 0:
            _f, s1, _x = ck._augment(t, nb, active, alive, one, *work, s1, touched, queue, m + 8, ck.CHAIN, -1,
                                     nolog, nonlog, nonlog, ck._no_guide())
    got = mate.copy()
    alive2 = alive.copy()
    no_points = np.zeros((0, 2))  # breadth-first, as the searches above
    ck._chain_matching(nb, active, alive2, got, *work, s1, queue, frees, tri, no_points, 1.0, 50.0)  # s1: stamps above any used
    n_one = int((active & (one < 0)).sum())
    n_got = int((active & (got < 0)).sum())
    np.testing.assert_array_equal(got, one)
    assert n_got == n_one <= 1 < len(frees)
    matched = np.flatnonzero(active & (got >= 0))
    np.testing.assert_array_equal(got[got[matched]], matched)
    for x in matched:  # across a dual edge, or a chain (its triangles now not alive)
        y = got[x]
        ends = [ck._chain_end(nb, active, alive, x, k)[0] for k in range(3)]
        assert y in nb[x] or y in ends
    assert (work[2] == -1).all()  # every label reset


@given(case=punched_delaunay(), rotate=st.booleans(), drop=st.booleans())
def test_local_split_at_a_quadrant_border(case, rotate: bool, drop: bool) -> None:
    # rows in renumber_local's order (as sparse mode hands them over): the halves are
    # the rows before and after a border between quadrants of that order's grid at
    # some level (no quadrant has rows on both sides), and the cover stays valid
    from hammesh.halfedge import renumber_local
    from hammesh.halfedge.locality import cell_bits
    from hammesh.postprocess.cycle_cover import _quadrant_cut

    pts, tri, _ = case
    m = len(tri)
    if m < 2:
        return
    loc = renumber_local(pts, tri, half_edges(tri, len(pts)).twin)
    r = _quadrant_cut(loc.points, loc.triangles, m)
    assert 0 < r < m
    bits = cell_bits(m)
    lo, hi = loc.points.min(axis=0), loc.points.max(axis=0)
    side = float((hi - lo).max())
    c = loc.points[loc.triangles].sum(axis=1) / 3.0
    cell = np.clip(((c - lo) * ((1 << bits) / side)).astype(np.int64), 0, (1 << bits) - 1)
    borders = [level for level in range(1, bits + 1)
               if not set(map(tuple, cell[:r] >> (bits - level))) & set(map(tuple, cell[r:] >> (bits - level)))]
    # (all rows in one cell: no border anywhere, the middle row then)
    assert borders or len(np.unique(cell, axis=0)) == 1, "the cut splits a quadrant at every level"
    # the coarsest level with a quadrant border within m / 8 rows of the middle row
    # gives the cut (brute force: every row where the quadrant changes)
    for level in range(1, bits + 1):
        q = cell >> (bits - level)
        change = np.nonzero((q[1:] != q[:-1]).any(axis=1))[0] + 1
        near = change[8 * np.abs(change - m // 2) <= m]
        if len(near):
            assert r in near and level in borders
            break
    cov = cycle_cover(loc.triangles, loc.twin, rotate=rotate, online=4, drop=drop, points=loc.points, local=True)
    oracle_check(loc.triangles, cov)


def test_guide_heap_pops_nearest_first() -> None:
    # _push / _pop with a guide: a binary heap on A*'s key, the cost given plus the
    # distance from the triangle's centroid to the goal times the goal's scale;
    # every push popped once, least key first
    from hammesh.postprocess import _cover_kernels as ck

    rng = np.random.default_rng(3)
    pts = rng.random((300, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    goal = np.array([0.3, 0.7, 10.0, 50.0])  # (x, y, steps per unit length, chain cost)
    n = len(tri)
    queue, keys, cost = np.empty(n + 8, np.int32), np.empty(n + 8), np.empty(n)
    guide = (tri, pts, goal, keys, cost)
    tail = 0
    pushed = rng.permutation(n)
    g = rng.random(n) * 3
    for w in pushed:
        tail = ck._push(queue, tail, w, guide, g[w])
    got = []
    while tail > 0:
        v, tail = ck._pop(queue, tail, guide)
        got.append(v)
    key = g + 10.0 * np.sqrt(((pts[tri].mean(axis=1) - goal[:2]) ** 2).sum(axis=1))
    assert sorted(got) == list(range(n))
    assert np.all(np.diff(key[got]) >= 0)
    np.testing.assert_array_equal(cost, g)  # each pushed triangle's cost kept


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(20, 400), gx=st.floats(0, 1), gy=st.floats(0, 1),
       mode=st.sampled_from(["PLAIN", "CHAIN"]))
def test_guided_search_finds_a_path_iff_breadth_first_does(seed: int, n: int, gx: float, gy: float,
                                                           mode: str) -> None:
    # Edmonds' search is complete in any expansion order: from every free triangle
    # of a greedy matching (shuffled, no searches), an unbounded best-first search
    # towards any goal finds an augmenting path exactly when the breadth-first one
    # does, and the matching it leaves is valid (mutual, across a dual edge or a
    # chain of degree-2 triangles)
    from hammesh.postprocess import _cover_kernels as ck

    pts, tri, nb, alive, active, mate, work, s = _shuffled_greedy(seed, n, 1.0, np.int64)
    m = len(tri)
    queue, touched = np.empty(m + 16, np.int64), np.empty(m + 16, np.int64)
    nolog, nonlog = np.empty((0, 4), np.int64), np.zeros(1, np.int64)
    guide = (tri, pts, np.array([gx, gy, 30.0, 50.0]), np.empty(m + 16), np.empty(m))  # (x, y, scale, chain cost)
    kind = getattr(ck, mode)
    for r in np.flatnonzero(active & (mate < 0)):
        if mate[r] >= 0:
            continue
        a = mate.copy()
        fa_, s, _ = ck._augment(r, nb, active, alive, a, *work, s, touched, queue, m + 8, kind, -1, nolog, nonlog,
                                nonlog, ck._no_guide())
        b = mate.copy()
        fb, s, _ = ck._augment(r, nb, active, alive, b, *work, s, touched, queue, m + 8, kind, -1, nolog, nonlog,
                               nonlog, guide)
        assert (fa_ >= 0) == (fb >= 0)
        assert (work[2] == -1).all()  # every label reset
        matched = np.flatnonzero(b >= 0)
        np.testing.assert_array_equal(b[b[matched]], matched)
        for x in matched:
            y = b[x]
            ends = [ck._chain_end(nb, active, alive, x, k)[0] for k in range(3)]
            assert y in nb[x] or (mode == "CHAIN" and y in ends)
        assert int((b < 0)[active].sum()) == int((a < 0)[active].sum())
        mate = b  # go on from the guided search's matching


@given(case=punched_delaunay(), rotate=st.booleans(), drop=st.booleans())
def test_guided_chain_searches_give_a_valid_cover(case, rotate: bool, drop: bool) -> None:
    # the chain phase's A* searches (forced on below GUIDE_MIN_TRIANGLES): the cover
    # still passes the brute-force oracle
    import hammesh.postprocess.cycle_cover as cc

    pts, tri, _ = case
    if len(tri) == 0:
        return
    keep = cc.GUIDE_MIN_TRIANGLES
    cc.GUIDE_MIN_TRIANGLES = 0
    try:
        c = cycle_cover(tri, half_edges(tri, len(pts)).twin, rotate=rotate, drop=drop, points=pts)
    finally:
        cc.GUIDE_MIN_TRIANGLES = keep
    oracle_check(tri, c)


@pytest.mark.slow
def test_guided_chain_searches_leave_fewer_uncovered_in_all(monkeypatch) -> None:
    # A* counts each chain triangle CHAIN_COST steps (breadth-first: a chain is one
    # step whatever its length): over five bundled domains at three sizes (with the
    # matching's breadth-first sweep, as from 100 k on) fewer triangles are left
    # uncovered in all (measured 116 -> 99; per mesh from 6 -> 8 to 25 -> 15), with a
    # valid cover each. Without the chain cost the paths ran along thin strokes' chains
    import hammesh.postprocess.cycle_cover as cc

    total = {"bfs": 0, "guided": 0}
    for name in ["face", "square_circle_hole", "A", "double_hex", "la"]:
        dom = bundled_domain(name)
        for div in (3000, 6000, 12000):
            m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / div)
            twin = half_edges(m.triangles, m.n_points).twin
            for arm, lim in (("bfs", 10**12), ("guided", 0)):
                monkeypatch.setattr(cc, "GUIDE_MIN_TRIANGLES", lim)
                c = cycle_cover(m.triangles, twin, points=m.points, online=256)
                oracle_check(m.triangles, c)
                total[arm] += c.n_uncovered
    assert total["guided"] < total["bfs"]


def _shuffled_greedy(seed: int, n: int, keep: float, dtype):
    """A Delaunay mesh of ``n`` random points (each triangle kept with probability
    ``keep``: dual bridges, parity defects) and its matching after a greedy in a
    shuffled order, no searches (many triangles left free); triangle ids ``dtype``.
    Returns ``(points, triangles, nb, alive, active, mate, work, next lca stamp)``."""
    from hammesh.postprocess import _cover_kernels as ck

    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    if keep < 1.0:
        tri = tri[rng.random(len(tri)) < keep]
    m = len(tri)
    nb = ck.neighbors(half_edges(tri, n).twin, m)
    alive, deg = ck.peel(nb, m)
    active = alive & (deg == 3)
    mate = np.full(m, -1, dtype)
    work = (np.empty(m, dtype), np.empty(m, dtype), np.full(m, -1, np.int8), np.zeros(m, np.int64))
    order = rng.permutation(np.flatnonzero(active)).astype(dtype)
    s = ck._greedy_matching(nb, active, m, no_edge_rule(), np.full(3 * m, EDGE_NOT_GOOD, np.int8), order, 0, *work,
                            np.empty(m + 16, dtype), mate)
    return pts, tri, nb, alive, active, mate, work, s


def _defects_state(seed: int, n: int, keep: float):
    """``_shuffled_greedy`` (int32 ids, as the cover's) and ``search_frees`` of 8
    triangles: many defects for the drop phase. Returns ``(nb, alive, active, mate,
    work, s, frees)``."""
    from hammesh.postprocess import _cover_kernels as ck

    _p, _t, nb, alive, active, mate, work, s = _shuffled_greedy(seed, n, keep, np.int32)
    frees, s = ck.search_frees(nb, active, alive, mate, *work, s, 8)
    return nb, alive, active, mate, work, s, frees


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(30, 400), keep=st.floats(0.75, 1.0),
       budget=st.sampled_from([6, 40, 100_000]), at=st.floats(0.0, 1.0))
def test_drop_phase_side_by_side_is_the_serial_phase(seed: int, n: int, keep: float, budget: int, at: float) -> None:
    # the drop phase in two parts side by side (the second on copies, checked after)
    # leaves exactly the serial phase's matching and flags, wherever the list is cut:
    # where the parts' searches met, the second part runs again after the first
    import hammesh.postprocess.cycle_cover as cc

    nb, alive, active, mate, work, s, frees = _defects_state(seed, n, keep)
    cut = int(round(at * len(frees)))
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(cc, "DEFECT_SEARCH_BUDGET", budget)
        mp.setattr(cc, "DROP_BUDGET", budget)
        serial = [mate.copy(), active.copy(), alive.copy()]
        s1, d1 = cc._drop_defects(nb, serial[1], serial[2], serial[0], tuple(a.copy() for a in work), s, frees, False)
        mp.setattr(cc, "defect_cut", lambda *a: cut)
        split = [mate.copy(), active.copy(), alive.copy()]
        s2, d2 = cc._drop_defects(nb, split[1], split[2], split[0], work, s, frees, True)
    for a, b in zip(serial, split):
        np.testing.assert_array_equal(a, b)
    assert d1 == d2
    assert (work[2] == -1).all()  # the search labels left clean for the chain phase


def test_drop_phase_speculation_is_checked(monkeypatch) -> None:
    # the check is not vacuous: over cuts of one list, some second parts read what
    # the first wrote (run again) and some did not (their writes copied)
    import hammesh.postprocess.cycle_cover as cc
    from hammesh.postprocess import _cover_kernels as ck

    outcomes = []
    real = ck.writes_meet

    def spy(*a):
        outcomes.append(bool(real(*a)))
        return outcomes[-1]

    monkeypatch.setattr(cc._k, "writes_meet", spy)
    monkeypatch.setattr(cc, "DEFECT_SEARCH_BUDGET", 40)
    monkeypatch.setattr(cc, "DROP_BUDGET", 40)
    for seed in range(6):
        nb, alive, active, mate, work, s, frees = _defects_state(seed, 300, 0.9)
        for cut in range(1, len(frees)):
            monkeypatch.setattr(cc, "defect_cut", lambda *a, c=cut: c)
            st_ = (mate.copy(), active.copy(), alive.copy())
            cc._drop_defects(nb, st_[1], st_[2], st_[0], tuple(a.copy() for a in work), s, frees, True)
    assert True in outcomes and False in outcomes


@given(rows=st.lists(st.integers(0, 10**6), min_size=0, max_size=40, unique=True), m_extra=st.integers(0, 5))
def test_defect_cut_splits_the_free_defects(rows: list, m_extra: int) -> None:
    # a position in the free list with free triangles on both sides (0 if fewer than
    # two are free), about half of them before it
    from hammesh.postprocess.cycle_cover import defect_cut

    rows = np.array(sorted(rows), np.int64)
    m = (int(rows.max()) + 1 if len(rows) else 1) + m_extra
    active = np.zeros(m, np.bool_)
    active[rows] = True
    mate = np.full(m, -1, np.int32)
    mate[rows[::3]] = 0  # every third matched since
    cut = defect_cut(rows, active, mate)
    still = (active[rows] & (mate[rows] < 0))
    n = int(still.sum())
    if n < 2:
        assert cut == 0
        return
    before, after = int(still[:cut].sum()), int(still[cut:].sum())
    assert before >= 1 and after >= 1
    assert abs(before - n // 2) <= 1


@pytest.mark.parametrize("min_rows", [500, None])
def test_beside_reads_the_rows_left_off_once(min_rows, monkeypatch) -> None:
    """``cycle_cover(..., beside=)`` is called once, with the rows the cover leaves off
    (-1) as in the cover it returns: beside the rotations on two threads (rows per
    thread lowered), or at the end; the cover is the one made without it."""
    from hammesh import threads
    from hammesh.halfedge import renumber_local

    dom = bundled_domain("face")
    msh = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 4000)
    loc = renumber_local(msh.points, msh.triangles, half_edges(msh.triangles, msh.n_points).twin)
    tri, pts, twin = loc.triangles, loc.points, loc.twin
    if min_rows is not None:
        monkeypatch.setattr(threads, "THREAD_MIN_ROWS", min_rows)
        monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    plain = cycle_cover(tri, twin, points=pts, online=256, local=True)
    seen = []
    cov = cycle_cover(tri, twin, points=pts, online=256, local=True,
                      beside=lambda cyc: seen.append((threading.get_ident(), cyc < 0)))
    assert len(seen) == 1
    np.testing.assert_array_equal(seen[0][1], cov.cycle < 0)
    assert plain.n_cycles > 1 and (seen[0][0] != threading.get_ident()) == (min_rows is not None)
    np.testing.assert_array_equal(plain.is_cov, cov.is_cov)
    np.testing.assert_array_equal(plain.cycle, cov.cycle)


@pytest.mark.parametrize("name", ["A", "face", "double_hex"])
def test_peel_from_degrees_is_peel(name: str) -> None:
    """``neighbors_degrees_into`` on row ranges then ``peel_active``: ``peel``'s rows left
    on, and the active rows (left on at degree 3), on meshes with ears."""
    from hammesh.postprocess import _cover_kernels as ck

    dom = bundled_domain(name)
    msh = hammesh.quality_mesh(dom, min_angle=20, max_area=hull_area(dom) / 300)
    tri = msh.triangles
    m = len(tri)
    twin = half_edges(tri, msh.n_points).twin
    nb = ck.neighbors(twin, m)
    alive, deg = ck.peel(nb, m)
    assert not alive.all()  # (ears and what peeling them leaves)
    nb2, deg2 = np.empty((m, 3), np.int32), np.empty(m, np.int8)
    for lo, hi in ((0, m // 3), (m // 3, m)):
        ck.neighbors_degrees_into(twin, nb2, deg2, lo, hi)
    np.testing.assert_array_equal(nb2, nb)
    alive2, active2 = ck.peel_active(nb2, deg2)
    np.testing.assert_array_equal(alive2, alive)
    np.testing.assert_array_equal(active2, alive & (deg == 3))
