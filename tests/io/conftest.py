"""Hand-built Hamiltonian meshes shared by the io tests."""

from __future__ import annotations

import numpy as np
import pytest

from hammesh.mesh import HamiltonianMesh, Mesh


def fan(center: tuple[float, float], k: int, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Centre point + regular ``k``-gon; triangles ``(0, i, i+1)`` CCW, in cycle order."""
    angles = 2 * np.pi * np.arange(k) / k
    ring = np.column_stack([np.cos(angles), np.sin(angles)]) * radius + center
    points = np.vstack([center, ring])
    i = np.arange(1, k + 1)
    triangles = np.column_stack([np.zeros(k, np.int64), i, i % k + 1])
    return points, triangles


def hamiltonian(points, triangles, components, segments=None, n_attributes=1) -> HamiltonianMesh:
    m = len(triangles)
    components = np.asarray(components, dtype=np.int64)
    starts = np.repeat(np.cumsum(components) - components, components)
    segments = np.zeros((0, 2), np.int64) if segments is None else np.asarray(segments, np.int64)
    return HamiltonianMesh(
        points=np.asarray(points, dtype=np.float64),
        triangles=np.asarray(triangles, dtype=np.int64),
        segments=segments,
        segment_markers=np.arange(1, len(segments) + 1, dtype=np.int64),
        components=components,
        position=np.arange(m, dtype=np.int64) - starts,
        parent=np.arange(m, dtype=np.int64) // 2,
        kind=(np.arange(m) % 3).astype(np.int8),
        triangle_attributes=np.column_stack(
            [np.linspace(0.1, 0.9, m) * (j + 1) for j in range(n_attributes)]
        ).reshape(m, n_attributes),
        report={"n_triangles": m},
    )


@pytest.fixture
def hexagon() -> HamiltonianMesh:
    """6 triangles around the centre of a regular hexagon: one cycle."""
    points, triangles = fan((0.0, 0.0), 6)
    boundary = np.column_stack([np.arange(1, 7), np.arange(1, 7) % 6 + 1])
    return hamiltonian(points, triangles, [6], segments=boundary)


@pytest.fixture
def two_cycles() -> HamiltonianMesh:
    """A hexagon fan (6 triangles) and a square fan (4 triangles): two cycles."""
    p1, t1 = fan((0.0, 0.0), 6)
    p2, t2 = fan((3.0, 0.5), 4, radius=0.7)
    points = np.vstack([p1, p2])
    triangles = np.vstack([t1, t2 + len(p1)])
    return hamiltonian(points, triangles, [6, 4], n_attributes=2)


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
