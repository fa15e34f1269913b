"""Minimum convex decomposition of a simple polygon by diagonals (Keil's dynamic program).

Theorem 2.3's Steiner count is ``k - 1`` (cycle) / ``k - 2`` (path) for the ``k`` pieces
of a *minimum* convex decomposition, so :mod:`~hammesh.polygon.steiner` needs the exact
minimum.  Pieces are bounded by polygon edges and diagonals (no Steiner points); their
angles are at most 180 degrees (``straight=True``) or, with ``straight=False``, strictly
less wherever a diagonal ends (a straight polygon vertex on a piece side is always fine).

Method (J. M. Keil, "Decomposing a polygon into simpler components", SIAM J. Comput.
14, 1985; J. M. Keil and J. Snoeyink, "On the time bound for convex decomposition of
simple polygons", IJCGA 12, 2002).  Vertices are numbered counter-clockwise from a
reflex vertex ``0``; ``P(i, j)`` is the sub-polygon ``i, i+1, ..., j`` closed by the
diagonal (or edge) ``(i, j)``, and the whole polygon is ``P(0, n-1)``.

* A minimum decomposition has no diagonal between two non-reflex vertices (removing it
  merges two pieces into a convex one), so only pairs ``(i, j)`` with a reflex end are
  sub-problems: ``O(r n)`` of them for ``r`` reflex vertices.
* Keil's exchange lemma: if the part of a decomposition inside ``P(i, j)`` has more than
  ``w(i, j)`` pieces (the minimum for ``P(i, j)``), replacing it by a minimum one and
  cutting along ``(i, j)`` costs no more.  So each sub-problem keeps only its minimum
  weight ``w(i, j)`` and, among its minimum decompositions, the *narrowest pairs*
  ``(a, b)``: the piece on ``(i, j)`` is ``i, a, ..., b, j`` and the outer piece can be
  merged across ``(i, j)`` more easily the larger ``a`` and the smaller ``b`` (the
  vertices a vertex sees appear around it in boundary order).  Only the Pareto front
  is stored, ``a`` and ``b`` both increasing.
* Recurrence: the piece on ``(i, j)`` is cut by a triangle ``(i, k, j)`` into up to
  three parts.  Each of ``(i, k)`` and ``(k, j)`` is a polygon side (or a chain of
  sides through straight vertices), a cut whose far side is decomposed on its own, or
  *merged*: the triangle joins the piece on that chord of a narrowest pair of that
  sub-problem, provided the angles at ``i``, ``k`` and ``j`` stay convex.  A triangle
  on its own weighs ``w(i,k) + w(k,j) + 1`` with pair ``(k, k)``; merged on ``(i, k)``
  ``w(i,k) + w(k,j)`` with pair ``(a', k)``; merged on ``(k, j)`` likewise with
  ``(k, b'')``.  With ``k = b`` (or ``k = a``) every piece is reached, except where a
  triangle degenerates: a piece straight at both ``i`` and ``j`` (``(i, j)`` lies on a
  longer side) is reached by merging on both sides (weight ``w(i,k) + w(k,j) - 1``,
  only with ``straight=True``), and for the piece on the edge ``(n-1, 0)`` straight at
  ``n-1``, ``n-1`` is made an anchor too.  When one end is not reflex, a cut from it
  needs a reflex ``k`` and so does a merge, so only ``O(r)`` split vertices are tried
  (reflex ones, and those joined to the non-reflex end by sides).

Cost: ``O(r^2)`` sub-problems with two reflex ends try ``O(n)`` splits, the ``O(r n)``
others ``O(r)``; each split scans a pair list (two, for the double merge).  So ``O(n r^2)`` splits after the
``O(n^2)`` visibility graph (:mod:`~hammesh.polygon.visibility`), against Keil and
Snoeyink's ``O(n + r^2 min(r^2, n))``, which also compresses the convex chains between
reflex vertices (not done here).  All orientation tests are exact
(:mod:`hammesh.predicates`).  Measured in ``benchmarks/bench_polygon.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hammesh.polygon._polygon import Polygon
from hammesh.polygon.visibility import visibility_matrix
from hammesh.predicates import orient, orient_rows

__all__ = ["minimum_convex_faces", "minimum_convex_diagonals", "faces_from_diagonals"]


def minimum_convex_diagonals(cp: np.ndarray, *, straight: bool = True) -> np.ndarray:
    """Diagonals of a minimum convex decomposition of the CCW polygon ``cp``.

    Parameters
    ----------
    cp : (n, 2) float64
        Counter-clockwise simple polygon (straight-angle vertices allowed).
    straight : bool
        Allow straight angles in the pieces where a diagonal ends.

    Returns
    -------
    (k - 1, 2) int64
        Pairs ``(u, v)``, ``u < v``, of indices into ``cp``: the diagonals that cut the
        polygon into the minimum number ``k`` of convex pieces.

    Examples
    --------
    >>> L = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]   # one reflex vertex
    >>> minimum_convex_diagonals(np.array(L, float)).tolist()
    [[0, 3]]
    """
    cp = np.ascontiguousarray(cp, dtype=np.float64)
    n = len(cp)
    prv, nxt = np.roll(np.arange(n), 1), np.roll(np.arange(n), -1)
    reflex = orient_rows(cp[prv], cp, cp[nxt]) < 0
    if not reflex.any():
        return np.zeros((0, 2), np.int64)
    # number from a reflex vertex so that the whole polygon is the sub-problem P(0, n-1)
    shift = int(np.flatnonzero(reflex)[0])
    rot = np.roll(np.arange(n), -shift)
    pts = np.ascontiguousarray(cp[rot])
    vis = visibility_matrix(Polygon(points=pts, order=np.arange(n), area=0.0))
    # sub-problems are anchored at reflex vertices, and at n-1: the piece on the edge
    # (n-1, 0) may be straight at n-1, and then only a split merged towards n-1 exists
    anchor = reflex[rot].copy()
    anchor[n - 1] = True
    cuts, status = _keil_dp(pts, vis, anchor, bool(straight))
    if status != 0:  # pragma: no cover - a simple polygon always has a decomposition
        raise AssertionError("minimum convex decomposition: no split found")
    out = rot[cuts]
    return np.sort(out, axis=1)[np.lexsort((out.max(axis=1), out.min(axis=1)))]


def minimum_convex_faces(cp: np.ndarray, *, straight: bool = True) -> list[list[int]]:
    """Pieces of a minimum convex decomposition of the CCW polygon ``cp``.

    Returns
    -------
    list of list of int
        The pieces as counter-clockwise lists of indices into ``cp`` (straight-angle
        vertices included on the sides they lie on); their number is the minimum.

    Examples
    --------
    >>> L = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]
    >>> minimum_convex_faces(np.array(L, float))
    [[0, 1, 2, 3], [0, 3, 4, 5]]
    """
    d = minimum_convex_diagonals(cp, straight=straight)
    return faces_from_diagonals(cp, d[:, 0], d[:, 1])


def faces_from_diagonals(cp: np.ndarray, a: np.ndarray, b: np.ndarray) -> list[list[int]]:
    """Faces of the CCW polygon ``cp`` cut by the non-crossing diagonals ``(a, b)``.

    Purely combinatorial: around a vertex ``v`` of a simple polygon, the vertices it is
    joined to appear counter-clockwise in the boundary order ``v+1, v+2, ..., v-1``, so
    no angle is computed.  Each face is a counter-clockwise list of indices, starting
    at its smallest index; faces are sorted.
    """
    m = len(cp)
    nbrs: dict[int, list[int]] = {v: [(v + 1) % m, (v - 1) % m] for v in range(m)}
    for u, v in zip(np.asarray(a).tolist(), np.asarray(b).tolist()):
        nbrs[u].append(v)
        nbrs[v].append(u)
    for v, ws in nbrs.items():
        ws.sort(key=lambda w, v=v: (w - v) % m)   # counter-clockwise around v
    pos = {(v, w): t for v, ws in nbrs.items() for t, w in enumerate(ws)}
    seen = set()
    faces = []
    for h0 in [(v, (v + 1) % m) for v in range(m)] + [(v, u) for u, ws in nbrs.items() for v in ws]:
        if h0 in seen or (h0[1] - h0[0]) % m == m - 1:   # (v+1, v) runs outside
            continue
        face, h = [], h0
        while h not in seen:
            seen.add(h)
            u, v = h
            face.append(u)
            ws = nbrs[v]
            h = (v, ws[pos[(v, u)] - 1])   # the next side turns clockwise from u around v
        s = face.index(min(face))
        faces.append(face[s:] + face[:s])
    return sorted(faces)


# ----------------------------------------------------------------------------- kernel

@njit(cache=True, nogil=True)
def _convex_turn(pts, p, q, r, straight, whole_angle):
    """Whether ``p -> q -> r`` turns left, or goes straight where that is allowed."""
    o = orient(pts[p, 0], pts[p, 1], pts[q, 0], pts[q, 1], pts[r, 0], pts[r, 1])
    return o > 0 or (o == 0 and (straight or whole_angle))


@njit(cache=True, nogil=True)
def _grow(arr, need):
    if need <= arr.shape[0]:
        return arr
    out = np.empty(max(need, 2 * arr.shape[0]), arr.dtype)
    out[:arr.shape[0]] = arr
    return out


@njit(cache=True, nogil=True)
def _keil_dp(pts, vis, reflex, straight):
    """Cut diagonals ``(d, 2)`` of a minimum decomposition; ``reflex[0]`` must hold.

    ``reflex`` marks the anchors (the reflex vertices and ``n - 1``).  Returns
    ``(cuts, status)``, status 0 on success.  Sub-problems are numbered in order of
    increasing ``j - i``; ``sub_i[rid[i], j]`` (``i`` an anchor) or ``sub_j[rid[j], i]``
    (only ``j``) gives the number of ``P(i, j)``.  Its narrowest pairs are entries
    ``first[s] .. first[s] + count[s] - 1`` of the pair arrays: ``pa``/``pb`` the pair,
    ``pk`` the split vertex, ``pmerge`` which sides were merged (0 none, 1 ``(i, k)``,
    2 ``(k, j)``, 3 both) and ``pref``/``pref2`` the merged sub-problems' pair entries.
    """
    n = pts.shape[0]
    rid = np.full(n, -1, np.int64)
    nr = 0
    for v in range(n):
        if reflex[v]:
            rid[v] = nr
            nr += 1
    rlist = np.nonzero(reflex)[0]
    # straight chains: (u, v) with only straight vertices between is a side, not a chord
    fwd = np.empty(n, np.int64)    # edge-like (u, v) iff u < v <= fwd[u]
    bwd = np.empty(n, np.int64)    # edge-like (u, v) iff bwd[v] <= u < v
    for u in range(n):
        v = u + 1
        while v < n - 1 and _straight(pts, v):
            v += 1
        fwd[u] = min(v, n - 1)
        v = u - 1
        while v > 0 and _straight(pts, v):
            v -= 1
        bwd[u] = max(v, 0)
    sub_i = np.full((nr, n), -1, np.int64)
    sub_j = np.full((nr, n), -1, np.int64)
    # enumerate sub-problems by increasing gap
    cap = 16
    si = np.empty(cap, np.int64)
    sj = np.empty(cap, np.int64)
    ns = 0
    for gap in range(2, n):
        for i in range(0, n - gap):
            j = i + gap
            if not (vis[i, j] or (i == 0 and j == n - 1)):
                continue
            if not (reflex[i] or reflex[j]):
                continue
            si = _grow(si, ns + 1)
            sj = _grow(sj, ns + 1)
            si[ns] = i
            sj[ns] = j
            if reflex[i]:
                sub_i[rid[i], j] = ns
            else:
                sub_j[rid[j], i] = ns
            ns += 1
    weight = np.zeros(ns, np.int64)
    first = np.zeros(ns, np.int64)
    count = np.zeros(ns, np.int64)
    pcap = 4 * ns + 16
    pa = np.empty(pcap, np.int64)
    pb = np.empty(pcap, np.int64)
    pk = np.empty(pcap, np.int64)
    pmerge = np.empty(pcap, np.int64)
    pref = np.empty(pcap, np.int64)
    pref2 = np.empty(pcap, np.int64)
    npairs = 0
    # candidates of one sub-problem
    cw = np.empty(2 * n, np.int64)
    ca = np.empty(2 * n, np.int64)
    cb = np.empty(2 * n, np.int64)
    ck = np.empty(2 * n, np.int64)
    cm = np.empty(2 * n, np.int64)    # 0 triangle alone, merged on 1 (i, k), 2 (k, j), 3 both
    cr = np.empty(2 * n, np.int64)
    cr2 = np.empty(2 * n, np.int64)
    ks = np.empty(2 * n, np.int64)
    for s in range(ns):
        i = si[s]
        j = sj[s]
        top = i == 0 and j == n - 1
        # split vertices: all when both ends are reflex; else the reflex ones and those
        # joined to an end by a side (a cut between two non-reflex vertices never is
        # in a minimum decomposition, and a merged part needs a sub-problem)
        nk = 0
        if reflex[i] and reflex[j]:
            for k in range(i + 1, j):
                ks[nk] = k
                nk += 1
        else:
            for k in range(i + 1, min(fwd[i], j - 1) + 1):
                ks[nk] = k
                nk += 1
            for k in range(max(bwd[j], fwd[i] + 1, i + 1), j):
                ks[nk] = k
                nk += 1
            for t in range(np.searchsorted(rlist, i + 1), rlist.shape[0]):
                k = rlist[t]
                if k >= j:
                    break
                if k > fwd[i] and k < bwd[j]:
                    ks[nk] = k
                    nk += 1
        nc = 0
        for t in range(nk):
            k = ks[t]
            # the triangle (i, k, j) of the piece on (i, j); its other sides are sides
            # of the polygon (-1), or sub-problems cut off or merged
            s_ik = -1 if k <= fwd[i] else _sub(i, k, vis, reflex, rid, sub_i, sub_j)
            s_kj = -1 if k >= bwd[j] else _sub(k, j, vis, reflex, rid, sub_i, sub_j)
            if s_ik == -2 or s_kj == -2:
                continue
            base = (weight[s_ik] if s_ik >= 0 else 0) + (weight[s_kj] if s_kj >= 0 else 0)
            if nc + 3 >= cw.shape[0]:
                cw, ca, cb = _grow(cw, nc + 4), _grow(ca, nc + 4), _grow(cb, nc + 4)
                ck, cm, cr = _grow(ck, nc + 4), _grow(cm, nc + 4), _grow(cr, nc + 4)
                cr2 = _grow(cr2, nc + 4)
            found = False
            if s_ik >= 0:
                # merged with the piece on (i, k), pair (a', b'): largest a' that fits
                for p in range(first[s_ik] + count[s_ik] - 1, first[s_ik] - 1, -1):
                    if (_convex_turn(pts, pb[p], k, j, straight, pb[p] >= bwd[k] and s_kj == -1)
                            and _convex_turn(pts, j, i, pa[p], straight, top and pa[p] <= fwd[i])):
                        cw[nc], ca[nc], cb[nc], ck[nc], cm[nc], cr[nc] = base, pa[p], k, k, 1, p
                        nc += 1
                        found = True
                        break
            if s_kj >= 0:
                # merged with the piece on (k, j), pair (a'', b''): smallest b'' that fits
                for p in range(first[s_kj], first[s_kj] + count[s_kj]):
                    if (_convex_turn(pts, i, k, pa[p], straight, pa[p] <= fwd[k] and s_ik == -1)
                            and _convex_turn(pts, pb[p], j, i, straight, top and pb[p] >= bwd[j])):
                        cw[nc], ca[nc], cb[nc], ck[nc], cm[nc], cr[nc] = base, k, pb[p], k, 2, p
                        nc += 1
                        found = True
                        break
            if straight and s_ik >= 0 and s_kj >= 0:
                # merged on both sides: needed when the piece is straight at i and at j
                # (then (i, j) lies on a longer side and no triangle on it has a side)
                for p in range(first[s_ik] + count[s_ik] - 1, first[s_ik] - 1, -1):
                    if not _convex_turn(pts, j, i, pa[p], straight, top and pa[p] <= fwd[i]):
                        continue
                    for q in range(first[s_kj], first[s_kj] + count[s_kj]):
                        if (_convex_turn(pts, pb[p], k, pa[q], straight, False)
                                and _convex_turn(pts, pb[q], j, i, straight, top and pb[q] >= bwd[j])):
                            if nc + 1 >= cw.shape[0]:
                                cw, ca, cb = _grow(cw, nc + 2), _grow(ca, nc + 2), _grow(cb, nc + 2)
                                ck, cm, cr = _grow(ck, nc + 2), _grow(cm, nc + 2), _grow(cr, nc + 2)
                                cr2 = _grow(cr2, nc + 2)
                            cw[nc], ca[nc], cb[nc], ck[nc], cm[nc] = base - 1, pa[p], pb[q], k, 3
                            cr[nc], cr2[nc] = p, q
                            nc += 1
                            found = True
                            break
            if not found:   # the triangle is a piece of its own
                cw[nc], ca[nc], cb[nc], ck[nc], cm[nc], cr[nc] = base + 1, k, k, k, 0, -1
                nc += 1
        if nc == 0:
            return np.zeros((0, 2), np.int64), 1
        wmin = cw[:nc].min()
        # Pareto front of the minimum-weight candidates: b ascending, a strictly rising
        key = cb[:nc] * (n + 1) + (n - ca[:nc])
        order = np.argsort(key)
        first[s] = npairs
        best_a = -1
        for t in order:
            if cw[t] != wmin or ca[t] <= best_a:
                continue
            best_a = ca[t]
            if npairs >= pa.shape[0]:
                pa = _grow(pa, npairs + 1)
                pb = _grow(pb, npairs + 1)
                pk = _grow(pk, npairs + 1)
                pmerge = _grow(pmerge, npairs + 1)
                pref = _grow(pref, npairs + 1)
                pref2 = _grow(pref2, npairs + 1)
            pa[npairs] = ca[t]
            pb[npairs] = cb[t]
            pk[npairs] = ck[t]
            pmerge[npairs] = cm[t]
            pref[npairs] = cr[t]
            pref2[npairs] = cr2[t]
            npairs += 1
        count[s] = npairs - first[s]
        weight[s] = wmin
    # walk back from the whole polygon: (sub-problem, pair entry) on a stack
    root = ns - 1
    cuts = np.empty((weight[root], 2), np.int64)
    nd = 0
    st_s = np.empty(ns + 1, np.int64)
    st_p = np.empty(ns + 1, np.int64)
    st_s[0] = root
    st_p[0] = first[root]
    top_ = 1
    while top_ > 0:
        top_ -= 1
        s = st_s[top_]
        p = st_p[top_]
        i = si[s]
        j = sj[s]
        k = pk[p]
        for side in range(2):
            u, v = (i, k) if side == 0 else (k, j)
            if v <= fwd[u]:
                continue
            c = _sub(u, v, vis, reflex, rid, sub_i, sub_j)
            st_s[top_] = c
            if pmerge[p] == 3:
                st_p[top_] = pref[p] if side == 0 else pref2[p]
            elif pmerge[p] == side + 1:
                st_p[top_] = pref[p]
            else:
                st_p[top_] = first[c]
                cuts[nd, 0] = u
                cuts[nd, 1] = v
                nd += 1
            top_ += 1
    return cuts[:nd], 0


@njit(cache=True, nogil=True)
def _straight(pts, v):
    n = pts.shape[0]
    u, w = (v - 1) % n, (v + 1) % n
    return orient(pts[u, 0], pts[u, 1], pts[v, 0], pts[v, 1], pts[w, 0], pts[w, 1]) == 0


@njit(cache=True, nogil=True, inline="always")
def _sub(i, j, vis, reflex, rid, sub_i, sub_j):
    """Number of the sub-problem ``P(i, j)``, or -2 if ``(i, j)`` is not one."""
    if not vis[i, j]:
        return -2
    if reflex[i]:
        return sub_i[rid[i], j]
    if reflex[j]:
        return sub_j[rid[j], i]
    return -2
