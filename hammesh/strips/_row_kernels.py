"""Compiled step of the row cover (:mod:`hammesh.strips.rows`): paths of a link graph of degree <= 2."""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel

__all__ = ["link_paths_into"]


@kernel
def link_paths_into(link, order, starts):
    """Cut the graph ``link`` (``(m, 3)``: each triangle's linked neighbours, -1 for none,
    symmetric, at most two per row) into its paths; a cycle is opened where it is met.

    Path ends (rows with at most one link) are walked first, so every path is found
    whole from one of its ends; what is left are cycles.  ``order`` ``(m,)`` receives the
    triangles path after path, ``starts`` ``(m + 1,)`` the offsets; returns the number
    of paths.
    """
    m = link.shape[0]
    seen = np.zeros(m, np.bool_)
    L = 0
    S = 0
    starts[0] = 0
    for sweep in range(2):
        for s in range(m):
            if seen[s]:
                continue
            if sweep == 0 and (link[s, 0] >= 0) + (link[s, 1] >= 0) + (link[s, 2] >= 0) > 1:
                continue  # inside a path or on a cycle: reached from an end, or in the second sweep
            cur = s
            while cur >= 0:
                seen[cur] = True
                order[L] = cur
                L += 1
                nxt = -1
                for k in range(3):
                    u = link[cur, k]
                    if u >= 0 and not seen[u]:
                        nxt = u
                        break
                cur = nxt
            S += 1
            starts[S] = L
    return S
