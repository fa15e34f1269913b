import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import polygon
from tests.polygon import brute, checks, shapes


def _check(points, T):
    checks.assert_triangulates(points, points, T)
    checks.assert_dual_path(T)
    checks.assert_two_ears(points, T)


@pytest.mark.parametrize("n", [3, 4, 5, 8, 17, 60])
def test_convex_polygons_are_always_hamiltonian(n):
    p = shapes.regular(n)
    T = polygon.hamiltonian_triangulation(p)
    _check(p, T)
    assert polygon.is_hamiltonian(p)


def test_figure3_like_polygon_is_not_hamiltonian():
    p = shapes.FIGURE3
    # the properties of Figure 3: unique triangulation, star-shaped, monotone
    tris = brute.all_triangulations([tuple(v) for v in p])
    assert len(tris) == 1 and not brute.is_hamiltonian(tris[0])
    centre = (0.0, 0.0)
    assert all(brute.orient(p[i], p[(i + 1) % 6], centre) > 0 for i in range(6))
    assert _is_monotone_somewhere(p)
    assert polygon.hamiltonian_triangulation(p) is None
    assert not polygon.is_hamiltonian(p)


def _is_monotone_somewhere(p):
    for a in np.linspace(0, np.pi, 360, endpoint=False):
        h = p @ np.array([np.cos(a), np.sin(a)])
        up = np.sign(np.roll(h, -1) - h)
        if np.all(up != 0) and np.count_nonzero(up != np.roll(up, 1)) == 2:
            return True
    return False


def test_comb_with_three_teeth_has_none():
    assert polygon.hamiltonian_triangulation(shapes.comb(2)) is not None
    assert polygon.hamiltonian_triangulation(shapes.comb(3)) is None


def _agree(p):
    tris = brute.all_triangulations(p)
    expected = any(brute.is_hamiltonian(t) for t in tris)
    T = polygon.hamiltonian_triangulation(p)
    assert (T is not None) == expected, p
    if T is not None:
        _check(p, T)


def test_agrees_with_brute_force_on_random_polygons():
    rng = np.random.default_rng(11)
    seen = {True: 0, False: 0}
    for _ in range(200):
        n = int(rng.integers(3, 10))
        p = brute.random_simple_polygon(rng, n, grid=int(rng.integers(3, 30)))
        if p is not None:
            _agree(p)
            seen[polygon.hamiltonian_triangulation(p) is not None] += 1
    assert seen[True] > 100


def test_agrees_with_brute_force_on_non_hamiltonian_families():
    # pinwheels (3 ears around a triangle) in many shapes: a mix of yes and no
    m = shapes.regular(3, 10.0)[[0, 1, 2]]
    answers = set()
    for s in (0.9, 1.1, 1.2, 1.3, 1.5):
        for o in (0.2, 0.3, 0.5):
            pts = []
            for i in range(3):
                a, b = m[i], m[(i + 1) % 3]
                d = b - a
                pts += [tuple(np.round(a)), tuple(np.round(a + d * s + np.array([d[1], -d[0]]) * o))]
            if brute.is_simple(pts):
                _agree(pts)
                answers.add(polygon.hamiltonian_triangulation(pts) is None)
    assert answers == {True, False}


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(3, 9), grid=st.integers(3, 40))
def test_agrees_with_brute_force_hypothesis(seed, n, grid):
    p = brute.random_simple_polygon(np.random.default_rng(seed), n, grid=grid, tries=20)
    if p is not None:
        _agree(p)


@pytest.mark.parametrize("make", [shapes.star, shapes.monotone])
def test_large_random_polygons_certificate(make):
    for seed in range(3):
        p = make(300, seed=seed)
        T = polygon.hamiltonian_triangulation(p)
        if T is not None:
            _check(p, T)
