"""Minimum convex decomposition of a small simple polygon by an integer program.

The reference that the dynamic program of :mod:`~hammesh.polygon.min_convex` is tested
against (a different formulation sharing only the exact predicates and the visibility
graph); not on any production path.  Pieces are bounded by polygon edges and diagonals (no Steiner points
in the decomposition); they are convex, and straight angles are allowed where a diagonal
ends (``straight=True``) or not.

Formulation (``scipy.optimize.milp``, HiGHS): one binary per candidate diagonal, i.e. per
visibility edge with a reflex end (a diagonal between two convex corners can always be
dropped from a convex decomposition).  Minimise the number of diagonals subject to

* two crossing candidates are not both chosen;
* at every reflex vertex ``v``, for every ray ``x`` out of ``v`` (the outgoing polygon
  edge or a chosen diagonal), some chosen ray or the incoming edge lies within 180
  degrees counter-clockwise of ``x`` (so every angle of every piece is at most 180
  degrees; strictly less with ``straight=False``).

All orientation tests are exact.  Size: ``O(E^2)`` crossing constraints for ``E``
candidates; the solver is exponential in the worst case, so callers limit the input to
:data:`MAX_VERTICES` vertices (well under a second on random star-shaped 24-gons on this machine; 30 corners can take seconds).
"""

from __future__ import annotations

import numpy as np

from hammesh.polygon._polygon import Polygon
from hammesh.polygon.min_convex import faces_from_diagonals
from hammesh.polygon.visibility import visibility_matrix
from hammesh.predicates import orient, orient_rows

__all__ = ["minimum_convex_faces_ip", "MAX_VERTICES"]

#: Largest number of polygon vertices for the exact decomposition.
MAX_VERTICES = 24


def minimum_convex_faces_ip(cp: np.ndarray, *, straight: bool = True,
                         time_limit: float = 20.0) -> list[list[int]] | None:
    """Faces of a minimum convex decomposition of the CCW polygon ``cp``.

    Parameters
    ----------
    cp : (m, 2) float64
        Counter-clockwise simple polygon (straight-angle vertices may end diagonals).
    straight : bool
        Allow straight angles (at diagonal ends) in the pieces.
    time_limit : float
        Seconds for the solver; past it ``None`` is returned.

    Returns
    -------
    list of list of int or None
        The pieces as counter-clockwise lists of indices into ``cp``, or ``None`` if the
        solver did not prove optimality in time.
    """
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import coo_matrix

    m = len(cp)
    prv, nxt = np.roll(np.arange(m), 1), np.roll(np.arange(m), -1)
    reflex = orient_rows(cp[prv], cp, cp[nxt]) < 0
    if not reflex.any():
        return [list(range(m))]
    vis = visibility_matrix(Polygon(points=np.ascontiguousarray(cp), order=np.arange(m), area=0.0))
    a, b = np.nonzero(np.triu(vis, 1))
    keep = reflex[a] | reflex[b]
    a, b = a[keep], b[keep]
    E = len(a)
    rows, cols, lo = [], [], []

    def add(coeffs, lower):
        r = len(lo)
        for c, v in coeffs:
            rows.append(r)
            cols.append(c)
            vals.append(v)
        lo.append(lower)

    vals: list[float] = []
    # crossings: s_p + s_q <= 1, written -s_p - s_q >= -1
    p, q = np.triu_indices(E, 1)
    distinct = ((a[p] != a[q]) & (a[p] != b[q]) & (b[p] != a[q]) & (b[p] != b[q]))
    p, q = p[distinct], q[distinct]
    if len(p):
        A, B, C, D = cp[a[p]], cp[b[p]], cp[a[q]], cp[b[q]]
        cross = ((orient_rows(A, B, C) * orient_rows(A, B, D) < 0)
                 & (orient_rows(C, D, A) * orient_rows(C, D, B) < 0))
        for x, y in zip(p[cross].tolist(), q[cross].tolist()):
            add([(x, -1.0), (y, -1.0)], -1.0)
    # angles at reflex vertices
    ends = {}
    for e in range(E):
        ends.setdefault(int(a[e]), []).append((int(b[e]), e))
        ends.setdefault(int(b[e]), []).append((int(a[e]), e))
    for v in np.flatnonzero(reflex).tolist():
        out_dir = cp[nxt[v]] - cp[v]
        base = np.arctan2(out_dir[1], out_dir[0])
        rays = sorted(ends.get(v, []),
                      key=lambda we: (np.arctan2(*(cp[we[0]] - cp[v])[::-1]) - base) % (2 * np.pi))
        # ray list: outgoing edge (var None), diagonals, incoming edge (var None)
        seq = [(int(nxt[v]), None)] + rays + [(int(prv[v]), None)]
        for s in range(len(seq) - 1):
            x, ex = seq[s]
            within, const = [], False
            for y, ey in seq[s + 1:]:
                o = orient(cp[v, 0], cp[v, 1], cp[x, 0], cp[x, 1], cp[y, 0], cp[y, 1])
                if o < 0 or (o == 0 and not straight):
                    break
                if ey is None:
                    const = True
                else:
                    within.append(ey)
            if const:
                continue
            # s_x <= sum(within)  (s_x = 1 for the polygon edge)
            coeffs = [(ey, 1.0) for ey in within]
            if ex is None:
                add(coeffs, 1.0)
            else:
                add(coeffs + [(ex, -1.0)], 0.0)
    if lo:
        A = coo_matrix((vals, (rows, cols)), shape=(len(lo), E)).tocsr()
        cons = [LinearConstraint(A, np.array(lo), np.inf)]
    else:  # pragma: no cover - a reflex vertex always adds a constraint
        cons = []
    res = milp(np.ones(E), integrality=np.ones(E), bounds=Bounds(0, 1), constraints=cons,
               options={"time_limit": time_limit})
    if res.status != 0 or res.x is None:
        return None
    chosen = np.flatnonzero(res.x > 0.5)
    return faces_from_diagonals(cp, a[chosen], b[chosen])

