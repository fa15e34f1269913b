"""Constrained edges of an output mesh: input segments, split where a midpoint went in.

Thm 2.4's conformal variant (paper, end of §2) inserts the midpoint ``M`` of a
constrained edge ``ab`` that the tree must cross; the edge then lives on as ``aM`` and
``Mb`` with the same marker. Shared by every construction that inserts midpoints.
"""

from __future__ import annotations

import numpy as np

__all__ = ["split_segments"]


def split_segments(
    segments: np.ndarray,
    markers: np.ndarray,
    mid_a: np.ndarray,
    mid_b: np.ndarray,
    first_midpoint: int,
    n_all: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Replace each segment ``(mid_a[i], mid_b[i])`` by its halves at vertex ``first_midpoint + i``.

    Parameters
    ----------
    segments : (s, 2) int64
    markers : (s,) int64
    mid_a, mid_b : (q,) int64
        The split edges (either direction), in midpoint order.
    first_midpoint : int
        Vertex index of midpoint 0 (midpoints are numbered consecutively).
    n_all : int
        Number of output points (a bound for the edge keys).

    Returns
    -------
    segments : (s + k, 2) int64
        Unsplit segments first, then the first halves, then the second halves.
    markers : (s + k,) int64
    """
    q = len(mid_a)
    if not q:
        return segments, markers
    key = np.minimum(segments[:, 0], segments[:, 1]) * n_all + np.maximum(segments[:, 0], segments[:, 1])
    mkey = np.minimum(mid_a, mid_b) * n_all + np.maximum(mid_a, mid_b)
    order = np.argsort(mkey)
    idx = np.searchsorted(mkey[order], key).clip(max=q - 1)
    hit = mkey[order][idx] == key
    mv = first_midpoint + order[idx[hit]]
    halves = np.concatenate([np.c_[segments[hit, 0], mv], np.c_[mv, segments[hit, 1]]])
    return (
        np.concatenate([segments[~hit], halves]),
        np.concatenate([markers[~hit], markers[hit], markers[hit]]),
    )
