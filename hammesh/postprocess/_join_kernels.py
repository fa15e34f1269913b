"""Compiled loops (numba) that judge and place the joins of sparse mode (issue 13).

A *join* merges two nodes of the cycle cover (two cycles, or a cycle and an uncovered
triangle) across the shared edge ``ab`` of ``t = (a, b, c)`` and ``u = (b, a, d)``:

* *swap*: ``ab`` flipped into ``cd``, new triangles ``(a, d, c)``, ``(d, b, c)``;
* *split*: a Steiner point ``M`` joined to ``a, b, c, d``, new triangles
  ``(a, M, c)``, ``(M, b, c)``, ``(b, M, d)``, ``(M, a, d)``. On a constrained edge
  (and on 3D surfaces) ``M`` is the midpoint of ``ab``; elsewhere it is placed to
  maximise the worst *slack* of the four triangles (below).

Every join is judged against its parents ``t`` and ``u`` (the local quality rule of
issue 13): with ``lo = keep x min(smallest angle of t, of u)`` and
``hi = largest input angle + 5 degrees`` its slack is
``min(smallest new angle - lo, hi - largest new angle)`` (radians): the join *meets
the rule* iff its slack is >= 0, and among several the larger slack is better.

Placing M is the optimal point placement problem of Amenta, Bern & Eppstein
("Optimal point placement for mesh smoothing", J. Algorithms 30, 1999): maximise the
smallest angle of the triangles of a star over the star's kernel. They solve it
exactly as an LP-type problem (each angle bound is a quasi-concave function of the
point); here, with only four triangles, a compass search (eight directions, step
halved when no direction improves, started from the midpoint of ``ab``, which is
always feasible) finds a point whose slack is within the final step of a local
optimum — simple, robust (every trial point is checked for a strictly positive
star) and a few microseconds per edge. The LP-type algorithm would give the exact
optimum; the compass search gives a feasible point at least as good as the midpoint.

Serial, nopython, ``cache=True``; O(number of candidate edges).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: join kinds
NO_JOIN, SWAP_JOIN, SPLIT_JOIN = 0, 1, 2


@njit(cache=True, nogil=True)
def _corner(o, q, r):
    """Angle at o of triangle (o, q, r) (coordinate rows, any dimension), radians."""
    uu = 0.0
    vv = 0.0
    uv = 0.0
    for i in range(o.shape[0]):
        u = q[i] - o[i]
        v = r[i] - o[i]
        uu += u * u
        vv += v * v
        uv += u * v
    cr = uu * vv - uv * uv
    if uu <= 0.0 or vv <= 0.0:
        return 0.0
    return math.atan2(math.sqrt(cr if cr > 0.0 else 0.0), uv)


@njit(cache=True, nogil=True)
def _min_max(x, y, z):
    """(smallest, largest) angle of triangle (x, y, z)."""
    a0 = _corner(x, y, z)
    a1 = _corner(y, z, x)
    a2 = math.pi - a0 - a1
    lo = min(a0, min(a1, a2))
    hi = max(a0, max(a1, a2))
    return lo, hi


@njit(cache=True, nogil=True)
def triangle_min_max_into(pts, tri, amin, amax):
    """Fill ``amin[t]``, ``amax[t]`` with the smallest and largest angle of triangle t."""
    for t in range(tri.shape[0]):
        lo, hi = _min_max(pts[tri[t, 0]], pts[tri[t, 1]], pts[tri[t, 2]])
        amin[t] = lo
        amax[t] = hi


@njit(cache=True, nogil=True)
def _orient(p, q, r):
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])


@njit(cache=True, nogil=True)
def _star4(pa, pb, pc, pd, mm, lo, hi):
    """Slack, smallest and largest angle of the four triangles around ``mm``.

    Planar: ``-inf`` slack unless all four are strictly counter-clockwise (by more
    than a relative ``1e-12`` of the squared edge, so a near-degenerate star never
    wins).
    """
    if pa.shape[0] == 2:
        s2 = (pb[0] - pa[0]) ** 2 + (pb[1] - pa[1]) ** 2
        eps = 1e-12 * s2
        if (
            _orient(pa, mm, pc) <= eps
            or _orient(mm, pb, pc) <= eps
            or _orient(pb, mm, pd) <= eps
            or _orient(mm, pa, pd) <= eps
        ):
            return -np.inf, 0.0, np.pi
    l1, h1 = _min_max(pa, mm, pc)
    l2, h2 = _min_max(mm, pb, pc)
    l3, h3 = _min_max(pb, mm, pd)
    l4, h4 = _min_max(mm, pa, pd)
    nmin = min(min(l1, l2), min(l3, l4))
    nmax = max(max(h1, h2), max(h3, h4))
    return min(nmin - lo, hi - nmax), nmin, nmax


@njit(cache=True, nogil=True)
def place_split(pa, pb, pc, pd, lo, hi, iters):
    """Compass search for the Steiner point of a split (planar, free edge).

    Starts at the midpoint of ``ab`` and maximises the slack of the four triangles
    (module docstring); at most ``iters`` step halvings. Returns
    ``(x, y, slack, smallest angle, largest angle)``.
    """
    mm = 0.5 * (pa + pb)
    best, bmin, bmax = _star4(pa, pb, pc, pd, mm, lo, hi)
    step = 0.25 * math.sqrt((pb[0] - pa[0]) ** 2 + (pb[1] - pa[1]) ** 2)
    trial = np.empty(2)
    halvings = 0
    while halvings < iters:
        moved = False
        bx = mm[0]
        by = mm[1]
        for k in range(8):
            ang = 0.25 * math.pi * k
            trial[0] = mm[0] + step * math.cos(ang)
            trial[1] = mm[1] + step * math.sin(ang)
            s, lmin, lmax = _star4(pa, pb, pc, pd, trial, lo, hi)
            if s > best:
                best = s
                bmin = lmin
                bmax = lmax
                bx = trial[0]
                by = trial[1]
                moved = True
        if moved:
            mm[0] = bx
            mm[1] = by
        else:
            step *= 0.5
            halvings += 1
    return mm[0], mm[1], best, bmin, bmax


@njit(cache=True, nogil=True)
def _swap_geometry(pts, a, b, c, d, cos_fold):
    """Is the swap of ab into cd legal (strictly convex / folded at most max_fold)?"""
    if pts.shape[1] == 2:
        return _orient(pts[a], pts[d], pts[c]) > 0.0 and _orient(pts[d], pts[b], pts[c]) > 0.0
    ux = pts[b, 0] - pts[a, 0]
    uy = pts[b, 1] - pts[a, 1]
    uz = pts[b, 2] - pts[a, 2]
    vx = pts[c, 0] - pts[a, 0]
    vy = pts[c, 1] - pts[a, 1]
    vz = pts[c, 2] - pts[a, 2]
    wx = pts[d, 0] - pts[a, 0]
    wy = pts[d, 1] - pts[a, 1]
    wz = pts[d, 2] - pts[a, 2]
    n1x = uy * vz - uz * vy  # normal of t: u x v
    n1y = uz * vx - ux * vz
    n1z = ux * vy - uy * vx
    n2x = wy * uz - wz * uy  # normal of u: w x u
    n2y = wz * ux - wx * uz
    n2z = wx * uy - wy * ux
    l1 = math.sqrt(n1x * n1x + n1y * n1y + n1z * n1z)
    l2 = math.sqrt(n2x * n2x + n2y * n2y + n2z * n2z)
    if l1 == 0.0 or l2 == 0.0:
        return False
    if (n1x * n2x + n1y * n2y + n1z * n2z) / (l1 * l2) < cos_fold:
        return False
    nx = n1x + n2x
    ny = n1y + n2y
    nz = n1z + n2z
    if (wy * vz - wz * vy) * nx + (wz * vx - wx * vz) * ny + (wx * vy - wy * vx) * nz <= 0.0:
        return False  # (a, d, c) folds over
    ex = ux - wx
    ey = uy - wy
    ez = uz - wz
    fx = vx - wx
    fy = vy - wy
    fz = vz - wz
    return (ey * fz - ez * fy) * nx + (ez * fx - ex * fz) * ny + (ex * fy - ey * fx) * nz > 0.0


@njit(cache=True, nogil=True)
def score_joins_into(
    pts, tri, twin, pinned, cand, amin, keep, hi, floor, cos_fold, swaps, edge_splits, place_iters,
    kind, slack, newmin, newmax, point,
):
    """Judge every candidate join (half-edge ``cand[i]`` of the covered triangle t).

    For each candidate the better of its swap and its split (a swap wins a tie: no
    Steiner point) is kept in ``kind[i]``, ``slack[i]``, ``newmin[i]``, ``newmax[i]``
    (smallest and largest new angle) and ``point[i]`` (the split's Steiner point). A split of a ``pinned`` edge
    (constrained, or between two regions) or in 3D keeps the midpoint; a free planar
    split is placed by :func:`place_split` unless the swap or the midpoint already
    meets the rule with room to spare. ``kind[i] = NO_JOIN`` where neither keeps every
    new angle at or above ``floor`` (the proven bound the certificate checks).
    """
    planar = pts.shape[1] == 2
    for i in range(cand.shape[0]):
        h = cand[i]
        t = h // 3
        k = h - 3 * t
        g = twin[h]
        u = g // 3
        kg = g - 3 * u
        a = tri[t, k]
        b = tri[t, (k + 1) % 3]
        c = tri[t, (k + 2) % 3]
        d = tri[u, (kg + 2) % 3]
        lo = keep * min(amin[t], amin[u])
        best = -np.inf
        bkind = NO_JOIN
        bmin = 0.0
        bmax = np.pi
        if swaps and not pinned[h] and _swap_geometry(pts, a, b, c, d, cos_fold):
            l1, h1 = _min_max(pts[a], pts[d], pts[c])
            l2, h2 = _min_max(pts[d], pts[b], pts[c])
            smin = min(l1, l2)
            if smin >= floor:
                best = min(smin - lo, hi - max(h1, h2))
                bkind = SWAP_JOIN
                bmin = smin
                bmax = max(h1, h2)
        for j in range(pts.shape[1]):
            point[i, j] = 0.5 * (pts[a, j] + pts[b, j])
        if edge_splits and best < 0.0:
            s, smin, smax = _star4(pts[a], pts[b], pts[c], pts[d], point[i], lo, hi)
            if planar and not pinned[h] and place_iters > 0:
                x, y, s2, m2, x2 = place_split(pts[a], pts[b], pts[c], pts[d], lo, hi, place_iters)
                if s2 > s:
                    s = s2
                    smin = m2
                    smax = x2
                    point[i, 0] = x
                    point[i, 1] = y
            if smin >= floor and s > best:
                best = s
                bkind = SPLIT_JOIN
                bmin = smin
                bmax = smax
        kind[i] = bkind
        slack[i] = best
        newmin[i] = bmin
        newmax[i] = bmax


@njit(cache=True, nogil=True)
def worst_radius_ratio(pts, tri):
    """Largest circumradius / (2 x inradius) over the triangles (1 when equilateral).

    ``R = abc / 4A`` and ``r = 2A / (a + b + c)``, so ``R / 2r = abc (a + b + c) / 16 A^2``
    with ``16 A^2`` from the Gram form (any dimension).
    """
    worst = 1.0
    for t in range(tri.shape[0]):
        p = pts[tri[t, 0]]
        q = pts[tri[t, 1]]
        r = pts[tri[t, 2]]
        uu = 0.0
        vv = 0.0
        uv = 0.0
        ww = 0.0
        for i in range(p.shape[0]):
            u = q[i] - p[i]
            v = r[i] - p[i]
            w = r[i] - q[i]
            uu += u * u
            vv += v * v
            uv += u * v
            ww += w * w
        a16 = 4.0 * (uu * vv - uv * uv)  # (2 x twice the area)^2 = 16 A^2
        la = math.sqrt(uu)
        lb = math.sqrt(vv)
        lc = math.sqrt(ww)
        if a16 <= 0.0:
            return np.inf
        x = la * lb * lc * (la + lb + lc) / a16
        if x > worst:
            worst = x
    return worst
