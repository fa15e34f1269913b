"""Compiled cache-aware dual path cover: strips laid side by side for a FIFO vertex cache.

What a FIFO cache of ``C`` entries rewards is reuse within the last ``C`` vertex loads.
A strip loads one new vertex per triangle; the vertices on its side are loaded again
by the next strip unless that strip runs along it while they are still cached.  So,
in the spirit of Sander, Nehab and Barczak's *Tipsy* (fast triangle reordering for
vertex locality, 2007) and Forsyth's linear-speed vertex cache optimisation (2006),
both as used by meshoptimizer's ``src/vcacheoptimizer.cpp`` (github.com/zeux/meshoptimizer),
but for strips rather than triangle lists (our code):

* the cache is simulated while the strips are made (the exact FIFO of
  :mod:`hammesh.strips._cache_kernels`, plus a ring of its entries, oldest first);
* a new strip starts at a free triangle on the *oldest* cached vertex that has one
  (most cached corners first, then fewest free neighbours): next to the start of the
  previous strip, whose vertices are about to be evicted;
* a strip grows through the neighbour whose new vertex is cached (hugging the previous
  strip), then the one with fewer free neighbours (no stranded triangles), then the
  alternating turn (no swap);
* a strip stops after ``max_len`` triangles, so that the next one reaches each shared
  vertex before ``C`` further loads evict it.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._cover_kernels import PathCover, free_step, pop_fewest_free, queue_free_degrees, take_triangle
from hammesh.strips._dual_kernels import REC_SCRATCH, REC_TWIN
from hammesh.strips._numba import carve, kernel, loop_helper

__all__ = ["cache_path_cover", "vertex_triangles"]


@kernel
def vertex_triangles(tri, n_points):
    """CSR of the triangles at each vertex: ``(offsets (n + 1,), triangles (3 m,))``."""
    m = tri.shape[0]
    off = np.zeros(n_points + 1, np.int64)
    for t in range(m):
        for k in range(3):
            off[tri[t, k] + 1] += 1
    for v in range(n_points):
        off[v + 1] += off[v]
    fill = off[:-1].copy()
    out = np.empty(3 * m, np.int64)
    for t in range(m):
        for k in range(3):
            v = tri[t, k]
            out[fill[v]] = t
            fill[v] += 1
    return off, out


@loop_helper
def _cached(stamp, now, cache_size, v):
    return now - stamp[v] <= cache_size


@loop_helper
def _load(stamp, ring, now, cache_size, v):
    """Look ``v`` up; on a miss insert it (FIFO).  Returns the new clock."""
    if now - stamp[v] > cache_size:
        stamp[v] = now
        ring[now % cache_size] = v
        return now + 1
    return now


@loop_helper
def _new_vertex(rec, h):
    """Vertex of the triangle of half-edge ``h`` opposite that edge."""
    u = h // 3
    return rec[u, (h - 3 * u + 2) % 3]


def cache_path_cover(rec, n_points, cache_size, max_len, seed_order, w_miss=2, w_swap=1, w_deg=2) -> PathCover:
    """Cover the dual graph with strips laid for a FIFO cache of ``cache_size`` vertices.

    ``rec``: the mesh's records (scratch column overwritten); ``seed_order`` breaks ties
    where no cached vertex has a free triangle (fewest free neighbours first, then the
    last of ``seed_order``); ``w_miss``: weight of a cache miss against a free neighbour
    (2 per neighbour) when choosing the next triangle.
    """
    m = rec.shape[0]
    off, vt = vertex_triangles(rec[:, :3], n_points)
    bucket, order, starts, top = carve(np.int64, (4, m), m, m + 1, 4)
    stamp = np.zeros(n_points, np.int64)
    ring = np.full(cache_size, -1, np.int64)
    S = _cache_path_cover_into(
        rec, off, vt, cache_size, max_len, w_miss, w_swap, w_deg, seed_order, bucket, order, starts, top, stamp, ring
    )
    return PathCover(order, starts[: S + 1].copy())


@kernel
def _cache_path_cover_into(rec, off, vt, C, max_len, w_miss, w_swap, w_deg, seed_order, bucket, order, starts, top, stamp, ring):
    m = rec.shape[0]
    queue_free_degrees(rec, seed_order, bucket, top)
    now = C + 1
    L = 0
    S = 0
    starts[0] = 0
    while L < m:
        # seed: a free triangle on the oldest cached vertex that has one
        seed = -1
        best = -(1 << 30)
        for j in range(C):
            v = ring[(now + j) % C]
            if v < 0 or stamp[v] != now - C + j:
                continue  # empty slot, or v was loaded again later (a newer slot holds it)
            for i in range(off[v], off[v + 1]):
                t = vt[i]
                d = rec[t, REC_SCRATCH]
                if d < 0:
                    continue
                c = 0
                for k in range(3):
                    if _cached(stamp, now, C, rec[t, k]):
                        c += 1
                score = 8 * c - d
                if score > best:
                    best = score
                    seed = t
            if seed >= 0 and best >= 16 - 3:
                break  # two or three cached corners at the oldest vertex: take it
        if seed < 0:
            seed = pop_fewest_free(rec, bucket, top)
        take_triangle(seed, rec, bucket, top)
        order[L] = seed
        L += 1
        n = 1
        cur = seed
        entry = -1
        prev_pivot = -1
        while n < max_len:
            bk = -1
            bscore = 1 << 30
            bpivot = -1
            for k in range(3):
                st = free_step(rec, cur, entry, k, prev_pivot)
                if st.h < 0:
                    continue
                miss = 0 if _cached(stamp, now, C, _new_vertex(rec, st.h)) else 1
                score = w_miss * miss + w_deg * st.degree + w_swap * st.swap
                if score < bscore:
                    bscore = score
                    bk = k
                    bpivot = st.pivot
            if bk < 0:
                break
            h = rec[cur, REC_TWIN + bk]
            u = h // 3
            if entry < 0:
                # the strip's head: the seed's corners in the order they are sent
                now = _load(stamp, ring, now, C, rec[cur, (bk + 2) % 3])
                now = _load(stamp, ring, now, C, rec[cur, bk])
                now = _load(stamp, ring, now, C, rec[cur, (bk + 1) % 3])
            now = _load(stamp, ring, now, C, _new_vertex(rec, h))
            take_triangle(u, rec, bucket, top)
            order[L] = u
            L += 1
            n += 1
            prev_pivot = bpivot
            entry = h - 3 * u
            cur = u
        if n == 1:
            for k in range(3):
                now = _load(stamp, ring, now, C, rec[seed, k])
        S += 1
        starts[S] = L
    return S
