"""Hamiltonian cycle surfaces: one cycle (strip) per connected piece of a 3D surface mesh.

The sparse construction of ``hammesh.postprocess.sparse`` on a triangle surface of any
genus, with or without boundary.  Real-world surfaces need not be clean manifolds
(issue 12): the surface is cut into pieces at every edge that is not *proper*
(:mod:`hammesh.strips.defects`: exactly two triangles using it in opposite directions),
so non-manifold edges, flipped neighbours and the seam of a non-orientable surface
(Klein bottle, Boy surface, Möbius strip) become piece boundaries, and each piece is
an oriented manifold (pinched vertices allowed) with its own cycle.  Rows that repeat
a vertex, zero-area rows (:data:`~hammesh.strips.defects.ZERO_AREA_RTOL`) and further
copies of a row with the same winding are dropped (they hold no area; listed in the
report); a double-sided face keeps both sides.  Every kept triangle keeps its winding.
On each piece:

* a cycle cover of the dual graph (``hammesh.postprocess.cycle_cover``; on a closed
  surface the dual is cubic and the cover is a 2-factor, as in Gopi & Eppstein 2004);
* cycles joined by *midpoint bridges*: the two triangles on either side of an edge are
  split at their incenters and the edge at its midpoint (the conformal variant of
  Thm 2.4, Arkin et al.). Every new triangle lies inside one input triangle, in its
  plane, so the surface is kept exactly (same points, same area, same boundary) and
  the planar angle argument applies inside each input triangle: the minimum angle is
  at least half the input's. The certificate (``hammesh.verify.surface``) checks all
  of it, including that every output triangle lies in its parent's plane.

``swaps=True`` also allows Steiner-free edge flips (the 2D mode's swaps) where the
angles allow: far fewer Steiner points, but a flipped pair of triangles spans a
different (folded) quadrilateral, so the surface moves by up to the pair's
out-of-plane height; the report gives the area change and the largest height, and the
certificate then checks everything but the exact-geometry item.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from hammesh import params

from hammesh.errors import InvalidMeshError
from hammesh.halfedge import mesh_arrays
from hammesh.mesh import HamiltonianMesh, cycle_positions
from hammesh.point_data import carry_point_data
from hammesh.postprocess.sparse import count_report, sparse_cycles
from hammesh.strips.defects import (
    MeshDefects,
    mesh_defects,
    proper_pairing,
    triangle_repeats,
    zero_area_rows,
)
from hammesh.verify.surface import verify_surface

__all__ = ["surface_hamiltonian", "prepare_surface", "PreparedSurface", "surface_angles", "unweld_cuts"]


class PreparedSurface(NamedTuple):
    """A surface ready for the construction (:func:`prepare_surface`)."""

    points: np.ndarray  #: (n, 3) float64
    triangles: np.ndarray  #: (k, 3) int64: the kept rows
    twin: np.ndarray  #: (3 k,) int64: proper pairing, -1 on boundaries and cuts
    rows: np.ndarray  #: (k,) int64: input row of each kept triangle
    defects: MeshDefects


def surface_angles(points: np.ndarray, triangles: np.ndarray) -> tuple[float, int, float, np.ndarray]:
    """``(min angle, argmin row, max angle, areas)`` of the construction's input; radians, 3D areas.

    (The certificate computes its own, :mod:`hammesh.verify.surface`.)
    """
    p = points[triangles]
    e = np.roll(p, -1, axis=1) - p  # e[:, k]: from vertex k to k + 1
    area = 0.5 * np.linalg.norm(np.cross(e[:, 0], e[:, 1]), axis=1)
    u = -np.roll(e, 1, axis=1)  # at vertex k: towards k - 1
    cr = np.linalg.norm(np.cross(e, u), axis=2)
    a = np.arctan2(cr, (e * u).sum(axis=2))
    amin = a.min(axis=1)
    i = int(np.argmin(amin))
    return float(amin[i]), i, float(a.max()), area


def unweld_cuts(triangles: np.ndarray, twin: np.ndarray, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Give each umbrella of a vertex its own copy: cut edges then join no triangles at all.

    The corners at a vertex are grouped by the proper edges between them (its
    *umbrellas*); the first umbrella keeps the vertex, each further one gets a new index
    ``n_points + j``.  The proper pairing is unchanged, and every cut edge (non-manifold,
    flipped, the seam of a non-orientable piece) becomes plain boundary on each side, so
    the construction sees an oriented manifold with boundary; the caller maps the copies
    back afterwards.

    Returns
    -------
    triangles : (m, 3) int64
        Renumbered corners.
    copy_of : (c,) int64
        The original vertex of each copy ``n_points + j``.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    tri = np.asarray(triangles, dtype=np.int64)
    m = len(tri)
    h = np.flatnonzero(twin >= 0)
    g = twin[h]
    nxt = lambda x: 3 * (x // 3) + (x % 3 + 1) % 3  # noqa: E731  (corner at the head of half-edge x)
    # half-edge h: corner h (its tail) ~ corner at the head of its twin; head of h ~ tail of twin
    a = np.r_[h, nxt(h)]
    b = np.r_[nxt(g), g]
    graph = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(3 * m, 3 * m))
    _, label = connected_components(graph, directed=False)
    vert = tri.reshape(-1)
    # one id per (vertex, umbrella): the umbrella holding the vertex's first corner keeps it
    order = np.lexsort((label, vert))
    v_s, l_s = vert[order], label[order]
    new_group = np.r_[True, (v_s[1:] != v_s[:-1]) | (l_s[1:] != l_s[:-1])]
    first_of_vertex = np.r_[True, v_s[1:] != v_s[:-1]]
    extra = new_group & ~first_of_vertex
    copy_id = np.cumsum(extra) - 1 + n_points
    start = np.maximum.accumulate(np.where(new_group, np.arange(len(v_s)), 0))  # first row of each group
    ids = np.where(extra[start], copy_id[start], v_s)
    out = np.empty(3 * m, np.int64)
    out[order] = ids
    return out.reshape(-1, 3), v_s[extra].astype(np.int64)


def prepare_surface(points: np.ndarray, triangles: np.ndarray) -> PreparedSurface:
    """Check a surface mesh, drop what holds no area, pair its proper edges.

    2D points get ``z = 0``.

    Raises
    ------
    InvalidMeshError
        Shapes, non-finite or out-of-range items, or no triangle of positive area.
    """
    pts, tri = mesh_arrays(points, triangles, dims=(2, 3))
    if pts.shape[1] == 2:
        pts = np.c_[pts, np.zeros(len(pts))]
    m = len(tri)
    repeated = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 2] == tri[:, 0])
    zero = zero_area_rows(pts, tri) & ~repeated
    _, _, dup = triangle_repeats(tri)
    dup &= ~(repeated | zero)
    rows = np.flatnonzero(~(repeated | zero | dup))
    if len(rows) == 0:
        raise InvalidMeshError(f"none of the {m} triangles has a positive area: no surface")
    kept = np.ascontiguousarray(tri[rows])
    pairing = proper_pairing(kept, len(pts))
    found = mesh_defects(pts, kept, pairing, repeated=int(repeated.sum()), zero_area=int(zero.sum()))
    found = MeshDefects(**(found.to_dict() | {"duplicate": int(dup.sum())}))
    return PreparedSurface(pts, kept, pairing.twin, rows.astype(np.int64), found)


def _check_options(points, triangles, max_fold_deg, triangle_attributes, attribute_names, point_data) -> None:
    """The options' shapes against the mesh's rows and points (before any work)."""
    params.number("max_fold_deg", max_fold_deg, low=0, high=180, what="degrees")
    n = np.shape(points)[0] if np.ndim(points) == 2 else 0
    m = np.shape(triangles)[0] if np.ndim(triangles) == 2 else 0
    if triangle_attributes is not None:
        shape = np.shape(triangle_attributes)
        if len(shape) != 2 or shape[0] != m:
            raise params.invalid("triangle_attributes", f"<array of shape {shape}>",
                                 f"an (m, k) array with one row per triangle (m = {m})")
        if attribute_names and len(attribute_names) != shape[1]:
            raise params.invalid("attribute_names", tuple(attribute_names),
                                 f"one name per attribute column ({shape[1]})")
    for key, values in (point_data or {}).items():
        if np.ndim(values) not in (1, 2) or np.shape(values)[0] != n:
            raise params.invalid(f"point_data[{key!r}]", f"<array of shape {np.shape(values)}>",
                                 f"one value or row per point (n = {n})")


def surface_hamiltonian(
    points: np.ndarray,
    triangles: np.ndarray,
    *,
    swaps: bool = False,
    max_fold_deg: float = 10.0,
    split_all: bool = False,
    triangle_attributes: np.ndarray | None = None,
    attribute_names: tuple[str, ...] = (),
    point_data: dict[str, np.ndarray] | None = None,
) -> HamiltonianMesh:
    """Make a triangle surface a verified Hamiltonian cycle surface, few Steiner points.

    Parameters
    ----------
    points : (n, 3) float64 (or (n, 2): z = 0)
    triangles : (m, 3) int64
        Any triangle surface: any genus, boundaries, non-manifold edges, flipped or
        non-orientable pieces, degenerate or doubled rows (see the module docstring).
    swaps : bool
        Also use Steiner-free edge flips (changes the surface slightly; see module).
    max_fold_deg : float
        With ``swaps``: only between triangles whose normals differ by at most this.
    split_all : bool
        Baseline: no cycle cover, every triangle split at its incenter and joined by
        midpoint bridges along a spanning tree (Thm 2.4's construction on a surface).
    triangle_attributes : (m, k) float64, optional
        Per-triangle values (a file's cell data): each output triangle takes its
        parent's row; ``attribute_names`` names the columns.
    point_data : dict of str to (n,) or (n, c) arrays, optional
        Per-point values: kept at the input points, interpolated linearly at Steiner
        points inside their input triangle (integers: the nearest corner's;
        :func:`hammesh.point_data.carry_point_data`).

    Returns
    -------
    HamiltonianMesh
        With 3D ``points``; triangles in cycle order, one cycle per connected piece;
        ``kind`` 0 incenter sector, 2 midpoint, 3 input triangle, 4 swapped;
        ``parent`` the input row; ``report`` with the counts, 3D angles in and out,
        areas, ``defects`` (what was found) and ``dropped_rows``, ``verified: True``.

    Raises
    ------
    InvalidMeshError
    VerificationError

    Examples
    --------
    >>> from hammesh.surface import icosphere, surface_hamiltonian
    >>> h = surface_hamiltonian(*icosphere(2))
    >>> len(h.components), h.report["verified"]
    (1, True)
    """
    t0 = time.perf_counter()
    _check_options(points, triangles, max_fold_deg, triangle_attributes, attribute_names, point_data)
    prep = prepare_surface(points, triangles)
    pts, tri, twin = prep.points, prep.triangles, prep.twin
    n, m = len(pts), len(tri)
    amin, _, amax_in, _ = surface_angles(pts, tri)
    tri_u, copy_of = unweld_cuts(tri, twin, n)
    r = sparse_cycles(
        np.concatenate([pts, pts[copy_of]]), tri_u, twin, np.zeros(3 * m, np.bool_), amin, swaps=swaps and not split_all,
        edge_splits=not split_all, flip_bridges=False, max_fold_deg=max_fold_deg, use_cover=not split_all,
    )
    r = _weld_back(r, n, copy_of)
    lengths = r.lengths
    parent = prep.rows[r.parent]  # input rows
    t1 = time.perf_counter()
    stats = verify_surface(
        r.points, r.triangles, lengths, reference_points=points, reference_triangles=triangles, parent=parent,
        exact=not swaps,
    )
    t2 = time.perf_counter()
    report = count_report(r, n, m)
    m_in = int(np.asarray(triangles).reshape(-1, 3).shape[0])
    keep = np.zeros(m_in, dtype=bool)
    keep[prep.rows] = True
    report["input_triangles"] = m_in
    report["defects"] = prep.defects.to_dict()
    report["dropped_rows"] = np.flatnonzero(~keep).tolist()
    for key in ("retries", "flips"):  # plane-only notions
        report.pop(key, None)
    report |= {
        "min_angle_input_deg": stats["min_angle_input_deg"],
        "min_angle_output_deg": stats["min_angle_output_deg"],
        "max_angle_output_deg": stats["max_angle_output_deg"],
        "max_angle_input_deg": float(np.degrees(amax_in)),
        "area_input": stats["area_input"],
        "area_change_rel": stats["area_change_rel"],
        "exact_surface": not swaps,
        "mode": "surface-all" if split_all else "surface-sparse" + ("+swaps" if swaps else ""),
        "verified": True,
        "seconds": {"hamiltonian": t1 - t0, "verify": t2 - t1},
    }
    if swaps:
        report["max_swap_height"] = _swap_height(r.points, r.triangles, r.kind, r.parent, pts, tri)
    position = cycle_positions(lengths)
    h = HamiltonianMesh(
        points=r.points,
        triangles=r.triangles,
        segments=np.zeros((0, 2), np.int64),
        segment_markers=np.zeros(0, np.int64),
        components=lengths,
        position=position,
        parent=parent,
        kind=r.kind,
        triangle_attributes=(np.zeros((len(r.triangles), 0)) if triangle_attributes is None
                             else np.asarray(triangle_attributes, dtype=np.float64).reshape(m_in, -1)[parent]),
        attribute_names=tuple(attribute_names) if triangle_attributes is not None else (),
        point_data=carry_point_data(point_data or {}, pts, tri, r.points, r.triangles, r.parent, r.kind),
        report=report,
    )
    return h


def _weld_back(r, n: int, copy_of: np.ndarray):
    """Map the copies of :func:`unweld_cuts` back to their vertices in a construction's result."""
    c = len(copy_of)
    if c == 0:
        return r
    t = r.triangles
    t = np.where(t >= n + c, t - c, np.where(t >= n, copy_of[np.clip(t - n, 0, c - 1)], t))
    pts = np.concatenate([r.points[:n], r.points[n + c :]])
    return replace(r, points=pts, triangles=t)


def _swap_height(points, tri, kind, parent, pts_in, tri_in) -> float:
    """Largest distance of a swapped triangle's vertex from its parent input triangle's plane."""
    rows = np.flatnonzero(kind == 4)
    if len(rows) == 0:
        return 0.0
    q = pts_in[tri_in[parent[rows]]]
    nrm = np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    d = np.abs(((points[tri[rows]] - q[:, :1]) * nrm[:, None]).sum(axis=2))
    return float(d.max())
