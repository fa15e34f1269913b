"""The renumbering along a space-filling curve (``hammesh.halfedge.renumber_local``) keeps the mesh.

It must be a pure renumbering (same triangles, same pairing, same marks, same
points), bring neighbours near each other in memory, and not depend on the number
of threads; ``restore_vertices`` must undo the vertex part.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh import threads
from hammesh.halfedge import _kernels, cell_order, half_edge_twins, renumber_local, restore_vertices
from hammesh.halfedge.locality import cell_bits


def _delaunay(seed: int, n: int, unused: int = 0):
    """A Delaunay mesh of ``n`` random points (counter-clockwise) and ``unused`` extra points in no triangle."""
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    tri[cw] = tri[cw][:, ::-1]
    if unused:
        pts = np.concatenate([pts, rng.random((unused, 2)) + 5.0])
        perm = rng.permutation(len(pts))  # the unused points anywhere in the numbering
        inv = np.empty_like(perm)
        inv[perm] = np.arange(len(perm))
        pts, tri = pts[perm], inv[tri]
    return pts, tri


def _check(pts, tri, marks=None):
    tw, bad = half_edge_twins(tri, len(pts))
    assert bad < 0
    r = renumber_local(pts, tri, tw, marks)
    to, vo = r.triangle_order, r.vertex_order
    m, n = len(tri), len(pts)
    np.testing.assert_array_equal(np.sort(to), np.arange(m))
    np.testing.assert_array_equal(np.sort(vo), np.arange(n))
    # the same rows (same rotation) in new numbers, the same points, the same pairing
    np.testing.assert_array_equal(vo[r.triangles], tri[to])
    np.testing.assert_array_equal(r.points, pts[vo])
    np.testing.assert_array_equal(r.twin, half_edge_twins(r.triangles, n)[0])
    if marks is not None:
        np.testing.assert_array_equal(r.marks, marks.reshape(m, 3)[to].ravel())
    # vertices by first use: every vertex of a row is numbered no later than the
    # rows before it needed, and the unused ones come last
    used = np.zeros(n, bool)
    used[tri] = True
    assert not used[vo[used.sum():]].any()
    first = np.maximum.accumulate(r.triangles.max(axis=1))
    assert (first[1:] <= first[:-1] + 3).all()
    rows = r.triangles.copy()
    restore_vertices(rows, vo)
    np.testing.assert_array_equal(rows, tri[to])
    return r


@settings(deadline=None, max_examples=25)
@given(seed=st.integers(0, 10**6), n=st.integers(3, 400), unused=st.integers(0, 5))
def test_renumbering_is_a_renumbering(seed: int, n: int, unused: int) -> None:
    pts, tri = _delaunay(seed, n, unused)
    marks = np.random.default_rng(seed).random(3 * len(tri)) < 0.2
    _check(pts, tri, marks)


def test_neighbours_come_near_each_other() -> None:
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]], holes=[[[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=2e-5, isolate=False)
    r = _check(m.points, m.triangles)
    inner = r.twin >= 0
    gap = np.abs(r.twin // 3 - np.repeat(np.arange(m.n_triangles), 3))[inner]
    tw0 = half_edge_twins(m.triangles, m.n_points)[0]
    gap0 = np.abs(tw0 // 3 - np.repeat(np.arange(m.n_triangles), 3))[tw0 >= 0]
    # Triangle's numbering puts neighbours hundreds of rows apart; the curve a few
    assert np.median(gap) <= 8 < 10 * 8 <= np.median(gap0)
    # vertices likewise: a row's corners are numbered close together
    spread = r.triangles.max(axis=1) - r.triangles.min(axis=1)
    spread0 = m.triangles.max(axis=1) - m.triangles.min(axis=1)
    assert np.median(spread) * 10 <= np.median(spread0)


def test_cell_order_is_the_hilbert_order_of_the_cells_and_stable_inside_a_cell(monkeypatch) -> None:
    pts, tri = _delaunay(7, 3000)
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 100)  # several row ranges
    order, inverse = cell_order(pts, tri)
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 10**9)
    one, _ = cell_order(pts, tri)
    np.testing.assert_array_equal(order, one)  # the threads change nothing
    np.testing.assert_array_equal(inverse[order], np.arange(len(tri)))
    bits = cell_bits(len(tri))
    c = pts[tri].mean(axis=1)
    side = max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1]))
    cell = np.minimum((c - pts.min(axis=0)) * ((1 << bits) / side), (1 << bits) - 1).astype(np.int64)
    table = np.empty(1 << (2 * bits), np.int64)
    _kernels.hilbert_table_into(bits, table, 0, 1 << bits)
    key = table[(cell[:, 0] << bits) | cell[:, 1]]
    np.testing.assert_array_equal(order, np.lexsort((np.arange(len(tri)), key)))


@pytest.mark.parametrize("bits", [1, 2, 3, 5])
def test_hilbert_table_is_a_curve(bits: int) -> None:
    """Every cell once, and consecutive keys in cells sharing a side."""
    side = 1 << bits
    table = np.empty(side * side, np.int64)
    _kernels.hilbert_table_into(bits, table, 0, side)
    np.testing.assert_array_equal(np.sort(table), np.arange(side * side))
    xy = np.empty((side * side, 2), np.int64)
    xy[table] = np.stack(np.divmod(np.arange(side * side), side), axis=1)
    assert (np.abs(np.diff(xy, axis=0)).sum(axis=1) == 1).all()


def test_keys_found_by_the_validation_give_the_same_renumbering(monkeypatch) -> None:
    """``prepare_mesh(cells=True)`` finds the cell keys in its orientation pass (rows given
    clockwise too: the keys are the centroids', whatever the orientation)."""
    from hammesh.halfedge import prepare_mesh

    pts, tri = _delaunay(11, 2500)
    tri[::3] = tri[::3, ::-1]  # some rows clockwise: the orientation pass writes a copy
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 300)
    clean, he, con = prepare_mesh(hammesh.Mesh(points=pts, triangles=tri), cells=True)
    keys = clean.info["validated"]["cells"]
    assert len(keys.spans) > 1
    fused = renumber_local(clean.points, clean.triangles, he.twin, con, keys)
    alone = renumber_local(clean.points, clean.triangles, he.twin, con)
    for a, b in zip(fused, alone):
        np.testing.assert_array_equal(a, b)
    plain, _, _ = prepare_mesh(hammesh.Mesh(points=pts, triangles=tri))
    assert plain.info["validated"]["cells"] is None
    np.testing.assert_array_equal(plain.triangles, clean.triangles)
