"""Hamiltonian cycle surfaces in 3D: one strip per connected piece, few Steiner points.

``surface_hamiltonian(points (n, 3), triangles (m, 3))`` -> verified
:class:`~hammesh.mesh.HamiltonianMesh` with 3D points (see ``hamiltonian.py``);
``read_surface`` / ``write_surface`` for .obj .ply .stl .off .vtu .vtk; ``shapes``
makes test surfaces.
"""

from hammesh.surface.files import SURFACE_SUFFIXES, read_surface, write_surface
from hammesh.surface.hamiltonian import prepare_surface, surface_hamiltonian
from hammesh.surface.shapes import (
    double_sided,
    duplicate_and_repeated,
    finned_torus,
    flipped_triangle,
    icosphere,
    klein_bottle,
    mobius_strip,
    noisy_sphere,
    pole_sphere,
    thick_plate,
    torus,
)

__all__ = [
    "surface_hamiltonian",
    "prepare_surface",
    "read_surface",
    "write_surface",
    "SURFACE_SUFFIXES",
    "icosphere",
    "torus",
    "thick_plate",
    "noisy_sphere",
    "mobius_strip",
    "klein_bottle",
    "finned_torus",
    "pole_sphere",
    "flipped_triangle",
    "double_sided",
    "duplicate_and_repeated",
]
