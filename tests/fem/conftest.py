"""A domain with every kind of tag: 4 outer sides of 4 markers, a hole with its own
marker, an interface segment (marker 5) between two regions, a marked corner point."""

from __future__ import annotations

import numpy as np
import pytest

import hammesh

#: outer ring of the two-material plate: sides bottom-left, bottom-right, right, top-right,
#: top-left, left
OUTER = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [0.0, 1.0]]
HOLE = [[1.4, 0.4], [1.6, 0.4], [1.6, 0.6], [1.4, 0.6]]
#: the outer sides' markers: Dirichlet left (4), Neumann bottom/top (1, 3), right (2)
OUTER_MARKERS = [1, 1, 2, 3, 3, 4]
HOLE_MARKER = 6
INTERFACE_MARKER = 5


def two_material_domain() -> hammesh.Domain:
    dom = hammesh.Domain.from_polygon(
        OUTER, holes=[HOLE], internal_segments=[[[1.0, 0.0], [1.0, 1.0]]],
        ring_markers=[OUTER_MARKERS, HOLE_MARKER], internal_markers=[INTERFACE_MARKER],
    )
    regions = np.array([[0.5, 0.5, 1.0, np.nan], [1.2, 0.5, 2.0, np.nan]])
    vertex_markers = dom.vertex_markers.copy()
    vertex_markers[0] = 9  # a marked corner
    return hammesh.Domain(dom.vertices, dom.segments, dom.holes, regions,
                          segment_markers=dom.segment_markers, vertex_markers=vertex_markers)


@pytest.fixture(scope="session")
def plate_mesh() -> hammesh.Mesh:
    return hammesh.quality_mesh(two_material_domain(), min_angle=30, max_area=0.004)


@pytest.fixture(scope="session", params=["sparse", "incircle"])
def plate(request, plate_mesh) -> hammesh.HamiltonianMesh:
    return hammesh.hamiltonian(plate_mesh, mode=request.param)
