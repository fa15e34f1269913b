"""Cover merges by re-colouring vertices (``_recolour_kernels``, session 14).

The cover after ``recolour_merges`` is re-checked from the triangles alone (a
dictionary of vertex pairs, networkx for the cycles), never from the kernels' own
arrays: every covered triangle has two cover edges, each on a real dual edge, the
components are single cycles and ``cycle`` / ``n_cycles`` / ``n_uncovered`` say so.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
import hammesh.postprocess.cycle_cover as cc
from hammesh.halfedge import half_edges
from hammesh.postprocess._recolour_kernels import recolour_merges, vertex_colours
from hammesh.verify.certificate import verify
from tests.helpers import assert_tiling_and_bound, bundled_domain, hull_area


def _dual_check(tri: np.ndarray, c) -> int:
    """Re-check a cover from the triangles alone; returns its node count (cycles +
    uncovered triangles)."""
    m = len(tri)
    sides: dict = {}
    for t in range(m):
        for k in range(3):
            a, b = int(tri[t, k]), int(tri[t, (k + 1) % 3])
            sides.setdefault((min(a, b), max(a, b)), []).append((t, k))
    cov = np.asarray(c.is_cov).reshape(m, 3)
    g = nx.Graph()
    for owners in sides.values():
        flags = [bool(cov[t, k]) for t, k in owners]
        if len(owners) == 1:
            assert not flags[0], "a boundary edge on the cover"
            continue
        assert flags[0] == flags[1], "a cover edge not paired with its twin"
        if flags[0]:
            g.add_edge(owners[0][0], owners[1][0])
    deg = cov.sum(axis=1)
    assert set(np.unique(deg).tolist()) <= {0, 2}
    assert ((deg == 0) == (np.asarray(c.cycle) < 0)).all()
    assert int((deg == 0).sum()) == c.n_uncovered
    comps = list(nx.connected_components(g))
    assert len(comps) == c.n_cycles
    for comp in comps:
        assert len({int(c.cycle[t]) for t in comp}) == 1
        assert all(d == 2 for _, d in g.degree(comp))
    return c.n_cycles + c.n_uncovered


def _covers(tri, n, good, monkeypatch):
    twin = half_edges(tri, n).twin
    monkeypatch.setattr(cc, "RECOLOUR_BELOW", 0)
    before = cc.cycle_cover(tri, twin, good=good)
    monkeypatch.setattr(cc, "RECOLOUR_BELOW", 10**9)
    after = cc.cycle_cover(tri, twin, good=good)
    return before, after


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(8, 400), p=st.floats(0.0, 0.5))
def test_recoloured_cover_is_a_cover_and_counts_its_merges(seed: int, n: int, p: float) -> None:
    with pytest.MonkeyPatch.context() as mp:
        rng = np.random.default_rng(seed)
        pts = rng.random((n, 2))
        tri = Delaunay(pts).simplices.astype(np.int64)
        good = rng.random(3 * len(tri)) < p
        before, after = _covers(tri, n, good, mp)
        # merges take one node each away, a shift leaves at most one more
        extra = _dual_check(tri, after) - (_dual_check(tri, before) - after.n_recoloured)
        assert 0 <= extra <= after.n_recolour_shifts


def test_colours_split_exactly_the_crossed_edges() -> None:
    dom = bundled_domain("face")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 1500)
    tri = np.asarray(m.triangles)
    twin = half_edges(tri, m.n_points).twin
    c = cc.cycle_cover(tri, twin)
    vstart = np.zeros(m.n_points + 1, np.int64)
    np.add.at(vstart, tri.ravel() + 1, 1)
    vstart = np.cumsum(vstart)
    vtri = np.argsort(tri.ravel(), kind="stable") // 3
    col = np.empty(m.n_points, np.int8)
    assert vertex_colours(tri, twin, c.is_cov, vstart, vtri, col)
    crossed = c.is_cov & (twin >= 0)
    diff = col[tri[:, [0, 1, 2]]] != col[tri[:, [1, 2, 0]]]
    np.testing.assert_array_equal(diff.ravel(), crossed)
    # one crossed edge made uncrossed on both sides: no colouring can exist
    h = int(np.flatnonzero(crossed)[0])
    broken = c.is_cov.copy()
    broken[h] = broken[twin[h]] = False
    assert not vertex_colours(tri, twin, broken, vstart, vtri, col)
    # and then nothing is re-coloured
    cyc = c.cycle.copy()
    got = recolour_merges(tri, twin, broken, cyc, c.n_cycles, np.zeros(3 * len(tri), np.bool_),
                          np.zeros(3 * len(tri), np.bool_), m.n_points,
                          64, 3, 64, 3)
    assert tuple(got) == (0, 0)
    np.testing.assert_array_equal(cyc, c.cycle)


def test_la_rows_below_the_parents_rule_drop(monkeypatch) -> None:
    # Triangle's la (one 4.09 deg corner) at ~4k triangles: the stars of single
    # interior vertices that had only joins below the rule are merged for free
    dom = bundled_domain("la")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 2500)
    monkeypatch.setattr(cc, "RECOLOUR_BELOW", 0)
    h0 = hammesh.hamiltonian(m, mode="sparse")
    monkeypatch.setattr(cc, "RECOLOUR_BELOW", 10**9)
    h1 = hammesh.hamiltonian(m, mode="sparse")
    verify(h1, reference=m)  # (the pairing derived by the certificate, no claim)
    assert_tiling_and_bound(m, h1)
    r0, r1 = h0.report, h1.report
    assert r1["below_parent_rule"] < r0["below_parent_rule"]
    assert r1["steiner_points"] < r0["steiner_points"]
    assert r1["min_angle_output_deg"] >= r0["min_angle_output_deg"] - 1e-9


@pytest.mark.parametrize("name", ["A", "face", "double_hex"])
def test_recoloured_sparse_meshes_pass_the_certificate(name: str) -> None:
    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 2000)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert h.report["cover_rotations"] > 0
    verify(h, reference=m)
    assert_tiling_and_bound(m, h)
