"""Options given as numpy scalars work; strings and booleans are refused with a HammeshError."""

from __future__ import annotations

import numpy as np
import pytest

import hammesh
from hammesh.errors import InvalidOptionError


@pytest.fixture(scope="module")
def square():
    return hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])


@pytest.mark.parametrize("bad", ["0.1", b"0.1", True, None.__class__, [0.1]])
def test_max_area_that_is_no_number_is_refused(square, bad):
    with pytest.raises(InvalidOptionError, match="max_area"):
        hammesh.quality_mesh(square, max_area=bad)


def test_numpy_scalars_are_numbers(square):
    m = hammesh.quality_mesh(square, min_angle=np.float32(25), max_area=np.float64(0.05))
    h = hammesh.hamiltonian(m, keep=np.float32(0.5))
    assert h.report["keep"] == pytest.approx(0.5)
    with pytest.raises(InvalidOptionError, match="keep"):
        hammesh.hamiltonian(m, keep=np.True_)
    with pytest.raises(InvalidOptionError, match="keep"):
        hammesh.hamiltonian(m, keep="0.5")
