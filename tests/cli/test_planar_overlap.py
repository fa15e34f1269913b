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


def _brute_force(pts, tri):
    """The lowest overlapping pair by testing every pair (exact predicate, no grid)."""
    from hammesh.predicates import orient

    def right_of(a, b, c):
        return orient(*pts[a], *pts[b], *pts[c]) <= 0

    for i in range(len(tri)):
        for j in range(i + 1, len(tri)):
            if len(set(tri[i].tolist()) & set(tri[j].tolist())) >= 2:
                continue
            sep = any(
                all(right_of(own[e], own[(e + 1) % 3], v) for v in other)
                for own, other in ((tri[i], tri[j]), (tri[j], tri[i]))
                for e in range(3)
            )
            if not sep:
                return (i, j)
    return None


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(2, 40), spread=st.floats(0.0, 6.0),
       lattice=st.booleans())
def test_grid_equals_brute_force_on_random_triangles(seed, m, spread, lattice):
    """Random counter-clockwise triangles of sizes over ``spread`` decades (several grid
    levels), on a coarse lattice or not (touching corners and collinear edges): the
    kernel's answer is the brute force's lowest overlapping pair (every triangle here
    has a boundary edge, so every pair is a candidate)."""
    rng = np.random.default_rng(seed)
    centre = rng.random((m, 1, 2)) * 10
    scale = 10.0 ** (-rng.random((m, 1, 1)) * spread)
    pts = (centre + scale * rng.normal(size=(m, 3, 2))).reshape(-1, 2)
    if lattice:
        pts = np.round(pts * 2) / 2
    tri = _ccw(pts, np.arange(3 * m, dtype=np.int64).reshape(m, 3))
    a, b, c = (pts[tri[:, i]] for i in range(3))
    keep = ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])) != 0
    tri = tri[keep]
    if lattice:  # shared vertex numbers where coordinates coincide (shared edges skipped)
        _, inv = np.unique(pts, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        rep = np.empty(inv.max() + 1, np.int64)
        rep[inv[::-1]] = np.arange(len(pts))[::-1]  # each coordinate's first vertex
        tri = rep[inv[tri]] if len(tri) else tri
        tri = tri[np.array([len(set(r)) == 3 for r in tri.tolist()], dtype=bool)] if len(tri) else tri
    assert find_overlap(pts, tri) == _brute_force(pts, tri)


def test_threaded_split_gives_the_same_lowest_pair(monkeypatch):
    import hammesh.threads as row_threads

    rng = np.random.default_rng(3)
    pts = rng.random((300, 2))
    tri = _ccw(pts, Delaunay(pts).simplices.astype(np.int64))
    pts2 = np.vstack([pts, pts[tri[[5, 40, 200]]].reshape(-1, 2) + 1e-3])
    n = len(pts)
    tri2 = np.vstack([tri, np.arange(n, n + 9).reshape(3, 3)])
    one = find_overlap(pts2, tri2)
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 50)
    assert find_overlap(pts2, tri2) == one == _brute_force(pts2, tri2)


def _pair_overlaps(pts, tri, pair):
    i, j = pair
    return _brute_force(pts, tri[[i, j]]) == (0, 1)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(4, 80), shift=st.floats(-0.3, 0.3),
       turn=st.floats(0.0, 6.3))
def test_two_meshes_stacked_are_found_from_their_boundary(seed, n, shift, turn):
    """Two Delaunay meshes on top of each other (the second moved and turned): every
    overlap the brute force sees is reported as some overlapping pair, found from a
    triangle with a boundary edge; each mesh alone has none."""
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = _ccw(pts, Delaunay(pts).simplices.astype(np.int64))
    rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    pts2 = np.vstack([pts, (pts - 0.5) @ rot.T + 0.5 + shift])
    both = np.vstack([tri, tri + n])
    assert find_overlap(pts, tri) is None
    want = _brute_force(pts2, both)
    got = find_overlap(pts2, both)
    assert (got is None) == (want is None)
    if got is not None:
        assert _pair_overlaps(pts2, both, got)
