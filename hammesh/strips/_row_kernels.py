"""Compiled steps of the row cover (:mod:`hammesh.strips.rows`): the links, and the paths of a link graph of degree <= 2."""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel

__all__ = ["link_paths_into", "row_links_into"]


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


@kernel
def row_links_into(points, tri, twin, cos_a, sin_a, refused, link):
    """Each triangle's edge most parallel to the axis ``(cos_a, sin_a)`` into ``refused``
    ``(m,)``, then ``link`` ``(m, 3)``: the neighbour across each edge, -1 where either
    side refuses it (see :func:`hammesh.strips.rows.row_links`; the same result as
    :func:`hammesh.strips.rows.parallel_edges` followed by it, in two compiled passes).

    The measure is ``|sin|`` of the edge's angle to the axis; a zero-length edge, or one
    whose length overflows, counts as parallel (any choice is a valid cover).
    """
    m = tri.shape[0]
    for t in range(m):
        best = 0
        best_s = 2.0
        for k in range(3):
            a = tri[t, k]
            b = tri[t, (k + 1) % 3]
            dx = points[b, 0] - points[a, 0]
            dy = points[b, 1] - points[a, 1]
            length = np.hypot(dx, dy)
            s = abs(dy * cos_a - dx * sin_a) / length if length > 0.0 else 0.0
            if not s == s:  # nan (overflowed differences)
                s = 0.0
            if s < best_s:
                best_s = s
                best = k
        refused[t] = best
    for t in range(m):
        for k in range(3):
            h = twin[3 * t + k]
            u = -1
            if h >= 0 and k != refused[t] and refused[h // 3] != h % 3:
                u = h // 3
            link[t, k] = u
