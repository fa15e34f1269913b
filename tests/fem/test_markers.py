"""Markers go everywhere: Domain.from_polygon per ring and per side, point markers
through Triangle, the post-process and every file format that stores them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.errors import InvalidDomainError
from hammesh.mesh import output_vertex_markers
from tests.fem.conftest import OUTER, OUTER_MARKERS

SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
HOLE = [[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]]


def test_from_polygon_default_markers_are_one():
    d = hammesh.Domain.from_polygon(SQUARE, [HOLE])
    assert d.segment_markers.tolist() == [1] * 8 and d.vertex_markers.tolist() == [1] * 8


def test_from_polygon_marker_per_ring():
    d = hammesh.Domain.from_polygon(SQUARE, [HOLE], ring_markers=[3, 7])
    assert d.segment_markers.tolist() == [3] * 4 + [7] * 4
    assert d.vertex_markers.tolist() == [3] * 4 + [7] * 4


@given(st.lists(st.integers(-(2**31), 2**31 - 1), min_size=4, max_size=4))
def test_from_polygon_marker_per_side(markers):
    d = hammesh.Domain.from_polygon(SQUARE, ring_markers=[markers])
    # side j runs from point j to point j + 1 and carries markers[j]; point j: the side leaving it
    assert d.segments.tolist() == [[0, 1], [1, 2], [2, 3], [3, 0]]
    assert d.segment_markers.tolist() == markers
    assert d.vertex_markers.tolist() == markers


def test_from_polygon_internal_markers():
    d = hammesh.Domain.from_polygon(SQUARE, internal_segments=[[[0.2, 0.2], [0.5, 0.2], [0.5, 0.8]]],
                                    internal_markers=[[4, 5]])
    assert d.segment_markers.tolist() == [1, 1, 1, 1, 4, 5]
    assert d.vertex_markers.tolist() == [1, 1, 1, 1, 0, 0, 0]
    d = hammesh.Domain.from_polygon(SQUARE, internal_segments=[[[0.2, 0.2], [0.5, 0.2]]], internal_markers=[9])
    assert d.segment_markers.tolist()[-1] == 9


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(ring_markers=[1]), r"ring_markers has 1 entries, expected 2"),
        (dict(ring_markers=5), r"ring_markers must be a sequence with one entry per ring"),
        (dict(ring_markers=[[1, 2, 3], 1]), r"ring_markers\[0\] has shape \(3,\), expected an int or 4 ints"),
        (dict(ring_markers=[1.5, 1]), r"ring_markers\[0\]\[0\] is 1.5, not an integer"),
        (dict(ring_markers=[1, "a"]), r"ring_markers\[1\]"),
        (dict(internal_markers=[1]), r"internal_markers given without internal_segments"),
    ],
)
def test_from_polygon_bad_markers(kwargs, message):
    with pytest.raises(InvalidDomainError, match=message):
        hammesh.Domain.from_polygon(SQUARE, [HOLE], **kwargs)


def test_from_polygon_markers_reach_the_mesh():
    d = hammesh.Domain.from_polygon(OUTER, ring_markers=[OUTER_MARKERS])
    m = hammesh.quality_mesh(d, min_angle=30, max_area=0.01)
    assert set(m.segment_markers.tolist()) == set(OUTER_MARKERS)
    left = m.segments[m.segment_markers == 4]
    assert np.allclose(m.points[left][..., 0], 0.0)  # the left side (point 5 -> point 0)


# --- point markers: Triangle, post-process, files --------------------------------------


def test_triangle_keeps_and_spreads_point_markers(plate_mesh):
    m = plate_mesh
    assert m.vertex_markers.shape == (m.n_points,) and m.vertex_markers.dtype == np.int64
    assert m.vertex_markers[0] == 9  # the marked corner
    # Triangle: every other point on a segment carries a marker of a segment through it
    seg_markers_at = {}
    for (a, b), k in zip(m.segments.tolist(), m.segment_markers.tolist()):
        seg_markers_at.setdefault(a, set()).add(k)
        seg_markers_at.setdefault(b, set()).add(k)
    for v, ks in seg_markers_at.items():
        if v != 0:
            assert m.vertex_markers[v] in ks, v
    interior = np.setdiff1d(np.arange(m.n_points), list(seg_markers_at))
    assert (m.vertex_markers[interior] == 0).all()


def test_hamiltonian_keeps_point_markers(plate_mesh, plate):
    n = plate_mesh.n_points
    np.testing.assert_array_equal(plate.vertex_markers[:n], plate_mesh.vertex_markers)
    new = np.arange(n, plate.n_points)
    on_segments = {}
    for (a, b), k in zip(plate.segments.tolist(), plate.segment_markers.tolist()):
        on_segments[a] = k
        on_segments[b] = k
    for v in new.tolist():  # a midpoint of a split segment: the segment's marker
        assert plate.vertex_markers[v] == on_segments.get(v, 0)
    assert plate.as_mesh().vertex_markers is plate.vertex_markers


def test_output_vertex_markers_unit():
    got = output_vertex_markers(np.array([4, 0, 2]), 6, np.array([[0, 3], [3, 1], [2, 5]]), np.array([8, 8, -1]))
    assert got.tolist() == [4, 0, 2, 8, 0, -1]


@pytest.mark.parametrize("suffix", [".vtu", ".vtk", ".xdmf", ".msh", ".ele"])
def test_point_markers_round_trip(tmp_path, plate, suffix):
    path = tmp_path / f"plate{suffix}"
    hammesh.write(plate, path)
    back = hammesh.read_mesh(path)
    np.testing.assert_array_equal(back.vertex_markers, plate.vertex_markers)
    np.testing.assert_array_equal(back.points, plate.points)


def test_mesh_without_point_markers_gets_zeros():
    m = hammesh.Mesh(np.array([[0.0, 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]]))
    assert m.vertex_markers.tolist() == [0, 0, 0]
    with pytest.raises(hammesh.errors.InvalidMeshError, match="vertex_markers"):  # wrong length: never zeroed in silence
        hammesh.Mesh(m.points, m.triangles, vertex_markers=[1, 2])


NONZERO = st.integers(-5, 5).filter(bool)


@settings(max_examples=10, deadline=None)
@given(st.lists(NONZERO, min_size=6, max_size=6), NONZERO)
def test_ring_markers_become_named_boundaries(markers, hole):
    """Any per-side markers of the outer ring and a hole marker end up as skfem boundaries
    holding exactly the mesh edges on those sides (0 is Triangle's "no marker": a
    boundary segment of marker 0 comes out as 1, see the next test)."""
    skfem = pytest.importorskip("skfem")  # noqa: F841
    hole_ring = [[0.3, 0.3], [0.6, 0.3], [0.6, 0.6], [0.3, 0.6]]
    d = hammesh.Domain.from_polygon(OUTER, [hole_ring], ring_markers=[markers, hole])
    h = hammesh.hamiltonian(hammesh.quality_mesh(d, min_angle=25, max_area=0.05))
    m = hammesh.to_skfem(h)
    assert sorted(m.boundaries) == sorted({f"marker_{k}" for k in [*markers, hole]})
    mid = m.p[:, m.facets].mean(axis=1)  # (2, nf) facet midpoints
    ring = np.asarray(OUTER)
    for j, k in enumerate(markers):
        a, b = ring[j], ring[(j + 1) % len(ring)]
        # facets on side j: midpoint on the segment a-b
        cross = (b[0] - a[0]) * (mid[1] - a[1]) - (b[1] - a[1]) * (mid[0] - a[0])
        t = ((mid[0] - a[0]) * (b[0] - a[0]) + (mid[1] - a[1]) * (b[1] - a[1])) / np.sum((b - a) ** 2)
        on_side = np.flatnonzero((np.abs(cross) < 1e-12) & (t > 0) & (t < 1))
        assert set(on_side.tolist()) <= set(np.asarray(m.boundaries[f"marker_{k}"]).tolist())
    total = sum(len(v) for v in m.boundaries.values())
    assert total == len(m.boundary_facets())  # no interior facet, no facet twice


def test_triangle_turns_marker_zero_on_the_boundary_into_one():
    d = hammesh.Domain.from_polygon(SQUARE, [HOLE], ring_markers=[0, 2])
    m = hammesh.quality_mesh(d, min_angle=30, max_area=0.05)
    assert set(m.segment_markers.tolist()) == {1, 2}
