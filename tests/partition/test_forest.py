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
