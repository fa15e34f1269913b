"""Shared test helpers: independent (pure numpy / networkx) re-checks of outputs.

These deliberately do not call hammesh's numba kernels, so that a bug there cannot
hide itself in a test.
"""

from __future__ import annotations

import numpy as np

import hammesh


def square(x0: float = 0.0, y0: float = 0.0, s: float = 1.0) -> list[list[float]]:
    return [[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]]


def angles_deg(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri]
    out = np.empty(tri.shape)
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        if p.shape[2] == 3:  # surfaces: angles in 3D
            cr = np.linalg.norm(np.cross(u, v), axis=1)
        else:
            cr = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        out[:, k] = np.degrees(np.arctan2(cr, (u * v).sum(axis=1)))
    return out


def signed_areas(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri]
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def assert_cycles(h: hammesh.HamiltonianMesh) -> None:
    """Each run closes: consecutive triangles (and last->first) share exactly 2 vertices."""
    tri = h.triangles
    assert int(np.sum(h.components)) == len(tri)
    start = 0
    for length in np.asarray(h.components).tolist():
        run = tri[start : start + length]
        nxt = np.roll(run, -1, axis=0)
        shared = (run[:, :, None] == nxt[:, None, :]).sum(axis=(1, 2))
        assert (shared == 2).all(), f"run starting at {start} breaks at {np.argmin(shared == 2)}"
        assert len({tuple(sorted(t)) for t in run.tolist()}) == length
        start += length


def dual_pieces(tri: np.ndarray, cut_edges: np.ndarray | None = None) -> int:
    """Number of connected pieces of the dual graph, optionally not crossing ``cut_edges``."""
    import networkx as nx

    cut = set()
    if cut_edges is not None:
        cut = {tuple(sorted(e)) for e in np.asarray(cut_edges).tolist()}
    owner: dict[tuple[int, int], list[int]] = {}
    for t, (a, b, c) in enumerate(np.asarray(tri).tolist()):
        for e in ((a, b), (b, c), (c, a)):
            owner.setdefault(tuple(sorted(e)), []).append(t)
    g = nx.Graph()
    g.add_nodes_from(range(len(tri)))
    for e, ts in owner.items():
        if len(ts) == 2 and e not in cut:
            g.add_edge(*ts)
    return nx.number_connected_components(g)


def assert_tiling_and_bound(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> None:
    """Independent re-check of the certificate's promises shared by every mode."""
    assert_cycles(h)
    assert (signed_areas(h.points, h.triangles) > 0).all()
    np.testing.assert_array_equal(h.points[: m.n_points], m.points)
    in_area = np.abs(signed_areas(m.points, m.triangles)).sum()
    assert np.isclose(signed_areas(h.points, h.triangles).sum(), in_area, rtol=1e-9)
    a_in = angles_deg(m.points, m.triangles).min()
    a_out = angles_deg(h.points, h.triangles).min()
    assert a_out >= 0.5 * a_in * (1 - 1e-9), (a_in, a_out)


def assert_certificate(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> None:
    """Independent re-check of what the certificate promises, with Thm 2.4's counts."""
    assert_tiling_and_bound(m, h)
    # counts of Thm 2.4 + midpoints
    q = h.report["midpoints"]
    assert h.n_triangles == 3 * m.n_triangles + 2 * q
    assert h.n_points == m.n_points + m.n_triangles + q
    assert len(h.components) == dual_pieces(m.triangles)


def plate(n_loops: int, pieces: int, max_area: float = 0.004) -> hammesh.Mesh:
    """Unit squares side by side (``pieces`` pieces), the first with ``n_loops`` closed
    internal constrained squares (interfaces: one midpoint each), meshed."""
    v: list[list[float]] = []
    segs: list[list[int]] = []
    for p in range(pieces):
        b = len(v)
        v += square(2.0 * p, 0, 1)
        segs += [[b, b + 1], [b + 1, b + 2], [b + 2, b + 3], [b + 3, b]]
    for i in range(n_loops):
        b = len(v)
        v += square(0.1 + 0.28 * i, 0.4, 0.2)
        segs += [[b, b + 1], [b + 1, b + 2], [b + 2, b + 3], [b + 3, b]]
    holes = [[2.0 * p - 0.5, 0.5] for p in range(1, pieces)]
    dom = hammesh.Domain(vertices=v, segments=segs, holes=holes or None)
    return hammesh.quality_mesh(dom, min_angle=30, max_area=max_area)
