"""``encode(fast=True)`` in two halves on two threads (:mod:`hammesh.strips.halves`)."""

from __future__ import annotations

import sys
from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import threads
from hammesh.errors import InvalidMeshError, VerificationError
from hammesh.halfedge import mesh_arrays
from hammesh.mesh import Mesh
from hammesh.strips import halves
from hammesh.strips.encode import encode
from hammesh.strips.gl import RESTART_INDEX, decode_gl_strip
from hammesh.strips._dual_kernels import REC_TWIN, REC_WIDTH
from hammesh.strips._halves_kernels import pair_records_into, row_cells_into, rows_of_cells_into, shared_edges

from .conftest import delaunay_mesh, oriented_set, square_mesh, torus_mesh
from .defect_meshes import ALL as DEFECT_MESHES

_encode_module = sys.modules["hammesh.strips.encode"]


def _halves(m: Mesh, verify: bool = True, fast: bool = True):
    pts, tri = mesh_arrays(m.points, m.triangles, dims=(2, 3))
    finish = None if fast else _encode_module.half_encoder(RESTART_INDEX)
    return halves.encode_in_halves(pts, tri, RESTART_INDEX, verify, 1, finish)


@given(st.integers(0, 2**32 - 1), st.integers(30, 300), st.booleans(), st.booleans())
@settings(max_examples=40, deadline=None)
def test_halves_draw_every_row_once_with_its_winding(seed, n, lift, fast):
    m = delaunay_mesh(seed, n, lift)
    s = _halves(m, fast=fast)
    assert s is not None  # a Delaunay mesh has interior vertices: more dual edges than triangles
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    assert s.n_triangles == len(m.triangles)
    assert np.count_nonzero(s.indices == RESTART_INDEX) == s.n_strips - 1


def test_closed_surface_and_quality_mesh_cost_few_more_indices():
    """The cut ends a few more paths than one cover would: within 0.01 indices per triangle from
    ~25k triangles (+0.009 at 31k on the square, +0.004 at 100k: the cut grows as sqrt(m))."""
    for m in (torus_mesh(160, 80), square_mesh(5e-5)):
        for fast in (True, False):
            s = _halves(m, fast=fast)
            one = encode(m, fast=fast)  # below HALVES_FROM: the one-thread path
            assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
            assert s.indices_per_triangle <= one.indices_per_triangle + 0.01


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize("name", sorted(DEFECT_MESHES))
def test_defects_take_the_one_thread_path(name, fast, monkeypatch):
    """A mesh with a bad edge or a repeated-vertex row is left to the one-thread path, which reports it."""
    pts, tri, _ = DEFECT_MESHES[name]()
    m = Mesh(pts, tri)
    want = encode(m, fast=fast)
    if want.defects.non_manifold_edges or want.defects.flipped_neighbours or want.defects.repeated_vertex:
        assert _halves(m, fast=fast) is None
    monkeypatch.setattr(_encode_module, "HALVES_FROM", 0)
    got = encode(m, fast=fast)
    assert got.defects == want.defects and np.array_equal(got.dropped, want.dropped)
    assert oriented_set(decode_gl_strip(got.indices, got.restart_index)) == oriented_set(tri[got_rows(tri)])


def got_rows(tri):
    """Rows OpenGL draws: those repeating no vertex."""
    t = np.asarray(tri)
    return (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])


def test_dual_forest_takes_the_one_thread_path():
    """A fan (no interior vertex) is a dual forest: Lemma 5.1's cover, not the halves."""
    k = 7
    ang = np.linspace(0, 1.5 * np.pi, k + 1)
    m = Mesh(np.r_[[[0.0, 0.0]], np.c_[np.cos(ang), np.sin(ang)]], np.array([[0, i, i + 1] for i in range(1, k + 1)]))
    assert _halves(m) is None


def test_the_proof_catches_a_corrupted_half(monkeypatch):
    m = delaunay_mesh(3, 400)
    real = halves.greedy_strip_buffer

    def corrupt(rec, w_swap, restart, work):
        g = real(rec, w_swap, restart, work)
        i = int(np.flatnonzero(g.indices != restart)[len(g.indices) // 2])
        g.indices[i] = (g.indices[i] + 1) % len(m.points)
        return g

    monkeypatch.setattr(halves, "greedy_strip_buffer", corrupt)
    with pytest.raises(VerificationError):
        _halves(m)
    assert _halves(m, verify=False) is not None  # the proof is what catches it


def test_the_proof_catches_a_corrupted_half_of_the_default_mode():
    m = delaunay_mesh(4, 400)
    real = _encode_module.half_encoder(RESTART_INDEX)

    def corrupt(pts, part, rec, twin):
        indices, order, n_strips, n_swaps = real(pts, part, rec, twin)
        order = order.copy()
        order[[0, 1]] = order[[1, 0]]  # a wrong claim: the first two rows swapped
        return indices, order, n_strips, n_swaps

    pts, tri = mesh_arrays(m.points, m.triangles, dims=(2, 3))
    s = halves.encode_in_halves(pts, tri, RESTART_INDEX, True, 1, corrupt)
    # the claim fails, the full comparison decides: the buffer itself is right
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)

    def corrupt_buffer(pts, part, rec, twin):
        indices, order, n_strips, n_swaps = real(pts, part, rec, twin)
        indices = indices.copy()
        indices[2] = indices[0]  # the first triangle drawn degenerate: a row goes missing
        return indices, order, n_strips, n_swaps

    with pytest.raises(VerificationError):
        halves.encode_in_halves(pts, tri, RESTART_INDEX, True, 1, corrupt_buffer)


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize(
    "bad, match",
    [
        ("nan", "non-finite"), ("inf", "non-finite"), ("nan z", "non-finite"),
        ("negative", "references vertex -1"), ("too large", "references vertex"),
    ],
)
def test_bad_input_is_checked_by_the_kernels_and_named_by_the_one_thread_path(bad, match, fast, monkeypatch):
    """The halves take the arrays unchecked: a non-finite coordinate (any of them) or an index
    out of range is found by the kernel that first reads it (no out-of-range read), the halves
    give way, and ``encode`` raises the one-thread path's named error."""
    m = delaunay_mesh(11, 300, lift=bad == "nan z")
    pts, tri = m.points.copy(), m.triangles.copy()
    t = len(tri) // 2
    if bad in ("nan", "inf", "nan z"):
        pts[tri[t, 1], 2 if bad == "nan z" else 0] = np.nan if bad != "inf" else np.inf
    else:
        tri[t, 2] = -1 if bad == "negative" else len(pts) + 7
    finish = None if fast else _encode_module.half_encoder(RESTART_INDEX)
    assert halves.encode_in_halves(pts, tri, RESTART_INDEX, True, 1, finish) is None
    monkeypatch.setattr(_encode_module, "HALVES_FROM", 0)
    with pytest.raises(InvalidMeshError, match=match):
        encode(Mesh(pts, tri), fast=fast)


@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]), st.sampled_from([np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0]))
@settings(max_examples=40, deadline=None)
def test_vertex_cells_find_a_non_finite_coordinate(seed, d, x):
    """Any one coordinate infinite or NaN, anywhere, is found; huge finite ones are not flagged."""
    rng = np.random.default_rng(seed)
    pts = rng.random((int(rng.integers(1, 400)), d)) * 10.0 ** rng.integers(-5, 5)
    pts[rng.integers(len(pts)), rng.integers(d)] = x
    assert halves.vertex_cells(pts, 1000).finite == bool(np.isfinite(x))


def test_one_thread_cap_keeps_the_one_thread_path(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("encode_in_halves called under a one-thread cap")

    monkeypatch.setattr(_encode_module, "HALVES_FROM", 0)
    monkeypatch.setattr(_encode_module, "encode_in_halves", refuse)
    old = threads.limit(1)
    try:
        m = delaunay_mesh(5, 200)
        s = encode(m, fast=True)
    finally:
        threads.limit(old)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)


def _with_defects(m: Mesh, rng, kind: int) -> Mesh:
    """``m`` plus a flipped copy of a row (kind 1) or a third triangle on an edge (kind 2)."""
    tri = m.triangles.copy()
    t = tri[rng.integers(len(tri))]
    if kind == 1:
        tri = np.r_[tri, [t[::-1]]]
    elif kind == 2:
        pts = np.r_[m.points, [m.points[t].mean(0) + 0.01]]
        tri = np.r_[tri, [[t[0], t[1], len(pts) - 1]]]
        return Mesh(pts, tri)
    return Mesh(m.points, tri)


@given(st.integers(0, 2**32 - 1), st.integers(10, 120), st.integers(0, 2))
@settings(max_examples=60, deadline=None)
def test_pairing_and_shared_edges_match_a_brute_force_count(seed, n, kind):
    """Each half's records pair exactly its proper edges; the shared-edge check accepts exactly
    when every edge with triangles on both sides is one triangle each way, and counts them."""
    rng = np.random.default_rng(seed)
    m = _with_defects(delaunay_mesh(seed % 997, n), rng, kind)
    tri = m.triangles
    label = rng.integers(0, 6, len(m.points)).astype(np.int32)  # cells 0-2: side 0, 3-5: side 1
    row_label = np.full(len(tri), -7, np.int32)
    mid = int(rng.integers(len(tri) + 1))  # two threads' slices, anywhere
    counts = np.zeros((2, 6), np.int64)
    assert row_cells_into(tri[:mid], label, row_label[:mid], counts[0]) == 0
    assert row_cells_into(tri[mid:], label, row_label[mid:], counts[1]) == 0
    assert np.array_equal(row_label, label[tri.min(1)])
    assert np.array_equal(counts.sum(0), np.bincount(label[tri.min(1)], minlength=6))
    parts = []
    for first, last in ((0, 3), (3, 6)):
        part = np.full((len(tri), 3), -9, np.int64)
        offsets = np.r_[0, np.cumsum(counts.sum(0)[first : last - 1])].astype(np.int64)
        k = int(counts.sum(0)[first:last].sum())
        rows_of_cells_into(tri, row_label, first, last, offsets, part)
        assert (part[k:] == -9).all()  # nothing written past this side's rows
        # the rows of these cells, cell after cell, in input order inside a cell
        cell = label[tri.min(1)]
        mine = np.flatnonzero((cell >= first) & (cell < last))
        assert k == len(mine) and np.array_equal(part[:k], tri[mine[np.argsort(cell[mine], kind="stable")]])
        part = part[:k]
        start = np.empty(len(m.points) + 1, np.int32)
        keys = np.empty(3 * k, np.int64)
        rec = np.empty((k, REC_WIDTH), np.int32)
        loose = np.empty((3 * k, 2), np.int64)
        hp = pair_records_into(part, start, np.empty(len(m.points), np.int32), keys, rec, loose)
        # brute force: directed uses of each undirected edge in this half
        uses: dict = {}
        for t, row in enumerate(part.tolist()):
            for j in range(3):
                a, b = row[j], row[(j + 1) % 3]
                uses.setdefault((min(a, b), max(a, b)), []).append((3 * t + j, a < b))
        bad = any(len(u) > 2 or (len(u) == 2 and u[0][1] == u[1][1]) for u in uses.values())
        assert (hp.pairs < 0) == bad
        if not bad:
            assert hp.pairs == sum(len(u) == 2 for u in uses.values())
            twin = rec[:, REC_TWIN : REC_TWIN + 3].ravel()
            for u in uses.values():
                if len(u) == 2:
                    assert twin[u[0][0]] == u[1][0] and twin[u[1][0]] == u[0][0]
                else:
                    assert twin[u[0][0]] == -1
            assert hp.n_loose == sum(len(u) == 1 for u in uses.values())
        parts.append((hp, start, keys, loose, Counter({e: len(u) for e, u in uses.items()}), uses))
    if any(p[0].pairs < 0 for p in parts):
        return
    (ha, sa, ka, la, ca, ua), (hb, sb, kb, lb, cb, ub) = parts
    both = set(ca) & set(cb)
    ok = all(ca[e] == 1 and cb[e] == 1 and ua[e][0][1] != ub[e][0][1] for e in both)
    ab = shared_edges(la, ha.n_loose, sb, kb)
    ba = shared_edges(lb, hb.n_loose, sa, ka)
    assert (ab.ok and ba.ok) == ok
    if ok:
        assert ab.proper == ba.proper == len(both)


def test_structured_meshes_keep_the_one_thread_default(monkeypatch):
    """Few swaps (a torus grid): the default mode's halves give way to the one-thread path, which
    also tries the swap-free chains over the whole mesh."""
    m = torus_mesh(60, 40)
    monkeypatch.setattr(_encode_module, "HALVES_FROM", 10**12)
    one = encode(m)
    monkeypatch.setattr(_encode_module, "HALVES_FROM", 0)
    got = encode(m)
    assert np.array_equal(got.indices, one.indices)
    assert _halves(m, fast=False).indices_per_triangle > one.indices_per_triangle  # what it avoids


@given(st.integers(0, 2**32 - 1), st.integers(3, 400), st.sampled_from([2, 3]), st.integers(1, 64))
@settings(max_examples=60, deadline=None)
def test_vertex_cells_split_at_the_median_and_cover_the_grid(seed, n, d, per_cell):
    """Side 0 is exactly the points up to the sample's median along the longest axis; every label
    is a cell of the grid (points outside the sample's box clamped to the nearest cell)."""
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, d)) * rng.uniform(0.1, 10, d)
    if seed % 5 == 0:
        pts[:, 0] = 1.0  # flat along one axis
    cells = halves.vertex_cells(pts, 4 * n, per_cell)
    sample = pts[:: max(1, n // 4096)]
    axis = int(np.argsort(np.ptp(sample, axis=0), kind="stable")[::-1][0])
    side0 = pts[:, axis] <= np.median(sample[:, axis])
    assert np.array_equal(cells.label < cells.split, side0)
    assert cells.label.min() >= 0 and cells.label.max() < cells.cells
    assert 0 < cells.split < cells.cells


def test_coordinates_whose_differences_overflow_still_split(monkeypatch):
    """Points spread over the whole float range (differences overflow to inf): one cell a side,
    no error, every row drawn once with its winding."""
    assert halves.vertex_cells(np.array([[-1.7e308, 0.0], [1.7e308, 1.0], [0.0, 2.0], [1.0, -1e308]]), 100).cells == 2
    m = delaunay_mesh(3, 200)
    huge = Mesh(np.sign(m.points - 0.5) * 1.7e308 * np.abs(m.points - 0.5) * 2, m.triangles)
    monkeypatch.setattr(_encode_module, "HALVES_FROM", 0)
    for fast in (True, False):
        s = encode(huge, fast=fast)
        assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)


@given(st.integers(0, 2**32 - 1), st.integers(0, 6), st.booleans())
@settings(max_examples=25, deadline=None)
def test_halves_count_double_sided_faces_as_the_census(seed, n_pillows, fast):
    """Closed two-triangle pieces (a face and its reverse on their own vertices) added to a
    mesh: the halves report as many double-sided faces as the one-thread census, the fast
    mode from the greedy cover's paths of two (halves.pillow_rows)."""
    from hammesh.strips.dual import dual_mesh

    m = delaunay_mesh(seed, 200)
    rng = np.random.default_rng(seed)
    pts, tri = [m.points], [m.triangles]
    n = len(m.points)
    for i in range(n_pillows):
        p = m.points[rng.integers(n)] + rng.random((3, 2)) * 1e-3
        pts.append(p)
        a, b, c = n + 3 * i, n + 3 * i + 1, n + 3 * i + 2
        tri.append(np.array([[a, b, c], [a, c, b]]))
    mesh = Mesh(np.concatenate(pts), np.concatenate(tri))
    s = _halves(mesh, fast=fast)
    assert s is not None
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(mesh.triangles)
    assert s.defects.double_sided == n_pillows == dual_mesh(mesh).defects.double_sided


@given(st.integers(0, 2**32 - 1), st.sampled_from(["repeat", "negative", "too_big"]))
@settings(max_examples=30, deadline=None)
def test_row_cells_refuse_a_bad_row_before_using_its_indices(seed, fault):
    """-1 for a row repeating a vertex, -2 for an index outside the points; a good mesh 0."""
    rng = np.random.default_rng(seed)
    m = delaunay_mesh(seed % 997, 40)
    label = rng.integers(0, 4, len(m.points)).astype(np.int32)
    out = np.empty(len(m.triangles), np.int32)
    assert row_cells_into(m.triangles, label, out, np.zeros(4, np.int64)) == 0
    tri = m.triangles.copy()
    t = int(rng.integers(len(tri)))
    if fault == "repeat":
        tri[t, 2] = tri[t, 0]
    else:
        tri[t, int(rng.integers(3))] = -1 if fault == "negative" else len(m.points)
    assert row_cells_into(tri, label, out, np.zeros(4, np.int64)) == (-1 if fault == "repeat" else -2)
