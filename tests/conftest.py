import os

import pytest
from hypothesis import HealthCheck, settings

from hammesh.mesh import HamiltonianMesh
from tests.helpers import hexagon_mesh, two_cycles_mesh

settings.register_profile(
    "ci", max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("dev", max_examples=15, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture
def hexagon() -> HamiltonianMesh:
    """6 triangles around the centre of a regular hexagon: one cycle."""
    return hexagon_mesh()


@pytest.fixture
def two_cycles() -> HamiltonianMesh:
    """A hexagon fan (6 triangles) and a square fan (4 triangles): two cycles."""
    return two_cycles_mesh()
