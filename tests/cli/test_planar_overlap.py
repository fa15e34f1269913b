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


def _fan(angles, radii, closed=True):
    """Triangles ``(0, i, i + 1)`` round point 0, rim points at ``angles`` (radians,
    increasing) and ``radii``; ``closed``: the last rim point joined to the first."""
    n = len(angles)
    pts = np.r_[[[0.0, 0.0]], np.c_[radii * np.cos(angles), radii * np.sin(angles)]]
    k = n if closed else n - 1
    tri = np.c_[np.zeros(k, np.int64), 1 + np.arange(k), 1 + (np.arange(k) + 1) % n]
    return pts, tri


def test_a_fan_of_50k_triangles_is_checked_in_near_linear_time():
    """A user's fan round one vertex: every bounding box holds the centre, so every pair
    was a candidate (32k triangles: 15 s before session 19, 0.05 s after); the pairs
    sharing the centre are decided by the angular order round it."""
    import time

    n = 50_000
    pts, tri = _fan(2 * np.pi * np.arange(n) / n, np.ones(n))
    start = time.perf_counter()
    assert find_overlap(pts, tri) is None
    assert time.perf_counter() - start < 8.0  # (quadratic: > 30 s)
    two = _fan(4 * np.pi * np.arange(2 * n) / (2 * n), 1 + np.arange(2 * n) / (4 * n))  # wound twice
    start = time.perf_counter()
    pair = find_overlap(*two)
    assert pair is not None and time.perf_counter() - start < 8.0
    assert _pair_overlaps(two[0], two[1], pair)


def _precondition(pts, tri) -> bool:
    """find_overlap's: counter-clockwise with positive area, each directed edge once."""
    from hammesh.predicates import orient

    if any(orient(*pts[a], *pts[b], *pts[c]) <= 0 for a, b, c in tri.tolist()):
        return False
    d = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    return len(np.unique(d, axis=0)) == len(d)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(17, 120), turn=st.floats(0.5, 2.2),
       closed=st.booleans(), mutate=st.sampled_from(["none", "apex", "copy"]))
def test_fans_with_one_wrong_triangle_are_found(seed, n, turn, closed, mutate):
    """Fans round a vertex of more than ``FAN_DEGREE`` triangles (rim angles random,
    spanning ``turn`` turns: more than one overlaps itself; closed or not), one rim
    point moved along its ray or one triangle stored again slightly turned (sharing
    the centre only): an overlap is reported iff the brute force sees one, and the
    pair reported overlaps."""
    rng = np.random.default_rng(seed)
    ang = np.sort(rng.random(n)) * 2 * np.pi * turn
    ang = ang[np.concatenate([[True], np.diff(ang) > 1e-9])]
    pts, tri = _fan(ang, rng.uniform(0.5, 1.5, len(ang)), closed=closed)
    k = int(rng.integers(len(tri)))
    if mutate == "apex":
        pts[tri[k, 2]] *= rng.uniform(0.3, 3.0)
    elif mutate == "copy":
        c, s_ = np.cos(0.3 * rng.random()), np.sin(0.3 * rng.random())
        pts = np.vstack([pts, pts[tri[k, 1:]] @ np.array([[c, s_], [-s_, c]]) * 0.9])
        tri = np.vstack([tri, [[0, len(pts) - 2, len(pts) - 1]]])
    if len(ang) < 17 or not _precondition(pts, tri):
        return
    want = _brute_force(pts, tri)
    got = find_overlap(pts, tri)
    assert (got is None) == (want is None)
    if got is not None:
        assert _pair_overlaps(pts, tri, got)
    if not closed and ang[-1] - ang[0] > 2 * np.pi + 1e-6:  # (wound more than once: the rim passes its start)
        assert got is not None


def test_check_refuses_a_fan_wound_twice(tmp_path, capsys):
    """A fan wound twice round its centre: one cycle of counter-clockwise triangles,
    every directed edge once, yet covering the disc twice: ``hammesh check`` exit 3."""
    import meshio

    from hammesh.cli import main

    n = 200
    pts, tri = _fan(4 * np.pi * np.arange(n) / n, 1 + np.arange(n) / (2 * n))
    path = tmp_path / "fan2.vtu"
    meshio.write(path, meshio.Mesh(np.c_[pts, np.zeros(len(pts))], [("triangle", tri)]))
    assert main(["check", str(path)]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "overlap" in err
    one = tmp_path / "fan1.vtu"
    pts, tri = _fan(2 * np.pi * np.arange(n) / n, np.ones(n))
    meshio.write(one, meshio.Mesh(np.c_[pts, np.zeros(len(pts))], [("triangle", tri)]))
    assert main(["check", str(one)]) == 0
