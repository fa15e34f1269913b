import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import polygon
from hammesh.polygon.sequential import zigzag
from tests.polygon import brute, checks, shapes


def _check(points, S):
    checks.assert_triangulates(points, points, S)
    checks.assert_dual_path(S)
    checks.assert_two_ears(points, S)
    checks.assert_alternates(S)


@pytest.mark.parametrize("n", [3, 4, 5, 9, 40])
def test_convex_polygons_have_exactly_2n_strip_starts(n):
    p = shapes.regular(n)
    _check(p, polygon.sequential_triangulation(p))
    starts = polygon.sequential_starts(p)
    assert len(starts) == 2 * n  # every vertex, both directions


def test_zigzag_order():
    assert zigzag(6, 0, 1).tolist() == [[0, 1, 5], [1, 2, 5], [2, 4, 5], [2, 3, 4]]


def test_figure3_like_polygon_has_none():
    assert polygon.sequential_triangulation(shapes.FIGURE3) is None
    assert len(polygon.sequential_starts(shapes.FIGURE3)) == 0


def test_clockwise_input_starts_are_in_input_order():
    p = np.array([(0, 0), (4, 0), (4, 3), (2, 1), (0, 3)], float)
    a = {tuple(r) for r in polygon.sequential_starts(p).tolist()}
    n = len(p)
    b = {((n - 1 - s), -d) for s, d in polygon.sequential_starts(p[::-1]).tolist()}
    assert a == b and a


def _agree(p):
    tris = brute.all_triangulations(p)
    expected = any(brute.is_sequential(t) for t in tris)
    S = polygon.sequential_triangulation(p)
    assert (S is not None) == expected, p
    if S is not None:
        _check(p, S)
        assert polygon.hamiltonian_triangulation(p) is not None


def test_agrees_with_brute_force_on_random_polygons():
    rng = np.random.default_rng(12)
    answers = []
    for _ in range(200):
        n = int(rng.integers(3, 10))
        p = brute.random_simple_polygon(rng, n, grid=int(rng.integers(3, 30)))
        if p is not None:
            _agree(p)
            answers.append(polygon.sequential_triangulation(p) is None)
    assert 0 < sum(answers) < len(answers)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(3, 9), grid=st.integers(3, 40))
def test_agrees_with_brute_force_hypothesis(seed, n, grid):
    p = brute.random_simple_polygon(np.random.default_rng(seed), n, grid=grid, tries=20)
    if p is not None:
        _agree(p)


def test_large_monotone_polygon():
    p = shapes.monotone(400, seed=1)
    S = polygon.sequential_triangulation(p)
    if S is not None:
        _check(p, S)
