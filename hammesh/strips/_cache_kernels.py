"""Compiled vertex-cache and vertex-fetch models of an index stream (restart indices skipped).

The FIFO model keeps a timestamp per vertex, bumped only when the vertex is loaded, so
a vertex is cached while fewer than ``cache_size`` loads happened since (an exact FIFO
in O(1) a lookup; the trick of meshoptimizer's ``meshopt_analyzeVertexCache``,
``src/indexanalyzer.cpp`` in github.com/zeux/meshoptimizer).  The fetch model is the
same file's ``meshopt_analyzeVertexFetch``: 64-byte lines in a 128 KiB direct-mapped
cache.  Our code, written from those descriptions.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel

__all__ = ["fifo_misses", "fetched_bytes", "first_use_order"]


@kernel
def fifo_misses(indices, restart, use_restart, n_vertices, cache_size):
    """``(loads, distinct vertices)`` of a FIFO cache of ``cache_size`` entries read in stream order."""
    stamp = np.zeros(n_vertices, np.int64)
    now = cache_size + 1
    loads = 0
    distinct = 0
    for i in range(indices.shape[0]):
        v = indices[i]
        if use_restart and v == restart:
            continue
        if stamp[v] == 0:
            distinct += 1
        if now - stamp[v] > cache_size:
            stamp[v] = now
            now += 1
            loads += 1
    return loads, distinct


@kernel
def fetched_bytes(indices, restart, use_restart, vertex_size):
    """Bytes a 128 KiB direct-mapped cache of 64-byte lines fetches for the stream."""
    line = 64
    n_lines = 128 * 1024 // line
    cache = np.zeros(n_lines, np.int64)
    total = 0
    for i in range(indices.shape[0]):
        v = indices[i]
        if use_restart and v == restart:
            continue
        a = v * vertex_size
        for tag in range(a // line, (a + vertex_size + line - 1) // line):
            slot = tag % n_lines
            if cache[slot] != tag + 1:
                total += line
            cache[slot] = tag + 1
    return total


@kernel
def first_use_order(indices, restart, use_restart, n_vertices):
    """``new_id`` numbering the vertices in order of first use (unused ones last, in order)."""
    new_id = np.full(n_vertices, -1, np.int64)
    nxt = 0
    for i in range(indices.shape[0]):
        v = indices[i]
        if use_restart and v == restart:
            continue
        if new_id[v] < 0:
            new_id[v] = nxt
            nxt += 1
    for v in range(n_vertices):
        if new_id[v] < 0:
            new_id[v] = nxt
            nxt += 1
    return new_id
