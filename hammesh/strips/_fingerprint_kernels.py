"""Compiled multiset fingerprints of oriented triangles: the two-halves encoder's self-check.

A buffer draws each input row once with its winding exactly when the multiset of the
triangles it draws (OpenGL's strip rules), each rotated to start at its least vertex
(winding kept), equals the multiset of the input rows rotated the same way.  Both sides
are summed here as 64-bit hashes (:func:`triangle_hash`, keyed per call): the input's rows
in any order (:func:`rows_fingerprint_into`, half of them by their numbers on each of the
halves' threads), the buffer by its own decoder (:func:`draws_fingerprint`).  No claim of the
encoder is read (no draw order, no row copy); the sums and the count of draws decide.

This is the additive multiset hash (MSet-Add-Hash) of Clarke, Devadas, van Dijk, Gassend
and Suh, *Incremental Multiset Hash Functions and Their Application to Memory Integrity
Checking*, ASIACRYPT 2003: with a random function into ``Z / 2**64``, two different
multisets (sizes ``< 2**63``) have equal sums with probability ``<= 2**-63``.  Here the
function is a keyed mix (odd multipliers and an offset drawn per call from the OS's
entropy, then MurmurHash3's 64-bit finaliser, github.com/aappleby/smhasher): a strong
mixer, not a proven random function, so the bound is a design figure, not a theorem; a
buffer that differs from the mesh passes only by such a coincidence, and every buffer
that draws the mesh passes (equal multisets have equal sums, whatever the keys).
Compared with the claimed-order proof it replaces on this path (an exact check of the
encoder's claim, ~11 ms a half at 1M triangles: gathers of the input rows at random),
both passes here read their arrays in order (session 16, docs/strips.md).

Nothing here is shared with the writers (:mod:`hammesh.strips._emit_kernels`) or the
encoder's copies of the rows.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.strips._numba import kernel, loop_helper, row

__all__ = ["fingerprint_keys", "triangle_hash", "rows_fingerprint_into", "DrawsFingerprint",
           "draws_fingerprint"]

_M1 = np.uint64(0xFF51AFD7ED558CCD)  # MurmurHash3 fmix64's multipliers
_M2 = np.uint64(0xC4CEB9FE1A85EC53)
_S33 = np.uint64(33)
_S32 = np.uint64(32)
#: An index outside ``[0, 2**32)`` is hashed as this one (no row holds it: rows index
#: fewer than ``2**31`` points on this path).
_OUTSIDE = np.int64(0xFFFFFFFF)


def fingerprint_keys() -> np.ndarray:
    """The keys of :func:`triangle_hash`, new: ``(3,) uint64``, two odd multipliers and an
    offset, from the OS's entropy."""
    import secrets

    k = np.array([secrets.randbits(64) for _ in range(3)], np.uint64)
    k[:2] |= np.uint64(1)
    return k


@loop_helper
def _index_bits(v):
    """``v`` as ``uint64``, an index outside ``[0, 2**32)`` as ``_OUTSIDE``."""
    return np.uint64(v if (v >= 0) & (v <= _OUTSIDE) else _OUTSIDE)


@loop_helper
def triangle_hash(a, b, c, keys):
    """64-bit hash of the oriented triangle ``(a, b, c)`` (three different indices), the same
    for its three rotations.

    Rotated to start at its least index (the winding kept: ``(a, b, c)``, ``(b, c, a)``
    and ``(c, a, b)`` hash alike, ``(a, c, b)`` does not), the first two indices packed in
    one word; then ``fmix64(u * k0 ^ (w * k1 + k2))`` (``u``: the packed pair, ``w``: the
    third index).  For fixed keys it is injective in ``u`` for a fixed ``w`` and in ``w``
    for a fixed ``u``.  Selects, not branches: the rotation is a coin toss per triangle.
    """
    x = _index_bits(a)
    y = _index_bits(b)
    z = _index_bits(c)
    xf = (x < y) & (x < z)
    yf = (y < x) & (y < z)
    p = x if xf else (y if yf else z)
    q = y if xf else (z if yf else x)
    r = z if xf else (x if yf else y)
    h = ((p << _S32) | q) * keys[0] ^ (r * keys[1] + keys[2])
    h ^= h >> _S33
    h *= _M1
    h ^= h >> _S33
    h *= _M2
    h ^= h >> _S33
    return h


@kernel
def rows_fingerprint_into(flat, keys, out):
    """``out[0]``: the sum (mod ``2**64``) of :func:`triangle_hash` over the rows ``flat``
    (``(3 m,)``: a C-contiguous ``(m, 3)`` array's ``reshape(-1)``; read flat, ~25% faster
    than through two indices at 1M triangles)."""
    s = np.uint64(0)
    for t in range(flat.shape[0] // 3):
        j = row(3 * t)
        s += triangle_hash(flat[j], flat[j + row(1)], flat[j + row(2)], keys)
    out[0] = s


#: :func:`draws_fingerprint`'s result: how many triangles the buffer draws and the sum of
#: their hashes (``uint64``).
DrawsFingerprint = namedtuple("DrawsFingerprint", ["count", "sum"])


@kernel
def draws_fingerprint(indices, restart, use_restart, keys):
    """The triangles ``indices`` draws with OpenGL's strip rules (a window of three distinct
    indices is a triangle, drawn ``(b, a, v)`` when it starts at an odd position of its
    strip; ``restart`` starts a new strip when ``use_restart``): how many, and the sum of
    their :func:`triangle_hash` (a :class:`DrawsFingerprint`).  A buffer cut just after a
    restart index: each part decodes as it does inside the whole, so the parts' counts and
    sums add up to the whole's."""
    total = np.uint64(0)
    count = 0
    # the last two indices of the current strip (a window's first two) and how many of
    # its indices have been read; a restart empties the window
    first = np.int64(-1)
    second = np.int64(-1)
    seen = 0
    for i in range(indices.shape[0]):
        v = np.int64(indices[i])
        if use_restart and v == restart:
            seen = 0
            continue
        if (seen >= 2) & (first != second) & (second != v) & (first != v):
            # odd position: drawn (second, first, v); selects, the parity is a coin toss
            flip = (seen & 1) == 1
            total += triangle_hash(second if flip else first, first if flip else second, v, keys)
            count += 1
        first = second
        second = v
        seen += 1
    return DrawsFingerprint(count, total)
