"""The certificate of a Hamiltonian surface mesh (3D points, ``hammesh.surface``).

It derives every fact it checks itself, from the two meshes, with code the construction
never runs (issue 11): its own edge matching (``numpy.unique`` over directed and
undirected edge keys), its own angles and areas; it shares nothing with the
construction but numpy.  Vocabulary: an edge is *proper* when exactly two triangles use
it, in opposite directions; every other edge (boundary, non-manifold, two triangles of
disagreeing winding) is a *cut*, and the pieces of a surface are joined across proper
edges only (see :mod:`hammesh.strips.defects` for why).

What is checked (each failure raises :class:`~hammesh.errors.VerificationError`
naming the triangle, edge or vertex at fault):

1. ``components`` are positive run lengths summing to the number of triangles; in each
   run consecutive triangles (and the last and first) share a proper edge: closed
   cycles (a run of two, a double-sided face, shares two edges).
2. No degenerate triangle (positive 3D area) and no oriented triangle twice.
3. Runs are exactly the pieces: no proper edge joins two runs.
4. With the input surface: its points are kept unchanged at the same indices.  Every
   input row is *covered* (some output triangle names it as ``parent``) or may be
   dropped: it repeats a vertex, has zero area (twice its area at most
   :data:`DROP_RTOL` times its longest side squared, measured here) or repeats an
   earlier row with the same winding.  Every vertex of a covered row is still used;
   the cuts are the same: the directed half-edges on cuts, as a multiset, are those of
   the covered input rows (so the boundary, every non-manifold edge, every flipped
   neighbour and the seam of a non-orientable piece are kept, and no new cut appears).
   With ``exact=True`` every output triangle lies in the plane of its parent and the
   output areas per parent sum to the parent's area -- so the output is the input
   surface itself, re-triangulated inside each input triangle.  The total area is
   compared in any case.
5. Minimum 3D angle at least ``angle_ratio`` times the covered input's (relative
   tolerance ``ANGLE_RTOL``).

A surface has no plane to orient in, so "counter-clockwise" is replaced by item 4's
cuts (a triangle flipped against its neighbours makes new cuts) and per-parent checks
(with all areas positive and the same total per parent, triangles cannot fold over).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hammesh.errors import VerificationError

__all__ = ["verify_surface", "infer_surface_runs", "ANGLE_RTOL", "AREA_RTOL", "PLANE_RTOL", "DROP_RTOL"]

#: beyond this magnitude this module's own cross products and squared lengths overflow
#: (its own bound: the construction refuses far smaller inputs, 1e30)
_MAX_ABS = 1e150

ANGLE_RTOL = 1e-9
AREA_RTOL = 1e-9
#: distance of an output vertex from its parent's plane, relative to the parent's longest side
PLANE_RTOL = 1e-9
#: an input row may be left out when twice its area is at most this times its longest
#: side squared (the construction drops below 1e-13: a tenfold margin for rounding)
DROP_RTOL = 1e-12


def _fail(msg: str) -> None:
    raise VerificationError(msg)


def _angles_areas(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angles ``(m, 3)`` (law of cosines on exact side vectors) and areas ``(m,)`` of ``p (m, 3, 3)``."""
    a = p[:, 1] - p[:, 0]
    b = p[:, 2] - p[:, 1]
    c = p[:, 0] - p[:, 2]
    ang = np.empty(p.shape[:2])
    for k, (x, y) in enumerate(((a, -c), (b, -a), (c, -b))):
        cx = x[:, 1] * y[:, 2] - x[:, 2] * y[:, 1]
        cy = x[:, 2] * y[:, 0] - x[:, 0] * y[:, 2]
        cz = x[:, 0] * y[:, 1] - x[:, 1] * y[:, 0]
        ang[:, k] = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), np.einsum("ij,ij->i", x, y))
    cx = a[:, 1] * c[:, 2] - a[:, 2] * c[:, 1]
    cy = a[:, 2] * c[:, 0] - a[:, 0] * c[:, 2]
    cz = a[:, 0] * c[:, 1] - a[:, 1] * c[:, 0]
    return ang, 0.5 * np.sqrt(cx * cx + cy * cy + cz * cz)


def _relative_twice_area(p: np.ndarray) -> np.ndarray:
    """Twice the area over the longest side squared, the cross product taken at each vertex (the least)."""
    best = np.full(len(p), np.inf)
    side = np.zeros(len(p))
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        w = np.cross(u, v)
        best = np.minimum(best, np.sqrt((w * w).sum(axis=1)))
        side = np.maximum(side, (u * u).sum(axis=1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(side > 0, best / np.where(side > 0, side, 1.0), 0.0)


def _half_edges(tri: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tails, heads and a proper-edge flag for every half-edge ``3 t + k``."""
    tail = tri.reshape(-1)
    head = tri[:, [1, 2, 0]].reshape(-1)
    undirected = np.minimum(tail, head) * n + np.maximum(tail, head)
    _, inv, cnt = np.unique(undirected, return_inverse=True, return_counts=True)
    _, dinv, dcnt = np.unique(tail * n + head, return_inverse=True, return_counts=True)
    # two users, and the directed key used once: one each way
    proper = (cnt[inv] == 2) & (dcnt[dinv] == 1)
    return tail, head, proper


def _partner(tail: np.ndarray, head: np.ndarray, proper: np.ndarray, n: int) -> np.ndarray:
    """For each proper half-edge, the one running the other way (-1 elsewhere)."""
    h = np.flatnonzero(proper)
    key = tail[h] * n + head[h]
    rev = head[h] * n + tail[h]
    o = np.argsort(key)
    pos = np.searchsorted(key[o], rev)
    out = np.full(len(tail), -1, np.int64)
    out[h] = h[o[pos]]
    return out


def _cut_keys(tail: np.ndarray, head: np.ndarray, proper: np.ndarray, n: int) -> np.ndarray:
    return np.sort(tail[~proper] * n + head[~proper])


def infer_surface_runs(triangles: np.ndarray, n_points: int) -> np.ndarray:
    """Run lengths of a surface stored piece after piece, pieces joined across proper edges only.

    What ``hammesh check`` needs to re-verify a file written by ``hammesh surface``: unlike
    the planar :func:`hammesh.verify.infer_runs`, cuts (non-manifold edges, flipped
    neighbours) are allowed and separate pieces.

    Raises
    ------
    VerificationError
        No triangles, or a piece split over several runs (not consecutive in the file).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    tri = np.asarray(triangles).astype(np.int64).reshape(-1, 3)
    m = len(tri)
    if m == 0:
        _fail("the mesh has no triangles")
    tail, head, proper = _half_edges(tri, int(n_points))
    partner = _partner(tail, head, proper, int(n_points))
    h = np.flatnonzero(partner >= 0)
    graph = coo_matrix((np.ones(len(h), dtype=np.int8), (h // 3, partner[h] // 3)), shape=(m, m))
    n_pieces, label = connected_components(graph, directed=False)
    starts = np.r_[0, np.flatnonzero(np.diff(label) != 0) + 1]
    if len(starts) != n_pieces:
        seen = np.zeros(n_pieces, dtype=bool)
        for s in starts:
            if seen[label[s]]:
                _fail(f"connected piece {int(label[s])} is split over several runs (triangle {int(s)} starts another)")
            seen[label[s]] = True
    return np.diff(np.r_[starts, m]).astype(np.int64)


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
    reference_points, reference_triangles : (n_in, 3) or (n_in, 2), (m_in, 3), optional
        The input surface, as the user gave it; enables items 4 and 5.
    parent : (m,) int64, optional
        Input row of each output triangle (needed for ``exact``; without it every
        input row that may not be dropped counts as covered).
    exact : bool
        Require every output triangle inside its parent's plane and the per-parent
        areas to match (the construction keeps the surface exactly).
    angle_ratio : float

    Returns
    -------
    dict
        ``min_angle_output_deg``, ``max_angle_output_deg``, ``area_output``,
        ``cut_half_edges`` and, with the input, ``min_angle_input_deg``,
        ``area_input``, ``area_change_rel``, ``input_rows_dropped``.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles)
    runs = np.asarray(components).reshape(-1)
    if pts.ndim != 2 or pts.shape[1] != 3 or tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
        _fail(f"bad shapes: points {pts.shape}, triangles {tri.shape}")
    tri = tri.astype(np.int64)
    runs = runs.astype(np.int64)
    n, m = len(pts), len(tri)
    if not np.isfinite(pts).all():
        _fail(f"point {int(np.argmax(~np.isfinite(pts).all(axis=1)))} is not finite")
    if n and np.abs(pts).max() > _MAX_ABS:
        _fail(f"point {int(np.argmax(np.abs(pts).max(axis=1)))} is beyond |x| <= {_MAX_ABS:g}: "
              "the check's own products would overflow")
    if tri.min() < 0 or tri.max() >= n:
        _fail(f"triangle {int(np.argmax(((tri < 0) | (tri >= n)).any(axis=1)))} references a vertex outside 0..{n - 1}")
    if (runs <= 0).any() or runs.sum() != m:
        _fail(f"components {runs.tolist()[:10]} are not positive run lengths summing to {m}")
    # 2. areas, repeated rows
    ang, area = _angles_areas(pts[tri])
    if not area.min() > 0:
        i = int(np.argmin(area))
        _fail(f"triangle {i} {tri[i].tolist()} is degenerate (area {area[i]:.3g})")
    r = np.argmin(tri, axis=1)
    canon = tri[np.arange(m)[:, None], (r[:, None] + np.arange(3)) % 3]  # rotated to its least vertex
    _, first, cnt = np.unique(canon, axis=0, return_index=True, return_counts=True)
    if (cnt > 1).any():
        i = int(first[np.argmax(cnt > 1)])
        _fail(f"triangle {tri[i].tolist()} appears twice with the same winding (row {i})")
    # 1. closed runs across proper edges
    tail, head, proper = _half_edges(tri, n)
    partner = _partner(tail, head, proper, n)
    ends = np.cumsum(runs)
    starts = ends - runs
    if (runs < 2).any():
        _fail(f"cycle {int(np.argmax(runs < 2))} has 1 triangle: not a cycle")
    nxt = np.arange(1, m + 1)
    nxt[ends - 1] = starts
    tri_of = np.where(partner >= 0, partner // 3, -1).reshape(-1, 3)
    links = (tri_of == nxt[:, None]).sum(axis=1)
    # a run of two (a double-sided triangle: a closed piece of two) needs two edges between them
    joined = links >= np.where(np.repeat(runs, runs) == 2, 2, 1)
    if not joined.all():
        i = int(np.argmax(~joined))
        _fail(
            f"cycle {int(np.searchsorted(ends, i, side='right'))} breaks at triangle {i}: it shares no proper edge "
            f"with triangle {int(nxt[i])}"
        )
    # 3. one run per piece
    run_of = np.repeat(np.arange(len(runs)), runs)
    h = np.flatnonzero(partner >= 0)
    cross = h[run_of[h // 3] != run_of[partner[h] // 3]]
    if len(cross):
        a = int(cross[0])
        _fail(f"triangles {a // 3} and {int(partner[a]) // 3} share a proper edge but lie in different cycles")
    stats: dict[str, Any] = {
        "min_angle_output_deg": math.degrees(float(ang.min())),
        "max_angle_output_deg": math.degrees(float(ang.max())),
        "area_output": float(area.sum()),
        "cut_half_edges": int(np.count_nonzero(~proper)),
    }
    if reference_points is None or reference_triangles is None:
        return stats
    # 4. the input surface
    rp = np.asarray(reference_points, dtype=np.float64)
    if rp.ndim == 2 and rp.shape[1] == 2:
        rp = np.c_[rp, np.zeros(len(rp))]
    rt = np.asarray(reference_triangles).astype(np.int64).reshape(-1, 3)
    n_in, m_in = len(rp), len(rt)
    if rp.ndim != 2 or rp.shape[1] != 3 or n < n_in or not np.array_equal(pts[:n_in], rp):
        _fail("the input points are not kept unchanged as the first output points")
    if m_in == 0 or rt.min() < 0 or rt.max() >= n_in:
        _fail("the reference triangles are empty or reference a vertex outside the input points")
    rep = (rt[:, 0] == rt[:, 1]) | (rt[:, 1] == rt[:, 2]) | (rt[:, 2] == rt[:, 0])
    flat = _relative_twice_area(rp[rt]) <= DROP_RTOL
    rr = np.argmin(rt, axis=1)
    rcanon = rt[np.arange(m_in)[:, None], (rr[:, None] + np.arange(3)) % 3]
    _, rfirst = np.unique(rcanon, axis=0, return_index=True)
    again = np.ones(m_in, dtype=bool)
    again[rfirst] = False  # a later copy with the same winding
    droppable = rep | flat | again
    if parent is not None:
        par = np.asarray(parent).astype(np.int64).reshape(-1)
        if len(par) != m or par.min() < 0 or par.max() >= m_in:
            _fail(f"parent must give an input row (0..{m_in - 1}) for each of the {m} output triangles")
        covered = np.zeros(m_in, dtype=bool)
        covered[par] = True
        bad = np.flatnonzero(~covered & ~droppable)
        if len(bad):
            t = int(bad[0])
            _fail(f"input triangle {t} {rt[t].tolist()} is left out, but it has an area and is no repeat")
        bad = np.flatnonzero(covered & (rep | again))
        if len(bad):
            t = int(bad[0])
            _fail(f"input triangle {t} {rt[t].tolist()} repeats a vertex or an earlier row, yet has output triangles")
    else:
        par = None
        covered = ~droppable
    cov_t = rt[covered]
    used_in = np.bincount(cov_t.reshape(-1), minlength=n_in) > 0
    used_out = np.bincount(tri.reshape(-1), minlength=n)[:n_in] > 0
    if (used_in & ~used_out).any():
        _fail(f"input vertex {int(np.argmax(used_in & ~used_out))} is no longer a vertex of the mesh")
    r_tail, r_head, r_proper = _half_edges(cov_t, n_in)
    k_out = _cut_keys(tail, head, proper, n)
    k_in = _cut_keys(r_tail, r_head, r_proper, n)  # keys in the output's numbering
    if not np.array_equal(k_out, k_in):
        diff = np.setxor1d(k_out, k_in)
        if len(diff) == 0:  # same keys, different multiplicities
            u_o, c_o = np.unique(k_out, return_counts=True)
            u_i, c_i = np.unique(k_in, return_counts=True)
            both = np.intersect1d(u_o, u_i)
            diff = both[c_o[np.searchsorted(u_o, both)] != c_i[np.searchsorted(u_i, both)]]
        k = int(diff[0])
        side = "input" if np.isin(k, k_in) and not np.isin(k, k_out) else "output"
        _fail(
            f"cuts changed: the half-edge ({k // n}, {k % n}) is on a boundary or cut of the {side} only "
            "(a flipped, missing or extra triangle, or an edge split on one side)"
        )
    r_ang, r_area = _angles_areas(rp[cov_t])
    total_in, total_out = float(r_area.sum()), float(area.sum())
    if exact:
        if par is None:
            _fail("exact surface check needs the parent of every output triangle")
        q = rp[rt]
        normal = np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])
        norm = np.linalg.norm(normal, axis=1)
        normal /= np.where(norm > 0, norm, 1.0)[:, None]
        size = np.linalg.norm(q - np.roll(q, 1, axis=1), axis=2).max(axis=1)
        dist = np.abs(((pts[tri] - q[par, 0][:, None, :]) * normal[par][:, None, :]).sum(axis=2)).max(axis=1)
        off = np.flatnonzero(dist > PLANE_RTOL * size[par])
        if len(off):
            i = int(off[0])
            _fail(f"triangle {i} leaves the plane of its input triangle {int(par[i])} by {dist[i]:.3g}")
        all_area = np.zeros(m_in)
        all_area[covered] = r_area
        per = np.bincount(par, weights=area, minlength=m_in)
        diff = np.abs(per - all_area) > AREA_RTOL * np.maximum(all_area, 1e-300) + 1e-15 * total_in
        if diff.any():
            t = int(np.argmax(diff))
            _fail(f"the output triangles in input triangle {t} cover area {per[t]!r}, not {all_area[t]!r}")
        if not math.isclose(total_out, total_in, rel_tol=AREA_RTOL):
            _fail(f"total area changed from {total_in!r} to {total_out!r}")
    # 5. angles
    r_min = float(r_ang.min())
    amin = float(ang.min())
    if amin < angle_ratio * r_min * (1.0 - ANGLE_RTOL):
        i = int(np.argmin(ang.min(axis=1)))
        _fail(
            f"triangle {i} {tri[i].tolist()} has angle {math.degrees(amin):.6f} deg, below "
            f"{angle_ratio} x the input minimum {math.degrees(r_min):.6f} deg"
        )
    stats.update(
        {
            "min_angle_input_deg": math.degrees(r_min),
            "area_input": total_in,
            "area_change_rel": (total_out - total_in) / total_in,
            "input_rows_dropped": int(np.count_nonzero(~covered)),
        }
    )
    return stats
