"""Decoupled parallel meshing (issue 15): tiles Triangle meshes alone into one conforming mesh.

``decompose`` cuts a domain into balanced tiles with pre-discretised separators
(:mod:`hammesh.parallel.tiles`), ``mesh_decoupled`` meshes every tile alone (Triangle
``-Y``) with repair rounds, ``assemble`` / ``check_union`` give and check their union.
See docs/scale.md.
"""

from hammesh.parallel.decoupled import DecoupledMesh, mesh_decoupled
from hammesh.parallel.tile_mesh import mesh_tile
from hammesh.parallel.tiles import Decomposition, Tile, decompose, split_segments
from hammesh.parallel.union import UnionFacts, assemble, check_union
from hammesh.parallel.run import parallel_hamiltonian
from hammesh.parallel.partitioned import write_partitioned

__all__ = ["decompose", "split_segments", "Decomposition", "Tile", "mesh_tile", "mesh_decoupled",
           "DecoupledMesh", "assemble", "check_union", "UnionFacts", "parallel_hamiltonian", "write_partitioned"]
