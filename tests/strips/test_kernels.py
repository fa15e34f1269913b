"""Compiled helpers of the strip encoder: the ``_nrt`` fallback, the path-order renumbering,
the one-pass restart emission and the half-edge pairing it starts from."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh import _kernels as core_kernels
from hammesh.mesh import Mesh
from hammesh.strips import _kernels
from hammesh.strips.dual import dual_mesh
from hammesh.strips.encode import _greedy_cover, encode, greedy_paths
from hammesh.strips.gl import decode_gl_strip

from .conftest import grid_mesh, oriented_set, square_mesh, torus_mesh

_REJECT_NRT = {
    # numba refuses the private option when decorating
    "decorate": """
        def njit(*args, **kw):
            if "_nrt" in kw:
                raise TypeError("unexpected keyword argument '_nrt'")
            return real(*args, **kw)
    """,
    # numba takes the option but the compiled function fails
    "compile": """
        def njit(*args, **kw):
            if "_nrt" in kw:
                def deco(f):
                    def broken(*a):
                        raise RuntimeError("no such flag: _nrt")
                    return broken
                return deco
            return real(*args, **kw)
    """,
}


@pytest.mark.slow
@pytest.mark.parametrize("how", sorted(_REJECT_NRT))
def test_package_works_when_numba_rejects_the_private_nrt_option(tmp_path, how):
    """Without ``_nrt=False`` the helpers fall back to plain ``njit(cache=True)``: import and encode still work."""
    script = textwrap.dedent(
        """
        import numba
        real = numba.njit
        """
    ) + textwrap.dedent(_REJECT_NRT[how]) + textwrap.dedent(
        """
        numba.njit = njit
        import hammesh
        from hammesh.strips import _kernels, encode, decode_gl_strip
        assert _kernels.LEAF_WITHOUT_NRT is False
        m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.01)
        s = encode(m)  # verify=True: the round trip is proven
        assert len(decode_gl_strip(s.indices, s.restart_index)) == m.n_triangles
        print("ok", s.n_strips)
        """
    )
    # a private numba cache: the NRT-compiled helpers must not replace the package's cached ones
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.startswith("ok")


def test_leaf_helpers_compile_without_nrt_here():
    assert _kernels.LEAF_WITHOUT_NRT  # this environment's numba accepts the option


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_packed_half_edge_pairing_equals_the_reference(seed):
    rng = np.random.default_rng(seed)
    m = grid_mesh(int(rng.integers(1, 7)), int(rng.integers(1, 7)))
    perm = rng.permutation(len(m.points))  # scattered vertex numbering
    tri = np.argsort(perm)[m.triangles][rng.permutation(m.n_triangles)]
    twin, bad = core_kernels.half_edge_twins(tri, len(m.points))
    ref, rbad = core_kernels._half_edge_twins_reference(tri, len(m.points))
    assert bad == rbad == -1 and np.array_equal(twin, ref)
    # every pair: opposite directions of one edge
    h = np.flatnonzero(twin >= 0)
    t, k = h // 3, h % 3
    g = twin[h]
    assert np.array_equal(twin[g], h)
    assert np.array_equal(tri[t, k], tri[g // 3, (g % 3 + 1) % 3])


@pytest.mark.parametrize(
    "tri",
    [
        [[0, 1, 2], [0, 1, 3]],  # edge (0, 1) twice in one direction
        [[0, 1, 2], [1, 0, 3], [0, 1, 4]],  # three triangles on one edge
        [[0, 1, 2], [1, 0, 3], [1, 0, 4]],
    ],
)
def test_packed_pairing_reports_the_same_bad_half_edge(tri):
    tri = np.array(tri, np.int64)
    assert core_kernels.half_edge_twins(tri, 5)[1] == core_kernels._half_edge_twins_reference(tri, 5)[1] >= 0


@pytest.mark.parametrize("mesh", [square_mesh(0.01), torus_mesh(9, 6), grid_mesh(6, 4, z=True)], ids=["square", "torus", "grid"])
def test_renumbered_cover_is_the_plain_one(mesh):
    """Improving in path order (permute_mesh) visits the ends in the input's order: same cover."""
    d = dual_mesh(mesh)
    tri2, twin2, order2, starts2, ids = _greedy_cover(d)
    order0, starts0 = _kernels.greedy_paths(d.triangles, d.twin, 1, np.arange(d.n_triangles - 1, -1, -1))
    if len(starts0) == 2:  # one path: left as the greedy pass made it, input numbering
        assert ids is None and np.array_equal(order2, order0) and tri2 is d.triangles
        return
    assert np.array_equal(tri2, d.triangles[ids])
    assert np.array_equal(order0, ids)
    plain, plain_starts = _kernels.improve_cover(
        d.triangles, d.twin, order0, starts0, 2, np.arange(d.n_triangles, dtype=np.int64)
    )
    assert np.array_equal(ids[order2], plain) and np.array_equal(starts2, plain_starts)
    order, starts = greedy_paths(d)
    assert np.array_equal(order, plain) and sorted(order.tolist()) == list(range(d.n_triangles))


def test_permute_mesh_keeps_the_pairing():
    d = dual_mesh(square_mesh(0.01))
    perm = np.random.default_rng(3).permutation(d.n_triangles)
    tri2, twin2, new_id = _kernels.permute_mesh(d.triangles, d.twin, perm)
    assert np.array_equal(tri2, d.triangles[perm]) and np.array_equal(new_id[perm], np.arange(d.n_triangles))
    h = np.arange(3 * d.n_triangles)
    t, k = h // 3, h % 3
    mapped = np.where(d.twin >= 0, 3 * new_id[d.twin // 3] + d.twin % 3, -1)
    assert np.array_equal(twin2[3 * new_id[t] + k], mapped)


def test_one_pass_emission_has_the_counted_length():
    m = square_mesh(0.001)
    s = encode(m)
    decoded = decode_gl_strip(s.indices, s.restart_index)
    assert oriented_set(decoded) == oriented_set(m.triangles)
    assert len(s.indices) == m.n_triangles + 2 * s.n_strips + s.n_swaps + s.n_strips - 1
