"""The constructions' half-edge pairing (``hammesh.halfedge._kernels``): packed and reference paths."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.halfedge import _kernels as core_kernels
from tests.helpers import BAD_EDGES, grid_mesh


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_packed_half_edge_pairing_equals_the_reference(seed):
    rng = np.random.default_rng(seed)
    m = grid_mesh(int(rng.integers(1, 7)), int(rng.integers(1, 7)))
    perm = rng.permutation(len(m.points))  # scattered vertex numbering
    tri = np.argsort(perm)[m.triangles][rng.permutation(m.n_triangles)]
    twin, bad = core_kernels.half_edge_twins(tri, len(m.points))
    ref, rbad = core_kernels.half_edge_twins_reference(tri, len(m.points))
    assert bad == rbad == -1 and np.array_equal(twin, ref)
    # every pair: opposite directions of one edge
    h = np.flatnonzero(twin >= 0)
    t, k = h // 3, h % 3
    g = twin[h]
    assert np.array_equal(twin[g], h)
    assert np.array_equal(tri[t, k], tri[g // 3, (g % 3 + 1) % 3])


@pytest.mark.parametrize("tri", BAD_EDGES)
def test_packed_pairing_reports_the_same_bad_half_edge(tri):
    tri = np.array(tri, np.int64)
    assert core_kernels.half_edge_twins(tri, 5)[1] == core_kernels.half_edge_twins_reference(tri, 5)[1] >= 0
