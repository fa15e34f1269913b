"""Tests of hammesh.domain.pslg: the Domain dataclass and Domain.from_polygon."""

from __future__ import annotations

import dataclasses
from importlib import resources

import numpy as np
import pytest
import triangle
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.domain import Domain, read_domain, read_poly, write_poly
from hammesh.errors import InvalidDomainError

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]
RING = [[0, 1], [1, 2], [2, 3], [3, 0]]


def winding_number(point, ring):
    """Independent point-in-polygon: winding number of ``ring`` around ``point``."""
    d = np.asarray(ring, float) - point
    ang = np.arctan2(d[:, 1], d[:, 0])
    turn = np.diff(np.r_[ang, ang[0]])
    turn = (turn + np.pi) % (2 * np.pi) - np.pi
    return int(round(turn.sum() / (2 * np.pi)))


def distance_to_ring(point, ring):
    a = np.asarray(ring, float)
    b = np.roll(a, -1, axis=0)
    ab = b - a
    t = np.clip(((point - a) * ab).sum(1) / (ab * ab).sum(1), 0, 1)
    return float(np.hypot(*(a + t[:, None] * ab - point).T).min())


# ----------------------------------------------------------------------------- Domain

def test_constructor_converts_lists_to_dtypes_and_shapes():
    d = Domain(SQUARE, RING)
    assert d.vertices.dtype == np.float64 and d.vertices.shape == (4, 2)
    assert d.segments.dtype == np.int64 and d.segments.shape == (4, 2)
    assert d.holes.shape == (0, 2) and d.holes.dtype == np.float64
    assert d.regions.shape == (0, 4) and d.regions.dtype == np.float64
    assert d.segment_markers.tolist() == [1, 1, 1, 1]
    assert d.vertex_markers.tolist() == [0, 0, 0, 0]
    assert d.segment_markers.dtype == d.vertex_markers.dtype == np.int64


def test_empty_lists_become_empty_arrays_of_right_shape():
    d = Domain(SQUARE, [], holes=[], regions=[], segment_markers=[])
    assert d.segments.shape == (0, 2) and d.holes.shape == (0, 2)
    assert d.regions.shape == (0, 4) and d.segment_markers.shape == (0,)


def test_none_means_none_of_these():
    d = Domain(vertices=[[0, 0], [1, 0], [0, 1]], segments=None, holes=None, regions=None)
    assert d.segments.shape == (0, 2) and d.holes.shape == (0, 2) and d.regions.shape == (0, 4)


def test_integral_float_segments_are_accepted_fractional_rejected():
    assert Domain(SQUARE, np.array(RING, float)).segments.dtype == np.int64
    with pytest.raises(InvalidDomainError, match=r"segments\[1, 0\] is 1\.5, not an integer"):
        Domain(SQUARE, [[0, 1], [1.5, 2]])
    with pytest.raises(InvalidDomainError, match=r"vertex_markers must hold integers"):
        Domain(SQUARE, vertex_markers=["a", "b", "c", "d"])


def test_unconvertible_input_names_field():
    with pytest.raises(InvalidDomainError, match=r"vertices cannot be converted to float64"):
        Domain([[0, 0], [1, 0, 3], [0, 1]])
    with pytest.raises(InvalidDomainError, match=r"vertices must have shape \(k, 2\)"):
        Domain([0, 1, 2, 3])
    with pytest.raises(InvalidDomainError, match=r"segment_markers must have shape \(4,\)"):
        Domain(SQUARE, RING, segment_markers=[1, 2])


def test_inputs_are_copied_and_stored_arrays_read_only():
    v = np.array(SQUARE, float)
    s = np.array(RING)
    d = Domain(v, s)
    v[0] = [0.5, 0.5]
    s[0] = [2, 2]
    assert d.vertices[0].tolist() == [0, 0] and d.segments[0].tolist() == [0, 1]
    with pytest.raises(ValueError):
        d.vertices[0, 0] = 7.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.vertices = np.zeros((3, 2))


def test_replace_revalidates():
    d = Domain(SQUARE, RING)
    d2 = dataclasses.replace(d, holes=[[0.25, 0.75]])
    assert d2.holes.tolist() == [[0.25, 0.75]]
    d3 = dataclasses.replace(d, holes=[[3.0, 3.0]])  # (outside the hull: dropped, reported)
    assert d3.holes.tolist() == [] and [r.kind for r in d3.repairs] == ["hole_outside"]
    with pytest.raises(InvalidDomainError, match=r"segments 4 and 5 cross"):
        dataclasses.replace(d, segments=RING + [[0, 2], [1, 3]], segment_markers=None,
                            strict=True)


def test_equality_is_identity():
    assert Domain(SQUARE) != Domain(SQUARE)


# ----------------------------------------------------------------------------- from_polygon

def test_from_polygon_square_with_square_hole():
    d = Domain.from_polygon([[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]],
                            [[[1, 1], [2, 1], [2, 2], [1, 2]]])
    assert len(d.vertices) == 8  # closing point dropped
    assert d.segments.tolist() == [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
    assert d.segment_markers.tolist() == [1] * 8 and d.vertex_markers.tolist() == [1] * 8
    (hx, hy), = d.holes
    assert 1 < hx < 2 and 1 < hy < 2


def test_from_polygon_internal_polylines_merge_with_existing_vertices():
    outer = [[0, 0], [4, 0], [4, 4], [0, 4]]
    crack = [[0, 4], [1, 3], [1.5, 2.5]]            # starts at a boundary vertex
    loop = [[2, 1], [3, 1], [3, 2], [2, 1]]          # repeated first point closes it
    d = Domain.from_polygon(outer, internal_segments=[crack, loop])
    assert len(d.vertices) == 4 + 2 + 3
    assert d.segments[4:].tolist() == [[3, 4], [4, 5], [6, 7], [7, 8], [8, 6]]
    assert d.segment_markers.tolist() == [1] * 4 + [0] * 5
    assert d.vertex_markers.tolist() == [1] * 4 + [0] * 5


@pytest.mark.parametrize("kwargs, pattern", [
    (dict(outer=[[0, 0], [1, 0], [0, 0]]), r"outer ring needs at least 3 distinct points, got 2"),
    (dict(outer=[[0, 0, 0], [1, 0, 0], [0, 1, 0]]), r"outer ring must have shape \(k, 2\)"),
    (dict(outer=SQUARE, holes=[[[2, 2], [3, 2], [3, 3]]]), r"hole ring 0 is not inside the outer ring"),
    (dict(outer=[[0, 0], [9, 0], [9, 9], [0, 9]],
          holes=[[[1, 1], [8, 1], [8, 8], [1, 8]], [[3, 3], [4, 3], [4, 4]]]),
     r"hole ring 1 lies inside hole ring 0"),
    (dict(outer=SQUARE, holes=[[[0.2, 0.2], [0.8, 0.2]]]), r"hole ring 0 needs at least 3"),
    (dict(outer=SQUARE, internal_segments=[[[0.5, 0.5]]]), r"internal polyline 0 needs at least 2"),
    (dict(outer=[[0, 0], [1, 0], [0, 1], [1, 1]]), r"segments 1 and 3 cross at \(0\.5, 0\.5\)"),
    (dict(outer=SQUARE, holes=[[[0.5, 0.5], [1.5, 0.5], [0.5, 0.7]]]), r"cross at"),
])
def test_from_polygon_rejects(kwargs, pattern):
    with pytest.raises(InvalidDomainError, match=pattern):
        Domain.from_polygon(**kwargs)


@st.composite
def star_polygons(draw, k_min=5, k_max=40, r_lo=0.5, r_hi=1.0):
    """Star-shaped around the origin: sorted angles (gaps < pi), random radii."""
    k = draw(st.integers(k_min, k_max))
    weights = np.array(draw(st.lists(st.floats(1, 3), min_size=k, max_size=k)))
    start = draw(st.floats(0, 2 * np.pi))
    angles = start + 2 * np.pi * np.cumsum(weights) / weights.sum()
    radii = np.array(draw(st.lists(st.floats(r_lo, r_hi), min_size=k, max_size=k)))
    return np.c_[radii * np.cos(angles), radii * np.sin(angles)]


@settings(max_examples=60, deadline=None)
# outer: >= 8 vertices, gaps <= 0.6 pi, radii >= 0.8, so every outer edge stays
# >= 0.8 cos(0.3 pi) = 0.47 from the origin; the hole reaches at most 0.3 + 0.071
@given(outer=star_polygons(k_min=8, r_lo=0.8), hole=star_polygons(r_lo=0.05, r_hi=0.3),
       centre=st.tuples(st.floats(-0.05, 0.05), st.floats(-0.05, 0.05)))
def test_from_polygon_hole_point_strictly_inside_and_roundtrip(outer, hole, centre, tmp_path_factory):
    hole = hole + np.array(centre)
    d = Domain.from_polygon(outer, [hole])
    assert len(d.vertices) == len(outer) + len(hole)
    (p,) = d.holes
    assert winding_number(p, hole) != 0
    assert distance_to_ring(p, hole) > 0
    assert winding_number(p, outer) != 0
    # write -> read is the identity on every array
    path = tmp_path_factory.mktemp("rt") / "star.poly"
    regions = [[0.9 * outer[0, 0], 0.9 * outer[0, 1], 3.25, np.nan]]
    d2 = dataclasses.replace(d, regions=regions)
    write_poly(d2, path)
    back = read_poly(path)
    for name in ("vertices", "segments", "holes", "regions", "segment_markers", "vertex_markers"):
        np.testing.assert_array_equal(getattr(back, name), getattr(d2, name), err_msg=name)
        assert getattr(back, name).dtype == getattr(d2, name).dtype


# ----------------------------------------------------------------------------- demo

def demo_path():
    return resources.files("hammesh") / "data" / "demo.poly"


def test_demo_domain_is_valid_and_as_described():
    d = read_domain(demo_path())
    assert len(d.holes) == 2 and len(d.regions) == 2
    assert sorted(d.regions[:, 2].tolist()) == [1.0, 2.0]
    assert np.all(np.isnan(d.regions[:, 3]))
    # the crack ends inside: exactly one vertex of degree 1, and it is not on the boundary
    deg = np.bincount(d.segments.ravel(), minlength=len(d.vertices))
    tip = np.flatnonzero(deg == 1)
    assert tip.size == 1 and d.vertex_markers[tip[0]] == 5
    # bore: 24 segments, hexagon: 6
    assert np.sum(d.segment_markers == 2) == 24 and np.sum(d.segment_markers == 4) == 6
    x, y = d.vertices.T
    assert x.min() == 0 and x.max() == 4 and y.min() == 0 and y.max() == 2


def test_demo_domain_meshes_with_triangle():
    d = read_domain(demo_path())
    regions = d.regions.copy()
    regions[np.isnan(regions[:, 3]), 3] = -1.0  # Triangle's "no regional limit"
    out = triangle.triangulate(
        {"vertices": d.vertices.copy(), "segments": d.segments.copy(), "holes": d.holes.copy(),
         "regions": regions, "segment_markers": d.segment_markers.copy()[:, None]},
        "pq30a0.01AQ")
    p, t = out["vertices"], out["triangles"]
    e1, e2, e3 = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 1]], p[t[:, 0]] - p[t[:, 2]]
    area = 0.5 * np.abs(e1[:, 0] * e3[:, 1] - e1[:, 1] * e3[:, 0])
    assert area.max() <= 0.01 * (1 + 1e-9)

    def angle(u, v):
        return np.degrees(np.arccos(np.clip(-(u * v).sum(1) / np.hypot(*u.T) / np.hypot(*v.T), -1, 1)))
    min_angle = np.min([angle(e1, e2), angle(e2, e3), angle(e3, e1)])
    assert min_angle >= 30 - 1e-6
    # total area: plate minus bore minus square (polygonal approximations)
    arc = 12 * 0.5 * np.sin(np.pi / 12)
    bore = 24 * 0.5 * 0.45**2 * np.sin(2 * np.pi / 24)
    assert area.sum() == pytest.approx(3 * 2 + arc - bore - 0.4 * 0.3, rel=1e-6)  # file rounds to 6 decimals
    attr = out["triangle_attributes"][:, 0]
    assert set(attr.tolist()) == {1.0, 2.0}
    hexagon = 1.5 * np.sqrt(3) * 0.4**2
    assert area[attr == 2].sum() == pytest.approx(hexagon, rel=1e-5)
    # no triangle inside the holes
    c = p[t].mean(axis=1)
    assert np.all(np.hypot(c[:, 0] - 3, c[:, 1] - 1) > 0.45 * np.cos(np.pi / 24))
    assert not np.any((c[:, 0] > 0.4) & (c[:, 0] < 0.8) & (c[:, 1] > 0.3) & (c[:, 1] < 0.6))
    # the crack survives as constrained edges (marker 5), with its full length
    segs, marks = out["segments"], out["segment_markers"][:, 0]
    crack = segs[marks == 5]
    tip = d.vertices[d.segments[d.segment_markers == 5]]
    assert np.hypot(*(p[crack[:, 1]] - p[crack[:, 0]]).T).sum() == pytest.approx(
        np.hypot(*(tip[:, 1] - tip[:, 0]).T).sum(), rel=1e-12)
