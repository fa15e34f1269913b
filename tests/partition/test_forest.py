"""The compact spanning forest (``_thm24_kernels.spanning_forest``, issue 14 item 1)."""

from __future__ import annotations

import networkx as nx
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.postprocess import _thm24_kernels as K
from tests.helpers import star_pslg


def _regions(tri: np.ndarray, twin: np.ndarray, is_con: np.ndarray, free_only: bool) -> int:
    g = nx.Graph()
    g.add_nodes_from(range(len(tri)))
    for h in range(len(twin)):
        if twin[h] > h and not (free_only and is_con[h]):
            g.add_edge(h // 3, twin[h] // 3)
    return nx.number_connected_components(g)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), threads=st.booleans())
def test_forest_spans_each_piece_crossing_fewest_constrained_edges(dom, threads: bool) -> None:
    import hammesh.threads as row_threads

    mesh = hammesh.quality_mesh(dom, min_angle=25, max_area=0.01)
    clean, he, is_con = prepare_mesh(mesh)
    old = row_threads.THREAD_MIN_ROWS
    row_threads.THREAD_MIN_ROWS = 20 if threads else old
    try:
        f = K.spanning_forest(clean.triangles, he.twin, is_con, clean.points)
    finally:
        row_threads.THREAD_MIN_ROWS = old
    m = clean.n_triangles
    assert sorted(f.order.tolist()) == list(range(m))
    np.testing.assert_array_equal(f.triangles, clean.triangles[f.order])
    rank = np.empty(m, np.int64)
    rank[f.order] = np.arange(m)
    # twins and constrained bits carried over to the new numbering
    tw = (f.code >> 2) - 1
    old_h = 3 * f.order[np.arange(3 * m) // 3] + np.arange(3 * m) % 3
    g = he.twin[old_h]
    np.testing.assert_array_equal(tw, np.where(g >= 0, 3 * rank[np.maximum(g, 0) // 3] + g % 3, -1))
    np.testing.assert_array_equal((f.code & K.CON_BIT) != 0, is_con[old_h])
    tree = (f.code & K.TREE_BIT) != 0
    assert (tree[tw[tree]]).all()  # both halves marked
    pieces = _regions(clean.triangles, he.twin, is_con, free_only=False)
    regions = _regions(clean.triangles, he.twin, is_con, free_only=True)
    assert tree.sum() == 2 * (m - pieces)  # a spanning forest
    g_tree = nx.Graph()
    g_tree.add_nodes_from(range(m))
    g_tree.add_edges_from((h // 3, tw[h] // 3) for h in np.flatnonzero(tree))
    assert nx.number_connected_components(g_tree) == pieces and nx.is_forest(g_tree)
    assert ((f.code & 3) == 3).sum() == 2 * (regions - pieces)  # fewest crossings
    np.testing.assert_array_equal(f.split, np.flatnonzero((f.code & 3) == 3))
    assert len(f.firsts) == pieces


@settings(max_examples=30, deadline=None)
@given(
    xy=st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)), min_size=3, max_size=60, unique=True),
    data=st.data(),
)
def test_quadtree_coords_count_the_triangles_below(xy, data) -> None:
    """Each axis is monotone in the centroid's coordinate and about the number of
    centroids below it (within a histogram bin's share), scaled by the box's aspect."""
    pts = np.array(xy, float)
    n = len(pts)
    tri = np.array(data.draw(st.lists(st.permutations(range(n)).map(lambda p: p[:3]), min_size=1, max_size=40)))  # below RANK_SAMPLE: the histogram is exact
    q = K.quadtree_coords(pts, tri)
    assert (q[:, 1] == -1).all()
    ix, iy = q[:, 0] >> K.CELL_BITS, q[:, 0] & ((1 << K.CELL_BITS) - 1)
    c = pts[tri].mean(axis=1)
    ext = pts.max(axis=0) - pts.min(axis=0)
    top = (1 << K.CELL_BITS) - 1
    m = len(tri)
    for axis, v in ((0, ix), (1, iy)):
        o = np.argsort(c[:, axis], kind="stable")
        assert (np.diff(v[o]) >= 0).all() or np.ptp(c[:, axis]) < 1e-9 * max(1.0, float(np.abs(c).max()))
        scale = top * ext[axis] / ext.max() / m if ext.max() > 0 else 0.0
        below = (c[:, axis][None, :] < c[:, axis][:, None]).sum(axis=1)
        at_most = (c[:, axis][None, :] <= c[:, axis][:, None]).sum(axis=1)
        # the count below a centroid, up to the other centroids in its histogram bin
        mates = _bin_mates(c[:, axis], pts[:, axis])
        assert (v >= np.floor((below - mates) * scale) - 1).all()
        assert (v <= np.ceil((at_most + mates) * scale) + 1).all()


def _bin_mates(c: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Centroids sharing each centroid's histogram bin (``RANK_BINS`` over the points' span)."""
    lo, hi = p.min(), p.max()
    b = np.clip(((c - lo) * (K.RANK_BINS / (hi - lo)) if hi > lo else 0 * c).astype(np.int64), 0, K.RANK_BINS - 1)
    return (b[None, :] == b[:, None]).sum(axis=1)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), area=st.sampled_from([0.003, 0.01, 0.03]))
def test_forest_is_a_minimum_spanning_forest_of_the_edge_classes(dom, area: float) -> None:
    """Prim's search is exact: the tree's total class equals a minimum spanning
    forest's (networkx), constrained edges weighing more than any free one; each piece
    starts at its lowest input triangle, pieces in that order."""
    mesh = hammesh.quality_mesh(dom, min_angle=25, max_area=area)
    clean, he, is_con = prepare_mesh(mesh)
    f = K.spanning_forest(clean.triangles, he.twin, is_con, clean.points)
    cl = K.forest_classes(clean.triangles, he.twin, is_con, clean.points)
    m = clean.n_triangles
    g = nx.Graph()
    g.add_nodes_from(range(m))
    for h in np.flatnonzero(he.twin > np.arange(3 * m)):
        a, b = h // 3, he.twin[h] // 3
        assert cl.cls[h] == cl.cls[he.twin[h]]  # one class per edge
        assert (cl.cls[h] == cl.frame.n_classes - 1) == is_con[h]  # constrained edges last, alone
        g.add_edge(a, b, w=int(cl.cls[h]))
    best = sum(d["w"] for _, _, d in nx.minimum_spanning_edges(g, weight="w", data=True))
    tw = (f.code >> 2) - 1
    tree = np.flatnonzero(((f.code & K.TREE_BIT) != 0) & (np.arange(3 * m) < tw))
    ours = sum(g.edges[f.order[h // 3], f.order[tw[h] // 3]]["w"] for h in tree)
    assert ours == best
    lowest = sorted(min(c) for c in nx.connected_components(g))
    assert f.order[f.firsts].tolist() == lowest


def test_forest_without_points_is_a_plain_spanning_forest() -> None:
    mesh = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]]), min_angle=25,
                                max_area=0.01)
    clean, he, is_con = prepare_mesh(mesh)
    f = K.spanning_forest(clean.triangles, he.twin, is_con)
    m = clean.n_triangles
    tw = (f.code >> 2) - 1
    tree = np.flatnonzero((f.code & K.TREE_BIT) != 0)
    t = nx.Graph()
    t.add_nodes_from(range(m))
    t.add_edges_from((h // 3, tw[h] // 3) for h in tree)
    assert len(tree) == 2 * (m - 1) and nx.is_tree(t)
    assert f.order[f.firsts].tolist() == [0]


def test_two_searches_join_across_the_halves_as_one_search_would() -> None:
    """The halves' searches (:func:`_prim_half_into`) see only the edges inside a
    top-level quadrant; Kruskal's join over the rest must still give a minimum
    spanning forest. A C-shaped domain whose two arms meet only in the other half
    (each arm a separate component in its half), with a constrained loop across the
    split and a second piece: the result is the same on one thread and on two, a
    minimum spanning forest of the classes (constrained edges last), each piece
    starting at its lowest input triangle."""
    import hammesh.threads as row_threads

    c_shape = [[0, 0], [3, 0], [3, 1], [1, 1], [1, 2], [3, 2], [3, 3], [0, 3]]
    v = [list(p) for p in c_shape] + [[1.3, 0.2], [1.7, 0.2], [1.7, 0.8], [1.3, 0.8]] + \
        [[4, 0], [5, 0], [5, 3], [4, 3]]
    segs = [[i, (i + 1) % 8] for i in range(8)] + [[8 + i, 8 + (i + 1) % 4] for i in range(4)] + \
           [[12 + i, 12 + (i + 1) % 4] for i in range(4)]
    mesh = hammesh.quality_mesh(hammesh.Domain(vertices=v, segments=segs), min_angle=25, max_area=0.01)
    clean, he, is_con = prepare_mesh(mesh)
    tri, twin, pts = clean.triangles, he.twin, clean.points
    old = row_threads.THREAD_MIN_ROWS
    try:
        row_threads.THREAD_MIN_ROWS = 10**9
        one = K.spanning_forest(tri, twin, is_con, pts)
        row_threads.THREAD_MIN_ROWS = 20
        two = K.spanning_forest(tri, twin, is_con, pts)
    finally:
        row_threads.THREAD_MIN_ROWS = old
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)
    cl = K.forest_classes(tri, twin, is_con, pts)
    m = len(tri)
    g = nx.Graph()
    g.add_nodes_from(range(m))
    for h in np.flatnonzero(twin > np.arange(3 * m)):
        g.add_edge(h // 3, twin[h] // 3, w=int(cl.cls[h]))
    # the arms really are apart in their half (else the join is not exercised)
    inside = nx.Graph([(a, b) for a, b, d in g.edges(data=True) if d["w"] < cl.frame.cross_from])
    inside.add_nodes_from(range(m))
    assert nx.number_connected_components(inside) > 4 + 1
    tw = (two.code >> 2) - 1
    tree = np.flatnonzero(((two.code & K.TREE_BIT) != 0) & (np.arange(3 * m) < tw))
    assert len(tree) == m - 2
    best = sum(d["w"] for _, _, d in nx.minimum_spanning_edges(g, weight="w", data=True))
    assert sum(g.edges[two.order[h // 3], two.order[tw[h] // 3]]["w"] for h in tree) == best
    assert two.order[two.firsts].tolist() == sorted(min(c) for c in nx.connected_components(g))
    assert len(two.split) == 2  # the loop's region joins the rest by one constrained edge


def gear(area: float):
    """bench_partition's gear, meshed at ``max_area`` ``area``."""
    k = np.arange(96)
    r = np.where((k // 4) % 2 == 0, 1.0, 0.8)  # 12 teeth, as in bench_partition
    ang = 2 * np.pi * k / 96
    a = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    dom = hammesh.Domain.from_polygon(np.c_[r * np.cos(ang), r * np.sin(ang)],
                                      holes=[np.c_[np.cos(a), np.sin(a)] * 0.3])
    return hammesh.quality_mesh(dom, min_angle=30, max_area=area)


def _top_cells_cut(pts, tri, twin, angle: float) -> int:
    """Dual edges between different cells of the quadtree's top two levels, turned by
    ``angle`` (counted on every triangle, not the forest's sample)."""
    q = K.quadtree_coords(pts, tri, angle=angle)[:, 0].astype(np.int64)
    x, y = q >> K.CELL_BITS, q & ((1 << K.CELL_BITS) - 1)
    h = np.flatnonzero(twin > np.arange(len(twin)))
    a, b = h // 3, twin[h] // 3
    return sum(int(np.count_nonzero((v[a] >> s) != (v[b] >> s))) for v in (x, y)
               for s in (K.CELL_BITS - 1, K.CELL_BITS - 2))


def test_quadtree_turns_off_the_gear_teeth_and_stays_put_on_boxes() -> None:
    """The quadtree's rotation (:func:`top_cross_angle`, judged on a sample; the
    forest's on meshes too small for a fishbone level) is one whose top cells cut
    fewer dual edges than the unrotated quadtree's, counted on the whole mesh; on a
    square and a 2:1 box the axes are best and are kept."""
    for dom in ([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 0], [2, 0], [2, 1], [0, 1]]):
        mesh = hammesh.quality_mesh(hammesh.Domain.from_polygon(dom), min_angle=30, max_area=2e-4)
        clean, he, _ = prepare_mesh(mesh)
        assert K.top_cross_angle(clean.points, clean.triangles, he.twin) == 0.0
    mesh = gear(2.4 / 10_000)
    clean, he, _ = prepare_mesh(mesh)
    pts, tri, twin = clean.points, clean.triangles, he.twin
    angle = K.top_cross_angle(pts, tri, twin)
    assert 0.0 < angle < np.pi / 2
    assert _top_cells_cut(pts, tri, twin, angle) < K.CROSS_GAIN * _top_cells_cut(pts, tri, twin, 0.0)


@settings(max_examples=20, deadline=None)
@given(
    xy=st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)), min_size=3, max_size=40, unique=True),
    turn=st.integers(0, 7),
    data=st.data(),
)
def test_turned_quadtree_coords_follow_the_turned_axes(xy, turn: int, data) -> None:
    """With ``angle``, each coordinate is monotone in the centroid's coordinate along
    the axis turned by that angle (``x cos + y sin``, ``y cos - x sin``)."""
    pts = np.array(xy, float)
    n = len(pts)
    tri = np.array(data.draw(st.lists(st.permutations(range(n)).map(lambda p: p[:3]), min_size=1, max_size=30)))
    angle = 0.5 * np.pi * turn / 8
    q = K.quadtree_coords(pts, tri, angle=angle)
    c = pts[tri].mean(axis=1)
    ca, sa = np.cos(angle), np.sin(angle)
    turned = np.c_[ca * c[:, 0] + sa * c[:, 1], ca * c[:, 1] - sa * c[:, 0]]
    for axis, v in ((0, q[:, 0] >> K.CELL_BITS), (1, q[:, 0] & ((1 << K.CELL_BITS) - 1))):
        o = np.argsort(turned[:, axis], kind="stable")
        gaps = np.diff(turned[o, axis])
        # monotone, except between centroids closer than rounding (ties in the turned axis)
        assert ((np.diff(v[o]) >= 0) | (gaps <= 1e-9 * max(1.0, float(np.abs(c).max())))).all()


def _numpy_top_cross_counts(points, tri, twin, sample, angles) -> np.ndarray:
    """Session 9's numpy count of :func:`K.top_cross_angle` (the reference the numba
    kernel must match): per rotation, the sampled dual edges crossing a border of the
    turned count quadtree's top two levels."""
    g = np.asarray(twin)[(3 * sample[:, None] + np.arange(3)).ravel()]
    inner = g >= 0
    n_ang = len(angles)
    turn = np.stack([np.c_[np.cos(angles), -np.sin(angles)], np.c_[np.sin(angles), np.cos(angles)]], axis=1)
    turn = turn.transpose(1, 0, 2).reshape(2, 2 * n_ang)

    def along(ts):
        c = (points[tri[ts, 0]] + points[tri[ts, 1]] + points[tri[ts, 2]]) / 3.0
        return c[:, :1] * turn[0] + c[:, 1:] * turn[1]

    p = along(sample)
    pt = np.repeat(p, 3, axis=0)[inner]
    pu = along(g[inner] // 3)
    srt = np.sort(p, axis=0)
    n = len(sample)
    ext = (srt[-1] - srt[0]).reshape(n_ang, 2)
    aspect = (ext / np.maximum(ext.max(axis=1, keepdims=True), 1e-300)).ravel()
    cols, ranks = [], []
    for j in range(2 * n_ang):
        for d in (2, 4):
            for k in range(1, d):
                if k < aspect[j] * d:
                    cols.append(j)
                    ranks.append(min(n - 1, int(n * k / (aspect[j] * d))))
    cols, ranks = np.array(cols, np.int64), np.array(ranks, np.int64)
    crossed = np.count_nonzero((pt[:, cols] >= srt[ranks, cols]) != (pu[:, cols] >= srt[ranks, cols]), axis=0)
    return np.bincount(cols // 2, weights=crossed, minlength=n_ang).astype(np.int64)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=st.sampled_from(["square", "rect", "gear", "star"]), stride=st.integers(1, 7), star=star_pslg())
def test_top_cross_counts_match_the_numpy_count(dom: str, stride: int, star) -> None:
    """The numba count behind the rotation (``_top_cross_counts_into``) gives session 9's
    numpy counts exactly, so the forest's rotation (and tree) is the same."""
    if dom == "gear":
        mesh = gear(2.4 / 3000)
    elif dom == "star":
        mesh = hammesh.quality_mesh(star, min_angle=25, max_area=0.01)
    else:
        box = [[0, 0], [1, 0], [1, 1], [0, 1]] if dom == "square" else [[0, 0], [2, 0], [2, 1], [0, 1]]
        mesh = hammesh.quality_mesh(hammesh.Domain.from_polygon(box), min_angle=30, max_area=1e-3)
    clean, he, _ = prepare_mesh(mesh)
    pts, tri, twin = clean.points, clean.triangles, he.twin
    sample = np.arange(0, len(tri), stride)
    angles = 0.5 * np.pi * np.arange(K.CROSS_ANGLES) / K.CROSS_ANGLES
    cuts = np.zeros(K.CROSS_ANGLES, np.int64)
    has_edges = K._top_cross_counts_into(pts, tri, twin, sample, np.cos(angles), np.sin(angles), cuts)
    assert has_edges == bool((twin[(3 * sample[:, None] + np.arange(3)).ravel()] >= 0).any())
    if has_edges:
        np.testing.assert_array_equal(cuts, _numpy_top_cross_counts(pts, tri, twin, sample, angles))
