"""Compiled readers of strip buffers: OpenGL's and IRIS GL's decoding rules, and the
one-pass round-trip proof.  Nothing here is shared with the writers
(:mod:`hammesh.strips._emit_kernels`): the proof derives every drawn triangle itself.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel

__all__ = ["decode_generalized_strips", "check_claimed_draws"]


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


@kernel
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
    seen = np.zeros(m, np.bool_)
    for k in range(m):
        t = order[k]
        if t < 0 or t >= m or seen[t]:
            return 4, k
        seen[t] = True
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
            # selects instead of branches: a degenerate window (a swap, ~1 in 5) or the
            # window's parity would be mispredicted; the row read for a degenerate
            # window is ignored, the two early exits almost never taken
            drawn = (a != b) & (b != v) & (a != v)
            if drawn & (k >= m):
                return 2, k
            t = order[min(k, m - 1)]
            odd = pos % 2 == 1  # window starts at an odd position: drawn (b, a, v)
            x = b if odd else a
            y = a if odd else b
            if drawn & (_same_rotation(x, y, v, tri[t, 0], tri[t, 1], tri[t, 2]) == False):  # noqa: E712
                return 1, k
            k += np.int64(drawn)
        pos += 1
    if k != m:
        return 3, k
    return 0, -1
