"""The certificate of a Hamiltonian surface mesh (3D points, ``hammesh.surface``).

What is checked (each failure raises :class:`~hammesh.errors.VerificationError`
naming the triangle, edge or vertex at fault):

1. ``components`` are positive run lengths summing to the number of triangles; in
   each run consecutive triangles (and the last and first) share an edge: closed cycles.
2. No degenerate triangle (positive 3D area) and no triangle twice.
3. Edge-manifold and consistently oriented: no directed edge used twice.
4. Runs are exactly the connected pieces: no edge joins two runs.
5. With the input surface: its points are kept unchanged at the same indices, every
   vertex it used is still used, the boundary edges (directed) are the same, and
   (``exact=True``) every output triangle lies in the plane of its ``parent`` input
   triangle and the output areas per parent sum to the parent's area -- so the output
   is the input surface itself, re-triangulated inside each input triangle. The total
   area is compared in any case.
6. Minimum 3D angle at least ``angle_ratio`` times the input's (relative tolerance
   ``ANGLE_RTOL``).

A surface has no plane to orient in, so "counter-clockwise" is replaced by item 3
(orientation consistent with the neighbours) and item 5's per-parent checks (with all
areas positive and the same total per parent, triangles cannot fold over inside it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hammesh.verify import _kernels
from hammesh.errors import VerificationError

__all__ = ["verify_surface", "surface_angles", "ANGLE_RTOL", "AREA_RTOL", "PLANE_RTOL"]

ANGLE_RTOL = 1e-9
AREA_RTOL = 1e-9
#: distance of an output vertex from its parent's plane, relative to the parent's longest side
PLANE_RTOL = 1e-9


def _fail(msg: str) -> None:
    raise VerificationError(msg)


def surface_angles(points: np.ndarray, triangles: np.ndarray) -> tuple[float, int, float, np.ndarray]:
    """``(min angle, argmin row, max angle, areas)``; angles in radians, 3D areas."""
    p = points[triangles]
    e0 = p[:, 1] - p[:, 0]
    e1 = p[:, 2] - p[:, 1]
    e2 = p[:, 0] - p[:, 2]
    area = 0.5 * np.linalg.norm(np.cross(e0, -e2), axis=1)
    angs = []
    for u, v in ((e0, -e2), (e1, -e0), (e2, -e1)):  # at vertex 0, 1, 2
        cr = np.linalg.norm(np.cross(u, v), axis=1)
        angs.append(np.arctan2(cr, (u * v).sum(axis=1)))
    a = np.stack(angs, axis=1)
    amin = a.min(axis=1)
    i = int(np.argmin(amin))
    return float(amin[i]), i, float(a.max()), area


def verify_surface(
    points: np.ndarray,
    triangles: np.ndarray,
    components: np.ndarray,
    *,
    reference_points: np.ndarray | None = None,
    reference_triangles: np.ndarray | None = None,
    parent: np.ndarray | None = None,
    exact: bool = True,
    angle_ratio: float = 0.5,
) -> dict[str, Any]:
    """Check a cycle-ordered surface mesh (see the module docstring).

    Parameters
    ----------
    points : (n, 3) float64
    triangles : (m, 3) int64, in cycle order
    components : (c,) int64 run lengths
    reference_points, reference_triangles : (n_in, 3), (m_in, 3), optional
        The input surface; enables items 5 and 6.
    parent : (m,) int64, optional
        Input triangle of each output triangle (needed for ``exact``).
    exact : bool
        Require every output triangle inside its parent's plane and the per-parent
        areas to match (the construction keeps the surface exactly).
    angle_ratio : float

    Returns
    -------
    dict
        ``min_angle_output_deg``, ``max_angle_output_deg``, ``area_output`` and, with
        the input, ``min_angle_input_deg``, ``area_input``, ``area_change_rel``.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    runs = np.asarray(components, dtype=np.int64).reshape(-1)
    n, m = len(pts), len(tri)
    if pts.ndim != 2 or pts.shape[1] != 3 or tri.ndim != 2 or tri.shape[1] != 3 or m == 0:
        _fail(f"bad shapes: points {pts.shape}, triangles {tri.shape}")
    if not np.isfinite(pts).all():
        _fail(f"point {int(np.argmax(~np.isfinite(pts).all(axis=1)))} is not finite")
    if tri.min() < 0 or tri.max() >= n:
        _fail(f"triangle {int(np.argmax(((tri < 0) | (tri >= n)).any(axis=1)))} references a vertex outside 0..{n - 1}")
    if (runs <= 0).any() or runs.sum() != m:
        _fail(f"components {runs.tolist()[:10]} are not positive run lengths summing to {m}")
    # 1. closed runs
    starts = np.cumsum(runs) - runs
    nxt = np.arange(1, m + 1)
    nxt[np.cumsum(runs) - 1] = starts
    shared = (tri[:, :, None] == tri[nxt][:, None, :]).sum(axis=(1, 2))
    bad = np.flatnonzero(shared != 2)
    if len(bad) or (runs < 3).any():
        i = int(bad[0]) if len(bad) else int(starts[np.argmax(runs < 3)])
        _fail(f"cycle {int(np.searchsorted(np.cumsum(runs), i, side='right'))} breaks at triangle {i}")
    # 2. areas, duplicates
    amin, imin, amax, area = surface_angles(pts, tri)
    if not area.min() > 0:
        i = int(np.argmin(area))
        _fail(f"triangle {i} {tri[i].tolist()} is degenerate (area {area[i]:.3g})")
    srt = np.sort(tri, axis=1)
    o = np.lexsort(srt.T[::-1])
    same = (srt[o[1:]] == srt[o[:-1]]).all(axis=1)
    if same.any():
        i = int(np.argmax(same))
        _fail(f"triangle {tri[o[i]].tolist()} appears twice (rows {int(o[i])}, {int(o[i + 1])})")
    # 3. manifold and oriented
    twin, dup = _kernels.half_edge_twins(tri, n)
    if dup >= 0:
        t, k = divmod(int(dup), 3)
        _fail(
            f"edge ({tri[t, k]}, {tri[t, (k + 1) % 3]}) of triangle {t} is used twice in the same "
            "direction (non-manifold edge or inconsistent orientation)"
        )
    # 4. one run per piece
    h = int(_kernels.first_cross_run_edge(twin, runs))
    if h >= 0:
        _fail(f"triangles {h // 3} and {int(twin[h]) // 3} share an edge but lie in different cycles")
    stats: dict[str, Any] = {
        "min_angle_output_deg": math.degrees(amin),
        "max_angle_output_deg": math.degrees(amax),
        "area_output": float(area.sum()),
    }
    if reference_points is None or reference_triangles is None:
        return stats
    # 5. the input surface
    rp = np.asarray(reference_points, dtype=np.float64)
    rt = np.ascontiguousarray(reference_triangles, dtype=np.int64)
    n_in = len(rp)
    if n < n_in or not np.array_equal(pts[:n_in], rp):
        _fail("the input points are not kept unchanged as the first output points")
    used_in = np.bincount(rt.reshape(-1), minlength=n_in) > 0
    used_out = np.bincount(tri.reshape(-1), minlength=n)[:n_in] > 0
    if (used_in & ~used_out).any():
        _fail(f"input vertex {int(np.argmax(used_in & ~used_out))} is no longer a vertex of the mesh")
    r_twin, r_dup = _kernels.half_edge_twins(rt, n_in)
    if r_dup >= 0:
        _fail("the input surface is not an oriented manifold; it cannot serve as a reference")
    b_out = _kernels.boundary_half_edges(tri, twin)
    b_in = _kernels.boundary_half_edges(rt, r_twin)
    k_out = np.sort(b_out[:, 0] * n + b_out[:, 1])
    k_in = np.sort(b_in[:, 0] * n + b_in[:, 1])
    if not np.array_equal(k_out, k_in):
        k = int(np.setxor1d(k_out, k_in)[0])
        _fail(f"boundary changed: edge ({k // n}, {k % n}) is on the boundary of only one of input and output")
    r_min, _, _, r_area = surface_angles(rp, rt)
    total_in, total_out = float(r_area.sum()), float(area.sum())
    if exact:
        if parent is None or len(parent) != m:
            _fail("exact surface check needs the parent of every output triangle")
        par = np.asarray(parent, dtype=np.int64)
        if par.min() < 0 or par.max() >= len(rt):
            _fail("parent indices outside the input triangles")
        q = rp[rt]
        normal = np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        size = np.linalg.norm(q - np.roll(q, 1, axis=1), axis=2).max(axis=1)
        dist = np.abs(((pts[tri] - q[par, 0][:, None, :]) * normal[par][:, None, :]).sum(axis=2)).max(axis=1)
        off = np.flatnonzero(dist > PLANE_RTOL * size[par])
        if len(off):
            i = int(off[0])
            _fail(f"triangle {i} leaves the plane of its input triangle {int(par[i])} by {dist[i]:.3g}")
        per = np.bincount(par, weights=area, minlength=len(rt))
        diff = np.abs(per - r_area) > AREA_RTOL * np.maximum(r_area, 1e-300) + 1e-15 * total_in
        if diff.any():
            t = int(np.argmax(diff))
            _fail(f"the output triangles in input triangle {t} cover area {per[t]!r}, not {r_area[t]!r}")
        if not math.isclose(total_out, total_in, rel_tol=AREA_RTOL):
            _fail(f"total area changed from {total_in!r} to {total_out!r}")
    # 6. angles
    if amin < angle_ratio * r_min * (1.0 - ANGLE_RTOL):
        _fail(
            f"triangle {imin} {tri[imin].tolist()} has angle {math.degrees(amin):.6f} deg, below "
            f"{angle_ratio} x the input minimum {math.degrees(r_min):.6f} deg"
        )
    stats.update(
        {
            "min_angle_input_deg": math.degrees(r_min),
            "area_input": total_in,
            "area_change_rel": (total_out - total_in) / total_in,
        }
    )
    return stats
