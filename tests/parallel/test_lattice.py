"""The tiles' interior lattice (tile_mesh.lattice_points): where its points go, and
that Triangle's mesh of a tile with them keeps every bound of the tile's own run."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.parallel import decompose
from hammesh.parallel._kernels import lattice_mark_inside_into
from hammesh.parallel.tile_mesh import (LATTICE_CLEARANCE, LATTICE_GRADING, lattice_points, lattice_spacing,
                                        mesh_tile)
from tests.helpers import angles_deg, signed_areas

DEMO = "hammesh/data/demo.poly"  # holes, a crack, two regions, a rounded end


def _segment_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(len(q), len(a)) distances of points to segments, plain numpy."""
    e = b - a
    ll = (e * e).sum(axis=1)
    t = np.clip(((q[:, None, :] - a[None]) * e[None]).sum(axis=2) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
    d = q[:, None, :] - a[None] - t[..., None] * e[None]
    return np.sqrt((d * d).sum(axis=2))


def _inside_domain(dom: hammesh.Domain, q: np.ndarray) -> np.ndarray:
    """Which points a Triangle mesh of the domain covers (matplotlib's locator, not ours)."""
    from matplotlib.tri import Triangulation

    m = hammesh.quality_mesh(dom, min_angle=20, max_area=0.05, isolate=False)
    return Triangulation(m.points[:, 0], m.points[:, 1], m.triangles).get_trifinder()(q[:, 0], q[:, 1]) >= 0


@pytest.mark.parametrize("n_tiles", [1, 2, 3])
def test_lattice_points_lie_inside_clear_of_segments_and_a_step_apart(n_tiles):
    dom = hammesh.read_domain(DEMO)
    a = 1e-3
    h = lattice_spacing(a)
    d = decompose(dom, min_angle=30, max_area=a, n_tiles=n_tiles)
    total = 0
    for t in d.tiles:
        q = lattice_points(t, a)
        total += len(q)
        assert q.shape[1] == 2 and len(q) > 0
        box = t.box
        assert ((q[:, 0] > box[0]) & (q[:, 0] < box[1]) & (q[:, 1] > box[2]) & (q[:, 1] < box[3])).all()
        assert _inside_domain(dom, q).all()
        v, s = t.vertices, t.segments
        length = np.linalg.norm(v[s[:, 0]] - v[s[:, 1]], axis=1)
        need = LATTICE_CLEARANCE * h + LATTICE_GRADING * np.maximum(0.0, h - length)
        assert (_segment_distance(q, v[s[:, 0]], v[s[:, 1]]) >= need[None] * (1 - 1e-12)).all()
        # an equilateral lattice: nearest neighbours exactly one step apart
        from scipy.spatial import cKDTree

        dist, _ = cKDTree(q).query(q, k=2)
        assert np.allclose(dist[:, 1], h, rtol=1e-9)
    # the lattice fills most of the domain: at least half the triangles it implies
    assert total >= 0.5 * d.area / (np.sqrt(3) / 2 * h * h)


def test_a_tile_meshed_with_its_lattice_keeps_the_bounds_and_the_count():
    dom = hammesh.read_domain(DEMO)
    a = 2e-4
    d = decompose(dom, min_angle=30, max_area=a, n_tiles=2)
    n_with = n_without = 0
    for t in d.tiles:
        q = lattice_points(t, a)
        m = mesh_tile(t, 30, a)
        plain = mesh_tile(t, 30, a, lattice=False)
        n_with, n_without = n_with + m.n_triangles, n_without + plain.n_triangles
        k = len(t.vertices)
        assert np.array_equal(m.points[:k], t.vertices)
        # the lattice is in the mesh (the band's outline points first, the inner ones last)
        rows = lambda p: p[np.lexsort((p[:, 1], p[:, 0]))]  # noqa: E731
        lat = m.points[k:][np.isin(m.points[k:].view("f8,f8").ravel(), q.view("f8,f8").ravel())]
        assert np.array_equal(rows(lat), rows(q))
        assert np.isin(np.arange(len(m.points)), m.triangles).all()  # every point used
        area = signed_areas(m.points, m.triangles)
        assert (area > 0).all() and area.max() <= a * (1 + 1e-9)
        assert area.sum() == pytest.approx(signed_areas(plain.points, plain.triangles).sum(), rel=1e-12)
        # as good as the tile's own run (which may miss 30 degrees next to a prescribed
        # point it may not split: the driver's repair rounds are for that)
        floor = min(30.0, angles_deg(plain.points, plain.triangles).min())
        assert angles_deg(m.points, m.triangles).min() >= floor * (1 - 1e-9)
        assert (angles_deg(m.points, m.triangles).min(axis=1) < 30 - 1e-9).sum() <= \
            (angles_deg(plain.points, plain.triangles).min(axis=1) < 30 - 1e-9).sum()
        # the separators are kept as given (both tiles along one have its subsegments)
        key = lambda e: set(map(tuple, np.sort(e, axis=1).tolist()))  # noqa: E731
        edges = np.concatenate([m.triangles[:, [0, 1]], m.triangles[:, [1, 2]], m.triangles[:, [2, 0]]])
        assert key(t.segments[t.separator]) <= key(edges)
    assert abs(n_with / n_without - 1) <= 0.03


def test_mesh_tile_without_lattice_is_triangles_own_run():
    dom = hammesh.read_domain(DEMO)
    d = decompose(dom, min_angle=30, max_area=1e-3, n_tiles=2)
    t = d.tiles[0]
    m = mesh_tile(t, 30, 1e-3, lattice=False)
    import triangle

    data = {"vertices": t.vertices, "segments": t.segments.astype(np.int32),
            "segment_markers": t.segment_markers.astype(np.int32)[:, None]}
    if len(t.holes):
        data["holes"] = t.holes
    out = triangle.triangulate(data, m.info["switches"])
    assert len(out["triangles"]) == m.n_triangles


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(corners=st.lists(st.tuples(st.floats(-1, 2), st.floats(-1, 2)), min_size=3, max_size=3),
       h=st.floats(0.03, 0.3), ox=st.floats(-0.5, 0.5), oy=st.floats(-0.5, 0.5))
def test_inside_marking_matches_barycentric_coordinates(corners, h, ox, oy):
    p = np.array(corners, float)
    area2 = (p[1, 0] - p[0, 0]) * (p[2, 1] - p[0, 1]) - (p[1, 1] - p[0, 1]) * (p[2, 0] - p[0, 0])
    if abs(area2) < 1e-3:
        return
    dy = h * np.sqrt(3) / 2
    ny, nx = int(3.5 // dy), int(3.5 // h)
    keep = np.zeros((ny, nx), np.bool_)
    x0, y0 = -1.2 + ox * h, -1.2 + oy * dy
    lattice_mark_inside_into(x0, y0, h, dy, p, np.array([[0, 1, 2]], np.int64), keep)
    j, i = np.mgrid[0:ny, 0:nx]
    x, y = x0 + (i + 0.5 * (j & 1)) * h, y0 + j * dy
    lam = []
    for k in range(3):
        a, b = p[(k + 1) % 3], p[(k + 2) % 3]
        lam.append(((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) / area2)
    depth = np.minimum(np.minimum(lam[0], lam[1]), lam[2])
    clear = np.abs(depth) > 1e-9  # points on an edge may go either way
    assert np.array_equal(keep[clear], (depth >= 0)[clear])


def test_no_lattice_when_the_domain_fills_little_of_the_box():
    """A thin slanted strip: its box is ~100x its area, the lattice is left out (the
    mask over the box would cost more than it saves) and the tile is Triangle's alone."""
    w = 0.005
    dom = hammesh.Domain(vertices=[[0, 0], [w, 0], [1, 1 - w], [1, 1], [1 - w, 1], [0, w]],
                         segments=[[i, (i + 1) % 6] for i in range(6)])
    d = decompose(dom, min_angle=30, max_area=2e-7, n_tiles=1)
    t = d.tiles[0]
    assert lattice_points(t, 2e-7).shape == (0, 2)
    m = mesh_tile(t, 30, 2e-7)
    assert m.n_triangles == mesh_tile(t, 30, 2e-7, lattice=False).n_triangles
