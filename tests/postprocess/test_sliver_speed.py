"""Sparse mode on a mesh of slivers: the ridge ascent does not refine points the rule is far out of reach of.

Triangle cannot repair a 1/x input angle: ``quality_mesh`` of the wedge below is all
slivers (~0.002 degrees at x = 3e4), every triangle is uncovered, and every fan or star
the placement searches try misses the largest angle allowed by 5-20 degrees. The
compass search's ridge ascent (``_join_kernels.ridge_ascent``) narrowed its active set
down to 1e-9 radians there, ~35 steps per search and ~5 searches per triangle
(docs/sparse.md, "Slivers").
"""

from __future__ import annotations

import time

import numpy as np

import hammesh
from hammesh.postprocess import _join_kernels as jk
from hammesh.verify.certificate import verify


def _wedge(x: float) -> hammesh.Mesh:
    d = hammesh.Domain(vertices=[[0, 0], [1, 0], [x, 1], [0, 1]], segments=[[0, 1], [1, 2], [2, 3], [3, 0]])
    return hammesh.quality_mesh(d, min_angle=30)


def _search(pts: np.ndarray, lo: float, hi: float, exact: bool) -> tuple:
    poly = np.arange(len(pts), dtype=np.int64)
    c = pts.mean(axis=0)
    return jk.compass_search(pts, poly, len(pts), c[0], c[1], lo, hi, 0.05, 6, 24, exact)


def test_far_short_ridge_still_climbs_to_the_rule() -> None:
    # a 20 x 1 strip: from its middle every fan point sees a long side under ~170
    # degrees (slack ~ -0.86 against 125); near an end it meets the rule
    pts = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 1.0], [0.0, 1.0]])
    plain = _search(pts, 0.01, np.radians(125.0), False)
    exact = _search(pts, 0.01, np.radians(125.0), True)
    assert plain[2] < -0.1
    assert exact[2] >= 0.0
    s, nmin, nmax = jk.fan_eval(pts, np.arange(4, dtype=np.int64), 4, exact[0], exact[1], 0.01, np.radians(125.0))
    assert s == exact[2] and nmin >= 0.01 and nmax <= np.radians(125.0)


def test_near_miss_ridge_never_worse() -> None:
    # a regular pentagon with lo just over its half corners (54 degrees): slack ~ -0.007
    a = np.pi / 2 + 2 * np.pi * np.arange(5) / 5
    pts = np.c_[np.cos(a), np.sin(a)]
    plain = _search(pts, np.radians(54.4), np.radians(125.0), False)
    exact = _search(pts, np.radians(54.4), np.radians(125.0), True)
    assert -0.1 < plain[2] < 0.0
    assert exact[2] >= plain[2]


def test_sliver_mesh_cpu_per_triangle_and_certified() -> None:
    m = _wedge(3e4)
    hammesh.hamiltonian(m)  # (compiles)
    t = time.process_time()
    h = hammesh.hamiltonian(m)
    cpu = time.process_time() - t
    verify(h, m)
    assert m.n_triangles > 3000
    # ~0.15 ms CPU a triangle on 2 loaded cores (0.25 ms before; a normal mesh
    # ~0.5 us): a generous bound that still catches a search that stops converging
    assert cpu < 1e-3 * m.n_triangles, (cpu, m.n_triangles)
