"""Sequential triangulations of sets with at most two interior points (paper §4, Lemma 4.2).

Lemma 4.2: a set in general position with at most two points strictly inside its
convex hull has a sequential triangulation (one alternating triangle strip).  The
proof, reproduced here, triangulates a small *core* around the interior points and
fills the rest of the hull by zigzags:

* **Zigzag of a convex piece.**  A strip that leaves a region through a chord
  ``(x, y)`` of the hull (``x`` the older of its two last vertices) into the convex
  piece beyond it is *forced*: the next vertex is the neighbour of ``x`` on the
  piece's hull chain, then the neighbour of ``y``, and so on alternately (any other
  vertex would make the next shared edge a hull edge or leave two pieces).  It is
  valid exactly when its last vertex, the *ear*, is a strict corner of the hull --
  always true in general position; with collinear hull points this decides which
  cores can be used.
* **0 interior points** ("trivial" in the paper): the strip starts with the ear at a
  strict corner ``s`` and zigzags over everything else.  Every sequential
  triangulation of a convex set is such a zigzag, so with collinear hull points the
  set has one *iff* some strict corner ``s`` has a strict corner as its ear; this
  is decided exactly in O(n) and ``None`` is a proof.
* **1 interior point** ``q``: the ray from a hull point ``p`` through ``q`` leaves
  the hull through an edge ``(p_i, p_{i+1})``; the core is the triangle
  ``(p, p_i, p_{i+1})`` split at ``q`` (strip ``p, p_i, q, p_{i+1}, p``), the pieces
  beyond ``(p, p_i)`` and ``(p_{i+1}, p)`` are zigzags.
* **2 interior points** ``q1, q2``: the line through them leaves the hull through
  edges ``(p_i, p_{i+1})`` (beyond ``q2``) and ``(p_j, p_{j+1})`` (beyond ``q1``); the
  core is the quadrilateral ``p_i, p_{i+1}, p_j, p_{j+1}`` (a triangle when the edges
  are consecutive), which contains both points, entered and left through its two
  chords.  The paper's cases -- 1: consecutive edges (Fig. 17); 2: a diagonal of
  the quadrilateral separates ``q1`` from ``q2`` (Fig. 18); 3: one side of the
  quadrilateral besides the two edges is a hull edge (Fig. 19); 4: the rest
  (Fig. 20) -- are reported by :func:`lemma42_plan`.  Measured on 3,000 random
  sets: case 1 always works with the triangle and case 2 with the quadrilateral;
  case 3 needs one more hull point (a neighbour of a corner) in about 60% of its
  instances, case 4 always does (the paper notes ``n > 4`` there, Figure 20 uses
  more hull points): the quadrilateral plus one neighbour works in about 70%,
  otherwise a *fan core* from one of the quadrilateral's four corners ``p``: ``p``
  and at most five consecutive fan triangles ``(p, p_t, p_{t+1})`` covering both
  interior points (the strip winds around one interior point and takes the other
  by the one-point pattern).

Our copy of the paper has the figures' captions but not their drawings, so the
numbering of the core points (Figures 17b-20b) is not transcribed: it is found by
the exhaustive strip search of :mod:`hammesh.pointset.sequential_search` run on the
core alone (at most 9 points, a constant), with the chords required at the strip's
ends and, at each end, the older vertex chosen so that the zigzag beyond it is
valid.  Evidence for general position: 13,000 random sets (3-200 hull points, one
or two interior points) were all constructed, case 4 needing the fan core in about
a third of its instances; ``tests/pointset/test_lemma42.py`` checks every case and
agreement with the exact search.

Without general position (collinear hull points, an interior point on a line
through hull points) the paper's cores can be degenerate or their zigzags invalid,
so fan cores from *every* hull point are tried as well (O(log n) to locate each, a
constant-size search each).  If none works :class:`NotConstructed` (an
:class:`~hammesh.errors.InvalidOptionError`) says so.  This is not a decision: of
3,000 random degenerate sets of at most 10 points, 127 were refused, and the exact
search found a sequential triangulation for one of them (a hull triangle with
collinear points on every edge, where the strip needs two separate cores joined by
a zigzag band).  The total is O(n log n) (O(n) plus a constant number of core
searches in general position); every result is certified (triangulates the set,
consecutive triangles share an edge, Thm 4.3 test).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.predicates import orient, orient_rows
from hammesh.pointset.sequential_search import check_sequential, strip_search, strip_triangles
from hammesh.pointset.validate import Hull, as_points, convex_hull

__all__ = ["few_interior_sequential", "lemma42_plan", "convex_sequential", "NotConstructed", "Plan"]


class NotConstructed(InvalidOptionError):
    """Lemma 4.2's construction does not apply (too many interior points, or degenerate input)."""


@dataclass(frozen=True)
class Plan:
    """How :func:`few_interior_sequential` built its strip.

    Attributes
    ----------
    case : str
        ``"convex"``, ``"one"``, ``"two/1"`` ... ``"two/4"`` (the paper's case of the
        two-point proof, from the hit edges of the line through the two points), or
        ``"none"`` (convex position, provably no sequential triangulation).
    core : tuple[int, ...]
        Point indices of the core's hull points (empty for convex position).
    source : str
        ``"zigzag"`` (convex position), ``"paper"`` (the proof's triangle,
        quadrilateral, or quadrilateral plus one neighbour), ``"quad-fan"`` (a fan core
        from a corner of the quadrilateral, case 4) or ``"fan"`` (a fan core from any
        hull point: degenerate input only).
    strip : tuple[int, ...]
        The strip's vertex sequence (empty for ``"none"``).
    """

    case: str
    core: tuple[int, ...]
    source: str
    strip: tuple[int, ...]


class _Ctx:
    """Hull positions of a checked point set."""

    def __init__(self, pts: np.ndarray, hull: Hull):
        self.pts = pts
        self.b = hull.boundary
        self.h = hull.h
        self.corner = hull.corner
        self.pos = np.full(len(pts), -1, dtype=np.int64)
        self.pos[self.b] = np.arange(self.h)
        self.inner = np.flatnonzero(self.pos < 0)
        self._hits: dict[tuple[int, int], tuple[int, bool]] = {}

    def o(self, a: int, b: int, c: int) -> int:
        p = self.pts
        return int(orient(p[a, 0], p[a, 1], p[b, 0], p[b, 1], p[c, 0], p[c, 1]))

    # -- zigzags -------------------------------------------------------------

    def ear(self, lo: int, hi: int, older_is_hi: bool) -> int | None:
        """Last hull position of the zigzag :meth:`piece` (O(1)), ``None`` if it is empty."""
        L = (hi - lo) % self.h - 1
        if L <= 0:
            return None
        half = (L + 1) // 2
        if older_is_hi:  # hi side first: lo+L, lo+1, lo+L-1, ...
            return (lo + L - half + 1 if L % 2 else lo + L // 2) % self.h
        return (lo + half if L % 2 else lo + L // 2 + 1) % self.h

    def piece_ok(self, lo: int, hi: int, older_is_hi: bool) -> bool:
        """The zigzag beyond the chord is valid: empty, or its ear is a strict corner."""
        e = self.ear(lo, hi, older_is_hi)
        return e is None or bool(self.corner[e])

    def piece(self, lo: int, hi: int, older_is_hi: bool) -> list[int] | None:
        """Zigzag over hull positions strictly between ``lo`` and ``hi`` (CCW from ``lo``).

        The strip arrives through the chord ``(lo, hi)``, its older vertex being ``hi``
        or ``lo``; returns the point indices appended, or ``None`` if the ear is not a
        strict corner (a triangle would be degenerate).
        """
        if not self.piece_ok(lo, hi, older_is_hi):
            return None
        h = self.h
        L = (hi - lo) % h - 1
        if L <= 0:
            return []
        k = np.arange(L)
        lo_side = lo + 1 + k // 2
        hi_side = lo + L - k // 2
        first_hi = (k % 2 == 0) == older_is_hi
        out = np.where(first_hi, hi_side, lo_side) % h
        return self.b[out].tolist()

    # -- ray location ----------------------------------------------------------

    def fan_hit(self, k: int, q: int) -> tuple[int, bool]:
        """Where the ray from hull position ``k`` through interior ``q`` leaves the hull.

        Returns ``(t, on_vertex)``: the ray crosses the edge ``(t, t + 1)`` (positions),
        or passes through position ``t`` itself when ``on_vertex``.  O(log h): the sign
        of ``orient(p_k, q, p_{k+s})`` is ``- ... - (0) + ... +`` for ``s = 1 .. h-1``.
        """
        key = (k, q)
        if key in self._hits:
            return self._hits[key]
        h, b = self.h, self.b
        p = int(b[k])
        lo, hi = 1, h - 1  # smallest s with sign >= 0 lies in [lo, hi]
        while lo < hi:
            mid = (lo + hi) // 2
            if self.o(p, q, int(b[(k + mid) % h])) >= 0:
                hi = mid
            else:
                lo = mid + 1
        t = (k + lo) % h
        hit = (t, True) if self.o(p, q, int(b[t])) == 0 else ((t - 1) % h, False)
        self._hits[key] = hit
        return hit


def _zigzag_strip(ctx: _Ctx) -> list[int] | None:
    """Convex position: the zigzag from a strict corner whose ear is a strict corner."""
    h, b = ctx.h, ctx.b
    for s in np.flatnonzero(ctx.corner):
        s = int(s)
        # strip s, s+1, s-1, s+2, ... (older s is the hi end of the arc s+1 .. s), or
        # strip s, s-1, s+1, ... (older s is the lo end of the arc s .. s-1)
        for lo, hi, older_is_hi, second in ((s + 1, s + h, True, s + 1), (s, s - 1 + h, False, s - 1)):
            if ctx.piece_ok(lo, hi, older_is_hi):  # O(1) per corner
                return [int(b[s]), int(b[second % h])] + ctx.piece(lo, hi, older_is_hi)
    return None


def _core_strip(ctx: _Ctx, core_pos: list[int]) -> list[int] | None:
    """Strip over the core (hull positions ``core_pos`` + all interior points) and the zigzags."""
    h, b = ctx.h, ctx.b
    K = sorted({int(k) % h for k in core_pos})
    if len(K) < 3:
        return None
    chords = []  # (lo, hi, {older point: (lo position, hi position, older is hi)})
    for ka, kb in zip(K, K[1:] + K[:1]):
        if (kb - ka) % h > 1:
            opts = {}
            for older_is_hi, older in ((True, int(b[kb])), (False, int(b[ka]))):
                if ctx.piece_ok(ka, kb, older_is_hi):  # O(1): zigzags are built at the end
                    opts[older] = (ka, kb, older_is_hi)
            if not opts:
                return None
            chords.append((int(b[ka]), int(b[kb]), opts))
    if len(chords) > 2:
        return None
    ring = [int(b[k]) for k in K]
    for q in ctx.inner:  # every interior point strictly inside the core
        for u, v in zip(ring, ring[1:] + ring[:1]):
            if ctx.o(u, v, int(q)) <= 0:
                return None

    def end_ok(x: int, y: int) -> bool:
        lo, hi, opts = chords[-1]
        return {x, y} == {lo, hi} and x in opts

    def start_ok(x: int, y: int) -> bool:
        lo, hi, opts = chords[0]
        return {x, y} == {lo, hi} and y in opts

    idx = ring + [int(q) for q in ctx.inner]
    core = strip_search(
        ctx.pts,
        idx,
        start_ok if len(chords) == 2 else None,
        end_ok if chords else None,
    )
    if core is None:
        return None
    head: list[int] = []
    tail: list[int] = []
    if chords:
        tail = ctx.piece(*chords[-1][2][core[-2]])
    if len(chords) == 2:
        head = ctx.piece(*chords[0][2][core[1]])[::-1]
    return head + core + tail


def _paper_cores(ctx: _Ctx) -> Iterator[tuple[str, list[int]]]:
    """The cores of the proof of Lemma 4.2, with the paper's case names."""
    h = ctx.h
    if len(ctx.inner) == 1:
        q = int(ctx.inner[0])
        for k in range(h):
            t, on_vertex = ctx.fan_hit(k, q)
            if not on_vertex:
                yield "one", [k, t, t + 1]
        return
    q1, q2 = (int(v) for v in ctx.inner)
    e_i, e_j = _hit_edges(ctx)
    seen = set()
    for i in e_i:
        for j in e_j:
            if i == j:
                continue
            quad = [i, i + 1, j, j + 1]
            case = _case(ctx, i, j, q1, q2)
            for extra in (None, i - 1, i + 2, j - 1, j + 2):
                core = quad if extra is None else quad + [extra]
                key = tuple(sorted({c % h for c in core}))
                if key not in seen:
                    seen.add(key)
                    yield case, core


def _hit_edges(ctx: _Ctx) -> tuple[list[int], list[int]]:
    """Hull edges (by first position) the line ``q1 q2`` leaves through, beyond ``q2`` and ``q1``.

    A line through a hull point offers both edges at that point.
    """
    q1, q2 = (int(v) for v in ctx.inner)
    pts, b = ctx.pts, ctx.b
    k = len(b)
    sign = orient_rows(
        np.broadcast_to(pts[q1], (k, 2)).copy(), np.broadcast_to(pts[q2], (k, 2)).copy(), pts[b]
    ).astype(np.int64)
    nxt = np.roll(sign, -1)
    # CCW around q1: right (-) to left (+) is the ray beyond q2, (+) to (-) beyond q1
    e_i = np.flatnonzero((sign <= 0) & (nxt >= 0) & ~((sign == 0) & (nxt == 0)))
    e_j = np.flatnonzero((sign >= 0) & (nxt <= 0) & ~((sign == 0) & (nxt == 0)))
    return e_i.tolist(), e_j.tolist()


def _case_of(ctx: _Ctx) -> str:
    e_i, e_j = _hit_edges(ctx)
    q1, q2 = (int(v) for v in ctx.inner)
    return _case(ctx, e_i[0], e_j[0], q1, q2)


def _mk(ctx: _Ctx, case: str, core: list[int], source: str, strip: list[int]) -> Plan:
    ring = tuple(int(ctx.b[c]) for c in sorted({c % ctx.h for c in core}))
    return Plan(case, ring, source, tuple(strip))


def _case(ctx: _Ctx, i: int, j: int, q1: int, q2: int) -> str:
    """The paper's case (1-4) of the two-point proof for hit edges ``i`` (near q2), ``j``."""
    h, b = ctx.h, ctx.b
    P = lambda t: int(b[t % h])  # noqa: E731
    if (j + 1) % h == i % h or (i + 1) % h == j % h:
        return "two/1"

    def inside(q: int, a: int, bb: int, c: int) -> bool:
        s = [ctx.o(a, bb, q), ctx.o(bb, c, q), ctx.o(c, a, q)]
        return all(x >= 0 for x in s) or all(x <= 0 for x in s)

    pi, pi1, pj, pj1 = P(i), P(i + 1), P(j), P(j + 1)
    if (inside(q1, pi1, pj, pj1) and inside(q2, pi, pi1, pj1)) or (
        inside(q1, pi, pj, pj1) and inside(q2, pi, pi1, pj)
    ):
        return "two/2"
    if (j + 1) % h == (i - 1) % h or (i + 2) % h == j % h:
        return "two/3"
    return "two/4"


#: Most fan triangles a fan core may span.
FAN_WIDTH = 5


def _fan_cores(ctx: _Ctx, apexes: Iterator[int] | list[int]) -> Iterator[list[int]]:
    """Fan cores: ``p_k`` and an arc of ``p_k``'s fan triangles holding every interior point.

    The fan triangles from hull position ``k`` are ``(p_k, p_{k+d}, p_{k+d+1})``,
    ``d = 1 .. h-2``; the narrowest range holding the interior points comes first,
    then wider ones (up to :data:`FAN_WIDTH` triangles).  Core: ``k`` and the arc.
    """
    h = ctx.h
    for k in apexes:
        k = int(k) % h
        lo, hi = h, -1
        for q in ctx.inner:
            t, on_vertex = ctx.fan_hit(k, int(q))
            d = (t - k) % h
            lo, hi = min(lo, d - 1 if on_vertex else d), max(hi, d)
        if lo < 1 or hi > h - 2:
            continue
        for width in range(hi - lo + 1, FAN_WIDTH + 1):
            for a in range(max(1, hi - width + 1), min(lo, h - 1 - width) + 1):
                yield [k] + [k + d for d in range(a, a + width + 1)]


def _plan(pts: np.ndarray) -> Plan:
    hull = convex_hull(pts)
    ctx = _Ctx(pts, hull)
    k = len(ctx.inner)
    if k == 0:
        strip = _zigzag_strip(ctx)
        if strip is None:
            return Plan("none", (), "zigzag", ())
        return Plan("convex", (), "zigzag", tuple(strip))
    if k > 2:
        raise NotConstructed(
            f"{k} points are inside the hull; Lemma 4.2 covers at most two"
        )
    for case, core in _paper_cores(ctx):
        strip = _core_strip(ctx, core)
        if strip is not None:
            return _mk(ctx, case, core, "paper", strip)
    fallback = []
    if k == 2:  # case 4 (and degenerate input): fans from the quadrilateral's corners
        e_i, e_j = _hit_edges(ctx)
        corners = [c for i in e_i for j in e_j for c in (i, i + 1, j, j + 1)]
        fallback.append(("quad-fan", list(dict.fromkeys(c % ctx.h for c in corners))))
    fallback.append(("fan", range(ctx.h)))  # degenerate input only
    for source, apexes in fallback:
        for core in _fan_cores(ctx, apexes):
            strip = _core_strip(ctx, core)
            if strip is not None:
                case = "one" if k == 1 else _case_of(ctx)
                return _mk(ctx, case, core, source, strip)
    flat = int((~ctx.corner).sum())
    why = (
        f"{flat} hull points lie on hull edges (collinear), and the lemma assumes general position"
        if flat
        else "the lemma assumes general position (is an interior point on a line through two "
        "other points?)"
    )
    raise NotConstructed(
        f"Lemma 4.2's construction found no core for these {len(pts)} points ({k} interior): {why}"
    )


def lemma42_plan(points: np.ndarray) -> Plan:
    """The construction :func:`few_interior_sequential` uses (case, core, strip), unverified.

    Raises
    ------
    NotConstructed
        More than two interior points, or degenerate input no core works for.
    """
    return _plan(as_points(points))


def few_interior_sequential(points: np.ndarray) -> np.ndarray | None:
    """Sequential triangulation of a set with at most two interior points (Lemma 4.2).

    Parameters
    ----------
    points : (n, 2) float64
        Distinct points, at most two of them strictly inside the convex hull.

    Returns
    -------
    (2 n - h - 2, 3) int64 or None
        Counter-clockwise triangles in strip order, certified (Thm 4.3).  ``None``
        only for a set in convex position whose collinear hull points leave no
        zigzag valid, which proves it has no sequential triangulation.

    Raises
    ------
    NotConstructed
        (an :class:`~hammesh.errors.InvalidOptionError`) more than two interior
        points, or input not in general position for which no core works.

    Examples
    --------
    >>> import numpy as np
    >>> ang = np.linspace(0, 2 * np.pi, 9)[:-1]
    >>> pts = np.vstack([np.c_[np.cos(ang), np.sin(ang)], [[0.1, 0.2], [-0.3, 0.05]]])
    >>> few_interior_sequential(pts).shape      # 2 * 10 - 8 - 2 triangles, one strip
    (10, 3)
    """
    pts = as_points(points)
    plan = _plan(pts)
    if not plan.strip:
        return None
    return check_sequential(pts, strip_triangles(pts, plan.strip))


def convex_sequential(points: np.ndarray) -> np.ndarray:
    """Sequential triangulation of a point set in convex position (Lemma 4.2, no interior point).

    Parameters
    ----------
    points : (n, 2) float64
        Every point on the hull boundary.

    Returns
    -------
    (n - 2, 3) int64
        Counter-clockwise triangles in strip order, certified (Thm 4.3).

    Raises
    ------
    InvalidOptionError
        A point is strictly inside the hull, or collinear hull points leave no valid
        zigzag (then the set has no sequential triangulation at all).

    Examples
    --------
    >>> import numpy as np
    >>> ang = np.linspace(0, 2 * np.pi, 7)[:-1]
    >>> convex_sequential(np.c_[np.cos(ang), np.sin(ang)]).shape
    (4, 3)
    """
    pts = as_points(points)
    hull = convex_hull(pts)
    if hull.h != len(pts):
        raise InvalidOptionError(
            f"{len(pts) - hull.h} points are inside the hull; convex_sequential needs convex position"
        )
    tri = few_interior_sequential(pts)
    if tri is None:
        raise InvalidOptionError(
            "collinear hull points: no zigzag from a strict corner ends at a strict corner, "
            "so this convex set has no sequential triangulation"
        )
    return tri
