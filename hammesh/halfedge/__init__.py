"""Half-edge topology of a triangle mesh handed to a construction (ours or read from a file).

``prepare_mesh`` checks a planar input and orients it counter-clockwise;
``half_edges`` pairs its half-edges (``local_half_edges``: once, in the renumbered
order); ``HalfEdges`` holds the pairing and the vertex rotations; ``renumber_local``
renumbers a mesh along a Hilbert curve so that neighbours sit near each other in
memory (``locality``). The constructions run on
these; the certificates (``hammesh.verify``) find the same facts with their own code.
"""

from hammesh.halfedge._kernels import bucket_half_edges_into, half_edge_twins, half_edge_twins_packed, orient_ccw
from hammesh.halfedge.input_mesh import (HalfEdges, half_edges, local_half_edges, match_half_edges, mesh_arrays,
                                         prepare_mesh)
from hammesh.halfedge.locality import Renumbered, cell_order, renumber_from_neighbors, renumber_local, restore_vertices

#: the kernels other packages call directly (strips' dual graph, sparse mode, point sets)
__all__ = ["HalfEdges", "half_edges", "mesh_arrays", "prepare_mesh", "match_half_edges", "local_half_edges",
           "half_edge_twins", "half_edge_twins_packed", "bucket_half_edges_into", "orient_ccw", "Renumbered",
           "renumber_local", "renumber_from_neighbors", "cell_order", "restore_vertices"]
