"""Certificates for triangulations returned by hammesh.polygon (pure numpy + Fractions)."""

from __future__ import annotations

from collections import Counter
from fractions import Fraction

import numpy as np

from tests.polygon import brute


def assert_triangulates(points, Q, T, *, steiner=False):
    """T triangulates the polygon ``points`` (vertices Q; Q[:n] == points).

    Every triangle is counter-clockwise (exactly), the areas add up to the polygon's
    (exactly), every edge is in at most two triangles and the edges in only one are
    exactly the polygon edges: together, the triangles tile the polygon without overlap.
    """
    pts = [tuple(map(float, p)) for p in np.asarray(points, dtype=float)]
    n = len(pts)
    Q = np.asarray(Q, dtype=float)
    T = np.asarray(T)
    assert T.ndim == 2 and T.shape[1] == 3 and T.dtype.kind == "i"
    assert np.array_equal(Q[:n], np.asarray(pts))
    if not steiner:
        assert len(Q) == n and len(T) == n - 2
    total = Fraction(0)
    for t in T:
        a, b, c = (tuple(Q[v]) for v in t)
        assert brute.orient(a, b, c) > 0, f"triangle {t} is not counter-clockwise"
        total += brute.signed_area2([a, b, c])
    assert total == abs(brute.signed_area2(pts)), "areas do not add up"
    count = Counter()
    for t in T:
        for k in range(3):
            count[frozenset((int(t[k]), int(t[(k + 1) % 3])))] += 1
    assert max(count.values()) <= 2
    boundary = {e for e, c in count.items() if c == 1}
    assert boundary == {frozenset((i, (i + 1) % n)) for i in range(n)}


def assert_dual_path(T, *, cycle=False):
    """Consecutive rows share an edge (and the last the first, for a cycle)."""
    m = len(T)
    for k in range(m - 1 + (cycle and m > 1)):
        shared = set(map(int, T[k])) & set(map(int, T[(k + 1) % m]))
        assert len(shared) == 2, f"rows {k} and {(k + 1) % m} share no edge"


def assert_two_ears(points, T):
    n = len(points)
    if len(T) == 1:
        return
    ears = 0
    for t in T:
        edges = sum(((int(t[k]) - int(t[(k + 1) % 3])) % n in (1, n - 1)) for k in range(3))
        ears += edges == 2
    assert ears == 2


def assert_alternates(T):
    """No three consecutive shared edges meet at one vertex (turns alternate)."""
    shared = [set(map(int, T[k])) & set(map(int, T[k + 1])) for k in range(len(T) - 1)]
    for k in range(len(shared) - 2):
        assert not (shared[k] & shared[k + 1] & shared[k + 2]), f"rows {k}..{k + 3} do not alternate"


def assert_triangulates_domain(rings, Q, T):
    """T triangulates the polygon with holes ``rings`` (outer first); Q starts with the
    rings' points concatenated.  Same certificate as :func:`assert_triangulates`."""
    rings = [[tuple(map(float, p)) for p in np.asarray(r, dtype=float)] for r in rings]
    flat = [p for r in rings for p in r]
    Q = np.asarray(Q, dtype=float)
    T = np.asarray(T)
    assert T.ndim == 2 and T.shape[1] == 3 and T.dtype.kind == "i"
    assert np.array_equal(Q[:len(flat)], np.asarray(flat))
    total = Fraction(0)
    for t in T:
        a, b, c = (tuple(Q[v]) for v in t)
        assert brute.orient(a, b, c) > 0, f"triangle {t} is not counter-clockwise"
        total += brute.signed_area2([a, b, c])
    want = abs(brute.signed_area2(rings[0])) - sum(abs(brute.signed_area2(r)) for r in rings[1:])
    assert total == want, "areas do not add up"
    count = Counter()
    for t in T:
        for k in range(3):
            count[frozenset((int(t[k]), int(t[(k + 1) % 3])))] += 1
    assert max(count.values()) <= 2
    boundary = {e for e, c in count.items() if c == 1}
    ring_edges, off = set(), 0
    for r in rings:
        ring_edges |= {frozenset((off + i, off + (i + 1) % len(r))) for i in range(len(r))}
        off += len(r)
    assert boundary == ring_edges
