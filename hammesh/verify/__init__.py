"""Certificates: every output of hammesh passes one before it is returned or written.

The certificates share only the exact predicates (``hammesh.predicates``) and numpy
with the constructions they check: every fact about an input is derived here.
"""

import sys as _sys
import types as _types

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


class _Package(_types.ModuleType):
    """``hammesh.verify``'s module type: every submodule bound here is bound on the
    function :func:`verify` too.

    Why: ``hammesh.verify`` is the function (``hammesh.verify(h, m)``), so ``import
    hammesh.verify.certificate as C`` (which imports the module, then reads
    ``hammesh.verify``, then its attribute ``certificate``) failed with "cannot import
    name 'certificate' from 'verify'" (tester18 r11); ``from hammesh.verify import
    certificate`` worked. With the submodules as attributes of the function both
    spellings work and ``hammesh.verify`` stays a plain function."""

    def __setattr__(self, name: str, value) -> None:
        super().__setattr__(name, value)
        if isinstance(value, _types.ModuleType) and value.__name__ == f"{self.__name__}.{name}":
            setattr(verify, name, value)


for _name, _module in list(_sys.modules.items()):  # (the ones imported above)
    if _name.startswith(__name__ + ".") and _name.count(".") == __name__.count(".") + 1:
        setattr(verify, _name.rsplit(".", 1)[1], _module)
_sys.modules[__name__].__class__ = _Package
del _name, _module
