import numpy as np
import pytest

from hammesh import polygon
from hammesh.polygon.min_convex import minimum_convex_faces
from tests.polygon import brute, shapes


def test_matches_brute_force_on_random_polygons():
    # straight angles allowed in the pieces; Thm 2.3 may still need strictly convex ones
    rng = np.random.default_rng(7)
    done = 0
    for _ in range(30):
        p = brute.random_simple_polygon(rng, int(rng.integers(4, 9)), grid=int(rng.integers(3, 12)))
        if p is None:
            continue
        best = brute.min_convex_pieces(p)
        poly = polygon.validate_polygon(p)
        assert len(minimum_convex_faces(poly.points)) == best, p
        # the decomposition Thm 2.3 uses: the minimum unless it admits no fan tree
        res = polygon.steiner_hamiltonian_result(p, "cycle", decomposition="optimal")
        assert res.k >= best
        assert (res.k == best) == (res.method == "optimal"), (p, res.method)
        done += 1
    assert done > 20


@pytest.mark.parametrize("teeth", [2, 3])
def test_comb_matches_brute_force(teeth):
    p = shapes.comb(teeth)
    assert len(polygon.convex_decomposition(p)) == brute.min_convex_pieces(
        [tuple(v) for v in p]) == teeth + 1


def test_never_worse_than_hertel_mehlhorn():
    for seed in range(2):
        p = shapes.star(18, seed=seed)
        opt = polygon.convex_decomposition(p, decomposition="optimal")
        hm = polygon.convex_decomposition(p, decomposition="hertel-mehlhorn")
        assert len(opt) <= len(hm)
