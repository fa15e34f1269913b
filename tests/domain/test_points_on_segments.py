"""A hole or region point exactly on a segment or a vertex is refused (session 19).

Triangle starts carving a hole (or spreading a region's attribute) from the triangle its
point location returns, and for a point on an edge that is either side's: the same
square hole removed the ring round it or the square, depending on the side the point
was on. hammesh refuses such a point by name (exit 2, one line) instead of handing
Triangle a coin toss."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.cli import main
from hammesh.errors import InvalidDomainError

OUTER = [[0, 0], [4, 0], [4, 4], [0, 4]]
INNER = [[1, 1], [3, 1], [3, 3], [1, 3]]
SEGMENTS = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]


def _domain(holes=(), regions=()):
    return hammesh.Domain(vertices=np.array(OUTER + INNER, float), segments=np.array(SEGMENTS),
                          holes=np.array(holes, float).reshape(-1, 2), regions=np.array(regions, float).reshape(-1, 4))


@pytest.mark.parametrize("point, on", [((2, 1), "segment 4"), ((2, 3), "segment 6"), ((1, 2), "segment 7"),
                                       ((1, 1), "vertex 4"), ((2, 0), "segment 0"), ((0, 0), "vertex 0"),
                                       ((3.0, 2.5), "segment 5")])
def test_hole_point_on_a_segment_or_vertex_is_refused(point, on):
    with pytest.raises(InvalidDomainError, match=rf"hole point 0 at .* lies exactly on {on}\b"):
        _domain(holes=[point])


@pytest.mark.parametrize("point, on", [((1, 1), "vertex 4"), ((2, 1), "segment 4"), ((0, 0), "vertex 0"),
                                       ((4, 2), "segment 1")])
def test_region_point_on_a_segment_or_vertex_is_refused(point, on):
    with pytest.raises(InvalidDomainError, match=rf"region point 0 at .* lies exactly on {on}\b"):
        _domain(regions=[[*point, 7.0, np.nan]])


def test_a_hole_point_on_a_vertex_of_no_segment_is_accepted():
    """A vertex on no segment lies inside one region: every triangle round it is in
    the hole, whichever Triangle's point location returns; accepted as Triangle does."""
    v = np.array(OUTER + INNER + [[2, 2]], float)
    dom = hammesh.Domain(vertices=v, segments=np.array(SEGMENTS), holes=np.array([[2.0, 2.0]]))
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.5, isolate=False)
    a, b, c = (m.points[m.triangles[:, k]] for k in range(3))
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    assert area.sum() == pytest.approx(12.0)


def test_points_off_the_segments_mesh_as_before():
    """The hole inside the square removes it, a region point inside the ring marks the
    ring; a point next to a segment (one ulp off) is fine."""
    m = hammesh.quality_mesh(_domain(holes=[[2, 2]], regions=[[np.nextafter(1.0, 0.0), 2, 7.0, np.nan]]),
                             min_angle=30, max_area=0.5, isolate=False)
    c = m.points[m.triangles].mean(axis=1)
    assert not ((c > 1) & (c < 3)).all(axis=1).any()  # (no triangle inside the square)
    assert set(np.unique(m.triangle_attributes[:, 0])) == {7.0}


@settings(max_examples=60, deadline=None)
@given(t=st.floats(0.0, 1.0), side=st.integers(0, 7), hole=st.booleans())
def test_any_point_on_any_segment_is_refused(t, side, hole):
    """Points on a segment by construction (``a + t (b - a)`` where that is exactly on
    it, by the exact predicate): refused; the check never refuses a point off every
    segment (the square's centre)."""
    from hammesh.predicates import orient

    v = np.array(OUTER + INNER, float)
    a, b = v[SEGMENTS[side][0]], v[SEGMENTS[side][1]]
    p = a + t * (b - a)
    if orient(*a, *b, *p) != 0:
        return
    kw = {"holes": [p]} if hole else {"regions": [[*p, 1.0, np.nan]]}
    with pytest.raises(InvalidDomainError, match="lies exactly on"):
        _domain(**kw)
    _domain(holes=[[2, 2]])


def test_cli_names_the_point_in_one_line_and_writes_nothing(tmp_path, capsys):
    poly = tmp_path / "sq.poly"
    lines = ["8 2 0 0", *[f"{i + 1} {x} {y}" for i, (x, y) in enumerate(OUTER + INNER)], "8 0",
             *[f"{i + 1} {a + 1} {b + 1}" for i, (a, b) in enumerate(SEGMENTS)], "1", "1 2 1"]
    poly.write_text("\n".join(lines) + "\n")
    assert main(["mesh", str(poly), "-q", "30", "-a", "0.5", "-o", str(tmp_path / "o.vtu")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "hole point 0 at (2.0, 1.0) lies exactly on segment 4" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sq.poly"]
