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
star) and a few microseconds per edge. Where it ends short of the rule,
:func:`ridge_ascent` climbs on along the slack's ridges to the optimum (the
smallest-angle problem is quasi-concave, so that is ABE's exact optimum; a largest-angle
bound at the point itself is not, and there it is a local one).

Serial, nopython, ``cache=True``; O(number of candidate edges).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

#: join kinds
NO_JOIN, SWAP_JOIN, SPLIT_JOIN = 0, 1, 2
#: the compass search's eight directions
_DIRS = np.array([[math.cos(0.25 * math.pi * k), math.sin(0.25 * math.pi * k)] for k in range(8)])


@njit(cache=True, nogil=True, inline="always")
def corner_atan2(y, x):
    """``atan2(y, x)`` for ``y >= 0`` (a corner's angle from ``|cross|`` and ``dot``), radians.

    Within 5e-16 rad of ``math.atan2`` (not its bits: a corner's angle was two libm
    ``atan2`` calls, ~21 ns each, most of the time the input's angles and the joins' scores
    take); here one division and a polynomial, ~11 ns, no libm call. The
    argument is folded to ``r = min(|x|, y) / max(|x|, y)`` in [0, 1], then, above
    ``tan 15 deg``, by ``atan r = 30 deg + atan((sqrt3 r - 1) / (sqrt3 + r))`` into
    ``|t| <= tan 15 deg`` (one division either way: the fold's numerator and
    denominator are formed before it), where the Taylor series to ``t^27`` is exact to
    ~2e-17 (next term ``0.268^29 / 29``). The classic three-interval reduction of
    Cody & Waite, *Software Manual for the Elementary Functions* (1980), ch. 11.
    ``(0, +0)`` is 0, ``(0, x < 0)`` and ``(0, -0)`` are pi, as ``math.atan2``.
    """
    ax = abs(x)
    big = y > ax
    num = ax if big else y
    den = y if big else ax
    if den < 1e-290 or den > 1e290:  # (subnormal or near overflow: the fold below would round off)
        f = 1e300 if den < 1e-290 else 1e-300
        num *= f
        den *= f
    low = num <= 0.2679491924311227 * den  # (tan 15 deg)
    tn = num if low else 1.7320508075688772 * num - den
    td = den if low else 1.7320508075688772 * den + num
    if td == 0.0:
        return math.pi if math.copysign(1.0, x) < 0.0 else 0.0  # (as atan2: (0, -0.0) is pi)
    t = tn / td
    z = t * t
    z2 = z * z
    # (the reciprocals are constants: ``z * (1 / k)``, not ``z / k``, no division per term)
    p = (((((((1.0 / 25.0 - z * (1.0 / 27.0)) * z2 + (1.0 / 21.0 - z * (1.0 / 23.0))) * z2
             + (1.0 / 17.0 - z * (1.0 / 19.0))) * z2 + (1.0 / 13.0 - z * (1.0 / 15.0))) * z2
           + (1.0 / 9.0 - z * (1.0 / 11.0))) * z2 + (1.0 / 5.0 - z * (1.0 / 7.0))) * z2
         + (1.0 - z * (1.0 / 3.0)))
    a = t * p
    a = a if low else 0.5235987755982989 + a
    a = (1.5707963267948966 - a) if big else a
    return (3.141592653589793 - a) if x < 0.0 else a


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
    return corner_atan2(math.sqrt(cr if cr > 0.0 else 0.0), uv)


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
def triangle_min_max_into(pts, tri, amin, amax, corners):
    """Fill ``amin[t]``, ``amax[t]`` with the smallest and largest angle of triangle t.

    ``corners`` (planar; ``(0, 3)``: not wanted): each corner's angle, ``corners[t, k]``
    at ``tri[t, k]``, as float32 (the cover's matching rules edges out by them,
    :func:`corners_rule_out`), from the same pass that finds the smallest and largest.

    Returns ``(worst, row)``: the worst circumradius / (2 x inradius) of the rows (1
    when equilateral, ``inf`` for a degenerate one; ``R = abc / 4A`` and
    ``r = 2A / (a + b + c)``, so ``R / 2r = abc (a + b + c) / 16 A^2`` with ``16 A^2``
    from the cross product, in 3D the Gram form) and the row that has it (-1 if none
    is worse than 1), so one pass over the rows gives both the angles and the
    report's radius ratio.
    """
    planar = pts.shape[1] == 2
    worst = 1.0
    arg = -1
    for t in range(tri.shape[0]):
        a = tri[t, 0]
        b = tri[t, 1]
        c = tri[t, 2]
        if planar:
            ax = pts[a, 0]
            ay = pts[a, 1]
            ux = pts[b, 0] - ax
            uy = pts[b, 1] - ay
            vx = pts[c, 0] - ax
            vy = pts[c, 1] - ay
            uu = ux * ux + uy * uy
            vv = vx * vx + vy * vy
            uv = ux * vx + uy * vy
            cr = ux * vy - uy * vx
            a16 = 4.0 * cr * cr
            ww = (pts[c, 0] - pts[b, 0]) ** 2 + (pts[c, 1] - pts[b, 1]) ** 2
            a0 = _corner2(ax, ay, pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1])
            a1 = _corner2(pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1], ax, ay)
            a2 = math.pi - a0 - a1  # (min_max_angles_2d's arithmetic: the same bits)
            lo, hi = min(a0, min(a1, a2)), max(a0, max(a1, a2))
            if corners.shape[0] > 0:
                corners[t, 0] = a0
                corners[t, 1] = a1
                corners[t, 2] = a2
        else:
            uu = 0.0
            vv = 0.0
            uv = 0.0
            ww = 0.0
            for i in range(pts.shape[1]):
                u = pts[b, i] - pts[a, i]
                v = pts[c, i] - pts[a, i]
                uu += u * u
                vv += v * v
                uv += u * v
                ww += (pts[c, i] - pts[b, i]) ** 2
            a16 = 4.0 * (uu * vv - uv * uv)
            lo, hi = _min_max(pts[a], pts[b], pts[c])
        amin[t] = lo
        amax[t] = hi
        la = math.sqrt(uu)
        lb = math.sqrt(vv)
        lc = math.sqrt(ww)
        x = np.inf if a16 <= 0.0 else la * lb * lc * (la + lb + lc) / a16
        if x > worst:
            worst = x
            arg = t
    return worst, arg


@njit(cache=True, nogil=True)
def _orient(p, q, r):
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])


@njit(cache=True, nogil=True)
def _spokes(ox, oy, qx, qy, rx, ry):
    """The vectors ``q - o`` and ``r - o`` of the corner at o of (o, q, r): ``(ux, uy, vx, vy)``."""
    return qx - ox, qy - oy, rx - ox, ry - oy


@njit(cache=True, nogil=True)
def _corner2(ox, oy, qx, qy, rx, ry):
    """Angle at o of the planar triangle (o, q, r), radians (scalars: no arrays)."""
    ux, uy, vx, vy = _spokes(ox, oy, qx, qy, rx, ry)
    return corner_atan2(abs(ux * vy - uy * vx), ux * vx + uy * vy)


@njit(cache=True, nogil=True)
def min_max_angles_2d(ax, ay, bx, by, cx, cy):
    """(smallest, largest) angle of the planar triangle (a, b, c)."""
    a0 = _corner2(ax, ay, bx, by, cx, cy)
    a1 = _corner2(bx, by, cx, cy, ax, ay)
    a2 = math.pi - a0 - a1
    return min(a0, min(a1, a2)), max(a0, max(a1, a2))


@njit(cache=True, nogil=True)
def _star4_2d(ax, ay, bx, by, cx, cy, dx, dy, mx, my, lo, hi):
    """Planar :func:`_star4` on scalars (the hot loop of the placement search)."""
    eps = 1e-12 * ((bx - ax) ** 2 + (by - ay) ** 2)
    if (
        (mx - ax) * (cy - ay) - (my - ay) * (cx - ax) <= eps
        or (bx - mx) * (cy - my) - (by - my) * (cx - mx) <= eps
        or (mx - bx) * (dy - by) - (my - by) * (dx - bx) <= eps
        or (ax - mx) * (dy - my) - (ay - my) * (dx - mx) <= eps
    ):
        return -np.inf, 0.0, np.pi
    l1, h1 = min_max_angles_2d(ax, ay, mx, my, cx, cy)
    l2, h2 = min_max_angles_2d(mx, my, bx, by, cx, cy)
    l3, h3 = min_max_angles_2d(bx, by, mx, my, dx, dy)
    l4, h4 = min_max_angles_2d(mx, my, ax, ay, dx, dy)
    nmin = min(min(l1, l2), min(l3, l4))
    nmax = max(max(h1, h2), max(h3, h4))
    return min(nmin - lo, hi - nmax), nmin, nmax


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
def place_split(ax, ay, bx, by, cx, cy, dx, dy, lo, hi, iters, exact=True):
    """Compass search for the Steiner point of a split (planar, free edge).

    The four triangles around the point are the fan over the quadrilateral
    ``(a, d, b, c)``, so this is :func:`compass_search` (corner cosines, a trial stops
    at the first corner that cannot beat the best so far: ~4x fewer arctangents than
    judging every trial on exact angles) started at the midpoint of ``ab`` with step
    ``|ab| / 4``, at most ``iters`` step halvings and ``4 x iters`` rounds. The result
    is judged on exact angles and is never worse than the midpoint. Returns
    ``(x, y, slack, smallest angle, largest angle)``.
    """
    mx = 0.5 * (ax + bx)
    my = 0.5 * (ay + by)
    s0, m0, x0 = _star4_2d(ax, ay, bx, by, cx, cy, dx, dy, mx, my, lo, hi)
    quad = np.empty((4, 2))
    quad[0, 0] = ax
    quad[0, 1] = ay
    quad[1, 0] = dx
    quad[1, 1] = dy
    quad[2, 0] = bx
    quad[2, 1] = by
    quad[3, 0] = cx
    quad[3, 1] = cy
    poly = np.arange(4)
    step = 0.25 * math.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
    px, py, s1, m1, x1 = compass_search(quad, poly, 4, mx, my, lo, hi, step, iters, 4 * iters, exact)
    if not s1 > s0:
        return mx, my, s0, m0, x0
    # the fan's strict-orientation test is per polygon edge; keep the split's own
    s2, m2, x2 = _star4_2d(ax, ay, bx, by, cx, cy, dx, dy, px, py, lo, hi)
    if not s2 > s0:
        return mx, my, s0, m0, x0
    return px, py, s2, m2, x2


@njit(cache=True, nogil=True)
def quad_corners(tri, twin, h):
    """``(t, u, a, b, c, d)`` of the quad over half-edge ``h``: ``t = (a, b, c)`` owns ``h``
    (from ``a`` to ``b``), ``u = (b, a, d)`` owns its twin."""
    t = h // 3
    k = h - 3 * t
    g = twin[h]
    u = g // 3
    kg = g - 3 * u
    return t, u, tri[t, k], tri[t, (k + 1) % 3], tri[t, (k + 2) % 3], tri[u, (kg + 2) % 3]


@njit(cache=True, nogil=True)
def quad_xy(pts, a, b, c, d):
    """Planar coordinates ``(ax, ay, bx, by, cx, cy, dx, dy)`` of the quad's corners (scalars
    for the hot loops)."""
    return pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1], pts[d, 0], pts[d, 1]


@njit(cache=True, nogil=True)
def swap_is_convex_2d(ax, ay, bx, by, cx, cy, dx, dy):
    """Can ``ab`` of ``t = (a, b, c)``, ``u = (b, a, d)`` be flipped into ``cd``: are the new
    triangles ``(a, d, c)`` and ``(d, b, c)`` strictly counter-clockwise?"""
    return (dx - ax) * (cy - ay) - (dy - ay) * (cx - ax) > 0.0 and (bx - dx) * (cy - dy) - (by - dy) * (cx - dx) > 0.0


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
def _swap_score(l1, h1, l2, h2, floor, lo, hi):
    """``(slack, kind, smallest, largest)`` of a swap whose new triangles have smallest and
    largest angles ``l1, h1`` and ``l2, h2``; no join (``-inf``) below ``floor``."""
    smin = min(l1, l2)
    if smin < floor:
        return -np.inf, NO_JOIN, 0.0, np.pi
    smax = max(h1, h2)
    return min(smin - lo, hi - smax), SWAP_JOIN, smin, smax


@njit(cache=True, nogil=True)
def score_joins_into(
    pts, tri, twin, pinned, cand, amin, keep, hi, floor, cos_fold, swaps, edge_splits, place_iters, reach,
    kind, slack, newmin, newmax, point, exact=True,
):
    """Judge every candidate join (half-edge ``cand[i]`` of the covered triangle t).

    For each candidate the better of its swap and its split (a swap wins a tie: no
    Steiner point) is kept in ``kind[i]``, ``slack[i]``, ``newmin[i]``, ``newmax[i]``
    (smallest and largest new angle) and ``point[i]`` (the split's Steiner point). A
    split of a ``pinned`` edge (constrained, or between two regions) or in 3D keeps
    the midpoint; a free planar split is placed by :func:`place_split` unless the swap
    or the midpoint already meets the rule, or the midpoint misses it by more than
    ``reach`` (radians; placement gains a few degrees, rarely ten: measured on q30
    meshes, every split it brought to the rule missed it by < 10 degrees at the
    midpoint). ``kind[i] = NO_JOIN`` where neither keeps
    every new angle at or above ``floor`` (the proven bound the certificate checks).
    """
    planar = pts.shape[1] == 2
    for i in range(cand.shape[0]):
        h = cand[i]
        t, u, a, b, c, d = quad_corners(tri, twin, h)
        lo = keep * min(amin[t], amin[u])
        best = -np.inf
        bkind = NO_JOIN
        bmin = 0.0
        bmax = np.pi
        if planar:
            ax, ay, bx, by, cx, cy, dx, dy = quad_xy(pts, a, b, c, d)
            if swaps and not pinned[h]:
                if swap_is_convex_2d(ax, ay, bx, by, cx, cy, dx, dy):
                    l1, h1 = min_max_angles_2d(ax, ay, dx, dy, cx, cy)
                    l2, h2 = min_max_angles_2d(dx, dy, bx, by, cx, cy)
                    best, bkind, bmin, bmax = _swap_score(l1, h1, l2, h2, floor, lo, hi)
            point[i, 0] = 0.5 * (ax + bx)
            point[i, 1] = 0.5 * (ay + by)
            if edge_splits and best < 0.0:
                s, smin, smax = _star4_2d(ax, ay, bx, by, cx, cy, dx, dy, point[i, 0], point[i, 1], lo, hi)
                if not pinned[h] and place_iters > 0 and -reach <= s < 0.0:
                    x, y, s2, m2, x2 = place_split(ax, ay, bx, by, cx, cy, dx, dy, lo, hi, place_iters, exact)
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
        else:
            if swaps and not pinned[h] and _swap_geometry(pts, a, b, c, d, cos_fold):
                l1, h1 = _min_max(pts[a], pts[d], pts[c])
                l2, h2 = _min_max(pts[d], pts[b], pts[c])
                best, bkind, bmin, bmax = _swap_score(l1, h1, l2, h2, floor, lo, hi)
            for j in range(pts.shape[1]):
                point[i, j] = 0.5 * (pts[a, j] + pts[b, j])
            if edge_splits and best < 0.0:
                s, smin, smax = _star4(pts[a], pts[b], pts[c], pts[d], point[i], lo, hi)
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
def _fan_edge(pts, poly, n, i, px, py):
    """Edge i of the fan over ``poly[:n]`` around ``p``: ``(ax, ay, bx, by, ok)``, ``ok`` if the
    triangle ``(p, a, b)`` is counter-clockwise by more than a relative ``1e-12`` of ``|ab|^2``."""
    a = poly[i]
    b = poly[(i + 1) % n]
    ax = pts[a, 0]
    ay = pts[a, 1]
    bx = pts[b, 0]
    by = pts[b, 1]
    s2 = (bx - ax) ** 2 + (by - ay) ** 2
    return ax, ay, bx, by, (ax - px) * (by - py) - (ay - py) * (bx - px) > 1e-12 * s2


@njit(cache=True, nogil=True)
def fan_eval(pts, poly, n, px, py, lo, hi):
    """Slack, smallest and largest angle of the fan ``(p, poly[i], poly[i + 1])``.

    Exact angles (``atan2``, two per triangle): what decides whether a fan is taken.
    """
    nmin = np.pi
    nmax = 0.0
    for i in range(n):
        ax, ay, bx, by, ok = _fan_edge(pts, poly, n, i, px, py)
        if not ok:
            return -np.inf, 0.0, np.pi
        l1, h1 = min_max_angles_2d(px, py, ax, ay, bx, by)
        nmin = min(nmin, l1)
        nmax = max(nmax, h1)
    return min(nmin - lo, hi - nmax), nmin, nmax


@njit(cache=True, nogil=True)
def _fan_eval_fast(pts, poly, n, px, py, lo, hi, c_lo, c_hi):
    """:func:`fan_eval`'s slack for the placement search: by cosines, two ``acos`` per fan.

    The smallest angle of the fan is the arccosine of its largest corner cosine and
    the largest angle that of the smallest: one square root per corner instead of an
    arctangent per corner (the search evaluates ~70 points per fan; on a sliver mesh
    this was nearly all of sparse mode's time). A corner cosine ``>= c_lo`` or ``<= c_hi``
    (the cosines of the angles at which the slack would not beat the search's best so
    far) stops the evaluation: ``-inf``. Cosines near 1 lose digits (~1e-8 rad), so the
    point found is re-judged by :func:`fan_eval` before a fan is taken.
    """
    cmax = -1.0
    cmin = 1.0
    for i in range(n):
        ax, ay, bx, by, ok = _fan_edge(pts, poly, n, i, px, py)
        if not ok:
            return -np.inf
        for k in range(3):
            if k == 0:
                ux, uy, vx, vy = ax - px, ay - py, bx - px, by - py
            elif k == 1:
                ux, uy, vx, vy = bx - ax, by - ay, px - ax, py - ay
            else:
                ux, uy, vx, vy = px - bx, py - by, ax - bx, ay - by
            nn = math.sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy))
            if nn <= 0.0:
                return -np.inf
            c = (ux * vx + uy * vy) / nn
            if c >= c_lo or c <= c_hi:
                return -np.inf
            cmax = max(cmax, c)
            cmin = min(cmin, c)
    nmin = math.acos(min(1.0, cmax))
    nmax = math.acos(max(-1.0, cmin))
    return min(nmin - lo, hi - nmax)


@njit(cache=True, nogil=True)
def _beat_cosines(best, lo, hi):
    """Corner cosines at which a fan's slack can no longer beat ``best``.

    Slack ``> best`` needs every angle ``> lo + best`` (cosine ``< cos(lo + best)``) and
    ``< hi - best`` (cosine ``> cos(hi - best)``); outside ``[0, pi]`` no cut (2, -2).
    """
    a = lo + best
    b = hi - best
    c_lo = 2.0 if a <= 0.0 else (-2.0 if a >= math.pi else math.cos(a))
    c_hi = -2.0 if b >= math.pi else (2.0 if b <= 0.0 else math.cos(b))
    return c_lo, c_hi


@njit(cache=True, nogil=True)
def place_fan(pts, poly, n, starts, n_starts, lo, hi, step, iters):
    """Steiner point of a fan over the polygon ``poly[:n]`` (counter-clockwise).

    Amenta-Bern-Eppstein's placement problem again (see module docstring): the best
    of the feasible ``starts``, improved by compass search. Returns
    ``(x, y, slack, smallest angle, largest angle)``; slack ``-inf`` if no start is
    inside the polygon's kernel.
    """
    best = -np.inf
    mx = 0.0
    my = 0.0
    for s in range(n_starts):
        sl = _fan_eval_fast(pts, poly, n, starts[s, 0], starts[s, 1], lo, hi, 2.0, -2.0)
        if sl > best:
            best = sl
            mx = starts[s, 0]
            my = starts[s, 1]
    if best == -np.inf:
        return 0.0, 0.0, best, 0.0, np.pi
    return compass_search(pts, poly, n, mx, my, lo, hi, step, iters, NO_ROUND_CAP)


#: ``compass_search``'s round cap for callers that stop on halvings alone
NO_ROUND_CAP = 1 << 62


@njit(cache=True, nogil=True)
def compass_search(pts, poly, n, px, py, lo, hi, step, iters, max_rounds, exact=True):
    """Compass search from ``(px, py)`` for the fan's point over ``poly[:n]``.

    Eight directions per round; the step halves when none improves the slack, up to
    ``iters`` halvings or ``max_rounds`` rounds. Candidates are compared on cosines
    (``_fan_eval_fast``); the result is judged on exact angles. Where it ends short of
    the rule (slack < 0) :func:`ridge_ascent` climbs on from there to the optimum (the
    compass alone stopped up to 0.8 degrees short on ``la``'s splits). Returns ``(x, y,
    slack, smallest angle, largest angle)``; slack ``-inf`` if ``(px, py)`` is not in
    the polygon's kernel.
    """
    best = _fan_eval_fast(pts, poly, n, px, py, lo, hi, 2.0, -2.0)
    if best == -np.inf:
        return px, py, best, 0.0, np.pi
    mx = px
    my = py
    c_lo, c_hi = _beat_cosines(best, lo, hi)
    halvings = 0
    rounds = 0
    while halvings < iters and rounds < max_rounds:
        rounds += 1
        moved = False
        bx = mx
        by = my
        for k in range(8):
            tx = mx + step * _DIRS[k, 0]
            ty = my + step * _DIRS[k, 1]
            sl = _fan_eval_fast(pts, poly, n, tx, ty, lo, hi, c_lo, c_hi)
            if sl > best:
                best = sl
                c_lo, c_hi = _beat_cosines(best, lo, hi)
                bx = tx
                by = ty
                moved = True
        if moved:
            mx = bx
            my = by
        else:
            step *= 0.5
            halvings += 1
    best, bmin, bmax = fan_eval(pts, poly, n, mx, my, lo, hi)
    if exact and best < 0.0:
        # short of the rule: where two constraints bind, the eight directions may all
        # leave the ridge between them; the optimum decides whether the rule is met
        rx, ry, rs = ridge_ascent(pts, poly, n, mx, my, lo, hi, 2.0 * step)
        if rs > best:
            mx = rx
            my = ry
            best, bmin, bmax = fan_eval(pts, poly, n, mx, my, lo, hi)
    return mx, my, best, bmin, bmax


@njit(cache=True, nogil=True)
def _with_apex(tri, poly, phe, n, i, y, kg, tpoly, tphe):
    """``poly[:n]`` with ``y``'s apex ``w`` inserted after corner i (``y`` lies across
    polygon edge i, its half-edge ``3 y + kg``), into ``tpoly``, ``tphe``: edges
    ``(a, w)``, ``(w, b)`` of ``y`` in place of ``(a, b)``. Returns ``w``."""
    w = tri[y, (kg + 2) % 3]
    for j in range(i + 1):
        tpoly[j] = poly[j]
        tphe[j] = phe[j]
    tpoly[i + 1] = w
    tphe[i] = 3 * y + (kg + 1) % 3  # a -> w
    tphe[i + 1] = 3 * y + (kg + 2) % 3  # w -> b
    for j in range(i + 1, n):
        tpoly[j + 1] = poly[j]
        tphe[j + 1] = phe[j]
    return w


@njit(cache=True, nogil=True)
def _fan_with(pts, tri, tpoly, n, members, nm, y, gm, px, py, have_pt, keep, hi, floor, hi_fan, iters, starts):
    """The fan over ``tpoly[:n]`` (a group's polygon with ``y`` added): its point, from the
    members' and ``y``'s centroids and the group's last point (``have_pt``), and
    whether it keeps the group's bounds (``fan_groups``). Returns ``(x, y, slack, group
    minimum, ok)``.

    No search where no point can keep the bound: the spokes to a corner split its
    interior angle in two, so every fan's smallest angle is at most half the polygon's
    smallest corner (:func:`half_smallest_corner`). On a one-triangle-wide strip every
    try fails that way (its pairs' corners are ~50 degrees against a bound of the
    input's ~30), and the searches, ridge ascents included, were ~0.1 ms a triangle."""
    need = max(floor, 0.5 * gm)
    if half_smallest_corner(pts, tpoly, n) < need * (1.0 - CORNER_BOUND_RTOL):
        return px, py, -np.inf, gm, False
    ns = 0
    for j in range(nm + 1):
        x = members[j] if j < nm else y
        starts[ns, 0] = (pts[tri[x, 0], 0] + pts[tri[x, 1], 0] + pts[tri[x, 2], 0]) / 3.0
        starts[ns, 1] = (pts[tri[x, 0], 1] + pts[tri[x, 1], 1] + pts[tri[x, 2], 1]) / 3.0
        ns += 1
    if have_pt:
        starts[ns, 0] = px
        starts[ns, 1] = py
        ns += 1
    step = 0.25 * math.sqrt(
        (pts[tri[y, 0], 0] - pts[tri[y, 1], 0]) ** 2 + (pts[tri[y, 0], 1] - pts[tri[y, 1], 1]) ** 2
    )
    x0, y0, sl, nmin, nmax = place_fan(pts, tpoly, n, starts, ns, keep * gm, hi, step, iters)
    ok = not (sl == -np.inf or nmin < max(floor, 0.5 * gm) or nmax > hi_fan)
    return x0, y0, sl, gm, ok


#: relative margin under which :func:`_fan_with`'s corner bound refuses a fan without a
#: search (far above the angles' rounding, so a fan the search could keep is never refused)
CORNER_BOUND_RTOL = 1e-6


@njit(cache=True, nogil=True)
def half_smallest_corner(pts, poly, n):
    """Half the smallest interior angle of the counter-clockwise polygon ``poly[:n]`` (radians).

    An upper bound on the smallest angle of any fan over the polygon: a fan point
    inside its kernel splits each corner's interior angle between two fan triangles.
    A reflex corner counts as its interior angle (over pi).
    """
    best = np.inf
    for i in range(n):
        a = poly[i - 1 if i > 0 else n - 1]
        b = poly[i]
        c = poly[i + 1 if i + 1 < n else 0]
        ux = pts[c, 0] - pts[b, 0]
        uy = pts[c, 1] - pts[b, 1]
        vx = pts[a, 0] - pts[b, 0]
        vy = pts[a, 1] - pts[b, 1]
        ang = math.atan2(ux * vy - uy * vx, ux * vx + uy * vy)  # from b->c counter-clockwise to b->a
        if ang < 0.0:
            ang += 2.0 * math.pi
        best = min(best, ang)
    return 0.5 * best


@njit(cache=True, nogil=True)
def _across(tri, twin, pinned, poly, phe, n, i):
    """The triangle across free polygon edge i and that edge's index in it, ``(y, kg)``;
    ``(-1, -1)`` on the boundary, a pinned edge, or where ``y``'s apex is a corner
    already (the union would not stay a disc without inner vertices)."""
    h = phe[i]
    g = twin[h]
    if g < 0 or pinned[h]:
        return -1, -1
    y = g // 3
    kg = g - 3 * y
    w = tri[y, (kg + 2) % 3]
    for j in range(n):
        if poly[j] == w:
            return -1, -1
    return y, kg


#: ``fan_groups``' mark (in ``group``, reset to -1 before it returns) of a start that
#: took in no neighbour: every pair fan with it was tried and failed, so a later start
#: does not search the same fan again (on a mesh of slivers, where no pair fan keeps
#: the bounds, half of ``fan_groups``' searches)
LONE = -2


@njit(cache=True, nogil=True)
def fan_groups(pts, tri, twin, pinned, cyc, amin, keep, hi, floor, hi_fan, max_group, iters, is_cov, absorb, unc,
               group):
    """Groups of adjacent uncovered triangles, each to be replaced by one fan.

    Chains of triangles no cover cycle passes (thin parts, what ears leave) would
    otherwise cost a Steiner point each. Greedy: from each uncovered triangle not yet
    grouped, add uncovered neighbours across free edges one at a time (their apex
    must be new, so the union stays a triangulated disc without inner vertices)
    while the polygon has a fan point whose triangles keep every angle >=
    ``max(floor, 1/2 x the group's smallest)`` (no worse than Thm 2.4's incenter
    sectors) and <= ``hi_fan``. A fan over a polygon of ``k + 2`` corners is a cycle of
    ``k + 2`` triangles with one Steiner point, in place of ``k`` triangles.

    With ``absorb`` (``is_cov``: the cover's half-edges) a grown group of two or more may then take
    in one *covered* triangle ``y`` across the polygon edge that is ``y``'s non-cover
    edge (the best fan of those within the same bounds; ``_absorb_covered``). ``y``'s two
    cover edges are then consecutive edges of the polygon, around its apex ``w``, and
    the fan's cycle cut at the spoke to ``w`` is a path from one to the other: the
    group joins ``y``'s cycle through its one Steiner point, with no join (on Triangle's
    ``A`` at 87 triangles each fan was otherwise a cycle of its own, joined by a Thm 2.4
    bridge: two incenters more).

    ``unc``: the uncovered triangles, ascending (``cyc < 0``), the groups' starts in
    that order; ``group`` (m,) int64, all -1, filled in place (the caller's pages: at
    1.5 M triangles a scan of every row and a fresh 12 MB array cost ~15 ms for a few
    dozen uncovered triangles).

    Returns ``(group (m,) int64, -1 if none; fan points (g, 2); group minimum angle
    (g,); polygon offsets (g + 1,); polygon corners; polygon edge half-edges;
    absorbed (g,) the covered triangle taken in or -1; apex (g,) the index of its apex
    in the group's polygon, from ``off[j]``, or -1)``: group j's polygon is
    ``corners[off[j]:off[j + 1]]`` counter-clockwise, its edge ``(corners[i],
    corners[i + 1])`` is the input half-edge ``he[i]`` (for an absorbed ``y``, the two
    edges around its apex are ``y``'s).
    """
    # a group has >= 2 uncovered members and at most one covered: <= k + 3 <= 2.5 k corners
    k_unc = unc.shape[0]
    fan_pt = np.empty((k_unc // 2 + 1, 2))
    gmin_out = np.empty(k_unc // 2 + 1)
    off = np.zeros(k_unc // 2 + 2, np.int64)
    corners = np.empty(3 * k_unc + 3, np.int64)
    hes = np.empty(3 * k_unc + 3, np.int64)
    absorbed = np.full(k_unc // 2 + 1, -1, np.int64)
    apex = np.full(k_unc // 2 + 1, -1, np.int64)
    ng = 0
    n_c = 0
    cap = max_group + 3
    poly = np.empty(cap, np.int64)
    phe = np.empty(cap, np.int64)
    tpoly = np.empty(cap, np.int64)
    tphe = np.empty(cap, np.int64)
    members = np.empty(cap, np.int64)
    starts = np.empty((cap, 2))
    lone = np.empty(k_unc, np.int64)
    n_lone = 0
    for s in unc:
        if cyc[s] >= 0 or group[s] >= 0:
            continue
        nm = 1
        members[0] = s
        n = 3
        for k in range(3):
            poly[k] = tri[s, k]
            phe[k] = 3 * s + k
        gmin = amin[s]
        px = 0.0
        py = 0.0
        while nm < max_group:
            grown = False
            for i in range(n):
                y, kg = _across(tri, twin, pinned, poly, phe, n, i)
                if y < 0 or cyc[y] >= 0 or group[y] >= 0 or (nm == 1 and group[y] == LONE):
                    continue  # (a lone start tried this pair's fan already: the same fan)
                dup = False
                for j in range(nm):
                    if members[j] == y:
                        dup = True
                if dup:
                    continue
                # insert w between poly[i] and poly[i + 1]: edges (a, w), (w, b) of y
                _with_apex(tri, poly, phe, n, i, y, kg, tpoly, tphe)
                x0, y0, sl, gm, ok = _fan_with(pts, tri, tpoly, n + 1, members, nm, y, min(gmin, amin[y]), px, py,
                                               nm > 1, keep, hi, floor, hi_fan, iters, starts)
                if not ok:
                    continue
                members[nm] = y
                nm += 1
                n += 1
                for j in range(n):
                    poly[j] = tpoly[j]
                    phe[j] = tphe[j]
                gmin = gm
                px = x0
                py = y0
                grown = True
                break
            if not grown:
                break
        if nm < 2:
            group[s] = LONE
            lone[n_lone] = s
            n_lone += 1
            continue
        y_in = -1
        if absorb and nm < max_group:
            y_in, iw, px, py, gmin, n = _absorb_covered(
                pts, tri, twin, pinned, cyc, is_cov, group, amin, keep, hi, floor, hi_fan, iters, poly, phe, n,
                members, nm, gmin, px, py, tpoly, tphe, starts,
            )
            if y_in >= 0:
                group[y_in] = ng
                absorbed[ng] = y_in
                apex[ng] = iw
        for j in range(nm):
            group[members[j]] = ng
        fan_pt[ng, 0] = px
        fan_pt[ng, 1] = py
        gmin_out[ng] = gmin
        for j in range(n):
            corners[n_c] = poly[j]
            hes[n_c] = phe[j]
            n_c += 1
        ng += 1
        off[ng] = n_c
    for j in range(n_lone):
        if group[lone[j]] == LONE:  # (a later group may have taken it in)
            group[lone[j]] = -1
    return group, fan_pt[:ng], gmin_out[:ng], off[: ng + 1], corners[:n_c], hes[:n_c], absorbed[:ng], apex[:ng]


@njit(cache=True, nogil=True)
def _absorb_covered(pts, tri, twin, pinned, cyc, is_cov, group, amin, keep, hi, floor, hi_fan, iters, poly, phe, n,
                    members, nm, gmin, px, py, tpoly, tphe, starts):
    """The best covered triangle a fan group can take in (``fan_groups``), in place.

    A candidate ``y`` lies across a free polygon edge that is ``y``'s non-cover edge,
    its apex is not a corner yet, and the fan over the grown polygon keeps the group's
    bounds (every angle ``>= max(floor, 1/2 x the smallest of the parents)``, ``<=
    hi_fan``); of several, the largest slack. Returns ``(y or -1, index of y's apex in
    the polygon, fan point x, y, group minimum, corners)``; with a ``y`` ``poly`` and
    ``phe`` hold the grown polygon.
    """
    best_y = -1
    best_i = -1
    best_sl = -np.inf
    bx = px
    by = py
    for i in range(n):
        y, kg = _across(tri, twin, pinned, poly, phe, n, i)
        if y < 0 or cyc[y] < 0 or group[y] >= 0 or is_cov[3 * y + kg]:
            continue
        _with_apex(tri, poly, phe, n, i, y, kg, tpoly, tphe)
        x0, y0, sl, gm, ok = _fan_with(pts, tri, tpoly, n + 1, members, nm, y, min(gmin, amin[y]), px, py, True,
                                       keep, hi, floor, hi_fan, iters, starts)
        if not ok:
            continue
        if sl > best_sl:
            best_sl = sl
            best_y = y
            best_i = i
            bx = x0
            by = y0
    if best_y < 0:
        return -1, -1, px, py, gmin, n
    y = best_y
    i = best_i
    _with_apex(tri, poly, phe, n, i, y, twin[phe[i]] - 3 * y, tpoly, tphe)
    n += 1
    for j in range(n):
        poly[j] = tpoly[j]
        phe[j] = tphe[j]
    return y, i + 1, bx, by, min(gmin, amin[y]), n


@njit(cache=True, nogil=True)
def _cos_at(ox, oy, qx, qy, rx, ry):
    """Cosine of the angle at o of the planar triangle (o, q, r) (2 if degenerate)."""
    ux, uy, vx, vy = _spokes(ox, oy, qx, qy, rx, ry)
    nn = (ux * ux + uy * uy) * (vx * vx + vy * vy)
    if nn <= 0.0:
        return 2.0
    return (ux * vx + uy * vy) / math.sqrt(nn)


@njit(cache=True, nogil=True)
def edge_meets_rule(pts, tri, twin, pinned, h, amin, keep, cos_hi, swaps, edge_splits):
    """Does the swap or the midpoint split over half-edge ``h`` meet the rule?

    By corner cosines (``lo <= angle <= hi`` iff ``cos hi <= cos <= cos lo``), the
    corners a join cuts first (they fail most often), and only the corners it
    changes: in a midpoint split the corners at ``a`` and ``b`` are t's and u's own
    (within the rule by definition) and the two angles at the midpoint on each side
    are supplementary (cosines of opposite sign), so six square roots decide a split
    instead of twelve.

    First the necessary condition (docs/sparse.md): both joins divide the corners
    opposite ``ab`` (the swap's diagonal and the split's spokes run from c and d), so
    each of those must be at least twice the rule's angle (``cos 2x = 2 cos^2 x - 1``):
    t's corner at c decides ~85 % of the edges before u's apex is read.
    """
    t = h // 3
    k = h - 3 * t
    u = twin[h] // 3
    cos_lo = math.cos(keep * min(amin[t], amin[u]))
    cos_2lo = 2.0 * cos_lo * cos_lo - 1.0 + 1e-12  # (margin: never rejects what the full test takes)
    a, b, c = tri[t, k], tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]
    ax, ay, bx, by, cx, cy = pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1]
    if _cos_at(cx, cy, ax, ay, bx, by) > cos_2lo:
        return False
    g = twin[h]
    d = tri[u, (g - 3 * u + 2) % 3]
    dx, dy = pts[d, 0], pts[d, 1]
    if _cos_at(dx, dy, bx, by, ax, ay) > cos_2lo:
        return False
    if swaps and not pinned[h]:
        if swap_is_convex_2d(ax, ay, bx, by, cx, cy, dx, dy):
            # (a, d, c) and (d, b, c): the cut corners at c and d first, then the merged ones
            ok = True
            for j in range(6):
                if j == 0:
                    x = _cos_at(cx, cy, ax, ay, dx, dy)
                elif j == 1:
                    x = _cos_at(dx, dy, cx, cy, ax, ay)
                elif j == 2:
                    x = _cos_at(cx, cy, dx, dy, bx, by)
                elif j == 3:
                    x = _cos_at(dx, dy, bx, by, cx, cy)
                elif j == 4:
                    x = _cos_at(ax, ay, dx, dy, cx, cy)
                else:
                    x = _cos_at(bx, by, cx, cy, dx, dy)
                if x > cos_lo or x < cos_hi:
                    ok = False
                    break
            if ok:
                return True
    if not edge_splits:
        return False
    mx = 0.5 * (ax + bx)
    my = 0.5 * (ay + by)
    for j in range(6):
        if j == 0:  # at c in (a, M, c), then in (M, b, c)
            x = _cos_at(cx, cy, ax, ay, mx, my)
        elif j == 1:
            x = _cos_at(cx, cy, mx, my, bx, by)
        elif j == 2:  # at d in (M, a, d), then in (b, M, d)
            x = _cos_at(dx, dy, mx, my, ax, ay)
        elif j == 3:
            x = _cos_at(dx, dy, bx, by, mx, my)
        elif j == 4:  # at M on t's side; (M, b, c) has its supplement
            x = _cos_at(mx, my, cx, cy, ax, ay)
        else:  # at M on u's side
            x = _cos_at(mx, my, ax, ay, dx, dy)
        if x > cos_lo or x < cos_hi:
            return False
        if j >= 4 and (-x > cos_lo or -x < cos_hi):
            return False
    return True


#: Radians a corner may miss the necessary test by in :func:`corners_rule_out` and
#: still go to the full test: covers the float32 rounding of ``corners`` (~3e-7 rad)
#: and atan2 against the full test's cosines with room to spare.
CORNER_MARGIN = 1e-5


@njit(cache=True, nogil=True)
def corners_rule_out(corners, twin, h, amin, keep):
    """Do the corners opposite inner half-edge ``h`` alone prove that no swap or split
    over it meets the rule? (:func:`edge_meets_rule`'s necessary test, both corners
    opposite ``ab`` >= twice the rule's angle, read off ``corners``, the angles
    :func:`triangle_min_max_into` measured, less ``CORNER_MARGIN``: never True where
    :func:`edge_meets_rule` would say yes.) No point, vertex or cosine is read: the
    test that rejects ~85 % of the edges the cover's matching asks about, at two
    rows of ``corners``."""
    t = h // 3
    g = twin[h]
    u = g // 3
    need = 2.0 * keep * min(amin[t], amin[u]) - CORNER_MARGIN
    return corners[t, (h - 3 * t + 2) % 3] < need or corners[u, (g - 3 * u + 2) % 3] < need


@njit(cache=True, nogil=True)
def good_edges_into(pts, tri, twin, pinned, he, amin, keep, hi, swaps, edge_splits, good):
    """``good[i]``: does the swap or the midpoint split over half-edge ``he[i]`` meet the rule?

    Planar only; the yes/no of :func:`score_joins_into` without placement, by cosines
    (:func:`edge_meets_rule`).
    """
    cos_hi = math.cos(hi)
    for i in range(he.shape[0]):
        good[i] = edge_meets_rule(pts, tri, twin, pinned, he[i], amin, keep, cos_hi, swaps, edge_splits)


#: Step halvings of the placement in :func:`placed_good_into` (as ``sparse.PLACE_ITERS``).
PLACE_GOOD_ITERS = 6


@njit(cache=True, nogil=True)
def _placed_split_meets(pts, tri, twin, h, amin, keep, hi):
    """Does the split over the free planar half-edge ``h``, its point placed by
    :func:`place_split`, meet the rule? (After the necessary test on the corners
    opposite ``ab``: both >= 2 x the rule's angle.)"""
    t, u, a, b, c, d = quad_corners(tri, twin, h)
    lo = keep * min(amin[t], amin[u])
    ax, ay, bx, by, cx, cy, dx, dy = quad_xy(pts, a, b, c, d)
    cos_2lo = math.cos(min(2.0 * lo, math.pi)) + 1e-12
    if _cos_at(cx, cy, ax, ay, bx, by) > cos_2lo or _cos_at(dx, dy, bx, by, ax, ay) > cos_2lo:
        return False
    x, y, s, smin, smax = place_split(ax, ay, bx, by, cx, cy, dx, dy, lo, hi, PLACE_GOOD_ITERS, True)
    return s >= 0.0


@njit(cache=True, nogil=True)
def good_half_edges_into(pts, tri, twin, pinned, amin, keep, hi, swaps, edge_splits, lo, hi_h, good):
    """:func:`good_edges_into` for every inner edge with a half-edge ``h`` in ``[lo, hi_h)``, ``h < twin[h]``.

    Sets ``good[h]`` and ``good[twin[h]]`` (both halves; ``good`` starts all False): no
    list of inner edges, no scatter afterwards. Threads may share ``good``: each edge
    is judged (and its two bytes written) by the one thread holding its lower half.
    Sparse mode's cover judges only the edges its matching asks about, by the same
    test (``cycle_cover(..., judge=True)``); this whole-mesh pass serves the
    re-colouring of small meshes, which reads every edge.
    """
    cos_hi = math.cos(hi)
    for h in range(lo, hi_h):
        g = twin[h]
        if g > h and edge_meets_rule(pts, tri, twin, pinned, h, amin, keep, cos_hi, swaps, edge_splits):
            good[h] = True
            good[g] = True


class EdgeRule(NamedTuple):
    """What an edge is judged good by (planar): :func:`good_half_edges_into`'s
    arguments, ``cos_hi`` the cosine of its ``hi`` (:func:`cos_of`, as that kernel
    takes it). A numba argument: the cover's greedy matching judges the edges it has
    to choose between by it (:func:`edge_meets_rule` of the edge's lower half-edge,
    ``cycle_cover(..., judge=True)``)."""

    pts: np.ndarray  # (n, 2) float64
    tri: np.ndarray  # (m, 3) int64
    twin: np.ndarray  # (3 m,) int64
    pinned: np.ndarray  # (3 m,) bool
    amin: np.ndarray  # (m,) float64: each triangle's smallest angle, radians
    keep: float
    cos_hi: float
    swaps: bool
    edge_splits: bool
    corners: np.ndarray  # (m, 3) float32: each corner's angle (triangle_min_max_into), or (0, 3): not known


def edge_rule(pts, tri, twin, pinned, amin, keep: float, hi: float, swaps: bool, edge_splits: bool,
              corners=None) -> EdgeRule:
    """An :class:`EdgeRule` with the types its kernels are compiled for (contiguous
    arrays, Python scalars): one compiled version for every caller. ``corners``: the
    corner angles (:func:`triangle_min_max_into`), if known."""
    cn = np.zeros((0, 3), np.float32) if corners is None else np.ascontiguousarray(corners, dtype=np.float32)
    return EdgeRule(np.ascontiguousarray(pts, dtype=np.float64), np.ascontiguousarray(tri, dtype=np.int64),
                    np.ascontiguousarray(twin, dtype=np.int64), np.ascontiguousarray(pinned, dtype=np.bool_),
                    np.ascontiguousarray(amin, dtype=np.float64), float(keep), float(cos_of(float(hi))),
                    bool(swaps), bool(edge_splits), cn)


def no_edge_rule() -> EdgeRule:
    """An :class:`EdgeRule` that is never asked (every edge already judged)."""
    return edge_rule(np.zeros((0, 2)), np.zeros((0, 3), np.int64), np.zeros(0, np.int64), np.zeros(0, np.bool_),
                     np.zeros(0), 0.0, 0.0, False, False)


@njit(cache=True, nogil=True)
def cos_of(x):
    """``math.cos`` as the kernels compute it (:func:`good_half_edges_into`'s ``cos_hi``)."""
    return math.cos(x)


#: the cover's memo of good edges (``_cover_kernels._greedy_matching``, one int8 per
#: half-edge): an edge not judged yet, judged not good, judged good
EDGE_UNKNOWN, EDGE_NOT_GOOD, EDGE_GOOD = 0, 1, 2


@njit(cache=True, nogil=True)
def placed_good_into(pts, tri, twin, pinned, amin, keep, hi, good):
    """Add to ``good`` (both halves) every free inner edge whose split meets the rule
    with its point placed (:func:`_placed_split_meets`): the joins Kruskal can take
    after placement, for ``_recolour_kernels`` (the matching keeps the midpoint's
    judgement: with these among its preferred edges the 16 k corpus got 1.3-1.5 x the
    cycles and 2-6 x the Steiner points)."""
    for h in range(twin.shape[0]):
        g = twin[h]
        if g > h and not good[h] and not pinned[h] and _placed_split_meets(pts, tri, twin, h, amin, keep, hi):
            good[h] = True
            good[g] = True


@njit(cache=True, nogil=True)
def star_polygon(out, twin, pinned, h, poly):
    """The link polygon of the vertex at half-edge ``h = 3 r + j`` (``out[r, j]``), counter-clockwise.

    Walks the star from row ``r`` across the twins of the edges into the vertex.
    Fills ``poly`` and returns its length; 0 if the star is open (a boundary edge),
    touches a pinned edge or holds more than ``poly`` can.
    """
    v = out[h // 3, h % 3]
    cur = h
    n = 0
    while True:
        r = cur // 3
        j = cur - 3 * r
        e_out = 3 * r + j
        e_in = 3 * r + (j + 2) % 3
        if twin[e_out] < 0 or twin[e_in] < 0 or pinned[e_out] or pinned[e_in] or n >= poly.shape[0]:
            return 0
        poly[n] = out[r, (j + 1) % 3]
        n += 1
        g = twin[e_in]  # v -> w in the next row counter-clockwise around v
        if out[g // 3, g % 3] != v:
            return 0
        cur = g
        if cur == h:
            return n


@njit(cache=True, nogil=True)
def move_to_targets(pts, out, twin, pinned, hs, lo, hi, floor, iters):
    """Move the Steiner points at half-edges ``hs`` towards the *global* targets (in place).

    The improvement step moves a point for the local rule (its star's slack against
    ``keep`` x its parents' smallest angle) and never lets the star's smallest angle
    drop. Where a star misses issue 13's absolute targets — an angle below
    ``lo`` (``keep`` x the input's smallest) or above ``hi`` (its largest + 5 degrees) —
    this compass search (Amenta-Bern-Eppstein's placement, see the module docstring)
    maximises ``min(smallest - lo, hi - largest)`` instead: e.g. an incenter sector of
    90 + 35.3 degrees over a boundary edge, whose two 27.4-degree half corners can give
    a little to bring it under the largest angle allowed. A point is moved only if
    that slack grows and the star's smallest angle stays >= ``min(its own, lo)``
    (a star below the target may trade its largest angle only against the target's
    margin, never against its own smallest) and >= ``floor`` (the proven floor).
    Returns the number of points moved.
    """
    poly = np.empty(64, np.int64)
    moved = 0
    for i in range(hs.shape[0]):
        h = hs[i]
        n = star_polygon(out, twin, pinned, h, poly)
        if n < 3:
            continue
        v = out[h // 3, h % 3]
        vx = pts[v, 0]
        vy = pts[v, 1]
        s0, n0, x0 = fan_eval(pts, poly, n, vx, vy, lo, hi)
        if s0 == -np.inf or s0 >= 0.0:
            continue
        d2 = np.inf
        for k in range(n):
            d2 = min(d2, (pts[poly[k], 0] - vx) ** 2 + (pts[poly[k], 1] - vy) ** 2)
        px, py, s1, n1, x1 = compass_search(pts, poly, n, vx, vy, lo, hi, 0.25 * math.sqrt(d2), iters, 4 * iters)
        if s1 > s0 + 1e-12 and n1 >= min(n0, lo) and n1 >= floor:
            pts[v, 0] = px
            pts[v, 1] = py
            moved += 1
    return moved


@njit(cache=True, nogil=True)
def _link_index(links, g):
    """Index of half-edge ``g`` in ``links`` (a ring's few links), -1 if absent."""
    for i in range(links.shape[0]):
        if links[i] == g:
            return i
    return -1


@njit(cache=True, nogil=True, inline="always")
def _link_in_range(links, lo, hi, g):
    """:func:`_link_index` of ``g``, ``lo``/``hi`` the least and greatest link: a walk
    far from the group (most of its steps) is told apart by two comparisons."""
    if g < lo or g > hi:
        return -1
    return _link_index(links, g)


@njit(cache=True, nogil=True)
def cover_exit(twin, is_cov, e):
    """The cover edge by which a cycle leaves the triangle it entered by half-edge
    ``twin[e]`` (the covered half-edge of ``twin[e] // 3`` other than ``twin[e]``),
    -1 where the cycle does not go on: no other cover edge, or it lies on the boundary."""
    g = twin[e]
    x = g // 3
    for k in range(3):
        h = 3 * x + k
        if h != g and is_cov[h]:
            return h if twin[h] >= 0 else -1
    return -1


@njit(cache=True, nogil=True)
def cycle_positions_into(twin, is_cov, pos, plen):
    """Each covered triangle's place along its cover cycle and that cycle's length.

    ``pos[t]`` counts from an arbitrary start of the cycle in its walking direction,
    ``plen[t]`` is the cycle's length (-1 for both off the cover or where the cover
    is not a closed cycle there). With them the outside pairing of a swap's links is
    read off (``pairs_by_position``) instead of walked. O(m).
    """
    m = pos.shape[0]
    for t in range(m):
        pos[t] = -1
        plen[t] = -1
    for s in range(m):
        if pos[s] >= 0:
            continue
        k = 0
        while k < 3 and not is_cov[3 * s + k]:
            k += 1
        if k == 3:
            continue  # (off the cover)
        e = 3 * s + k
        # walk: leave s by e, then by each triangle's other cover edge
        e0 = e
        pos[s] = 0
        n = 1
        closed = False
        while True:
            if twin[e] < 0:
                break
            x = twin[e] // 3
            if x == s:
                closed = True
                break
            if pos[x] >= 0:
                break
            pos[x] = n
            n += 1
            e = cover_exit(twin, is_cov, e)
            if e < 0:
                break
        # second pass: the length (or -1 for a broken walk)
        length = n if closed else -1
        x = s
        e2 = e0
        for i in range(n):
            plen[x] = length
            if not closed:
                pos[x] = -2  # (seen, unusable)
            if i + 1 < n:
                x = twin[e2] // 3
                e2 = cover_exit(twin, is_cov, e2)
    for t in range(m):
        if pos[t] == -2:
            pos[t] = -1


@njit(cache=True, nogil=True)
def pairs_by_position(twin, pos, plen, hs):
    """:func:`ring_outside_pairs`' answer from cycle positions (``cycle_positions_into``).

    ``hs`` are one cycle's links (group side). The outside path from link ``a`` (group
    triangle ``x`` to ``y``) runs along the cycle away from ``x`` until it enters the
    group again, by the link at the first link triangle in that direction whose own
    outside triangle faces back. Returns ``pair`` (-1 everywhere if a position is
    missing).
    """
    n = hs.shape[0]
    pair = np.full(n, -1, np.int64)
    xs = np.empty(n, np.int64)
    ds = np.empty(n, np.int64)
    for a in range(n):
        x = hs[a] // 3
        y = twin[hs[a]] // 3
        L = plen[x]
        if L <= 0 or pos[x] < 0 or pos[y] < 0 or plen[y] != L:
            return np.full(n, -1, np.int64)
        xs[a] = x
        ds[a] = 1 if (pos[y] - pos[x]) % L == 1 else -1
    for a in range(n):
        L = plen[xs[a]]
        best = -1
        bd = L + 1
        for b in range(n):
            if b == a or ds[b] != -ds[a]:
                continue
            d = ((pos[xs[b]] - pos[xs[a]]) * ds[a]) % L
            if d == 0:
                d = L
            if d < bd:
                bd = d
                best = b
        if best < 0:
            return np.full(n, -1, np.int64)
        pair[a] = best
    for a in range(n):
        if pair[pair[a]] != a:
            return np.full(n, -1, np.int64)  # (not a matching: positions stale)
    return pair


@njit(cache=True, nogil=True, inline="always")
def pair_last_two(pair):
    """Pair the two links a walk left unpaired (``pair`` -1: the rest are paired, so
    they can only join each other) and return the first of them (the deduced pair)."""
    a = -1
    for i in range(pair.shape[0]):
        if pair[i] < 0:
            if a < 0:
                a = i
            else:
                pair[a] = i
                pair[i] = a
    return a


@njit(cache=True, nogil=True)
def ring_outside_pairs(twin, is_cov, links, budget):
    """Which links of a ring fan's group the cover cycles join *outside* the group.

    ``links`` are the group's outer half-edges (member side) that carry a cover edge;
    each is followed outwards along its cycle (through covered triangles, by the
    cover edge other than the one it came in by) until the cycle re-enters the group
    by another link. All walks advance in lock-step and a walk stops when its path is
    found from its other end, so the cost is about the links times the *second*
    longest outside path: the last two links left pair with each other without
    walking the longest (a cycle around the whole mesh costs nothing). Local where
    ``cycle_ids`` would relabel every triangle (``sparse._ring_outcome``).

    Returns ``(pair, deduced)``: ``pair`` (int64, one per link; -1 where ``budget``
    steps in all did not decide it) and the link of the pair found without walking
    its path (-1 if every path was walked).
    """
    n = links.shape[0]
    pair = np.full(n, -1, np.int64)
    deduced = -1
    cur = links.copy()  # the half-edge each walk last crossed, on the side it came from
    lo, hi = links.min(), links.max()
    left = n
    steps = 0
    while left > 2 and steps < budget:
        for i in range(n):
            if pair[i] >= 0:
                continue
            f = cover_exit(twin, is_cov, cur[i])
            steps += 1
            if f < 0:
                return np.full(n, -1, np.int64), -1  # not a closed cycle: undecided
            j = _link_in_range(links, lo, hi, twin[f])
            if j >= 0:
                if j != i and pair[j] < 0:
                    pair[i] = j
                    pair[j] = i
                    left -= 2
                else:
                    return np.full(n, -1, np.int64), -1
            else:
                cur[i] = f
    if left == 2:
        deduced = pair_last_two(pair)
    return pair, deduced


#: a walk memo's table rows (a power of two; at most half of them used) and steps
#: (``new_walk_memo``); at 1.5 M triangles the swap tests of one cover start ~900
#: distinct walks, most under 2 k steps
WALK_MEMO_ROWS = 1 << 11
WALK_MEMO_STEPS = 1 << 19
#: the first room a walk's steps get in the memo (then doubled where it outgrows it)
WALK_MEMO_CHUNK = 256


class WalkMemo(NamedTuple):
    """The cover walks one thread made from border half-edges (:func:`ring_outside_pairs_memo`).

    ``table (rows, 4) int64``: per start half-edge (open addressing on column 0, -1
    empty) the offset, count and room of its steps in ``steps (k,) int64``, each the
    half-edge the walk entered (the twin of the cover edge it left by; -1: the cycle
    does not go on); ``state (2,) int64``: the steps' top and the rows used. Valid
    for one cover: cleared (:func:`clear_walk_memo`) when the cover changes.
    """

    table: np.ndarray
    steps: np.ndarray
    state: np.ndarray


def new_walk_memo(rows: int = WALK_MEMO_ROWS, steps: int = WALK_MEMO_STEPS) -> WalkMemo:
    """An empty :class:`WalkMemo` (``rows`` a power of two); ``steps`` 0: none (plain walks)."""
    memo = WalkMemo(np.empty((rows, 4), np.int64), np.empty(steps, np.int64), np.zeros(2, np.int64))
    clear_walk_memo(memo)
    return memo


def clear_walk_memo(memo: WalkMemo) -> None:
    """Forget every walk (the cover changed)."""
    memo.table[:, 0] = -1
    memo.state[:] = 0


@njit(cache=True, nogil=True)
def _memo_row(table, state, h):
    """``table``'s row of start half-edge ``h``, made (no steps yet) where it has none;
    -1 if the table is half full (the walk is then not kept)."""
    mask = table.shape[0] - 1
    i = (h * 0x9E3779B1) & mask
    while table[i, 0] >= 0:
        if table[i, 0] == h:
            return i
        i = (i + 1) & mask
    if 2 * (state[1] + 1) > table.shape[0]:
        return -1
    table[i, 0] = h
    table[i, 1] = 0
    table[i, 2] = 0
    table[i, 3] = 0
    state[1] += 1
    return i


@njit(cache=True, nogil=True, inline="always")
def _entered_next(twin, is_cov, g):
    """The half-edge a cover walk enters next after entering by ``g``: ``twin`` of
    ``cover_exit`` (-1 where the cycle does not go on)."""
    x = g // 3
    for k in range(3):
        h = 3 * x + k
        if h != g and is_cov[h]:
            return twin[h] if twin[h] >= 0 else -1
    return -1


@njit(cache=True, nogil=True)
def _memo_keep(table, steps, state, row, g):
    """Append step ``g`` to memo row ``row`` (its count of steps is the step's index):
    in its room, else grown in place where it is the last row, else moved to the top
    with twice the room; not kept where the memo is full. Returns the row's offset."""
    off, n, cap = table[row, 1], table[row, 2], table[row, 3]
    if n == cap:
        top = state[0]
        if cap > 0 and off + cap == top:  # the last row: grow in place
            grow = min(cap, steps.shape[0] - top)
            table[row, 3] = cap + grow
            state[0] = top + grow
        else:
            room = max(2 * cap, WALK_MEMO_CHUNK)
            if top + room <= steps.shape[0]:
                for i in range(n):
                    steps[top + i] = steps[off + i]
                table[row, 1] = top
                table[row, 3] = room
                state[0] = top + room
        off, cap = table[row, 1], table[row, 3]
    if n < cap:
        steps[off + n] = g
        table[row, 2] = n + 1
    return off


@njit(cache=True, nogil=True)
def ring_outside_pairs_memo(twin, is_cov, links, budget, table, steps, state):
    """:func:`ring_outside_pairs` (the same answer, the same lock-step budget) with
    each link's walk read from a :class:`WalkMemo` where an earlier call on this
    cover walked it (the swap tests of one cover walk the same links again and again:
    at 1.5 M triangles 71 % of the slow tests' walk starts; a step read from the memo
    is one read in a row where a walk's is two scattered ones), and kept there."""
    n = links.shape[0]
    pair = np.full(n, -1, np.int64)
    deduced = -1
    rows = np.empty(n, np.int64)
    off = np.zeros(n, np.int64)  # where each walk's kept steps start
    have = np.zeros(n, np.int64)  # how many there are (the row's count, while it grows)
    room = np.zeros(n, np.int64)  # and room for
    cur = np.empty(n, np.int64)  # the half-edge each walk entered last
    done = np.zeros(n, np.int64)  # its steps
    for i in range(n):
        r = _memo_row(table, state, links[i])
        rows[i] = r
        if r >= 0:
            off[i] = table[r, 1]
            have[i] = table[r, 2]
            room[i] = table[r, 3]
        cur[i] = twin[links[i]]
    lo, hi = links.min(), links.max()
    left = n
    n_steps = 0
    while left > 2 and n_steps < budget:
        for i in range(n):
            if pair[i] >= 0:
                continue
            k = done[i]
            if k < have[i]:
                g = steps[off[i] + k]
            else:
                g = _entered_next(twin, is_cov, cur[i])
                if k == have[i] and rows[i] >= 0:  # (the walk is the row's longest: kept)
                    r = rows[i]
                    if k < room[i]:
                        steps[off[i] + k] = g
                        table[r, 2] = k + 1
                    else:
                        off[i] = _memo_keep(table, steps, state, r, g)
                        room[i] = table[r, 3]
                    have[i] = table[r, 2]
            done[i] = k + 1
            n_steps += 1
            if g < 0:
                return np.full(n, -1, np.int64), -1  # not a closed cycle: undecided
            j = _link_in_range(links, lo, hi, g)
            if j >= 0:
                if j != i and pair[j] < 0:
                    pair[i] = j
                    pair[j] = i
                    left -= 2
                else:
                    return np.full(n, -1, np.int64), -1
            else:
                cur[i] = g
    if left == 2:
        deduced = pair_last_two(pair)
    return pair, deduced


@njit(cache=True, nogil=True)
def label_outside_into(twin, is_cov, start, links, out, value):
    """``out[x] = value`` for every triangle on the cover's path from link ``start``
    outwards until it re-enters the group by one of ``links`` (as
    ``ring_outside_pairs`` walks it): a piece of a cycle the group split off.
    Returns the link index it re-entered by (-1: not a closed path)."""
    cur = start
    while True:
        out[twin[cur] // 3] = value
        f = cover_exit(twin, is_cov, cur)
        if f < 0:
            return -1
        j = _link_index(links, twin[f])
        if j >= 0:
            return j
        cur = f


@njit(cache=True, nogil=True)
def relabel_cycles_into(cycle, lut):
    """``cycle[t] = lut[cycle[t]]`` for covered triangles (in place): new cycle ids after
    ring fans merged some (``sparse._apply_rings``)."""
    for t in range(cycle.shape[0]):
        c = cycle[t]
        if c >= 0:
            cycle[t] = lut[c]


def load_ring_kernels() -> None:
    """Load (or compile) the kernels only ring fans, ring joins, re-routes and cover swaps
    reach (``ring_outside_pairs``, ``label_outside_into``, ``relabel_cycles_into``,
    ``alternating_cycles_into``, ``swap_merge_outcome``, the ring fans' polygon and
    point with ``place_fan``, the improvement step's ``move_to_targets``), on two
    triangles: ``hammesh.postprocess.load_kernels``' small mesh leaves no triangle
    off its cover, so those steps do not run there."""
    twin = np.array([3, 4, -1, 0, 1, -1], np.int64)
    is_cov = np.array([True, True, False, True, True, False])
    links = np.array([0, 1], np.int64)
    ring_outside_pairs(twin, is_cov, links, 0)
    out = np.zeros(2, np.int64)
    label_outside_into(twin, is_cov, 0, links, out, 0)
    relabel_cycles_into(out, np.zeros(1, np.int64))
    # the cover swaps' search and test (``sparse._alternating_merges``): the two
    # triangles again, their third edges joined (not on the cover)
    twin = np.array([3, 4, 5, 0, 1, 2], np.int64)
    buf = np.empty(8, np.int64)
    starts = np.empty(3, np.int64)
    alternating_cycles_into(twin, is_cov, np.zeros(2, np.bool_), 2, 4, 16, buf, starts, 2)
    pos = np.empty(2, np.int64)
    plen = np.empty(2, np.int64)
    cycle_positions_into(twin, is_cov, pos, plen)
    for p in (pos, np.empty(0, np.int64)):
        swap_merge_outcome(twin, is_cov, np.zeros(2, np.int64), np.zeros(1, np.int64), buf[:2], np.arange(2), 0, 0, 0,
                           True, p, plen, *new_walk_memo(2, 0 if len(p) else 8))
    # the ring fans' polygon and point (``sparse._union_polygon``, ``_best_ring``; since
    # session 14's re-colouring the covers of small meshes reach them): two triangles
    from hammesh.postprocess import _sparse_kernels as _sk  # (at call time: it imports this module)

    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    tri = np.array([[0, 1, 2], [2, 1, 3]], np.int64)
    twin = np.array([-1, 3, -1, 1, -1, -1], np.int64)
    poly, hes = np.empty(4, np.int64), np.empty(4, np.int64)
    members = np.arange(2, dtype=np.int64)
    n = _sk.union_polygon_into(tri, twin, np.zeros(6, np.bool_), members, poly, hes)
    for amin, keep in ((np.zeros(0), 0.0), (np.full(2, 0.5), 0.9)):
        _sk.ring_fan_point(pts, tri, members, poly, int(n), amin, keep, 0.1, 2.5, 2, 0.0)
    # the improvement step's repair of rows missing the absolute targets
    # (``sparse._repair_targets``: a first call at 1.5 M loaded it, 5-14 ms)
    move_to_targets(pts, tri, twin, np.zeros(6, np.bool_), np.zeros(0, np.int64), 0.1, 2.5, 0.05, 2)


@njit(cache=True, nogil=True)
def _fan_slack(pts, poly, n, px, py, lo, hi):
    """:func:`fan_eval`'s slack alone (exact angles; ``-inf`` off the kernel)."""
    return fan_eval(pts, poly, n, px, py, lo, hi)[0]


@njit(cache=True, nogil=True)
def _near_active_gradients(pts, poly, n, px, py, lo, hi, level, grads):
    """Gradients (in ``p``) of the fan's angle constraints within ``level`` of binding.

    Each triangle ``(p, a, b)`` of the fan has its angles at ``a``, ``b`` and ``p`` as
    functions of ``p``: ``arg(p - a) - arg(b - a)`` grows along ``perp(p - a) / |p - a|^2``,
    the angle at ``b`` along ``-perp(p - b) / |p - b|^2`` and the angle at ``p`` along
    minus their sum. Constraint ``angle - lo`` has that gradient, ``hi - angle`` its
    negative. Fills ``grads[:k]`` with the gradients of the constraints whose value is
    ``<= level`` and returns ``k``.
    """
    k = 0
    for i in range(n):
        ax, ay, bx, by, _ = _fan_edge(pts, poly, n, i, px, py)
        wax = px - ax
        way = py - ay
        wbx = px - bx
        wby = py - by
        ra = wax * wax + way * way
        rb = wbx * wbx + wby * wby
        gax = -way / ra
        gay = wax / ra
        gbx = wby / rb
        gby = -wbx / rb
        t_a = _corner2(ax, ay, bx, by, px, py)
        t_b = _corner2(bx, by, px, py, ax, ay)
        t_p = math.pi - t_a - t_b
        for j in range(3):
            if j == 0:
                th, gx, gy = t_a, gax, gay
            elif j == 1:
                th, gx, gy = t_b, gbx, gby
            else:
                th, gx, gy = t_p, -gax - gbx, -gay - gby
            if th - lo <= level and k < grads.shape[0]:
                grads[k, 0] = gx
                grads[k, 1] = gy
                k += 1
            if hi - th <= level and k < grads.shape[0]:
                grads[k, 0] = -gx
                grads[k, 1] = -gy
                k += 1
    return k


@njit(cache=True, nogil=True)
def _steepest_minmax_direction(grads, k):
    """The unit direction ``d`` maximising ``min_i grads[i] . d`` over ``i < k``, and that value.

    In the plane the optimum is either one gradient's direction or a direction at which
    two of the linear functions are equal (perpendicular to their difference): every
    candidate is tried (``k`` is a handful). A value ``<= 0`` means no direction improves
    every near-binding constraint: the point is stationary for this active set.
    """
    best = -np.inf
    dx = 0.0
    dy = 0.0
    for c in range(k + 2 * k * k):
        if c < k:
            cx = grads[c, 0]
            cy = grads[c, 1]
        else:
            q = c - k
            i = q // (2 * k)
            r = q - 2 * k * i
            j = r // 2
            if j <= i:
                continue
            ex = grads[i, 0] - grads[j, 0]
            ey = grads[i, 1] - grads[j, 1]
            cx = -ey if r % 2 == 0 else ey
            cy = ex if r % 2 == 0 else -ex
        nn = math.sqrt(cx * cx + cy * cy)
        if nn <= 0.0:
            continue
        cx /= nn
        cy /= nn
        v = np.inf
        for i in range(k):
            v = min(v, grads[i, 0] * cx + grads[i, 1] * cy)
        if v > best:
            best = v
            dx = cx
            dy = cy
    return dx, dy, best


#: the ridge ascent's limits: line searches, and the active set's widest margin (radians)
RIDGE_ITERS = 256
RIDGE_LEVEL = 1e-2


@njit(cache=True, nogil=True)
def ridge_ascent(pts, poly, n, px, py, lo, hi, step):
    """Climb the fan's slack from ``(px, py)`` along its ridges (Amenta-Bern-Eppstein's optimum).

    The slack is the minimum of a few smooth functions (the angles against ``lo`` and
    ``hi``); where two of them bind, a compass search's eight fixed directions may all
    fall off the ridge between them and it stops short of the optimum (on ``la``'s
    splits by up to 0.8 degrees). Here each step takes the constraints within a margin
    of binding, moves along the direction that raises all of them fastest
    (:func:`_steepest_minmax_direction`) with a halving line search, and narrows the
    margin when no direction raises them all: an epsilon-subgradient ascent, which ends
    at the maximum of a quasi-concave slack (ABE: the angle constraints are; the
    largest-angle ones at the point itself are not, so this is a local maximum there).
    Returns ``(x, y, slack)`` judged on exact angles, never worse than the start.
    """
    best = _fan_slack(pts, poly, n, px, py, lo, hi)
    if best == -np.inf:
        return px, py, best
    grads = np.empty((6 * n, 2))
    level = RIDGE_LEVEL
    h = step
    min_step = 1e-9 * step
    for _ in range(RIDGE_ITERS):
        k = _near_active_gradients(pts, poly, n, px, py, lo, hi, best + level, grads)
        dx, dy, rate = _steepest_minmax_direction(grads, k)
        if not rate > 0.0:
            level *= 0.1
            if level < 1e-9:
                break
            continue
        t = h
        moved = False
        while t >= min_step:
            s = _fan_slack(pts, poly, n, px + t * dx, py + t * dy, lo, hi)
            if s > best:
                best = s
                px += t * dx
                py += t * dy
                moved = True
                break
            t *= 0.5
        if moved:
            h = 2.0 * t
        else:
            level *= 0.1
            if level < 1e-9:
                break
    return px, py, best


@njit(cache=True, nogil=True)
def _on_path(nodes, n, x):
    for i in range(n):
        if nodes[i] == x:
            return True
    return False


#: slots of ``_back_distances``' table (a power of two) and most triangles it labels
BACK_SLOTS = 1 << 15
BACK_MAX = 1 << 13


@njit(cache=True, nogil=True)
def _dist_get(keys, vals, x, far):
    """``x``'s distance in ``_back_distances``' table, ``far`` if it has none."""
    mask = keys.shape[0] - 1
    i = (x * 0x9E3779B1) & mask
    while keys[i] >= 0:
        if keys[i] == x:
            return vals[i]
        i = (i + 1) & mask
    return far


@njit(cache=True, nogil=True)
def _back_distances(twin, blocked, t, radius):
    """Dual distances from ``t`` through triangles not ``blocked``, up to ``radius``.

    An open-addressing table (``BACK_SLOTS`` slots, no O(m) array per call) of at most
    ``BACK_MAX`` triangles, breadth-first: a triangle not in it is at least ``far``
    away (one more than the last whole layer). Returns ``(keys, vals, far)`` for
    :func:`_dist_get`.
    """
    keys = np.full(BACK_SLOTS, -1, np.int64)
    vals = np.empty(BACK_SLOTS, np.int64)
    queue = np.empty(BACK_MAX, np.int64)
    mask = BACK_SLOTS - 1
    i = (t * 0x9E3779B1) & mask
    keys[i] = t
    vals[i] = 0
    queue[0] = t
    head = 0
    tail = 1
    far = radius + 1
    while head < tail:
        x = queue[head]
        head += 1
        dx = _dist_get(keys, vals, x, far)
        if dx >= radius:
            break
        for k in range(3):
            g = twin[3 * x + k]
            if g < 0:
                continue
            y = g // 3
            if blocked[y] and y != t:
                continue
            j = (y * 0x9E3779B1) & mask
            found = False
            while keys[j] >= 0:
                if keys[j] == y:
                    found = True
                    break
                j = (j + 1) & mask
            if found:
                continue
            if tail == BACK_MAX:
                return keys, vals, dx + 1  # (the layer after dx is not whole)
            keys[j] = y
            vals[j] = dx + 1
            queue[tail] = y
            tail += 1
    return keys, vals, far


@njit(cache=True, nogil=True)
def alternating_cycles_into(twin, is_cov, blocked, h0, depth, budget, out, starts, max_cycles):
    """Alternating cycles of the cover through its non-cover half-edge ``h0`` (``t -> u``), shorter first.

    From ``u`` a cover edge to ``y``, ``y``'s non-cover edge to ``z``, a cover edge
    from ``z``, ... until a cover edge ends at ``t``: swapping cover and non-cover
    along such a cycle leaves every triangle on it with two cover edges (a rotation
    around a vertex is the shortest kind). Depth-first over the pairs ``(y, z)``,
    each triangle at most once per cycle and none with ``blocked`` set, deepened by 4
    pairs at a time up to ``depth`` pairs (the shortest cycles often split some cover
    cycle: the caller judges each in turn), at most ``budget`` steps in all. Writes
    each cycle's half-edges whose cover state the swap changes (one per edge, ``h0``
    first) to ``out[starts[i]:starts[i + 1]]``; returns the number of cycles (at most
    ``max_cycles``).
    """
    t = h0 // 3
    u = twin[h0] // 3
    nodes = np.empty(2 * depth + 2, np.int64)
    flips = np.empty(2 * depth + 2, np.int64)
    stack_x = np.empty(depth + 1, np.int64)
    stack_j = np.empty(depth + 1, np.int64)
    # dual distances back to t (through triangles a cycle may pass): a pair at z with
    # r pairs left can close only if z is within 2 r + 1 steps of t, so the search's
    # budget goes to paths that can still return (``_back_distances``)
    keys, vals, far = _back_distances(twin, blocked, t, 2 * depth + 1)
    n_out = 0
    starts[0] = 0
    steps = 0
    for limit in range(4, depth + 1, 4):
        level = 0
        stack_x[0] = u
        stack_j[0] = 0
        nodes[0] = t
        nodes[1] = u
        n_nodes = 2
        flips[0] = h0
        n_fl = 1
        while level >= 0:
            x = stack_x[level]
            j = stack_j[level]
            if j == 3:
                level -= 1
                n_nodes -= 2
                n_fl -= 2
                continue
            stack_j[level] = j + 1
            f = 3 * x + j
            if not is_cov[f] or twin[f] < 0:
                continue
            steps += 1
            if steps > budget:
                return n_out
            y = twin[f] // 3
            if y == t:
                # new at this depth (the shallower ones were written before)
                if (level > limit - 4 or limit == 4) and starts[n_out] + n_fl + 1 <= out.shape[0]:
                    p = starts[n_out]
                    for i in range(n_fl):
                        out[p + i] = flips[i]
                    out[p + n_fl] = f
                    starts[n_out + 1] = p + n_fl + 1
                    n_out += 1
                    if n_out == max_cycles:
                        return n_out
                continue
            if level >= limit or blocked[y] or _on_path(nodes, n_nodes, y):
                continue
            g = -1
            for i in range(3):
                if not is_cov[3 * y + i]:
                    g = 3 * y + i
                    break
            if g < 0 or twin[g] < 0:
                continue  # (y's non-cover edge is on the boundary)
            z = twin[g] // 3
            if blocked[z] or _on_path(nodes, n_nodes, z):
                continue
            if _dist_get(keys, vals, z, far) > 2 * (limit - level - 1) + 1:
                continue  # (z cannot get back to t within this depth)
            nodes[n_nodes] = y
            nodes[n_nodes + 1] = z
            n_nodes += 2
            flips[n_fl] = f
            flips[n_fl + 1] = g
            n_fl += 2
            level += 1
            stack_x[level] = z
            stack_j[level] = 0
    return n_out


@njit(cache=True, nogil=True)
def _index_of(a, n, x):
    for i in range(n):
        if a[i] == x:
            return i
    return -1


@njit(cache=True, nogil=True)
def _root_of(root, c):
    while root[c] != c:
        c = root[c]
    return c


@njit(cache=True, nogil=True)
def swap_only_merges(twin, is_cov, cyc, root, flips, group, ca, cb, budget, any_merge):
    """Does swapping the cover along ``flips`` make cycles ``ca`` and ``cb`` one and leave every
    other cycle crossing ``group`` one cycle of its own? (:func:`swap_merge_outcome`'s
    first answer; ``any_merge``: its second, True wherever no cycle splits and some merge)."""
    none = np.empty(0, np.int64)
    return swap_merge_outcome(twin, is_cov, cyc, root, flips, group, ca, cb, budget, any_merge, none, none,
                              np.empty((0, 4), np.int64), none, none) > 0


@njit(cache=True, nogil=True)
def swap_merge_outcome(twin, is_cov, cyc, root, flips, group, ca, cb, budget, wide, pos, plen, m_table, m_steps,
                       m_state):
    """Does swapping the cover along ``flips`` make cycles ``ca`` and ``cb`` one and leave every
    other cycle crossing ``group`` one cycle of its own? (``sparse._alternating_merges``' test)

    ``flips``: one half-edge per edge whose cover state the swap changes; ``group``:
    their triangles; a triangle's cycle is ``root``'s root of ``cyc[t]``. As
    ``sparse._swap_outcome`` decides it (links: cover edges across the group's border;
    outside, each cycle pairs its links, walked in lock-step by
    :func:`ring_outside_pairs` where it crosses more than once; inside, the swapped
    cover pairs them; the new cycles are the components of both pairings), without
    building the outcome: not where a walk is undecided within ``budget``, a cycle
    would split or lie wholly inside the group, or a third cycle would merge.

    Returns 1 if so; else, with ``wide``, 2 wherever no cycle splits and some merge
    (which ones is the caller's to read off ``sparse._swap_outcome``); else 0. Both
    answers come from one walk: the caller asking the wider question where the first
    fails walked the same cycles twice before (session 12: 725 tests at 1.5 M, 40 % of
    them the wider one).

    With ``pos`` and ``plen`` (``cycle_positions_into`` on this cover; empty: walk)
    the outside pairing is read off the positions (``pairs_by_position``): no walk, no
    budget, so no check is left undecided. Else the walks go through the
    :class:`WalkMemo` ``m_table``, ``m_steps``, ``m_state`` of this cover
    (:func:`ring_outside_pairs_memo`; empty ``m_steps``: plain walks), the same answers.
    """
    ng = group.shape[0]
    nf = flips.shape[0]
    links = np.empty(3 * ng, np.int64)
    nl = 0
    for gi in range(ng):
        x = group[gi]
        for k in range(3):
            h = 3 * x + k
            g = twin[h]
            if g >= 0 and is_cov[h] and _index_of(group, ng, g // 3) < 0:
                links[nl] = h
                nl += 1
    ids = np.empty(nl, np.int64)
    for i in range(nl):
        ids[i] = _root_of(root, cyc[twin[links[i]] // 3])
    for gi in range(ng):
        if _index_of(ids, nl, _root_of(root, cyc[group[gi]])) < 0:
            return 0  # a cycle wholly inside the group: it would merge unseen
    inp = np.full(nl, -1, np.int64)
    seen = np.zeros(ng, np.bool_)
    for i in range(nl):
        if inp[i] >= 0:
            continue
        came = links[i]
        while True:
            x = came // 3
            seen[_index_of(group, ng, x)] = True
            f = -1
            for k in range(3):
                h = 3 * x + k
                if h == came:
                    continue
                flipped = _index_of(flips, nf, h) >= 0 or _index_of(flips, nf, twin[h]) >= 0
                if is_cov[h] != flipped:
                    if f >= 0:
                        return 0
                    f = h
            if f < 0 or twin[f] < 0:
                return 0
            if _index_of(group, ng, twin[f] // 3) < 0:
                j = _index_of(links, nl, f)
                inp[i] = j
                inp[j] = i
                break
            came = twin[f]
    for gi in range(ng):
        if not seen[gi]:
            return 0  # a new cycle wholly inside the group
    # cheap refusals before any walk: an inside path between two other cycles merges
    # them (not the first answer); none between ca and cb merges nothing wanted
    narrow = True
    joins = joins_any = False
    for i in range(nl):
        a = ids[i]
        b = ids[inp[i]]
        if a != b:
            joins_any = True
            if (a == ca and b == cb) or (a == cb and b == ca):
                joins = True
            else:
                narrow = False
    narrow = narrow and joins
    wide = wide and joins_any
    if not (narrow or wide):
        return 0
    outp = np.full(nl, -1, np.int64)
    sel = np.empty(nl, np.int64)
    for i in range(nl):
        if outp[i] >= 0:
            continue
        ns = 0
        for j in range(nl):
            if ids[j] == ids[i]:
                sel[ns] = j
                ns += 1
        if ns == 2:
            outp[sel[0]] = sel[1]
            outp[sel[1]] = sel[0]
            continue
        hs = np.empty(ns, np.int64)
        for a in range(ns):
            hs[a] = links[sel[a]]
        if pos.shape[0]:
            pair = pairs_by_position(twin, pos, plen, hs)
        elif m_steps.shape[0]:
            pair, _ = ring_outside_pairs_memo(twin, is_cov, hs, budget, m_table, m_steps, m_state)
        else:
            pair, _ = ring_outside_pairs(twin, is_cov, hs, budget)
        for a in range(ns):
            if pair[a] < 0:
                return 0
            outp[sel[a]] = sel[pair[a]]
    uf = np.arange(nl)
    for i in range(nl):
        for other in (outp[i], inp[i]):
            a = _root_of(uf, i)
            b = _root_of(uf, other)
            if a != b:
                uf[a] = b
    merged = merged_any = False
    for i in range(nl):
        ri = _root_of(uf, i)
        for j in range(i + 1, nl):
            same = ri == _root_of(uf, j)
            if ids[i] == ids[j]:
                if not same:
                    return 0  # a split
            elif same:
                merged_any = True
                if (ids[i] == ca and ids[j] == cb) or (ids[i] == cb and ids[j] == ca):
                    merged = True
                else:
                    narrow = False  # a third cycle merged
    if narrow and merged:
        return 1
    return 2 if wide and merged_any else 0
