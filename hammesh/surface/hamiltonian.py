"""Hamiltonian cycle surfaces: one cycle (strip) per connected piece of a 3D surface mesh.

The sparse construction of ``hammesh.postprocess.sparse`` on a manifold, consistently
oriented triangle surface of any genus, with or without boundary:

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
import numpy as np

from hammesh.halfedge import _kernels
from hammesh.errors import InvalidMeshError
from hammesh.mesh import HamiltonianMesh, cycle_positions
from hammesh.postprocess.sparse import count_report, sparse_cycles
from hammesh.halfedge import mesh_arrays
from hammesh.verify.surface import surface_angles, verify_surface

__all__ = ["surface_hamiltonian", "prepare_surface"]


def prepare_surface(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Check a surface mesh; return ``(points (n, 3), triangles (m, 3), twin (3 m,))``.

    2D points get ``z = 0``.

    Raises
    ------
    InvalidMeshError
        Shapes, non-finite or out-of-range items, a triangle with a repeated vertex
        or zero area, two triangles on the same vertices, an edge shared by three
        triangles or inconsistently oriented.
    """
    pts, tri = mesh_arrays(points, triangles, dims=(2, 3))
    if pts.shape[1] == 2:
        pts = np.c_[pts, np.zeros(len(pts))]
    rep = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 2] == tri[:, 0])
    if rep.any():
        t = int(np.argmax(rep))
        raise InvalidMeshError(f"triangle {t} {tri[t].tolist()} repeats a vertex")
    _, _, _, area = surface_angles(pts, tri)
    if not area.min() > 0:
        t = int(np.argmin(area))
        raise InvalidMeshError(f"triangle {t} {tri[t].tolist()} has zero area")
    srt = np.sort(tri, axis=1)
    o = np.lexsort(srt.T[::-1])
    same = (srt[o[1:]] == srt[o[:-1]]).all(axis=1)
    if same.any():
        i = int(np.argmax(same))
        raise InvalidMeshError(f"triangles {int(o[i])} and {int(o[i + 1])} have the same vertices {tri[o[i]].tolist()}")
    twin, bad = _kernels.half_edge_twins(tri, len(pts))
    if bad >= 0:
        t, k = divmod(int(bad), 3)
        raise InvalidMeshError(
            f"edge ({tri[t, k]}, {tri[t, (k + 1) % 3]}) of triangle {t} is shared by more than two "
            "triangles or by two in the same direction (non-manifold edge or inconsistent orientation)"
        )
    return pts, tri, twin


def surface_hamiltonian(
    points: np.ndarray,
    triangles: np.ndarray,
    *,
    swaps: bool = False,
    max_fold_deg: float = 10.0,
    split_all: bool = False,
) -> HamiltonianMesh:
    """Make a triangle surface a verified Hamiltonian cycle surface, few Steiner points.

    Parameters
    ----------
    points : (n, 3) float64 (or (n, 2): z = 0)
    triangles : (m, 3) int64
        Edge-manifold and consistently oriented; any genus, boundaries allowed.
    swaps : bool
        Also use Steiner-free edge flips (changes the surface slightly; see module).
    max_fold_deg : float
        With ``swaps``: only between triangles whose normals differ by at most this.
    split_all : bool
        Baseline: no cycle cover, every triangle split at its incenter and joined by
        midpoint bridges along a spanning tree (Thm 2.4's construction on a surface).

    Returns
    -------
    HamiltonianMesh
        With 3D ``points``; triangles in cycle order, one cycle per connected piece;
        ``kind`` 0 incenter sector, 2 midpoint, 3 input triangle, 4 swapped;
        ``report`` with the counts, 3D angles in and out, areas, ``verified: True``.

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
    pts, tri, twin = prepare_surface(points, triangles)
    n, m = len(pts), len(tri)
    amin, _, amax_in, _ = surface_angles(pts, tri)
    r = sparse_cycles(
        pts, tri, twin, np.zeros(3 * m, np.bool_), amin, swaps=swaps and not split_all,
        edge_splits=not split_all, flip_bridges=False, max_fold_deg=max_fold_deg, use_cover=not split_all,
    )
    lengths = r.lengths
    t1 = time.perf_counter()
    stats = verify_surface(
        r.points, r.triangles, lengths, reference_points=pts, reference_triangles=tri, parent=r.parent, exact=not swaps
    )
    t2 = time.perf_counter()
    report = count_report(r, n, m)
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
        parent=r.parent,
        kind=r.kind,
        triangle_attributes=np.zeros((len(r.triangles), 0)),
        report=report,
    )
    return h


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
