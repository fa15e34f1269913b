"""Generalized (IRIS GL) strips: one vertex per triangle plus a turn bit; exact decoding."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hammesh.errors import InvalidMeshError
from hammesh.strips.dual import dual_mesh
from hammesh.strips.generalized import GeneralizedStrips, decode_generalized, generalized_strips
from hammesh.strips.gl import decode_gl_strip, gl_strip

from .conftest import SMALL_MESHES, fan_mesh, oriented_set, random_path_cover, zigzag_mesh

MESHES = SMALL_MESHES


@given(st.sampled_from(sorted(MESHES)), st.integers(0, 2**32 - 1))
def test_round_trip_exact_order(name, seed):
    mesh = MESHES[name]()
    d = dual_mesh(mesh)
    order, starts = random_path_cover(d.neighbor_triangles, np.random.default_rng(seed))
    g = generalized_strips(d.triangles, d.twin, order, starts)
    S = len(starts) - 1
    assert len(g.vertices) == mesh.n_triangles + 2 * S
    assert len(g.swaps) == mesh.n_triangles
    decoded = decode_generalized(g)
    # triangle i of the decode is order[i] with its own winding
    assert [oriented_set([t]) for t in decoded] == [oriented_set([mesh.triangles[t]]) for t in order]
    # same bits as the GL encoding's repeated indices
    s = gl_strip(d.triangles, d.twin, order, starts)
    assert g.n_swaps == s.n_swaps
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(decoded)


def test_zigzag_and_fan_bits():
    z = dual_mesh(zigzag_mesh(6))
    g = generalized_strips(z.triangles, z.twin, np.arange(6), [0, 6])
    assert g.vertices.tolist() == list(range(8)) and not g.swaps.any()
    f = dual_mesh(fan_mesh(6))
    g = generalized_strips(f.triangles, f.twin, np.arange(6), [0, 6])
    assert g.swaps.tolist() == [False, False, True, True, True, False]


def test_decoder_rejects_inconsistent_offsets():
    g = GeneralizedStrips(np.arange(5), np.zeros(3, bool), np.array([0, 5]), np.array([0, 2]))
    with pytest.raises(InvalidMeshError):
        decode_generalized(g)
    g = GeneralizedStrips(np.arange(5), np.array([True, False, False]), np.array([0, 5]), np.array([0, 3]))
    with pytest.raises(InvalidMeshError, match="first triangle"):
        decode_generalized(g)


def test_to_dict():
    z = dual_mesh(zigzag_mesh(2))
    doc = generalized_strips(z.triangles, z.twin, [0, 1], [0, 2]).to_dict()
    assert doc["primitive"] == "generalized_strip"
    assert doc["indices"] == [0, 1, 2, 3] and doc["swap_bits"] == [0, 0]
    assert doc["triangles"] == 2 and doc["strips"] == 1
