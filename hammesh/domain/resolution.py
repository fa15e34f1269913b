"""Is a domain's detail representable where its Hamiltonian mesh must place points?

Triangle meshes a 1e-6 square at offset 1e9, features of 10 ulps or vertices 1e-15
apart: its output points are the input ones plus Steiner points it rounds to
float64. A Hamiltonian mesh needs more: Thm 2.4 puts a Steiner point at every
triangle's incenter and promises that every output angle is at least half the input's
smallest, which is *tight* (an incenter triangle has exactly half an input angle).
Rounding an incenter to float64 moves it by up to half a unit in the last place
(ulp) of its coordinates, which turns an angle by about ``ulp / feature`` radians.
At 8 ulps (the 1e-6 square at 1e9) that is several degrees: no float64 point
satisfies the guarantee, in any frame, because the output must be given in the
input's coordinates (a translated or scaled frame does not survive the way back).
The run then fails its own certificate (issue 12: exit 3, "angle below half").

:func:`check_resolution` names such a domain (``hamiltonian`` calls it when its certificate fails), with an
:class:`~hammesh.errors.InvalidDomainError` naming the two closest vertices and
their distance in ulps, when that distance is below :data:`MIN_FEATURE_ULPS`.
Above it the rounding error is at most ``1 / MIN_FEATURE_ULPS`` of the smallest
feature. (Refinement can still make triangles smaller than the input's features;
their incenters are bounded the same way by the certificate's tolerance.)
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidDomainError

__all__ = ["check_resolution", "closest_pair_ulps", "snap_steiner_points", "check_rounding", "MIN_FEATURE_ULPS"]

#: Two distinct vertices closer than this many ulps of their coordinates are refused.
MIN_FEATURE_ULPS = 4096.0
_BRUTE_FORCE = 2048  # up to this many vertices, all pairs (no scipy.spatial import)


def closest_pair_ulps(vertices: np.ndarray) -> tuple[int, int, float, float]:
    """The pair of vertices closest in ulps of their own coordinates.

    Parameters
    ----------
    vertices : (n, 2) float64, pairwise distinct, n >= 2

    Returns
    -------
    i, j : int
        The pair (each vertex's nearest neighbour, in a local frame: exact
        differences, so no precision is lost far from the origin).
    distance : float
    ulps : float
        ``distance`` over the spacing of float64 at the pair's largest coordinate.
    """
    v = np.asarray(vertices, dtype=np.float64)
    local = v - v.min(axis=0)  # coordinates far out: distances from exact differences
    if len(v) <= _BRUTE_FORCE:  # small domains: no scipy.spatial import (0.2 s)
        d = np.empty(len(v))
        j = np.empty(len(v), np.int64)
        for a in range(0, len(v), 256):
            blk = local[a:a + 256]
            dd = np.hypot(blk[:, None, 0] - local[None, :, 0], blk[:, None, 1] - local[None, :, 1])
            dd[np.arange(len(blk)), a + np.arange(len(blk))] = np.inf
            j[a:a + 256] = np.argmin(dd, axis=1)
            d[a:a + 256] = dd[np.arange(len(blk)), j[a:a + 256]]
    else:
        from scipy.spatial import cKDTree

        tree = cKDTree(local, balanced_tree=False, compact_nodes=False)
        dist, idx = tree.query(local, k=2)
        d, j = dist[:, 1], idx[:, 1]
    mag = np.maximum(np.abs(v).max(axis=1), np.abs(v[j]).max(axis=1))
    ulps = d / np.spacing(np.maximum(mag, np.finfo(float).tiny))
    i = int(np.argmin(ulps))
    return i, int(j[i]), float(d[i]), float(ulps[i])


def check_resolution(vertices: np.ndarray) -> None:
    """Refuse vertices too close for a Hamiltonian mesh's Steiner points in float64.

    Raises
    ------
    InvalidDomainError
        Two vertices fewer than :data:`MIN_FEATURE_ULPS` ulps apart (message: the pair,
        the distance, the offset, what to do).

    Examples
    --------
    >>> sq = np.array([[0, 0], [1e-6, 0], [1e-6, 1e-6], [0, 1e-6]]) + 1e9
    >>> check_resolution(sq)
    Traceback (most recent call last):
    ...
    hammesh.errors.InvalidDomainError: vertices 0 and 1 are 9.54e-07 apart, only 8 float64 steps (ulps) at coordinates of 1e+09: ...
    >>> check_resolution(sq - 1e9)   # the same square near the origin is fine
    """
    v = np.asarray(vertices, dtype=np.float64)
    if len(v) < 2:
        return
    i, j, d, ulps = closest_pair_ulps(v)
    if ulps < MIN_FEATURE_ULPS:
        i, j = min(i, j), max(i, j)
        mag = float(np.abs(v[[i, j]]).max())
        raise InvalidDomainError(
            f"vertices {i} and {j} are {d:.3g} apart, only {ulps:.0f} float64 steps (ulps) at "
            f"coordinates of {mag:.3g}: the incenters of a Hamiltonian mesh cannot be placed "
            f"that finely (its half-angle guarantee would fail); translate the domain nearer "
            f"the origin or scale it up (features of at least {MIN_FEATURE_ULPS:.0f} ulps)")


def check_rounding(points: np.ndarray, triangles: np.ndarray, bound: float, mode: str = "incircle") -> None:
    """Refuse an output whose rows below the angle ``bound`` (radians) are all explained
    by float64 rounding: each misses it by less than rounding a corner by one ulp can
    turn an angle (``2 x spacing(|coordinate|) / shortest side``).

    Thm 2.4's bound is tight (an incenter triangle has exactly half an input angle), so
    where the mesh's triangles are only ~1e6 ulps wide (a 1e-4 feature at offset 1e7:
    coordinates in metres, features of a tenth of a millimetre) no float64 incenter keeps
    it to the certificate's 1e-9, in any frame; the input's closest vertices
    (:func:`check_resolution`) may still be far apart in ulps, because the refinement
    makes the small triangles. Nothing is refused when a row misses by more (a fault of
    the construction: the caller's ``VerificationError`` stands).

    Raises
    ------
    InvalidDomainError
        Naming the worst row, its size in ulps and the way out.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    angle = _min_angles(pts, tri)
    low = np.flatnonzero(angle < bound)
    if len(low) == 0:
        return
    corners = pts[tri[low]]  # (k, 3, 2)
    sides = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).min(axis=1)
    mag = np.abs(corners).max(axis=(1, 2))
    turn = 2.0 * np.spacing(np.maximum(mag, np.finfo(float).tiny)) / np.maximum(sides, np.finfo(float).tiny)
    if (bound - angle[low] > turn).any():
        return
    w = int(np.argmax(bound - angle[low]))
    ulps = sides[w] / np.spacing(max(mag[w], np.finfo(float).tiny))
    why, way = ((", and Thm 2.4's bound is exact (an incenter halves an angle)", "use mode='sparse', or ")
                if mode == "incircle" else ("", ""))
    raise InvalidDomainError(
        f"triangle {int(low[w])} misses the half-angle bound by {np.degrees(bound - angle[low[w]]):.2g} deg, "
        f"which rounding to float64 explains: its shortest side is only {ulps:.3g} float64 steps (ulps) at "
        f"coordinates of {mag[w]:.3g}{why}; {way}translate the domain nearer the origin or scale it up")


def _min_angles(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Smallest angle (radians) of each row, by ``atan2(|cross|, dot)`` at every corner."""
    return _corner_min_angles(pts[tri])


def _corner_min_angles(corners: np.ndarray) -> np.ndarray:
    """:func:`_min_angles` of rows given by their corners ``(..., 3, 2)``."""
    a, b, c = corners[..., 0, :], corners[..., 1, :], corners[..., 2, :]
    out = np.full(corners.shape[:-2], np.inf)
    for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
        u, v = q - p, r - p
        cross = np.abs(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0])
        out = np.minimum(out, np.arctan2(cross, (u * v).sum(axis=-1)))
    return out


def snap_steiner_points(
    points: np.ndarray,
    triangles: np.ndarray,
    n_fixed: int,
    bound: float,
    *,
    keep: np.ndarray | None = None,
    reach: int = 3,
    rounds: int = 6,
) -> tuple[np.ndarray, int]:
    """Move Steiner points to nearby float64 values where rounding broke the angle bound.

    Where features are a few ulps wide (a 1e-6 square at offset 1e9 is 8 ulps), the
    float64 point nearest an incenter can turn an angle by degrees; another nearby
    float64 point often keeps every incident angle above ``bound`` (the square: the
    lattice point (5, 3) ulps in from a corner, where the incenter is at (5.66, 2.34)).
    Each round, every movable Steiner point of a row below ``bound`` tries the points up
    to ``reach`` ulps away on each axis and takes the one whose incident rows have the
    largest smallest angle, all counter-clockwise by the exact predicate (coordinate
    descent: the rows of two Steiner points are improved in turn).

    Nothing here is trusted: the caller runs the full certificate on the result.

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64
    n_fixed : int
        Points ``0..n_fixed-1`` (the input's) never move.
    bound : float
        Radians.
    keep : (n,) bool, optional
        Steiner points that must not move either (e.g. midpoints of constrained edges,
        which must stay exact midpoints).

    Returns
    -------
    points : (n, 2) float64
        A copy with the moved points.
    moved : int
        How many points moved.
    """
    from hammesh.predicates import orient_rows

    pts = np.array(points, dtype=np.float64, copy=True)
    tri = np.asarray(triangles, dtype=np.int64)
    n = len(pts)
    movable = np.zeros(n, dtype=bool)
    movable[n_fixed:] = True
    if keep is not None:
        movable &= ~np.asarray(keep, dtype=bool)
    order = np.argsort(tri.ravel(), kind="stable")
    starts = np.searchsorted(tri.ravel()[order], np.arange(n + 1))
    steps = np.arange(-reach, reach + 1, dtype=np.float64)
    dx, dy = (g.ravel() for g in np.meshgrid(steps, steps))
    moved: set[int] = set()
    for _ in range(rounds):
        low = np.flatnonzero(_min_angles(pts, tri) < bound)
        cand = np.unique(tri[low].ravel())
        cand = cand[movable[cand]]
        if len(cand) == 0:
            break
        changed = False
        for s in cand.tolist():
            rows = tri[order[starts[s]:starts[s + 1]] // 3]  # the rows around s
            here = float(_min_angles(pts, rows).min())
            if here >= bound:
                continue
            x, y = pts[s]
            trial = np.c_[x + dx * np.spacing(abs(x)), y + dy * np.spacing(abs(y))]
            # every candidate position in every incident row: (k, r, 3, 2) corners
            corners = np.broadcast_to(pts[rows], (len(trial),) + rows.shape + (2,)).copy()
            at = rows == s
            corners[:, at] = trial[:, None, :]
            angle = _corner_min_angles(corners)  # (k, r)
            best = np.argsort(-angle.min(axis=1), kind="stable")
            for k in best[:8].tolist():
                if angle[k].min() <= here:
                    break
                c = corners[k]
                if (orient_rows(c[:, 0], c[:, 1], c[:, 2]) > 0).all():  # exact: no row turned over
                    pts[s] = trial[k]
                    moved.add(s)
                    changed = True
                    break
        if not changed:
            break
    return pts, len(moved)
