"""Per-tile Hamiltonian cycles joined across separators (issue 15 step 2)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.parallel.run import parallel_hamiltonian
from tests.helpers import angles_deg, assert_cycles, dual_pieces, signed_areas
from tests.parallel.test_tiles import _pieces_domain


def _domain_area(dom, q, a):
    m = hammesh.quality_mesh(dom, min_angle=q, max_area=a, isolate=False)
    return np.abs(signed_areas(m.points, m.triangles)).sum()


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_demo_tiles_joined_into_one_certified_cycle(mode):
    dom = hammesh.read_domain("hammesh/data/demo.poly")
    h = parallel_hamiltonian(dom, min_angle=30, max_area=1e-3, tiles=3, mode=mode)
    rep = h.report
    assert rep["verified"] is True
    par = rep["parallel"]
    assert par["tiles"] == 3 and par["pieces"] == 1
    assert par["joins"] == par["tile_cycles"] - 1 >= 2
    assert par["joins_not_whole"] == 0  # every bridge between whole triangles: Thm 2.4's bound
    # independent of the certificate
    assert len(h.components) == 1
    assert_cycles(h)
    assert dual_pieces(h.triangles) == 1
    assert (signed_areas(h.points, h.triangles) > 0).all()
    assert signed_areas(h.points, h.triangles).sum() == pytest.approx(_domain_area(dom, 30, 1e-3), rel=1e-9)
    assert angles_deg(h.points, h.triangles).min() >= 15.0 * (1 - 1e-9)
    np.testing.assert_array_equal(h.points[: len(dom.vertices)], dom.vertices)
    # regional attributes travel with the triangles (the demo's two regions)
    assert set(np.unique(h.triangle_attributes[:, 0]).tolist()) == {1.0, 2.0}


def test_several_pieces_get_one_cycle_each():
    dom = _pieces_domain()
    h = parallel_hamiltonian(dom, min_angle=28, max_area=1e-3, tiles=4)
    assert h.report["verified"] is True
    assert len(h.components) == 2 == dual_pieces(h.triangles)
    assert_cycles(h)
    assert signed_areas(h.points, h.triangles).sum() == pytest.approx(_domain_area(dom, 28, 1e-3), rel=1e-9)


def test_one_tile_is_the_plain_pipeline():
    dom = hammesh.read_domain("hammesh/data/demo.poly")
    h = parallel_hamiltonian(dom, min_angle=30, max_area=2e-3, tiles=1)
    assert h.report["parallel"]["joins"] == 0
    assert len(h.components) == 1
    assert_cycles(h)


def test_swap_min_angles_of_a_square_and_of_a_reflex_quad():
    from hammesh.parallel.joins import _swap_min_angles

    # t = a b c, u = b a d on the unit square's diagonal a-b: flipping gives two 45-45-90
    t = np.array([[[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],    # a, b, c
                  [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]])
    d = np.array([[1.0, 0.0], [3.0, 2.0]])  # second: reflex at b, the flip is not legal
    got = _swap_min_angles(t, d)
    assert np.isclose(got[0], 45.0) and got[1] == 0.0


@settings(max_examples=80, deadline=None)
@given(st.lists(st.floats(-2, 2, allow_nan=False), min_size=4, max_size=4))
def test_bridge_min_angles_are_the_six_triangles_and_keep_half_the_parents(coords):
    """Thm 2.4's bridge over ab of t = abc, u = bad: its six triangles' smallest angle,
    recomputed here from the incenters, and at least half of t's and u's smallest."""
    from hammesh.parallel.joins import _bridge_min_angles

    a, b = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    c = np.array([coords[0], 0.2 + abs(coords[1])])   # above ab: t = abc counter-clockwise
    d = np.array([coords[2], -0.2 - abs(coords[3])])  # below: u = bad counter-clockwise

    def incenter(p, q, r):
        w = np.array([np.linalg.norm(q - r), np.linalg.norm(r - p), np.linalg.norm(p - q)])
        return (w[0] * p + w[1] * q + w[2] * r) / w.sum()

    def smallest(p, q, r):
        out = []
        for x, y, z in ((p, q, r), (q, r, p), (r, p, q)):
            u, v = y - x, z - x
            out.append(np.degrees(np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1))))
        return min(out)

    it, iu = incenter(a, b, c), incenter(b, a, d)
    six = [(it, c, a), (it, a, iu), (iu, a, d), (iu, d, b), (iu, b, it), (it, b, c)]
    want = min(smallest(*x) for x in six)
    got = _bridge_min_angles(np.array([[a, b, c]]), np.array([d]))[0]
    assert np.isclose(got, want, atol=1e-7)
    assert got >= 0.5 * min(smallest(a, b, c), smallest(b, a, d)) - 1e-9


def _edges_within_numpy(tri, k):
    rows, slots = [], []
    for s in range(3):
        a, b = tri[:, s], tri[:, (s + 1) % 3]
        near = np.flatnonzero((a < k) & (b < k))
        rows.append(near)
        slots.append(np.full(len(near), s))
    return np.concatenate(rows), np.concatenate(slots)


def test_edges_within_match_numpy_masks():
    """``edges_within_into`` finds the same rows and slots as numpy's masks over the
    columns (row by row; ``border_rows`` sorts them slot by slot), and counts them
    when its arrays are too short."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from hammesh.parallel._kernels import edges_within_into

    @settings(max_examples=60, deadline=None)
    @given(st.integers(0, 400), st.integers(1, 60), st.integers(0, 2**31 - 1))
    def check(m, n, seed):
        tri = np.random.default_rng(seed).integers(0, n, (m, 3)).astype(np.int64)
        k = int(np.random.default_rng(seed + 1).integers(0, n + 1))
        count = edges_within_into(tri, k, np.zeros(0, np.int64), np.zeros(0, np.int64))
        rows, slots = np.empty(count, np.int64), np.empty(count, np.int64)
        assert edges_within_into(tri, k, rows, slots) == count
        order = np.argsort(slots, kind="stable")
        want_rows, want_slots = _edges_within_numpy(tri, k)
        assert np.array_equal(rows[order], want_rows) and np.array_equal(slots[order], want_slots)
        assert np.array_equal(np.lexsort((slots, rows)), np.arange(count))  # row by row

    check()


def test_outcome_size_computes_nothing():
    """Dask's size of a tile's outcome counts the arrays held and never computes the
    Hamiltonian mesh's neighbours (a cached property: 1.3 s per 9M rows, unused)."""
    from hammesh.parallel.run import _outcome_nbytes, tile_task
    from hammesh.parallel.tiles import decompose

    d = decompose(hammesh.read_domain("hammesh/data/demo.poly"), min_angle=30, max_area=4e-3, n_tiles=2)
    out = tile_task(d.tiles[0], d.n_input, 30, 4e-3, "incircle", 0.9, keep_mesh=True)
    size = _outcome_nbytes(out)
    assert "neighbors" not in vars(out.ham)
    held = sum(a.nbytes for m in (out.mesh, out.ham) for a in vars(m).values() if isinstance(a, np.ndarray))
    assert size <= 1000 + held
    assert size >= out.ham.triangles.nbytes + out.mesh.triangles.nbytes + out.mesh.neighbors.nbytes
