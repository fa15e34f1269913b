"""hammesh: guaranteed-quality triangle meshes whose triangles form Hamiltonian cycles.

The public contract::

    dom = hammesh.read_domain("plate.poly")          # or hammesh.Domain(...)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.01)
    h = hammesh.hamiltonian(m)                        # sparse mode, verified
    hammesh.write(h, "plate.vtu")

Based on Arkin, Held, Mitchell, Skiena, "Hamiltonian Triangulations for Fast
Rendering".
"""

from hammesh import pointset, polygon, strips
from hammesh.domain import Domain, read_domain
from hammesh.errors import (
    FileFormatError,
    HammeshError,
    InvalidDomainError,
    InvalidMeshError,
    InvalidOptionError,
    MeshingError,
    VerificationError,
)
from hammesh.io import read_mesh, write
from hammesh.mesh import KIND_NAMES, HamiltonianMesh, Mesh
from hammesh.meshing import quality_mesh
from hammesh.postprocess import hamiltonian
from hammesh.verify import verify

__version__ = "0.1.0"

__all__ = [
    "Domain",
    "read_domain",
    "quality_mesh",
    "hamiltonian",
    "verify",
    "write",
    "read_mesh",
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
    "VerificationError",
]
