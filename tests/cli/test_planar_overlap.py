"""hammesh.planar_overlap: the exact overlap test behind ``hammesh check`` (issue 12 #10)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from hammesh.planar_overlap import find_overlap


def _ccw(pts, tri):
    a, b, c = (pts[tri[:, i]] for i in range(3))
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    tri = tri.copy()
    tri[area < 0] = tri[area < 0][:, [0, 2, 1]]
    return tri


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(4, 200), shift=st.floats(0.0, 0.2))
def test_a_delaunay_mesh_has_none_and_a_shifted_copy_is_found(seed, n, shift):
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = _ccw(pts, Delaunay(pts).simplices.astype(np.int64))
    assert find_overlap(pts, tri) is None
    k = int(rng.integers(len(tri)))
    # a copy of triangle k, moved by less than its inradius's share: it overlaps k
    a, b, c = pts[tri[k]]
    centre = (a + b + c) / 3
    copy = centre + (pts[tri[k]] - centre) * (1 - shift)
    pts2 = np.vstack([pts, copy])
    tri2 = np.vstack([tri, [[n, n + 1, n + 2]]])
    pair = find_overlap(pts2, tri2)
    assert pair is not None and len(tri) in pair


def test_two_pieces_touching_at_a_vertex_do_not_overlap():
    pts = np.array([[0.0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [2, 1]])
    assert find_overlap(pts, np.array([[0, 1, 2], [1, 3, 4]])) is None
    # the same triangle twice under other vertex numbers
    pts = np.vstack([pts, pts[[0, 1, 2]]])
    assert find_overlap(pts, np.array([[0, 1, 2], [6, 7, 8]])) == (0, 1)
