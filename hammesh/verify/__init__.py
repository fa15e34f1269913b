"""Certificates: every output of hammesh passes one before it is returned or written."""

from hammesh.verify.certificate import ANGLE_RTOL, AREA_RTOL, verify, verify_cycle_mesh
from hammesh.verify.input_mesh import HalfEdges, half_edges, prepare_mesh

__all__ = [
    "verify",
    "verify_cycle_mesh",
    "prepare_mesh",
    "half_edges",
    "HalfEdges",
    "ANGLE_RTOL",
    "AREA_RTOL",
]
