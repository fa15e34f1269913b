"""Compiled walks along dual paths: which edge leads to a neighbour, pivots, swaps, turns.

A dual path enters triangle ``t`` through local edge ``kin`` and leaves through ``kout``;
its *pivot* is the vertex the two edges share, and two consecutive equal pivots cost
one repeated index (a swap) in a GL strip.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hammesh.strips._numba import NEXT_CORNER, kernel, loop_helper

__all__ = [
    "edge_towards",
    "edge_to_neighbour",
    "slot_of",
    "vertex_between",
    "TurnArrays",
    "path_turns",
    "starts_with_swap",
    "turn_path_if_better",
    "orient_paths",
]


@loop_helper
def edge_towards(twin, t, u):
    """Local edge of ``t`` shared with triangle ``u >= 0`` (first one), or -1.

    Branch-free: which edge leads to a path neighbour is a coin toss, and mispredicted
    branches had cost more than half of the cover moves' set-up.
    """
    e0 = np.int64(twin[3 * t] // 3 == u)  # a boundary's -1 // 3 is -1: never u
    e1 = np.int64(twin[3 * t + 1] // 3 == u)
    e2 = np.int64(twin[3 * t + 2] // 3 == u)
    return (1 - e0) * (e1 + (1 - e1) * (3 * e2 - 1))


@loop_helper
def edge_to_neighbour(twin3, t, u):
    """:func:`edge_towards` on twins shaped ``(m, 3)`` (``twin.reshape(-1, 3)``, or a view of
    the records' twin columns): the local edge of ``t`` shared with ``u``, or -1."""
    e0 = np.int64(twin3[t, 0] // 3 == u)
    e1 = np.int64(twin3[t, 1] // 3 == u)
    e2 = np.int64(twin3[t, 2] // 3 == u)
    return (1 - e0) * (e1 + (1 - e1) * (3 * e2 - 1))


@loop_helper
def slot_of(table, t, u):
    """First ``k`` with ``table[t, k] == u``, or -1 (branch-free, as :func:`edge_towards`)."""
    e0 = np.int64(table[t, 0] == u)
    e1 = np.int64(table[t, 1] == u)
    e2 = np.int64(table[t, 2] == u)
    return (1 - e0) * (e1 + (1 - e1) * (3 * e2 - 1))


@loop_helper
def vertex_between(tri, t, k0, k1):
    """Vertex shared by the distinct local edges ``k0`` and ``k1`` of ``t`` (either order)."""
    return tri[t, k1 if k1 == NEXT_CORNER[k0] else k0]


#: :func:`path_turns`'s arrays (see :class:`hammesh.strips.paths.PathTurns`); ``err`` 0,
#: 1 (positions ``pos``, ``pos + 1`` share no edge) or 2 (the path turns back at ``pos``).
TurnArrays = namedtuple(
    "TurnArrays", ["first", "last", "entry", "exit", "new_vertex", "pivot", "swap", "head", "err", "pos"]
)


@kernel
def path_turns(tri, twin, order, starts):
    """Entry/exit edges, pivots, swaps and heads of flat dual paths (:class:`TurnArrays`).

    On an error the arrays are incomplete.
    """
    L = order.shape[0]
    S = starts.shape[0] - 1
    first = np.zeros(L, np.bool_)
    last = np.zeros(L, np.bool_)
    entry = np.full(L, -1, np.int64)
    exit_ = np.full(L, -1, np.int64)
    new_vertex = np.full(L, -1, np.int64)
    pivot = np.full(L, -1, np.int64)
    swap = np.zeros(L, np.bool_)
    head = np.zeros((L, 3), np.int64)
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        first[a] = True
        last[b - 1] = True
        for i in range(a, b - 1):
            k = edge_towards(twin, order[i], order[i + 1])
            if k < 0:
                return TurnArrays(first, last, entry, exit_, new_vertex, pivot, swap, head, 1, i)
            exit_[i] = k
            entry[i + 1] = twin[3 * order[i] + k] - 3 * order[i + 1]
    for s in range(S):
        for i in range(starts[s] + 1, starts[s + 1] - 1):
            if entry[i] == exit_[i]:
                return TurnArrays(first, last, entry, exit_, new_vertex, pivot, swap, head, 2, i)
    for s in range(S):
        a = starts[s]
        b = starts[s + 1]
        t = order[a]
        if b - a == 1:
            for j in range(3):
                head[a, j] = tri[t, j]
            continue
        k = exit_[a]
        pivot[a] = tri[t, k]
        head[a, 0] = tri[t, (k + 2) % 3]
        head[a, 1] = tri[t, k]
        head[a, 2] = tri[t, (k + 1) % 3]
        for i in range(a + 1, b):
            t = order[i]
            kin = entry[i]
            new_vertex[i] = tri[t, (kin + 2) % 3]
            if i < b - 1:
                pivot[i] = vertex_between(tri, t, kin, exit_[i])
                swap[i] = pivot[i] == pivot[i - 1]
    return TurnArrays(first, last, entry, exit_, new_vertex, pivot, swap, head, 0, -1)


@loop_helper
def starts_with_swap(tri, twin3, a, b, c):
    """Does a path starting ``a, b, c`` need a swap after ``a``?  (Its exit tail is ``b``'s pivot.)

    ``twin3``: the pairing shaped ``(m, 3)`` (:func:`edge_to_neighbour`).
    """
    kb = edge_to_neighbour(twin3, b, a)
    kc = edge_to_neighbour(twin3, b, c)
    return tri[a, edge_to_neighbour(twin3, a, b)] == vertex_between(tri, b, kb, kc)


@loop_helper
def turn_path_if_better(tri, twin3, order, a, b):
    """Reverse path ``order[a:b + 1]`` in place if that removes the swap after its first
    triangle (interior swaps do not depend on the direction); returns whether it did."""
    if b - a < 2 or not starts_with_swap(tri, twin3, order[a], order[a + 1], order[a + 2]):
        return False
    if starts_with_swap(tri, twin3, order[b], order[b - 1], order[b - 2]):
        return False
    for i in range((b - a + 1) // 2):
        x = order[a + i]
        order[a + i] = order[b - i]
        order[b - i] = x
    return True


@kernel
def orient_paths(tri, twin, order, starts):
    """Reverse each path whose first swap goes away that way.

    Interior pivots (so interior swaps) do not depend on the direction; only the swap
    after the first triangle does.  Paths must be valid dual paths.
    Returns ``(order, any_reversed)``.
    """
    out = order.copy()
    twin3 = twin.reshape((twin.shape[0] // 3, 3))
    flipped = False
    for s in range(starts.shape[0] - 1):
        flipped |= turn_path_if_better(tri, twin3, out, starts[s], starts[s + 1] - 1)
    return out, flipped
