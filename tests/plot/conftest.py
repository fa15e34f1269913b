"""Fixtures of the plot tests (hexagon and two_cycles: tests/conftest.py)."""

from __future__ import annotations

import numpy as np
import pytest

from hammesh.mesh import HamiltonianMesh
from tests.helpers import hand_hamiltonian


def strip(n_quads: int) -> HamiltonianMesh:
    """A 2 x (n_quads + 1) strip; its 2 n_quads triangles in strip order (one run)."""
    x = np.arange(n_quads + 1, dtype=np.float64)
    points = np.column_stack([np.r_[x, x], np.r_[np.zeros_like(x), np.ones_like(x)]])
    i = np.arange(n_quads)
    top = i + n_quads + 1
    lower = np.column_stack([i, i + 1, top + 1])
    upper = np.column_stack([i, top + 1, top])
    triangles = np.empty((2 * n_quads, 3), np.int64)
    triangles[0::2], triangles[1::2] = lower, upper
    return hand_hamiltonian(points, triangles, [2 * n_quads], [[0, 1]], n_attributes=0)


@pytest.fixture
def make_strip():
    return strip
