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

from hammesh import pointset, polygon, strips  # noqa: E402
from hammesh.domain import Domain, read_domain  # noqa: E402
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
from hammesh.io import read_mesh, write  # noqa: E402
from hammesh.fem import dual_graph, to_meshio, to_pyvista, to_skfem  # noqa: E402
from hammesh.mesh import KIND_NAMES, HamiltonianMesh, Mesh  # noqa: E402
from hammesh.meshing import quality_mesh  # noqa: E402
from hammesh.postprocess import hamiltonian  # noqa: E402
from hammesh.partition import partition, partitioned  # noqa: E402  (the function shadows the module's name here)
from hammesh.verify import verify  # noqa: E402

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
