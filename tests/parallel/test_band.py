"""A tile made of its lattice's own triangles and Triangle's mesh of the band around
them (tile_mesh.mesh_band): the same bounds, a conforming mesh, the same count."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
import hammesh.parallel.tile_mesh as tm
from hammesh.parallel import decompose
from hammesh.parallel._kernels import lattice_mesh_into, lattice_triangles_into
from tests.helpers import angles_deg, signed_areas

DEMO = "hammesh/data/demo.poly"  # holes, a crack, two regions, a rounded end


def _edges(t: np.ndarray) -> np.ndarray:
    return np.stack([t, np.roll(t, -1, axis=1)], axis=-1)  # (m, 3, 2): edge s = (s, s + 1)


def _check_neighbors(t: np.ndarray, nbr: np.ndarray) -> None:
    """``nbr[r, s]`` holds the reversed edge ``(s, s + 1)`` of ``r``; -1 exactly where no
    other triangle has that edge reversed (plain dictionary of directed edges)."""
    owner = {(int(a), int(b)): r for r, row in enumerate(_edges(t)) for a, b in row}
    assert len(owner) == 3 * len(t)  # no directed edge twice
    for r, row in enumerate(_edges(t)):
        for s, (a, b) in enumerate(row):
            assert nbr[r, s] == owner.get((int(b), int(a)), -1)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ny=st.integers(2, 9), nx=st.integers(2, 9), seed=st.integers(0, 2**32 - 1), fill=st.floats(0.3, 1.0),
       block=st.integers(1, 4), order=st.sampled_from(["rows", "hilbert"]))
def test_lattice_triangles_are_equilateral_ccw_with_their_neighbours(ny, nx, seed, fill, block, order):
    keep = np.random.default_rng(seed).random((ny, nx)) < fill
    index = np.empty((ny - 1, 2 * (nx - 1)), np.int64)
    from hammesh.parallel.tile_mesh import lattice_blocks

    blocks = lattice_blocks(ny - 1, nx - 1, block, order)
    assert len(np.unique(blocks, axis=0)) == len(blocks) == -(-(ny - 1) // block) * -(-(nx - 1) // block)
    count = lattice_triangles_into(keep, block, blocks, index)
    assert np.array_equal(np.sort(index[index >= 0]), np.arange(count))  # numbered 0..count-1
    corners, nbr, inc = np.empty((count, 3), np.int64), np.empty((count, 3), np.int64), np.empty(nx * ny, np.int64)
    lattice_mesh_into(index, nx, corners, nbr, inc)
    j, i = np.divmod(np.arange(nx * ny), nx)
    xy = np.stack([i + 0.5 * (j & 1), j * np.sqrt(3) / 2], axis=1)
    if count:
        assert keep.ravel()[corners].all()
        assert np.allclose(signed_areas(xy, corners), np.sqrt(3) / 4)  # counter-clockwise, side 1
        assert np.allclose(angles_deg(xy, corners), 60.0)
        _check_neighbors(corners, nbr)
    assert np.array_equal(inc, np.bincount(corners.ravel(), minlength=nx * ny))
    # every triangle of the lattice with three kept corners is there: the unit triangles
    # of the kept points' unit-distance graph (trace of its adjacency cubed / 6)
    q = xy[keep.ravel()]
    unit = np.isclose(np.linalg.norm(q[:, None] - q[None], axis=2), 1.0).astype(np.int64)
    want = int(np.trace(unit @ unit @ unit)) // 6
    assert count == want


def _band_and_plain(tile, a, monkeypatch):
    band = tm.mesh_tile(tile, 30, a)
    monkeypatch.setattr(tm, "LATTICE_BAND", False)
    plain = tm.mesh_tile(tile, 30, a)
    monkeypatch.setattr(tm, "LATTICE_BAND", True)
    return band, plain


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.function_scoped_fixture])
@given(a=st.floats(2e-5, 3e-4), n_tiles=st.integers(1, 3))
def test_band_mesh_keeps_the_bounds_conforms_and_counts_as_triangles_own(a, n_tiles, monkeypatch):
    d = decompose(hammesh.read_domain(DEMO), min_angle=30, max_area=a, n_tiles=n_tiles)
    for t in d.tiles:
        m, plain = _band_and_plain(t, a, monkeypatch)
        assert m.info.get("lattice") == "band" and plain.info.get("lattice") is None
        # the rows are local (sparse mode skips its renumbering: ``sparse.renumbers``):
        # neighbours near each other in memory, nine in ten within a tenth of the rows
        gap = np.abs(m.neighbors - np.arange(m.n_triangles)[:, None])[m.neighbors >= 0]
        assert m.info.get("rows_local") is True and np.percentile(gap, 90) <= 0.1 * m.n_triangles
        k = len(t.vertices)
        assert np.array_equal(m.points[:k], t.vertices)
        assert np.isin(np.arange(len(m.points)), m.triangles).all()  # every point used
        area = signed_areas(m.points, m.triangles)
        assert (area > 0).all() and area.max() <= a * (1 + 1e-9)
        assert area.sum() == pytest.approx(signed_areas(plain.points, plain.triangles).sum(), rel=1e-12)
        bad = angles_deg(m.points, m.triangles).min(axis=1) < 30 * (1 - 1e-9)
        assert not (bad & ~(m.triangles < k).any(axis=1)).any()  # only ever at the tile's own points
        _check_neighbors(m.triangles, m.neighbors)
        # the tile's boundary is the plain run's (the separators kept as given) and the
        # segments are the domain's only (no outline of the lattice among them)
        bnd = lambda h: {tuple(sorted(map(tuple, h.points[e].tolist())))  # noqa: E731
                         for e in _edges(h.triangles)[h.neighbors < 0]}
        assert bnd(m) == bnd(plain)
        seg = lambda h: {tuple(sorted(map(tuple, h.points[e].tolist()))) for e in h.segments}  # noqa: E731
        assert seg(m) == seg(plain)
        assert np.array_equal(np.unique(m.triangle_attributes), np.unique(plain.triangle_attributes))
        # every triangle's regional attribute is that of the plain run's triangle under its centroid
        rows = np.random.default_rng(0).choice(m.n_triangles, min(m.n_triangles, 400), replace=False)
        under = tm.locate_in_triangles(plain.points, plain.triangles, m.points[m.triangles[rows]].mean(axis=1))
        assert (under >= 0).all()
        assert np.array_equal(m.triangle_attributes[rows], plain.triangle_attributes[under])
        assert abs(m.n_triangles / plain.n_triangles - 1) <= 0.01


def test_band_that_fails_its_check_falls_back_to_the_lattice_points(monkeypatch):
    """A band Triangle could not make good enough (here: told every angle is 0) is not
    used: the tile is Triangle's run of the lattice's points, as before."""
    import hammesh.parallel.union as union

    d = decompose(hammesh.read_domain(DEMO), min_angle=30, max_area=1e-4, n_tiles=2)
    t = d.tiles[0]
    assert tm.mesh_band(t, tm.lattice_grid(t, 1e-4), 30, 1e-4) is not None
    monkeypatch.setattr(union, "min_angles_deg", lambda p, tri: np.zeros(len(tri)))
    assert tm.mesh_band(t, tm.lattice_grid(t, 1e-4), 30, 1e-4) is None
    m = tm.mesh_tile(t, 30, 1e-4)
    assert m.info.get("lattice") is None
    assert np.isin(tm.lattice_points(t, 1e-4).view("f8,f8").ravel(), m.points.view("f8,f8").ravel()).all()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ny=st.integers(2, 12), nx=st.integers(2, 12), seed=st.integers(0, 2**32 - 1), fill=st.floats(0.3, 1.0))
def test_outline_hole_points_fall_in_every_piece_of_the_lattice(ny, nx, seed, fill):
    """Triangle's hole points for the lattice (one per loop of its outline): each is the
    centroid of a lattice triangle, and every piece of the lattice (its triangles'
    edge-connected components, found here by a plain walk) holds at least one."""
    keep = np.random.default_rng(seed).random((ny, nx)) < fill
    index = np.empty((ny - 1, 2 * (nx - 1)), np.int64)
    count = lattice_triangles_into(keep, 1, tm.lattice_blocks(ny - 1, nx - 1, 1), index)
    if count == 0:
        return
    corners, nbr, inc = np.empty((count, 3), np.int64), np.empty((count, 3), np.int64), np.empty(nx * ny, np.int64)
    lattice_mesh_into(index, nx, corners, nbr, inc)
    grid = tm.LatticeGrid(keep=keep, x0=0.0, y0=0.0, h=1.0, dy=np.sqrt(3) / 2)
    out_t, out_s = np.nonzero(nbr < 0)
    outline = np.stack([corners[out_t, out_s], corners[out_t, (out_s + 1) % 3]], axis=1)
    holes = tm.outline_hole_points(grid, corners, out_t, outline, nx)
    j, i = np.divmod(np.arange(nx * ny), nx)
    centroids = np.stack([i + 0.5 * (j & 1), j * np.sqrt(3) / 2], axis=1)[corners].mean(axis=1)
    dist = np.linalg.norm(holes[:, None] - centroids[None], axis=2)
    assert np.isclose(dist.min(axis=1), 0).all()  # each one a lattice triangle's centroid
    holder = dist.argmin(axis=1)
    piece = np.full(count, -1)
    for seed_t in range(count):
        if piece[seed_t] >= 0:
            continue
        piece[seed_t], todo = seed_t, [seed_t]
        while todo:
            t = todo.pop()
            for u in nbr[t]:
                if u >= 0 and piece[u] < 0:
                    piece[u] = seed_t
                    todo.append(u)
    assert set(np.unique(piece)) <= set(piece[holder].tolist())
