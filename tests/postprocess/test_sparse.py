"""Sparse mode (issue 6): the Thm 2.4 bound with few Steiner points, same certificate."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh.mesh import KIND_NAMES
from tests.helpers import assert_tiling_and_bound, dual_pieces, signed_areas, square
from tests.helpers import bundled_domain, hull_area, plate_with_loops, star_pslg

CORPUS = ["A", "la", "face", "double_hex", "square_circle_hole", "spiral"]


def assert_sparse_certificate(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> None:
    """Independent re-check (numpy only) of what the certificate promises, plus counts."""
    assert h.report["verified"] is True
    assert_tiling_and_bound(m, h)
    assert len(h.components) == dual_pieces(m.triangles)
    r = h.report
    # every split adds 2 triangles (3 sectors for 1), every midpoint 2 more, every
    # fan over k triangles k + 2 triangles
    assert r["steiner_points"] == r["incenters"] + r["midpoints"] + r["fans"]
    assert r["triangles_added"] == 2 * r["steiner_points"] == h.n_triangles - m.n_triangles
    assert h.n_points == m.n_points + r["steiner_points"]
    assert set(np.unique(h.kind).tolist()) <= set(range(len(KIND_NAMES)))
    # kept input triangles are input rows, unchanged up to rotation
    kept = h.triangles[h.kind == 3]
    keys_in = {tuple(sorted(t)) for t in np.asarray(m.triangles).tolist()}
    assert all(tuple(sorted(t)) in keys_in for t in kept.tolist())
    np.testing.assert_array_equal(h.position[np.cumsum(h.components) - h.components], 0)


@pytest.mark.parametrize("name", CORPUS)
def test_corpus_steiner_target(name: str) -> None:
    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 6000)
    assert m.n_triangles > 4000
    h = hammesh.hamiltonian(m, mode="sparse")
    assert_sparse_certificate(m, h)
    assert h.report["mode"] == "sparse"
    assert h.report["steiner_points"] <= 0.05 * m.n_triangles  # issue 6's target
    # what we aim for (issue 13: <= 1%); A's thin strokes leave ~1% of its triangles
    # off the cover at this size, each absorbed by a split or split at its incenter
    assert h.report["steiner_points"] <= (0.025 if name == "A" else 0.01) * m.n_triangles
    assert h.report["cycles_before_merging"] >= 1
    assert_quality_report(m, h)


def _angles(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(k, 3) angles in degrees, from the law of cosines (numpy only)."""
    x = p[t]
    e = [np.linalg.norm(x[:, (i + 2) % 3] - x[:, (i + 1) % 3], axis=1) for i in range(3)]
    out = []
    for i in range(3):
        a, b, c = e[i], e[(i + 1) % 3], e[(i + 2) % 3]
        out.append(np.degrees(np.arccos(np.clip((b * b + c * c - a * a) / (2 * b * c), -1, 1))))
    return np.stack(out, axis=1)


def assert_quality_report(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> None:
    """The local-rule report (issue 13) against angles recomputed here."""
    r = h.report
    a_in = _angles(m.points, m.triangles)
    a_out = _angles(h.points, h.triangles)
    assert r["max_angle_input_deg"] == pytest.approx(a_in.max(), abs=1e-6)
    assert r["max_angle_output_deg"] == pytest.approx(a_out.max(), abs=1e-6)
    assert r["min_angle_output_deg"] == pytest.approx(a_out.min(), abs=1e-6)
    new = h.kind != 3
    # the rule compares with the smaller of a triangle's parents' smallest angles,
    # which lies between the input's minimum and its own parent's: two bounds
    lo_out, k = a_out.min(axis=1), r["keep"]
    below_global = new & (lo_out < k * a_in.min() * (1 - 1e-6))
    below_own = new & (lo_out < k * a_in.min(axis=1)[h.parent] * (1 + 1e-6))
    assert below_global.sum() <= r["below_parent_rule"] <= below_own.sum()
    assert r["above_max_rule"] == int((new & (a_out.max(axis=1) > a_in.max() + 5 + 1e-6)).sum())

    def ratio(p, t):
        x = p[t]
        la, lb, lc = (np.linalg.norm(x[:, i] - x[:, (i + 1) % 3], axis=1) for i in range(3))
        u, v = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
        area = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        return (la * lb * lc * (la + lb + lc) / (16 * area**2)).max()

    assert r["radius_ratio_input"] == pytest.approx(ratio(m.points, m.triangles), rel=1e-6)
    assert r["radius_ratio_output"] == pytest.approx(ratio(h.points, h.triangles), rel=1e-6)


def test_keep_trades_steiner_points_for_quality() -> None:
    dom = bundled_domain("face")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 3000)
    lax = hammesh.hamiltonian(m, mode="sparse", keep=0.0)
    strict = hammesh.hamiltonian(m, mode="sparse", keep=0.9)
    for h in (lax, strict):
        assert_sparse_certificate(m, h)
        assert_quality_report(m, h)
    assert lax.report["below_parent_rule"] == 0  # nothing is below 0 x anything
    # the strict rule never makes the worst triangle worse than the lax one does
    assert strict.report["min_angle_output_deg"] >= lax.report["min_angle_output_deg"] - 1e-9
    assert strict.report["worst_parent_ratio"] >= 0.5 * (1 - 1e-9)  # Thm 2.4's floor, locally
    with pytest.raises(hammesh.InvalidOptionError, match="keep"):
        hammesh.hamiltonian(m, mode="sparse", keep=1.5)


def test_constrained_loops_kept() -> None:
    m = hammesh.quality_mesh(plate_with_loops(3), min_angle=30, max_area=0.005)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert_sparse_certificate(m, h)
    out_edges = {tuple(sorted(e)) for t in h.triangles.tolist() for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    for a, b in m.segments.tolist():
        if tuple(sorted((a, b))) not in out_edges:  # split at its midpoint
            mid = 0.5 * (m.points[a] + m.points[b])
            c = int(np.flatnonzero((h.points == mid).all(axis=1))[0])
            assert tuple(sorted((a, c))) in out_edges and tuple(sorted((c, b))) in out_edges
    for a, b in h.segments.tolist():
        assert tuple(sorted((a, b))) in out_edges


def test_constrained_edges_never_swapped_or_flipped() -> None:
    # every free edge is constrained: no swap, no flip, only midpoints can join cycles
    m = hammesh.quality_mesh(hammesh.Domain.from_polygon(square()), min_angle=30, max_area=0.01)
    edges = np.sort(np.concatenate([m.triangles[:, [0, 1]], m.triangles[:, [1, 2]], m.triangles[:, [2, 0]]]), axis=1)
    all_edges = np.unique(edges, axis=0)
    mc = hammesh.Mesh(points=m.points, triangles=m.triangles, segments=all_edges)
    h = hammesh.hamiltonian(mc, mode="sparse")
    assert h.report["swaps"] == 0 and h.report["flips"] == 0
    assert h.report["midpoints"] == h.report["bridges"] + h.report["edge_splits"]
    assert_sparse_certificate(mc, h)


def test_disconnected_pieces_one_cycle_each() -> None:
    v = square(0, 0, 1) + square(2, 0, 1) + square(4, 0.5, 0.5)
    segs = []
    for b in (0, 4, 8):
        segs += [[b, b + 1], [b + 1, b + 2], [b + 2, b + 3], [b + 3, b]]
    dom = hammesh.Domain(vertices=v, segments=segs, holes=[[1.5, 0.5], [3.5, 0.5]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.02)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert len(h.components) == 3
    assert_sparse_certificate(m, h)


def test_sharp_wedge_bound_relative_to_input() -> None:
    ang = np.radians(5)
    v = [[0, 0], [1, 0], [np.cos(ang), np.sin(ang)]]
    m = hammesh.quality_mesh(hammesh.Domain(vertices=v, segments=[[0, 1], [1, 2], [2, 0]]), min_angle=20, max_area=0.001)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert_sparse_certificate(m, h)


@pytest.mark.parametrize("n_tri", [1, 2, 3])
def test_tiny_meshes(n_tri: int) -> None:
    pts = np.array([[0, 0], [1, 0], [0.5, 0.9], [1.5, 0.9], [1.0, 1.8]], float)
    tri = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])[:n_tri]
    m = hammesh.Mesh(points=pts[: tri.max() + 1], triangles=tri)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert_sparse_certificate(m, h)
    assert h.report["incenters"] == n_tri  # no dual cycle exists: every triangle is split


def test_file_mesh_either_orientation() -> None:
    rng = np.random.default_rng(7)
    pts = rng.random((400, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    ccw = tri.copy()
    tri[::2] = tri[::2, ::-1]
    m = hammesh.Mesh(points=pts, triangles=tri)
    h = hammesh.hamiltonian(m, mode="sparse")
    sa = signed_areas(pts, ccw)
    ccw[sa < 0] = ccw[sa < 0, ::-1]
    assert_sparse_certificate(hammesh.Mesh(points=pts, triangles=ccw), h)


def test_attributes_follow_parent() -> None:
    v = square(0, 0, 2) + square(0.5, 0.5, 1)
    segs = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
    dom = hammesh.Domain(vertices=v, segments=segs, regions=[[0.1, 0.1, 1, np.nan], [1, 1, 2, np.nan]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.02)
    h = hammesh.hamiltonian(m, mode="sparse")
    np.testing.assert_array_equal(h.triangle_attributes, m.triangle_attributes[h.parent])
    assert_sparse_certificate(m, h)


def test_bad_inputs_raise_named_errors() -> None:
    pts = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], float)
    with pytest.raises(hammesh.InvalidMeshError, match="triangle 1"):
        hammesh.hamiltonian(hammesh.Mesh(points=pts, triangles=np.array([[0, 1, 2], [1, 1, 3]])), mode="sparse")
    with pytest.raises(hammesh.InvalidMeshError, match="vertex 9"):
        hammesh.hamiltonian(hammesh.Mesh(points=pts, triangles=np.array([[0, 1, 9]])), mode="sparse")
    with pytest.raises(hammesh.InvalidOptionError, match="mode"):
        hammesh.hamiltonian(hammesh.Mesh(points=pts, triangles=np.array([[0, 1, 2]])), mode="sparsest")


def test_cli_mode_sparse(tmp_path, capsys) -> None:
    from hammesh.cli import main

    poly = tmp_path / "sq.poly"
    poly.write_text("4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n")
    out = tmp_path / "sq.vtu"
    rep = tmp_path / "sq.json"
    assert main(["mesh", str(poly), "-q", "30", "-a", "0.001", "--mode", "sparse", "-o", str(out), "--report", str(rep)]) == 0
    import json

    r = json.loads(rep.read_text())
    assert r["mode"] == "sparse" and r["verified"] and "cycles_before_merging" in r
    assert f"{r['cycles_before_merging']:,} cover cycles joined" in capsys.readouterr().out
    assert main(["check", str(out)]) == 0
    proc = subprocess.run(
        [sys.executable, "-m", "hammesh", "mesh", str(poly), "--mode", "nope"], capture_output=True, text=True
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


@given(dom=star_pslg(), min_angle=st.floats(0, 30), area=st.sampled_from([None, 0.05, 0.01]))
def test_random_pslg_certificate(dom: hammesh.Domain, min_angle: float, area: float | None) -> None:
    m = hammesh.quality_mesh(dom, min_angle=min_angle, max_area=area, isolate=False)
    h = hammesh.hamiltonian(m, mode="sparse")
    assert_sparse_certificate(m, h)


def test_cli_keep_option(tmp_path) -> None:
    import json

    from hammesh.cli import main

    poly = tmp_path / "sq.poly"
    poly.write_text("4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n")
    rep = tmp_path / "sq.json"
    assert main(["mesh", str(poly), "-q", "30", "-a", "0.001", "--mode", "sparse", "--keep", "0.7", "--report", str(rep)]) == 0
    assert json.loads(rep.read_text())["keep"] == 0.7
    proc = subprocess.run(
        [sys.executable, "-m", "hammesh", "mesh", str(poly), "--mode", "sparse", "--keep", "2"], capture_output=True, text=True
    )
    assert proc.returncode == 2 and "keep" in proc.stderr and "Traceback" not in proc.stderr


def test_good_edges_agree_with_the_scored_joins() -> None:
    """The cover's fast yes/no (cosines) and the join scoring (angles) judge alike."""
    import math

    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import _join_kernels as J
    from hammesh.postprocess.sparse import triangle_angles

    dom = bundled_domain("face")
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 3000)
    clean, he, is_con = prepare_mesh(m)
    pts, tri, tw = clean.points, clean.triangles, he.twin
    amin, amax = triangle_angles(pts, tri)
    hi = amax.max() + math.radians(5)
    inner = np.flatnonzero(tw > np.arange(len(tw)))
    good = np.zeros(len(inner), bool)
    J.good_edges_into(pts, tri, tw, is_con, inner, amin, 0.9, hi, True, True, good)
    n = len(inner)
    kind, slack = np.zeros(n, np.int8), np.empty(n)
    J.score_joins_into(
        pts, tri, tw, is_con, inner, amin, 0.9, hi, 0.5 * amin.min(), -2.0, True, True, 0, 0.0,
        kind, slack, np.empty(n), np.empty(n), np.empty((n, 2)),
    )
    # equal up to rounding at the threshold (cosine vs arctangent)
    differ = good != (slack >= 0)
    assert differ.sum() <= 2 and np.all(np.abs(slack[differ]) < 1e-9)
    assert 0 < good.sum() < n


@given(
    c=st.tuples(st.floats(-1.5, 1.5), st.floats(0.2, 2.0)),
    d=st.tuples(st.floats(-1.5, 1.5), st.floats(-2.0, -0.2)),
    lo_deg=st.floats(5, 40),
)
def test_placed_split_point_never_worse_than_the_midpoint(c, d, lo_deg) -> None:
    from hammesh.postprocess import _join_kernels as J

    a, b = (0.0, 0.0), (1.0, 0.0)
    lo, hi = np.radians(lo_deg), np.radians(125)
    mid = J._star4_2d(*a, *b, *c, *d, 0.5, 0.0, lo, hi)
    x, y, s, smin, smax = J.place_split(*a, *b, *c, *d, lo, hi, 6)
    assert s >= mid[0]
    # the four triangles around the placed point: counter-clockwise, angles as reported
    quad = [(a, (x, y), c), ((x, y), b, c), (b, (x, y), d), ((x, y), a, d)]
    angles = []
    for p, q, r in quad:
        p, q, r = map(np.array, (p, q, r))
        e, f = q - p, r - p
        assert e[0] * f[1] - e[1] * f[0] > 0
        for o, u, v in ((p, q, r), (q, r, p), (r, p, q)):
            cu, cv = u - o, v - o
            # (atan2 of cross and dot: arccos of a cosine near 1 cannot resolve angles
            # below ~1e-8, e.g. a point placed next to a corner, c=(-1.5, 0.5),
            # d=(-1.5, -2), 5 degrees: 3.3e-12 rad)
            angles.append(np.arctan2(abs(cu[0] * cv[1] - cu[1] * cv[0]), cu @ cv))
    assert min(angles) == pytest.approx(smin, abs=1e-9) and max(angles) == pytest.approx(smax, abs=1e-9)


def test_fans_take_thin_parts_with_fewer_points() -> None:
    # Triangle's A at 87 triangles (q30): strokes one or two triangles wide
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess.sparse import sparse_cycles

    m = hammesh.quality_mesh(bundled_domain("A"), min_angle=30)
    h = hammesh.hamiltonian(m)
    assert_sparse_certificate(m, h)
    assert h.report["fans"] >= 1 and h.report["fan_triangles_replaced"] >= 2 * h.report["fans"]
    clean, he, is_con = prepare_mesh(m)
    amin = np.radians(h.report["min_angle_input_deg"])
    without = sparse_cycles(clean.points, clean.triangles, he.twin, is_con, amin, fans=False)
    steiner_without = without.counts["incenters"] + without.counts["midpoints"]
    assert h.report["steiner_points"] < steiner_without
    # fan points follow the input points (then incenters, midpoints): a fan triangle
    # not split again (one fan point, two input points) keeps the input's minimum angle
    n, f = m.n_points, h.report["fans"]
    t = h.triangles
    fan_rows = (((t >= n) & (t < n + f)).sum(axis=1) == 1) & ((t < n).sum(axis=1) == 2)
    assert fan_rows.any()
    assert _angles(h.points, t[fan_rows]).min() >= h.report["min_angle_input_deg"] * (1 - 1e-9)


def _sliver_circle(n: int) -> hammesh.Mesh:
    """A regular n-gon meshed without a quality switch: n - 2 triangles, angles down to 180/n deg."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return hammesh.quality_mesh(hammesh.Domain.from_polygon(np.c_[np.cos(t), np.sin(t)]), min_angle=None)


def _best_time(f, repeat: int) -> float:
    """Best process CPU seconds of ``repeat`` calls: other processes' load (a CI with
    helpers beside it: load 7 on 2 cores) stretches wall times by bursts that broke
    the linearity ratios, not the CPU the call itself spends."""
    import time

    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        f()
        best = min(best, time.process_time() - t0)
    return best


def test_sliver_circle_is_fast_and_linear() -> None:
    # A 2,000-gon without quality refinement is all slivers and no cover cycle: every
    # triangle goes to a fan, whose placement search once cost ~90 % of sparse mode
    # (5x incircle's time per call, and a cold numba cache cost a minute). The bound is
    # generous for a loaded CI; compilation is kept out by a warm-up call.
    hammesh.hamiltonian(_sliver_circle(100))
    m2 = _sliver_circle(2000)
    h = None

    def run2() -> None:
        nonlocal h
        h = hammesh.hamiltonian(m2)

    t2 = _best_time(run2, 1)
    assert t2 < 20.0
    assert_sparse_certificate(m2, h)
    assert h.report["fans"] >= 1
    # linear, not quadratic: 4x the triangles must cost well under 16x (best of 5
    # against load; fixed per-call costs only make the ratio smaller)
    m1, m4 = _sliver_circle(1000), _sliver_circle(4000)
    t1 = _best_time(lambda: hammesh.hamiltonian(m1), 5)
    t4 = _best_time(lambda: hammesh.hamiltonian(m4), 5)
    assert t4 < 8.0 * t1, (t1, t4)


def test_thin_strip_is_fast_and_linear() -> None:
    # A one-triangle-wide strip (50 x 0.01, q30: ~6 k triangles) has a path for its dual:
    # no cover cycle, every triangle uncovered. The fan groups tried to grow a fan from
    # every triangle, each try a placement search and ridge ascent that could not keep
    # the bound (the strip's corners are ~50 degrees, the fans' bound the input's ~30):
    # 0.57 s CPU at 6 k triangles (1.2 s at 12 k), now refused by the corner bound
    # without a search (``_join_kernels.half_smallest_corner``). Bounds generous for a
    # loaded machine (CPU seconds: the step is one thread's).
    def strip(length: float) -> hammesh.Mesh:
        dom = hammesh.Domain.from_polygon([[0, 0], [length, 0], [length, 0.01], [0, 0.01]])
        return hammesh.quality_mesh(dom, min_angle=30, isolate=False)

    m1, m2 = strip(12.5), strip(50.0)
    hammesh.hamiltonian(m1)  # (compiled kernels loaded)
    h = hammesh.hamiltonian(m2)
    assert_sparse_certificate(m2, h)
    assert h.report["uncovered"] == m2.n_triangles  # (the dual is a path: no cycle to cover)
    assert h.report["step_cpu_seconds"]["fans"] < 0.25, h.report["step_cpu_seconds"]
    # linear: 4x the triangles well under 16x the time (best of 3 against load)
    t1 = _best_time(lambda: hammesh.hamiltonian(m1), 3)
    t2 = _best_time(lambda: hammesh.hamiltonian(m2), 3)
    assert t2 < 8.0 * t1 + 0.5, (t1, t2)
    assert t2 < 20.0


@pytest.mark.parametrize("name, div, keep", [("A", 3000, 0.9), ("A", 3000, 1.0), ("face", 16000, 1.0)])
def test_improvement_on_big_outputs_works_only_where_the_targets_are_missed(name: str, div: int, keep: float,
                                                                           monkeypatch) -> None:
    # session 19: from ``IMPROVE_ALL_BELOW`` output rows the improvement step flips and
    # moves only around the new rows that miss issue 13's absolute targets; every row
    # it changes is one of those, the one after it in its cycle (a flip's partner), or
    # in the star of a Steiner point at a corner of one; the targets' misses and the
    # extremes are never worse than without the step, and the certificate holds
    from hammesh.halfedge import _kernels, prepare_mesh
    from hammesh.postprocess import sparse
    from hammesh.postprocess.sparse import sparse_cycles

    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / div)
    clean, he, is_con = prepare_mesh(m)
    amin = float(clean.info["validated"]["min_angle"])
    monkeypatch.setattr(sparse, "ALT_MERGE_TRIES", 0)  # (joins below the rule left: work to do)
    monkeypatch.setattr(sparse, "IMPROVE_ALL_BELOW", 1)
    runs = {imp: sparse_cycles(clean.points, clean.triangles, he.twin, is_con, amin, keep=keep, improve=imp)
            for imp in (False, True)}
    off, on = runs[False], runs[True]
    assert len(on.triangles) == len(off.triangles) and len(on.points) == len(off.points)
    assert on.counts["steiner_moved"] > 0
    lo, hi = np.degrees(keep * amin), off.counts["max_angle_input_deg"] + 5.0
    a_off, a_on = _angles(off.points, off.triangles), _angles(on.points, on.triangles)
    miss = (a_off.min(axis=1) < lo - 1e-9) | (a_off.max(axis=1) > hi + 1e-9)
    assert ((a_on.min(axis=1) < lo - 1e-9) | (a_on.max(axis=1) > hi + 1e-9)).sum() <= miss.sum()
    assert a_on.min() >= a_off.min() - 1e-9 and a_on.max() <= max(a_off.max(), hi) + 1e-9
    # where the step may reach: missing rows, their cycle successors, the stars of
    # Steiner points at their corners (rows are changed in place: the same row numbers)
    n_in = len(clean.points)
    starts = np.cumsum(on.lengths) - on.lengths
    run = np.repeat(np.arange(len(on.lengths)), on.lengths)
    i = np.arange(len(on.triangles))
    nxt = np.where(i + 1 < starts[run] + on.lengths[run], i + 1, starts[run])
    prv = np.where(i > starts[run], i - 1, starts[run] + on.lengths[run] - 1)
    reach = miss | miss[prv] | miss[nxt]
    pts_of_miss = off.triangles[miss].ravel()
    reach |= np.isin(off.triangles, pts_of_miss[pts_of_miss >= n_in]).any(axis=1)
    changed = (on.triangles != off.triangles).any(axis=1)
    moved = np.flatnonzero((on.points != off.points).any(axis=1))
    changed |= np.isin(on.triangles, moved).any(axis=1)
    assert changed.any()
    assert not (changed & ~reach).any(), np.flatnonzero(changed & ~reach)[:10]
    twin, dup = _kernels.half_edge_twins(on.triangles, len(on.points))
    assert dup < 0
    np.testing.assert_array_equal(on.claim, twin)
    h = hammesh.hamiltonian(m)
    assert_sparse_certificate(m, h)


@pytest.mark.parametrize("name", ["face", "square_circle_hole"])
def test_improvement_flips_keep_the_cycle_and_never_worsen(name: str, monkeypatch) -> None:
    # issue 13: the cavity of a join re-triangulated by flips of edges the cycle
    # crosses between consecutive triangles (``_improve_kernels``)
    from hammesh.halfedge import _kernels, prepare_mesh
    from hammesh.postprocess import sparse
    from hammesh.postprocess.sparse import sparse_cycles

    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 3000)
    clean, he, is_con = prepare_mesh(m)
    amin = float(clean.info["validated"]["min_angle"])
    # (the joins' cavities without the cover swaps, which take most joins below the
    # rule away on these meshes since session 13: the flips have work to do)
    monkeypatch.setattr(sparse, "ALT_MERGE_TRIES", 0)
    runs = {imp: sparse_cycles(clean.points, clean.triangles, he.twin, is_con, amin, improve=imp) for imp in (0, 1)}
    off, on = runs[False], runs[True]
    assert off.counts["improvement_flips"] == 0 < on.counts["improvement_flips"]
    assert off.counts["steiner_moved"] == 0
    if name == "face":
        assert on.counts["steiner_moved"] > 0  # incenters moved into their larger stars
    np.testing.assert_array_equal(on.points[: m.n_points], clean.points)  # input points stay
    # the pairing handed to the certificate is the output's true one after the flips
    twin, dup = _kernels.half_edge_twins(on.triangles, len(on.points))
    assert dup < 0
    np.testing.assert_array_equal(on.claim, twin)
    # consecutive rows of each run share an edge (the cycle is intact)
    start = 0
    for ln in on.lengths.tolist():
        rows = np.arange(start, start + ln)
        nxt = np.roll(rows, -1)
        assert np.all((twin.reshape(-1, 3)[rows] // 3 == nxt[:, None]).any(axis=1))
        start += ln
    # a flip raises the smallest angle of the pair it touches, a Steiner point moves
    # only where its star's smallest angle does not drop (so the output's minimum never
    # drops); the largest stays within max(input max + 5, what it was)
    lo_off, hi_off = _angles(off.points, off.triangles).min(), _angles(off.points, off.triangles).max()
    lo_on, hi_on = _angles(on.points, on.triangles).min(), _angles(on.points, on.triangles).max()
    assert lo_on >= lo_off - 1e-9
    assert hi_on <= max(hi_off, on.counts["max_angle_input_deg"] + 5) + 1e-9
    assert len(on.triangles) == len(off.triangles) and len(on.points) == len(off.points)
    h = hammesh.hamiltonian(m)
    assert_sparse_certificate(m, h)
    assert_quality_report(m, h)


def _interior_corners(domain: hammesh.Domain) -> np.ndarray:
    """Interior angle (degrees) at every vertex of a star_pslg domain's outer polygon and
    hole, from its vertex list alone (outer counter-clockwise; a hole's corners seen
    from the domain)."""
    v = np.asarray(domain.vertices, dtype=np.float64)
    segs = np.asarray(domain.segments)
    out = []
    inner = segs[-1][1] != 0  # star_pslg's last loop closes at 0 unless it is the inner square
    loops = [np.arange(len(v) - 4), np.arange(len(v) - 4, len(v))] if inner else [np.arange(len(v))]
    for j, loop in enumerate(loops):
        if j == 1 and not len(domain.holes):
            continue  # an inner loop of constrained edges, not boundary
        p = v[loop]
        nxt, prv = np.roll(p, -1, axis=0) - p, np.roll(p, 1, axis=0) - p
        ang = np.arctan2(prv[:, 1], prv[:, 0]) - np.arctan2(nxt[:, 1], nxt[:, 0])
        out.append(np.degrees(np.mod(-ang if j == 1 else ang, 2 * np.pi)))
    return np.concatenate(out)


@given(dom=star_pslg())
def test_corner_bound_is_half_the_smallest_corner(dom: hammesh.Domain) -> None:
    """Half the smallest corner of the domain's boundary, found by walking the mesh's wedges."""
    from hammesh.halfedge import half_edge_twins
    from hammesh.postprocess.sparse import corner_bound

    m = hammesh.quality_mesh(dom, min_angle=20, max_area=0.02)
    tw, _ = half_edge_twins(np.asarray(m.triangles, dtype=np.int64), m.n_points)
    expect = 0.5 * min(_interior_corners(dom).min(), 180.0)  # boundary points Triangle adds: 180
    assert np.degrees(corner_bound(m.points, m.triangles, tw)) == pytest.approx(expect, abs=1e-7)
    h = hammesh.hamiltonian(m)
    assert h.report["corner_bound_deg"] == pytest.approx(expect, abs=1e-7)
    assert h.report["min_angle_output_deg"] <= expect + 1e-7  # no construction beats it


@given(
    c=st.tuples(st.floats(-1.5, 1.5), st.floats(0.2, 2.0)),
    d=st.tuples(st.floats(-1.5, 1.5), st.floats(-2.0, -0.2)),
    lo_deg=st.floats(5, 40),
)
def test_no_join_keeps_more_than_half_the_opposite_corners(c, d, lo_deg) -> None:
    """A swap or a split (point placed anywhere) over ab divides the corners at c and d."""
    from hammesh.postprocess import _join_kernels as J

    a, b = (0.0, 0.0), (1.0, 0.0)

    def corner(o, p, q):
        u, v = np.subtract(p, o), np.subtract(q, o)
        return np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1))

    bound = 0.5 * min(corner(c, a, b), corner(d, b, a))
    x, y, s, smin, smax = J.place_split(*a, *b, *c, *d, np.radians(lo_deg), np.radians(125), 6)
    assert smin <= bound + 1e-12
    if J.swap_is_convex_2d(*a, *b, *c, *d):
        l1, _ = J.min_max_angles_2d(*a, *d, *c)
        l2, _ = J.min_max_angles_2d(*d, *b, *c)
        assert min(l1, l2) <= bound + 1e-12


@pytest.mark.parametrize("name", ["A", "square_circle_hole"])
def test_join_bounds_cap_every_join_of_an_uncovered_triangle(name: str, monkeypatch) -> None:
    """join_bounds equals its definition by plain loops, and no scored join of an isolated
    uncovered triangle (placed or swapped) beats it; the report carries its minimum."""
    import math

    from hammesh.halfedge import half_edge_twins
    from hammesh.postprocess import _join_kernels as J
    from hammesh.postprocess.cycle_cover import cycle_cover
    from hammesh.postprocess.sparse import join_bounds, triangle_facts

    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 2000)
    pts, tri = np.asarray(m.points, dtype=np.float64), np.asarray(m.triangles, dtype=np.int64)
    tw, _ = half_edge_twins(tri, len(pts))
    cyc = cycle_cover(tri, tw).cycle
    rows, bound, on_bnd = join_bounds(pts, tri, tw, cyc)
    assert len(rows) >= 1
    ang = np.radians(_angles(pts, tri))
    amin = triangle_facts(pts, tri)[0]
    for t, bd, ob in zip(rows, bound, on_bnd):
        expect = 0.5 * ang[t].min()
        for k in range(3):
            g = tw[3 * t + k]
            assert g < 0 or cyc[g // 3] >= 0  # isolated
            if g >= 0:
                expect = max(expect, 0.5 * min(ang[t, (k + 2) % 3], ang[g // 3, (g % 3 + 2) % 3]))
                kind, slack, nmin, nmax = np.zeros(1, np.int8), np.empty(1), np.empty(1), np.empty(1)
                J.score_joins_into(
                    pts, tri, tw, np.zeros(3 * len(tri), np.bool_), np.array([g]), amin, 0.9, math.radians(125),
                    0.0, -2.0, True, True, 6, math.inf, kind, slack, nmin, nmax, np.empty((1, 2)),
                )
                assert nmin[0] <= bd + 1e-12
        assert bd == pytest.approx(expect, abs=1e-12)
        assert ob == (tw[3 * t:3 * t + 3] < 0).any()
    # the report's figures over the cover the construction made (recorded on its way)
    from hammesh.postprocess import sparse

    seen = []

    def recording_cover(*args, **kwargs):
        seen.append(cycle_cover(*args, **kwargs))
        return seen[-1]

    monkeypatch.setattr(sparse, "cycle_cover", recording_cover)
    r = hammesh.hamiltonian(m).report
    cyc = seen[0].cycle
    rows, bound, on_bnd = join_bounds(pts, tri, tw, cyc)
    assert r["uncovered"] == int((cyc < 0).sum())
    assert r["uncovered_boundary"] == int(sum((tw[3 * t:3 * t + 3] < 0).any() for t in np.flatnonzero(cyc < 0)))
    assert r["join_bound_deg"] == pytest.approx(np.degrees(bound.min()), abs=1e-9)
    assert r["uncovered_below_target"] == int((bound < 0.9 * amin.min() * (1 - 1e-9)).sum())
