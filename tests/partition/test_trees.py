"""The tree schemes of ``benchmarks/partition_trees.py`` (issue 14 experiments): each is a
spanning forest the incircle construction accepts, and the cells they are built from
have the counts they claim."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import networkx as nx
import numpy as np
import pytest

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.partition import partition
from hammesh.postprocess import _thm24_kernels as K

_spec = importlib.util.spec_from_file_location(
    "partition_trees", Path(__file__).parents[2] / "benchmarks" / "partition_trees.py"
)
trees = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(trees)


def _plate():
    a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    hole = np.c_[np.cos(a), np.sin(a)] * 0.3 + [1.0, 0.5]
    dom = hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]], holes=[hole])
    return hammesh.quality_mesh(dom, min_angle=30, max_area=0.002)


@pytest.mark.parametrize(
    "scheme", ["quadtree", "bisection", "cross", "cross_exact64_l3", "cross_local_l3", "fishbone_x", "ring"]
)
def test_scheme_gives_a_minimum_spanning_forest_the_walk_accepts(scheme: str) -> None:
    mesh = _plate()
    clean, he, is_con = prepare_mesh(mesh)
    tri, twin, pts = clean.triangles, he.twin, clean.points
    w = trees.SCHEMES[scheme](pts, tri, twin, is_con)
    assert np.array_equal(w, w[np.where(twin >= 0, twin, np.arange(len(twin)))])  # one weight per edge
    f = trees.forest_from_weights(tri, twin, is_con, w)
    m = len(tri)
    tree = (f.code & K.TREE_BIT) != 0
    assert tree.sum() == 2 * (m - 1) and (tree[twin[tree]]).all()
    g = nx.Graph()
    g.add_nodes_from(range(m))
    for h in np.flatnonzero(twin > np.arange(3 * m)):
        g.add_edge(h // 3, twin[h] // 3, weight=float(w[h]))
    t = nx.Graph()
    t.add_nodes_from(range(m))
    t.add_edges_from((h // 3, twin[h] // 3) for h in np.flatnonzero(tree))
    assert nx.is_tree(t)
    best = nx.minimum_spanning_tree(g).size(weight="weight")
    assert sum(g.edges[e]["weight"] for e in t.edges) == pytest.approx(best)
    with trees.tree(trees.SCHEMES[scheme]):
        h = hammesh.hamiltonian(mesh, mode="incircle")  # verified by its certificate
    assert h.n_triangles == 3 * m and len(h.components) == 1
    p = partition(h, 8)
    assert p.connected and p.sizes.max() - p.sizes.min() <= 1
    # and the shipped tree is back after the block
    assert hammesh.postprocess.incircle._kernels is K


def test_cross_cells_hold_equal_counts() -> None:
    rng = np.random.default_rng(3)
    c = rng.random((4096, 2)) * [3.0, 1.0]
    lab, hubs = trees.cross_labels(c, np.zeros(0, np.int64), np.zeros(0, np.int64), 3)
    sizes = np.bincount(lab, minlength=64)
    assert sizes.min() == sizes.max() == 64  # 4096 / 4**3, exactly
    # a cell's four quadrants meet at its hub: each lies in one quadrant of the cross
    # around the hub, so the hub is inside the cell's bounding box
    top = hubs[(0, 0)]
    assert (c.min(axis=0) < top).all() and (top < c.max(axis=0)).all()


def test_sampled_cross_cells_hold_equal_counts_once_moved_to_exact_medians() -> None:
    rng = np.random.default_rng(5)
    c = rng.random((4096, 2)) * [1.0, 2.0]
    no_edges = np.full(3 * len(c), -1, np.int64)
    lab, _ = trees.cross_labels_sampled(c, no_edges, 3, sample=512, exact=True)
    assert (np.bincount(lab, minlength=64) == 64).all()  # the sample only picks the directions
    # without ``exact`` the lines sit at the sample's medians: the counts are off
    lab, _ = trees.cross_labels_sampled(c, no_edges, 3, sample=512)
    sizes = np.bincount(lab, minlength=64)
    assert sizes.sum() == 4096 and sizes.max() > sizes.min()


def test_local_quadtree_nests_in_its_cells() -> None:
    """``local_quadtree_weights``: a cell's inside edges rank by its own triangles only
    (cutting another cell in two leaves them alone), and its own quadtree's top split
    (the cell's median) is crossed by its edges."""
    mesh = _plate()
    clean, he, is_con = prepare_mesh(mesh)
    tri, twin, pts = clean.triangles, he.twin, clean.points
    c = pts[tri].mean(axis=1)
    lab = (c[:, 0] > np.median(c[:, 0])).astype(np.int64)  # two cells: the halves
    finer = 2 * lab + ((lab == 1) & (c[:, 1] > 0.5))  # the right half cut again
    w = trees.local_quadtree_weights(pts, tri, twin, is_con, lab)
    w2 = trees.local_quadtree_weights(pts, tri, twin, is_con, finer)
    h = np.flatnonzero((twin > np.arange(len(twin))) & ~is_con)
    a, b = h // 3, twin[h] // 3
    left = (lab[a] == 0) & (lab[b] == 0)
    np.testing.assert_array_equal(w[h][left], w2[h][left])
    right = (lab[a] == 1) & (lab[b] == 1) & (finer[a] == finer[b])
    assert not np.array_equal(w[h][right], w2[h][right])  # the cut cell's own ranks did change
    levels = w[h][left].astype(np.int64) // K.CENTRE_BINS
    assert levels.max() == K.CELL_BITS


def test_bisection_cells_halve_counts() -> None:
    rng = np.random.default_rng(4)
    c = rng.random((1024, 2))
    lab = trees.bisection_labels(c, np.zeros(0, np.int64), np.zeros(0, np.int64), 4)
    assert (np.bincount(lab, minlength=16) == 64).all()


def test_runs_of_cells_cut_the_cycle_where_each_cell_begins() -> None:
    # rows are input triangles here; cell 2 wraps round the cycle's start, row 2 is a spine's
    cell = np.array([2, 2, -1, 0, 0, 1, 1, 2])
    run = trees.runs_of_cells(np.arange(8), cell)
    # one run per cell, the spine row with the run before it (cell 2's, round the end)
    np.testing.assert_array_equal(run, [2, 2, 2, 0, 0, 1, 1, 2])


def _square_mesh():
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    return hammesh.quality_mesh(dom, min_angle=30, max_area=0.0005)


def test_fishbone_children_split_each_cell_in_equal_quarters() -> None:
    """Each cell's region (spine triangles counted on their centroid's side) is cut in
    four equal counts (within one) by its spine line and each side's median along it;
    its children are those regions without the spine triangles."""
    mesh = _square_mesh()
    c = mesh.points[mesh.triangles].mean(axis=1)
    fb = trees.fishbone_labels(mesh.points, mesh.triangles)
    for level in range(3):
        along = (fb.axis + level) % 2
        for cell in range(4**level):
            own = np.flatnonzero(fb.regions[level] == cell)
            side = c[own, 1 - along] >= fb.lines[level][cell]
            assert abs(2 * int(side.sum()) - len(own)) <= 1
            counts = []
            for s in (False, True):
                x = np.sort(c[own[side == s], along])
                far = x >= x[len(x) // 2]
                counts += [int((~far).sum()), int(far.sum())]
            assert max(counts) - min(counts) <= 1
            quarters = np.bincount(fb.regions[level + 1][own] - 4 * cell, minlength=4)
            assert len(quarters) == 4 and sorted(quarters) == sorted(counts)
            kids = fb.labels[level + 1][own]
            spine = fb.spine_level[own] == level
            assert (kids[spine] == -1).all()
            member = fb.labels[level][own] == cell
            np.testing.assert_array_equal(kids[member & ~spine], fb.regions[level + 1][own][member & ~spine])


def test_fishbone_children_are_runs_of_the_cycle() -> None:
    """The fishbone's point: every child hangs from its parent's spine by one edge, so
    the walk visits it whole, one run of the cycle (the shipped tree splits the child
    holding a cell's entry); on a square, and the cells then cut about as the stretches."""
    mesh = _square_mesh()
    fb = trees.fishbone_labels(mesh.points, mesh.triangles)
    with trees.tree(trees.SCHEMES["fishbone_x"]):
        h = hammesh.hamiltonian(mesh, mode="incircle")
    lab = fb.labels[1][h.parent]
    for cell in range(4):
        rows = lab == cell
        assert np.count_nonzero(rows & ~np.roll(rows, 1)) == 1  # one run, round the cycle
    run = trees.runs_of_cells(h.parent, fb.labels[1])
    sizes = np.bincount(run)
    assert len(sizes) == 4 and sizes.max() - sizes.min() <= 0.02 * h.n_triangles


def test_fishbone_spine_is_joined_round_a_hole() -> None:
    """The plate's top line (along x, through its hole) leaves two pieces of spine;
    with the twins the gap is joined round the hole's rim, so the spine is one path."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    mesh = _plate()  # 2 x 1, a hole of radius 0.3 at its centre
    clean, he, _ = prepare_mesh(mesh)
    tri, twin, pts = clean.triangles, he.twin, clean.points
    m = len(tri)
    h = np.flatnonzero(twin >= 0)

    def pieces(spine: np.ndarray) -> int:
        a, b = h // 3, twin[h] // 3
        keep = spine[a] & spine[b]
        g = coo_matrix((np.ones(int(keep.sum())), (a[keep], b[keep])), shape=(m, m))
        _, comp = connected_components(g, directed=False)
        return len(np.unique(comp[spine]))

    plain = trees.fishbone_labels(pts, tri, axis=0)
    joined = trees.fishbone_labels(pts, tri, axis=0, twin=twin)
    assert pieces(plain.spine_level == 0) == 2
    assert pieces(joined.spine_level == 0) == 1
    added = (joined.spine_level == 0) & (plain.spine_level != 0)
    c = pts[tri].mean(axis=1)
    assert added.any() and (np.hypot(*(c[added] - [1.0, 0.5]).T) < 0.4).all()  # on the rim
