"""Certificates: every output of hammesh passes one before it is returned or written.

The certificates share only the exact predicates (``hammesh.predicates``) and numpy
with the constructions they check: every fact about an input is derived here.
"""

from hammesh.verify.certificate import ANGLE_RTOL, AREA_RTOL, verify, verify_cycle_mesh
from hammesh.verify.runs import infer_runs
# the certificate's own pairing and hull (not hammesh.halfedge's): for the other checkers
from hammesh.verify._kernels import half_edge_twins, hull_chain

__all__ = [
    "verify",
    "verify_cycle_mesh",
    "infer_runs",
    "ANGLE_RTOL",
    "AREA_RTOL",
    "half_edge_twins",
    "hull_chain",
]
