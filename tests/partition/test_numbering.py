"""``hammesh.numbering``: vertex renumberings keep the mesh, change bandwidth/profile."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.numbering import NUMBERINGS, bandwidth_profile, hilbert_keys, renumber
from tests.helpers import square, star_pslg


def _brute(tri: np.ndarray, n: int) -> tuple[int, int]:
    nb: list[set[int]] = [set() for _ in range(n)]
    for a, b, c in tri.tolist():
        for x, y in ((a, b), (b, c), (c, a)):
            nb[x].add(y)
            nb[y].add(x)
    bw = max((abs(i - j) for i in range(n) for j in nb[i]), default=0)
    return bw, sum(i - min([i, *nb[i]]) for i in range(n))


def _geometry(points: np.ndarray, tri: np.ndarray) -> list:
    return [tuple(map(tuple, points[t])) for t in tri.tolist()]


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), method=st.sampled_from(NUMBERINGS), mode=st.sampled_from(["sparse", "incircle"]))
def test_renumbering_keeps_every_triangle_and_segment(dom, method: str, mode: str) -> None:
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.05), mode=mode)
    r, info = renumber(h, method)
    order = info["order"]
    assert sorted(order.tolist()) == list(range(h.n_points))
    # same triangles row by row (the cycle), same segments, same coordinates
    assert _geometry(r.points, r.triangles) == _geometry(h.points, h.triangles)
    assert _geometry(r.points, r.segments) == _geometry(h.points, h.segments)
    np.testing.assert_array_equal(r.segment_markers, h.segment_markers)
    assert (info["bandwidth"], info["profile"]) == _brute(r.triangles, r.n_points)
    assert (info["bandwidth_before"], info["profile_before"]) == _brute(h.triangles, h.n_points)
    assert r.report["numbering"]["method"] == method


def test_cycle_numbering_follows_first_visits(hexagon) -> None:
    r, info = renumber(hexagon, "cycle")
    flat = r.triangles.reshape(-1)
    _, first = np.unique(flat, return_index=True)
    assert (np.diff(flat[np.sort(first)]) == 1).all() and flat[0] == 0


def test_rcm_and_cycle_shrink_the_incircle_bandwidth() -> None:
    """Thm 2.4 numbers incenters after all input points (bandwidth ~ n): RCM and the
    cycle order bring it down to the width of a stretch."""
    dom = hammesh.Domain.from_polygon(square(0, 0, 1))
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=0.001), mode="incircle")
    bw0, pf0 = bandwidth_profile(h.triangles, h.n_points)
    for method in ("rcm", "cycle", "hilbert"):
        _, info = renumber(h, method)
        assert info["profile"] < pf0 / 2, (method, info)
    assert renumber(h, "rcm")[1]["bandwidth"] < bw0 / 5


def test_hilbert_keys_follow_the_curve() -> None:
    """On a 4x4 grid the Hilbert order visits neighbours only (unit steps)."""
    g = np.array([[x, y] for x in range(4) for y in range(4)], float)
    path = g[np.argsort(hilbert_keys(g, bits=2))]
    assert (np.abs(np.diff(path, axis=0)).sum(axis=1) == 1).all()
    assert len(set(hilbert_keys(g, bits=2).tolist())) == 16


def test_unknown_method_is_refused(hexagon) -> None:
    with pytest.raises(hammesh.InvalidOptionError, match="renumber="):
        renumber(hexagon, "metis")


def test_plain_mesh_renumbered(hexagon) -> None:
    m = hexagon.as_mesh()
    r, info = renumber(m, "rcm")
    assert isinstance(r, hammesh.Mesh) and _geometry(r.points, r.triangles) == _geometry(m.points, m.triangles)
