"""Decoupled parallel meshing (issue 15): tiles Triangle meshes alone into one conforming mesh.

``decompose`` cuts a domain into balanced tiles with pre-discretised separators
(:mod:`hammesh.parallel.tiles`), ``mesh_decoupled`` meshes every tile alone (Triangle
``-Y``) with repair rounds, ``assemble`` / ``check_union`` give and check their union.
See docs/scale.md.

The names are imported on first use (PEP 562, as ``hammesh`` itself does): the
command's parallel path imports :mod:`hammesh.parallel.cluster` to start its local
cluster before anything else, and importing every module here first (numba, the
kernels, the domain's modules: ~0.2 s) would put them ahead of that start.
"""

import importlib

__all__ = ["decompose", "split_segments", "Decomposition", "Tile", "mesh_tile", "mesh_decoupled",
           "DecoupledMesh", "assemble", "check_union", "UnionFacts", "parallel_hamiltonian", "write_partitioned"]

#: public name -> the module that defines it
_WHERE = {"decompose": "tiles", "split_segments": "tiles", "Decomposition": "tiles", "Tile": "tiles",
          "mesh_tile": "tile_mesh", "mesh_decoupled": "decoupled", "DecoupledMesh": "decoupled",
          "assemble": "union", "check_union": "union", "UnionFacts": "union",
          "parallel_hamiltonian": "run", "write_partitioned": "partitioned"}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(f"hammesh.parallel.{_WHERE[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'hammesh.parallel' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
