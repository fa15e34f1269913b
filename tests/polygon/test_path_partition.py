import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import polygon
from hammesh.errors import InvalidMeshError
from tests.polygon import brute, shapes


def _check(points, tris, paths):
    tris = np.asarray(tris)
    rows = np.concatenate(paths)
    assert sorted(rows.tolist()) == list(range(len(tris)))
    for p in paths:
        for a, b in zip(p[:-1], p[1:]):
            assert len(set(tris[a].tolist()) & set(tris[b].tolist())) == 2
    edges = brute.dual_edges([tuple(t) for t in tris.tolist()])
    assert len(paths) == brute.min_path_partition_size(len(tris), edges)


def test_hamiltonian_triangulation_is_one_path():
    p = shapes.regular(10)
    T = polygon.hamiltonian_triangulation(p)
    paths = polygon.path_partition(p, T)
    assert len(paths) == 1 and sorted(paths[0].tolist()) == list(range(8))


def test_figure3_needs_two_paths():
    tri = brute.all_triangulations([tuple(v) for v in shapes.FIGURE3])[0]
    paths = polygon.path_partition(shapes.FIGURE3, np.array(tri))
    _check(shapes.FIGURE3, tri, paths)
    assert len(paths) == 2


def test_minimum_on_random_polygon_triangulations():
    rng = np.random.default_rng(3)
    done = 0
    for _ in range(120):
        n = int(rng.integers(3, 11))
        p = brute.random_simple_polygon(rng, n, grid=30)
        if p is None:
            continue
        tris = brute.all_triangulations(p)
        for k in rng.choice(len(tris), size=min(3, len(tris)), replace=False):
            _check(p, tris[k], polygon.path_partition(p, np.array(tris[k])))
            done += 1
    assert done > 150


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(3, 11))
def test_minimum_hypothesis(seed, n):
    rng = np.random.default_rng(seed)
    p = brute.random_simple_polygon(rng, n, grid=40, tries=20)
    if p is not None:
        tris = brute.all_triangulations(p)
        tri = tris[int(rng.integers(len(tris)))]
        _check(p, tri, polygon.path_partition(p, np.array(tri)))


def test_large_triangulation_is_linear_and_valid():
    from hammesh.polygon._triangulate import triangulate_polygon

    p = shapes.star(5000, seed=1)
    T = triangulate_polygon(p)
    paths = polygon.path_partition(p, T)
    assert sum(len(q) for q in paths) == len(T)


def test_empty_and_errors():
    pts = [[0, 0], [1, 0], [0, 1], [1, 1]]
    assert polygon.path_partition(pts, np.zeros((0, 3), int)) == []
    with pytest.raises(InvalidMeshError, match="references vertex 7"):
        polygon.path_partition(pts, [[0, 1, 7]])
    with pytest.raises(InvalidMeshError, match="shape"):
        polygon.path_partition(pts, [[0, 1]])
    with pytest.raises(InvalidMeshError, match="degenerate"):
        polygon.path_partition([[0, 0], [1, 0], [2, 0]], [[0, 1, 2]])
    # a wheel: the dual is a cycle
    wheel = [[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]]
    with pytest.raises(InvalidMeshError, match="cycle"):
        polygon.path_partition(wheel, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    with pytest.raises(InvalidMeshError, match="more than two"):
        polygon.path_partition(wheel + [[0.5, 2]], [[0, 1, 2], [1, 0, 4], [0, 1, 5]])
