"""Fixtures of the io tests (the hand-built meshes live in tests/helpers.py and tests/conftest.py)."""

from __future__ import annotations

import numpy as np
import pytest

from hammesh.mesh import HamiltonianMesh, Mesh


@pytest.fixture(params=["hexagon", "two_cycles"])
def hmesh(request) -> HamiltonianMesh:
    return request.getfixturevalue(request.param)


@pytest.fixture
def plain(hexagon) -> Mesh:
    return hexagon.as_mesh()


def _assert_cycle_order(triangles, components) -> None:
    """Consecutive rows of each run share an edge, and so do its last and first rows."""
    tri = [frozenset(t) for t in np.asarray(triangles).tolist()]
    start = 0
    for length in np.asarray(components).tolist():
        run = tri[start:start + length]
        for a, b in zip(run, run[1:] + run[:1]):
            assert len(a & b) == 2
        start += length
    assert start == len(tri)


@pytest.fixture
def assert_cycle_order():
    """``assert_cycle_order(triangles, components)``."""
    return _assert_cycle_order
