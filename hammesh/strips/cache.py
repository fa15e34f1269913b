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
* :func:`fifo_strip_order`: the order (and direction) in which a cover's strips are sent
  so that each finds its vertices in a FIFO of ``cache_size`` entries
  (:mod:`hammesh.strips._cache_order_kernels`): the cover's indices kept, fewer vertex
  loads; :func:`split_paths` first cuts strips too long to hand their vertices on.
* :func:`reorder_vertices`: renumber vertices in order of first use in the buffer (what
  meshoptimizer's ``optimizeVertexFetch`` does for a triangle list): the GPU then reads
  the vertex buffer almost sequentially.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.strips import _cache_kernels, _cache_order_kernels
from hammesh.strips._emit_kernels import restart_buffer

__all__ = [
    "VertexCacheStats",
    "vertex_cache_stats",
    "fifo_strip_order",
    "reorder_vertices",
    "VERTEX_SIZE",
    "DEFAULT_CACHE",
    "CACHE_MODE_FIFO",
    "REVERSAL_WEIGHT",
    "PIECE_LENGTH",
    "SHORT_PIECE_LENGTH",
    "split_paths",
]

#: FIFO entries the strip documents report their cache figures for when no ``--cache`` is
#: given (a typical post-transform cache: 16-32).
DEFAULT_CACHE = 16

#: FIFO entries ``hammesh strip --cache`` lays the strips for when it is given without a
#: number (a typical post-transform cache holds 16-32).  32: there the planar bands keep
#: fewer loads than meshoptimizer's vertex-cache order + stripify at ~1.30 indices per
#: triangle (q30 meshes 1.29-1.32 against its 1.72-1.74; at 16 they need ~1.38:
#: docs/strips.md, session 14).
CACHE_MODE_FIFO = 32

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


#: Weight of one more index (a reversed strip may need one more swap) against one more
#: vertex load in :func:`fifo_strip_order`: a pair whose gain does not beat it does not
#: fix a direction.  On the q30 square of 10k triangles (FIFO 16, the swap-free chains'
#: strips, session 11's nearest-neighbour order): 0 gave 1.282 indices per triangle at
#: ACMR 0.901, 0.3 1.281 / 0.900, 0.7 1.275 / 0.896, 1.5 1.271 / 0.899.
REVERSAL_WEIGHT = 0.7


#: Longest strip, in multiples of the FIFO size, that :func:`split_paths` leaves a cover
#: with before its strips are put in FIFO order: a strip reused by the next one must not
#: load more than the FIFO holds before that one reaches its start.  On the q30 square of
#: 10k triangles (FIFO 16, swap-free chains): no cut 1.2745 ipt at ACMR16 0.885, 64
#: triangles 1.2837 / 0.876, 48 1.2947 / 0.856, 40 1.2988 / 0.848, 36 1.3029 / 0.846,
#: 28 1.3264 / 0.825, 20 1.3610 / 0.797, 12 1.4405 / 0.782.
PIECE_LENGTH = 3

#: The same for ``encode(cache=N)`` with ``method="auto"``: the swap-free chains cut at
#: ``1.25 N`` triangles, the fewest vertex loads of ours.  Against session 10's cache-aware
#: cover (strips grown while the FIFO is simulated, 3 N at most; then in FIFO order) on the
#: 14 meshes of ``bench_strips.py --peers --quick``: fewer indices on all 14 (q30 10k
#: 1.375 -> 1.360), lower ACMR16 on 12 (0.835 -> 0.796), 0.008 higher on two
#: (pyvista's Sphere 30x30, Delaunay 10k).
SHORT_PIECE_LENGTH = 1.25


def split_paths(starts: np.ndarray, longest: int) -> np.ndarray:
    """Path offsets with every path longer than ``longest`` cut into equal pieces.

    Examples
    --------
    >>> split_paths(np.array([0, 3, 10]), 4).tolist()
    [0, 3, 6, 10]
    """
    starts = np.asarray(starts, np.int64)
    lens = np.diff(starts)
    k = np.maximum(-(-lens // int(longest)), 1)
    i = np.repeat(np.arange(len(lens)), k)
    j = np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)
    return np.r_[starts[:-1][i] + lens[i] * j // k[i], starts[-1:]].astype(np.int64)


def _segments(buf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the strips of a buffer joined by ``-1``."""
    cuts = np.flatnonzero(buf == -1)
    return np.r_[0, cuts + 1].astype(np.int64), np.r_[cuts, len(buf)].astype(np.int64)


def fifo_strip_order(
    tri: np.ndarray, twin: np.ndarray, order: np.ndarray, starts: np.ndarray, n_points: int, cache_size: int
) -> tuple[np.ndarray, np.ndarray]:
    """The dual paths ``order``/``starts`` re-ordered and turned for a FIFO of ``cache_size`` entries.

    Each path keeps its triangles (so the buffer keeps its length, but for a swap where a
    reversed path needs one); the paths are chained pair by pair, the pairs that save the
    most vertex loads first (:mod:`hammesh.strips._cache_order_kernels`, greedy edge).
    ``tri``/``twin``: the rows the paths refer to and their pairing; ``order`` must be
    valid dual paths.  Returns the new ``(order, starts)``.
    """
    S = len(starts) - 1
    if S < 2:
        return order, starts
    rev, _ = _cache_order_kernels.paths_in_order(order, starts, np.arange(S, dtype=np.int64), np.ones(S, np.bool_))
    fw = restart_buffer(tri, twin, order, starts, -1).indices
    bw = restart_buffer(tri, twin, rev, starts, -1).indices
    fw_lo, fw_hi = _segments(fw)
    bw_lo, bw_hi = _segments(bw)
    vt_off, vt = _cache_order_kernels.strips_at_vertices(fw, fw_lo, fw_hi, int(n_points))
    gain, ab = _cache_order_kernels.pair_gains(fw, fw_lo, fw_hi, bw, bw_lo, bw_hi, vt_off, vt, int(n_points), int(cache_size))
    nf, nb = fw_hi - fw_lo, bw_hi - bw_lo
    short = np.minimum(nf, nb)
    pick, flip = _cache_order_kernels.greedy_edge_order(
        gain, ab, (nf - short).astype(np.float64), (nb - short).astype(np.float64), float(REVERSAL_WEIGHT)
    )
    return _cache_order_kernels.paths_in_order(order, starts, pick, flip)


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
