import time

import numpy as np

from hammesh import polygon
from tests.polygon import brute, shapes


def test_square_and_collinear_vertices():
    assert polygon.visibility_graph([[0, 0], [1, 0], [1, 1], [0, 1]]).tolist() == [[0, 2], [1, 3]]
    # 0-3 passes through the reflex vertex 2: not a visibility edge
    assert polygon.visibility_graph([[0, 0], [2, 0], [1, 1], [2, 2], [0, 2]]).tolist() == [[0, 2], [2, 4]]
    # straight-angle vertices 1 and 4: 0-2 and 3-5 run along edges
    got = polygon.visibility_graph([[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [0, 1]]).tolist()
    assert got == [[0, 3], [0, 4], [1, 3], [1, 4], [1, 5], [2, 4], [2, 5]]


def test_convex_polygon_sees_everything():
    n = 12
    e = polygon.visibility_graph(shapes.regular(n))
    assert len(e) == n * (n - 3) // 2


def test_matches_brute_force_on_random_grid_polygons():
    rng = np.random.default_rng(7)
    done = 0
    for _ in range(150):
        n = int(rng.integers(3, 13))
        p = brute.random_simple_polygon(rng, n, grid=int(rng.integers(3, 25)))
        if p is None:
            continue
        got = {tuple(e) for e in polygon.visibility_graph(p).tolist()}
        assert got == brute.visibility_pairs(p), p
        done += 1
    assert done > 100


def test_two_thousand_vertices_in_a_few_seconds():
    p = shapes.star(2000, seed=3)
    polygon.visibility_graph(shapes.star(50))  # compile
    t = time.perf_counter()
    e = polygon.visibility_graph(p)
    assert time.perf_counter() - t < 5.0
    assert len(e) > 2000 and e.min() >= 0 and e.max() < 2000
