"""Vertex cache and vertex fetch of a strip buffer: the figures a GPU pays besides indices.

* :func:`vertex_cache_stats`: a FIFO post-transform cache of ``cache_size`` entries reading
  the index stream in order (one lookup per index, restart indices skipped, degenerate
  windows included: the GPU looks those indices up too).  ``acmr``: vertices transformed
  per drawn triangle (0.5 is the ideal of a large planar mesh); ``atvr``: per distinct
  vertex (1.0 ideal).  ``overfetch``: bytes a 128 KiB direct-mapped cache of 64-byte lines
  fetches from a vertex buffer of ``vertex_size``-byte vertices, over the bytes of the
  vertices used (1.0 ideal).  The models are meshoptimizer's ``meshopt_analyzeVertexCache``
  (without warps) and ``meshopt_analyzeVertexFetch`` (``src/indexanalyzer.cpp``,
  github.com/zeux/meshoptimizer), applied to the strip's index stream.
* :func:`reorder_vertices`: renumber vertices in order of first use in the buffer (what
  meshoptimizer's ``optimizeVertexFetch`` does for a triangle list): the GPU then reads
  the vertex buffer almost sequentially.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.strips import _cache_kernels

__all__ = ["VertexCacheStats", "vertex_cache_stats", "reorder_vertices", "VERTEX_SIZE", "DEFAULT_CACHE"]

#: FIFO entries the strip documents report their cache figures for when no ``--cache`` is
#: given (a typical post-transform cache: 16-32).
DEFAULT_CACHE = 16

#: Bytes per vertex assumed by the fetch model (a position and a normal as half floats, or
#: a float3 position and a packed normal).
VERTEX_SIZE = 16


@dataclass(frozen=True)
class VertexCacheStats:
    """Cache figures of one index buffer (see the module docstring)."""

    cache_size: int
    vertices_transformed: int
    acmr: float
    atvr: float
    bytes_fetched: int
    overfetch: float

    def to_dict(self) -> dict:
        return {
            "cache_size": self.cache_size,
            "vertices_transformed": self.vertices_transformed,
            "acmr": self.acmr,
            "atvr": self.atvr,
            "bytes_fetched": self.bytes_fetched,
            "overfetch": self.overfetch,
            "vertex_size": VERTEX_SIZE,
        }


def _stream(indices, restart_index):
    idx = np.ascontiguousarray(indices, dtype=np.int64).reshape(-1)
    use_r = restart_index is not None
    return idx, int(restart_index) if use_r else -1, use_r


def vertex_cache_stats(
    indices: np.ndarray, restart_index: int | None, n_triangles: int, cache_size: int = 16
) -> VertexCacheStats:
    """FIFO cache and fetch figures of a strip buffer drawing ``n_triangles`` triangles.

    Examples
    --------
    >>> s = vertex_cache_stats(np.array([0, 1, 2, 3, 4, 5]), None, 4)
    >>> s.vertices_transformed, s.acmr, s.atvr
    (6, 1.5, 1.0)
    """
    if int(cache_size) < 3:
        raise InvalidOptionError(f"cache size must be at least 3 entries, got {cache_size}")
    idx, r, use_r = _stream(indices, restart_index)
    drawn = idx[idx != r] if use_r else idx
    n = int(drawn.max()) + 1 if len(drawn) else 0
    loads, distinct = _cache_kernels.fifo_misses(idx, r, use_r, n, int(cache_size))
    fetched = _cache_kernels.fetched_bytes(idx, r, use_r, VERTEX_SIZE)
    return VertexCacheStats(
        cache_size=int(cache_size),
        vertices_transformed=int(loads),
        acmr=float(loads) / max(int(n_triangles), 1),
        atvr=float(loads) / max(int(distinct), 1),
        bytes_fetched=int(fetched),
        overfetch=float(fetched) / max(int(distinct) * VERTEX_SIZE, 1),
    )


def reorder_vertices(indices: np.ndarray, restart_index: int | None, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices renumbered in order of first use: ``(new_indices, vertex_order)``.

    ``vertex_order[i]`` is the old number of new vertex ``i`` (unused vertices last, in
    their order): write ``points[vertex_order]`` as the vertex buffer.  Restart indices
    are kept.

    Examples
    --------
    >>> new, order = reorder_vertices(np.array([5, 2, 7, 2, 9]), None, 10)
    >>> new.tolist(), order[:4].tolist()
    ([0, 1, 2, 1, 3], [5, 2, 7, 9])
    """
    idx, r, use_r = _stream(indices, restart_index)
    new_id = _cache_kernels.first_use_order(idx, r, use_r, int(n_points))
    out = new_id[np.where(idx == r, 0, idx)] if use_r else new_id[idx]
    if use_r:
        out[idx == r] = r
    order = np.empty(int(n_points), np.int64)
    order[new_id] = np.arange(int(n_points))
    return out, order
