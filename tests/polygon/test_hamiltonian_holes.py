import numpy as np
import pytest

from hammesh import polygon
from hammesh.errors import InvalidOptionError
from tests.polygon import brute, checks, shapes

SQUARE = np.array([[0, 0], [6, 0], [6, 6], [0, 6]], float)
TRI = [np.array([[1, 1], [2, 1], [1.5, 2]]), np.array([[4, 4], [5, 4], [4.5, 5]]),
       np.array([[4, 1], [5, 1], [4.5, 2]])]


def _check(outer, holes, T, kind):
    Q = np.vstack([outer, *holes]).astype(float)
    checks.assert_triangulates_domain([outer, *holes], Q, T)
    assert len(T) == len(Q) + 2 * len(holes) - 2
    checks.assert_dual_path(T, cycle=kind == "cycle")


@pytest.mark.parametrize("kind", ["path", "cycle"])
@pytest.mark.parametrize("nholes", [1, 2, 3])
def test_square_with_triangular_holes(kind, nholes):
    holes = TRI[:nholes]
    T = polygon.hamiltonian_triangulation_holes(SQUARE, holes, kind)
    if T is not None:
        _check(SQUARE, holes, T, kind)
    if kind == "path":   # these have one (found by the search, certified above)
        assert T is not None


def test_agrees_with_theorem_21_without_holes():
    rng = np.random.default_rng(22)
    done = 0
    for _ in range(40):
        p = brute.random_simple_polygon(rng, int(rng.integers(4, 10)), grid=12)
        if p is None:
            continue
        p = np.array(p, float)
        T = polygon.hamiltonian_triangulation_holes(p, [])
        assert (T is not None) == polygon.is_hamiltonian(p)
        if T is not None:
            _check(p, [], T, "path")
        done += 1
    assert done > 25
    assert polygon.hamiltonian_triangulation_holes(shapes.comb(3), []) is None


def test_size_limit_points_to_steiner():
    with pytest.raises(InvalidOptionError, match="limited to 16 vertices.*steiner_hamiltonian"):
        polygon.hamiltonian_triangulation_holes(shapes.regular(12), [shapes.regular(5, 0.5)])
    with pytest.raises(InvalidOptionError, match="kind must be one of"):
        polygon.hamiltonian_triangulation_holes(SQUARE, [], kind="tour")
