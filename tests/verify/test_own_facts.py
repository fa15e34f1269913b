"""The certificate's own facts: its half-edge pairing, the input's facts, the hull.

Each is compared with an independent computation (pure numpy / Python, or the
constructions' code, which a test may use as a second opinion) on random meshes,
and each bad input must be named.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh.verify import _kernels
from hammesh.verify.reference import input_facts
from tests.helpers import BAD_EDGES, angles_deg, grid_mesh, signed_areas


def dict_pairing(tri: np.ndarray) -> np.ndarray:
    """Half-edge twins by a Python dict of directed edges (the plainest method)."""
    where = {}
    for h, (a, b) in enumerate(zip(tri.ravel(), np.roll(tri, -1, axis=1).ravel())):
        where[(int(a), int(b))] = h
    twin = np.full(tri.size, -1, np.int64)
    for (a, b), h in where.items():
        twin[h] = where.get((b, a), -1)
    return twin


def run_wide(tri: np.ndarray, n: int) -> tuple[np.ndarray, int]:
    """The pairing's path for meshes too large to pack, called directly."""
    lo = np.minimum(tri, np.roll(tri, -1, axis=1)).ravel()
    start = np.r_[0, np.cumsum(np.bincount(lo, minlength=n))].astype(np.int64)
    return _kernels.half_edge_twins_wide(tri, n, start, start[:-1].copy())


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_pairing_equals_a_dictionary_of_edges(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m = grid_mesh(int(rng.integers(1, 8)), int(rng.integers(1, 8)))
    perm = rng.permutation(len(m.points))  # scattered numbering, as Triangle writes
    tri = np.argsort(perm)[m.triangles][rng.permutation(m.n_triangles)].astype(np.int64)
    want = dict_pairing(tri)
    for twin, bad in (_kernels.half_edge_twins(tri, len(m.points)), run_wide(tri, len(m.points))):
        assert bad == -1
        np.testing.assert_array_equal(twin, want)


def test_pairing_around_a_vertex_of_high_degree() -> None:
    """A fan of 200 triangles around vertex 0 (the bucket is sorted, not insertion-sorted)."""
    k = 200
    ang = np.linspace(0, 2 * np.pi, k, endpoint=False)
    pts = np.r_[[[0.0, 0.0]], np.c_[np.cos(ang), np.sin(ang)]]
    tri = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)], np.int64)[::-1].copy()
    for twin, bad in (_kernels.half_edge_twins(tri, len(pts)), run_wide(tri, len(pts))):
        assert bad == -1
        np.testing.assert_array_equal(twin, dict_pairing(tri))
        assert (twin < 0).sum() == k  # the rim


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(-(2**31), 2**31 - 1), max_size=300), st.sampled_from([np.int32, np.int64]),
       st.integers(0, 5), st.integers(0, 5))
def test_sort_range_sorts_exactly_the_range(values, dtype, pad_lo, pad_hi) -> None:
    """The heapsort of high-degree buckets: sorted like numpy, outside the range untouched."""
    a = np.array([7] * pad_lo + values + [-7] * pad_hi, dtype)
    want = a.copy()
    want[pad_lo:pad_lo + len(values)] = np.sort(want[pad_lo:pad_lo + len(values)])
    _kernels.sort_range(a, pad_lo, pad_lo + len(values))
    np.testing.assert_array_equal(a, want)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 2**40)), max_size=200), st.integers(0, 4))
def test_sort_pairs_range_sorts_by_key_then_half(pairs, pad) -> None:
    key = np.array([9] * pad + [p[0] for p in pairs], np.int64)
    half = np.array([-1] * pad + [p[1] for p in pairs], np.int64)
    _kernels.sort_pairs_range(key, half, pad, len(key))
    assert list(zip(key[pad:].tolist(), half[pad:].tolist())) == sorted(pairs)
    assert key[:pad].tolist() == [9] * pad and half[:pad].tolist() == [-1] * pad


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(-50, 50), max_size=40), st.integers(-60, 60))
def test_lower_bound_is_numpys_left_search(values, x) -> None:
    a = np.sort(np.array(values, np.int64))
    assert _kernels.lower_bound(a, x) == np.searchsorted(a, x, side="left")


@pytest.mark.parametrize("tri", BAD_EDGES)
def test_pairing_names_a_bad_edge(tri) -> None:
    tri = np.array(tri, np.int64)
    for twin, bad in (_kernels.half_edge_twins(tri, 5), run_wide(tri, 5)):
        assert bad >= 0
        t, k = divmod(int(bad), 3)
        a, b = tri[t, k], tri[t, (k + 1) % 3]
        uses = sum(1 for r in tri.tolist() for j in range(3) if {r[j], r[(j + 1) % 3]} == {a, b})
        same_way = sum(1 for r in tri.tolist() for j in range(3) if (r[j], r[(j + 1) % 3]) == (a, b))
        assert uses > 2 or same_way > 1


@settings(max_examples=20, deadline=None)
@given(st.integers(20, 200), st.integers(0, 2**32 - 1))
def test_input_facts_are_measured_from_the_mesh_as_given(n: int, seed: int) -> None:
    """Rows in either orientation; angle, area, used vertices and boundary as plain
    numpy finds them."""
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts[: n - 3]).simplices.astype(np.int64)  # the last 3 points unused
    flip = rng.random(len(tri)) < 0.5
    tri[flip] = tri[flip, ::-1]
    f = input_facts(hammesh.Mesh(points=pts, triangles=tri))
    assert np.isclose(np.degrees(f.min_angle), angles_deg(pts, tri).min(), rtol=1e-9)
    assert np.isclose(f.area, np.abs(signed_areas(pts, tri)).sum(), rtol=1e-12)
    np.testing.assert_array_equal(f.used, np.arange(n) < n - 3)
    ccw = np.where((signed_areas(pts, tri) > 0)[:, None], tri, tri[:, ::-1])
    twin = dict_pairing(ccw)
    h = np.flatnonzero(twin < 0)
    a, b = ccw.ravel()[h], np.roll(ccw, -1, axis=1).ravel()[h]
    np.testing.assert_array_equal(f.boundary, np.sort(a * (1 << 32) + b))


SQ = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)


@pytest.mark.parametrize(
    "kw, needle",
    [
        ({"points": [[0, 0], [1, 0], [1, np.nan], [0, 1]]}, "point 2 is not finite"),
        ({"triangles": [[0, 1, 2], [0, 2, 7]]}, "triangle 1 .* outside"),
        ({"triangles": [[0, 1, 2], [0, 2, 2]]}, "triangle 1 .* degenerate"),
        ({"points": [[0, 0], [1, 0], [2, 0], [0, 1]]}, "triangle 0 .* degenerate"),
        ({"triangles": [[0, 1, 2], [0, 1, 3]]}, "edge .*non-manifold edge or overlap"),
        ({"triangles": np.zeros((0, 3), int)}, "triangles have shape \\(0, 3\\)"),
        ({"segments": [[1, 3]]}, "segment 0 \\[1, 3\\] is not an edge"),
        ({"segments": [[0, 1], [0, 9]]}, "segment 1 .* outside"),
    ],
)
def test_bad_input_is_named(kw: dict, needle: str) -> None:
    args = {"points": SQ, "triangles": [[0, 1, 2], [0, 2, 3]], **kw}
    m = hammesh.Mesh(points=np.asarray(args["points"], float), triangles=np.asarray(args["triangles"]),
                     segments=np.asarray(args.get("segments", np.zeros((0, 2), int))))
    with pytest.raises(hammesh.VerificationError, match="input mesh is not a valid triangulation: " + needle):
        input_facts(m)


@settings(max_examples=40, deadline=None)
@given(st.integers(4, 60), st.integers(0, 2**32 - 1), st.booleans())
def test_hull_chain_equals_the_point_sets_hull(n: int, seed: int, lattice: bool) -> None:
    """Counter-clockwise, collinear boundary points included; on lattice points (many
    collinear) too."""
    from hammesh.pointset import convex_hull

    rng = np.random.default_rng(seed)
    pts = rng.integers(0, 5, (3 * n, 2)).astype(float) if lattice else rng.random((n, 2))
    pts = np.unique(pts, axis=0)
    rng.shuffle(pts)
    if len(pts) < 3 or np.linalg.matrix_rank(pts[1:] - pts[0]) < 2:
        assume(False)  # all collinear: no hull polygon (the certificate rejects such sets)
    got = _kernels.hull_chain(pts, np.lexsort((pts[:, 1], pts[:, 0])).astype(np.int64))
    want = convex_hull(pts).boundary
    assert len(got) == len(want) and set(got.tolist()) == set(want.tolist())
    i = int(np.argmin(got))  # same cyclic order
    j = int(np.argmin(want))
    np.testing.assert_array_equal(np.roll(got, -i), np.roll(want, -j))


def boundary_by_dict(tri: np.ndarray) -> np.ndarray:
    """Sorted directed boundary edge keys of counter-clockwise rows, by a dictionary."""
    twin = dict_pairing(tri)
    h = np.flatnonzero(twin < 0)
    a, b = tri.ravel()[h], np.roll(tri, -1, axis=1).ravel()[h]
    return np.sort(a * (1 << 32) + b)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([np.int32, np.int64]))
def test_input_boundary_equals_a_dictionary_of_edges(seed: int, key_dtype) -> None:
    """The input's bucket matching (rows read through the scan's flips, int32 or
    int64 keys, a fan of 40 around one vertex heap-sorted) finds the boundary."""
    rng = np.random.default_rng(seed)
    k = 40
    ang = np.sort(rng.random(k)) * 2 * np.pi
    pts = np.r_[[[0.0, 0.0]], np.c_[np.cos(ang), np.sin(ang)], rng.random((30, 2)) * 0.2 + 3.0]
    fan = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)], np.int64)
    far = Delaunay(pts[k + 1:]).simplices.astype(np.int64) + k + 1
    ccw = np.r_[fan, np.where((signed_areas(pts, far) > 0)[:, None], far, far[:, ::-1])]
    ccw = ccw[rng.permutation(len(ccw))]
    flip = rng.random(len(ccw)) < 0.5
    given_rows = ccw.copy()
    given_rows[flip] = given_rows[flip][:, ::-1]
    n = len(pts)
    used = np.zeros(n, bool)
    start = np.zeros(n + 1, np.int64)
    seen = np.zeros(len(ccw), bool)
    scan = _kernels.scan_input_into(pts, given_rows, seen, used, start)
    np.testing.assert_array_equal(seen, flip)
    assert scan.n_flipped == flip.sum() and scan.bad < 0 and scan.bad_index < 0
    # constrained edges asked for: some edges of the mesh (the fan's centre's among
    # them), and pairs of vertices that are not an edge
    edges = {(min(a, b), max(a, b)) for row in ccw.tolist() for a, b in zip(row, row[1:] + row[:1])}
    pairs = list(edges)[: int(rng.integers(0, len(edges)))] + [(0, 1), (0, k // 2), (1, k + 1), (2, 2)]
    want = np.unique([a * n + b for a, b in pairs]).astype(np.int64)
    found = np.zeros(len(want), bool)
    got, ok = _kernels.input_boundary_into(given_rows, seen, start, np.empty(3 * len(ccw), key_dtype), want, found)
    assert ok
    np.testing.assert_array_equal(np.sort(got), boundary_by_dict(ccw))
    np.testing.assert_array_equal(found, [divmod(int(w), n) in edges for w in want])


@pytest.mark.parametrize("tri", BAD_EDGES)
def test_input_boundary_refuses_a_bad_edge(tri) -> None:
    tri = np.array(tri, np.int64)
    start = np.r_[0, np.bincount(np.minimum(tri, np.roll(tri, -1, axis=1)).ravel(), minlength=5)].astype(np.int64)
    none = np.zeros(0, np.int64)
    _, ok = _kernels.input_boundary_into(tri, np.zeros(len(tri), bool), start, np.empty(tri.size, np.int32), none,
                                         np.zeros(0, bool))
    assert not ok


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_constrained_edges_are_found_either_way_round(seed: int) -> None:
    """Every edge of a mesh, named in either direction and in any order, is a
    constrained edge the certificate finds; a pair of vertices that is no edge is named."""
    rng = np.random.default_rng(seed)
    m = grid_mesh(int(rng.integers(2, 6)), int(rng.integers(1, 6)))
    tri = np.asarray(m.triangles, np.int64)
    e = np.r_[tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]
    e = e[rng.permutation(len(e))][: int(rng.integers(1, len(e) + 1))]
    e = np.where(rng.random((len(e), 1)) < 0.5, e, e[:, ::-1])
    f = input_facts(hammesh.Mesh(points=m.points, triangles=tri, segments=e))
    np.testing.assert_array_equal(f.segments, e)
    n = len(m.points)
    far = np.array([[0, n - 1]])  # opposite corners of the grid: never an edge
    with pytest.raises(hammesh.VerificationError, match=f"segment {len(e)} \\[0, {n - 1}\\] is not an edge"):
        input_facts(hammesh.Mesh(points=m.points, triangles=tri, segments=np.r_[e, far]))
