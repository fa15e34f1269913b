"""The mesh size a quality Triangle run would use, and graded 1D discretisations.

A tile is meshed alone with its separators kept unsplit (Triangle ``-Y``), so the
separators (and the user's segments, which ``-Y`` keeps unsplit too where they bound
the tile) are discretised beforehand with the spacing Triangle itself would pick:
``EDGE_PER_SQRT_AREA * sqrt(max_area)`` where nothing is near, and the local feature
size near input features (read off a coarse quality mesh of the whole domain, whose
edges Triangle grades to the features). The spacing is then graded (neighbouring
subsegments differ by a bounded ratio) so that no subsegment is much longer than its
neighbour: a long subsegment next to a short one is encroached by the short one's
apex, and ``-Y`` forbids the split that would repair it (Linardakis & Chrisochoides,
*Graded Delaunay decoupling method for parallel guaranteed quality planar mesh
generation*, SIAM J. Sci. Comput. 30(4), 2008: separator points spaced by the local
size function, graded, so each subdomain's Delaunay refinement never needs to split
them).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["EDGE_PER_SQRT_AREA", "AREA_FILL", "GRADING", "graded_points"]

#: Triangle's boundary subsegments on a ``q30 a A`` mesh are ~1.25 sqrt(A) long
#: (measured on a unit square, A = 1e-5); 1.2 sqrt(A) meets q30 in every tile with no
#: over-refinement (1.0: +0.07 % triangles, 1.6: q30 missed by 0.02 degrees)
EDGE_PER_SQRT_AREA = 1.2
#: the mean triangle area of a ``q30 a A`` Triangle mesh is ~0.63 A (same run)
AREA_FILL = 0.63
#: sizes of neighbouring subsegments: h grows by at most GRADING x distance
GRADING = 0.25
#: a piece whose size integral (its wanted number of subsegments) is at least this
#: keeps its end subsegments at exactly the size there (:func:`graded_points_many`)
PIN_ROOM = 2.5
#: a short piece that is split is split into equal parts (False: evenly in the size integral)
SHORT_EQUAL = True
#: most samples of the size function along one piece
MAX_SAMPLES = 2_000_000


def graded_points(length: float, size, cap0: float, cap1: float) -> np.ndarray:
    """Interior stations ``0 < s_1 < ... < s_{n-1} < length`` of a graded discretisation.

    Parameters
    ----------
    length : float
        Length of the piece (> 0).
    size : callable
        ``size(s) -> h`` for an array of stations ``s``: the wanted edge length there.
    cap0, cap1 : float
        Largest edge length allowed at the two ends (features meeting there).

    Returns
    -------
    (n - 1,) float64
        Stations of the new points; the ``n`` subsegments follow ``size`` (at most
        ``cap`` at the ends), graded by at most ``GRADING`` per unit length.
    """
    ends = np.array([0.0, length])
    h_end = np.minimum(size(ends), [cap0, cap1])
    h_min = max(float(h_end.min()), 1e-300)
    m = int(min(MAX_SAMPLES, max(16, np.ceil(4.0 * length / h_min))))
    s = np.linspace(0.0, length, m + 1)
    h = np.asarray(size(s), dtype=np.float64)
    m2 = int(min(MAX_SAMPLES, max(m, np.ceil(4.0 * length / max(float(h.min()), 1e-300)))))
    if m2 > m:  # a feature finer than the first sampling: sample again at its scale
        s = np.linspace(0.0, length, m2 + 1)
        h = np.asarray(size(s), dtype=np.float64)
    h[0] = min(h[0], cap0)
    h[-1] = min(h[-1], cap1)
    # Lipschitz limit h(s) <= h(t) + GRADING |s - t|: two passes of a running minimum
    ds = s[1] - s[0]
    k = GRADING * ds * np.arange(len(s))
    h = np.minimum(h, np.minimum.accumulate(h - k) + k)
    rev = h[::-1]
    rev = np.minimum(rev, np.minimum.accumulate(rev - k) + k)
    h = rev[::-1]
    inv = 1.0 / h
    F = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * ds)])
    n = max(1, int(math.ceil(F[-1] - 0.05)))  # ceil: no subsegment much over its size
    if n == 1:
        return np.zeros(0)
    targets = F[-1] * np.arange(1, n) / n
    return np.interp(targets, F, s)


def _segmented_min_accumulate(values: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Running minimum restarting at every new ``seg`` (``seg`` non-decreasing)."""
    span = float(np.abs(values).max()) if len(values) else 0.0
    big = 4.0 * span + 1.0
    # every later segment is lowered by ``big``: the running minimum never carries over
    shifted = values - seg * big
    return np.minimum.accumulate(shifted) + seg * big


def graded_points_many(lengths: np.ndarray, stations: np.ndarray, seg: np.ndarray, h: np.ndarray,
                       cap0: np.ndarray, cap1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`graded_points` for many pieces at once, sizes already sampled.

    ``stations`` / ``h``: samples of every piece (``seg`` its index, non-decreasing, each
    piece sampled from 0 to its length, at least two samples); returns the new points'
    stations and their piece index. A piece with room (``PIN_ROOM``) has its end
    subsegments exactly at the capped, graded size there, so pieces meeting at a
    corner start equally long once their caps agree; a short piece that is split is
    split into equal parts (``SHORT_EQUAL``).
    """
    first = np.concatenate([[True], seg[1:] != seg[:-1]])
    last = np.concatenate([seg[1:] != seg[:-1], [True]])
    h = h.copy()
    h[first] = np.minimum(h[first], cap0[seg[first]])
    h[last] = np.minimum(h[last], cap1[seg[last]])
    g = GRADING * stations
    h = np.minimum(h, _segmented_min_accumulate(h - g, seg) + g)
    rev = (h + g)[::-1]
    h = np.minimum(h, (_segmented_min_accumulate(rev, (seg.max() - seg)[::-1]))[::-1] - g)
    inv = 1.0 / h
    inc = np.zeros(len(h))
    inc[1:] = 0.5 * (inv[1:] + inv[:-1]) * np.diff(stations)
    inc[first] = 0.0
    F = np.cumsum(inc)
    per = np.bincount(seg)[np.unique(seg)]
    F -= np.repeat(F[first], per)
    total = F[last]
    pieces = np.unique(seg)
    # global monotone keys: every piece's F (and station) lifted above the previous pieces'
    lift = np.concatenate([[0.0], np.cumsum(total + 1.0)[:-1]])
    G = F + np.repeat(lift, per)
    length = stations[last]
    slift = np.concatenate([[0.0], np.cumsum(length + 1.0)[:-1]])
    S = stations + np.repeat(slift, per)
    # pinned ends: a piece with room keeps its end subsegments exactly at the (capped,
    # graded) size there, so every piece meeting a vertex starts with the same length
    # once the caps agree; the middle is split evenly in F as before
    e0, e1 = h[first], h[last]
    pin = (total >= PIN_ROOM) & (e0 + e1 < 0.75 * length)
    g0 = np.interp(np.where(pin, e0, 0.0) + slift, S, G)
    g1 = np.interp(np.where(pin, length - e1, length) + slift, S, G)
    mid = np.where(pin, g1 - g0, total)
    n_mid = np.maximum(1, np.ceil(mid - 0.05).astype(np.int64))  # ceil: no subsegment much over its size
    count = n_mid - 1 + 2 * pin
    owner = np.repeat(pieces, count)
    k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)  # 0 .. count-1
    pinned = np.repeat(pin, count)
    kk = np.where(pinned, k, k + 1)  # the pinned pieces' first point is g0 itself
    target = np.repeat(g0, count) + kk / np.repeat(n_mid, count) * np.repeat(mid, count)
    target = np.where(pinned & (k == np.repeat(count, count) - 1), np.repeat(g1, count), target)
    j = np.clip(np.searchsorted(G, target), 1, len(G) - 1)
    w = (target - G[j - 1]) / np.maximum(G[j] - G[j - 1], 1e-300)
    st = stations[j - 1] + np.clip(w, 0, 1) * (stations[j] - stations[j - 1])
    # a short piece (no pinned ends) split in two or three: equal parts, as many as its
    # finest size asks (split evenly in F, its parts would differ by the grading over
    # the whole piece, up to ~1.9x side by side: the longer one encroached)
    short = ~pin & (n_mid >= 2) & SHORT_EQUAL
    if short.any():
        hmin = np.minimum.reduceat(h, np.flatnonzero(first))
        n_eq = np.where(short, np.maximum(n_mid, np.ceil(length / hmin - 0.05).astype(np.int64)), 0)
        keep = ~np.repeat(short, count)
        c2 = np.maximum(n_eq - 1, 0)
        o2 = np.repeat(pieces, c2)
        k2 = np.arange(c2.sum()) - np.repeat(np.cumsum(c2) - c2, c2) + 1
        s2 = k2 / np.repeat(np.maximum(n_eq, 1), c2) * np.repeat(length, c2)
        st = np.concatenate([st[keep], s2])
        owner = np.concatenate([owner[keep], o2])
        order = np.lexsort((st, owner))
        st, owner = st[order], owner[order]
    return st, owner
