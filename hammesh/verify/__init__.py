"""Certificates: every output of hammesh passes one before it is returned or written."""

from hammesh.verify.certificate import ANGLE_RTOL, AREA_RTOL, verify, verify_cycle_mesh
from hammesh.verify.input_mesh import HalfEdges, half_edges, prepare_mesh
from hammesh.verify.runs import infer_runs

__all__ = [
    "verify",
    "verify_cycle_mesh",
    "infer_runs",
    "prepare_mesh",
    "half_edges",
    "HalfEdges",
    "ANGLE_RTOL",
    "AREA_RTOL",
]
