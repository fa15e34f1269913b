"""Compiled forced chains of the sequential test (Thm 4.3, :mod:`hammesh.strips.sequential`)."""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel, loop_helper

__all__ = ["triangle_across", "follow_chain", "sequential_chain"]


@loop_helper
def triangle_across(tri, twin, t, b, c):
    """Triangle across edge {b, c} of triangle t and its third vertex, or (-1, -1)."""
    for k in range(3):
        x = tri[t, k]
        y = tri[t, (k + 1) % 3]
        if (x == b and y == c) or (x == c and y == b):
            h = twin[3 * t + k]
            if h < 0:
                return -1, -1
            u = h // 3
            return u, tri[u, (h - 3 * u + 2) % 3]
    return -1, -1


@loop_helper
def follow_chain(tri, twin, t, x, y, seen, out_t, out_v):
    """Follow the forced alternating chain from ``t`` across edge ``{x, y}``, then ``{y, z}``, ...

    ``z`` being each new triangle's third vertex; stops at the boundary, at a triangle
    already ``seen`` (marked on the way) or after ``m - 1`` steps.  Writes the triangles
    and third vertices to ``out_t``, ``out_v``; returns how many.
    """
    m = tri.shape[0]
    n = 0
    while n < m - 1:
        u, z = triangle_across(tri, twin, t, x, y)
        if u < 0 or seen[u]:
            break
        seen[u] = True
        out_t[n] = u
        out_v[n] = z
        n += 1
        t = u
        x = y
        y = z
    return n


@kernel
def sequential_chain(tri, twin, t0, a, b, c):
    """Forced alternating strip through triangle ``t0`` read as vertices ``a, b, c``.

    In a strip whose turns alternate, triangle ``i`` is ``{v_i, v_(i+1), v_(i+2)}``, so
    ``(a, b, c)`` fixes the successor (across ``{b, c}``) and the predecessor (across
    ``{a, b}``) and so on (Thm 4.3).  Both directions are followed until the boundary or
    a repeated triangle, at most ``m - 1`` steps each.  A sliding window then looks for
    ``m`` consecutive distinct triangles.

    Returns ``(order, vertices)``: the ``m`` triangles and ``m + 2`` vertices of such a
    window, or two empty arrays.
    """
    m = tri.shape[0]
    seen = np.zeros(m, np.bool_)
    succ_t = np.empty(m, np.int64)
    succ_v = np.empty(m, np.int64)
    seen[t0] = True
    ns = follow_chain(tri, twin, t0, b, c, seen, succ_t, succ_v)
    for i in range(ns):
        seen[succ_t[i]] = False
    # predecessors: the same rule read backwards, across {a, b} first
    pred_t = np.empty(m, np.int64)
    pred_v = np.empty(m, np.int64)
    npr = follow_chain(tri, twin, t0, b, a, seen, pred_t, pred_v)
    # chain: pred (reversed), t0, succ ; vertices: pred_v reversed, a, b, c, succ_v
    L = npr + 1 + ns
    chain = np.empty(L, np.int64)
    verts = np.empty(L + 2, np.int64)
    for i in range(npr):
        chain[i] = pred_t[npr - 1 - i]
        verts[i] = pred_v[npr - 1 - i]
    chain[npr] = t0
    verts[npr] = a
    verts[npr + 1] = b
    verts[npr + 2] = c
    for i in range(ns):
        chain[npr + 1 + i] = succ_t[i]
        verts[npr + 3 + i] = succ_v[i]
    empty = np.empty(0, np.int64)
    if L < m:
        return empty, empty
    count = np.zeros(m, np.int64)
    distinct = 0
    for i in range(L):
        if count[chain[i]] == 0:
            distinct += 1
        count[chain[i]] += 1
        if i >= m:
            j = chain[i - m]
            count[j] -= 1
            if count[j] == 0:
                distinct -= 1
        if i >= m - 1 and distinct == m:
            s = i - m + 1
            return chain[s : s + m].copy(), verts[s : s + m + 2].copy()
    return empty, empty
