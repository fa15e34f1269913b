"""The dual cycle cover: disjoint cycles, checked independently with networkx."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh.postprocess.cycle_cover import cycle_cover
from hammesh.halfedge import half_edges
from tests.helpers import bundled_domain, hull_area


def check_cover(tri: np.ndarray, n: int) -> tuple:
    twin = half_edges(tri, n).twin
    c = cycle_cover(tri, twin)
    cov = c.is_cov
    m = len(tri)
    # symmetric, never on the boundary
    assert not cov[twin < 0].any()
    np.testing.assert_array_equal(cov[twin[cov]], True)
    deg = cov.reshape(m, 3).sum(axis=1)
    assert set(np.unique(deg).tolist()) <= {0, 2}
    assert ((deg == 0) == (c.cycle < 0)).all()
    assert int((deg == 0).sum()) == c.n_uncovered
    g = nx.Graph()
    hs = np.flatnonzero(cov)
    g.add_edges_from(zip((hs // 3).tolist(), (twin[hs] // 3).tolist()))
    comps = list(nx.connected_components(g))
    assert len(comps) == c.n_cycles
    for comp in comps:  # each a cycle with one id
        assert len({int(c.cycle[t]) for t in comp}) == 1
        assert all(d == 2 for _, d in g.degree(comp))
    return c


def icosphere(nsub: int) -> tuple[np.ndarray, np.ndarray]:
    from hammesh.surface.shapes import icosphere as ico

    return ico(nsub)


def test_fan_is_one_cycle() -> None:
    tri = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    c = check_cover(tri, 5)
    assert (c.n_cycles, c.n_uncovered) == (1, 0)


def test_ears_stay_uncovered() -> None:
    # a strip: every triangle has a boundary edge; the ends are ears
    tri = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    c = check_cover(tri, 5)
    assert c.n_cycles == 0 and c.n_uncovered == 3


def test_closed_surface_nearly_all_covered() -> None:
    pts, tri = icosphere(4)  # dual cubic and bridgeless: a perfect matching exists
    c = check_cover(tri, len(pts))
    assert c.n_uncovered == 0 and c.n_unmatched == 0


@pytest.mark.parametrize("name", ["A", "face", "square_circle_hole"])
def test_quality_meshes_nearly_all_covered(name: str) -> None:
    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 3000)
    c = check_cover(m.triangles, m.n_points)
    assert c.n_uncovered <= 0.02 * m.n_triangles
    assert c.n_cycles <= 0.05 * m.n_triangles


@given(seed=st.integers(0, 10_000), n=st.integers(4, 300))
def test_random_delaunay(seed: int, n: int) -> None:
    pts = np.random.default_rng(seed).random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    check_cover(tri, n)


@pytest.mark.parametrize("seed", [18, 88, 162])
def test_matching_defects_are_repaired(seed: int) -> None:
    # Delaunay with random triangles removed: dual bridges, no perfect matching; the
    # repair (drop a cover arc between two free triangles) must leave valid cycles
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 60))
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    tri = tri[rng.random(len(tri)) > 0.2]
    c = check_cover(tri, n)
    assert c.n_unmatched > 0
    h = hammesh.hamiltonian(hammesh.Mesh(points=pts, triangles=tri), mode="sparse")
    assert h.report["verified"] and h.report["unmatched"] > 0
