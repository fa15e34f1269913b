"""Thm 4.3: the O(n) sequential test against brute force over all Hamiltonian paths."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hammesh.mesh import Mesh
from hammesh.strips.dual import dual_mesh
from hammesh.strips.gl import gl_strip, verify_gl_strip
from hammesh.strips.sequential import sequential_order

from tests.helpers import grid_mesh

from .conftest import delaunay_mesh, fan_mesh, square_mesh, torus_mesh, zigzag_mesh


def _shared(t, u):
    return set(t) & set(u)


def alternates(tri, order) -> bool:
    """Consecutive triangles share an edge and no three consecutive crossed edges share a vertex."""
    edges = []
    for i in range(len(order) - 1):
        e = _shared(tri[order[i]], tri[order[i + 1]])
        if len(e) != 2:
            return False
        edges.append(e)
    return all(not (edges[i] & edges[i + 1] & edges[i + 2]) for i in range(len(edges) - 2))


def brute_force_sequential(tri) -> bool:
    tri = [tuple(t) for t in np.asarray(tri).tolist()]
    m = len(tri)
    nbr = [[u for u in range(m) if u != t and len(_shared(tri[t], tri[u])) == 2] for t in range(m)]

    def dfs(path, used):
        if len(path) == m:
            return True
        for u in nbr[path[-1]]:
            if not used[u]:
                cand = path + [u]
                if len(cand) >= 4 and not alternates(tri, cand[-4:]):
                    continue
                used[u] = True
                if dfs(cand, used):
                    return True
                used[u] = False
        return False

    for s in range(m):
        used = [False] * m
        used[s] = True
        if dfs([s], used):
            return True
    return False


def check_result(mesh, res):
    tri = mesh.triangles
    m = len(tri)
    assert sorted(res.order.tolist()) == list(range(m))
    assert alternates(tri.tolist(), res.order.tolist())
    for i, t in enumerate(res.order.tolist()):
        assert set(res.vertices[i : i + 3].tolist()) == set(tri[t].tolist())


@pytest.mark.parametrize("k", [1, 2, 3, 5, 10])
def test_zigzag_is_sequential(k):
    mesh = zigzag_mesh(k)
    res = sequential_order(mesh)
    assert res is not None
    check_result(mesh, res)
    d = dual_mesh(mesh)
    s = gl_strip(d.triangles, d.twin, res.order, [0, k])
    assert len(s.indices) <= k + 3  # no swap but, at most, the start's parity
    verify_gl_strip(mesh.triangles, s.indices)


@pytest.mark.parametrize("k,expected", [(3, True), (4, False), (6, False)])
def test_fans(k, expected):
    assert (sequential_order(fan_mesh(k)) is not None) is expected
    assert brute_force_sequential(fan_mesh(k).triangles) is expected


def test_grid_row_sequential_and_two_pieces_not():
    assert sequential_order(grid_mesh(6, 1)) is not None
    m = grid_mesh(2, 1)
    two = Mesh(np.r_[m.points, m.points + 10], np.r_[m.triangles, m.triangles + len(m.points)])
    assert sequential_order(two) is None


def test_real_meshes_are_not_sequential():
    # interior vertices of degree >= 5 everywhere; the test still runs in O(m)
    assert sequential_order(square_mesh()) is None
    assert sequential_order(torus_mesh()) is None


@given(st.integers(0, 2**32 - 1), st.integers(4, 9))
def test_matches_brute_force_on_random_delaunay(seed, n):
    mesh = delaunay_mesh(seed, n)  # counter-clockwise rows
    tri = mesh.triangles
    res = sequential_order(mesh)
    assert (res is not None) == brute_force_sequential(tri)
    if res is not None:
        check_result(mesh, res)


@given(st.integers(0, 2**32 - 1))
def test_matches_brute_force_on_grid_pieces(seed):
    rng = np.random.default_rng(seed)
    g = grid_mesh(3, 3)
    d = dual_mesh(g)
    # a random connected set of 3..9 grid triangles (grown from one)
    k = int(rng.integers(3, 10))
    chosen = [int(rng.integers(len(g.triangles)))]
    while len(chosen) < k:
        frontier = sorted({int(u) for t in chosen for u in d.neighbor_triangles[t] if u >= 0} - set(chosen))
        chosen.append(frontier[rng.integers(len(frontier))])
    mesh = Mesh(g.points, g.triangles[chosen])
    res = sequential_order(mesh)
    assert (res is not None) == brute_force_sequential(mesh.triangles)
    if res is not None:
        check_result(mesh, res)
