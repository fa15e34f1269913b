"""Half-edge topology of a triangle mesh handed to a construction (ours or read from a file).

``prepare_mesh`` checks a planar input and orients it counter-clockwise;
``half_edges`` pairs its half-edges; ``HalfEdges`` holds the pairing and the vertex
rotations. The constructions run on these; the certificates (``hammesh.verify``)
find the same facts with their own code.
"""

from hammesh.halfedge._kernels import bucket_half_edges_into, half_edge_twins, half_edge_twins_packed, orient_ccw
from hammesh.halfedge.input_mesh import HalfEdges, half_edges, mesh_arrays, prepare_mesh

#: the kernels other packages call directly (strips' dual graph, sparse mode, point sets)
__all__ = ["HalfEdges", "half_edges", "mesh_arrays", "prepare_mesh", "half_edge_twins", "half_edge_twins_packed", "bucket_half_edges_into",
           "orient_ccw"]
