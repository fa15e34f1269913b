"""Certificates: every output of hammesh passes one before it is returned or written."""

from hammesh.verify.certificate import ANGLE_RTOL, AREA_RTOL, verify, verify_cycle_mesh
from hammesh.verify.runs import infer_runs

__all__ = [
    "verify",
    "verify_cycle_mesh",
    "infer_runs",
    "ANGLE_RTOL",
    "AREA_RTOL",
]
