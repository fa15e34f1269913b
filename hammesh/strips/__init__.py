"""Strip encodings of triangle meshes (paper §4, §5): GL strips, generalized strips, bounds.

=======================================  =================================================
module                                   what
=======================================  =================================================
:mod:`hammesh.strips.dual`               checked input: any 2D/3D mesh and its dual graph
:mod:`hammesh.strips.paths`              turns, pivots and swaps along dual paths
:mod:`hammesh.strips.generalized`        IRIS GL strips: one vertex + one turn bit each
:mod:`hammesh.strips.gl`                 GL_TRIANGLE_STRIP buffers, restart / stitching,
                                         the OpenGL decoder and the round-trip proof
:mod:`hammesh.strips.sequential`         Thm 4.3: is a triangulation sequential, O(n)
:mod:`hammesh.strips.encode`             scalable encoder (greedy dual paths, cycles,
                                         Lemma 5.1 on dual forests)
:mod:`hammesh.strips.rows`               row cover along an axis; rows laid in bands for
                                         a FIFO vertex cache
:mod:`hammesh.strips.halves`             two halves on two threads (from 50k triangles)
:mod:`hammesh.strips.scratch`            work arrays kept between two-halves encodings
:mod:`hammesh.strips.warm`               ``prepare()``: load the large-mesh kernels ahead
:mod:`hammesh.strips.christofides`       Thm 5.3: 9/4-approximate encoding (networkx)
:mod:`hammesh.strips.cache`              vertex cache / fetch figures, first-use numbering
:mod:`hammesh.strips.files`              3D mesh reading, ``.json`` / ``.npz`` output
=======================================  =================================================

>>> import hammesh
>>> from hammesh import strips
>>> m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.05)
>>> s = strips.encode(m)                      # verified round trip
>>> tri = strips.decode_gl_strip(s.indices, s.restart_index)
>>> len(tri) == m.n_triangles
True
"""

from hammesh.strips.cache import VertexCacheStats, reorder_vertices, vertex_cache_stats
from hammesh.strips.choose import StripChoice, choose_strip
from hammesh.strips.christofides import ChristofidesEncoding, christofides_strip, christofides_walk
from hammesh.strips.dual import DualMesh, dual_mesh, oriented_key
from hammesh.strips.encode import encode, encode_generalized, greedy_paths, mesh_paths
from hammesh.strips.files import write_strip
from hammesh.strips.generalized import (
    GeneralizedStrips,
    decode_generalized,
    generalized_strips,
)
from hammesh.strips.gl import RESTART_INDEX, GLStrip, decode_gl_strip, gl_strip, verify_gl_strip
from hammesh.strips.paths import PathTurns, path_turns
from hammesh.strips.sequential import SequentialOrder, sequential_order
from hammesh.strips.warm import prepare

__all__ = [
    "choose_strip",
    "StripChoice",
    "encode",
    "encode_generalized",
    "christofides_strip",
    "christofides_walk",
    "ChristofidesEncoding",
    "sequential_order",
    "SequentialOrder",
    "gl_strip",
    "decode_gl_strip",
    "verify_gl_strip",
    "GLStrip",
    "RESTART_INDEX",
    "generalized_strips",
    "decode_generalized",
    "GeneralizedStrips",
    "greedy_paths",
    "mesh_paths",
    "path_turns",
    "PathTurns",
    "dual_mesh",
    "DualMesh",
    "oriented_key",
    "write_strip",
    "vertex_cache_stats",
    "VertexCacheStats",
    "reorder_vertices",
    "prepare",
]
