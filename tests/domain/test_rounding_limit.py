"""Incircle mode far from the origin with small features: where float64 rounding of the
incenters explains every row below Thm 2.4's (exact) half-angle bound, the run is
refused as the input's limit (``InvalidDomainError``, exit 2), not "verification
failed" (exit 3); near the origin the same domain is verified."""

from __future__ import annotations

import numpy as np
import pytest

import hammesh
from hammesh.domain.resolution import check_rounding
from hammesh.errors import InvalidDomainError


def _square_with_hole(scale: float, offset: float) -> hammesh.Domain:
    sq = lambda a, b: np.array([[a, a], [b, a], [b, b], [a, b]], float)  # noqa: E731
    return hammesh.Domain.from_polygon(sq(0, 10) * scale + offset, [sq(2, 8) * scale + offset])


@pytest.mark.parametrize("scale, offset", [(1e-5, 1e5), (1e-2, -1e7)])
def test_incircle_far_out_is_refused_naming_the_resolution(scale, offset):
    mesh = hammesh.quality_mesh(_square_with_hole(scale, offset), min_angle=20)
    try:
        h = hammesh.hamiltonian(mesh, mode="incircle")
    except InvalidDomainError as exc:
        assert "float64" in str(exc) and "mode='sparse'" in str(exc)
    else:  # (rounding may happen to keep the bound: then it must be verified)
        assert h.report["verified"]
    assert hammesh.hamiltonian(mesh, mode="sparse").report["verified"]
    near = hammesh.quality_mesh(_square_with_hole(scale, 0.0), min_angle=20)
    assert hammesh.hamiltonian(near, mode="incircle").report["verified"]


def test_a_miss_rounding_cannot_explain_is_not_excused():
    # a right triangle split badly on purpose: angles far below a 40 degree bound
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.9, 0.05]])
    tri = np.array([[0, 1, 3], [0, 3, 2], [3, 1, 2]])
    check_rounding(pts, tri, np.radians(1.0))  # (all above: nothing to say)
    check_rounding(pts, tri, np.radians(40.0))  # (misses by degrees: not rounding, no refusal)
    far = pts * 1e-9 + 1e7  # the same shape ~5 ulps wide: rounding explains anything
    with pytest.raises(InvalidDomainError, match="float64 steps"):
        check_rounding(far, tri, np.radians(40.0))
