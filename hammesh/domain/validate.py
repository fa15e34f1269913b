"""Validation of a planar straight-line graph before it reaches Triangle.

Triangle (a C library) trusts its input: duplicate vertices, crossing segments,
out-of-range indices or huge coordinates make it loop, silently split segments or
crash the interpreter with SIGSEGV.  :func:`validate_domain` therefore checks every
precondition in numpy first and raises :class:`~hammesh.errors.InvalidDomainError`
with a one-line message naming the offending field, index or point.

Decisions
---------
* Crossing segments are rejected (not split at the intersection).
* A segment passing through a vertex that is not one of its endpoints is rejected
  (Triangle would silently split it there).  Segments sharing an endpoint are fine.
* Orientation tests use float64 cross products; ``|cross| <= 1e-14 * scale**2`` counts
  as collinear, where ``scale`` is the larger side of the vertices' bounding box.

Complexity: sorting for duplicates, and a uniform grid (cell size adapted to the
segment lengths) whose candidate pairs are tested in vectorized chunks, so about
``O((n + s) log(n + s))`` for well-spread inputs; 100k boundary segments take well
under a second.  Known weak spot: many long segments closer together than their length
(a vertex of degree 10^4, stacks of thousands of long thin strips) put thousands of
segments into one cell, and the work grows with the number of pairs sharing a cell
(about 10^7 pairs per second).
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidDomainError

__all__ = ["validate_domain", "point_array", "MAX_ABS_COORDINATE", "COLLINEAR_RTOL"]

#: Beyond this magnitude Triangle's floating-point predicates overflow.
MAX_ABS_COORDINATE = 1e30
#: ``|cross| <= COLLINEAR_RTOL * scale**2`` is treated as collinear.
COLLINEAR_RTOL = 1e-14

_PAIR_CHUNK = 1 << 20  # candidate pairs tested per vectorized batch
_XY = ("x coordinate", "y coordinate")


def point_array(value, what: str, rows: str = "k") -> np.ndarray:
    """``value`` as a new ``(k, 2) float64`` array, or an error naming ``what``.

    ``rows`` is how the message names the row count (``"n"`` for a point set).

    Raises
    ------
    InvalidDomainError
        Not numbers, or not of shape ``(k, 2)``.
    """
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidDomainError(f"{what} cannot be converted to float64: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidDomainError(f"{what} must have shape ({rows}, 2), got {arr.shape}")
    return arr


def validate_domain(domain) -> None:
    """Check that ``domain`` is a valid planar straight-line graph for Triangle.

    Parameters
    ----------
    domain : Domain or any object with the attributes
        ``vertices (n, 2) float64``, ``segments (s, 2) int64``, ``holes (h, 2) float64``,
        ``regions (r, 4) float64`` (x, y, attribute, max_area with NaN = no limit),
        ``segment_markers (s,) int64`` and ``vertex_markers (n,) int64``.

    Raises
    ------
    InvalidDomainError
        On the first problem found, in this order: field shapes and dtypes; non-finite
        or too large (> 1e30) coordinates; fewer than 3 vertices; duplicate vertices;
        all vertices collinear; segment indices out of range or repeated; duplicate
        segments; crossing or collinearly overlapping segments; a segment through a
        vertex; region max_area not NaN or > 0.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> bad = SimpleNamespace(vertices=np.zeros((3, 2)), segments=np.zeros((0, 2), np.int64),
    ...                       holes=np.zeros((0, 2)), regions=np.zeros((0, 4)),
    ...                       segment_markers=np.zeros(0, np.int64),
    ...                       vertex_markers=np.zeros(3, np.int64))
    >>> validate_domain(bad)
    Traceback (most recent call last):
    ...
    hammesh.errors.InvalidDomainError: vertices 0 and 1 are duplicates: both at (0.0, 0.0)
    """
    vertices = _field(domain, "vertices", np.float64, 2)
    segments = _field(domain, "segments", np.int64, 2)
    holes = _field(domain, "holes", np.float64, 2)
    regions = _field(domain, "regions", np.float64, 4)
    segment_markers = _field(domain, "segment_markers", np.int64, None)
    vertex_markers = _field(domain, "vertex_markers", np.int64, None)
    n, s = len(vertices), len(segments)
    if segment_markers.shape != (s,):
        raise InvalidDomainError(
            f"segment_markers must have shape ({s},) (one per segment), got {segment_markers.shape}")
    if vertex_markers.shape != (n,):
        raise InvalidDomainError(
            f"vertex_markers must have shape ({n},) (one per vertex), got {vertex_markers.shape}")

    _check_points(vertices, "vertex", _XY)
    _check_points(holes, "hole", _XY)
    _check_points(regions[:, :3], "region", _XY + ("attribute",))
    _check_max_area(regions)

    if n < 3:
        raise InvalidDomainError(f"a domain needs at least 3 vertices, got {n}")
    _check_duplicate_vertices(vertices)
    tol = _check_not_collinear(vertices)

    if s:
        _check_segment_indices(segments, n)
        _check_duplicate_segments(segments)
        _check_segment_geometry(vertices, segments, tol)


# ----------------------------------------------------------------------------- fields

def _field(domain, name, dtype, ncols):
    try:
        value = getattr(domain, name)
    except AttributeError:
        raise InvalidDomainError(f"domain has no field {name!r}") from None
    if not isinstance(value, np.ndarray):
        raise InvalidDomainError(f"{name} must be a numpy array, got {type(value).__name__}")
    if value.dtype != dtype:
        raise InvalidDomainError(f"{name} must have dtype {np.dtype(dtype)}, got {value.dtype}")
    if ncols is not None and (value.ndim != 2 or value.shape[1] != ncols):
        raise InvalidDomainError(f"{name} must have shape (k, {ncols}), got {value.shape}")
    if ncols is None and value.ndim != 1:
        raise InvalidDomainError(f"{name} must be one-dimensional, got shape {value.shape}")
    return value


def _fmt(x) -> str:
    return repr(float(x))


def _point(p) -> str:
    return f"({_fmt(p[0])}, {_fmt(p[1])})"


def _check_points(values, what, columns):
    if values.size == 0:
        return
    bad = ~np.isfinite(values)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise InvalidDomainError(
            f"{what} {i} has a non-finite {columns[j]} ({_fmt(values[i, j])})")
    big = np.abs(values) > MAX_ABS_COORDINATE
    if big.any():
        i, j = np.argwhere(big)[0]
        raise InvalidDomainError(
            f"{what} {i} has {columns[j]} = {_fmt(values[i, j])} beyond +-{MAX_ABS_COORDINATE:g}; "
            "Triangle's predicates would overflow (rescale the domain)")


def _check_max_area(regions):
    area = regions[:, 3]
    bad = ~(np.isnan(area) | ((area > 0) & np.isfinite(area)))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidDomainError(
            f"region {i} has max_area {_fmt(area[i])}; it must be NaN (no limit) "
            "or a finite number > 0")


# ----------------------------------------------------------------------------- vertices

def _check_duplicate_vertices(vertices):
    order = np.lexsort((np.arange(len(vertices)), vertices[:, 1], vertices[:, 0]))
    v = vertices[order]
    same = np.flatnonzero((v[1:] == v[:-1]).all(axis=1))
    if same.size:
        # report the duplicate pair whose later index is smallest
        pairs = np.stack([order[same], order[same + 1]], axis=1)
        pairs.sort(axis=1)
        i, j = pairs[np.lexsort((pairs[:, 0], pairs[:, 1]))[0]]
        raise InvalidDomainError(
            f"vertices {i} and {j} are duplicates: both at {_point(vertices[i])}")


def _check_not_collinear(vertices) -> float:
    """Raise if all vertices are collinear; return the collinearity tolerance."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    scale = float((hi - lo).max())
    tol = COLLINEAR_RTOL * scale * scale
    axis = int(np.argmax(hi - lo))
    a = vertices[np.argmin(vertices[:, axis])]
    b = vertices[np.argmax(vertices[:, axis])]
    cross = _orient(a, b, vertices)
    if np.all(np.abs(cross) <= tol):
        raise InvalidDomainError(
            f"all {len(vertices)} vertices are collinear (the convex hull has zero area)")
    return tol


def _orient(a, b, c):
    """Twice the signed area of (a, b, c); positive when counter-clockwise."""
    a, b, c = np.asarray(a), np.asarray(b), np.asarray(c)
    return ((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))


def _sign(x, tol):
    return np.where(x > tol, 1, np.where(x < -tol, -1, 0))


# ----------------------------------------------------------------------------- segments

def _check_segment_indices(segments, n):
    neg = segments < 0
    if neg.any():
        i, j = np.argwhere(neg)[0]
        raise InvalidDomainError(f"segment {i} references negative vertex index {segments[i, j]}")
    out = segments >= n
    if out.any():
        i, j = np.argwhere(out)[0]
        raise InvalidDomainError(
            f"segment {i} references vertex {segments[i, j]} but there are only {n} vertices")
    same = np.flatnonzero(segments[:, 0] == segments[:, 1])
    if same.size:
        i = int(same[0])
        raise InvalidDomainError(
            f"segment {i} has zero length: both ends are vertex {segments[i, 0]}")


def _check_duplicate_segments(segments):
    key = np.sort(segments, axis=1)
    order = np.lexsort((np.arange(len(key)), key[:, 1], key[:, 0]))
    k = key[order]
    same = np.flatnonzero((k[1:] == k[:-1]).all(axis=1))
    if same.size:
        pairs = np.stack([order[same], order[same + 1]], axis=1)
        pairs.sort(axis=1)
        i, j = pairs[np.lexsort((pairs[:, 0], pairs[:, 1]))[0]]
        a, b = segments[i]
        raise InvalidDomainError(
            f"segments {i} and {j} are duplicates: both connect vertices {a} and {b}")


def _grid(vertices, segments, tol):
    """Bucket segments into a uniform grid.

    Returns ``(origin, h, ncols, seg_of_entry, key_of_entry)`` with entries sorted by
    cell key; every segment is entered in every cell its (padded) bounding box touches.
    """
    a = vertices[segments[:, 0]]
    b = vertices[segments[:, 1]]
    length = np.hypot(*(b - a).T)
    # pad so that points within the collinearity tolerance of a segment share a cell
    pad = tol / length + 1e-12 * max(float(np.abs(vertices).max()), 1.0)
    lo = np.minimum(a, b) - pad[:, None]
    hi = np.maximum(a, b) + pad[:, None]
    origin = vertices.min(axis=0) - pad.max()
    extent = float((vertices.max(axis=0) - origin).max()) + pad.max()
    s = len(segments)
    h = max(float(np.median(np.abs(b - a).max(axis=1))), extent / 2.0**30)  # keys < 2**62
    while True:
        c0 = np.floor((lo - origin) / h).astype(np.int64)
        c1 = np.floor((hi - origin) / h).astype(np.int64)
        span = c1 - c0 + 1
        cover = span[:, 0] * span[:, 1]
        if cover.sum() <= 16 * s + 64 or extent / h < 2:
            break
        h *= 2.0
    ncols = int(np.floor((extent + 2 * pad.max()) / h)) + 3
    seg = np.repeat(np.arange(s), cover)
    start = np.cumsum(cover) - cover
    local = np.arange(len(seg)) - np.repeat(start, cover)
    w = np.repeat(span[:, 1], cover)
    cx = np.repeat(c0[:, 0], cover) + local // w
    cy = np.repeat(c0[:, 1], cover) + local % w
    key = cx * ncols + cy
    order = np.argsort(key, kind="stable")
    return origin, h, ncols, seg[order], key[order]


def _pairs_in_groups(keys):
    """Yield chunks ``(p, q)`` of positions ``p < q`` in ``keys`` (sorted) with equal keys."""
    m = len(keys)
    if m < 2:
        return
    new = np.ones(m, bool)
    new[1:] = keys[1:] != keys[:-1]
    gstart = np.flatnonzero(new)
    gsize = np.diff(np.append(gstart, m))
    group_end = np.repeat(gstart + gsize, gsize)
    after = group_end - np.arange(m) - 1  # partners following each entry in its group
    pos = 0
    while pos < m:
        csum = np.cumsum(after[pos:])
        stop = pos + max(int(np.searchsorted(csum, _PAIR_CHUNK, side="right")), 1)
        cnt = after[pos:stop]
        total = int(cnt.sum())
        if total:
            p = np.repeat(np.arange(pos, stop), cnt)
            offs = np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            yield p, p + 1 + offs
        pos = stop


def _check_segment_geometry(vertices, segments, tol):
    origin, h, ncols, seg, key = _grid(vertices, segments, tol)
    a_all = vertices[segments[:, 0]]
    b_all = vertices[segments[:, 1]]
    for p, q in _pairs_in_groups(key):
        i, j = seg[p], seg[q]
        i, j = np.minimum(i, j), np.maximum(i, j)
        found = _test_segment_pairs(vertices, segments, a_all, b_all, i, j, tol)
        if found is not None:  # deterministic: smallest bad pair of the first bad chunk
            raise InvalidDomainError(found[2])
    _check_vertices_on_segments(vertices, segments, a_all, b_all, tol, origin, h, ncols, seg, key)


def _test_segment_pairs(vertices, segments, a_all, b_all, i, j, tol):
    """Test candidate pairs ``i < j``; return ``(i, j, message)`` of the first bad pair."""
    # bounding-box filter (with a tolerance margin)
    lo_i, hi_i = np.minimum(a_all[i], b_all[i]), np.maximum(a_all[i], b_all[i])
    lo_j, hi_j = np.minimum(a_all[j], b_all[j]), np.maximum(a_all[j], b_all[j])
    margin = 1e-12 * max(float(np.abs(vertices).max()), 1.0) + np.sqrt(tol)
    keep = ((lo_i <= hi_j + margin) & (lo_j <= hi_i + margin)).all(axis=1)
    i, j = i[keep], j[keep]
    if i.size == 0:
        return None
    si, sj = segments[i], segments[j]
    a, b, c, d = vertices[si[:, 0]], vertices[si[:, 1]], vertices[sj[:, 0]], vertices[sj[:, 1]]
    shared = (si[:, :, None] == sj[:, None, :])  # (k, 2, 2)
    nshared = shared.sum(axis=(1, 2))

    bad = np.zeros(len(i), bool)
    kind = np.zeros(len(i), np.int8)  # 1 cross, 2 overlap, 3 touch, 4 overlap at shared end

    # pairs without a shared endpoint
    d1, d2 = _orient(a, b, c), _orient(a, b, d)
    d3, d4 = _orient(c, d, a), _orient(c, d, b)
    s1, s2, s3, s4 = (_sign(x, tol) for x in (d1, d2, d3, d4))
    free = nshared == 0
    collinear = free & (((s1 == 0) & (s2 == 0)) | ((s3 == 0) & (s4 == 0)))
    cross = free & ~collinear & (s1 * s2 < 0) & (s3 * s4 < 0)
    touch = free & ~collinear & ~cross & (s1 * s2 <= 0) & (s3 * s4 <= 0)
    # collinear overlap: project on the direction of the longer segment
    ab, cd = b - a, d - c
    use_ab = (ab * ab).sum(1) >= (cd * cd).sum(1)
    o = np.where(use_ab[:, None], a, c)
    u = np.where(use_ab[:, None], ab, cd)
    t = [((x - o) * u).sum(1) for x in (a, b, c, d)]
    lo1, hi1 = np.minimum(t[0], t[1]), np.maximum(t[0], t[1])
    lo2, hi2 = np.minimum(t[2], t[3]), np.maximum(t[2], t[3])
    overlap = collinear & (np.maximum(lo1, lo2) < np.minimum(hi1, hi2))
    kind[cross] = 1
    kind[overlap] = 2
    kind[touch] = 3
    bad |= cross | overlap | touch

    # pairs sharing one endpoint: bad only if they overlap collinearly
    one = nshared == 1
    if one.any():
        k = np.flatnonzero(one)
        sh = shared[k]
        ii = np.argmax(sh.any(axis=2), axis=1)  # position of shared vertex in segment i
        jj = np.argmax(sh.any(axis=1), axis=1)  # position in segment j
        pivot = vertices[si[k, ii]]
        u_end = vertices[si[k, 1 - ii]]
        w_end = vertices[sj[k, 1 - jj]]
        col = np.abs(_orient(pivot, u_end, w_end)) <= tol
        same_dir = ((u_end - pivot) * (w_end - pivot)).sum(1) > 0
        hit = k[col & same_dir]
        kind[hit] = 4
        bad[hit] = True

    if not bad.any():
        return None
    cand = np.flatnonzero(bad)
    first = cand[np.lexsort((j[cand], i[cand]))[0]]
    I, J = int(i[first]), int(j[first])
    kd = kind[first]
    if kd == 1:
        x = c[first] + (d[first] - c[first]) * (d1[first] / (d1[first] - d2[first]))
        msg = f"segments {I} and {J} cross at {_point(x)}"
    elif kd == 2:
        o_, u_ = o[first], u[first]
        uu = float((u_ * u_).sum())
        p0 = o_ + u_ * (max(lo1[first], lo2[first]) / uu)
        p1 = o_ + u_ * (min(hi1[first], hi2[first]) / uu)
        msg = f"segments {I} and {J} overlap collinearly between {_point(p0)} and {_point(p1)}"
    elif kd == 4:
        ends_i, ends_j = set(segments[I].tolist()), set(segments[J].tolist())
        pivot = (ends_i & ends_j).pop()
        (ui,), (wj,) = ends_i - {pivot}, ends_j - {pivot}
        near = ui if (np.sum((vertices[ui] - vertices[pivot]) ** 2)
                      <= np.sum((vertices[wj] - vertices[pivot]) ** 2)) else wj
        msg = (f"segments {I} and {J} overlap collinearly between "
               f"{_point(vertices[pivot])} and {_point(vertices[near])}")
    else:
        # one endpoint lies on the other segment (T-junction)
        sg = [s1[first], s2[first], s3[first], s4[first]]
        z = sg.index(0)
        seg_idx, vtx = [(I, segments[J, 0]), (I, segments[J, 1]),
                        (J, segments[I, 0]), (J, segments[I, 1])][z]
        msg = (f"segment {seg_idx} passes through vertex {vtx} at {_point(vertices[vtx])}, "
               "which is not one of its endpoints")
    return I, J, msg


def _check_vertices_on_segments(vertices, segments, a_all, b_all, tol,
                                origin, h, ncols, seg, key):
    cell = np.floor((vertices - origin) / h).astype(np.int64)
    vkey = cell[:, 0] * ncols + cell[:, 1]
    left = np.searchsorted(key, vkey, side="left")
    right = np.searchsorted(key, vkey, side="right")
    cnt = right - left
    step = _PAIR_CHUNK
    csum = np.cumsum(cnt)
    vstart = 0
    n = len(vertices)
    while vstart < n:
        base = csum[vstart - 1] if vstart else 0
        vstop = max(int(np.searchsorted(csum, base + step, side="right")), vstart + 1)
        vstop = min(vstop, n)
        c = cnt[vstart:vstop]
        m = int(c.sum())
        if m:
            v = np.repeat(np.arange(vstart, vstop), c)
            offs = np.arange(m) - np.repeat(np.cumsum(c) - c, c)
            sgi = seg[np.repeat(left[vstart:vstop], c) + offs]
            not_end = (segments[sgi, 0] != v) & (segments[sgi, 1] != v)
            v, sgi = v[not_end], sgi[not_end]
            a, b, p = a_all[sgi], b_all[sgi], vertices[v]
            on = ((np.abs(_orient(a, b, p)) <= tol)
                  & (((p - a) * (b - a)).sum(1) > 0)
                  & (((p - b) * (a - b)).sum(1) > 0))
            if on.any():
                k = np.flatnonzero(on)
                best = k[np.lexsort((v[k], sgi[k]))[0]]
                sgi, v = int(sgi[best]), int(v[best])
                raise InvalidDomainError(
                    f"segment {sgi} passes through vertex {v} at {_point(vertices[v])}, "
                    "which is not one of its endpoints")
        vstart = vstop
