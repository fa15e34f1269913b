"""Validation of meshes handed to hamiltonian(): every bad input is named."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh import threads
from hammesh.halfedge import _kernels, half_edges, prepare_mesh
from hammesh.verify import _kernels as cert_kernels
from hammesh.verify import infer_runs

SQ = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
TWO = np.array([[0, 1, 2], [0, 2, 3]])


def mesh(points=SQ, triangles=TWO, **kw) -> hammesh.Mesh:
    return hammesh.Mesh(points=np.asarray(points, float), triangles=np.asarray(triangles), **kw)


@pytest.mark.parametrize(
    "m, needle",
    [
        (mesh(points=[[0, 0], [1, 0], [1, np.nan], [0, 1]]), "point 2"),
        (mesh(points=[[0, 0], [1, 0], [1, 1e200], [0, 1]]), "point 2"),
        (mesh(triangles=[[0, 1, 2], [0, 2, 7]]), "vertex 7"),
        (mesh(triangles=[[0, 1, 2], [0, -1, 3]]), "vertex -1"),
        (mesh(triangles=np.array([[0, 1, 2], [0, 2**64 - 1, 3]], dtype=np.uint64)), "triangle 1 .*vertex 18446744073709551615"),
        (mesh(triangles=[[0, 1, 2], [0, 2, 2]]), "triangle 1"),
        (mesh(points=[[0, 0], [1, 0], [2, 0], [0, 1]], triangles=[[0, 1, 2], [0, 2, 3]]), "triangle 0 .*zero area"),
        (mesh(triangles=np.zeros((0, 3), int)), "no triangles"),
        (mesh(triangles=[[0, 1], [1, 2]]), "shape"),
        (mesh(segments=np.array([[1, 3]])), "segment 0"),
        (mesh(segments=np.array([[0, 1], [0, 9]])), "segment 1"),
    ],
)
def test_bad_meshes_are_named(m: hammesh.Mesh, needle: str) -> None:
    with pytest.raises(hammesh.InvalidMeshError, match=needle):
        hammesh.hamiltonian(m)


def test_non_manifold_edge_is_rejected() -> None:
    pts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, -1], [0.6, 0.8]], float)
    tri = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])  # edge (0, 1) in three triangles
    with pytest.raises(hammesh.InvalidMeshError, match="edge"):
        hammesh.hamiltonian(mesh(points=pts, triangles=tri))


def test_overlapping_triangles_are_rejected() -> None:
    pts = np.array([[0, 0], [1, 0], [0.5, 1], [0.5, 0.5]], float)
    tri = np.array([[0, 1, 2], [0, 1, 3]])  # same side of (0, 1): overlap
    with pytest.raises(hammesh.InvalidMeshError, match="overlap"):
        hammesh.hamiltonian(mesh(points=pts, triangles=tri))


def test_wrong_neighbours_are_not_trusted() -> None:
    rng = np.random.default_rng(5)
    pts = rng.random((60, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    good = half_edges(tri[:, ::-1].copy(), len(pts))  # reference (CCW as Delaunay is CCW?)
    nbr = rng.integers(-1, len(tri), size=tri.shape)
    m = hammesh.Mesh(points=pts, triangles=tri, neighbors=nbr)
    clean, he, _ = prepare_mesh(m)
    ref = half_edges(clean.triangles, len(pts))
    np.testing.assert_array_equal(he.twin, ref.twin)
    assert good.twin.shape == ref.twin.shape


@given(st.integers(10, 200), st.integers(0, 10_000))
def test_twins_from_neighbours_equal_bucket_matching(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    d = Delaunay(pts)
    tri = d.simplices.astype(np.int64)
    # scipy: neighbors[t, k] is opposite vertex k; ours is across edge (k, k+1)
    nbr = d.neighbors[:, [2, 0, 1]].astype(np.int64)
    a, bad_a = _kernels.twins_from_neighbors(tri, nbr)
    b, bad_b = _kernels.half_edge_twins(tri, n)
    assert bad_a == -1 and bad_b == -1
    np.testing.assert_array_equal(a, b)


def test_segment_found_at_a_vertex_where_two_fans_touch() -> None:
    # two triangles sharing only vertex 0 (a bow-tie); a segment on the second fan
    pts = np.array([[0, 0], [1, 0], [1, 1], [-1, 0], [-1, -1]], float)
    tri = np.array([[0, 1, 2], [0, 3, 4]])
    he = half_edges(tri, len(pts))
    _, found = he.mark(np.array([[0, 1], [0, 4], [3, 0], [1, 4]]))
    assert found.tolist() == [True, True, True, False]
    # the same edge given twice (both directions), both off the first fan: both found
    is_con, found = he.mark(np.array([[4, 0], [0, 4], [1, 4]]))
    assert found.tolist() == [True, True, False]
    assert np.flatnonzero(is_con).tolist() == [5]  # half-edge 4 -> 0 of triangle 1


def test_infer_runs_from_pieces_in_order() -> None:
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [3, 0], [4, 0], [4, 1]], float)
    tri = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6]])
    assert infer_runs(tri, len(pts)).tolist() == [2, 1]
    with pytest.raises(hammesh.VerificationError, match="consecutive"):
        infer_runs(tri[[0, 2, 1]], len(pts))


@pytest.mark.parametrize("seed", range(6))
def test_twins_from_neighbours_in_threads(seed: int, monkeypatch) -> None:
    """Row ranges in three threads: the same twins, and bad neighbours still caught."""
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 5)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 3)
    rng = np.random.default_rng(seed)
    pts = rng.random((60, 2))
    d = Delaunay(pts)
    tri = d.simplices.astype(np.int64)
    nbr = d.neighbors[:, [2, 0, 1]].astype(np.int64)
    a, bad = _kernels.twins_from_neighbors(tri, nbr)
    assert bad == -1
    np.testing.assert_array_equal(a, _kernels.half_edge_twins(tri, len(pts))[0])
    # a neighbour that does not name its triangle back, in the last thread's range
    t = len(tri) - 1 - int(np.argmax((nbr[::-1] >= 0).any(axis=1)))
    k = int(np.argmax(nbr[t] >= 0))
    wrong = nbr.copy()
    wrong[t, k] = -1  # t says boundary, its neighbour still names t
    assert _kernels.twins_from_neighbors(tri, wrong)[1] >= 0


@pytest.mark.parametrize("threaded", [False, True])
def test_a_lower_neighbour_that_does_not_name_its_triangle_back_is_found(threaded: bool, monkeypatch) -> None:
    """Every pair is matched from its lower triangle; a higher one naming a lower neighbour
    that says boundary there is caught by counting (matches against lower neighbours named)."""
    if threaded:
        monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 5)
        monkeypatch.setattr(threads.os, "cpu_count", lambda: 3)
    rng = np.random.default_rng(5)
    pts = rng.random((60, 2))
    d = Delaunay(pts)
    tri = d.simplices.astype(np.int64)
    nbr = d.neighbors[:, [2, 0, 1]].astype(np.int64)
    for t in (len(tri) - 1, len(tri) // 2):
        u = int(nbr[t].max())  # (a neighbour of t; Delaunay numbers them either side of t)
        row = int(max(t, u))
        low = int(min(t, u))
        wrong = nbr.copy()
        wrong[low, int(np.argmax(wrong[low] == row))] = -1  # the lower one says boundary
        twin, bad = _kernels.twins_from_neighbors(tri, wrong)
        assert bad >= 0 and bad // 3 == row and wrong[row, bad % 3] == low


@pytest.mark.parametrize("seed", range(4))
def test_validated_facts_equal_the_certificates_own(seed: int, monkeypatch) -> None:
    """Angle, area and used vertices found while orienting (in threads) are what the
    certificate would compute from the clean mesh itself."""
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 7)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 3)
    rng = np.random.default_rng(seed)
    pts = rng.random((80, 2))
    tri = Delaunay(pts[:70]).simplices.astype(np.int64)  # points 70.. unused
    tri[::3] = tri[::3, ::-1]  # some clockwise rows
    clean, _, _ = prepare_mesh(hammesh.Mesh(points=pts, triangles=tri))
    seen = clean.info["validated"]
    stats = cert_kernels.angle_area_stats(clean.points, clean.triangles)
    assert np.isclose(seen["min_angle"], stats.min_angle, rtol=1e-14, atol=0)  # arcsin: numpy vs numba
    assert np.isclose(seen["total"], stats.total_area, rtol=1e-14)
    np.testing.assert_array_equal(seen["used"], np.bincount(tri.ravel(), minlength=80) > 0)


@pytest.mark.parametrize("seed", range(3))
def test_unmeasured_validation_orients_and_pairs_the_same(seed: int, monkeypatch) -> None:
    """``prepare_mesh(measure=False)`` (Thm 2.4's: no angle needed) orients, pairs and
    refuses exactly as the measured one; it only leaves out ``info["validated"]``."""
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 7)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 3)
    rng = np.random.default_rng(seed)
    pts = rng.random((80, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    tri[::3] = tri[::3, ::-1]  # some clockwise rows
    m = hammesh.Mesh(points=pts, triangles=tri)
    a, he_a, con_a = prepare_mesh(m)
    b, he_b, con_b = prepare_mesh(m, measure=False)
    np.testing.assert_array_equal(a.triangles, b.triangles)
    np.testing.assert_array_equal(he_a.twin, he_b.twin)
    np.testing.assert_array_equal(con_a, con_b)
    assert "validated" in a.info and "validated" not in b.info
    r = _kernels.orient_ccw(pts, tri, measure=False)
    assert np.isnan(r.min_angle) and np.isnan(r.area) and r.n_flipped == len(tri[::3])
    flat = tri.copy()
    flat[5] = [flat[5, 0], flat[5, 1], flat[5, 1]]  # a repeated vertex: refused alike
    for measure in (True, False):
        with pytest.raises(hammesh.InvalidMeshError, match="triangle 5"):
            prepare_mesh(hammesh.Mesh(points=pts, triangles=flat), measure=measure)


def test_counter_clockwise_rows_are_not_copied() -> None:
    """Rows already counter-clockwise (Triangle's) are used as given, no 36 MB copy at
    1.5 M triangles; a clockwise row makes a copy and leaves the caller's rows alone."""
    rng = np.random.default_rng(3)
    pts = rng.random((50, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    tri[signed_area_sign(pts, tri) < 0] = tri[signed_area_sign(pts, tri) < 0, ::-1]
    o = _kernels.orient_ccw(pts, tri)
    assert o.n_flipped == 0 and o.triangles is tri
    cw = tri.copy()
    cw[::4] = cw[::4, ::-1]
    before = cw.copy()
    o = _kernels.orient_ccw(pts, cw)
    assert o.n_flipped == len(cw[::4]) and o.triangles is not cw
    np.testing.assert_array_equal(o.triangles, tri)
    np.testing.assert_array_equal(cw, before)


def signed_area_sign(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    return np.sign((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


@pytest.mark.parametrize("mode", ["incircle", "sparse"])
def test_hamiltonian_never_writes_the_callers_arrays(mode: str) -> None:
    """The construction works on the caller's rows when they need no reversing: every
    input array is left as it was (compared with a copy taken before)."""
    m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]],
                                                         holes=[[[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]]]),
                             min_angle=30, max_area=0.002, isolate=False)
    arrays = {k: getattr(m, k) for k in ("points", "triangles", "neighbors", "segments", "segment_markers")}
    before = {k: a.copy() for k, a in arrays.items()}
    h = hammesh.hamiltonian(m, mode=mode)
    assert h.report["verified"]
    for k, a in arrays.items():
        np.testing.assert_array_equal(a, before[k], err_msg=k)


@pytest.mark.parametrize("bad", ["far", "negative", "self"])
def test_neighbour_array_entries_out_of_place_are_not_trusted(bad: str) -> None:
    """A neighbour index beyond the mesh, below -1, or naming the triangle itself makes
    the construction pair the half-edges itself (the same twins as without it)."""
    rng = np.random.default_rng(11)
    pts = rng.random((40, 2))
    d = Delaunay(pts)
    tri = d.simplices.astype(np.int64)
    nbr = d.neighbors[:, [2, 0, 1]].astype(np.int64)
    t = int(np.argmax((nbr >= 0).all(axis=1)))
    nbr[t, 0] = {"far": len(tri), "negative": -7, "self": t}[bad]
    assert _kernels.twins_from_neighbors(tri, nbr)[1] >= 0
    clean, he, _ = prepare_mesh(hammesh.Mesh(points=pts, triangles=tri, neighbors=nbr))
    np.testing.assert_array_equal(he.twin, half_edges(clean.triangles, len(pts)).twin)


_coordinate = st.one_of(st.floats(-1e6, 1e6), st.sampled_from([np.nan, np.inf, -np.inf, 0.0, -0.0]))


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40), st.integers(1, 30), st.sampled_from([2, 3]), st.integers(0, 10**6),
       st.booleans(), st.data())
def test_input_ranges_are_numpys(n: int, m: int, d: int, seed: int, threaded: bool, data) -> None:
    """``input_ranges`` (one compiled pass per row range) finds what numpy's passes find:
    all coordinates finite, each column's range (when finite), the least and most index."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-5, 5, (n, d))
    for _ in range(data.draw(st.integers(0, 3))):
        pts[data.draw(st.integers(0, n - 1)), data.draw(st.integers(0, d - 1))] = data.draw(_coordinate)
    tri = rng.integers(-3, n + 3, (m, 3)).astype(np.int64)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(threads, "THREAD_MIN_ROWS", 4 if threaded else 10**9)
        finite, lo, hi, least, most = _kernels.input_ranges(pts, tri)
    assert finite == bool(np.isfinite(pts).all())
    if finite:
        assert lo == list(pts.min(axis=0)) and hi == list(pts.max(axis=0))
    assert (least, most) == (tri.min(), tri.max())


def test_validation_hands_its_ranges_to_the_grid(monkeypatch) -> None:
    """``prepare_mesh(cells=True)`` builds the cells' grid from the ranges its checks
    found, without reading the points again."""
    from hammesh.halfedge import locality

    rng = np.random.default_rng(3)
    pts = rng.random((200, 2)) * [3.0, 0.5] + [-1.0, 2.0]
    tri = Delaunay(pts).simplices
    seen = []
    real = locality.grid_frame
    monkeypatch.setattr(locality, "grid_frame", lambda p, m, ranges=None: seen.append(ranges) or real(p, m, ranges))
    clean = prepare_mesh(mesh(points=pts, triangles=tri), cells=True)[0]
    assert seen == [(list(pts.min(axis=0)), list(pts.max(axis=0)))]
    keys = clean.info["validated"]["cells"]
    want = locality.cell_keys(pts, clean.triangles, locality.cell_grid(pts, len(tri)))
    np.testing.assert_array_equal(keys.key, want.key)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(4, 120), st.sampled_from([-2, -1, 0, 3]), st.booleans(), st.booleans())
def test_indices_out_of_range_are_found_by_the_orientation_pass(seed: int, n: int, off: int, earlier: bool,
                                                                threaded: bool) -> None:
    """The validation checks vertex indices in its orientation pass (no pass of their
    own): ``orient_ccw`` names a row with an index out of range as bad without reading
    its points, and ``prepare_mesh`` names the first such row, as ``mesh_arrays`` does,
    before any row with a repeated vertex or zero area."""
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    t = int(rng.integers(0, len(tri)))
    tri[t, int(rng.integers(0, 3))] = off - 2 if off < 0 else n + off  # (-4, -3, n, n + 3)
    if earlier and t > 0:
        tri[t - 1, 1] = tri[t - 1, 0]  # a repeated vertex before it
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(threads, "THREAD_MIN_ROWS", 3 if threaded else 10**9)
        o = _kernels.orient_ccw(pts, tri)
        assert o.bad == (t - 1 if earlier and t > 0 else t)
        with pytest.raises(hammesh.InvalidMeshError) as got:
            prepare_mesh(mesh(points=pts, triangles=tri), cells=True, match=False)
        with pytest.raises(hammesh.InvalidMeshError) as want:
            hammesh.halfedge.mesh_arrays(pts, tri)
    assert str(got.value) == str(want.value) and f"triangle {t} references vertex" in str(got.value)


def test_validated_ranges_are_the_points_column_ranges() -> None:
    """``info["validated"]["ranges"]``: each column's least and greatest coordinate, for a
    construction's grid (``locality.grid_frame(..., ranges=)``) without another look."""
    rng = np.random.default_rng(5)
    pts = rng.random((300, 2)) * [2.0, 7.0] - [5.0, 1.0]
    clean = prepare_mesh(mesh(points=pts, triangles=Delaunay(pts).simplices))[0]
    assert clean.info["validated"]["ranges"] == (list(pts.min(axis=0)), list(pts.max(axis=0)))
