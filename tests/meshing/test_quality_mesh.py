"""Quality meshing: options, traps of the C backends, isolation."""

from __future__ import annotations

import os
import signal
import time

import numpy as np
import pytest

import hammesh
from hammesh.meshing import MeshOptions, format_number, triangle_switches
from hammesh.meshing.isolate import run_isolated
from tests.helpers import angles_deg, signed_areas, square

SQUARE = hammesh.Domain(vertices=square(), segments=[[0, 1], [1, 2], [2, 3], [3, 0]])


def _crash() -> None:
    os.kill(os.getpid(), signal.SIGSEGV)


def _hang() -> None:
    time.sleep(60)


def _boom() -> None:
    raise KeyError("inner")


@pytest.mark.parametrize("backend", ["triangle", "meshpy"])
def test_min_angle_and_max_area_hold(backend: str) -> None:
    m = hammesh.quality_mesh(SQUARE, min_angle=30, max_area=0.01, backend=backend)
    assert angles_deg(m.points, m.triangles).min() >= 30 - 1e-9
    areas = signed_areas(m.points, m.triangles)
    assert (areas > 0).all() and areas.max() <= 0.01 + 1e-15
    assert np.isclose(areas.sum(), 1.0)


@pytest.mark.parametrize("area", [1e-5, 1.5e-5])
def test_small_area_is_not_misread(area: float) -> None:
    # Triangle reads "a1e-05" as area 1.0 and "a1E-05" as nothing: we write decimals
    assert "e" not in triangle_switches(SQUARE, MeshOptions(max_area=area)).lower().replace("pc", "")
    m = hammesh.quality_mesh(SQUARE, max_area=area)
    assert signed_areas(m.points, m.triangles).max() <= area * (1 + 1e-12)
    assert m.n_triangles >= 1.0 / area


def test_format_number_is_positional() -> None:
    assert format_number(1e-05) == "0.00001"
    assert format_number(2.5e-7) == "0.00000025"
    assert format_number(30.0) == "30"


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"max_area": -1.0}, "max_area"),
        ({"max_area": 0.0}, "max_area"),
        ({"max_area": float("nan")}, "max_area"),
        ({"min_angle": 35}, "min_angle"),
        ({"min_angle": -1}, "min_angle"),
        ({"min_angle": "steep"}, "min_angle"),
        ({"max_steiner": -3}, "max_steiner"),
        ({"max_steiner": 1.5}, "max_steiner"),
        ({"backend": "gmsh"}, "backend"),
        ({"timeout": -1}, "timeout"),
        ({"max_area": 1e-12}, "max_area"),  # would need 1e12 triangles
    ],
)
def test_impossible_options_are_named(kwargs: dict, field: str) -> None:
    with pytest.raises(hammesh.InvalidOptionError, match=field):
        hammesh.quality_mesh(SQUARE, **kwargs)


def test_meshpy_zero_area_and_tiny_area_are_refused() -> None:
    # meshpy exits the process on a zero area ("%.20f" turns 1e-21 into 0)
    with pytest.raises(hammesh.InvalidOptionError, match="max_area"):
        hammesh.quality_mesh(SQUARE, max_area=0, backend="meshpy")
    tiny = hammesh.Domain(vertices=square(0, 0, 1e-6), segments=[[0, 1], [1, 2], [2, 3], [3, 0]])
    with pytest.raises(hammesh.InvalidOptionError, match="meshpy"):
        hammesh.quality_mesh(tiny, max_area=1e-16, backend="meshpy")


def test_bad_domains_are_rejected_before_c_code() -> None:
    with pytest.raises(hammesh.InvalidDomainError, match="vertex 1"):
        hammesh.Domain(vertices=[[0, 0], [np.nan, 0], [0, 1]])
    with pytest.raises(hammesh.InvalidDomainError, match="vertex 2"):
        hammesh.Domain(vertices=[[0, 0], [1, 0], [1e300, 1]])
    with pytest.raises(hammesh.InvalidDomainError, match="segment 1"):
        hammesh.Domain(vertices=square(), segments=[[0, 1], [1, 9]])
    with pytest.raises(hammesh.InvalidDomainError, match="duplicate|same"):
        hammesh.Domain(vertices=square() + [[1, 1]], segments=[[0, 1], [1, 4], [4, 3], [3, 0]], strict=True)


def test_segments_markers_and_neighbours_are_kept() -> None:
    dom = hammesh.Domain(vertices=square(), segments=[[0, 1], [1, 2], [2, 3], [3, 0]], segment_markers=[5, 6, 7, 8])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.05)
    assert set(m.segment_markers.tolist()) == {5, 6, 7, 8}
    # every constrained edge lies on the side its marker names
    p = m.points
    for (a, b), mk in zip(m.segments.tolist(), m.segment_markers.tolist()):
        y = {5: 0.0, 7: 1.0}.get(mk)
        x = {6: 1.0, 8: 0.0}.get(mk)
        if y is not None:
            assert p[a, 1] == y and p[b, 1] == y
        else:
            assert p[a, 0] == x and p[b, 0] == x
    # neighbours: across edge (k, k+1) of t lies a triangle sharing exactly that edge
    for t in range(0, m.n_triangles, 7):
        for k in range(3):
            u = m.neighbors[t, k]
            e = {m.triangles[t, k], m.triangles[t, (k + 1) % 3]}
            if u >= 0:
                assert e <= set(m.triangles[u].tolist())


@pytest.mark.parametrize("backend", ["triangle", "meshpy"])
@pytest.mark.parametrize("isolate", [False, True])
def test_mesh_arrays_are_c_contiguous(backend: str, isolate: bool) -> None:
    """Plain C-order arrays: consumers (the post-process) must not pay a copy."""
    dom = hammesh.Domain(vertices=square(), segments=[[0, 1], [1, 2], [2, 3], [3, 0]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.05, backend=backend, isolate=isolate)
    for name in ("points", "triangles", "neighbors", "segments", "triangle_attributes"):
        a = getattr(m, name)
        if a is not None:
            assert a.flags["C_CONTIGUOUS"], name


def test_regions_attributes_and_regional_area() -> None:
    v = square(0, 0, 2) + square(0.5, 0.5, 1)
    segs = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
    dom = hammesh.Domain(vertices=v, segments=segs, regions=[[0.1, 0.1, 1, np.nan], [1, 1, 2, 0.001]])
    m = hammesh.quality_mesh(dom, min_angle=20, max_area=0.1)
    c = m.points[m.triangles].mean(axis=1)
    inside = (np.abs(c - 1.0) < 0.5).all(axis=1)
    assert (m.triangle_attributes[inside, 0] == 2).all()
    assert (m.triangle_attributes[~inside, 0] == 1).all()
    areas = signed_areas(m.points, m.triangles)
    assert areas[inside].max() <= 0.001 + 1e-15
    assert areas[~inside].max() > 0.001


def test_conforming_delaunay_and_steiner_limit() -> None:
    m = hammesh.quality_mesh(SQUARE, min_angle=30, max_area=0.001, max_steiner=10)
    assert m.n_points <= 4 + 10
    m = hammesh.quality_mesh(SQUARE, min_angle=20, conforming_delaunay=True)
    assert m.n_triangles >= 2


def test_node_only_domain_meshes_the_convex_hull() -> None:
    rng = np.random.default_rng(0)
    pts = rng.random((40, 2))
    m = hammesh.quality_mesh(hammesh.Domain(vertices=pts), min_angle=20)
    from scipy.spatial import ConvexHull

    assert np.isclose(signed_areas(m.points, m.triangles).sum(), ConvexHull(pts).volume)


def test_isolation_turns_a_crash_into_an_error() -> None:
    with pytest.raises(hammesh.MeshingError, match="SIGSEGV"):
        run_isolated(_crash, (), name="Triangle", timeout=30)


def test_isolation_timeout_stops_the_child() -> None:
    t0 = time.perf_counter()
    with pytest.raises(hammesh.MeshingError, match="did not finish within 0.5 s"):
        run_isolated(_hang, (), name="Triangle", timeout=0.5)
    assert time.perf_counter() - t0 < 10


def test_isolation_reports_other_errors_in_one_line() -> None:
    with pytest.raises(hammesh.MeshingError, match="KeyError") as info:
        run_isolated(_boom, (), name="Triangle", timeout=30)
    assert "\n" not in str(info.value)


def test_in_process_and_isolated_agree() -> None:
    a = hammesh.quality_mesh(SQUARE, min_angle=25, max_area=0.02, isolate=False)
    b = hammesh.quality_mesh(SQUARE, min_angle=25, max_area=0.02, isolate=True)
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.triangles, b.triangles)


def test_domain_type_is_checked() -> None:
    with pytest.raises(hammesh.InvalidOptionError, match="Domain"):
        hammesh.quality_mesh({"vertices": square()})  # type: ignore[arg-type]
