"""Compiled loop (numba) of sparse mode's last step: cycle-keeping improvement flips.

After the joins, every triangle a join created (a swap, a split's four, a bridge's
sectors and flips, a fan) is judged against its parents. Where its angles are poor,
a *Lawson flip* of an edge the cycle crosses can help: it merges the small angle with
a neighbour's and re-splits the cavity of two triangles along the other diagonal --
the local re-triangulation of a join's cavity that keeps the cycle.

For two consecutive rows ``x = (a, b, c)``, ``y = (b, a, d)`` of a cycle (the cycle
crosses ``ab``), the flip of ``ab`` into ``cd`` gives ``X = (a, d, c)`` and
``Y = (d, b, c)``. The cycle enters ``x`` across one of ``bc``, ``ca`` and leaves ``y``
across one of ``ad``, ``db``; if those two edges end up in different new triangles
(``ca`` with ``db``, or ``bc`` with ``ad``) the cycle runs through ``X`` and ``Y``
across ``cd`` in the same order: still one Hamiltonian cycle, no other row touched.
An edge the cycle does *not* cross (between two rows of one cycle that are not
consecutive, e.g. an incenter sector's outer edge) is never flipped: in the plane
that always splits the cycle in two (the dual path from ``x`` to ``y`` across the edge
is a chord of the closed curve the cycle draws; each new triangle closes one side of
it). Such an edge could only go with a second flip that joins the two cycles again
(not done).

A flip is taken only if the quadrilateral is strictly convex, neither edge is pinned
(constrained, or between regions), the pair's smallest angle grows and its largest
stays within ``max(hi, the pair's largest)``. The sorted angle vector of the mesh
then grows lexicographically with every flip, so the loop ends (and is capped).

Nopython, ``cache=True``. The flips and the moves are serial (each sees the ones
before it); what each try would do on the rows as they are is worked out on both
cores first (:func:`failing_flips`, :func:`smooth_steiner`), and the serial loop
takes it wherever the rows it read are unchanged (same result, array for array).
"""

from __future__ import annotations

import math

from functools import partial

import numpy as np
from numba import njit

from hammesh import threads
from hammesh.pages import fresh
from hammesh.threads import row_ranges, run_all

from hammesh.postprocess._join_kernels import compass_search, fan_eval, min_max_angles_2d


@njit(cache=True, nogil=True)
def _min_max(pts, a, b, c):
    return min_max_angles_2d(pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1], pts[c, 0], pts[c, 1])


@njit(cache=True, nogil=True)
def _ccw(pts, a, b, c):
    """Strictly counter-clockwise by more than a relative 1e-12 (no near-degenerate flip)."""
    ux = pts[b, 0] - pts[a, 0]
    uy = pts[b, 1] - pts[a, 1]
    vx = pts[c, 0] - pts[a, 0]
    vy = pts[c, 1] - pts[a, 1]
    return ux * vy - uy * vx > 1e-12 * (ux * ux + uy * uy + vx * vx + vy * vy)


@njit(cache=True, nogil=True)
def _set_edge(twin, pinned, h, g, pin):
    twin[h] = g
    pinned[h] = pin
    if g >= 0:
        twin[g] = h


@njit(cache=True, nogil=True)
def _input_edge(tri, t, x, y):
    """Half-edge of input triangle ``t`` from ``x`` to ``y`` or back (-1 if none)."""
    if t < 0:
        return -1
    for k in range(3):
        a = tri[t, k]
        b = tri[t, (k + 1) % 3]
        if (a == x and b == y) or (a == y and b == x):
            return 3 * t + k
    return -1


@njit(cache=True, nogil=True)
def _input_end(v, w, first_mid, mid_a, mid_b):
    """The input vertex standing for ``v`` on the output edge ``(v, w)``: ``v`` itself, or
    if ``v`` is the midpoint of input edge ``(p, q)`` and ``w`` one of its ends, the other
    end. ``(vertex, ok)``; not ok if ``v`` is a midpoint and ``w`` no end of its edge (the
    output edge lies on no input edge)."""
    if first_mid <= v < first_mid + mid_a.shape[0]:
        i = v - first_mid
        if w == mid_a[i]:
            return mid_b[i], True
        if w == mid_b[i]:
            return mid_a[i], True
        return v, False
    return v, True


def pinned_output_edges(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, rows=None, pinned=None):
    """Which output half-edges lie on a pinned interior input edge (whole or a half)?

    A pinned input edge (``con``: constrained, or between regions) with a triangle on
    both sides stays where it is; in the output it is the same edge or, split at its
    midpoint, its two halves. Every output row lies in its ``parent`` (or, a swapped
    row, in ``parent`` and ``partner``), so an output edge on an input edge is an edge
    of one of those two, and a half ends at a midpoint ``>= first_mid`` whose ends are
    ``mid_a``, ``mid_b``: O(1) per half-edge, no search over the mesh; one row range per core
    (:func:`_pinned_output_edges_into`), into an array from ``hammesh.pages``.
    ``rows`` (with ``pinned``): only those rows' entries of ``pinned`` are found (in
    place), the others are the caller's (sparse mode's gather writes the kept rows':
    ``_sparse_kernels.rows_in_cycle_order``).
    """
    if rows is not None and pinned is not None:
        run_all([
            partial(_pinned_rows_into, out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, rows,
                    lo, hi)
            for lo, hi in row_ranges(len(rows), PINNED_MIN_ROWS)
        ])
        return pinned
    k_rows = out.shape[0]
    pinned = fresh(3 * k_rows, np.bool_)
    run_all([
        partial(
            _pinned_output_edges_into, out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, lo, hi
        )
        for lo, hi in row_ranges(k_rows, threads.THREAD_MIN_ROWS)
    ])
    return pinned


#: rows a thread below which :func:`pinned_output_edges` of given ``rows`` runs in one call
PINNED_MIN_ROWS = 8_192


@njit(cache=True, nogil=True)
def _pinned_output_edges_into(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, lo, hi):
    """Rows ``lo..hi`` of :func:`pinned_output_edges` (every entry of theirs written)."""
    for r in range(lo, hi):
        _pin_row(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, r)


@njit(cache=True, nogil=True)
def _pinned_rows_into(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, rows, lo, hi):
    """Rows ``rows[lo:hi]`` of :func:`pinned_output_edges` (every entry of theirs written)."""
    for i in range(lo, hi):
        _pin_row(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, rows[i])


@njit(cache=True, nogil=True, inline="always")
def _pin_row(out, parent, partner, tri, twin, con, first_mid, mid_a, mid_b, pinned, r):
    """Row ``r``'s three entries of :func:`pinned_output_edges`."""
    t = parent[r]
    if partner[r] < 0 and out[r, 0] == tri[t, 0] and out[r, 1] == tri[t, 1] and out[r, 2] == tri[t, 2]:
        for j in range(3):  # a row kept whole: its parent's edges, in order
            h = 3 * t + j
            pinned[3 * r + j] = con[h] and twin[h] >= 0
    else:
        for j in range(3):
            pinned[3 * r + j] = False
            x = out[r, j]
            y = out[r, (j + 1) % 3]
            ex, ok = _input_end(x, y, first_mid, mid_a, mid_b)
            ey = y
            if ok and ex == x:  # (x is no midpoint: y may be)
                ey, ok = _input_end(y, x, first_mid, mid_a, mid_b)
            if not ok:
                continue
            h = _input_edge(tri, parent[r], ex, ey)
            if h < 0:
                h = _input_edge(tri, partner[r], ex, ey)
            if h >= 0 and con[h] and twin[h] >= 0:
                pinned[3 * r + j] = True


@njit(cache=True, nogil=True)
def _run_of(starts, lengths, x):
    """(start, length) of the run (cycle) holding row ``x``: binary search over ``starts``."""
    i = np.searchsorted(starts, x, side="right") - 1
    return starts[i], lengths[i]


@njit(cache=True, nogil=True, inline="always")
def _failed_since(failed, touched, s, ln, x):
    """Did the try at row ``x`` (of the run ``s .. s + ln``) fail since ``x`` and its
    successor last changed (it fails again: :func:`improve_flips`)?"""
    nx = x + 1 if x + 1 < s + ln else s
    return failed[x] >= touched[x] and failed[x] >= touched[nx]


@njit(cache=True, nogil=True)
def _try_flip(pts, out, twin, pinned, starts, lengths, pm, kind, hi, x, touched, clock, apply):
    """Flip the edge between row ``x`` and its successor if that keeps the cycle and helps.

    The decision reads rows ``x`` and its successor ``y`` only (their corners and their
    points, twins, pinned edges; the neighbours by their place in the run): a flip
    stamps the rows it changes (``x``, ``y`` and the four across its outer edges)
    with the advanced ``clock`` in ``touched`` (see :func:`improve_flips`).
    ``apply`` False: decide only (returns ``y`` where it would flip, writes nothing).
    """
    s, ln = _run_of(starts, lengths, x)
    if ln < 4:
        return -1
    y = x + 1 if x + 1 < s + ln else s
    p = x - 1 if x > s else s + ln - 1
    q = y + 1 if y + 1 < s + ln else s
    kh = -1
    kp = -1
    for k in range(3):
        g = twin[3 * x + k]
        if g >= 0 and g // 3 == y:
            kh = k
        if g >= 0 and g // 3 == p:
            kp = k
    if kh < 0 or kp < 0 or pinned[3 * x + kh]:
        return -1
    h = 3 * x + kh
    g = twin[h]
    kg = g - 3 * y
    kq = -1
    for k in range(3):
        f = twin[3 * y + k]
        if f >= 0 and f // 3 == q:
            kq = k
    if kq < 0:
        return -1
    a = out[x, kh]
    b = out[x, (kh + 1) % 3]
    c = out[x, (kh + 2) % 3]
    d = out[y, (kg + 2) % 3]
    x_ca = kp == (kh + 2) % 3
    y_db = kq == (kg + 2) % 3
    if x_ca != y_db:
        return -1  # both links would land in one new triangle
    if not (_ccw(pts, a, d, c) and _ccw(pts, d, b, c)):
        return -1
    l1, h1 = _min_max(pts, a, b, c)
    l2, h2 = _min_max(pts, b, a, d)
    l3, h3 = _min_max(pts, a, d, c)
    l4, h4 = _min_max(pts, d, b, c)
    old_min = min(l1, l2)
    new_min = min(l3, l4)
    if new_min <= old_min * (1.0 + 1e-9) or max(h3, h4) > max(hi, max(h1, h2)):
        return -1
    if not apply:
        return y
    e_ad = 3 * y + (kg + 1) % 3
    e_db = 3 * y + (kg + 2) % 3
    e_bc = 3 * x + (kh + 1) % 3
    e_ca = 3 * x + (kh + 2) % 3
    t_ad = twin[e_ad]
    t_db = twin[e_db]
    t_bc = twin[e_bc]
    t_ca = twin[e_ca]
    p_ad = pinned[e_ad]
    p_db = pinned[e_db]
    p_bc = pinned[e_bc]
    p_ca = pinned[e_ca]
    # X = (a, d, c) where the link to p is (ca: row x) or to q (ad: row y)
    rx = x if x_ca else y
    ry = y if x_ca else x
    out[rx, 0] = a
    out[rx, 1] = d
    out[rx, 2] = c
    out[ry, 0] = d
    out[ry, 1] = b
    out[ry, 2] = c
    _set_edge(twin, pinned, 3 * rx, t_ad, p_ad)
    _set_edge(twin, pinned, 3 * rx + 2, t_ca, p_ca)
    _set_edge(twin, pinned, 3 * ry, t_db, p_db)
    _set_edge(twin, pinned, 3 * ry + 1, t_bc, p_bc)
    _set_edge(twin, pinned, 3 * rx + 1, 3 * ry + 2, False)
    pinned[3 * ry + 2] = False
    clock[0] += 1
    for f in (t_ad, t_db, t_bc, t_ca):  # rows whose twins changed
        if f >= 0:
            touched[f // 3] = clock[0]
    touched[x] = clock[0]
    touched[y] = clock[0]
    m = min(pm[x], pm[y])
    pm[x] = m
    pm[y] = m
    kind[x] = 4
    kind[y] = 4
    return y


@njit(cache=True, nogil=True)
def improve_flips(pts, out, twin, pinned, starts, lengths, pm, kind, hi, max_flips, rows, touched, failed, clock):
    """Cycle-keeping Lawson flips around ``rows`` (the new ones, ``kind != 3``; module docstring).

    ``starts``, ``lengths``: the runs (cycles) of rows. Modifies ``out``, ``twin`` (the
    output's half-edge twins), ``pinned``, ``pm`` (each row's parents' smallest angle:
    a flipped pair gets the smaller of the two) and ``kind`` (4 for a flipped row) in
    place. Returns the number of flips. The work stack holds the new rows and grows
    with the flips (not sized for the whole mesh).

    A failed try changes nothing, so a try that failed at ``clock`` time
    ``failed[x]`` is not made again while neither ``x`` nor its successor was
    changed since (``touched``, stamped by each flip and by ``smooth_steiner`` for
    the rows around a moved point; ``clock`` a one-entry array, the same across the
    rounds): it would fail again. The same flips happen in the same order as
    trying every row, at half the tries in the first round (each row is tried as
    itself and as its successor's predecessor) and a few in the later ones.
    ``touched`` (0) and ``failed`` (-1): one entry per row, made once for all rounds.
    """
    top = rows.shape[0]
    stack = np.empty(2 * top + 64, np.int64)
    stack[:top] = rows
    n = 0
    while top > 0 and n < max_flips:
        top -= 1
        r = stack[top]
        s, ln = _run_of(starts, lengths, r)
        for x in (r, r - 1 if r > s else s + ln - 1):  # (the row and its predecessor)
            if _failed_since(failed, touched, s, ln, x):
                continue  # tried since it or its successor last changed: fails again
            y = _try_flip(pts, out, twin, pinned, starts, lengths, pm, kind, hi, x, touched, clock, True)
            if y < 0:
                failed[x] = clock[0]
            if y >= 0:
                n += 1
                if top + 2 > stack.shape[0]:
                    grown = np.empty(2 * stack.shape[0], np.int64)
                    grown[:top] = stack[:top]
                    stack = grown
                stack[top] = x
                stack[top + 1] = y
                top += 2
                break
    return n


def failing_flips(pts, out, twin, pinned, starts, lengths, hi, rows, touched, failed, clock, min_rows):
    """Mark, on both cores, the tries of :func:`improve_flips` that fail as the rows are now.

    A try's outcome is a function of its two rows as they are (``_try_flip``), and
    ``failed[x] = clock`` records exactly that it fails while neither row changes
    (``touched``): so every try :func:`improve_flips` would make first (each row of
    ``rows`` and its predecessor, not tried since they changed) is decided here, read
    only, one range of ``rows`` per core (``min_rows`` a thread at least), and the
    failing ones are marked at the current ``clock``. The serial loop then skips them
    and makes only the flips and the tries around them: the same flips in the same
    order (a mark holds only while the try's rows are unchanged, as its own would).
    Returns nothing; ``failed`` is written in place (two ranges may mark one
    predecessor, with the same value).
    """
    spans = row_ranges(rows.shape[0], min_rows)
    if len(spans) < 2:
        return  # (one core: the loop's own tries cost the same)
    dummy_pm = np.zeros(0)
    dummy_kind = np.zeros(0, np.int8)
    run_all([
        partial(_failing_flips_into, pts, out, twin, pinned, starts, lengths, dummy_pm, dummy_kind, float(hi), rows,
                touched, failed, clock, lo, hi_)
        for lo, hi_ in spans
    ])


@njit(cache=True, nogil=True)
def _failing_flips_into(pts, out, twin, pinned, starts, lengths, pm, kind, hi, rows, touched, failed, clock, lo,
                        hi_):
    """``rows[lo:hi_]`` of :func:`failing_flips` (reads only, bar ``failed``)."""
    stamp = clock[0]
    for i in range(lo, hi_):
        r = rows[i]
        s, ln = _run_of(starts, lengths, r)
        for x in (r, r - 1 if r > s else s + ln - 1):  # (the row and its predecessor)
            if _failed_since(failed, touched, s, ln, x):
                continue
            if _try_flip(pts, out, twin, pinned, starts, lengths, pm, kind, hi, x, touched, clock, False) < 0:
                failed[x] = stamp


def smooth_steiner(pts, out, twin, pinned, pm, first, keep, hi, iters, new_rows, touched, clock, judged,
                   min_points=None):
    """Move each free Steiner point to a better place in its star (in place).

    ``new_rows``: every row that can hold a Steiner point (those of kind != 3; a row
    kept whole has input corners only).

    Amenta, Bern & Eppstein's optimal point placement (see ``_join_kernels``):
    ``compass_search`` maximises the star's slack (smallest angle minus ``keep`` x its
    rows' parents' smallest, ``hi`` minus the largest) from the point's current place,
    in at most ``4 x iters`` rounds so a long thin star costs no more than a round one. Points ``>= first`` whose star is closed
    and touches no pinned edge (a midpoint of a constrained edge stays) and that miss
    the rule (slack < 0) are moved where the star's smallest angle does not drop, its largest stays within
    ``max(hi, its own)`` and its slack grows. An incenter's star, once improvement
    flips took its sectors' outer edges, is larger than the triangle it split: the
    point can move towards the whole angles. Returns the number of points moved.
    The rows around a moved point are stamped in ``touched`` with the advanced
    ``clock`` (:func:`improve_flips` tries them again). ``judged[v - first]``: the
    clock when point ``v`` was last judged and left where it was (-1: never); it is
    not judged again while no row around it changed since (the same rows, corners,
    parents' angles and points: the same outcome). A flip that takes a row out of
    a star stamps the row it leaves there.

    The points are judged in order, each against the points moved before it. A
    point's outcome is a function of its star as it is (its rows, their corners'
    places and parents' angles), so it is first worked out for every point on both
    cores from the stars as they are (``min_points`` points a thread at least,
    default ``hammesh.threads.THREAD_MIN_ROWS``; every other point a thread:
    :func:`_judge_points_into`); the
    serial pass (:func:`_smooth_points`) takes that outcome for each point none of
    whose star rows a move before it stamped, and judges the others again: the same
    moves as judging one point after the other.
    """
    n_pts = pts.shape[0]
    k = max(n_pts - first, 0)
    cnt, rows = _steiner_stars(out, first, n_pts, new_rows)
    code = np.full(k, -1, np.int8)  # -1: not worked out ahead; 0: stays; 1: moves to ``to``
    to = np.empty((k, 2))
    parts = len(row_ranges(k, threads.THREAD_MIN_ROWS if min_points is None else min_points))
    stamp = int(clock[0])
    if parts > 1:  # (one core: the serial pass's own judging costs the same)
        # every parts-th point a thread: the incenters (numbered first) miss the rule and
        # need the search far more often than the midpoints after them
        run_all([
            partial(_judge_points_into, pts, out, twin, pinned, pm, first, float(keep), float(hi), int(iters), cnt,
                    rows, touched, judged, code, to, j, parts)
            for j in range(parts)
        ])
    return _smooth_points(pts, out, twin, pinned, pm, first, float(keep), float(hi), int(iters), cnt, rows, touched,
                          clock, judged, code, to, stamp)


@njit(cache=True, nogil=True)
def _steiner_stars(out, first, n_pts, new_rows):
    """``(cnt, rows)``: the half-edges ``3 r + j`` of ``new_rows`` whose corner ``j`` is a
    Steiner point ``v >= first``, grouped by point (point ``v``'s at
    ``rows[cnt[v - first]:cnt[v - first + 1]]``, in the order of ``new_rows``)."""
    cnt = np.zeros(max(n_pts - first, 0) + 1, np.int64)
    for r in new_rows:
        for j in range(3):
            v = out[r, j]
            if v >= first:
                cnt[v - first + 1] += 1
    for i in range(1, cnt.shape[0]):
        cnt[i] += cnt[i - 1]
    rows = np.empty(cnt[-1], np.int64)
    fill = cnt[:-1].copy()
    for r in new_rows:
        for j in range(3):
            v = out[r, j]
            if v >= first:
                rows[fill[v - first]] = 3 * r + j
                fill[v - first] += 1
    return cnt, rows


@njit(cache=True, nogil=True)
def _unchanged_since(touched, rows, a0, a1, t):
    """No row of ``rows[a0:a1]`` (half-edges) stamped after clock ``t``."""
    for i in range(a0, a1):
        if touched[rows[i] // 3] > t:
            return False
    return True


@njit(cache=True, nogil=True)
def _point_outcome(pts, out, twin, pinned, pm, keep, hi, iters, rows, a0, n, us, ws, poly):
    """``(moves, x, y)``: where point ``out[rows[a0] // 3, rows[a0] % 3]``'s star ``rows[a0:a0 + n]``
    would move it (:func:`smooth_steiner`'s test; reads only)."""
    cap = us.shape[0]
    if n < 3 or n > cap:
        return False, 0.0, 0.0
    lo = np.inf
    for i in range(n):
        h = rows[a0 + i]
        r = h // 3
        kv = h - 3 * r
        e_out = 3 * r + kv  # v -> u
        e_in = 3 * r + (kv + 2) % 3  # w -> v
        if twin[e_out] < 0 or twin[e_in] < 0 or pinned[e_out] or pinned[e_in]:
            return False, 0.0, 0.0
        us[i] = out[r, (kv + 1) % 3]
        ws[i] = out[r, (kv + 2) % 3]
        lo = min(lo, pm[r])
    # the link polygon, counter-clockwise: u -> w in each star triangle (v, u, w)
    poly[0] = us[0]
    cur = ws[0]
    m = 1
    while cur != us[0] and m < n:
        poly[m] = cur
        nxt = -1
        for i in range(n):
            if us[i] == cur:
                nxt = ws[i]
                break
        if nxt < 0:
            break
        cur = nxt
        m += 1
    if m != n or cur != us[0]:
        return False, 0.0, 0.0
    lo *= keep
    h = rows[a0]
    v = out[h // 3, h % 3]
    vx = pts[v, 0]
    vy = pts[v, 1]
    s0, n0, x0 = fan_eval(pts, poly, n, vx, vy, lo, hi)
    if s0 == -np.inf or s0 >= 0.0:
        return False, 0.0, 0.0  # already meets the rule (most fan points: placed for it)
    d2 = np.inf
    for i in range(n):
        d2 = min(d2, (pts[poly[i], 0] - vx) ** 2 + (pts[poly[i], 1] - vy) ** 2)
    px, py, s1, n1, x1 = compass_search(pts, poly, n, vx, vy, lo, hi, 0.25 * math.sqrt(d2), iters, 4 * iters)
    if s1 > s0 and n1 >= n0 and x1 <= max(hi, x0):
        return True, px, py
    return False, 0.0, 0.0


#: a star of more rows than this is left alone (the buffers' size)
STAR_CAP = 64


@njit(cache=True, nogil=True)
def _judge_points_into(pts, out, twin, pinned, pm, first, keep, hi, iters, cnt, rows, touched, judged, code, to,
                       start, step):
    """Points ``first + start``, every ``step``-th after it, of :func:`smooth_steiner`,
    worked out ahead on the stars as they are (reads only, bar ``code`` and ``to``); a
    point left alone since it was last judged is not (``code`` stays -1)."""
    us = np.empty(STAR_CAP, np.int64)
    ws = np.empty(STAR_CAP, np.int64)
    poly = np.empty(STAR_CAP, np.int64)
    for i in range(start, cnt.shape[0] - 1, step):
        a0 = cnt[i]
        a1 = cnt[i + 1]
        last = judged[i]
        if last >= 0 and _unchanged_since(touched, rows, a0, a1, last):
            continue
        moves, x, y = _point_outcome(pts, out, twin, pinned, pm, keep, hi, iters, rows, a0, a1 - a0, us, ws, poly)
        code[i] = 1 if moves else 0
        to[i, 0] = x
        to[i, 1] = y


@njit(cache=True, nogil=True)
def _smooth_points(pts, out, twin, pinned, pm, first, keep, hi, iters, cnt, rows, touched, clock, judged, code, to,
                   stamp):
    """The serial pass of :func:`smooth_steiner`: each point in order, its outcome worked
    out ahead (``code`` >= 0, at clock ``stamp``) taken while its star is unchanged."""
    us = np.empty(STAR_CAP, np.int64)
    ws = np.empty(STAR_CAP, np.int64)
    poly = np.empty(STAR_CAP, np.int64)
    moved = 0
    for i in range(cnt.shape[0] - 1):
        a0 = cnt[i]
        a1 = cnt[i + 1]
        last = judged[i]
        if last >= 0 and _unchanged_since(touched, rows, a0, a1, last):
            continue
        judged[i] = clock[0]  # (unless moved below)
        if code[i] >= 0 and _unchanged_since(touched, rows, a0, a1, stamp):
            moves, x, y = code[i] == 1, to[i, 0], to[i, 1]
        else:
            moves, x, y = _point_outcome(pts, out, twin, pinned, pm, keep, hi, iters, rows, a0, a1 - a0, us, ws,
                                         poly)
        if moves:
            v = first + i
            pts[v, 0] = x
            pts[v, 1] = y
            moved += 1
            judged[i] = -1
            clock[0] += 1
            for j in range(a0, a1):
                touched[rows[j] // 3] = clock[0]
    return moved


def load_improve_kernels() -> None:
    """Load (or compile) the kernels only big outputs reach: the improvement step's work
    ahead on both cores (:func:`failing_flips`, :func:`smooth_steiner`, from
    ``sparse.IMPROVE_MIN_ROWS`` rows / ``sparse.SMOOTH_MIN_POINTS`` points a thread),
    with the types the step passes (no row, no point: nothing is read);
    ``hammesh.postprocess.load_kernels``' small mesh does not reach them, and a first
    call at 1.5 M triangles loaded each on both threads (10-16 ms each)."""
    pts = np.zeros((3, 2))
    out = np.zeros((1, 3), np.int64)
    twin = np.full(3, -1, np.int64)
    pinned = np.zeros(3, np.bool_)
    none = np.zeros(0, np.int64)
    one = np.zeros(1, np.int64)
    clock = np.zeros(1, np.int64)
    _failing_flips_into(pts, out, twin, pinned, one, np.ones(1, np.int64), np.zeros(0), np.zeros(0, np.int8), 1.0,
                        none, one, one.copy(), clock, 0, 0)
    _judge_points_into(pts, out, twin, pinned, np.zeros(1), 3, 0.9, 1.0, 2, np.zeros(1, np.int64), none, one,
                       none.copy(), np.zeros(0, np.int8), np.zeros((0, 2)), 0, 2)
