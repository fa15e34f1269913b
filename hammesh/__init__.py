"""hammesh: guaranteed-quality triangle meshes whose triangles form Hamiltonian cycles.

The public contract::

    dom = hammesh.read_domain("plate.poly")          # or hammesh.Domain(...)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.01)
    h = hammesh.hamiltonian(m)                        # sparse mode, verified
    hammesh.write(h, "plate.vtu")

Based on Arkin, Held, Mitchell, Skiena, "Hamiltonian Triangulations for Fast
Rendering".
"""

from hammesh.numba_cache import ensure_cache

ensure_cache()  # before any kernel is compiled (issue 12 #12)

import importlib  # noqa: E402
import types  # noqa: E402

from hammesh.errors import (  # noqa: E402
    FileFormatError,
    HammeshError,
    InvalidDomainError,
    InvalidMeshError,
    InvalidOptionError,
    MeshingError,
    MissingDependencyError,
    OutputError,
    VerificationError,
)

# Everything else is imported on first use (PEP 562): ``import hammesh`` used to import
# every subpackage, 2.5-2.9 s of CPU on a loaded machine (numba kernels declared, the
# strips' compile probe run), paid by every CLI call, Dask worker and ``--help``.
# ``hammesh.quality_mesh`` etc. behave as before; only their import moves to first use.
_LAZY_NAMES = {
    "Domain": "hammesh.domain",
    "read_domain": "hammesh.domain",
    "read_mesh": "hammesh.io",
    "write": "hammesh.io",
    "dual_graph": "hammesh.fem",
    "to_meshio": "hammesh.fem",
    "to_pyvista": "hammesh.fem",
    "to_skfem": "hammesh.fem",
    "KIND_NAMES": "hammesh.mesh",
    "HamiltonianMesh": "hammesh.mesh",
    "Mesh": "hammesh.mesh",
    "quality_mesh": "hammesh.meshing",
    "hamiltonian": "hammesh.postprocess",
    "partition": "hammesh.partition",
    "partitioned": "hammesh.partition",
    "verify": "hammesh.verify",
}
#: subpackages and modules reachable as ``hammesh.NAME`` after a plain ``import hammesh``
#: (the docs write ``hammesh.io.unwritten_data``, ``hammesh.fem.boundary_facets``)
_LAZY_SUBPACKAGES = ("strips", "polygon", "pointset", "io", "fem", "domain", "surface", "meshing",
                     "parallel", "plot", "numbering", "halfedge", "postprocess", "params", "predicates")

#: Public functions named like the subpackage that defines them (``hammesh.verify`` is
#: the function, ``hammesh.partition`` too): the import system binds a subpackage to
#: its parent's attribute when it is first imported, which must not replace them.
_FUNCTIONS_NAMED_LIKE_MODULES = frozenset(("verify", "partition"))


def __getattr__(name: str):
    if name in _LAZY_SUBPACKAGES:
        return importlib.import_module(f"hammesh.{name}")
    module = _LAZY_NAMES.get(name)
    if module is None:
        raise AttributeError(f"module 'hammesh' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups are plain attribute reads
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """hammesh's module type: keeps ``verify`` and ``partition`` the functions."""

    def __setattr__(self, name: str, value) -> None:
        if name in _FUNCTIONS_NAMED_LIKE_MODULES and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


import sys  # noqa: E402

sys.modules[__name__].__class__ = _Package
del sys

__version__ = "0.1.0"

__all__ = [
    "Domain",
    "read_domain",
    "quality_mesh",
    "hamiltonian",
    "verify",
    "partition",
    "partitioned",
    "write",
    "read_mesh",
    "to_skfem",
    "to_meshio",
    "to_pyvista",
    "dual_graph",
    "Mesh",
    "HamiltonianMesh",
    "KIND_NAMES",
    "strips",
    "polygon",
    "pointset",
    "HammeshError",
    "InvalidDomainError",
    "InvalidMeshError",
    "InvalidOptionError",
    "FileFormatError",
    "MeshingError",
    "OutputError",
    "VerificationError",
    "MissingDependencyError",
]
