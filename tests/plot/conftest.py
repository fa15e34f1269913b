"""Small hand-built Hamiltonian meshes for the plot tests."""

from __future__ import annotations

import numpy as np
import pytest

from hammesh.mesh import HamiltonianMesh


def _fan(center, k, radius=1.0):
    angles = 2 * np.pi * np.arange(k) / k
    ring = np.column_stack([np.cos(angles), np.sin(angles)]) * radius + center
    i = np.arange(1, k + 1)
    return np.vstack([center, ring]), np.column_stack([np.zeros(k, np.int64), i, i % k + 1])


def _hamiltonian(points, triangles, components, segments):
    m = len(triangles)
    components = np.asarray(components, dtype=np.int64)
    starts = np.repeat(np.cumsum(components) - components, components)
    return HamiltonianMesh(
        points=points, triangles=triangles, segments=np.asarray(segments, np.int64).reshape(-1, 2),
        segment_markers=np.ones(len(segments), np.int64), components=components,
        position=np.arange(m) - starts, parent=np.arange(m), kind=np.zeros(m, np.int8),
        triangle_attributes=np.zeros((m, 0)),
    )


@pytest.fixture
def hexagon() -> HamiltonianMesh:
    points, triangles = _fan((0.0, 0.0), 6)
    ring = np.arange(1, 7)
    return _hamiltonian(points, triangles, [6], np.column_stack([ring, ring % 6 + 1]))


@pytest.fixture
def two_cycles() -> HamiltonianMesh:
    p1, t1 = _fan((0.0, 0.0), 6)
    p2, t2 = _fan((3.0, 0.5), 4, radius=0.7)
    return _hamiltonian(np.vstack([p1, p2]), np.vstack([t1, t2 + len(p1)]), [6, 4], [[0, 1]])


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
    return _hamiltonian(points, triangles, [2 * n_quads], [[0, 1]])


@pytest.fixture
def make_strip():
    return strip
