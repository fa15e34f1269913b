"""The union of the tile meshes: global numbering and its check.

The check (:func:`check_union`) derives everything from the tile meshes and the
decomposition, with the exact orientation predicate: conforming along the separators,
the domain's area, every input vertex and segment kept, the requested min angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import VerificationError
from hammesh.mesh import Mesh
from hammesh.parallel.tiles import Decomposition
from hammesh.predicates import orient_many

__all__ = ["global_ids", "offsets", "assemble", "check_union", "min_angles_deg", "UnionFacts", "AREA_RTOL"]

AREA_RTOL = 1e-9


def global_ids(decomp: Decomposition, tile: int, n_points: int, offset: int) -> np.ndarray:
    """Global index of every point of tile ``tile``'s mesh: its tile vertices, then
    its Steiner points numbered from ``offset``."""
    ids = decomp.tiles[tile].vertex_ids
    return np.concatenate([ids, offset + np.arange(n_points - len(ids), dtype=np.int64)])


def offsets(decomp: Decomposition, n_points: list[int]) -> np.ndarray:
    """Where each tile's Steiner points start in the global numbering."""
    extra = [n - len(t.vertex_ids) for t, n in zip(decomp.tiles, n_points)]
    return len(decomp.vertices) + np.concatenate([[0], np.cumsum(extra)[:-1]]).astype(np.int64)


def assemble(decomp: Decomposition, meshes: list[Mesh], start: np.ndarray | None = None) -> Mesh:
    """The tile meshes as one mesh in the global numbering (separators not constrained).

    The segments are the tiles' constrained edges minus the separators, each once;
    ``triangle_attributes`` are the tiles' (regional attributes), else the tile index.
    ``start``: where each tile's Steiner points start (default: one after the other,
    :func:`offsets`).
    """
    if start is None:
        start = offsets(decomp, [m.n_points for m in meshes])
    points = [decomp.vertices]
    tris, segs, marks, owner = [], [], [], []
    sep_keys = _keys(decomp.segments[decomp.separator], 1 << 40)
    for i, m in enumerate(meshes):
        g = global_ids(decomp, i, m.n_points, int(start[i]))
        points.append(m.points[len(decomp.tiles[i].vertex_ids):])
        tris.append(g[m.triangles])
        s = g[m.segments]
        keep = ~np.isin(_keys(s, 1 << 40), sep_keys)
        segs.append(s[keep])
        marks.append(m.segment_markers[keep])
        at = np.asarray(m.triangle_attributes)
        owner.append(at if at.ndim == 2 and at.shape[1] else np.full((len(m.triangles), 1), i, np.float64))
    seg = np.concatenate(segs)
    mk = np.concatenate(marks)
    k = _keys(seg, 1 << 40)
    _, first = np.unique(k, return_index=True)
    return Mesh(
        points=np.concatenate(points),
        triangles=np.concatenate(tris),
        segments=seg[np.sort(first)],
        segment_markers=mk[np.sort(first)],
        triangle_attributes=np.concatenate(owner),
        info={"tiles": len(meshes)},
    )


def _keys(edges: np.ndarray, base: int) -> np.ndarray:
    e = np.sort(np.asarray(edges, dtype=np.int64).reshape(-1, 2), axis=1)
    return e[:, 0] * base + e[:, 1]


def min_angles_deg(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    la = np.linalg.norm(b - c, axis=1)
    lb = np.linalg.norm(c - a, axis=1)
    lc = np.linalg.norm(a - b, axis=1)
    # law of cosines on the shortest side: the smallest angle is opposite it
    s = np.sort(np.stack([la, lb, lc], axis=1), axis=1)
    cos = (s[:, 1] ** 2 + s[:, 2] ** 2 - s[:, 0] ** 2) / (2 * s[:, 1] * s[:, 2])
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


@dataclass(frozen=True)
class UnionFacts:
    """What :func:`check_union` established."""

    triangles: int
    area: float
    min_angle_deg: float
    separator_edges: int
    triangles_below_min_angle: int


def check_union(decomp: Decomposition, union: Mesh, *, single_run_min_angle: float | None = None) -> UnionFacts:
    """Check that the union of the tile meshes is one valid mesh of the domain.

    1. every triangle counter-clockwise by the exact predicate;
    2. edge-manifold and conforming: no directed edge twice; every separator
       subsegment is an edge of the union with triangles on both sides (it was kept
       whole by both tiles); no separator subsegment lies on the union's boundary;
    3. the area equals the domain's (the coarse constrained triangulation's) within
       ``AREA_RTOL``;
    4. every input vertex the domain uses is used, and every boundary edge of the
       union lies on the decomposition's user segments (the input segments, cut and
       discretised): the union's boundary is the domain's;
    5. every input segment piece is kept: each is an edge of the union or the union's
       constrained edges along it add up to its length;
    6. min angle >= the requested one (``decomp.min_angle``), except where the
       single Triangle run of the whole domain does not reach it either
       (``single_run_min_angle``, measured by the caller): then >= that.

    Raises
    ------
    VerificationError
        Naming the fault.
    """
    p = union.points
    t = union.triangles
    n = len(p)
    o = orient_many(np.ascontiguousarray(p), np.ascontiguousarray(t)) if len(t) else np.zeros(0)
    if (np.asarray(o) <= 0).any():
        i = int(np.flatnonzero(np.asarray(o) <= 0)[0])
        raise VerificationError(f"union: triangle {i} is not counter-clockwise")
    # 2. directed edges
    d = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    dk = d[:, 0] * n + d[:, 1]
    uniq, cnt = np.unique(dk, return_counts=True)
    if (cnt > 1).any():
        k = int(uniq[np.argmax(cnt > 1)])
        raise VerificationError(f"union: directed edge ({k // n}, {k % n}) is used twice (tiles overlap)")
    rk = d[:, 1] * n + d[:, 0]
    boundary = ~np.isin(dk, rk, assume_unique=False)
    sep = decomp.segments[decomp.separator]
    fwd = sep[:, 0] * n + sep[:, 1]
    back = sep[:, 1] * n + sep[:, 0]
    both = np.isin(fwd, uniq) & np.isin(back, uniq)
    if not both.all():
        i = int(np.flatnonzero(~both)[0])
        a, b = sep[i]
        raise VerificationError(
            f"union: separator edge ({a}, {b}) at {decomp.vertices[a].tolist()} is not shared by two tiles' triangles")
    # 3. area
    pa, pb, pc = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    area = float(0.5 * ((pb[:, 0] - pa[:, 0]) * (pc[:, 1] - pa[:, 1]) - (pb[:, 1] - pa[:, 1]) * (pc[:, 0] - pa[:, 0])).sum())
    if abs(area - decomp.area) > AREA_RTOL * max(abs(decomp.area), 1e-300) * max(1.0, np.sqrt(len(t))):
        raise VerificationError(f"union: area {area!r} differs from the domain's {decomp.area!r}")
    # 4. vertices and boundary
    used = np.zeros(n, bool)
    used[t.ravel()] = True
    coarse_used = np.zeros(len(decomp.coarse_points), bool)
    coarse_used[decomp.coarse_triangles.ravel()] = True
    need = coarse_used[: decomp.n_input]
    if (need & ~used[: decomp.n_input]).any():
        i = int(np.flatnonzero(need & ~used[: decomp.n_input])[0])
        raise VerificationError(f"union: input vertex {i} is not used by any triangle")
    bnd = d[boundary]
    user = decomp.segments[~decomp.separator]
    seg_keys = np.concatenate([_keys(user, n), _keys(union.segments, n)])
    on = np.isin(_keys(bnd, n), seg_keys)
    if not on.all():
        a, b = bnd[np.argmax(~on)]
        raise VerificationError(f"union: boundary edge ({a}, {b}) lies on no input segment")
    # 5. segments kept
    edge_keys = np.unique(_keys(d, n))
    kept = np.isin(_keys(user, n), edge_keys)
    ends_used = used[user[:, 0]] & used[user[:, 1]]
    missing = user[ends_used & ~kept]
    if len(missing):
        # split by Triangle (internal segments may be): the pieces on the line must add up
        cs = union.segments
        cl = np.linalg.norm(p[cs[:, 0]] - p[cs[:, 1]], axis=1)
        new = ~np.isin(_keys(cs, n), _keys(user, n))
        ml = np.linalg.norm(p[missing[:, 0]] - p[missing[:, 1]], axis=1)
        if abs(cl[new].sum() - ml.sum()) > 1e-9 * max(ml.sum(), 1e-300):
            a, b = missing[0]
            raise VerificationError(f"union: input segment piece ({a}, {b}) is not kept")
    # 6. angles
    ang = min_angles_deg(p, t)
    amin = float(ang.min())
    below = 0
    if decomp.min_angle is not None:
        want = decomp.min_angle
        if single_run_min_angle is not None:
            want = min(want, single_run_min_angle)
        below = int((ang < want * (1 - 1e-9)).sum())
        if below:
            raise VerificationError(
                f"union: min angle {amin:.6f} deg is below the requested {want} deg ({below} triangles)")
    return UnionFacts(triangles=len(t), area=area, min_angle_deg=amin,
                      separator_edges=len(sep), triangles_below_min_angle=below)
