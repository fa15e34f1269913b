"""Tests of hammesh.domain.validate: every rejected input, with the offending item named."""

from __future__ import annotations

import time
from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.domain import Domain, validate_domain
from hammesh.errors import HammeshError, InvalidDomainError

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]
RING = [[0, 1], [1, 2], [2, 3], [3, 0]]


def raw(**overrides):
    """A namespace with valid square-domain fields, bypassing Domain's conversion."""
    fields = dict(vertices=np.array(SQUARE, np.float64), segments=np.array(RING, np.int64),
                  holes=np.zeros((0, 2)), regions=np.zeros((0, 4)),
                  segment_markers=np.ones(4, np.int64), vertex_markers=np.zeros(4, np.int64))
    fields.update(overrides)
    return SimpleNamespace(**fields)


def test_valid_square_passes():
    validate_domain(raw())
    d = Domain(SQUARE, RING, holes=[[5, 5]], regions=[[0.5, 0.5, 1, np.nan]])
    validate_domain(d)


def test_error_type_is_hammesh_and_value_error():
    with pytest.raises(InvalidDomainError) as info:
        Domain([[0, 0], [1, 0]])
    assert isinstance(info.value, HammeshError) and isinstance(info.value, ValueError)


@pytest.mark.parametrize("fields, pattern", [
    (dict(vertices=np.zeros((4, 3))), r"vertices must have shape \(k, 2\), got \(4, 3\)"),
    (dict(vertices=np.array(SQUARE, np.float32)), r"vertices must have dtype float64, got float32"),
    (dict(segments=np.array(RING, np.float64)), r"segments must have dtype int64, got float64"),
    (dict(segments=np.array(RING, np.int32)), r"segments must have dtype int64, got int32"),
    (dict(holes=np.zeros((1, 3))), r"holes must have shape"),
    (dict(regions=np.zeros((1, 3))), r"regions must have shape \(k, 4\)"),
    (dict(segment_markers=np.ones(3, np.int64)), r"segment_markers must have shape \(4,\)"),
    (dict(vertex_markers=np.ones((4, 1), np.int64)), r"vertex_markers must be one-dimensional"),
    (dict(vertices=SQUARE), r"vertices must be a numpy array, got list"),
])
def test_wrong_field_shape_or_dtype_names_field(fields, pattern):
    with pytest.raises(InvalidDomainError, match=pattern):
        validate_domain(raw(**fields))


def test_missing_field_is_named():
    ns = raw()
    del ns.holes
    with pytest.raises(InvalidDomainError, match="no field 'holes'"):
        validate_domain(ns)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_vertex_is_named(bad):
    v = np.array(SQUARE, float)
    v[2, 1] = bad
    with pytest.raises(InvalidDomainError,
                       match=rf"vertex 2 has a non-finite y coordinate \({bad!r}\)"):
        Domain(v, RING)


def test_non_finite_hole_and_region_are_named():
    with pytest.raises(InvalidDomainError, match=r"hole 1 has a non-finite x coordinate \(nan\)"):
        Domain(SQUARE, RING, holes=[[5, 5], [np.nan, 0]])
    with pytest.raises(InvalidDomainError, match=r"region 0 has a non-finite attribute \(inf\)"):
        Domain(SQUARE, RING, regions=[[0.5, 0.5, np.inf, 1.0]])
    with pytest.raises(InvalidDomainError, match=r"region 1 has a non-finite y coordinate"):
        Domain(SQUARE, RING, regions=[[0.5, 0.5, 1, 1.0], [0.5, -np.inf, 1, 1.0]])


def test_huge_coordinate_is_named_with_reason():
    v = np.array(SQUARE, float)
    v[3, 0] = -2e30
    with pytest.raises(InvalidDomainError, match=r"vertex 3 has x coordinate = -2e\+30 beyond.*overflow"):
        Domain(v, RING)
    with pytest.raises(InvalidDomainError, match=r"hole 0 has y coordinate = 1e\+31"):
        Domain(SQUARE, RING, holes=[[0, 1e31]])
    # 1e30 itself is allowed
    Domain([[0, 0], [1e30, 0], [0, 1e30]])


@pytest.mark.parametrize("n", [0, 1, 2])
def test_fewer_than_three_vertices(n):
    with pytest.raises(InvalidDomainError, match=rf"at least 3 vertices, got {n}"):
        Domain(np.arange(2 * n, dtype=float).reshape(n, 2) * [1, 0])


def test_all_collinear_vertices():
    with pytest.raises(InvalidDomainError, match=r"all 5 vertices are collinear"):
        Domain([[0, 0], [1, 1], [2, 2], [3, 3], [-7, -7]])
    # a tiny but genuine triangle far from the axis is not collinear
    Domain([[0, 0], [1, 0], [0.5, 1e-6]])


def test_duplicate_vertices_name_both_indices():
    v = [[0, 0], [1, 0], [1, 1], [0, 1], [1, 0]]
    with pytest.raises(InvalidDomainError,
                       match=r"vertices 1 and 4 are duplicates: both at \(1\.0, 0\.0\)"):
        Domain(v, strict=True)
    with pytest.raises(InvalidDomainError, match=r"vertices 0 and 3 are duplicates"):
        Domain([[0.0, 0], [1, 0], [1, 1], [-0.0, 0]], strict=True)  # -0.0 == 0.0


def test_segment_index_out_of_range_and_negative():
    with pytest.raises(InvalidDomainError,
                       match=r"segment 2 references vertex 12 but there are only 4 vertices"):
        Domain(SQUARE, [[0, 1], [1, 2], [2, 12]])
    with pytest.raises(InvalidDomainError, match=r"segment 1 references negative vertex index -1"):
        Domain(SQUARE, [[0, 1], [-1, 2]])


def test_segment_with_repeated_index():
    with pytest.raises(InvalidDomainError, match=r"segment 3 has zero length: both ends are vertex 2"):
        Domain(SQUARE, [[0, 1], [1, 2], [2, 3], [2, 2]], strict=True)


def test_zero_length_segment_between_equal_vertices_is_a_duplicate_vertex():
    with pytest.raises(InvalidDomainError, match=r"vertices 1 and 4 are duplicates"):
        Domain(SQUARE + [[1, 0]], RING + [[1, 4]], strict=True)


@pytest.mark.parametrize("extra", [[1, 0], [0, 1]])
def test_duplicate_segments_either_order(extra):
    with pytest.raises(InvalidDomainError,
                       match=r"segments 0 and 4 are duplicates: both connect vertices"):
        Domain(SQUARE, RING + [extra], strict=True)


def test_crossing_segments_name_both_and_point():
    with pytest.raises(InvalidDomainError, match=r"segments 4 and 5 cross at \(0\.5, 0\.5\)"):
        Domain(SQUARE, RING + [[0, 2], [1, 3]], strict=True)


def test_crossing_point_is_accurate():
    v = [[0, 0], [3, 1], [0, 2], [2, -1], [1, 5]]
    with pytest.raises(InvalidDomainError) as info:
        Domain(v, [[0, 1], [3, 4]], strict=True)
    x, y = (float(t) for t in info.value.args[0].split("at (")[1].rstrip(")").split(", "))
    # intersection of y = x/3 with the line through (2,-1), (1,5): y = -6x + 11
    assert x == pytest.approx(33 / 19) and y == pytest.approx(11 / 19)


def test_collinear_overlap_without_shared_endpoint():
    v = [[0, 0], [2, 0], [1, 0], [3, 0], [0, 1]]
    with pytest.raises(InvalidDomainError,
                       match=r"segments 0 and 1 overlap collinearly between \(1\.0, 0\.0\) and \(2\.0, 0\.0\)"):
        Domain(v, [[0, 1], [2, 3]], strict=True)


def test_collinear_overlap_with_shared_endpoint():
    v = [[0, 0], [2, 0], [1, 0], [0, 1]]
    with pytest.raises(InvalidDomainError,
                       match=r"segments 0 and 1 overlap collinearly between \(0\.0, 0\.0\) and \(1\.0, 0\.0\)"):
        Domain(v, [[0, 1], [0, 2]], strict=True)


def test_collinear_segments_meeting_end_to_end_are_fine():
    Domain([[0, 0], [1, 0], [2, 0], [0, 1]], [[0, 1], [1, 2]])
    Domain([[0, 0], [1, 0], [-1, 0], [0, 1]], [[0, 1], [0, 2]])


def test_segment_endpoint_on_other_segment_is_named():
    # T-junction: vertex 4 (end of segment 4) lies inside segment 0
    v = SQUARE + [[0.5, 0], [0.5, 0.5]]
    with pytest.raises(InvalidDomainError,
                       match=r"segment 0 passes through vertex 4 at \(0\.5, 0\.0\), which is not one of its endpoints"):
        Domain(v, RING + [[4, 5]], strict=True)


def test_free_vertex_on_segment_is_named():
    with pytest.raises(InvalidDomainError, match=r"segment 1 passes through vertex 4"):
        Domain(SQUARE + [[1, 0.25]], RING, strict=True)
    # the same vertex just off the segment is fine, and so is a vertex on the
    # segment's line but beyond its end
    Domain(SQUARE + [[1 - 1e-9, 0.25]], RING)
    Domain(SQUARE + [[1, 1.5]], RING)


def test_shared_endpoints_and_free_vertices_are_fine():
    d = Domain(SQUARE + [[0.5, 0.5], [0.2, 0.7]], RING + [[0, 4], [4, 2], [1, 4]])
    assert len(d.segments) == 7


@pytest.mark.parametrize("area", [0.0, -1.0, np.inf])
def test_region_max_area_must_be_nan_or_positive(area):
    with pytest.raises(InvalidDomainError, match=rf"region 1 has max_area {area!r}"):
        Domain(SQUARE, RING, regions=[[0.5, 0.5, 1, np.nan], [0.5, 0.5, 2, area]])


def test_region_max_area_nan_and_positive_ok():
    d = Domain(SQUARE, RING, regions=[[0.5, 0.5, 1, np.nan], [0.2, 0.2, 2, 1e-3]])
    assert np.isnan(d.regions[0, 3]) and d.regions[1, 3] == 1e-3


# ----------------------------------------------------------------------------- reference

def _exact_problem(points, segs):
    """Brute-force, exact reference: is any segment crossed, overlapped or touched?"""
    P = [(Fraction(x), Fraction(y)) for x, y in points]

    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    def on_open_segment(a, b, p):
        if orient(a, b, p) != 0:
            return False
        dot1 = (p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1])
        dot2 = (p[0] - b[0]) * (a[0] - b[0]) + (p[1] - b[1]) * (a[1] - b[1])
        return dot1 > 0 and dot2 > 0

    for i, (a, b) in enumerate(segs):
        for v in range(len(P)):
            if v not in (a, b) and on_open_segment(P[a], P[b], P[v]):
                return True
        for c, d in segs[i + 1:]:
            if {a, b} & {c, d}:
                continue  # overlaps at a shared end are caught by the vertex test
            o1, o2 = orient(P[a], P[b], P[c]), orient(P[a], P[b], P[d])
            o3, o4 = orient(P[c], P[d], P[a]), orient(P[c], P[d], P[b])
            if o1 * o2 < 0 and o3 * o4 < 0:
                return True
    return False


@st.composite
def segment_soups(draw, grid=12):
    n = draw(st.integers(3, 14))
    pts = draw(st.lists(st.tuples(st.integers(0, grid), st.integers(0, grid)),
                        min_size=n, max_size=n, unique=True))
    pairs = draw(st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1))
                          .filter(lambda p: p[0] != p[1]), max_size=10,
                          unique_by=lambda p: frozenset(p)))
    return pts, pairs


def _agrees_with_reference(pts, pairs):
    arr = np.array(pts, float)
    collinear = np.linalg.matrix_rank(np.c_[arr, np.ones(len(arr))]) < 3
    expected_bad = (not collinear) and _exact_problem(pts, pairs)
    try:
        Domain(pts, np.array(pairs, np.int64).reshape(-1, 2), strict=True)
    except InvalidDomainError as exc:
        msg = str(exc)
        if collinear:
            assert "collinear" in msg
        else:
            assert expected_bad, msg
            assert ("cross at" in msg or "overlap collinearly" in msg
                    or "passes through vertex" in msg), msg
    else:
        assert not expected_bad and not collinear


@settings(max_examples=300, deadline=None)
@given(segment_soups())
def test_geometry_checks_agree_with_exact_brute_force(soup):
    # integer coordinates on a small grid: collinearities and T-junctions are frequent
    _agrees_with_reference(*soup)


@settings(max_examples=60, deadline=None)
@given(segment_soups(grid=40))
def test_geometry_checks_on_a_finer_grid(soup):
    _agrees_with_reference(*soup)


# ----------------------------------------------------------------------------- scale

def _wavy_polygon(n):
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 1 + 0.3 * np.sin(7 * th)
    pts = np.c_[r * np.cos(th), r * np.sin(th)]
    idx = np.arange(n)
    return pts, np.c_[idx, np.roll(idx, -1)]


def test_hundred_thousand_segments_are_fast():
    pts, segs = _wavy_polygon(100_000)
    t = time.perf_counter()
    Domain(pts, segs)
    assert time.perf_counter() - t < 5.0
    # one extra segment leaving the polygon is found among the 100k
    with pytest.raises(InvalidDomainError, match=r"segments \d+ and 100000 cross at"):
        Domain(np.r_[pts, [[5.0, 0.1]]], np.r_[segs, [[33_333, 100_000]]], strict=True)
    # one extra vertex exactly on an edge is found too (a square's edge: exact midpoint)
    sq = np.array([[-2.0, -2], [2, -2], [2, 2], [-2, 2]])
    with pytest.raises(InvalidDomainError, match=r"segment 100000 passes through vertex 100004"):
        Domain(np.r_[pts, sq, [[0.0, -2.0]]], np.r_[segs, 100_000 + np.array(RING)], strict=True)


def test_many_short_random_segments_are_fast():
    rng = np.random.default_rng(1)
    a = rng.random((50_000, 2)) * 1000
    pts = np.r_[a, a + [1e-3, 2e-4]]
    segs = np.c_[np.arange(50_000), np.arange(50_000, 100_000)]
    t = time.perf_counter()
    Domain(pts, segs)
    assert time.perf_counter() - t < 5.0


def test_translation_far_from_origin_keeps_small_features():
    # UTM-like coordinates: features of 1 m at 5e6 m must not be called collinear
    off = np.array([5e6, 5e6])
    pts = np.array(SQUARE, float) * 100 + off
    inner = np.array([[40, 40], [60, 40], [50, 41]], float) + off
    Domain(np.r_[pts, inner], RING + [[4, 5], [5, 6], [6, 4]])


@pytest.mark.parametrize("field", ["vertices", "holes", "ring", "vertex_attributes"])
def test_complex_numbers_are_refused_not_cast(field: str) -> None:
    """numpy would keep only the real part (a ComplexWarning): the domain says what is wrong."""
    import warnings

    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=complex)
    square[2, 1] = 1 + 1e-3j
    real = square.real
    segs = [[0, 1], [1, 2], [2, 3], [3, 0]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (no ComplexWarning on the way to the error)
        with pytest.raises(hammesh.InvalidDomainError, match="complex numbers"):
            if field == "vertices":
                hammesh.Domain(vertices=square, segments=segs)
            elif field == "holes":
                hammesh.Domain(vertices=real, segments=segs, holes=[[0.5 + 0.1j, 0.5]])
            elif field == "ring":
                hammesh.Domain.from_polygon(square)
            else:
                hammesh.Domain(vertices=real, segments=segs, vertex_attributes=square[:, :1])
        hammesh.Domain(vertices=real, segments=segs)  # the real square is fine


@settings(max_examples=120, deadline=None)
@given(n=st.integers(1, 40), scales=st.lists(st.sampled_from([0.0, 1e-70, 1e-61, 1e-59, 1.0, 1e6]), min_size=2,
                                              max_size=3), seed=st.integers(0, 2**31 - 1))
def test_check_extent_refuses_exactly_the_spans_below_the_floor(n, scales, seed):
    # the columns' ranges (1-D reductions) are the whole array's range per axis: refused
    # exactly where the largest span is positive and below MIN_EXTENT, whichever column it is
    from hammesh.domain.validate import MIN_EXTENT, check_extent
    from hammesh.errors import InvalidMeshError

    pts = np.random.default_rng(seed).random((n, len(scales))) * np.array(scales)
    span = float((pts.max(axis=0) - pts.min(axis=0)).max())
    if 0 < span < MIN_EXTENT:
        with pytest.raises(InvalidMeshError, match="spans only"):
            check_extent(pts, InvalidMeshError)
    else:
        check_extent(pts, InvalidMeshError)
