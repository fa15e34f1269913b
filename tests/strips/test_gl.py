"""GL_TRIANGLE_STRIP buffers: decoder semantics, exact counts, round trips of any dual path cover."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hammesh.errors import InvalidMeshError, InvalidOptionError, VerificationError
from hammesh.strips.dual import dual_mesh
from hammesh.strips.gl import RESTART_INDEX, decode_gl_strip, gl_strip, verify_gl_strip

from tests.helpers import grid_mesh

from .conftest import (
    SMALL_MESHES,
    corrupt_claim,
    fan_mesh,
    gl_decode_reference,
    oriented_set,
    random_path_cover,
    torus_mesh,
    zigzag_mesh,
)


# --- decoder: OpenGL rules, literally -------------------------------------------------


def test_decoder_parity_and_degenerates():
    assert decode_gl_strip([0, 1, 2, 3]).tolist() == [[0, 1, 2], [2, 1, 3]]
    assert decode_gl_strip([0, 1, 2, 2, 3, 4]).tolist() == [[0, 1, 2], [3, 2, 4]]  # position 3 is odd
    assert decode_gl_strip([0, 1]).tolist() == []
    assert decode_gl_strip([5, 5, 5, 5]).tolist() == []


def test_decoder_restart_resets_parity():
    r = 99
    # without restart parity would make [5, 4, 6] out of the second strip's first triangle
    assert decode_gl_strip([0, 1, 2, 3, r, 4, 5, 6], r).tolist() == [[0, 1, 2], [2, 1, 3], [4, 5, 6]]
    assert decode_gl_strip([r, 0, 1, r, 2, 3, 4, r], r).tolist() == [[2, 3, 4]]
    # restart disabled: the value is an ordinary index
    assert decode_gl_strip([0, 1, 99], None).tolist() == [[0, 1, 99]]


@given(
    st.lists(st.integers(0, 6), min_size=0, max_size=40),
    st.sampled_from([None, 6]),
)
def test_decoder_matches_reference(indices, restart):
    got = [tuple(t) for t in decode_gl_strip(np.array(indices, dtype=np.int64), restart).tolist()]
    assert got == gl_decode_reference(indices, restart)


# --- exact counts on known cases -------------------------------------------------------


@pytest.mark.parametrize("k", [1, 2, 3, 4, 7, 12])
def test_zigzag_needs_no_swap(k):
    m = zigzag_mesh(k)
    d = dual_mesh(m)
    s = gl_strip(d.triangles, d.twin, np.arange(k), [0, k])
    assert s.n_swaps == 0
    assert len(s.indices) == k + 2
    assert s.indices.tolist() == list(range(k + 2))
    verify_gl_strip(m.triangles, s.indices)


@pytest.mark.parametrize("k", [3, 4, 5, 6, 7])
def test_fan_needs_swaps(k):
    # the path crosses k - 1 edges all at vertex 0: every third consecutive one repeats the pivot
    m = fan_mesh(k)
    d = dual_mesh(m)
    s = gl_strip(d.triangles, d.twin, np.arange(k), [0, k])
    assert s.n_swaps == k - 3
    assert len(s.indices) == k + 2 + (k - 3)
    verify_gl_strip(m.triangles, s.indices)


def test_restart_and_stitch_costs():
    m = grid_mesh(3, 2)  # 12 triangles
    d = dual_mesh(m)
    order, starts = np.arange(12), np.array([0, 5, 6, 12])
    # rows of a grid are not all dual-adjacent in index order; take a valid cover instead
    order, starts = random_path_cover(d.neighbor_triangles, np.random.default_rng(1))
    S = len(starts) - 1
    r = gl_strip(d.triangles, d.twin, order, starts, join="restart")
    s = gl_strip(d.triangles, d.twin, order, starts, join="stitch")
    assert r.n_strips == s.n_strips == S
    assert len(r.indices) == 12 + 2 * S + r.n_swaps + (S - 1)
    assert int(np.sum(r.indices == RESTART_INDEX)) == S - 1
    # stitching: two per join, and odd starts may trade the first swap (never costs more)
    assert len(s.indices) == 12 + 2 * S + s.n_swaps + 2 * (S - 1)
    assert len(s.indices) <= 12 + 2 * S + r.n_swaps + 2 * (S - 1) + (S - 1)
    verify_gl_strip(m.triangles, r.indices, RESTART_INDEX)
    verify_gl_strip(m.triangles, s.indices, None)


# --- round trips -----------------------------------------------------------------------

MESHES = SMALL_MESHES


@given(st.sampled_from(sorted(MESHES)), st.integers(0, 2**32 - 1), st.sampled_from(["restart", "stitch"]))
def test_random_path_covers_round_trip(name, seed, join):
    mesh = MESHES[name]()
    d = dual_mesh(mesh)
    order, starts = random_path_cover(d.neighbor_triangles, np.random.default_rng(seed))
    s = gl_strip(d.triangles, d.twin, order, starts, join=join)
    decoded = decode_gl_strip(s.indices, s.restart_index)
    assert oriented_set(decoded) == oriented_set(mesh.triangles)
    assert len(decoded) == mesh.n_triangles
    # the drawn order is the path order
    assert oriented_set(decoded[:1]) == oriented_set(mesh.triangles[order[:1]])
    verify_gl_strip(mesh.triangles, s.indices, s.restart_index)


def test_stitch_single_triangles_and_pairs():
    # strips of 1 and 2 triangles at odd starts use the re-ordered start
    m = grid_mesh(2, 1)
    d = dual_mesh(m)
    nb = d.neighbor_triangles
    t1 = int(nb[0][nb[0] >= 0][0])
    rest = [t for t in range(4) if t not in (0, t1)]
    for order, starts in [([0, t1] + rest, [0, 2, 3, 4]), ([rest[0], 0, t1, rest[1]], [0, 1, 3, 4])]:
        s = gl_strip(d.triangles, d.twin, order, starts, join="stitch")
        verify_gl_strip(m.triangles, s.indices)


# --- errors ----------------------------------------------------------------------------


def test_non_adjacent_order_is_rejected():
    m = grid_mesh(3, 3)
    d = dual_mesh(m)
    far = int(np.flatnonzero((d.neighbor_triangles != 0).all(axis=1))[-1])
    with pytest.raises(InvalidMeshError, match="share no edge"):
        gl_strip(d.triangles, d.twin, [0, far], [0, 2])


def test_walk_turning_back_is_rejected():
    m = grid_mesh(2, 2)
    d = dual_mesh(m)
    u = int(d.neighbor_triangles[0][d.neighbor_triangles[0] >= 0][0])
    with pytest.raises(InvalidMeshError, match="turns back"):
        gl_strip(d.triangles, d.twin, [0, u, 0], [0, 3])


def test_bad_options():
    m = zigzag_mesh(3)
    d = dual_mesh(m)
    with pytest.raises(InvalidOptionError):
        gl_strip(d.triangles, d.twin, [0, 1, 2], [0, 3], join="glue")
    with pytest.raises(InvalidOptionError, match="restart index 1"):
        gl_strip(d.triangles, d.twin, [0, 1, 2], [0, 2, 3], restart_index=1)
    with pytest.raises(InvalidMeshError, match="offsets"):
        gl_strip(d.triangles, d.twin, [0, 1, 2], [0, 2])


def test_verify_names_reversed_and_missing():
    m = zigzag_mesh(3)
    with pytest.raises(VerificationError, match="reversed"):
        verify_gl_strip(m.triangles, [1, 0, 2, 3, 4])
    with pytest.raises(VerificationError, match="not drawn"):
        verify_gl_strip(m.triangles, [0, 1, 2, 3])
    with pytest.raises(VerificationError, match="twice"):
        verify_gl_strip(m.triangles[:1], [0, 1, 2, 9, 0, 1, 2], 9)


# --- the fast proof: a claimed draw order, checked by one compiled pass ------------------


@given(st.integers(0, 2**32 - 1), st.sampled_from(["restart", "stitch"]), st.integers(0, 4))
def test_claimed_order_proof_agrees_with_the_full_comparison(seed, join, corrupt):
    """check_draws accepts exactly the buffers the literal decoder proves right."""
    from hammesh.strips._decode_kernels import check_claimed_draws

    m = grid_mesh(4, 3) if seed % 2 else torus_mesh(6, 4)
    d = dual_mesh(m)
    rng = np.random.default_rng(seed)
    order, starts = random_path_cover(d.neighbor_triangles, rng)
    s = gl_strip(d.triangles, d.twin, order, starts, join=join)
    idx, claim = corrupt_claim(s.indices, order, corrupt, rng, len(m.points), RESTART_INDEX)
    use_r = s.restart_index is not None
    status, _ = check_claimed_draws(d.triangles, idx, s.restart_index if use_r else -1, use_r, claim)
    truth = oriented_set(decode_gl_strip(idx, s.restart_index)) == oriented_set(m.triangles)
    if status == 0:
        assert truth  # the fast proof never accepts a wrong buffer
    if corrupt == 0:
        assert status == 0
    # verify_gl_strip with the claim decides exactly like the full comparison
    if truth:
        verify_gl_strip(m.triangles, idx, s.restart_index, order=claim)
    else:
        with pytest.raises(VerificationError):
            verify_gl_strip(m.triangles, idx, s.restart_index, order=claim)


def _claimed_status_reference(tri, indices, restart, order):
    """The claimed-order proof's ``(status, k)``, draw by draw in plain Python."""
    draws = gl_decode_reference(indices, restart)
    seen = set()
    for k, d in enumerate(draws):
        if k >= len(order):
            return 2, k
        t = int(order[k])
        if not 0 <= t < len(tri) or t in seen:
            return 4, k
        seen.add(t)
        row = [int(x) for x in tri[t]]
        if list(d) not in (row, row[1:] + row[:1], row[2:] + row[:2]):
            return 1, k
    return (0, -1) if len(draws) == len(order) else (3, len(draws))


def _faulty_claim(seed: int, corrupt: int):
    """A grid or torus mesh, a random path cover's restart buffer and its claim, with
    :func:`corrupt_claim`'s fault ``corrupt`` (none above 4): ``(mesh, dual, rng, order, idx, claim)``."""
    m = grid_mesh(4, 3) if seed % 2 else torus_mesh(6, 4)
    d = dual_mesh(m)
    rng = np.random.default_rng(seed)
    order, starts = random_path_cover(d.neighbor_triangles, rng)
    s = gl_strip(d.triangles, d.twin, order, starts, join="restart")
    idx, claim = corrupt_claim(s.indices, order, corrupt if corrupt <= 4 else 0, rng, len(m.points), RESTART_INDEX)
    return m, d, rng, order, idx, claim


@given(st.integers(0, 2**32 - 1), st.integers(0, 6))
def test_claimed_part_in_two_passes_reports_the_first_wrong_draw(seed, corrupt):
    """check_claimed_part (decode pass, then the gather pass) gives the status and draw of
    the one-pass definition for every fault, including an index too big for ``int32``
    (6) that must not wrap onto a vertex."""
    from hammesh.strips._decode_kernels import check_claimed_part

    m, d, rng, order, idx, claim = _faulty_claim(seed, corrupt)
    if corrupt == 5:
        claim = claim[:-1]  # one draw more than claimed
    if corrupt == 6:
        i = int(rng.integers(len(idx)))
        if idx[i] != RESTART_INDEX:
            idx[i] += 2**32  # the same vertex modulo 2**32
    tri = d.triangles.astype(np.int64)
    got = check_claimed_part(tri, idx.astype(np.int64), RESTART_INDEX, True, np.asarray(claim, np.int64),
                             np.zeros(len(tri), np.bool_))
    assert tuple(int(x) for x in got) == _claimed_status_reference(tri, idx, RESTART_INDEX, claim)


def test_claimed_order_with_a_bad_claim_falls_back_to_naming_the_problem():
    m = zigzag_mesh(3)
    with pytest.raises(VerificationError, match="reversed"):
        verify_gl_strip(m.triangles, [1, 0, 2, 3, 4], order=[0, 1, 2])
    # a right buffer passes whatever the claim (the full comparison decides)
    verify_gl_strip(m.triangles, [0, 1, 2, 3, 4], order=[2, 0, 1])
    verify_gl_strip(m.triangles, [0, 1, 2, 3, 4], order=[0, 0, 1])
    verify_gl_strip(m.triangles, [0, 1, 2, 3, 4], order=[0, 1])


@given(st.integers(0, 2**32 - 1), st.booleans())
def test_one_pass_restart_encoder_equals_the_turn_arrays(seed, restart_is_vertex):
    """_emit_kernels.restart_buffer (encode's fast path) == path_turns + emission, index for index."""
    from hammesh.strips.encode import restart_strip

    m = grid_mesh(5, 3, z=True) if seed % 3 else torus_mesh(7, 5)
    d = dual_mesh(m)
    order, starts = random_path_cover(d.neighbor_triangles, np.random.default_rng(seed))
    order, starts = np.asarray(order, np.int64), np.asarray(starts, np.int64)
    R = 3 if restart_is_vertex else RESTART_INDEX
    if restart_is_vertex and len(starts) > 2:
        with pytest.raises(InvalidOptionError, match="restart index 3"):
            restart_strip(d.triangles, d.twin, order, starts, R)
        with pytest.raises(InvalidOptionError, match="restart index 3"):
            gl_strip(d.triangles, d.twin, order, starts, restart_index=R)
        return
    a = gl_strip(d.triangles, d.twin, order, starts, restart_index=R)
    b = restart_strip(d.triangles, d.twin, order, starts, R)
    assert a.indices.tolist() == b.indices.tolist()
    assert (a.n_swaps, a.n_strips, a.n_triangles) == (b.n_swaps, b.n_strips, b.n_triangles)


def test_one_pass_restart_encoder_names_bad_paths():
    from hammesh.strips.encode import restart_strip

    m = grid_mesh(3, 3)
    d = dual_mesh(m)
    far = int(np.flatnonzero((d.neighbor_triangles != 0).all(axis=1))[-1])
    with pytest.raises(InvalidMeshError, match="share no edge"):
        restart_strip(d.triangles, d.twin, np.array([0, far]), np.array([0, 2]), RESTART_INDEX)
    u = int(d.neighbor_triangles[0][d.neighbor_triangles[0] >= 0][0])
    with pytest.raises(InvalidMeshError, match="turns back"):
        restart_strip(d.triangles, d.twin, np.array([0, u, 0]), np.array([0, 3]), RESTART_INDEX)
