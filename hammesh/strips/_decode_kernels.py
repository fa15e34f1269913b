"""Compiled readers of strip buffers: OpenGL's and IRIS GL's decoding rules, and the
one-pass round-trip proof.  Nothing here is shared with the writers
(:mod:`hammesh.strips._emit_kernels`): the proof derives every drawn triangle itself.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel

__all__ = ["decode_generalized_strips", "check_claimed_draws", "check_claimed_part"]


@kernel
def decode_generalized_strips(vertices, vertex_starts, swaps, tri_starts):
    """Oriented triangles of generalized strips (two registers, IRIS GL ``swaptmesh``).

    Strip ``s`` has vertices ``vertices[vertex_starts[s]:vertex_starts[s + 1]]`` (its
    triangle count plus two) and one swap bit per triangle.  The registers start as
    the first two vertices; for each further vertex ``v``: if its bit is set the
    registers swap, the triangle is ``(r0, r1, v)`` on even parity and ``(r1, r0, v)``
    on odd parity (parity flips per triangle and per swap), then ``r0, r1 = r1, v``.
    """
    T = swaps.shape[0]
    out = np.empty((T, 3), np.int64)
    S = tri_starts.shape[0] - 1
    for s in range(S):
        va = vertex_starts[s]
        ta = tri_starts[s]
        k = tri_starts[s + 1] - ta
        r0 = vertices[va]
        r1 = vertices[va + 1]
        parity = 0
        for j in range(k):
            v = vertices[va + 2 + j]
            if swaps[ta + j]:
                tmp = r0
                r0 = r1
                r1 = tmp
                parity ^= 1
            if parity == 0:
                out[ta + j, 0] = r0
                out[ta + j, 1] = r1
            else:
                out[ta + j, 0] = r1
                out[ta + j, 1] = r0
            out[ta + j, 2] = v
            r0 = r1
            r1 = v
            parity ^= 1
    return out


@kernel
def _same_rotation(a, b, c, x, y, z):
    # & and | rather than short-circuit `and` / `or`: no branches
    return ((a == x) & (b == y) & (c == z)) | ((a == y) & (b == z) & (c == x)) | ((a == z) & (b == x) & (c == y))


def check_claimed_draws(tri, indices, restart, use_restart, order):
    """Decode ``indices`` with OpenGL's strip rules and compare with a claimed draw order.

    The ``k``-th non-degenerate triangle drawn must be ``tri[order[k]]`` with the same
    winding (any rotation), and ``order`` must name every row exactly once: then the
    buffer draws exactly the mesh's oriented triangles.  Returns ``(status, k)``:
    0 ok; 1 draw ``k`` differs from the claim; 2 more draws than rows; 3 fewer (``k``
    draws); 4 ``order[k]`` out of range or repeated.
    """
    m = tri.shape[0]
    if order.shape[0] != m:
        return 4, min(order.shape[0], m)
    return check_claimed_part(tri, indices, restart, use_restart, order, np.zeros(m, np.bool_))


@kernel
def check_claimed_part(tri, indices, restart, use_restart, order, seen):
    """:func:`check_claimed_draws` on a part of a buffer that starts a strip (at a restart).

    ``indices`` must draw exactly the rows ``order``, in that order; each is marked in
    ``seen`` (shared by the parts, so a row repeated *within* the part is status 4).  The
    parts of one buffer cut just after restart indices decode as the whole does (a
    restart resets the strip), so when every part returns 0, the claims add up to ``m``
    rows and every row is in ``seen``, the buffer draws each row once with its winding.
    """
    m = tri.shape[0]
    n = order.shape[0]
    L = indices.shape[0]
    pos = 0  # position inside the current strip
    k = 0
    for i in range(L):
        v = indices[i]
        if use_restart and v == restart:
            pos = 0
            continue
        if pos >= 2:
            a = indices[i - 2]
            b = indices[i - 1]
            if (a != b) & (b != v) & (a != v):
                if k >= n:
                    return 2, k
                t = order[k]
                if t < 0 or t >= m or seen[t]:
                    return 4, k
                seen[t] = True
                # selects instead of branches: the window's parity would be mispredicted
                odd = pos % 2 == 1  # window starts at an odd position: drawn (b, a, v)
                x = b if odd else a
                y = a if odd else b
                if not _same_rotation(x, y, v, tri[t, 0], tri[t, 1], tri[t, 2]):
                    return 1, k
                k += 1
        pos += 1
    if k != n:
        return 3, k
    return 0, -1
