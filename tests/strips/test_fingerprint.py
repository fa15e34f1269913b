"""The two-halves encoder's self-check: multiset fingerprints of oriented triangles
(:mod:`hammesh.strips._fingerprint_kernels`), against plain-Python references."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import VerificationError
from hammesh.halfedge import mesh_arrays
from hammesh.strips import halves
from hammesh.strips._fingerprint_kernels import draws_fingerprint, fingerprint_keys, rows_fingerprint_into
from hammesh.strips.encode import encode
from hammesh.strips.gl import RESTART_INDEX

from .conftest import delaunay_mesh, gl_decode_reference, oriented_set

_MASK = 2**64 - 1


def _hash_reference(a: int, b: int, c: int, keys) -> int:
    """triangle_hash in Python integers: rotated to the least index, then the keyed mix."""
    r = [x if 0 <= x <= 0xFFFFFFFF else 0xFFFFFFFF for x in (a, b, c)]
    i = r.index(min(r))
    p, q, w = r[i:] + r[:i]
    k0, k1, k2 = (int(k) for k in keys)
    h = ((((p << 32) | q) * k0) & _MASK) ^ ((w * k1 + k2) & _MASK)
    for mult in (0xFF51AFD7ED558CCD, 0xC4CEB9FE1A85EC53):
        h ^= h >> 33
        h = (h * mult) & _MASK
    return h ^ (h >> 33)


def _rows_sum(tri, keys) -> int:
    out = np.zeros(1, np.uint64)
    rows_fingerprint_into(np.ascontiguousarray(tri, np.int64).reshape(-1), keys, out)
    return int(out[0])


def _distinct(r) -> bool:
    """Three different indices once out-of-range ones are read as one (drawn triangles and
    checked rows always have three)."""
    return len({x if 0 <= x <= 0xFFFFFFFF else -1 for x in r}) == 3


@given(st.lists(st.tuples(*[st.integers(-3, 2**33)] * 3).filter(_distinct), min_size=1, max_size=20))
@settings(max_examples=60, deadline=None)
def test_hash_matches_the_reference_and_ignores_rotations_only(rows):
    keys = fingerprint_keys()
    tri = np.array(rows, np.int64)
    for a, b, c in rows:
        h = _hash_reference(a, b, c, keys)
        # as a kernel sums them: one row at a time
        assert _rows_sum(np.array([[a, b, c]]), keys) == h == _rows_sum(np.array([[b, c, a]]), keys)
        assert _rows_sum(np.array([[c, a, b]]), keys) == h
    assert _rows_sum(tri, keys) == sum(_hash_reference(*r, keys) for r in rows) & _MASK


def test_a_reversed_winding_hashes_differently():
    keys = fingerprint_keys()
    rng = np.random.default_rng(5)
    for _ in range(200):
        a, b, c = (int(x) for x in rng.choice(10**6, 3, replace=False))
        assert _hash_reference(a, b, c, keys) != _hash_reference(a, c, b, keys)


def _draws(indices, keys):
    return draws_fingerprint(np.asarray(indices, np.int64), RESTART_INDEX, True, keys)


@given(st.integers(0, 2**32 - 1), st.integers(20, 200), st.integers(0, 5))
@settings(max_examples=80, deadline=None)
def test_fingerprints_agree_exactly_when_the_buffer_draws_the_mesh(seed, n, corrupt):
    """Over encoded buffers, right and damaged (an index changed, two swapped, one dropped,
    one repeated, a strip reversed): the count and the sum of what a buffer draws equal the
    rows' exactly when the plain-Python OpenGL decoder draws the rows' oriented multiset."""
    m = delaunay_mesh(seed, n)
    s = encode(m, fast=True)
    idx = np.array(s.indices, np.int64)
    rng = np.random.default_rng(seed)
    i, j = (int(x) for x in rng.integers(len(idx), size=2))
    if corrupt == 1:
        idx[i] = (idx[i] + 1 + int(rng.integers(5))) % len(m.points)
    elif corrupt == 2:
        idx[[i, j]] = idx[[j, i]]
    elif corrupt == 3:
        idx = np.delete(idx, i)
    elif corrupt == 4:
        idx = np.insert(idx, i, idx[j])
    elif corrupt == 5 and len(idx) >= 3:
        idx[: 3] = idx[2::-1]  # the first triangle wound the other way (or its strip reread)
    keys = fingerprint_keys()
    got = _draws(idx, keys)
    drawn = gl_decode_reference(idx.tolist(), RESTART_INDEX)
    truth = oriented_set(drawn) == oriented_set(m.triangles)
    assert (got.count == len(m.triangles) and int(got.sum) == _rows_sum(m.triangles, keys)) == truth
    assert got.count == len(drawn)


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=30, deadline=None)
def test_parts_cut_after_a_restart_add_up_to_the_whole(seed):
    m = delaunay_mesh(seed, 150)
    s = encode(m, fast=True)
    idx = np.array(s.indices, np.int64)
    cuts = np.flatnonzero(idx == RESTART_INDEX)
    if len(cuts) == 0:
        return
    c = int(cuts[len(cuts) // 2])
    keys = fingerprint_keys()
    whole, a, b = _draws(idx, keys), _draws(idx[:c], keys), _draws(idx[c + 1 :], keys)
    assert whole.count == a.count + b.count
    assert int(whole.sum) == (int(a.sum) + int(b.sum)) & _MASK


def _wrong_half(m, monkeypatch, damage):
    real = halves.greedy_strip_buffer

    def broken(rec, w_swap, restart, work):
        g = real(rec, w_swap, restart, work)
        damage(g.indices, restart)
        return g

    monkeypatch.setattr(halves, "greedy_strip_buffer", broken)
    pts, tri = mesh_arrays(m.points, m.triangles, dims=(2, 3))
    return lambda verify: halves.encode_in_halves(pts, tri, RESTART_INDEX, verify, 1, None)


def _flip_a_lone_triangle(indices, restart):
    """A strip of one triangle wound the other way: as many draws, one winding wrong."""
    r = np.flatnonzero(indices == restart)
    ends = np.r_[-1, r, len(indices)]
    lone = [int(a) + 1 for a, b in zip(ends[:-1], ends[1:]) if b - a - 1 == 3]
    if not lone:
        indices[:3] = indices[2::-1]
        return
    t = lone[0]
    indices[t], indices[t + 1] = indices[t + 1], indices[t]


def _draw_one_row_twice(indices, restart):
    """The first lone triangle's strip replaced by the second's: a row drawn twice, one missing."""
    r = np.flatnonzero(indices == restart)
    ends = np.r_[-1, r, len(indices)]
    lone = [int(a) + 1 for a, b in zip(ends[:-1], ends[1:]) if b - a - 1 == 3]
    if len(lone) < 2:
        indices[1] = indices[0]
        return
    indices[lone[0] : lone[0] + 3] = indices[lone[1] : lone[1] + 3]


@pytest.mark.parametrize("damage", [_flip_a_lone_triangle, _draw_one_row_twice])
def test_the_halves_proof_catches_a_buffer_with_the_right_count(monkeypatch, damage):
    """Mutations the count of draws cannot see (a winding flipped, a row drawn twice and
    another never): the fingerprints differ, the full comparison names the problem."""
    run = _wrong_half(delaunay_mesh(11, 3000), monkeypatch, damage)
    with pytest.raises(VerificationError):
        run(True)
    assert run(False) is not None  # the proof is what catches it
