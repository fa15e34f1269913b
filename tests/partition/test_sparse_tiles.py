"""Sparse mode's fishbone cells as tiles (``hammesh.postprocess.sparse_tiles``, issue 14
session 14, second round): each cell's own sparse cycle, the cells joined across the
cut edges."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import hammesh
from hammesh.halfedge import half_edge_twins, prepare_mesh
from hammesh.partition import partition
from hammesh.postprocess import _sparse_tiles_kernels as K
from hammesh.postprocess import sparse_cells as sc
from hammesh.postprocess import sparse_tiles as tiles
from tests.helpers import assert_tiling_and_bound
from tests.partition.test_sparse_cells import _rect


def _pieces(tri: np.ndarray, keep: np.ndarray) -> tuple[int, np.ndarray]:
    tw, _ = half_edge_twins(tri, int(tri.max()) + 1)
    h = np.flatnonzero(tw >= 0)
    a, b = h // 3, tw[h] // 3
    ok = keep[a] == keep[b]
    g = coo_matrix((np.ones(int(ok.sum())), (a[ok], b[ok])), shape=(len(tri), len(tri)))
    return connected_components(g, directed=False)


def test_cells_have_no_small_pieces_and_cut_vertices_part_them() -> None:
    """Every connected piece of a tile has ``MIN_PIECE`` triangles or more; after
    ``_cut_vertices`` no vertex is a corner in two cells and every copy stands for the
    vertex it replaced."""
    mesh = _rect(2.0, 2e-4, hole=(1.1, 0.4))
    clean, he, _ = prepare_mesh(mesh)
    tri = clean.triangles
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sc, "CELL_TRIANGLES", 256)
        cell = tiles.tile_cells(clean.points, tri, he.twin)
    assert len(np.unique(cell)) >= 16
    _, piece = _pieces(tri, cell)
    assert np.bincount(piece).min() >= tiles.MIN_PIECE
    cut, dup_of = tiles._cut_vertices(tri, cell, clean.n_points)
    owner = np.full(int(cut.max()) + 1, -1)
    owner[cut.reshape(-1)] = np.repeat(cell, 3)
    assert (owner[cut] == cell[:, None]).all()  # (each vertex id in one cell only)
    back = np.where(cut < clean.n_points, cut, dup_of[np.maximum(cut - clean.n_points, 0)])
    np.testing.assert_array_equal(back, tri)


def test_walk_reads_cycles_and_refuses_broken_links() -> None:
    """``walk_links_into`` on a strip of four triangles closed into one cycle by its
    links; a link whose twin does not link back is refused (names the row)."""
    # a fan of 4 triangles round vertex 0: rows 0-1-2-3-0 share the spokes
    pts = np.array([[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]], float)
    tri = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    tw, _ = half_edge_twins(tri, len(pts))
    link = np.zeros((4, 3), np.bool_)
    link[:, 0] = link[:, 2] = True  # spokes 0->b and a->0
    order, lengths = np.empty(4, np.int64), np.empty(4, np.int64)
    assert K.walk_links_into(tw, link, order, lengths) == 1 and lengths[0] == 4
    assert sorted(order.tolist()) == [0, 1, 2, 3]
    assert all(len(set(tri[order[i]]) & set(tri[order[(i + 1) % 4]])) == 2 for i in range(4))
    link[2, 0] = False
    link[2, 1] = True  # row 2 now links its outer edge (no twin)
    assert K.walk_links_into(tw, link, order, lengths) < 0


def test_plan_joins_spans_the_cycles_in_class_order() -> None:
    """Kruskal in class order: candidates of a lower class first, one join per
    triangle, a spanning tree of the cycles; inside a class the one nearest the
    cycles' anchors wins."""
    # cycles 0, 1, 2 of length 10; candidates: (0,1) class 1 at positions 5/5 and
    # 0/0, (1,2) class 2 at positions 1/3 (near the anchor 0 of cycle 1) and 6/3
    row_t = np.array([5, 0, 11, 16])
    row_u = np.array([15, 10, 23, 23])
    cyc_t = np.array([0, 0, 1, 1])
    cyc_u = np.array([1, 1, 2, 2])
    pos_t, pos_u = row_t % 10, row_u % 10
    cls = np.array([1, 1, 2, 2])
    pref = np.zeros(4, np.int64)
    take = np.zeros(4, np.bool_)
    order = np.array([1, 0, 3, 2])
    n = K.plan_tile_joins_into(order, cls, pref, np.zeros(4, np.int64), row_t, row_u, cyc_t, cyc_u, pos_t, pos_u, np.full(3, 10), 30, 3, take)
    assert n == 2 and take.tolist() == [False, True, True, False]


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(aspect=st.floats(0.8, 3.0), hx=st.floats(0.3, 0.7), holed=st.booleans(), cells=st.sampled_from([128, 512]))
def test_tiles_keep_every_guarantee(aspect: float, hx: float, holed: bool, cells: int) -> None:
    """``tree="fishbone"`` with the cells as tiles, rectangles with and without a hole:
    certified, re-checked (one cycle, a tiling of the same area, the proven angle
    bound), one join per edge of a spanning tree of the cells' pieces, and the
    partitions connected and balanced."""
    mesh = _rect(aspect, aspect / 6000, hole=(hx * aspect, 0.5) if holed else None)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sc, "CELL_TRIANGLES", cells)
        mp.setattr(tiles, "TILES", True)
        h = hammesh.hamiltonian(mesh, mode="sparse", tree="fishbone")
    r = h.report
    assert r["verified"] and len(h.components) == 1
    assert_tiling_and_bound(mesh, h)
    if "tile_fallback" not in r:
        assert r["tile_pieces"] >= 4
        assert r["tile_swaps"] + r["tile_bridges"] == r["tile_pieces"] - 1
    for k in (4, 8):
        p = partition(h, k)
        assert p.connected and p.sizes.max() - p.sizes.min() <= 1


def test_failed_joins_fall_back_to_one_construction(monkeypatch) -> None:
    """Where the joins cannot make one cycle (here: none taken) the construction runs
    on the uncut mesh: still one certified cycle, the report says so."""
    mesh = _rect(1.5, 3e-4)
    monkeypatch.setattr(sc, "CELL_TRIANGLES", 256)
    monkeypatch.setattr(tiles, "TILES", True)
    monkeypatch.setattr(tiles._k, "plan_tile_joins_into", lambda *a: 0)
    h = hammesh.hamiltonian(mesh, mode="sparse", tree="fishbone")
    assert h.report["verified"] and len(h.components) == 1 and h.report["tile_fallback"] == 1
    assert_tiling_and_bound(mesh, h)
