"""Minimum convex decomposition (Keil's dynamic program) against two references.

The references share nothing with the dynamic program but the exact predicates and the
visibility graph: a brute-force enumeration of diagonal sets (``tests/polygon/brute``,
small polygons) and an integer program (``min_convex_ip``, up to 24 vertices).
"""

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import polygon
from hammesh.errors import InvalidDomainError
from hammesh.polygon.min_convex import (
    faces_from_diagonals,
    minimum_convex_diagonals,
    minimum_convex_faces,
)
from hammesh.polygon.min_convex_ip import MAX_VERTICES, minimum_convex_faces_ip
from hammesh.predicates import orient_rows
from tests.polygon import brute, shapes


def _assert_convex_partition(cp, faces, straight=True):
    """The faces use every polygon edge once, are convex, and their areas add up."""
    n = len(cp)
    sides = {}
    area = 0.0
    for f in faces:
        P = cp[f]
        o = orient_rows(np.roll(P, 1, axis=0), P, np.roll(P, -1, axis=0))
        assert (o >= 0).all(), f
        if not straight:   # straight only where the polygon itself is straight
            for s in np.flatnonzero(o == 0):
                v = f[s]
                assert {f[s - 1], f[(s + 1) % len(f)]} == {(v - 1) % n, (v + 1) % n}, f
        for s in range(len(f)):
            e = (f[s], f[(s + 1) % len(f)])
            sides[e] = sides.get(e, 0) + 1
        x, y = P[:, 0], P[:, 1]
        area += 0.5 * (x @ np.roll(y, -1) - np.roll(x, -1) @ y)
    for v in range(n):
        assert sides.get((v, (v + 1) % n)) == 1
    for (u, v), c in sides.items():
        assert c == 1 and ((v - u) % n == 1 or sides.get((v, u)) == 1)
    x, y = cp[:, 0], cp[:, 1]
    assert np.isclose(area, 0.5 * (x @ np.roll(y, -1) - np.roll(x, -1) @ y))


def test_matches_brute_force_on_random_polygons():
    rng = np.random.default_rng(7)
    done = 0
    for _ in range(40):
        p = brute.random_simple_polygon(rng, int(rng.integers(4, 9)), grid=int(rng.integers(3, 12)))
        if p is None:
            continue
        best = brute.min_convex_pieces(p)
        cp = polygon.validate_polygon(p).points
        faces = minimum_convex_faces(cp)
        assert len(faces) == best, p
        _assert_convex_partition(cp, faces)
        # the decomposition Thm 2.3 uses: the minimum unless it admits no fan tree
        res = polygon.steiner_hamiltonian_result(p, "cycle", decomposition="optimal")
        assert res.k >= best
        assert (res.k == best) == (res.method == "optimal"), (p, res.method)
        done += 1
    assert done > 25


@pytest.mark.parametrize("teeth", [2, 3])
def test_comb_matches_brute_force(teeth):
    p = shapes.comb(teeth)
    assert len(polygon.convex_decomposition(p)) == brute.min_convex_pieces(
        [tuple(v) for v in p]) == teeth + 1


def _polygon(data, n):
    kind = data.draw(st.sampled_from(["grid", "star", "dented"]))
    seed = data.draw(st.integers(0, 2**32 - 1))
    if kind == "grid":   # integer coordinates: collinear and straight vertices
        p = brute.random_simple_polygon(np.random.default_rng(seed), n,
                                        grid=data.draw(st.integers(4, 3 * n)), tries=20)
        return None if p is None else np.array(p, float)
    if kind == "star":
        return shapes.star(n, seed=seed % 2**31)
    return shapes.dented(n, data.draw(st.integers(1, n // 2)), seed=seed % 2**31)


@settings(max_examples=40, deadline=None)
@given(data=st.data(), n=st.integers(4, MAX_VERTICES), straight=st.booleans())
def test_matches_integer_program(data, n, straight):
    p = _polygon(data, n)
    try:
        cp = polygon.validate_polygon(p).points
    except (InvalidDomainError, TypeError):   # None, or random radii that degenerate
        return
    ip = minimum_convex_faces_ip(cp, straight=straight)
    if ip is None:   # solver time limit
        return
    faces = minimum_convex_faces(cp, straight=straight)
    _assert_convex_partition(cp, faces, straight)
    assert len(faces) == len(ip), p.tolist()


def test_diagonals_and_faces():
    L = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    d = minimum_convex_diagonals(L)
    assert d.tolist() == [[0, 3]]
    assert faces_from_diagonals(L, d[:, 0], d[:, 1]) == [[0, 1, 2, 3], [0, 3, 4, 5]]
    sq = shapes.regular(6)
    assert minimum_convex_diagonals(sq).shape == (0, 2)
    assert minimum_convex_faces(sq) == [list(range(6))]


def test_straight_angles_at_both_ends_of_a_diagonal():
    # the piece 2..7 has straight angles at both ends of its diagonal (7, 2): 6, 7, 2, 3
    # lie on one line, so no triangle on that diagonal has a third side in the piece
    p = np.array([(2, 0), (4, 1), (3, 3), (4, 3), (2, 4), (0, 4), (0, 3), (1, 3), (0, 2)], float)
    cp = polygon.validate_polygon(p).points
    assert len(minimum_convex_faces(cp)) == 2 == brute.min_convex_pieces([tuple(v) for v in p])
    strict = minimum_convex_faces(cp, straight=False)
    _assert_convex_partition(cp, strict, straight=False)
    assert len(strict) == len(minimum_convex_faces_ip(cp, straight=False)) > 2


def test_never_worse_than_hertel_mehlhorn():
    for seed in range(3):
        p = shapes.star(80, seed=seed)
        opt = polygon.convex_decomposition(p, decomposition="optimal")
        hm = polygon.convex_decomposition(p, decomposition="hertel-mehlhorn")
        assert len(opt) <= len(hm)


@pytest.mark.parametrize("teeth, limit", [(11, 5.0), (50, 5.0), (200, 5.0)])
@pytest.mark.parametrize("kind", ["cycle", "path"])
def test_comb_steiner_count_is_minimum(teeth, limit, kind):
    """Figure 7 combs: ``k = t + 1`` pieces (its reflex vertices lie on one line, so only
    pairs across an inner tooth see each other), and Thm 2.3's count is ``k - 1`` / ``k - 2``."""
    p = shapes.comb(teeth)
    polygon.steiner_hamiltonian_result(shapes.comb(2), kind)   # compiled
    t = time.perf_counter()
    res = polygon.steiner_hamiltonian_result(p, kind)
    took = time.perf_counter() - t
    assert res.method == "optimal" and res.k == teeth + 1
    assert res.n_steiner == res.k - (1 if kind == "cycle" else 2)
    assert took <= limit, took


def test_any_size_and_few_reflex_vertices():
    p = shapes.dented(300, 20, seed=1)
    cp = polygon.validate_polygon(p).points
    r = int((orient_rows(np.roll(cp, 1, axis=0), cp, np.roll(cp, -1, axis=0)) < 0).sum())
    assert r == 20
    faces = minimum_convex_faces(cp)
    _assert_convex_partition(cp, faces)
    # every reflex vertex needs a diagonal and one diagonal serves at most two, and
    # Hertel--Mehlhorn keeps at most two per reflex vertex
    hm = polygon.convex_decomposition(p, decomposition="hertel-mehlhorn")
    assert r // 2 + 1 <= len(faces) <= len(hm) <= 2 * r + 1
