"""Compiled helpers of the strip encoder: the ``_nrt`` fallback, the greedy cover against
its plain-Python oracle, the path-order renumbering, the one-pass restart emission and
the records it pairs half-edges in (the core pairing itself: tests/halfedge/test_kernels.py)."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.halfedge import _kernels as core_kernels
from tests.helpers import BAD_EDGES
from hammesh.mesh import Mesh
from hammesh.strips import _numba
from hammesh.strips._cover_kernels import greedy_path_cover, renumber_in_path_order
from hammesh.strips._dual_kernels import REC_TWIN, mesh_records, records_from_twin
from hammesh.strips._moves_kernels import improve_cover
from hammesh.strips._path_kernels import edge_towards, slot_of
from hammesh.strips.defects import proper_pairing
from hammesh.strips.dual import dual_mesh
from hammesh.strips.encode import _greedy_cover, encode, greedy_paths
from hammesh.strips.gl import decode_gl_strip

from tests.helpers import grid_mesh

from .conftest import delaunay_mesh, oriented_set, square_mesh, torus_mesh
from .reference_cover import reference_greedy_cover

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
        from hammesh.strips import _numba, encode, decode_gl_strip
        assert _numba.HELPERS_WITHOUT_REFCOUNT is False
        # isolate=False: no background loading of hamiltonian()'s kernels (compiled from
        # scratch in this private cache, minutes that this test is not about)
        m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.01, isolate=False)
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


def test_loop_helpers_compile_without_nrt_here():
    assert _numba.HELPERS_WITHOUT_REFCOUNT  # this environment's numba accepts the option


@pytest.mark.parametrize("mesh", [square_mesh(0.01), torus_mesh(9, 6), grid_mesh(6, 4, z=True)], ids=["square", "torus", "grid"])
def test_renumbered_cover_is_the_plain_one(mesh):
    """Improving in path order (permute_records) visits the ends from the last path back: the
    same cover as visiting them in that order in the input's numbering."""
    d = dual_mesh(mesh)
    tri2, twin2, order2, starts2, ids = _greedy_cover(d)
    order0, starts0 = greedy_path_cover(d.cover_records().copy(), 1, np.arange(d.n_triangles - 1, -1, -1))
    if len(starts0) == 2:  # one path: left as the greedy pass made it, input numbering
        assert ids is None and np.array_equal(order2, order0) and tri2 is d.triangles
        return
    assert np.array_equal(tri2, d.triangles[ids])
    assert np.array_equal(order0, ids)
    plain, plain_starts = improve_cover(d.triangles, d.twin, order0.astype(np.int64), starts0, 2, order0[::-1].astype(np.int64))
    assert np.array_equal(ids[order2], plain) and np.array_equal(starts2, plain_starts)
    order, starts = greedy_paths(d)
    assert np.array_equal(order, plain) and sorted(order.tolist()) == list(range(d.n_triangles))


def test_renumbering_keeps_the_pairing():
    d = dual_mesh(square_mesh(0.01))
    perm = np.random.default_rng(3).permutation(d.n_triangles)
    tri2, twin2, new_id = renumber_in_path_order(d.records, perm)
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


def _scattered_mesh(seed: int) -> tuple[np.ndarray, int]:
    """A grid (2D or a 3D surface) with scattered vertex and row numbering, as Triangle writes."""
    rng = np.random.default_rng(seed)
    m = grid_mesh(int(rng.integers(1, 7)), int(rng.integers(1, 7)), z=bool(rng.integers(2)))
    perm = rng.permutation(len(m.points))
    return np.argsort(perm)[m.triangles][rng.permutation(m.n_triangles)], len(m.points)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_mesh_records_pair_like_the_reference(seed):
    tri, n = _scattered_mesh(seed)
    rec, twin = mesh_records(tri, n)
    ref, bad = core_kernels.half_edge_twins_reference(tri, n)
    assert bad == -1 and np.array_equal(twin, ref)
    assert rec.dtype == np.int32 and np.array_equal(rec[:, :3], tri)
    assert np.array_equal(rec[:, REC_TWIN : REC_TWIN + 3].ravel(), ref)


@pytest.mark.parametrize("tri", BAD_EDGES)
def test_mesh_records_refuse_bad_edges(tri):
    """No packed records for a bad edge: dual_mesh then pairs proper edges only (bad ones cut)."""
    assert mesh_records(np.array(tri, np.int64), 5) is None
    d = dual_mesh(Mesh(np.random.default_rng(0).random((5, 2)), np.array(tri)))
    assert d.defects.non_manifold_edges + d.defects.flipped_neighbours >= 1
    assert np.array_equal(d.twin, proper_pairing(np.array(tri), 5).twin)


def test_mesh_records_of_two_triangles_on_the_same_three_edges():
    """A closed two-triangle 'pillow': each triangle is the other's neighbour three times."""
    tri = np.array([[0, 1, 2], [0, 2, 1]], np.int64)
    rec, twin = mesh_records(tri, 3)
    assert np.array_equal(twin, core_kernels.half_edge_twins_reference(tri, 3)[0])
    m = Mesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), tri)
    assert oriented_set(decode_gl_strip(*(lambda s: (s.indices, s.restart_index))(encode(m)))) == oriented_set(tri)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 3))
def test_greedy_cover_is_the_plain_python_one(seed, w_swap):
    """The compiled greedy cover, on int32 and on int64 records, is the oracle's cover."""
    tri, n = _scattered_mesh(seed)
    rec, twin = mesh_records(tri, n)
    m = len(tri)
    seeds = np.random.default_rng(seed).permutation(m)
    want = reference_greedy_cover(tri, twin, w_swap, seeds)
    rec64 = np.empty(rec.shape, np.int64)
    records_from_twin(tri, twin, rec64)
    for r in (rec, rec64):
        order, starts = greedy_path_cover(r, w_swap, seeds)
        assert np.array_equal(order, want[0]) and np.array_equal(starts, want[1])
    a = renumber_in_path_order(rec, want[0])
    b = renumber_in_path_order(rec64, want[0])
    assert a.tri.dtype == np.int32 and b.tri.dtype == np.int64
    assert all(np.array_equal(x, y) for x, y in zip(a, b))


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(20, 300), st.booleans())
def test_greedy_cover_matches_the_oracle_on_delaunay_meshes(seed, n, lift):
    d = dual_mesh(delaunay_mesh(seed, n, lift))
    seeds = np.arange(d.n_triangles - 1, -1, -1)
    want = reference_greedy_cover(d.triangles, d.twin, 1, seeds)
    got = greedy_path_cover(d.cover_records().copy(), 1, seeds)
    assert np.array_equal(got.order, want[0]) and np.array_equal(got.starts, want[1])


def test_cover_without_records_is_the_same():
    """A DualMesh built by hand (no records) builds them: the same cover."""
    d = dual_mesh(square_mesh(0.01))
    bare = dataclasses.replace(d, records=None)
    a, b = _greedy_cover(d), _greedy_cover(bare)
    assert all(np.array_equal(x, y) for x, y in zip(a[1:], b[1:]))


@pytest.mark.parametrize("row", [[5, 7, 9], [7, 7, 9], [9, 5, 7], [-1, 4, -1], [3, 3, 3]])
@pytest.mark.parametrize("u", [7, 9, -1, 4, 3, 8])
def test_branch_free_edge_search_is_the_first_match(row, u):
    nb = np.array([row], np.int32)
    want = row.index(u) if u in row else -1
    assert slot_of(nb, 0, u) == want
    if u >= 0:  # edge_towards: the half-edge pairing, twin 3 u + j lies in triangle u
        twin = np.array([3 * v + 1 if v >= 0 else -1 for v in row], np.int64)
        assert edge_towards(twin, 0, u) == want


@pytest.mark.slow
@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(20, 400), st.booleans())
def test_tunnel_pre_filter_skips_only_moves_that_would_be_rejected(seed, n, lift):
    """The pre-filter is exact: the same cover as evaluating every tunnel."""
    d = dual_mesh(delaunay_mesh(seed, n, lift))
    m = d.n_triangles
    order, starts = greedy_path_cover(d.cover_records().copy(), 1, np.arange(m - 1, -1, -1))
    order = order.astype(np.int64)
    visit = np.random.default_rng(seed).permutation(m)
    a = improve_cover(d.triangles, d.twin, order, starts, 2, visit)
    b = improve_cover(d.triangles, d.twin, order, starts, 2, visit, skip_hopeless_tunnels=False)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 3))
def test_cover_without_a_seed_order_is_the_oracle_with_seeds_last_first(seed, w_swap):
    """No seed order (each degree taken as its row is queued, one pass over the records) is the
    oracle's cover with seeds ``m - 1, ..., 0``, on int32 and int64 records."""
    from hammesh.strips._greedy_strip_kernels import NO_SEED_ORDER

    tri, n = _scattered_mesh(seed)
    rec, twin = mesh_records(tri, n)
    want = reference_greedy_cover(tri, twin, w_swap, np.arange(len(tri) - 1, -1, -1))
    rec64 = np.empty(rec.shape, np.int64)
    records_from_twin(tri, twin, rec64)
    for r in (rec, rec64):
        order, starts = greedy_path_cover(r, w_swap, NO_SEED_ORDER)
        assert np.array_equal(order, want[0]) and np.array_equal(starts, want[1])
