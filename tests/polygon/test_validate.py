import numpy as np
import pytest

from hammesh import polygon
from hammesh.errors import HammeshError, InvalidDomainError

FUNCS = [polygon.hamiltonian_triangulation, polygon.sequential_triangulation,
         polygon.steiner_hamiltonian, polygon.visibility_graph]


@pytest.mark.parametrize("func", FUNCS)
@pytest.mark.parametrize("points, match", [
    ([[0, 0], [1, 1], [1, 0], [0, 1]], "not a simple polygon: edges 0 and 2 cross"),
    ([[0, 0], [1, 0]], "at least 3 vertices, got 2"),
    ([[0, 0], [1, 0], [1, 1], [1, 0]], "repeated vertices: vertices 1 and 3"),
    ([[0, 0], [1, 0], [2, 0]], "zero area"),
    ([[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]], "edge 0 passes through vertex 3"),
    ([[0, 0], [2, 0], [1, 0], [1, 1]], "edges 0 and 1 overlap"),
    ([[0, 0], [1, np.nan], [1, 1]], "non-finite"),
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], r"shape \(n, 2\)"),
])
def test_invalid_polygons_name_the_problem(func, points, match):
    with pytest.raises(InvalidDomainError, match=match) as info:
        func(points)
    assert isinstance(info.value, HammeshError) and isinstance(info.value, ValueError)
    assert "\n" not in str(info.value)


def test_clockwise_and_counter_clockwise_inputs_give_the_same_answer():
    p = np.array([(0, 0), (4, 0), (4, 3), (2, 1), (0, 3)], float)
    for q in (p, p[::-1]):
        T = polygon.hamiltonian_triangulation(q)
        assert T is not None and T.max() < 5
        a = q[T]
        cross = ((a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1])
                 - (a[:, 1, 1] - a[:, 0, 1]) * (a[:, 2, 0] - a[:, 0, 0]))
        assert (cross > 0).all()
