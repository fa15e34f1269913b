"""Test oracle: the greedy dual path cover in plain Python (no numba, no records).

The same rules as :func:`hammesh.strips._cover_kernels.greedy_path_cover`, written
from its description with lists and dicts: seeds from a bucket queue of free degrees
(most recent first, stale entries skipped), each path grown forward from its seed and
then backward, each step taking the free neighbour with the least
``2 * free degree + w_swap * swap``.
"""

from __future__ import annotations

import numpy as np


def reference_greedy_cover(tri: np.ndarray, twin: np.ndarray, w_swap: int, seed_order: np.ndarray):
    tri = np.asarray(tri).tolist()
    twin = np.asarray(twin).tolist()
    m = len(tri)
    nbrs = [[twin[3 * t + k] for k in range(3)] for t in range(m)]
    deg = [sum(h >= 0 for h in nbrs[t]) for t in range(m)]
    buckets: list[list[int]] = [[], [], [], []]
    for t in np.asarray(seed_order).tolist():
        buckets[deg[t]].append(t)

    def take(t):
        deg[t] = -1
        for h in nbrs[t]:
            if h >= 0 and deg[h // 3] >= 0:
                u = h // 3
                deg[u] -= 1
                buckets[deg[u]].append(u)

    def pivot_of(t, kin, kout):
        if kin < 0:
            return tri[t][kout]
        return tri[t][kout] if kout == (kin + 1) % 3 else tri[t][kin]

    def grow(cur, entry, prev_pivot):
        out = []
        first_exit = -1
        while True:
            best = None
            for k in range(3):
                h = nbrs[cur][k]
                if k == entry or h < 0 or deg[h // 3] < 0:
                    continue
                p = pivot_of(cur, entry, k)
                score = 2 * deg[h // 3] + w_swap * int(prev_pivot >= 0 and p == prev_pivot)
                if best is None or score < best[0]:
                    best = (score, k, p)
            if best is None:
                return out, first_exit
            _, k, p = best
            if not out:
                first_exit = k
            h = nbrs[cur][k]
            u = h // 3
            take(u)
            out.append(u)
            prev_pivot = p
            entry = h - 3 * u
            cur = u

    paths = []
    while True:
        seed = None
        for d in range(4):
            while buckets[d]:
                t = buckets[d].pop()
                if deg[t] == d:
                    seed = t
                    break
            if seed is not None:
                break
        if seed is None:
            break
        take(seed)
        fwd, kf = grow(seed, -1, -1)
        bwd = []
        if fwd:
            p1 = -1
            if len(fwd) >= 2:
                u = fwd[0]
                ein = twin[3 * seed + kf] - 3 * u
                eout = [k for k in range(3) if nbrs[u][k] >= 0 and nbrs[u][k] // 3 == fwd[1]][-1]
                p1 = pivot_of(u, ein, eout)
            bwd, _ = grow(seed, kf, p1)
        paths.append(bwd[::-1] + [seed] + fwd)
    order = np.array([t for p in paths for t in p], np.int64)
    starts = np.r_[0, np.cumsum([len(p) for p in paths])].astype(np.int64)
    return order, starts
