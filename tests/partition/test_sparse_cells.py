"""Sparse mode's compact cycle: the fishbone's cells and bands, the joins' classes
(``hammesh.postprocess.sparse_cells``, issue 14 session 14)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.postprocess import _thm24_kernels as K
from hammesh.postprocess import sparse_cells as sc
from hammesh.postprocess.cycle_cover import cycle_cover
from tests.helpers import assert_one_cycle_in_balanced_parts, assert_tiling_and_bound
from tests.partition.test_forest import gear

LOW = (1 << K.FISH_SHIFT) - 1


def _rect(aspect: float, area: float, hole: tuple[float, float] | None = None) -> hammesh.Mesh:
    a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    holes = [np.c_[np.cos(a), np.sin(a)] * 0.15 + hole] if hole is not None else []
    dom = hammesh.Domain.from_polygon([[0, 0], [aspect, 0], [aspect, 1], [0, 1]], holes=holes)
    return hammesh.quality_mesh(dom, min_angle=30, max_area=area)


def _dual(twin: np.ndarray):
    h = np.flatnonzero(twin >= 0)
    return h // 3, twin[h] // 3


def test_bands_hold_their_spines_within_their_cells(monkeypatch) -> None:
    """Each band is its spine (the fishbone's own, unchanged) plus the triangles at
    most ``band_steps`` dual steps from it inside the same cell of its level, found
    again here by shortest paths; every other triangle keeps its deepest cell; the
    confinement ids tell bands of different levels and cells apart."""
    monkeypatch.setattr(sc, "SMOOTH_PASSES", 0)  # (smoothing moves a few triangles: checked below)
    mesh = _rect(2.0, 2e-4)
    clean, he, _ = prepare_mesh(mesh)
    pts, tri, tw = clean.points, clean.triangles, he.twin
    m = len(tri)
    c = sc.fishbone_cells(pts, tri, tw, cell_triangles=128, band_steps=2)
    d = c.frame.depth
    assert d == sc.cell_levels(m, 128) >= 3
    qr = np.empty((m, 3), K.index_dtype(m))
    K.fishbone_frame(tri, tw, pts, qr, levels=d)
    spine0, key = qr[:, 2] >> K.FISH_SHIFT, qr[:, 2] & LOW
    level = c.fish[:, 2] >> K.FISH_SHIFT
    np.testing.assert_array_equal(c.fish[:, 2] & LOW, key)  # the cells stay
    assert (level <= spine0).all()  # (a spine in a higher band stays there)
    a, b = _dual(tw)
    for lv in range(d):
        pre = key >> (2 * (d - lv))
        # the band of level lv: within 2 steps of its spine through triangles of the
        # same level-lv cell that no band of a higher level holds
        free = (level >= lv) & (spine0 >= lv)
        keep = free[a] & free[b] & (pre[a] == pre[b])
        g = coo_matrix((np.ones(int(keep.sum())), (a[keep], b[keep])), shape=(m, m))
        src = np.flatnonzero(spine0 == lv)
        if not len(src):
            continue
        dist = dijkstra(g, directed=False, unweighted=True, indices=src, min_only=True)
        want = free & (dist <= 2) & (level >= lv)
        np.testing.assert_array_equal(level == lv, want & ~(level < lv))
    ids = c.cell
    assert len(np.unique(ids[level == d])) <= 4 ** d
    for lv in range(d):  # one id per band of a level-lv cell
        on = level == lv
        assert len(np.unique(ids[on])) == len(np.unique(key[on] >> (2 * (d - lv))))
    assert not np.isin(ids[level < d], ids[level == d]).any()


def test_smoothing_moves_cell_and_spine_level_together() -> None:
    """With smoothing on, a triangle's id and its packed fishbone word move together:
    triangles with one id have one word's cell prefix and level."""
    mesh = _rect(1.0, 2e-4, hole=(0.5, 0.5))
    clean, he, _ = prepare_mesh(mesh)
    c = sc.fishbone_cells(clean.points, clean.triangles, he.twin, cell_triangles=256)
    d = c.frame.depth
    word = c.fish[:, 2].astype(np.int64)
    level, key = word >> K.FISH_SHIFT, word & LOW
    again = (level << 32) | (key >> (2 * (d - level)))
    np.testing.assert_array_equal(again, c.cell)


def test_join_classes_rank_levels_then_band_hang_wall() -> None:
    """The join classes (``sparse_cells.join_classes``) of every dual edge: inside one
    deepest cell 0 (merged) or the quadtree's; at each fishbone level the edges along
    a band rank below those that hang a child on it, below the walls; a deeper level
    ranks below every shallower one."""
    mesh = _rect(2.0, 2e-4)
    clean, he, _ = prepare_mesh(mesh)
    c = sc.fishbone_cells(clean.points, clean.triangles, he.twin, cell_triangles=256)
    d = c.frame.depth
    a, b = _dual(he.twin)
    cls = sc.join_classes(c, a, b)
    raw = sc.join_classes(c, a, b, merge_leaf=False)
    word = c.fish[:, 2].astype(np.int64)
    la, lb = word[a] >> K.FISH_SHIFT, word[b] >> K.FISH_SHIFT
    same_leaf = (word[a] == word[b]) & (la == d)
    assert (cls[same_leaf] == 0).all() and (raw[same_leaf] < K.LEAF_CLASSES).all()
    assert (cls[~same_leaf] >= K.LEAF_CLASSES).all()
    ka, kb = word[a] & LOW, word[b] & LOW
    common = np.array([d - (int(x ^ y).bit_length() + 1) // 2 for x, y in zip(ka, kb)])
    lvl = np.minimum(common, np.minimum(la, lb))
    top = -1
    for lv in range(d - 1, -1, -1):  # deepest first
        at = ~same_leaf & (lvl == lv)
        if not at.any():
            continue
        assert cls[at].min() > top
        band = at & (la == lv) & (lb == lv)
        hang = at & ((la == lv) != (lb == lv))
        wall = at & (la != lv) & (lb != lv)
        if lv >= 2 or c.frame.span == 0.0:  # (the ring frame's top levels: one class level)
            if band.any() and hang.any():
                assert cls[band].max() < cls[hang].min()
            if hang.any() and wall.any():
                assert cls[hang].max() < cls[wall].min()
        top = cls[at].max()


def test_strict_confinement_keeps_every_cycle_in_its_cell(monkeypatch) -> None:
    """``STRICT``: ``cycle_cover(..., cells=)`` removes the border edges, so no cover
    edge joins two cells; without it (pinned borders) the cover still covers."""
    mesh = _rect(1.5, 3e-4, hole=(0.7, 0.4))
    clean, he, _ = prepare_mesh(mesh)
    pts, tri, tw = clean.points, clean.triangles, he.twin
    c = sc.fishbone_cells(pts, tri, tw, cell_triangles=256)
    h = np.flatnonzero(tw >= 0)
    for strict in (True, False):
        monkeypatch.setattr(sc, "STRICT", strict)
        cov = cycle_cover(tri, tw, points=pts, cells=c.cell)
        on = h[cov.is_cov[h]]
        across = int((c.cell[on // 3] != c.cell[tw[on] // 3]).sum())
        covered = cov.cycle >= 0
        assert (cov.is_cov.reshape(-1, 3).sum(axis=1)[covered] == 2).all()
        if strict:
            assert across == 0
        assert covered.mean() > 0.8


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(aspect=st.floats(0.8, 3.0), hx=st.floats(0.3, 0.7), holed=st.booleans(), strict=st.booleans(),
       cells=st.sampled_from([128, 512]))
def test_sparse_fishbone_keeps_every_guarantee(aspect: float, hx: float, holed: bool, strict: bool,
                                               cells: int) -> None:
    """``hamiltonian(mode="sparse", tree="fishbone")`` on rectangles with and without
    a hole, both confinements: certified (``report["verified"]``), re-checked here
    (one closing cycle, a tiling of the same area, the proven angle bound), and its
    partitions are connected and balanced."""
    mesh = _rect(aspect, aspect / 6000, hole=(hx * aspect, 0.5) if holed else None)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sc, "CELL_TRIANGLES", cells)
        mp.setattr(sc, "STRICT", strict)
        h = hammesh.hamiltonian(mesh, mode="sparse", tree="fishbone")
    assert_one_cycle_in_balanced_parts(mesh, h, (4, 8))


def test_gear_ring_frame_and_default_sparse_unchanged() -> None:
    """On the gear (the ring frame from depth 3) the option certifies; the default
    sparse call (``tree="quadtree"``) is the same output as without the argument, and
    the fishbone one is another cycle over the same input."""
    mesh = gear(0.0007)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sc, "CELL_TRIANGLES", 64)
        clean, he, _ = prepare_mesh(mesh)
        c = sc.fishbone_cells(clean.points, clean.triangles, he.twin)
        assert c.frame.depth >= 3 and c.frame.span > 0.0  # the ring frame
        fish = hammesh.hamiltonian(mesh, mode="sparse", tree="fishbone")
    plain = hammesh.hamiltonian(mesh, mode="sparse")
    quad = hammesh.hamiltonian(mesh, mode="sparse", tree="quadtree")
    np.testing.assert_array_equal(plain.triangles, quad.triangles)
    assert fish.report["verified"] and len(fish.components) == 1
    assert_tiling_and_bound(mesh, fish)
    assert not np.array_equal(fish.parent, plain.parent)
