"""The certificate rejects every kind of broken output (and accepts good ones)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import hammesh
from hammesh.verify import _kernels, verify, verify_cycle_mesh
from tests.helpers import square


def certify_all(points: np.ndarray, tri: np.ndarray, runs: np.ndarray) -> _kernels.RowChecks:
    """The certificate's row checks in one call over all rows (no pairing claim)."""
    return _kernels.certify_row_range(
        points, tri, np.asarray(runs, np.int64), np.empty(0, np.int64), 0, len(tri),
        np.zeros(len(points), np.bool_), np.empty(0, np.bool_),
    )


@pytest.fixture(scope="module")
def pair() -> tuple[hammesh.Mesh, hammesh.HamiltonianMesh]:
    v = square(0, 0, 1) + square(0.3, 0.3, 0.3)
    segs = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
    m = hammesh.quality_mesh(hammesh.Domain(vertices=v, segments=segs), min_angle=30, max_area=0.02)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert h.report["midpoints"] == 1
    return m, h


def test_good_output_passes(pair) -> None:
    m, h = pair
    stats = verify(h, reference=m)
    assert stats["min_angle_output_deg"] >= 0.5 * stats["min_angle_input_deg"] * (1 - 1e-9)
    assert np.isclose(stats["area"], 1.0)


def test_swapped_rows_break_the_cycle(pair) -> None:
    _, h = pair
    tri = h.triangles.copy()
    tri[[3, 10]] = tri[[10, 3]]
    with pytest.raises(hammesh.VerificationError, match="breaks at triangle"):
        verify(replace(h, triangles=tri))


def test_inverted_triangle(pair) -> None:
    _, h = pair
    tri = h.triangles.copy()
    tri[5] = tri[5][::-1]
    with pytest.raises(hammesh.VerificationError, match="triangle 5 .*inverted"):
        verify(replace(h, triangles=tri))


def test_duplicate_triangle(pair) -> None:
    _, h = pair
    # repeat a triangle in place of its neighbour's neighbour: cycle breaks or repeats
    tri = np.concatenate([h.triangles, h.triangles[:1]])
    comps = h.components.copy()
    comps[-1] += 1
    with pytest.raises(hammesh.VerificationError):
        verify(replace(h, triangles=tri, components=comps))


def test_components_must_sum(pair) -> None:
    _, h = pair
    with pytest.raises(hammesh.VerificationError, match="run lengths"):
        verify(replace(h, components=h.components + 1))


def test_split_run_is_rejected(pair) -> None:
    _, h = pair
    n = h.n_triangles
    with pytest.raises(hammesh.VerificationError):
        verify(replace(h, components=np.array([n // 2, n - n // 2])))


def test_moved_steiner_point_is_caught(pair) -> None:
    m, h = pair
    pts = h.points.copy()
    inc = int(h.triangles[0, 0])  # the incenter of the first triangle
    assert inc >= m.n_points
    pts[inc] = pts[h.triangles[0, 1]] + 2.0 * (pts[h.triangles[0, 1]] - pts[inc])  # pushed out
    with pytest.raises(hammesh.VerificationError):
        verify(replace(h, points=pts), reference=m)


def test_slightly_moved_steiner_point_still_valid_but_angles_checked(pair) -> None:
    m, h = pair
    pts = h.points.copy()
    inc = int(h.triangles[0, 0])
    pts[inc] += 1e-9  # still a valid tiling: the certificate accepts it (no false alarm)
    stats = verify(replace(h, points=pts), reference=m)
    assert stats["min_angle_output_deg"] > 0


def test_input_points_must_be_kept(pair) -> None:
    m, h = pair
    pts = h.points.copy()
    pts[0, 0] += 1e-12
    with pytest.raises(hammesh.VerificationError, match="input point 0 .* not kept unchanged"):
        verify(replace(h, points=pts), reference=m)


def test_angle_bound_is_enforced(pair) -> None:
    m, h = pair
    with pytest.raises(hammesh.VerificationError, match="below 0.9 x the input minimum"):
        verify(h, reference=m, angle_ratio=0.9)


def test_input_segment_that_is_no_input_edge_is_named(pair) -> None:
    m, h = pair
    # an input that claims a constrained edge it does not have: a diagonal of the square
    bad = replace(m, segments=np.r_[m.segments, [[0, 2]]], segment_markers=np.r_[m.segment_markers, [1]])
    s = len(m.segments)
    with pytest.raises(hammesh.VerificationError, match=f"input mesh is not a valid triangulation: segment {s} "):
        verify(h, reference=bad)


def test_output_segments_must_be_edges(pair) -> None:
    _, h = pair
    with pytest.raises(hammesh.VerificationError, match="not an edge"):
        verify(replace(h, segments=np.r_[h.segments, [[0, 2]]]))


def test_removed_triangle_changes_boundary(pair) -> None:
    m, h = pair
    # drop the last two triangles of the cycle but keep it closed is impossible; instead
    # cut the mesh: a reference with one more triangle than the output covers
    with pytest.raises(hammesh.VerificationError):
        verify_cycle_mesh(h.points, h.triangles[:-1], [h.n_triangles - 1], reference=m)


def test_non_finite_points(pair) -> None:
    _, h = pair
    pts = h.points.copy()
    pts[7] = np.nan
    with pytest.raises(hammesh.VerificationError, match="point 7"):
        verify(replace(h, points=pts))


def test_threaded_row_checks_equal_one_pass(pair, monkeypatch) -> None:
    """Split across threads, the row checks give exactly the one-call result."""
    import hammesh.threads as row_threads
    from hammesh.verify import certificate

    _, h = pair
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 7)
    monkeypatch.setattr(row_threads.os, "cpu_count", lambda: 3)
    empty = np.empty(0, dtype=np.int64)
    tri = h.triangles.copy()
    for broken in (None, len(tri) // 2, len(tri) - 1):
        if broken is not None:  # break the cycle in the middle chunk / the last row
            tri = h.triangles.copy()
            tri[broken] = tri[broken][[1, 2, 0]][::-1]
        one = certify_all(h.points, tri, h.components)
        used = np.zeros(len(h.points), dtype=bool)
        split, _ = certificate._certify_rows(h.points, tri, h.components, empty, used)
        assert np.array_equal(used, np.bincount(tri.ravel(), minlength=len(h.points)) > 0)
        for name in ("bad_index", "bad_consecutive", "bad_pair", "cross_run", "argmin", "argmax", "bad_orientation"):
            assert getattr(split, name) == getattr(one, name), name
        assert np.isclose(split.min_angle, one.min_angle) and np.isclose(split.max_angle, one.max_angle)
        assert np.isclose(split.total_area, one.total_area, rtol=1e-12)
        if broken is not None:  # reversed row: negative area
            assert split.min_area < 0 and split.argmin_area == broken == split.bad_orientation


@pytest.mark.parametrize("cores", [2, 3])
def test_row_checks_run_a_side_task_once_after_a_range_when_the_cores_are_taken(pair, monkeypatch, cores) -> None:
    """Session 21: with as many row ranges as cores, the side task (the claim's boundary
    keys) runs once, after the range that ends first, and the caller's thread takes a
    range (no pool of three threads beside an idle caller); the checks are the one-call
    result and the side task's result comes back."""
    import threading

    import hammesh.threads as row_threads
    from hammesh.verify import certificate

    _, h = pair
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 7)
    monkeypatch.setattr(row_threads.os, "cpu_count", lambda: cores)
    one = certify_all(h.points, h.triangles, h.components)
    ran: list = []
    real = _kernels.certify_row_range

    def spy(*a):
        ran.append(threading.get_ident())
        return real(*a)

    monkeypatch.setattr(certificate._kernels, "certify_row_range", spy)
    sides: list = []
    empty = np.empty(0, dtype=np.int64)
    used = np.zeros(len(h.points), dtype=bool)
    split, got = certificate._certify_rows(h.points, h.triangles, h.components, empty, used,
                                           side=lambda: sides.append(1) or "keys")
    assert got == "keys" and sides == [1]
    assert len(ran) == cores and threading.get_ident() in ran
    for name in ("bad_index", "bad_consecutive", "bad_pair", "cross_run", "argmin", "argmax", "bad_orientation"):
        assert getattr(split, name) == getattr(one, name), name
    assert np.isclose(split.total_area, one.total_area, rtol=1e-12)
    assert np.array_equal(used, np.bincount(h.triangles.ravel(), minlength=len(h.points)) > 0)


def test_threaded_certificate_names_the_bad_row(pair, monkeypatch) -> None:
    import hammesh.threads as row_threads

    _, h = pair
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 5)
    tri = h.triangles.copy()
    k = 2 * len(tri) // 3
    tri[[k, k + 5]] = tri[[k + 5, k]]
    with pytest.raises(hammesh.VerificationError, match=f"breaks at triangle {k - 1}"):
        verify(replace(h, triangles=tri))


def test_nearly_flat_inverted_triangle_is_caught_exactly() -> None:
    """Float area says counter-clockwise, the exact predicate says clockwise: rejected."""
    from hammesh.predicates import orient
    from hammesh.verify import _kernels

    rng = np.random.default_rng(1)
    for _ in range(200_000):  # a nearly flat triangle whose rounded area has the wrong sign
        y = rng.uniform(0.5, 24, 3)
        p = np.c_[y, y + rng.integers(-3, 4, 3) * 2.0**-48]
        (ax, ay), (bx, by) = p[1] - p[0], p[2] - p[1]
        if ax * by - ay * bx > 0 and orient(*p[0], *p[1], *p[2]) < 0:
            break
    else:
        pytest.fail("no test triangle found")
    tri = np.array([[0, 1, 2]] * 3)
    res = _kernels.certify_row_range(
        p, tri, np.array([3]), np.empty(0, np.int64), 0, 3, np.zeros(3, bool), np.empty(0, bool)
    )
    assert res.min_area > 0  # the floating-point area is positive ...
    assert res.bad_orientation == 0  # ... and the exact test flags row 0


def test_degenerate_row_is_a_verification_error(pair) -> None:
    """A row with a repeated vertex (zero-length sides) is reported, not a ZeroDivisionError."""
    _, h = pair
    tri = h.triangles.copy()
    tri[5] = [tri[5, 0], tri[5, 0], tri[5, 1]]
    with pytest.raises(hammesh.VerificationError):
        verify(replace(h, triangles=tri))
    res = certify_all(h.points, tri, h.components)
    assert res.bad_orientation == 5  # flagged by the exact orientation test


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_each_mode_hands_the_certificate_a_claim_it_accepts(monkeypatch, mode: str) -> None:
    """Issue 13 item 3: both constructions hand the certificate their output pairing as a
    claim, which it checks (one read per half-edge) instead of finding the pairing by
    its own bucket matching; a claim that failed its checks would fall back to that."""
    m = hammesh.quality_mesh(hammesh.Domain.from_polygon(square(0, 0, 1), holes=[square(0.4, 0.4, 0.2)]),
                             min_angle=30, max_area=0.002)

    def no_matching(*args):
        raise AssertionError("the certificate matched the output's half-edges itself")

    monkeypatch.setattr(_kernels, "half_edge_twins", no_matching)
    h = hammesh.hamiltonian(m, mode=mode)
    assert h.report["verified"] and h.n_triangles > m.n_triangles
    with pytest.raises(AssertionError, match="matched the output's half-edges itself"):
        verify(h, reference=m)  # the public entry takes no claim: it pairs by itself


def test_claims_boundary_made_beside_the_rows_is_used_only_if_the_claim_passes(monkeypatch) -> None:
    """Session 13: without ``prepared`` (sparse mode) the certificate finds the claim's
    boundary keys beside its row checks. A claim that fails its checks must not lend
    them: a bogus boundary from the claim is ignored then (and trusted only with a
    claim that passes, as the certificate's own function of a checked pairing)."""
    from hammesh.verify import certificate as cert
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import sparse_hamiltonian
    from hammesh.verify.reference import input_facts

    m = hammesh.quality_mesh(hammesh.Domain.from_polygon(square(0, 0, 1), holes=[square(0.4, 0.4, 0.2)]),
                             min_angle=30, max_area=0.002, isolate=False)  # (no kernel warm-up thread)
    clean, he, is_con = prepare_mesh(m)
    h, claim = sparse_hamiltonian(clean, he, is_con)
    facts = input_facts(m)
    seen = []
    real = cert.claim_structure

    def bogus(tri, c):  # (the keys of one boundary edge too few)
        seen.append(len(c))
        return {"boundary": real(tri, c)["boundary"][1:]}

    monkeypatch.setattr(cert, "claim_structure", bogus)
    with pytest.raises(hammesh.VerificationError, match="boundary changed"):
        cert.certify(h, facts, claim=claim)  # a passing claim: its (here bogus) keys are used
    broken = claim.copy()
    inner = np.flatnonzero(broken >= 0)
    broken[inner[0]], broken[inner[1]] = broken[inner[1]], broken[inner[0]]  # no longer an involution
    stats = cert.certify(h, facts, claim=broken)  # its keys ignored: the certificate pairs by itself
    assert stats["min_angle_output_deg"] > 0 and seen.count(3 * h.n_triangles) == 2
