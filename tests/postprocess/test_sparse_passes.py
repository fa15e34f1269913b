"""Sparse mode's fused and threaded passes (issue 13, speed) give what the plain ones gave."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import hammesh
import hammesh.postprocess.cycle_cover as cycle_cover_module
from hammesh import threads
from tests.helpers import angles_deg, bundled_domain, hull_area, plate_with_loops, square


def _reference_facts(pts: np.ndarray, tri: np.ndarray):
    """Angles and R / 2r of every triangle by numpy alone (law of cosines, Heron-free)."""
    p = pts[tri]
    e = [p[:, (k + 2) % 3] - p[:, (k + 1) % 3] for k in range(3)]  # edge opposite corner k
    ln = [np.linalg.norm(x, axis=1) for x in e]
    ang = []
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        c = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        ang.append(np.arccos(np.clip(c, -1, 1)))
    ang = np.stack(ang, axis=1)
    u, v = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    a16 = 4 * (np.einsum("ij,ij->i", u, u) * np.einsum("ij,ij->i", v, v) - np.einsum("ij,ij->i", u, v) ** 2)
    ratio = ln[0] * ln[1] * ln[2] * (ln[0] + ln[1] + ln[2]) / a16
    return ang.min(axis=1), ang.max(axis=1), ratio


@settings(max_examples=300, deadline=None)
@given(
    xy=arrays(np.float64, (4, 2), elements=st.floats(-10, 10, allow_nan=False).map(lambda x: round(x, 2))),
    at=st.floats(0.5, 1.5),
    nudge=st.sampled_from([0.0, 1e-9, -1e-9, 1e-6, -1e-6]),
    pinned=st.booleans(),
)
def test_corners_rule_out_only_what_the_full_test_refuses(xy, at, nudge, pinned) -> None:
    """The cover's first test of an edge, off the corner angles (``corners_rule_out``),
    is only ever True where ``edge_meets_rule`` says no, with the rule's angle put
    right at (``at`` ~ 1, ``nudge``) the smaller corner opposite the edge."""
    from hammesh.halfedge import half_edges
    from hammesh.postprocess import _join_kernels as J
    from hammesh.postprocess.sparse import triangle_facts

    tri = np.array([[0, 1, 2], [1, 0, 3]], np.int64)  # edge 0-1 shared: 2 on one side, 3 on the other
    e = xy[1] - xy[0]
    side = [e[0] * (xy[k, 1] - xy[0, 1]) - e[1] * (xy[k, 0] - xy[0, 0]) for k in (2, 3)]
    scale = np.ptp(xy, axis=0).max()
    if not (side[0] > 1e-2 * scale**2 and side[1] < -1e-2 * scale**2):
        return  # (both triangles counter-clockwise, well away from degenerate)
    tw = half_edges(tri, 4).twin
    corners = np.empty((2, 3), np.float32)
    amin, amax, _, _ = triangle_facts(xy, tri, corners=corners)
    opposite = min(corners[0, 2], corners[1, 2])
    keep = min(1.0, max(0.0, at * (opposite / (2.0 * amin.min())) + nudge))
    h = 0  # (row 0's edge 0-1)
    pin = np.zeros(6, np.bool_)
    pin[[0, tw[0]]] = pinned
    meets = J.edge_meets_rule(xy, tri, tw, pin, h, amin, keep, float(np.cos(amax.max() + 0.1)), True, True)
    for x in (h, int(tw[h])):
        if J.corners_rule_out(corners, tw, x, amin, keep):
            assert not meets


def _pinning_domain(name: str) -> hammesh.Domain:
    """A bundled domain, or constrained loops inside a plate, or two regions (whose shared
    edges are pinned too)."""
    if name == "loops":
        return plate_with_loops(3)
    if name == "regions":
        v = square(0, 0, 2) + square(0.5, 0.5, 1)
        segs = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
        return hammesh.Domain(vertices=v, segments=segs, regions=[[0.1, 0.1, 1, np.nan], [1, 1, 2, np.nan]])
    return bundled_domain(name)


@settings(max_examples=40, deadline=None)
@given(
    pts=st.integers(2, 3).flatmap(
        lambda d: arrays(np.float64, (24, d), elements=st.floats(-10, 10, allow_nan=False).map(lambda x: round(x, 3)))
    ),
    seed=st.integers(0, 2**16),
    min_rows=st.sampled_from([1, 3, 1000]),
)
def test_triangle_facts_match_numpy(pts, seed, min_rows) -> None:
    from hammesh.postprocess.sparse import triangle_facts

    rng = np.random.default_rng(seed)
    tri = np.array([rng.choice(len(pts), 3, replace=False) for _ in range(12)], dtype=np.int64)
    p = pts[tri]
    u, v = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    gram = np.einsum("ij,ij->i", u, u) * np.einsum("ij,ij->i", v, v) - np.einsum("ij,ij->i", u, v) ** 2
    lens = np.linalg.norm(np.concatenate([u, v]), axis=1)
    tri = tri[(gram > 1e-3 * lens.reshape(2, -1).max(axis=0) ** 4)]  # well away from degenerate
    if len(tri) == 0:
        return
    old = threads.THREAD_MIN_ROWS
    threads.THREAD_MIN_ROWS = min_rows  # several row ranges side by side, or one
    corners = np.full((len(tri), 3), np.nan, np.float32) if pts.shape[1] == 2 else None
    try:
        lo, hi, worst, row = triangle_facts(pts, tri, corners=corners)
    finally:
        threads.THREAD_MIN_ROWS = old
    rlo, rhi, ratio = _reference_facts(pts, tri)
    np.testing.assert_allclose(lo, rlo, atol=1e-7)
    np.testing.assert_allclose(hi, rhi, atol=1e-7)
    if corners is not None:  # every corner's angle, at tri[t, k], from the same pass
        np.testing.assert_allclose(corners, np.radians(angles_deg(pts, tri)), atol=1e-6)
        assert np.array_equal(corners.min(axis=1), lo.astype(np.float32))
    assert worst == pytest.approx(max(1.0, ratio.max()), rel=1e-6)
    if row >= 0:
        assert ratio[row] == pytest.approx(ratio.max(), rel=1e-6)


def test_degenerate_row_has_infinite_ratio() -> None:
    from hammesh.postprocess.sparse import triangle_facts

    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 0.0]])
    lo, hi, worst, row = triangle_facts(pts, np.array([[0, 1, 2], [0, 1, 3]]))
    assert worst == np.inf and row == 1


@pytest.mark.parametrize("name", ["A", "square_circle_hole"])
def test_report_ratio_equals_a_full_measure(name: str) -> None:
    """The output's radius ratio (kept rows known from the input's worst) is the full one."""

    def worst_radius_ratio(pts, tri):
        return max(1.0, float(_reference_facts(pts, tri)[2].max()))

    m = hammesh.quality_mesh(bundled_domain(name), min_angle=30, max_area=None)
    for keep in (0.9, 0.0):
        h = hammesh.hamiltonian(m, keep=keep)
        assert h.report["radius_ratio_output"] == pytest.approx(worst_radius_ratio(h.points, h.triangles), rel=1e-9)
        assert h.report["radius_ratio_input"] == pytest.approx(worst_radius_ratio(m.points, m.triangles), rel=1e-9)


def test_threaded_scoring_gives_the_same_mesh(monkeypatch) -> None:
    """Scoring and judging in many row ranges side by side changes nothing."""
    from hammesh.postprocess import sparse

    m = hammesh.quality_mesh(bundled_domain("face"), min_angle=30, max_area=None)
    one = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "SCORE_MIN_ROWS", 7)
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 13)
    many = hammesh.hamiltonian(m)
    np.testing.assert_array_equal(one.triangles, many.triangles)
    np.testing.assert_array_equal(one.points, many.points)
    assert one.report["below_parent_rule"] == many.report["below_parent_rule"]


def _pinned_by_keys(out, tri, tw, con, mid_a, mid_b, first_mid, n_all):
    """The output's pinned half-edges by vertex-pair keys (what sparse mode did before)."""
    m = len(tri)
    inner = np.flatnonzero(con & (tw >= 0))
    a = tri.reshape(-1)[inner]
    b = tri[:, [1, 2, 0]].reshape(-1)[inner]
    keys = [np.minimum(a, b) * n_all + np.maximum(a, b)]
    if len(mid_a):
        ma, mb = np.minimum(mid_a, mid_b), np.maximum(mid_a, mid_b)
        split = np.isin(ma * n_all + mb, keys[0])
        mv = first_mid + np.arange(len(mid_a))
        for end in (ma, mb):
            keys.append(np.minimum(end, mv)[split] * n_all + np.maximum(end, mv)[split])
    o0, o1 = out.reshape(-1), out[:, [1, 2, 0]].reshape(-1)
    assert m == len(tri)
    return np.isin(np.minimum(o0, o1) * n_all + np.maximum(o0, o1), np.concatenate(keys))


@pytest.mark.parametrize("name", ["loops", "regions", "la"])
def test_pinned_output_edges_from_parents_equal_the_key_search(name: str, monkeypatch) -> None:
    from hammesh.postprocess import _improve_kernels as ik
    from hammesh.postprocess import sparse

    seen = []
    real = ik.pinned_output_edges

    def spy(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, **given):
        # (sparse mode hands in the kept rows' entries from its gather, ``rows`` the new ones:
        # the whole array is compared, so both halves are checked)
        got = real(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, **given)
        seen.append((got.copy(), _pinned_by_keys(out, tri, twin, con, mid_a, mid_b, first_mid, int(out.max()) + 1)))
        return got

    monkeypatch.setattr(sparse._ik, "pinned_output_edges", spy)
    dom = _pinning_domain(name)
    scale = np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1])
    for area in (0.01 * scale, 0.002 * scale):
        m = hammesh.quality_mesh(dom, min_angle=30, max_area=area)
        hammesh.hamiltonian(m)
    assert seen
    for got, want in seen:
        np.testing.assert_array_equal(got, want)
    if name != "la":
        assert any(w.any() for _, w in seen)


def _cross(u, v) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def _angles(p, q, r):
    out = []
    for o, u, v in ((p, q, r), (q, r, p), (r, p, q)):
        cu, cv = u - o, v - o
        out.append(np.arccos(np.clip(cu @ cv / np.linalg.norm(cu) / np.linalg.norm(cv), -1, 1)))
    return out


@settings(max_examples=200, deadline=None)
@given(
    c=st.tuples(st.floats(-1.5, 2.5), st.floats(0.1, 2.0)),
    d=st.tuples(st.floats(-1.5, 2.5), st.floats(-2.0, -0.1)),
    keep=st.floats(0.5, 1.0),
    swaps=st.booleans(),
)
def test_edge_rule_by_cosines_equals_exact_angles(c, d, keep, swaps) -> None:
    """The cover's yes/no per edge (six corner cosines per join) against all twelve angles."""
    from hammesh.postprocess import _join_kernels as J

    pts = np.array([[0.0, 0.0], [1.0, 0.0], c, d])
    a, b, c, d = pts
    tri = np.array([[0, 1, 2], [1, 0, 3]])
    twin = np.array([3, -1, -1, 0, -1, -1])
    amin = np.array([min(_angles(a, b, c)), min(_angles(b, a, d))])
    hi = np.radians(125)
    lo = keep * amin.min()
    margins = []
    if swaps and _cross(d - a, c - a) > 0 and _cross(b - d, c - d) > 0:
        sw = _angles(a, d, c) + _angles(d, b, c)
        margins.append(min(min(sw) - lo, hi - max(sw)))
    mid = 0.5 * (a + b)
    sp = _angles(a, mid, c) + _angles(mid, b, c) + _angles(b, mid, d) + _angles(mid, a, d)
    margins.append(min(min(sp) - lo, hi - max(sp)))
    want = max(margins) >= 0
    good = np.zeros(1, bool)
    J.good_edges_into(pts, tri, twin, np.zeros(6, bool), np.array([0]), amin, keep, hi, swaps, True, good)
    if abs(max(margins)) > 1e-9:
        assert good[0] == want
    half = np.zeros(6, bool)
    J.good_half_edges_into(pts, tri, twin, np.zeros(6, bool), amin, keep, hi, swaps, True, 0, 6, half)
    assert half[0] == half[3] == good[0] and not half[[1, 2, 4, 5]].any()


def test_open_candidates_are_those_kruskal_can_still_take() -> None:
    from hammesh.postprocess._sparse_kernels import open_candidates

    # t0, t1 on cycle 0; t2, t3 on cycle 1; t4 on cycle 2; t5 uncovered
    cyc = np.array([0, 0, 1, 1, 2, -1])
    twin = np.full(18, -1)
    for h, g in [(0, 6), (3, 9), (10, 12), (7, 15)]:
        twin[h], twin[g] = g, h
    cand = np.array([0, 3, 10, 7])  # t0-t2 meets; t1-t3 same nodes by then; t3-t4 open; t2-t5: t2 taken
    meets = np.array([True, False, False, False])
    np.testing.assert_array_equal(open_candidates(twin, cyc, 3, cand, meets), [False, False, True, False])
    # nothing meets: every candidate is open
    assert open_candidates(twin, cyc, 3, cand, np.zeros(4, bool)).all()


def open_candidates_by_python(twin, cyc, cand, meets) -> np.ndarray:
    """The open candidates by their definition, in plain Python: the joins meeting the
    rule taken in order (a dict union-find over cycles and uncovered triangles, one
    join per triangle), then a candidate is open if both its triangles are free and
    its nodes apart."""
    parent: dict = {}

    def find(x):
        while parent.get(x, x) != x:
            x = parent[x]
        return x

    def node(t):
        return ("c", int(cyc[t])) if cyc[t] >= 0 else ("t", int(t))

    used = set()
    for h, ok in zip(cand.tolist(), meets.tolist()):
        t, u = h // 3, int(twin[h]) // 3
        if ok and t not in used and u not in used and find(node(t)) != find(node(u)):
            parent[find(node(t))] = find(node(u))
            used |= {t, u}
    return np.array([not ok and t not in used and u not in used and find(node(t)) != find(node(u))
                     for t, u, ok in ((h // 3, int(twin[h]) // 3, ok) for h, ok in zip(cand.tolist(), meets.tolist()))],
                    dtype=bool)


@pytest.mark.parametrize("seed", [0, 1])
def test_open_candidates_in_ranges_are_those_of_the_definition(seed: int, monkeypatch) -> None:
    """``open_candidates`` (the joins meeting the rule taken, then the rest judged in one
    range per core against the roots) is the plain definition, on a cover's
    candidates with random ones meeting the rule."""
    from hammesh.halfedge import half_edges
    from hammesh.postprocess import _sparse_kernels as sk
    from hammesh.postprocess.cycle_cover import cycle_cover

    dom = bundled_domain("face")
    msh = hammesh.quality_mesh(dom, min_angle=30, max_area=0.5 if seed else 2.0, isolate=False)
    twin = half_edges(msh.triangles, msh.n_points).twin
    cov = cycle_cover(msh.triangles, twin, rotate=False)
    cand = sk.join_candidates(twin, cov.cycle)
    rng = np.random.default_rng(seed)
    cand = cand[rng.permutation(len(cand))]
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", max(1, len(cand) // 3))
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    for share in (0.0, 0.1, 0.5, 1.0):
        meets = rng.random(len(cand)) < share
        want = open_candidates_by_python(twin, cov.cycle, cand, meets)
        np.testing.assert_array_equal(sk.open_candidates(twin, cov.cycle, cov.n_cycles, cand, meets), want)


@pytest.mark.parametrize("name", ["face", "gear"])
def test_placing_only_open_candidates_loses_nothing(name: str, monkeypatch) -> None:
    """Placing every candidate's point (as before) gives no better mesh than placing the open ones."""
    import importlib
    from pathlib import Path

    from hammesh.postprocess import sparse

    monkeypatch.syspath_prepend(str(Path(__file__).parents[2] / "benchmarks"))
    bench_sparse = importlib.import_module("bench_sparse")

    dom = dict(bench_sparse._domains())[name]
    m = bench_sparse._mesh_at(dom, 4000)
    lazy = hammesh.hamiltonian(m).report
    monkeypatch.setattr(sparse._k, "open_candidates", lambda tw, cyc, n, cand, meets: ~meets)
    every = hammesh.hamiltonian(m).report
    assert lazy["steiner_points"] <= every["steiner_points"]
    assert lazy["below_parent_rule"] <= every["below_parent_rule"] + 2
    assert lazy["min_angle_output_deg"] >= every["min_angle_output_deg"] - 0.5


@pytest.mark.parametrize("name", ["A", "la", "loops", "regions"])
def test_claim_from_the_input_twins_equals_a_full_matching(name: str, monkeypatch) -> None:
    """Twins of kept rows taken from the input's, the rest matched by end points: as on the whole output."""
    from hammesh.halfedge import half_edge_twins
    from hammesh.postprocess import sparse

    seen = []
    real = sparse._k.rows_in_cycle_order

    def spy(*args, **kw):
        got = real(*args, **kw)
        out, kind, claim = got[0], got[3], got[6]
        # (copied: the improvement flips change the rows and the claim in place afterwards)
        seen.append((claim.copy(), half_edge_twins(out, int(out.max()) + 1), (kind != 3).sum()))
        return got

    monkeypatch.setattr(sparse._k, "rows_in_cycle_order", spy)
    dom = _pinning_domain(name)
    scale = np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1])
    for area in (None, 0.01 * scale, 0.002 * scale):
        m = hammesh.quality_mesh(dom, min_angle=30, max_area=area)
        hammesh.hamiltonian(m)
    assert len(seen) >= 3  # (and the kernels' warm-up call, in a fresh process)
    for claim, (want, want_bad), n_new in seen:
        assert want_bad == -1 and n_new > 0
        np.testing.assert_array_equal(claim, want)


def test_new_row_twins_name_an_edge_used_twice() -> None:
    from hammesh.postprocess._sparse_kernels import PASS, SWAP, new_row_twins

    tri = np.array([[0, 1, 2], [1, 0, 3]])  # kept t0 faces the changed t1 across 0-1
    twin_in = np.array([3, -1, -1, 0, -1, -1])
    status = np.array([PASS, SWAP], np.int8)
    ok = np.array([[1, 0, 4], [4, 0, 3], [1, 4, 3]])  # t1 replaced, edge 1 -> 0 kept
    ch = np.flatnonzero(status != PASS)
    tw, changed, face_tw, bad = new_row_twins(ok, tri, twin_in, status, 5, ch)
    assert bad == -1 and list(changed) == [1]
    assert tw[0] == 0 and face_tw[0] == 6  # kept 0 -> 1 pairs with new row 0's 1 -> 0 (virtual 3 x 2 + 0)
    twice = np.array([[0, 1, 4]])  # 0 -> 1 again, in the kept row's direction
    assert new_row_twins(twice, tri, twin_in, status, 5, ch)[3] >= 0
    three = np.array([[1, 0, 4], [1, 0, 3]])  # a third row on edge 0-1
    assert new_row_twins(three, tri, twin_in, status, 5, ch)[3] >= 0

@pytest.mark.parametrize("name", ["A", "la", "face"])
def test_new_row_twins_are_the_virtual_meshs_twins(name: str, monkeypatch) -> None:
    # the twins ``new_row_twins`` matches (new rows', and the kept half-edges' facing a
    # changed triangle, filed where ``_faced`` reads them) are those of the whole
    # virtual output (kept input rows, then the new rows) paired from scratch
    from hammesh.halfedge import half_edge_twins
    from hammesh.postprocess import _sparse_kernels as sk
    from hammesh.postprocess import sparse

    seen = []
    real = sk.new_row_twins

    def spy(out, tri, twin_in, status, n_points, changed):
        got = real(out, tri, twin_in, status, n_points, changed)
        seen.append((out.copy(), tri.copy(), twin_in.copy(), status.copy(), n_points, [np.copy(a) for a in got[:3]],
                     got[3]))
        return got

    monkeypatch.setattr(sparse._k, "new_row_twins", spy)
    dom = bundled_domain(name)
    for area in (None, 0.002 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))):
        hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=area, isolate=False))
    assert len(seen) == 2
    for out, tri, twin_in, status, n_points, (tw_new, changed, face_tw), bad in seen:
        m, k = len(tri), len(out)
        kept = np.flatnonzero(status == sk.PASS)
        assert bad == -1 and changed.tolist() == np.flatnonzero(status != sk.PASS).tolist()
        rows = np.concatenate([tri[kept], out])
        virtual = np.concatenate([kept, m + np.arange(k)])  # each row's virtual id
        tw, _ = half_edge_twins(rows, n_points)
        to_virtual = np.where(tw >= 0, 3 * virtual[np.maximum(tw, 0) // 3] + np.maximum(tw, 0) % 3, -1)
        np.testing.assert_array_equal(tw_new, to_virtual[3 * len(kept):])
        # kept half-edges facing a changed triangle: under the changed triangle's half-edge
        row_of = np.full(m, -1)
        row_of[kept] = np.arange(len(kept))
        want = np.full(3 * len(changed), -1)
        for r, u in enumerate(changed.tolist()):
            for j in range(3):
                g = twin_in[3 * u + j]
                if g >= 0 and status[g // 3] == sk.PASS:
                    want[3 * r + j] = to_virtual[3 * row_of[g // 3] + g % 3]
        np.testing.assert_array_equal(face_tw, want)


def _shuffled_cycle_rows(h: hammesh.HamiltonianMesh, seed: int):
    """``h``'s rows shuffled, with the link bits of each row (the edges its cycle crosses)."""
    from hammesh.halfedge import half_edge_twins

    tri = np.asarray(h.triangles, np.int64)
    k = len(tri)
    tw, _ = half_edge_twins(tri, h.n_points)
    ends = np.cumsum(h.components)
    nxt = np.arange(1, k + 1)
    nxt[ends - 1] = ends - h.components  # each run closes on itself
    link = np.zeros(k, np.uint8)
    for r in range(k):  # (small meshes: a plain loop says what the kernel must find)
        for j in range(3):
            g = tw[3 * r + j]
            if g >= 0 and (g // 3 == nxt[r] or nxt[g // 3] == r):
                link[r] |= 1 << j
    perm = np.random.default_rng(seed).permutation(k)
    inv = np.argsort(perm)
    shuffled = tri[perm]
    return shuffled, link[perm], half_edge_twins(shuffled, h.n_points)[0], inv


@pytest.mark.parametrize("kept", [True, False])
@pytest.mark.parametrize("name", ["A", "loops"])
def test_walk_links_orders_every_cycle_and_the_gather_claims_its_twins(name: str, kept: bool) -> None:
    """The one-pass walk finds each run again from shuffled rows, all kept (input rows and their cover
    edges) or all new (own rows and links); the gather's claim is the output's twins."""
    from hammesh.halfedge import half_edge_twins
    from hammesh.postprocess._sparse_kernels import PASS, SPLIT, rows_in_cycle_order, walk_links

    dom = plate_with_loops(3) if name == "loops" else bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.003 * np.ptp(dom.vertices[:, 0]) ** 2)
    h = hammesh.hamiltonian(m)
    rows, link, tw, inv = _shuffled_cycle_rows(h, 7)
    k = len(rows)
    none = np.zeros(0, np.int64)
    parent = np.arange(k)
    partner = np.where(parent % 5 == 0, (parent + 1) % k, -1)

    def walk(link):
        if kept:  # virtual rows 0..k-1 are input triangles kept whole, their links their cover edges
            is_cov = ((link[:, None] >> np.arange(3)) & 1).astype(np.bool_).reshape(-1)
            status = np.full(k, PASS, np.int8)
            return walk_links(status, is_cov, np.zeros(0, np.uint8), none, tw, none, none, none), status
        status = np.zeros(0, np.int8)  # no input: every row is a new one (virtual rows 0 + i)
        return walk_links(status, np.zeros(0, np.bool_), link, parent, none, tw, none, none), status

    (order, lengths, low, bad), status = walk(link)
    assert bad == -1
    assert sorted(lengths) == sorted(h.components)
    assert np.array_equal(np.sort(order), np.arange(k))
    start = 0
    for n, lo in zip(lengths, low):  # consecutive rows of a run share an edge, and the run closes
        run = rows[order[start:start + n]]
        for x, y in zip(run, np.roll(run, -1, axis=0)):
            assert len(set(x) & set(y)) == 2
        assert lo == order[start:start + n].min()  # (parent = row here)
        start += n
    amin = np.linspace(0.1, 0.5, k)
    run_order = np.arange(len(lengths))[::-1].copy()
    if kept:
        got = rows_in_cycle_order(order, lengths, run_order, rows, tw, status, np.zeros((0, 3), np.int64), none,
                                  none, np.zeros(0, np.int8), none, none, none, amin)
    else:
        got = rows_in_cycle_order(order, lengths, run_order, np.zeros((0, 3), np.int64), none, status, rows, parent,
                                  partner, np.full(k, SPLIT, np.int8), tw, none, none, amin)
    out, par, prt, kind, pm, new_len, claim = got
    np.testing.assert_array_equal(claim, half_edge_twins(out, h.n_points)[0])
    np.testing.assert_array_equal(new_len, lengths[::-1])
    np.testing.assert_array_equal(out, rows[par])
    assert (kind == 3).all() == kept and (prt == -1).all() == kept
    want = np.where(prt >= 0, np.minimum(amin[par], amin[np.maximum(prt, 0)]), amin[par])
    np.testing.assert_array_equal(pm, want)
    # a row with one link, and a link the other side does not return: named
    for r in (0, k // 2):
        broken = link.copy()
        broken[r] &= broken[r] - 1  # drop its lowest link bit
        assert walk(broken)[0][3] >= 0

def test_step_seconds_cover_the_construction_within_its_time() -> None:
    """The report's per-step times (bench_sparse --breakdown) are each >= 0 and add up to at most the call."""
    m = hammesh.quality_mesh(bundled_domain("face"), min_angle=30, max_area=None)
    r = hammesh.hamiltonian(m).report
    wall, cpu = r["step_seconds"], r["step_cpu_seconds"]
    assert set(wall) == set(cpu) >= {"input_angles", "judge_edges", "cover", "plan_joins", "output_rows", "improve"}
    assert all(v >= 0 for v in [*wall.values(), *cpu.values()])
    assert sum(wall.values()) <= r["seconds"]["hamiltonian"]


@pytest.mark.slow
def test_bench_sparse_breakdown_prints_every_step() -> None:
    """``bench_sparse.py --breakdown`` (a fresh process) prints each step's wall and CPU against raw Triangle."""
    import subprocess
    import sys
    from pathlib import Path

    bench = Path(__file__).parent.parent.parent / "benchmarks" / "bench_sparse.py"
    proc = subprocess.run(
        [sys.executable, str(bench), "--breakdown", "--max-area", "0.001"], capture_output=True, text=True,
        timeout=1200,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    for step in ("input_angles", "judge_edges", "cover", "plan_joins", "output_rows", "improve", "certificate"):
        row = next(x for x in lines if x.startswith(step + " "))
        wall = float(row.split()[1])
        assert wall >= 0
    ratio = float(next(x for x in lines if x.startswith("BREAKDOWN_RATIO")).split()[1])
    assert ratio > 0


@pytest.mark.parametrize("name", ["A", "plate_2_holes"])
def test_placing_taken_joins_after_the_plan_only_lifts_them(name: str, monkeypatch) -> None:
    """Joins the plan took below the rule, placed again without a reach: fewer rows below
    keep x the input's minimum, the plan itself (merges, bridges, incenters) unchanged."""
    import importlib
    from pathlib import Path

    from hammesh.postprocess import sparse
    from tests.postprocess.test_sparse import _angles, assert_sparse_certificate

    monkeypatch.syspath_prepend(str(Path(__file__).parents[2] / "benchmarks"))
    bench_sparse = importlib.import_module("bench_sparse")
    m = bench_sparse._mesh_at(dict(bench_sparse._domains())[name], 4000)
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (no session-14 re-colouring: it leaves nothing here)
    # one plan (no ring joins, whose second plan starts from the first's joins, nor
    # cover swaps, which take some of the placed joins away)
    monkeypatch.setattr(sparse, "RING_JOIN_PASSES", 0)
    monkeypatch.setattr(sparse, "ALT_MERGE_TRIES", 0)
    late = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "PLACE_TAKEN", False)
    plan_only = hammesh.hamiltonian(m)
    assert late.report["joins_placed_after_plan"] >= 1
    assert plan_only.report["joins_placed_after_plan"] == 0
    assert_sparse_certificate(m, late)
    for key in ("merges", "bridges", "incenters", "uncovered", "retries"):
        assert late.report[key] == plan_only.report[key], key
    # each one placed turned a swap or a midpoint into a placed split (one point each at most)
    extra = late.report["steiner_points"] - plan_only.report["steiner_points"]
    assert 0 <= extra <= late.report["joins_placed_after_plan"]
    lo = 0.9 * _angles(m.points, m.triangles).min()

    def below(h):
        return int((_angles(h.points, h.triangles).min(axis=1) < lo).sum())

    assert below(late) < below(plan_only)
    assert late.report["max_angle_output_deg"] <= max(
        plan_only.report["max_angle_output_deg"], late.report["max_angle_input_deg"] + 5
    ) + 1e-9


@pytest.mark.slow
def test_bench_sparse_angles_prints_the_bounds_and_checks_them() -> None:
    """``bench_sparse.py --angles``: every domain's row with its corner and join bounds, which the
    marks check against the printed minimum, and the closing target lines."""
    import subprocess
    import sys
    from pathlib import Path

    bench = Path(__file__).parent.parent.parent / "benchmarks" / "bench_sparse.py"
    proc = subprocess.run(
        [sys.executable, str(bench), "--angles", "--target", "1500"], capture_output=True, text=True, timeout=1200
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    names = ("A", "face", "double_hex", "gear", "la")
    rows = [
        x for x in lines
        if len(x.split()) > 13 and x.split()[0] in names and x.split()[1].replace(",", "").isdigit()
    ]
    assert len(rows) >= 5
    for row in rows:
        f = row.split()
        min_in, min_out, corner, join = float(f[3]), float(f[4]), float(f[11]), f[12]
        bounds = row.split(";")[1].split()
        goal = min(0.9 * min_in, corner)
        assert (bounds[0] == "ok") == (min_out >= goal - 0.005)  # (printed to 2 decimals)
        assert min_out <= corner + 0.005  # no construction beats the corner bound
        if join != "-":
            assert (bounds[1] == "ok") == (min_out >= min(goal, float(join)) - 0.005)
    assert any(x.strip().startswith("... >= min(that, join bound)") for x in lines)
    assert any(x.startswith("A at 87 triangles") for x in lines)


@pytest.mark.parametrize("name, max_area", [("face", None), ("A", None), ("square_circle_hole", 0.003)])
def test_improvement_worked_out_ahead_on_both_cores_gives_the_same_mesh(name: str, max_area, monkeypatch) -> None:
    """The improvement step's tries and moves decided ahead on two cores (``failing_flips``,
    ``smooth_steiner``'s ``_judge_points_into``), then taken by the serial loops where their
    rows are unchanged, give the mesh of the serial loops alone, flip for flip and move for
    move (a mesh where both flips and moves happen, so the ahead work is used and overruled)."""
    from hammesh.postprocess import sparse

    m = hammesh.quality_mesh(bundled_domain(name), min_angle=30, max_area=max_area)
    monkeypatch.setattr(threads, "cores", lambda: 2)  # (two ranges even on a one-core runner)
    monkeypatch.setattr(sparse, "IMPROVE_MIN_ROWS", 10**9)
    monkeypatch.setattr(sparse, "SMOOTH_MIN_POINTS", 10**9)
    serial = hammesh.hamiltonian(m, mode="sparse")
    monkeypatch.setattr(sparse, "IMPROVE_MIN_ROWS", 1)
    monkeypatch.setattr(sparse, "SMOOTH_MIN_POINTS", 1)
    ahead = hammesh.hamiltonian(m, mode="sparse")
    assert serial.report["improvement_flips"] > 0 and serial.report["steiner_moved"] > 0
    for key in ("improvement_flips", "steiner_moved", "below_parent_rule"):
        assert ahead.report[key] == serial.report[key]
    for a, b in ((ahead.points, serial.points), (ahead.triangles, serial.triangles), (ahead.kind, serial.kind),
                 (ahead.parent, serial.parent), (ahead.components, serial.components)):
        np.testing.assert_array_equal(a, b)


_finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@settings(max_examples=400, deadline=None)
@given(_finite, _finite, st.floats(1e-300, 1e300))
def test_corner_atan2_is_atan2_within_rounding(y, x, scale):
    """``_join_kernels.corner_atan2`` (a corner's angle, ``y = |cross| >= 0``) agrees with
    ``math.atan2`` to a few units in the last place at any scale, signs of ``x`` and the
    special points ``(0, +0)`` (0) and ``(0, x <= -0)`` (pi) included."""
    import math

    from hammesh.postprocess._join_kernels import corner_atan2

    yy, xx = abs(y) * scale, x * scale
    if not (math.isfinite(yy) and math.isfinite(xx)):
        return
    got = corner_atan2(yy, xx)
    want = math.atan2(yy, xx)
    assert abs(got - want) <= 1e-15, (yy, xx, got, want)
    assert 0.0 <= got <= math.pi


def test_corner_atan2_special_points_and_folds():
    """Exact where ``math.atan2`` is: the axes and the diagonals' folds (tan 15 degrees,
    45 degrees, the swap of ``|x|`` and ``y``) land on the right side."""
    import math

    from hammesh.postprocess._join_kernels import corner_atan2

    assert corner_atan2(0.0, 0.0) == 0.0
    assert corner_atan2(0.0, -0.0) == math.pi
    assert corner_atan2(0.0, 2.0) == 0.0
    assert corner_atan2(0.0, -2.0) == math.pi
    assert corner_atan2(3.0, 0.0) == pytest.approx(0.5 * math.pi, abs=1e-16)
    for deg in (1e-9, 0.1, 14.999, 15.0, 15.001, 29.9, 30.0, 44.999, 45.0, 45.001, 60.0, 89.999, 90.0,
                90.001, 120.0, 135.0, 165.0, 179.999):
        a = math.radians(deg)
        assert corner_atan2(math.sin(a), math.cos(a)) == pytest.approx(math.atan2(math.sin(a), math.cos(a)),
                                                                         abs=5e-16), deg


@settings(max_examples=300, deadline=None)
@given(
    arrays(np.float64, st.integers(0, 300), elements=st.sampled_from([-1.5, -0.25, 0.0, 0.25, 3.0, 8.0, np.nan])),
    st.booleans(),
)
def test_stable_argsort_is_numpys_stable_order(key, spread) -> None:
    """``sparse.stable_argsort`` (an unstable sort with its ties put back in index order,
    session 20) gives exactly ``np.argsort(kind="stable")``: many ties, NaNs, and (spread)
    keys made distinct but close."""
    from hammesh.postprocess.sparse import stable_argsort

    if spread:
        key = key + np.arange(len(key)) % 3 * 1e-15
    assert np.array_equal(stable_argsort(key.copy()), np.argsort(key, kind="stable"))


@pytest.mark.parametrize("ties_max", [None, 10])
def test_stable_argsort_many_ties(ties_max, monkeypatch) -> None:
    """Many tied places (fixed together, session 21), and beyond ``STABLE_TIES_MAX``
    (the stable sort again): numpy's stable order either way."""
    from hammesh.postprocess import sparse

    if ties_max is not None:
        monkeypatch.setattr(sparse, "STABLE_TIES_MAX", ties_max)
    key = np.repeat(np.arange(50.0), 20)[::-1].copy()
    assert np.array_equal(sparse.stable_argsort(key), np.argsort(key, kind="stable"))
    few = np.linspace(0, 1, 5000)
    few[100:110] = 0.5
    few[4000:4003] = few[17]
    assert np.array_equal(sparse.stable_argsort(few), np.argsort(few, kind="stable"))
    rng = np.random.default_rng(21)
    mixed = rng.integers(0, 700, 60_000) * 0.125 - rng.integers(0, 3, 60_000) * 8.0
    assert np.array_equal(sparse.stable_argsort(mixed), np.argsort(mixed, kind="stable"))


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    rounds=st.lists(st.tuples(st.integers(0, 6), st.integers(0, 4), st.booleans()), min_size=1, max_size=5),
    lo_deg=st.floats(10, 40),
    hi_deg=st.floats(80, 130),
)
def test_missing_rows_measuring_only_stamped_rows_equals_a_full_pass(seed, rounds, lo_deg, hi_deg) -> None:
    """``sparse._MissingRows`` (the improvement step's repeated ask, measuring only the rows
    stamped in ``touched`` since it last measured) answers what a full pass over the rows
    answers, as points move and rows change corners and join the asked set, each change
    stamped with the advanced clock as the step's kernels stamp it."""
    from hammesh.postprocess import sparse

    rng = np.random.default_rng(seed)
    pts = rng.random((40, 2))
    tri = np.array([rng.choice(40, 3, replace=False) for _ in range(60)], np.int64)
    touched = np.zeros(len(tri), np.int64)
    clock = np.zeros(1, np.int64)
    ask = sparse._MissingRows(touched, clock)
    rows = np.flatnonzero(rng.random(len(tri)) < 0.5)
    lo, hi = np.radians(lo_deg), np.radians(hi_deg)
    for moves, flips, grow in rounds:
        for v in rng.choice(40, moves, replace=False):  # a point moved: its rows stamped
            pts[v] += rng.normal(0.0, 0.05, 2)
            clock[0] += 1
            touched[np.flatnonzero((tri == v).any(axis=1))] = clock[0]
        for x in rng.choice(len(tri), flips, replace=False):  # a row's corners changed
            tri[x] = rng.choice(40, 3, replace=False)
            clock[0] += 1
            touched[x] = clock[0]
        if grow:  # rows joining the asked set (flips make kept rows new)
            rows = np.union1d(rows, rng.choice(len(tri), 5))
        np.testing.assert_array_equal(ask(pts, tri, rows, lo, hi), sparse._missing_rows(pts, tri, rows, lo, hi))


@pytest.mark.parametrize("name", ["A", "face"])
def test_improvement_asks_missing_rows_as_a_full_pass_answers(name: str, monkeypatch) -> None:
    """On a mesh where the improvement step asks only the rows missing the targets
    (``IMPROVE_ALL_BELOW`` lowered) and both flips and moves happen, every ask of the
    incremental ``_MissingRows`` equals a full pass over the rows as they are then: the
    flips' and moves' stamps in ``touched`` cover every row whose angles changed."""
    from hammesh.postprocess import sparse

    m = hammesh.quality_mesh(bundled_domain(name), min_angle=30)
    monkeypatch.setattr(sparse, "IMPROVE_ALL_BELOW", 0)
    real = sparse._MissingRows.__call__
    asks = []

    def checked(self, pts, out, rows, lo, hi):
        got = real(self, pts, out, rows, lo, hi)
        np.testing.assert_array_equal(got, sparse._missing_rows(pts, out, rows, lo, hi))
        asks.append(self.at)
        return got

    monkeypatch.setattr(sparse._MissingRows, "__call__", checked)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert h.report["improvement_flips"] > 0 and h.report["steiner_moved"] > 0
    assert len(asks) >= 3 and asks[-1] > asks[0]  # (asked again after rows changed)


@pytest.mark.parametrize("name", ["A", "face", "square_circle_hole"])
def test_repair_from_the_improvements_ask_gives_the_same_mesh_and_report(name: str, monkeypatch) -> None:
    """``_repair_targets``' first round taken from the improvement step's ask
    (``_MissingRows``, only the rows changed since it measured) and its full pass made
    only where no point moves gives the mesh and the report (its new rows' facts) of a
    full pass every round."""
    from hammesh.postprocess import sparse

    m = hammesh.quality_mesh(bundled_domain(name), min_angle=30)
    monkeypatch.setattr(sparse, "IMPROVE_ALL_BELOW", 0)
    asked = hammesh.hamiltonian(m, mode="sparse")
    real = sparse._repair_targets
    monkeypatch.setattr(sparse, "_repair_targets", lambda *a, missing_rows=None: real(*a))
    full = hammesh.hamiltonian(m, mode="sparse")
    for key in full.report:
        if "seconds" not in key:
            assert asked.report[key] == full.report[key], key
    for a, b in ((asked.points, full.points), (asked.triangles, full.triangles), (asked.kind, full.kind)):
        np.testing.assert_array_equal(a, b)


def test_twin_keys_in_two_parts_give_the_same_output(monkeypatch) -> None:
    """``_row_twin_keys_split`` in two parts (``TWIN_KEYS_TWO_MIN`` lowered) and in one
    serial call (``_row_twin_keys``) give the same keys, so the same output, array for
    array (and the same report)."""
    from hammesh.postprocess import _sparse_kernels as sk

    dom = bundled_domain("la")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 6000, isolate=False)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    one = hammesh.hamiltonian(m, mode="sparse")
    calls = []
    real = sk._twin_keys_into

    def counted(*a):
        calls.append(a[6])
        return real(*a)

    monkeypatch.setattr(sk, "TWIN_KEYS_TWO_MIN", 1)
    monkeypatch.setattr(sk, "_twin_keys_into", counted)
    two = hammesh.hamiltonian(m, mode="sparse")
    assert len(calls) == 2 and calls[0] == 0 < calls[1]
    for name in ("points", "triangles", "kind", "parent"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    strip = ("step_seconds", "step_cpu_seconds", "seconds")
    assert {k: v for k, v in one.report.items() if not any(s in k for s in strip)} == {
        k: v for k, v in two.report.items() if not any(s in k for s in strip)}
