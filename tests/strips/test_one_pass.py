"""The one-pass greedy strips of ``encode(fast=True)`` and the proof in two parts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import VerificationError
from hammesh.strips.dual import dual_mesh
from hammesh.strips.encode import encode, is_forest, restart_strip
from hammesh.strips.gl import RESTART_INDEX, decode_gl_strip, gl_strip, verify_gl_strip
from hammesh.strips._cover_kernels import greedy_path_cover
from hammesh.strips._greedy_strip_kernels import greedy_strip_buffer
from hammesh.strips._path_kernels import orient_paths

from .conftest import corrupt_claim, delaunay_mesh, oriented_set, random_path_cover, torus_mesh


@given(st.integers(0, 2**32 - 1), st.integers(8, 150), st.booleans())
@settings(max_examples=40, deadline=None)
def test_one_pass_equals_cover_then_direction_then_writer(seed, n, lift):
    """greedy_strip_buffer == greedy_path_cover + orient_paths + restart_buffer, index for index."""
    d = dual_mesh(delaunay_mesh(seed, n, lift))
    m = d.n_triangles
    seeds = np.arange(m - 1, -1, -1)
    g = greedy_strip_buffer(d.cover_records().copy(), 1, RESTART_INDEX)
    order, starts = greedy_path_cover(d.cover_records().copy(), 1, seeds)
    order, _ = orient_paths(d.triangles, d.twin, order.astype(np.int64), starts)
    want = restart_strip(d.triangles, d.twin, order, starts, RESTART_INDEX)
    assert np.array_equal(g.order, order) and np.array_equal(g.starts, starts)
    assert np.array_equal(g.indices, want.indices) and g.n_swaps == want.n_swaps
    assert g.max_index == int(d.triangles.max())
    # index_starts: each path's first index, right after a restart (the first at 0)
    assert g.index_starts[0] == 0
    assert np.all(g.indices[g.index_starts[1:] - 1] == RESTART_INDEX)
    assert len(g.index_starts) == np.count_nonzero(g.indices == RESTART_INDEX) + 1


@given(st.integers(0, 2**32 - 1), st.integers(20, 150))
@settings(max_examples=25, deadline=None)
def test_fast_encode_is_the_one_pass_buffer_and_round_trips(seed, n):
    m = delaunay_mesh(seed, n)
    s = encode(m, fast=True)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    d = dual_mesh(m)
    if not is_forest(d):
        g = greedy_strip_buffer(d.cover_records().copy(), 1, RESTART_INDEX)
        assert np.array_equal(s.indices, g.indices) and s.n_strips == len(g.starts) - 1
    r = encode(m, fast=True, reorder_vertices=True)
    assert oriented_set(r.vertex_order[decode_gl_strip(r.indices, r.restart_index)]) == oriented_set(m.triangles)


@given(st.integers(0, 2**32 - 1), st.integers(0, 5), st.integers(0, 10**6), st.integers(-2, 2))
@settings(max_examples=80, deadline=None)
def test_proof_in_two_parts_decides_as_the_full_comparison(seed, corrupt, at, shift):
    """verify_gl_strip(split=...) accepts exactly the buffers the literal decoder proves right,
    for any cut (a cut not just after a restart index is checked in one piece)."""
    m = torus_mesh(6, 4) if seed % 2 else delaunay_mesh(seed % 1000, 40)
    d = dual_mesh(m)
    rng = np.random.default_rng(seed)
    order, starts = random_path_cover(d.neighbor_triangles, rng)
    s = gl_strip(d.triangles, d.twin, order, starts, join="restart")
    cuts = np.flatnonzero(s.indices == RESTART_INDEX) + 1
    p = int(cuts[at % len(cuts)]) + shift if len(cuts) else at % len(s.indices)
    q = int(starts[min(1 + at % max(len(cuts), 1), len(starts) - 1)])
    # 1 a wrong index, 2 a wrong claim, 3 a triangle missing, 4 a row claimed twice
    idx, claim = corrupt_claim(s.indices, order, corrupt, rng, len(m.points), RESTART_INDEX)
    if corrupt == 5:  # the cut's claim off by one
        q = max(q - 1, 0)
    truth = oriented_set(decode_gl_strip(idx, RESTART_INDEX)) == oriented_set(m.triangles)
    if truth:
        verify_gl_strip(m.triangles, idx, RESTART_INDEX, order=claim, split=(p, q))
    else:
        with pytest.raises(VerificationError):
            verify_gl_strip(m.triangles, idx, RESTART_INDEX, order=claim, split=(p, q))


def test_a_row_claimed_in_both_parts_is_caught():
    """Each part draws its claim, but the claims name one row in both parts (and a copy of
    it in neither): the marks the parts share catch it, whatever each part saw alone."""
    from hammesh.strips.gl import _check_in_two_parts

    R = RESTART_INDEX
    strip = [0, 1, 2, 3, 4]  # draws (0 1 2), (2 1 3), (2 3 4)
    tri = np.array([[0, 1, 2], [2, 1, 3], [2, 3, 4]] * 2)  # every row twice
    idx = np.array(strip + [R] + strip)
    assert _check_in_two_parts(tri, idx, R, np.array([0, 1, 2, 3, 4, 5]), (6, 3))
    assert not _check_in_two_parts(tri, idx, R, np.array([0, 1, 2, 0, 1, 2]), (6, 3))
    # the full proof still accepts the right buffer with the wrong claim (it falls back)
    verify_gl_strip(tri, idx, R, order=[0, 1, 2, 0, 1, 2], split=(6, 3))
