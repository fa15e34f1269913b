"""Thm 3.1 / Lemma 3.2: Hamiltonian triangulations of point sets, checked by the certificate."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hammesh.errors import HammeshError, InvalidDomainError, MeshingError, VerificationError
from hammesh.pointset import convex_hull, hamiltonian_triangulation, verify_point_triangulation
from hammesh.predicates import orient


def _check(pts, tri, convex=None):
    pts = np.asarray(pts, dtype=float)
    hull = convex_hull(pts)
    n, h = len(pts), hull.h
    assert tri.shape == (2 * n - h - 2, 3)
    assert tri.dtype == np.int64
    order = "path" if h == n else "cycle"
    if convex is not None:
        assert (h == n) == convex
    verify_point_triangulation(pts, tri, order)
    return order


coords = st.integers(-50, 50)
point_sets = st.lists(st.tuples(coords, coords), min_size=3, max_size=40, unique=True)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(3, 200), st.integers(0, 2**32 - 1))
def test_random_uniform_sets(n, seed):
    pts = np.random.default_rng(seed).random((n, 2))
    _check(pts, hamiltonian_triangulation(pts, seed=seed))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(3, 60), st.integers(0, 2**32 - 1))
def test_points_on_hull_edges_and_interior(k, seed):
    """Collinear points on every hull edge of a square plus random interior points."""
    rng = np.random.default_rng(seed)
    t = np.unique(rng.integers(1, 1000, size=k)) / 1000.0
    side = [np.c_[t, 0 * t], np.c_[1 + 0 * t, t], np.c_[1 - t, 1 + 0 * t], np.c_[0 * t, 1 - t]]
    corners = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    interior = 0.05 + 0.9 * rng.random((int(rng.integers(0, 30)), 2))
    pts = np.vstack([corners, *side, interior])
    pts = pts[rng.permutation(len(pts))]
    _check(pts, hamiltonian_triangulation(pts, seed=seed), convex=len(interior) == 0)


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 80), st.integers(0, 2**32 - 1), st.booleans())
def test_convex_position_gives_a_path(n, seed, center):
    """Co-circular points: convex position (a path); with the centre: a cycle."""
    ang = np.sort(np.random.default_rng(seed).choice(100_000, size=n, replace=False)) * (2 * np.pi / 100_000)
    pts = np.c_[np.cos(ang), np.sin(ang)]
    if center:
        pts = np.vstack([pts, [[0.0, 0.0]]])
    hull = convex_hull(pts)
    if hull.h < 3 or len(np.unique(hull.boundary)) < 3:
        return
    tri = hamiltonian_triangulation(pts, seed=seed)
    order = _check(pts, tri)
    assert order == ("cycle" if center and hull.h == n else "path") or hull.h < n


@settings(max_examples=80, deadline=None)
@given(point_sets, st.integers(0, 1000))
def test_integer_sets_with_collinearities(raw, seed):
    """Small integer sets (many collinear triples): a verified result or a clear error."""
    pts = np.array(raw, dtype=float)
    try:
        tri = hamiltonian_triangulation(pts, seed=seed)
    except InvalidDomainError:
        xs = pts - pts[0]
        assert np.all(xs[:, 0] * xs[-1, 1] - xs[:, 1] * xs[-1, 0] == 0) or len(pts) < 3
        return
    _check(pts, tri)


def _collinear(pts):
    d, e = pts[1:] - pts[0], pts[-1] - pts[0]
    return bool(np.all(d[:, 0] * e[1] - d[:, 1] * e[0] == 0))


def _grid(kx, ky):
    return np.stack(np.meshgrid(np.arange(float(kx)), np.arange(float(ky))), -1).reshape(-1, 2)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(2, 10), st.integers(2, 10), st.integers(0, 2**32 - 1))
def test_integer_grids_up_to_10x10(kx, ky, seed):
    """Grids: every interior point is on many lines through other points (issue 5)."""
    pts = _grid(kx, ky)
    if kx * ky < 3:
        return
    _check(pts, hamiltonian_triangulation(pts, seed=seed), convex=kx == 2 or ky == 2)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(3, 10), st.integers(3, 10), st.floats(0.2, 1.0), st.integers(0, 2**32 - 1))
def test_random_subsets_of_grids(kx, ky, keep, seed):
    rng = np.random.default_rng(seed)
    pts = _grid(kx, ky)
    pts = pts[rng.random(len(pts)) < keep]
    if len(pts) < 3 or _collinear(pts):
        return
    pts = pts[rng.permutation(len(pts))]
    _check(pts, hamiltonian_triangulation(pts, seed=seed))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(1, 5), st.integers(2, 12), st.integers(0, 2**32 - 1))
def test_points_on_a_few_lines(n_lines, per_line, seed):
    """Several lines through a common or random point, each holding many points."""
    rng = np.random.default_rng(seed)
    chunks = [rng.integers(-20, 21, size=(3, 2)).astype(float)]
    for _ in range(n_lines):
        a = rng.integers(-20, 21, size=2)
        d = rng.integers(-3, 4, size=2)
        if not d.any():
            d = np.array([1, 0])
        chunks.append(a + np.outer(np.arange(per_line), d))
    pts = np.unique(np.vstack(chunks), axis=0)
    if len(pts) < 3 or _collinear(pts):
        return
    _check(pts, hamiltonian_triangulation(pts, seed=seed))


def _parallel_runs(per_line: int, tilt: float, seed: int) -> np.ndarray:
    """Two runs of ``per_line`` points, nearly parallel at ``tilt``, and 3 random points."""
    rng = np.random.default_rng(seed)
    t = np.arange(per_line, dtype=float)
    a = np.c_[t, tilt * t * t / per_line]
    b = np.c_[t * np.cos(tilt), 1.0 + t * np.sin(tilt)]
    return np.unique(np.vstack([a, b, rng.random((3, 2)) * [per_line, 1.0]]), axis=0)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(5, 30), st.floats(1e-9, 0.05), st.integers(0, 2**32 - 1))
def test_nearly_collinear_runs(per_line, tilt, seed):
    """Two long nearly-parallel runs in floating point: triangles of three run points are
    positive exactly but nearly flat (their floating-point area may even be negative);
    the certificate decides them exactly."""
    pts = _parallel_runs(per_line, tilt, seed)
    _check(pts, hamiltonian_triangulation(pts, seed=seed))


@pytest.mark.parametrize("k", [5, 8, 10])
def test_grids_that_used_to_stall(k):
    pts = _grid(k, k)
    for seed in range(10):
        _check(pts, hamiltonian_triangulation(pts, seed=seed))


def test_fruitless_repairs_restart_instead_of_searching_on(monkeypatch):
    """Bounded failure mode: fruitless region searches end an attempt after its budget of
    wasted steps; MAX_ATTEMPTS such attempts are a MeshingError naming the restarts."""
    from hammesh.pointset import hamiltonian as thm31

    spent = []

    def fruitless(pts, tri, nbr, nxt, prv, lo, hi, B, n_tri, budget):
        spent.append(budget)
        return 0, B, budget

    monkeypatch.setattr(thm31, "insert_by_chain", fruitless)
    monkeypatch.setattr(thm31, "repair", lambda *a: (True, a[7]))
    bound = sum(
        thm31.WASTED_STEPS_PER_ATTEMPT * min(k + 1, 4) + thm31.CHAIN_BUDGET
        for k in range(thm31.MAX_ATTEMPTS)
    )
    pts = _grid(12, 12)  # stalls in almost every attempt
    errors = 0
    for seed in range(3):
        spent.clear()
        try:
            _check(pts, hamiltonian_triangulation(pts, seed=seed))  # an attempt that never stalled
        except MeshingError as exc:
            assert "restarts" in str(exc)
            errors += 1
        assert 0 < sum(spent) <= bound
        assert max(spent) == thm31.CHAIN_BUDGET and min(spent) == thm31.RETRY_BUDGET
    assert errors


@pytest.mark.slow
def test_nearly_parallel_runs_that_used_to_take_minutes():
    """27 + 27 points on two nearly parallel runs (tilt 3.6e-4) and 3 more: 65 fruitless
    searches (~120 s) before attempts gave up early; now a few seconds."""
    per_line, tilt, seed = 27, 0.00035868819999230713, 290117535
    pts = _parallel_runs(per_line, tilt, seed)
    _check(pts, hamiltonian_triangulation(pts, seed=seed))


@pytest.mark.slow
@pytest.mark.parametrize("k", [15, 20])
def test_larger_grids(k):
    pts = _grid(k, k)
    for seed in range(3):
        _check(pts, hamiltonian_triangulation(pts, seed=seed))


def test_small_grids_and_collinear_interior():
    g = np.stack(np.meshgrid(np.arange(3.0), np.arange(3.0)), -1).reshape(-1, 2)
    _check(g, hamiltonian_triangulation(g, seed=0))
    pts = np.array([[0, 0], [10, 0], [5, 9], [5, 1], [5, 3], [5, 5], [2, 1], [8, 1]], dtype=float)
    _check(pts, hamiltonian_triangulation(pts, seed=3))


def test_same_seed_same_output():
    pts = np.random.default_rng(5).random((500, 2))
    a = hamiltonian_triangulation(pts, seed=7)
    b = hamiltonian_triangulation(pts, seed=7)
    assert np.array_equal(a, b)


def test_count_triangle_with_interior_point_is_cycle_of_three():
    pts = np.array([[0.0, 0], [1, 0], [0, 1], [0.2, 0.2]])
    tri = hamiltonian_triangulation(pts)
    assert len(tri) == 3
    verify_point_triangulation(pts, tri, "cycle")


@pytest.mark.parametrize(
    "pts, needle",
    [
        (np.zeros((2, 2)), "at least 3 points"),
        (np.array([[0.0, 0], [1, 1], [2, 2], [3, 3]]), "one line"),
        (np.array([[0.0, 0], [1, 0], [0, 1], [1, 0]]), "points 1 and 3 are duplicates"),
        (np.array([[0.0, 0], [1, np.nan], [0, 1]]), "point 1"),
        (np.zeros((4, 3)), "shape (n, 2)"),
    ],
)
def test_bad_input_names_the_item(pts, needle):
    with pytest.raises(InvalidDomainError, match=None) as info:
        hamiltonian_triangulation(pts)
    assert needle in str(info.value)
    assert isinstance(info.value, ValueError) and isinstance(info.value, HammeshError)


def test_verifier_rejects_broken_outputs():
    pts = np.random.default_rng(2).random((30, 2))
    tri = hamiltonian_triangulation(pts, seed=1)
    with pytest.raises(VerificationError, match="cycle"):
        verify_point_triangulation(pts, np.roll(tri, 1, axis=0)[::-1][[0, 2, 1, *range(3, len(tri))]])
    bad = tri.copy()
    bad[0] = bad[0, ::-1]
    with pytest.raises(VerificationError, match="clockwise"):
        verify_point_triangulation(pts, bad)
    with pytest.raises(VerificationError, match="triangles"):
        verify_point_triangulation(pts, tri[:-1])


def test_orient_is_exact_near_degenerate():
    # classic failure of the naive float determinant
    assert orient(0.5, 0.5, 12.0, 12.0, 24.0, 24.0) == 0
    x = 0.5 + 2.0**-52
    assert orient(x, 0.5, 12.0, 12.0, 24.0, 24.0) != 0
    assert orient(0.0, 0.0, 1.0, 0.0, 0.5, 1e-300) == 1


@pytest.mark.slow
def test_one_hundred_thousand_points():
    pts = np.random.default_rng(0).random((100_000, 2))
    _check(pts, hamiltonian_triangulation(pts, seed=0))
