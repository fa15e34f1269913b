"""Lemma 4.2 (convex position), the exact search, and Thm 4.1's family."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import InvalidOptionError
from hammesh.mesh import Mesh
from hammesh.pointset import (
    SEARCH_LIMIT,
    convex_hull,
    convex_sequential,
    no_sequential_example,
    search_sequential,
    sequential_triangulation,
    verify_point_triangulation,
)
from hammesh.pointset.no_sequential import LABELS
from hammesh.strips import sequential_order


def _assert_sequential(pts, tri):
    verify_point_triangulation(pts, tri, "path")
    seq = sequential_order(Mesh(points=np.asarray(pts, float), triangles=tri))
    assert seq is not None


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 200), st.integers(0, 2**32 - 1))
def test_lemma42_convex_position_is_sequential(n, seed):
    ang = np.sort(np.random.default_rng(seed).choice(10**6, size=n, replace=False)) * (2 * np.pi / 10**6)
    pts = np.c_[np.cos(ang), np.sin(ang)] * [2.0, 1.0]
    tri = sequential_triangulation(pts)
    assert len(tri) == n - 2
    _assert_sequential(pts, tri)


def test_convex_with_collinear_hull_points():
    pts = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [3, 1], [0, 1]], dtype=float)
    _assert_sequential(pts, convex_sequential(pts))


@settings(max_examples=25, deadline=None)
@given(st.integers(4, 9), st.integers(0, 2**32 - 1))
def test_search_results_are_sequential(n, seed):
    pts = np.random.default_rng(seed).random((n, 2))
    tri = search_sequential(pts)
    if tri is not None:
        _assert_sequential(pts, tri)


@pytest.mark.parametrize("inner", [1, 2])
def test_small_sets_with_one_or_two_interior_points_have_one(inner):
    """Lemma 4.2's claim on small random sets."""
    rng = np.random.default_rng(inner)
    for _ in range(5):
        k = int(rng.integers(3, 8))
        ang = np.sort(rng.random(k)) * 2 * np.pi
        hull = np.c_[np.cos(ang), np.sin(ang)]
        pts = np.vstack([hull, 0.3 * (rng.random((inner, 2)) - 0.5)])
        tri = sequential_triangulation(pts)
        assert tri is not None
        _assert_sequential(pts, tri)


def test_triangle_with_interior_point_is_a_fan_of_three():
    pts = np.array([[0.0, 0], [1, 0], [0, 1], [0.2, 0.2]])
    tri = sequential_triangulation(pts)
    assert len(tri) == 3
    _assert_sequential(pts, tri)


def test_thm41_example_has_no_sequential_triangulation():
    pts = no_sequential_example(9)
    assert pts.shape == (9, 2)
    assert len(LABELS) == 9
    assert search_sequential(pts) is None
    assert sequential_triangulation(pts) is None


@pytest.mark.parametrize("n", [8, 9.5, 0, -3])
def test_thm41_bad_sizes(n):
    with pytest.raises(InvalidOptionError):
        no_sequential_example(n)


def _crosses(p, q, r, s):
    o = lambda a, b, c: np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))  # noqa: E731
    return o(p, q, r) * o(p, q, s) < 0 and o(r, s, p) * o(r, s, q) < 0


@pytest.mark.parametrize("n", [9, 10, 14, 40])
def test_thm41_family_forces_triangle_abc(n):
    """The property the proof starts from: no segment between two points crosses an edge
    of A B C (so every triangulation contains A B C), hull = the n - 3 other points."""
    pts = no_sequential_example(n)
    assert pts.shape == (n, 2)
    hull = convex_hull(pts)
    assert hull.h == n - 3 and hull.corner.all() and set(hull.boundary.tolist()) == set(range(3, n))
    for u in range(n):
        for v in range(u + 1, n):
            for a, b in ((0, 1), (1, 2), (2, 0)):
                assert not _crosses(pts[u], pts[v], pts[a], pts[b]), (u, v, a, b)


@pytest.mark.parametrize("n", [10, 11])
def test_thm41_family_has_no_sequential_triangulation(n):
    assert search_sequential(no_sequential_example(n)) is None


@pytest.mark.slow
def test_thm41_family_at_the_search_limit():
    assert search_sequential(no_sequential_example(SEARCH_LIMIT)) is None


def test_thm41_literal_extension_fails():
    """The paper's text only asks the extra points to avoid arcs E-F, G-H, I-D; a point in
    the middle of arc D-E sees G and H across A B, and the set has a sequential one."""
    base = no_sequential_example(9)
    x = 3.0 * np.array([[np.cos(1.5 * np.pi), np.sin(1.5 * np.pi)]])
    pts = np.vstack([base, x])
    assert _crosses(pts[9], pts[7], pts[0], pts[1])  # X-H crosses A-B
    tri = search_sequential(pts)
    assert tri is not None
    _assert_sequential(pts, tri)


def test_too_large_to_decide_is_a_clear_error():
    pts = np.random.default_rng(0).random((SEARCH_LIMIT + 1, 2))
    with pytest.raises(InvalidOptionError, match="cannot decide"):
        sequential_triangulation(pts)
    with pytest.raises(InvalidOptionError, match="limited to"):
        search_sequential(pts)


@pytest.mark.slow
def test_search_at_the_limit():
    pts = np.random.default_rng(3).random((SEARCH_LIMIT, 2))
    tri = search_sequential(pts)
    if tri is not None:
        _assert_sequential(pts, tri)
