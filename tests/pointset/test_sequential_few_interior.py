"""Lemma 4.2: sequential triangulations of sets with at most two interior points."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import InvalidOptionError
from hammesh.pointset import (
    NotConstructed,
    convex_hull,
    lemma42_plan,
    few_interior_sequential,
    search_sequential,
    sequential_triangulation,
    verify_point_triangulation,
)
from hammesh.pointset.sequential_search import check_sequential

SEEDS = st.integers(0, 2**32 - 1)


def _assert_sequential(pts, tri):
    """Triangulates the set, consecutive rows share an edge, Thm 4.3 accepts it in this order."""
    verify_point_triangulation(pts, tri, "path")
    check_sequential(pts, tri)  # Thm 4.3 (hammesh.strips.sequential_order) accepts it
    # alternating turns: the shared edges (v_{i+1}, v_{i+2}) of consecutive rows never
    # meet three times at one vertex
    shared = [set(tri[t]) & set(tri[t + 1]) for t in range(len(tri) - 1)]
    for e0, e1, e2 in zip(shared, shared[1:], shared[2:]):
        assert not (e0 & e1 & e2)


def _general(rng, h, k):
    """``h`` points on an ellipse and ``k`` interior points: general position (a.s.)."""
    ang = np.sort(rng.random(h)) * 2 * np.pi
    hull = np.c_[np.cos(ang), np.sin(ang)] * [rng.uniform(0.2, 3.0), 1.0]
    inner = [rng.dirichlet(np.ones(3)) @ hull[rng.choice(h, 3, replace=False)] for _ in range(k)]
    return np.vstack([hull, *inner]) if inner else hull


def _lattice_corners(rng, h):
    """Strictly convex integer polygon with at most ``h`` corners (sorted edge vectors)."""
    while True:
        v = rng.integers(-30, 31, (h - 1, 2))
        v = v[(v != 0).any(axis=1)]
        v = np.vstack([v, -v.sum(axis=0)])
        if (v[-1] == 0).all():
            continue
        v = v[np.argsort(np.arctan2(v[:, 1], v[:, 0]), kind="stable")]
        merged: list[np.ndarray] = []
        for w in v:  # merge parallel edge vectors of the same direction
            if merged and merged[-1][0] * w[1] - merged[-1][1] * w[0] == 0 and merged[-1] @ w > 0:
                merged[-1] = merged[-1] + w
            else:
                merged.append(w.copy())
        if len(merged) >= 3:
            first, last = merged[0], merged[-1]
            if not (first[0] * last[1] - first[1] * last[0] == 0 and first @ last > 0):
                break
    v = np.array(merged)
    return np.cumsum(v, axis=0) - v[0]


def _degenerate(rng, h, max_run, kind):
    """Exactly degenerate sets on an integer lattice (coordinates are exact in float64).

    ``kind`` 0: collinear hull points (runs of up to ``max_run`` points on hull edges)
    plus 1-2 interior points; 1: an interior point at the midpoint of two hull corners
    (collinear with them); 2: two interior points on the segment between two hull
    corners (a line through hull vertices).
    """
    scale = 6 * int(np.lcm.reduce(np.arange(1, max_run + 2)))
    C = _lattice_corners(rng, h) * scale
    m = len(C)
    pts = []
    for e in range(m):
        a, b = C[e], C[(e + 1) % m]
        run = int(rng.integers(0, max_run + 1)) if kind == 0 else 0
        pts.append(a)
        pts += [a + (b - a) * t // (run + 1) for t in range(1, run + 1)]
    a, b = rng.choice(m, 2, replace=False)
    if kind == 1:
        inner = [(C[a] + C[b]) // 2]
        if rng.random() < 0.5:
            inner.append(np.round(rng.dirichlet(np.ones(3)) @ C[rng.choice(m, 3, replace=False)]))
    elif kind == 2:
        inner = [(2 * C[a] + C[b]) // 3, (C[a] + 2 * C[b]) // 3]
    else:
        inner = [np.round(rng.dirichlet(np.ones(3)) @ C[rng.choice(m, 3, replace=False)])
                 for _ in range(int(rng.integers(1, 3)))]
    out = np.unique(np.vstack([np.array(pts), np.array(inner)]).astype(float), axis=0)
    return out


def _interior(pts):
    return len(pts) - convex_hull(np.asarray(pts, float)).h


# -- general position: the construction always applies --------------------------


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 198), st.integers(1, 2), SEEDS)
def test_general_position_is_constructed(h, k, seed):
    pts = _general(np.random.default_rng(seed), h, k)
    plan = lemma42_plan(pts)
    assert plan.source in ("paper", "quad-fan")
    assert set(pts_i for pts_i in plan.strip) == set(range(len(pts)))
    tri = few_interior_sequential(pts)
    assert len(tri) == 2 * len(pts) - h - 2
    _assert_sequential(pts, tri)
    assert np.array_equal(sequential_triangulation(pts), tri)


def test_every_case_of_the_proof_occurs_and_is_constructed():
    rng = np.random.default_rng(2024)
    seen: dict[str, int] = {}
    for _ in range(400):
        h, k = int(rng.integers(3, 14)), int(rng.integers(1, 3))
        pts = _general(rng, h, k)
        plan = lemma42_plan(pts)
        seen[plan.case] = seen.get(plan.case, 0) + 1
        if plan.case == "two/1":
            assert plan.source == "paper" and len(plan.core) == 3  # the triangle
        if plan.case == "two/2":
            assert plan.source == "paper" and len(plan.core) == 4  # the quadrilateral
        if plan.case == "two/3":
            assert plan.source == "paper"  # the quadrilateral, maybe with one neighbour
        _assert_sequential(pts, few_interior_sequential(pts))
    assert {"one", "two/1", "two/2", "two/3", "two/4"} <= set(seen), seen


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 8), st.integers(1, 2), SEEDS)
def test_agrees_with_the_exact_search_in_general_position(h, k, seed):
    pts = _general(np.random.default_rng(seed), h, k)
    assert search_sequential(pts) is not None
    _assert_sequential(pts, few_interior_sequential(pts))


# -- degenerate input ---------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 60), st.integers(0, 4), st.integers(0, 2), SEEDS)
def test_degenerate_sets_are_certified_or_refused_clearly(h, max_run, kind, seed):
    pts = _degenerate(np.random.default_rng(seed), h, max_run, kind)
    if _interior(pts) == 0 or _interior(pts) > 2 or len(pts) > 200:
        return
    try:
        tri = few_interior_sequential(pts)
    except NotConstructed as exc:
        assert "general position" in str(exc)
        if len(pts) > 12:
            with pytest.raises(InvalidOptionError, match="cannot decide"):
                sequential_triangulation(pts)
        return
    _assert_sequential(pts, tri)


@pytest.mark.parametrize("kind", [1, 2])
def test_interior_points_on_lines_through_hull_vertices_up_to_200(kind):
    """Strictly convex hulls with interior points on chords: constructed (fan cores)."""
    rng = np.random.default_rng(kind)
    done = 0
    for _ in range(30):
        pts = _degenerate(rng, int(rng.integers(3, 200)), 0, kind)
        if _interior(pts) in (1, 2) and len(pts) <= 200:
            _assert_sequential(pts, few_interior_sequential(pts))
            done += 1
    assert done >= 20


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 7), st.integers(0, 3), st.integers(0, 2), SEEDS)
def test_degenerate_agrees_with_the_exact_search(h, max_run, kind, seed):
    pts = _degenerate(np.random.default_rng(seed), h, max_run, kind)
    if len(pts) > 10 or _interior(pts) > 2:
        return
    exact = search_sequential(pts)
    try:
        plan = lemma42_plan(pts)
    except NotConstructed:
        plan = None
    if plan is not None and plan.strip:
        assert exact is not None  # the construction is sound
    if plan is not None and not plan.strip:
        assert exact is None  # convex position: the zigzag test is exact
    got = sequential_triangulation(pts)
    assert (got is None) == (exact is None)
    if got is not None:
        _assert_sequential(pts, got)


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 9), st.integers(0, 3), SEEDS)
def test_convex_position_zigzag_test_is_exact(h, max_run, seed):
    rng = np.random.default_rng(seed)
    C = _lattice_corners(rng, h) * 12
    pts = []
    for e in range(len(C)):
        a, b = C[e], C[(e + 1) % len(C)]
        run = int(rng.integers(0, max_run + 1))
        pts += [a] + [a + (b - a) * t // (run + 1) for t in range(1, run + 1)]
    pts = np.array(pts, dtype=float)
    if len(pts) > 10:
        return
    got = few_interior_sequential(pts)
    assert (got is None) == (search_sequential(pts) is None)
    if got is not None:
        _assert_sequential(pts, got)


def test_known_answers():
    square_centre = np.array([[0.0, 0], [2, 0], [2, 2], [0, 2], [1, 1]])
    with pytest.raises(NotConstructed, match="general position"):
        few_interior_sequential(square_centre)  # the centre is on both diagonals
    assert sequential_triangulation(square_centre) is None  # only the 4-fan remains
    fan3 = np.array([[0.0, 0], [1, 0], [2, 0], [3, 0], [0, 1]])  # only triangulation: a 3-fan
    _assert_sequential(fan3, few_interior_sequential(fan3))
    fan4 = np.array([[0.0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [0, 1]])  # only a 4-fan: none
    assert few_interior_sequential(fan4) is None
    assert search_sequential(fan4) is None


def test_more_than_two_interior_points():
    pts = np.vstack([_general(np.random.default_rng(0), 12, 0), [[0.1, 0.1], [0.2, -0.1], [-0.1, 0.3]]])
    with pytest.raises(NotConstructed, match="at most two"):
        few_interior_sequential(pts)
    with pytest.raises(InvalidOptionError, match="cannot decide"):
        sequential_triangulation(pts)
