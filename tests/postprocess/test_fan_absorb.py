"""Fans that take in a covered neighbour (``_join_kernels.fan_groups(..., absorb=True)``).

A fan over a chain of uncovered triangles is a cycle of its own; with one covered
triangle ``y`` taken in across ``y``'s non-cover edge it is a path of ``y``'s cycle
instead (``y``'s two cover edges are consecutive polygon edges around its apex), so
the chain joins that cycle without a join. Checked here on the cover ``sparse._fans``
hands on: every covered triangle on exactly two cover edges, matched across twins,
one id per cycle and every id used, and the certificate on the whole output.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.postprocess import sparse as S
from hammesh.postprocess.cycle_cover import cycle_cover
from tests.helpers import bundled_domain
from tests.postprocess.test_sparse import assert_sparse_certificate


def _walk_cycles(tw: np.ndarray, is_cov: np.ndarray, cycle: np.ndarray) -> list[list[int]]:
    """The cover's cycles found by walking its edges (numpy/Python only, no kernel)."""
    m = len(cycle)
    seen = np.zeros(m, bool)
    out = []
    for s in range(m):
        if cycle[s] < 0 or seen[s]:
            continue
        run, t, prev = [], s, -1
        while not seen[t]:
            seen[t] = True
            run.append(t)
            nxt = [tw[3 * t + k] // 3 for k in range(3) if is_cov[3 * t + k] and tw[3 * t + k] // 3 != prev]
            prev, t = t, nxt[0]
        assert t == s  # closed
        out.append(run)
    return out


def _fans_on(mesh: hammesh.Mesh):
    clean, he, is_con = prepare_mesh(mesh)
    pts, tri, tw = clean.points, clean.triangles, he.twin
    amin_t, amax_t, _, _ = S.triangle_facts(pts, tri)
    amin = float(amin_t.min())
    hi = float(amax_t.max()) + math.radians(S.MAX_ANGLE_SLACK_DEG)
    floor = 0.5 * amin * (1.0 + S.SWAP_MARGIN)
    cover = cycle_cover(tri, tw)
    got = S._fans(pts, tri, tw, is_con, cover, amin_t, S.KEEP, hi, floor, float(amax_t.max()),
                  np.flatnonzero(cover.cycle < 0))
    return cover, got, amin


def _assert_cover_consistent(tw, is_cov, cycle, n_cycles) -> list[list[int]]:
    m = len(cycle)
    cov = is_cov.reshape(m, 3)
    on = cycle >= 0
    assert (cov[on].sum(axis=1) == 2).all()
    assert not cov[~on].any()
    h = np.flatnonzero(is_cov)
    assert (tw[h] >= 0).all() and is_cov[tw[h]].all()  # a cover edge is one on both sides
    runs = _walk_cycles(tw, is_cov, cycle)
    ids = [set(cycle[r].tolist()) for r in runs]
    assert all(len(i) == 1 for i in ids)  # one id per cycle
    assert sorted(next(iter(i)) for i in ids) == list(range(n_cycles))  # each id one cycle, none unused
    return runs


def _flag(size: float, width: float, arm: float, y0: float, arm2: float) -> hammesh.Domain:
    """A square (``size``) with a thin arm (``width`` x ``arm``) on its right side at
    height ``y0`` (a fraction of the side), and a second arm ``arm2`` long (0: none)
    on its left side: the square's cover cycles beside the arms' uncovered chains."""
    lo, hi = y0 * size - 0.5 * width, y0 * size + 0.5 * width
    right = [[size, lo], [size + arm, lo], [size + arm, hi], [size, hi]]
    left = [[0.0, hi], [-arm2, hi], [-arm2, lo], [0.0, lo]] if arm2 > 0 else []
    return hammesh.Domain.from_polygon(np.array([[0.0, 0.0], [size, 0.0], *right, [size, size], [0.0, size], *left]))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    size=st.floats(0.3, 1.0),
    width=st.floats(0.03, 0.12),
    arm=st.floats(0.2, 1.5),
    y0=st.floats(0.2, 0.8),
    arm2=st.one_of(st.just(0.0), st.floats(0.2, 1.5)),
)
def test_absorbing_fans_keep_the_cover_a_cover(size, width, arm, y0, arm2) -> None:
    # the arms inside their side, clear of the square's corners: an arm flush with a
    # corner (size 0.3, width 0.12, y0 0.2) leaves a sliver Triangle refines without
    # end at 30 degrees (out of memory after ~20 GB)
    assume(0.05 * size < y0 * size - 0.5 * width and y0 * size + 0.5 * width < 0.95 * size)
    mesh = hammesh.quality_mesh(_flag(size, width, arm, y0, arm2), min_angle=30)
    cover, got, amin = _fans_on(mesh)
    pts, tri, tw, con, cov2, amin_p, orig_of, is_fan, n_fan = got
    if n_fan == 0:
        return
    runs = _assert_cover_consistent(tw, cov2.is_cov, cov2.cycle, cov2.n_cycles)
    fan_rows = np.flatnonzero(is_fan)
    # a fan either is a cycle of its own or lies on one cycle with kept rows
    n_own = sum(1 for r in runs if is_fan[r].all())
    assert cov2.n_cycles == cover.n_cycles + n_own
    assert n_own <= n_fan
    # every fan angle keeps the input's minimum (a later bridge may halve it: Thm 2.4's floor)
    p = pts[tri[fan_rows]]
    for k in range(3):
        u, v = p[:, (k + 1) % 3] - p[:, k], p[:, (k + 2) % 3] - p[:, k]
        ang = np.arctan2(np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]), (u * v).sum(axis=1))
        assert ang.min() >= amin * (1 - 1e-6)
    h = hammesh.hamiltonian(mesh)
    assert_sparse_certificate(mesh, h)


def test_a_takes_covered_neighbours_into_fans_and_saves_points(monkeypatch) -> None:
    # Triangle's A at 87 triangles: a fan of the foot takes in the stroke's covered
    # triangle next to it instead of becoming a cycle joined by a Thm 2.4 bridge
    mesh = hammesh.quality_mesh(bundled_domain("A"), min_angle=30)
    cover, got, _ = _fans_on(mesh)
    pts, tri, tw, con, cov2, amin_p, orig_of, is_fan, n_fan = got
    runs = _assert_cover_consistent(tw, cov2.is_cov, cov2.cycle, cov2.n_cycles)
    mixed = [r for r in runs if is_fan[r].any() and not is_fan[r].all()]
    assert mixed  # at least one fan now lies on a cover cycle
    h = hammesh.hamiltonian(mesh)
    assert_sparse_certificate(mesh, h)
    monkeypatch.setattr(S, "FAN_ABSORB", False)
    h0 = hammesh.hamiltonian(mesh)
    assert_sparse_certificate(mesh, h0)
    assert h.report["steiner_points"] < h0.report["steiner_points"]


@pytest.mark.parametrize("absorb", [False, True])
def test_without_absorbing_every_fan_is_its_own_cycle(monkeypatch, absorb) -> None:
    monkeypatch.setattr(S, "FAN_ABSORB", absorb)
    mesh = hammesh.quality_mesh(bundled_domain("A"), min_angle=30)
    cover, got, _ = _fans_on(mesh)
    pts, tri, tw, con, cov2, amin_p, orig_of, is_fan, n_fan = got
    runs = _assert_cover_consistent(tw, cov2.is_cov, cov2.cycle, cov2.n_cycles)
    n_own = sum(1 for r in runs if is_fan[r].all())
    assert (n_own == n_fan) == (not absorb)
