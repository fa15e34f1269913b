"""Compiled readers of strip buffers: OpenGL's and IRIS GL's decoding rules, and the
one-pass round-trip proof.  Nothing here is shared with the writers
(:mod:`hammesh.strips._emit_kernels`): the proof derives every drawn triangle itself.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel, loop_helper, row

__all__ = ["decode_generalized_strips", "check_claimed_draws", "check_claimed_part", "claimed_part_status",
           "decode_draws_into", "first_wrong_draw", "mark_drawn_row"]


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


def check_claimed_part(tri, indices, restart, use_restart, order, seen, drawn=None):
    """:func:`check_claimed_draws` on a part of a buffer that starts a strip (at a restart).

    ``indices`` must draw exactly the rows ``order``, in that order; each is marked in
    ``seen`` (shared by the parts, so a row repeated *within* the part is status 4).  The
    parts of one buffer cut just after restart indices decode as the whole does (a
    restart resets the strip), so when every part returns 0, the claims add up to ``m``
    rows and every row is in ``seen``, the buffer draws each row once with its winding.

    Two passes: :func:`decode_draws_into` decodes the buffer alone (sequential reads and
    writes), then :func:`first_wrong_draw` compares the draws with the claimed rows, a
    loop of a few instructions around one gather of ``tri[order[k]]``.  Split this way
    more of those scattered reads are in flight at once: at 1M triangles a half's proof
    took 15.7-17.5 ms in one pass and 10.7-11.1 ms in two (thread CPU, caches cold).
    ``drawn``: ``(len(order) + 1) * 3`` ``int32`` of scratch (made here if not given).
    """
    n = order.shape[0]
    if drawn is None or drawn.shape[0] < 3 * (n + 1):
        drawn = np.empty(3 * (n + 1), np.int32)
    return claimed_part_status(tri, indices, restart, use_restart, order, seen, drawn[: 3 * (n + 1)].reshape(n + 1, 3))


@kernel
def claimed_part_status(tri, indices, restart, use_restart, order, seen, drawn):
    """:func:`check_claimed_part`'s two passes (:func:`decode_draws_into`, then
    :func:`first_wrong_draw`), called from one kernel: a fresh process loads one compiled
    kernel for the proof, not two.  ``drawn``: ``(len(order) + 1, 3)`` ``int32`` scratch."""
    n = order.shape[0]
    count = decode_draws_into(indices, restart, use_restart, drawn)
    status, k = first_wrong_draw(tri, drawn, min(count, n), order, seen)
    if status != 0:
        return status, k
    if count > n:
        return 2, n
    if count < n:
        return 3, count
    return 0, -1


@kernel
def decode_draws_into(indices, restart, use_restart, drawn):
    """The triangles ``indices`` draws (OpenGL's strip rules), each with its winding, into
    ``drawn`` (``int32``; an index outside ``[0, 2**31)`` is written as -1, which no row
    holds).  Returns how many, stopping at ``len(drawn)``."""
    cap = drawn.shape[0]
    L = indices.shape[0]
    top = np.int64(0x7FFFFFFF)
    pos = 0  # position inside the current strip
    k = 0
    for i in range(L):
        v = indices[i]
        if use_restart and v == restart:
            pos = 0
            continue
        if pos >= 2:
            a = indices[row(i - 2)]  # row(): no negative-index wraparound (see _cover_kernels)
            b = indices[row(i - 1)]
            if (a != b) & (b != v) & (a != v):
                if k >= cap:
                    return k
                # selects instead of branches: the window's parity would be mispredicted
                odd = pos % 2 == 1  # window starts at an odd position: drawn (b, a, v)
                x = b if odd else a
                y = a if odd else b
                j = row(k)
                drawn[j, 0] = x if (x >= 0) & (x <= top) else -1
                drawn[j, 1] = y if (y >= 0) & (y <= top) else -1
                drawn[j, 2] = v if (v >= 0) & (v <= top) else -1
                k += 1
        pos += 1
    return k


@kernel
def first_wrong_draw(tri, drawn, count, order, seen):
    """``(0, -1)`` if draw ``k`` is row ``order[k]`` with its winding for every ``k <
    count`` (each row marked in ``seen``, none twice), else ``(status, k)`` of the first
    that is not: 4 ``order[k]`` out of range or already seen, 1 a different triangle."""
    for k in range(count):
        status = mark_drawn_row(tri, drawn, k, order[k], seen)
        if status != 0:
            return status, k
    return 0, -1


@loop_helper
def mark_drawn_row(tri, drawn, k, t, seen):
    """0 if draw ``k >= 0`` is row ``t`` of ``tri`` with its winding (``t`` then marked in
    ``seen``), 4 if ``t`` is out of range or already seen, 1 if a different triangle."""
    if t < 0 or t >= tri.shape[0]:
        return 4
    r = row(t)  # in range: no negative-index wraparound (see _cover_kernels)
    if seen[r]:
        return 4
    seen[r] = True
    j = row(k)
    x = drawn[j, 0]
    y = drawn[j, 1]
    z = drawn[j, 2]
    # -1 marks an index that does not fit: never a vertex, even of a row holding -1
    if (min(x, min(y, z)) < 0) | (not _same_rotation(x, y, z, tri[r, 0], tri[r, 1], tri[r, 2])):
        return 1
    return 0
