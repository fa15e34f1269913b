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


def _with_neighbours(seed: int, n: int):
    """A Delaunay mesh with its neighbour array in Triangle's convention (``nbr[t, k]``
    across edge ``(k, k + 1)``) and some segments: hull edges and a few inner edges."""
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    d = Delaunay(pts)
    tri = d.simplices.astype(np.int64)  # (scipy's rows are counter-clockwise)
    nbr = d.neighbors[:, [2, 0, 1]].astype(np.int64)
    hull = d.convex_hull.astype(np.int64)
    inner = tri[rng.integers(0, len(tri), 3), :2]
    return pts, tri, nbr, np.concatenate([hull[: 1 + len(hull) // 2], inner])


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10**6), st.integers(3, 900), st.sampled_from([7, 60, 10**9]))
def test_twins_matched_once_in_the_new_order_are_the_renumbered_twins(seed: int, n: int, min_rows: int) -> None:
    """``renumber_from_neighbors`` (the twins matched once, in the new order, from the old
    neighbour array) gives what matching in the old order and renumbering gives:
    rows, points, orders, twins and segment marks, whatever the number of row ranges."""
    from hammesh.halfedge import renumber_from_neighbors

    pts, tri, nbr, segs = _with_neighbours(seed, n)
    tw, bad = half_edge_twins(tri, len(pts))
    assert bad < 0
    vh = _kernels.vertex_half_edges(tri, len(pts))
    marks, found = _kernels.mark_segments(tri, tw, vh, segs)
    assert found.all()
    before = threads.THREAD_MIN_ROWS
    threads.THREAD_MIN_ROWS = min_rows
    try:
        got = renumber_from_neighbors(pts, tri, nbr, segs, room=(5, 3))
        want = renumber_local(pts, tri, tw, marks)
    finally:
        threads.THREAD_MIN_ROWS = before
    assert got is not None
    r, found_new = got
    assert found_new.all()
    for f in want._fields:
        np.testing.assert_array_equal(getattr(r, f), getattr(want, f), err_msg=f)


def _spoil(tri: np.ndarray, nbr: np.ndarray, how: str) -> np.ndarray:
    """``nbr`` with one entry wrong in way ``how``."""
    nbr = nbr.copy()
    t = int(np.argmax((nbr >= 0).all(axis=1)))
    u = int(nbr[t, 0])
    if how in ("far", "negative", "self"):
        nbr[t, 0] = {"far": len(tri), "negative": -7, "self": t}[how]
    elif how == "one_sided":  # t names u, u does not name t back
        nbr[u, list(nbr[u]).index(t)] = -1
    elif how == "other_row":  # t names a row that does not hold the edge
        nbr[t, 0] = int(nbr[t, 1])
    elif how == "swapped":  # two entries of a row exchanged
        nbr[t, [0, 1]] = nbr[t, [1, 0]]
    return nbr


@pytest.mark.parametrize("how", ["far", "negative", "self", "one_sided", "other_row", "swapped"])
def test_neighbours_refused_in_the_new_order_exactly_when_in_the_old(how: str) -> None:
    """The matching in the new order trusts a neighbour array on the test the old
    order's makes (``twins_from_neighbors``): refused alike, and then
    ``local_half_edges`` matches the half-edges itself, as ``prepare_mesh`` does."""
    from hammesh.halfedge import local_half_edges, prepare_mesh, renumber_from_neighbors

    pts, tri, nbr, segs = _with_neighbours(3, 400)
    bad_nbr = _spoil(tri, nbr, how)
    assert _kernels.twins_from_neighbors(tri, bad_nbr)[1] >= 0
    assert renumber_from_neighbors(pts, tri, bad_nbr, segs) is None
    m = hammesh.Mesh(points=pts, triangles=tri, segments=segs, neighbors=bad_nbr)
    clean, he, con = prepare_mesh(m, cells=True)
    want = renumber_local(clean.points, clean.triangles, he.twin, con)
    lazy, none_he, none_con = prepare_mesh(m, cells=True, match=False)
    assert none_he is None and none_con is None
    got = local_half_edges(lazy)
    for f in want._fields:
        np.testing.assert_array_equal(getattr(got, f), getattr(want, f), err_msg=f)


def test_an_edge_of_three_triangles_is_accepted_or_refused_alike() -> None:
    """Three triangles on one edge: with neighbours that pair two of them consistently
    (the third claims none) both orders accept them and give the same twins; without
    neighbours both refuse the edge with the same message, naming the input's rows."""
    from hammesh.halfedge import local_half_edges, prepare_mesh

    pts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, -1], [0.6, 0.9]], float)
    tri = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])  # rows 0 and 2 both run 0 -> 1
    nbr = np.array([[1, -1, -1], [0, -1, -1], [-1, -1, -1]])
    m = hammesh.Mesh(points=pts, triangles=tri, neighbors=nbr)
    clean, he, con = prepare_mesh(m, cells=True)
    want = renumber_local(clean.points, clean.triangles, he.twin, con)
    got = local_half_edges(prepare_mesh(m, cells=True, match=False)[0])
    for f in want._fields:
        np.testing.assert_array_equal(getattr(got, f), getattr(want, f), err_msg=f)
    plain = hammesh.Mesh(points=pts, triangles=tri)
    with pytest.raises(hammesh.InvalidMeshError) as old:
        prepare_mesh(plain)
    with pytest.raises(hammesh.InvalidMeshError) as new:
        local_half_edges(prepare_mesh(plain, cells=True, match=False)[0])
    assert str(new.value) == str(old.value) and "triangle" in str(old.value)


@pytest.mark.parametrize("trusted", [True, False])
def test_a_segment_off_the_mesh_is_named_as_the_input_gave_it(trusted: bool) -> None:
    """A segment that is no edge: the same message from the matching in the new order
    (segment number and the input's vertex numbers) as from ``prepare_mesh``."""
    from hammesh.halfedge import local_half_edges, prepare_mesh

    pts, tri, nbr, segs = _with_neighbours(5, 300)
    a, b = int(tri[0, 0]), int(tri[-1, 1])
    assert not ((tri == a).any(axis=1) & (tri == b).any(axis=1)).any()  # (no edge a b)
    segs = np.concatenate([segs, [[a, b]], segs[:2]])
    m = hammesh.Mesh(points=pts, triangles=tri, segments=segs, neighbors=nbr if trusted else None)
    with pytest.raises(hammesh.InvalidMeshError) as old:
        prepare_mesh(m)
    with pytest.raises(hammesh.InvalidMeshError) as new:
        local_half_edges(prepare_mesh(m, cells=True, match=False)[0])
    assert str(new.value) == str(old.value)
    assert f"segment {len(segs) - 3} [{a}, {b}]" in str(old.value)


@settings(max_examples=50, deadline=None)
@given(st.integers(1, 4), st.integers(1, 40), st.integers(0, 10**6))
def test_first_slots_are_the_counting_sorts(ranges: int, keys: int, seed: int) -> None:
    """``first_slots_in_place`` turns each range's histogram into its first slot of each
    key, as the prefix sum over keys, then ranges inside a key, says."""
    count = np.random.default_rng(seed).integers(0, 4, (ranges, keys)).astype(np.int64)
    flat = count.T.ravel()
    want = (np.cumsum(flat) - flat).reshape(keys, ranges).T
    got = count.copy()
    _kernels.first_slots_in_place(got)
    np.testing.assert_array_equal(got, want)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10**6), st.integers(3, 300), st.integers(0, 6))
def test_vertices_renumbered_from_zeroed_memory(seed: int, n: int, unused: int) -> None:
    """``renumber_vertices_into`` takes ``vertex_new`` zeroed (fresh pages, no fill) and
    ``leaving`` with anything in it: the numbering is by first use, ``vertex_new`` its
    inverse, ``leaving[j]`` a half-edge of the new rows leaving ``j`` (the first use),
    -1 for the unused vertices, which come last."""
    pts, tri = _delaunay(seed, n, unused)
    order = np.random.default_rng(seed).permutation(len(tri)).astype(np.int64)
    nv = len(pts)
    vertex_new = np.zeros(nv, np.int64)
    vertex_order = np.full(nv, 12345, np.int64)
    tri_new = np.empty_like(tri)
    leaving = np.full(nv, 12345, np.int64)
    _kernels.renumber_vertices_into(tri, order, nv, vertex_new, vertex_order, tri_new, leaving)
    np.testing.assert_array_equal(np.sort(vertex_order), np.arange(nv))
    np.testing.assert_array_equal(vertex_new[vertex_order], np.arange(nv))
    np.testing.assert_array_equal(vertex_order[tri_new], tri[order])
    flat = tri_new.ravel()
    first = np.full(nv, -1, np.int64)
    first[flat[::-1]] = np.arange(len(flat))[::-1]  # (the first half-edge leaving each new vertex)
    np.testing.assert_array_equal(leaving, first)
    used = (first >= 0).sum()
    assert (first[:used] >= 0).all() and used == nv - unused
    assert (np.diff(first[:used]) > 0).all()  # numbered in order of first use


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10**6), st.integers(3, 300))
def test_grid_frame_from_the_validations_ranges_is_the_same(seed: int, n: int) -> None:
    """The grid over the bounding box the validation found (``ranges``) is the one
    found from the points."""
    from hammesh.halfedge.locality import cell_grid, grid_frame

    pts, tri = _delaunay(seed, n)
    pts = pts * np.random.default_rng(seed).uniform(0.1, 10.0, 2) - 3.0
    ranges = (list(pts.min(axis=0)), list(pts.max(axis=0)))
    assert grid_frame(pts, len(tri), ranges) == grid_frame(pts, len(tri))
    a, b = cell_grid(pts, len(tri), ranges), cell_grid(pts, len(tri))
    assert a[:4] == b[:4]
    np.testing.assert_array_equal(a.table, b.table)


@pytest.mark.parametrize("bits", [1, 4, 7])
def test_hilbert_tables_are_made_once_per_size(bits: int, monkeypatch) -> None:
    """``hilbert_table`` makes a size's table once (in row ranges when threads are
    allowed, the same keys) and hands the same array to every grid of that size."""
    from hammesh.halfedge import locality

    monkeypatch.setattr(locality, "_tables", {})
    monkeypatch.setattr(locality, "TABLE_MIN_CELLS", 1)  # (several ranges)
    want = np.empty(1 << (2 * bits), np.int64)
    _kernels.hilbert_table_into(bits, want, 0, 1 << bits)
    made = locality.hilbert_table(bits)
    np.testing.assert_array_equal(made, want)
    assert locality.hilbert_table(bits) is made
    pts = np.random.default_rng(bits).random((50, 2))
    m = 4 * 4**bits  # (a mesh size whose grid has 2**bits cells a side)
    assert cell_bits(m) == bits and locality.cell_grid(pts, m).table is made


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(3, 200), st.sampled_from([1, 5, 9, 10**9]))
def test_orientation_pass_counts_every_key_once(seed: int, n: int, min_rows: int) -> None:
    """The orientation pass counts each row's key ``KEY_AHEAD_ROWS`` rows after finding it
    (the histogram entry asked for meanwhile) and the last rows' at the end: the keys
    and each range's histogram are ``cell_keys``', whatever the range lengths (shorter
    than that lag too) and with rows given clockwise."""
    from hammesh.halfedge import locality

    pts, tri = _delaunay(seed, n)
    tri[::2] = tri[::2, ::-1]
    before = threads.THREAD_MIN_ROWS
    threads.THREAD_MIN_ROWS = min_rows
    try:
        grid = locality.cell_grid(pts, len(tri))
        keys = locality.empty_cell_keys(grid, len(tri))
        ccw = _kernels.orient_ccw(pts, tri, cells=(grid, keys)).triangles
        want = locality.cell_keys(pts, ccw, grid)  # (the centroid of the counter-clockwise corners)
    finally:
        threads.THREAD_MIN_ROWS = before
    assert keys.spans == want.spans
    np.testing.assert_array_equal(keys.key, want.key)
    np.testing.assert_array_equal(keys.count, want.count)
