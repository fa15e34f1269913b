"""Compiled writers of GL strip buffers: restart-joined paths in one pass, and stitching.

The reading side (OpenGL's decoding rules, the round-trip proof) is
:mod:`hammesh.strips._decode_kernels`: it shares nothing with these writers.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.strips._numba import NEXT_CORNER, kernel, loop_helper, row
from hammesh.strips._path_kernels import edge_to_neighbour

__all__ = ["stitch_strips", "emit_restart_joined", "RestartBuffer", "restart_buffer", "WrittenPath", "write_path"]


@kernel
def _stitched_length(n_enc, ntri, swap1, odd):
    if odd and ntri >= 3:
        return n_enc - 1 if swap1 else n_enc + 1
    return n_enc


@kernel
def stitch_strips(enc, enc_starts, ntri, swap1):
    """Join GL strips into one by degenerate stitching, fixing each start's parity.

    ``enc[enc_starts[s]:enc_starts[s + 1]]`` is strip ``s`` encoded to start at an even
    position: ``x, p, q, [p], w1, ...`` (``[p]`` present iff ``swap1[s]``).  Strips are
    joined by repeating the previous strip's last index and the next strip's first
    (two degenerate triangles each way).  A strip that then starts at an odd position
    is sent as ``x, q, p, [q], w1, ...`` instead: same triangles, same windings, and the
    swap before ``w1`` toggles (so the join always costs exactly two indices).
    """
    S = enc_starts.shape[0] - 1
    total = 0
    for s in range(S):
        if s > 0:
            total += 2
        total += _stitched_length(enc_starts[s + 1] - enc_starts[s], ntri[s], swap1[s], total % 2 == 1)
    out = np.empty(total, np.int64)
    pos = 0
    for s in range(S):
        a = enc_starts[s]
        b = enc_starts[s + 1]
        if s > 0:
            out[pos] = out[pos - 1]
            out[pos + 1] = enc[a]
            pos += 2
        rest = a
        if pos % 2 == 1:
            if ntri[s] == 1:
                # one triangle x p q sent as x q p at an odd position: winding (q, x, p)
                out[pos] = enc[a]
                out[pos + 1] = enc[a + 2]
                out[pos + 2] = enc[a + 1]
                pos += 3
                rest = b
            else:
                p = enc[a + 1]
                q = enc[a + 2]
                out[pos] = enc[a]
                out[pos + 1] = q
                out[pos + 2] = p
                pos += 3
                rest = a + 3
                if ntri[s] >= 3:
                    if swap1[s]:
                        rest = a + 4
                    else:
                        out[pos] = q
                        pos += 1
        for i in range(rest, b):
            out[pos] = enc[i]
            pos += 1
    return out


@kernel
def emit_restart_joined(first, swap, head, pivot, new_vertex, starts, restart):
    """The GL buffer of analysed paths, each from an even position, joined by ``restart``.

    Returns ``(indices, max_index)``.
    """
    L = first.shape[0]
    S = starts.shape[0] - 1
    total = S - 1
    for i in range(L):
        if first[i]:
            total += 3
        else:
            total += 2 if swap[i] else 1
    out = np.empty(total, np.int64)
    pos = 0
    mx = -1
    for s in range(S):
        if s > 0:
            out[pos] = restart
            pos += 1
        a = starts[s]
        for j in range(3):
            v = head[a, j]
            out[pos] = v
            pos += 1
            mx = max(mx, v)
        for i in range(a + 1, starts[s + 1]):
            if swap[i]:
                out[pos] = pivot[i - 1]
                pos += 1
            v = new_vertex[i]
            out[pos] = v
            pos += 1
            mx = max(mx, v)
    return out, mx


#: :func:`restart_buffer`'s result; ``err`` is 0, or 1 when a path is not a dual path
#: (then call :func:`hammesh.strips._path_kernels.path_turns` for the message).
RestartBuffer = namedtuple("RestartBuffer", ["indices", "n_swaps", "max_index", "err"])


def restart_buffer(tri, twin, order, starts, restart) -> RestartBuffer:
    """The restart-joined GL buffer of flat dual paths in one pass, no per-position arrays.

    The same turns as :func:`~hammesh.strips._path_kernels.path_turns` +
    :func:`emit_restart_joined` (each path written by :func:`write_path`), computed on
    the fly: the encoder's fast path.  The buffer is allocated by numpy at its bound
    ``2 L + 3 S`` and ``indices`` is its filled prefix (one pass instead of counting the
    swaps first).
    """
    out = np.empty(2 * order.shape[0] + 3 * (starts.shape[0] - 1), np.int64)
    n, n_swaps, mx, err = _restart_buffer_into(tri, twin.reshape(-1, 3), order, starts, restart, out)
    if err:
        return RestartBuffer(out[:0], 0, -1, err)
    return RestartBuffer(out[:n], n_swaps, mx, 0)


@kernel
def _restart_buffer_into(tri, twin3, order, starts, restart, out):
    S = starts.shape[0] - 1
    n_swaps = 0
    pos = 0
    mx = -1
    for s in range(S):
        if s > 0:
            out[pos] = restart
            pos += 1
        w = write_path(tri, twin3, order, starts[s], starts[s + 1], out, pos)
        if w.err:
            return 0, 0, -1, 1
        pos = w.pos
        n_swaps += w.swaps
        mx = max(mx, w.max_index)
    return pos, n_swaps, mx, 0


#: :func:`write_path`'s result: the position after the path, swaps written, the largest
#: index written, and 1 if ``order[a:b]`` is not a dual path (then the rest is unset).
WrittenPath = namedtuple("WrittenPath", ["pos", "swaps", "max_index", "err"])


@loop_helper
def write_path(tri, twin3, order, a, b, out, pos):
    """Write the GL strip of dual path ``order[a:b]`` at ``out[pos]`` (:class:`WrittenPath`).

    ``tri[t, :3]`` are row ``t``'s vertices, ``twin3[t, k]`` the half-edge across its edge
    ``k`` (``twin.reshape(-1, 3)``, or a view of the records' twin columns).  Head: the
    first triangle's vertex opposite its exit edge, then the exit half-edge's tail and
    head (the first triangle keeps its winding at an even position); then one new vertex
    per triangle, preceded by the previous pivot where two pivots coincide.
    """
    # rows and positions as row(): no negative-index wraparound (see _cover_kernels)
    t = row(order[a])
    mx = max(tri[t, 0], tri[t, 1], tri[t, 2])
    if b - a == 1:
        for j in range(3):
            out[row(pos + j)] = tri[t, j]
        return WrittenPath(pos + 3, 0, mx, 0)
    k = edge_to_neighbour(twin3, t, order[a + 1])
    if k < 0:
        return WrittenPath(pos, 0, mx, 1)
    out[row(pos)] = tri[t, (k + 2) % 3]
    out[row(pos + 1)] = tri[t, k]
    out[row(pos + 2)] = tri[t, NEXT_CORNER[k]]
    pos += 3
    prev_pivot = tri[t, k]
    swaps = 0
    for i in range(a + 1, b):
        u = row(order[i])
        kin = np.int64(twin3[t, k]) - 3 * np.int64(u)
        v = tri[u, (kin + 2) % 3]
        if i < b - 1:
            kout = edge_to_neighbour(twin3, u, order[i + 1])
            if kout < 0 or kout == kin:
                return WrittenPath(pos, swaps, mx, 1)
            p = tri[u, kout if kout == NEXT_CORNER[kin] else kin]
            # a swap (two equal pivots) in ~1 of 5 positions: written always, kept by
            # advancing or not (a branch here would be mispredicted at every swap)
            sw = np.int64(p == prev_pivot)
            out[row(pos)] = prev_pivot
            pos += sw
            swaps += sw
            prev_pivot = p
            k = kout
        out[row(pos)] = v
        pos += 1
        mx = max(mx, v)
        t = u
    return WrittenPath(pos, swaps, mx, 0)
