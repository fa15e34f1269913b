import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import polygon
from hammesh.errors import InvalidOptionError
from tests.polygon import brute, checks, shapes


def _check(points, res):
    Q, T = res.points, res.triangles
    checks.assert_triangulates(points, Q, T, steiner=True)
    checks.assert_dual_path(T, cycle=res.kind == "cycle")
    n = len(points)
    assert len(Q) == n + res.n_steiner
    # every Steiner point is used, and lies inside the polygon (it is a vertex of
    # triangles that tile the polygon)
    assert set(range(n, len(Q))) <= set(T.ravel().tolist())
    if res.k > 1:
        assert res.n_steiner == res.k - (1 if res.kind == "cycle" else 2)
    else:
        assert res.n_steiner == (1 if res.kind == "cycle" else 0)
    # the pieces are convex and partition the vertices' polygon area
    area = sum(abs(brute.signed_area2([tuple(points[v]) for v in piece])) for piece in res.pieces)
    assert area == abs(brute.signed_area2([tuple(v) for v in np.asarray(points, float)]))
    for piece in res.pieces:
        q = [tuple(points[v]) for v in piece]
        assert all(brute.orient(q[i - 1], q[i], q[(i + 1) % len(q)]) >= 0 for i in range(len(q)))


@pytest.mark.parametrize("kind", ["cycle", "path"])
def test_two_convex_pieces(kind):
    p = np.array([[0, 0], [2, 0], [2, 2], [1, 1], [0, 2]], float)
    res = polygon.steiner_hamiltonian_result(p, kind)
    _check(p, res)
    Q, T = polygon.steiner_hamiltonian(p, kind=kind)
    assert np.array_equal(Q, res.points) and np.array_equal(T, res.triangles)


@pytest.mark.parametrize("kind", ["cycle", "path"])
@pytest.mark.parametrize("n", [3, 4, 7])
def test_convex_polygon(kind, n):
    p = shapes.regular(n)
    res = polygon.steiner_hamiltonian_result(p, kind)
    assert res.k == 1
    _check(p, res)


@pytest.mark.parametrize("teeth", [2, 3, 4, 5, 6])
@pytest.mark.parametrize("kind", ["cycle", "path"])
def test_figure7_comb(teeth, kind):
    p = shapes.comb(teeth)
    res = polygon.steiner_hamiltonian_result(p, kind)
    _check(p, res)
    # Minimum convex decomposition by diagonals: the 2 (teeth - 1) reflex vertices lie
    # on one line, so only the two across an inner tooth see each other; every reflex
    # vertex ends a diagonal, hence at least (teeth - 2) + 2 diagonals, teeth + 1 pieces
    # (the base with straight angles at the inner teeth, and the teeth).
    assert res.method == "optimal"
    assert res.k == teeth + 1
    assert res.n_steiner == (teeth if kind == "cycle" else teeth - 1)
    hm = polygon.steiner_hamiltonian_result(p, kind, decomposition="hertel-mehlhorn")
    _check(p, hm)
    assert hm.method == "hertel-mehlhorn" and hm.k == 3 * (teeth - 1)
    if teeth >= 3:
        # needed: without Steiner points there is no Hamiltonian path at all
        assert polygon.hamiltonian_triangulation(p) is None


@pytest.mark.parametrize("kind", ["cycle", "path"])
def test_straight_angles_at_both_ends_of_the_root(kind):
    # a rectangle with two rectangular teeth: the optimal base piece has straight
    # angles at every diagonal end, so it must not be fanned from any of them
    p = np.array([[0, 0], [7, 0], [7, 1], [6, 1], [6, 3], [5, 3], [5, 1], [2, 1], [2, 3],
                  [1, 3], [1, 1], [0, 1]], float)
    res = polygon.steiner_hamiltonian_result(p, kind)
    _check(p, res)
    assert res.method in ("optimal", "optimal-strict")


def test_decomposition_option():
    p = shapes.comb(3)
    assert len(polygon.convex_decomposition(p)) == 4
    assert len(polygon.convex_decomposition(p, decomposition="hertel-mehlhorn")) == 6
    with pytest.raises(InvalidOptionError, match="decomposition must be one of"):
        polygon.steiner_hamiltonian(p, decomposition="keil")
    # the minimum at any size (Keil's dynamic program), never more pieces than H-M
    star = shapes.star(60)
    res = polygon.steiner_hamiltonian_result(star, "path", decomposition="optimal")
    assert res.method in ("optimal", "optimal-strict")
    hm = polygon.steiner_hamiltonian_result(star, "path", decomposition="hertel-mehlhorn")
    assert hm.method == "hertel-mehlhorn" and res.k <= hm.k


def test_sheared_comb():
    # a sheared comb: no more horizontal collinearities
    p = shapes.comb(3) @ np.array([[1, 0.01], [0, 1]])
    res = polygon.steiner_hamiltonian_result(p, "path")
    _check(p, res)


def test_unknown_kind():
    with pytest.raises(InvalidOptionError, match="kind must be one of 'cycle', 'path'"):
        polygon.steiner_hamiltonian(shapes.regular(5), kind="tour")


def test_random_polygons():
    rng = np.random.default_rng(21)
    done = 0
    for _ in range(50):
        p = brute.random_simple_polygon(rng, int(rng.integers(3, 16)), grid=int(rng.integers(4, 40)))
        if p is None:
            continue
        p = np.array(p, float)
        for kind in ("cycle", "path"):
            _check(p, polygon.steiner_hamiltonian_result(p, kind))
        done += 1
    assert done > 35


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(3, 14), kind=st.sampled_from(["cycle", "path"]))
def test_random_polygons_hypothesis(seed, n, kind):
    p = brute.random_simple_polygon(np.random.default_rng(seed), n, grid=30, tries=20)
    if p is not None:
        p = np.array(p, float)
        _check(p, polygon.steiner_hamiltonian_result(p, kind))


@pytest.mark.parametrize("kind", ["cycle", "path"])
def test_clockwise_and_large(kind):
    p = shapes.star(400, seed=2)[::-1]
    res = polygon.steiner_hamiltonian_result(p, kind)
    Q, T = res.points, res.triangles
    assert np.array_equal(Q[:400], p)
    checks.assert_dual_path(T, cycle=kind == "cycle")
    a = Q[T]
    cross = ((a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1])
             - (a[:, 1, 1] - a[:, 0, 1]) * (a[:, 2, 0] - a[:, 0, 0]))
    assert (cross > 0).all()
    assert np.isclose(cross.sum() / 2, polygon.validate_polygon(p).area)
