"""What the certificate knows about the input mesh, found by its own code.

The construction checks and orients its input with ``hammesh.halfedge``; the
certificate does not read any of that (nor a cache in ``Mesh.info``): from the
caller's mesh it takes a copy of the points and, with its own kernels
(``hammesh.verify._kernels``) and the exact orientation predicate
(``hammesh.predicates``), orients the rows, pairs their half-edges, and measures
the smallest angle, the area, the used vertices, the boundary and the constrained
edges. It reads the caller's rows twice (a scan, then the bucket matching, with the
orientation flips of the scan) and copies none of them: of the pairing it keeps only
the boundary edges. A construction bug in any of those steps therefore cannot reach the
certificate's side of the comparison.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import VerificationError
from hammesh.mesh import Mesh
from hammesh.pages import fresh
from hammesh.verify import _kernels

__all__ = ["InputFacts", "input_facts", "KEY_BASE", "edge_keys", "boundary_keys", "undirected_keys"]

#: Directed edge keys ``a * KEY_BASE + b``: one base for input and output (any vertex < 2**31).
KEY_BASE = 1 << 32


def edge_keys(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Keys of the directed edges ``a[i] -> b[i]``."""
    return a.astype(np.int64) * KEY_BASE + b.astype(np.int64)


def undirected_keys(edges: np.ndarray, n_points: int) -> np.ndarray:
    """Keys ``lo * n_points + hi`` of undirected edges (as :func:`_kernels.find_edges` wants)."""
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    return np.minimum(e[:, 0], e[:, 1]) * np.int64(n_points) + np.maximum(e[:, 0], e[:, 1])


def boundary_keys(tri: np.ndarray, twin: np.ndarray) -> np.ndarray:
    """Sorted keys of the directed boundary edges (half-edges without partner)."""
    e = _kernels.boundary_half_edges(tri, twin)
    return np.sort(edge_keys(e[:, 0], e[:, 1]))


@dataclass(frozen=True, eq=False)
class InputFacts:
    """The certificate's facts about an input mesh (see :func:`input_facts`)."""

    points: np.ndarray  # (n, 2) float64, a copy taken before the construction ran
    segments: np.ndarray  # (s, 2) int64 constrained edges, each an edge of the input
    used: np.ndarray  # (n,) bool: vertex of some triangle
    min_angle: float  # radians
    area: float
    boundary: np.ndarray  # sorted directed boundary edge keys, rows counter-clockwise
    #: the input's rows as the caller gave them (int64; no copy where they were): only
    #: read where the float areas disagree (:func:`hammesh.verify.certificate.area_rounding_bound`)
    triangles: np.ndarray | None = None


def _bad_input(msg: str) -> None:
    raise VerificationError(f"the input mesh is not a valid triangulation: {msg}", check="input")


def input_facts(mesh: Mesh) -> InputFacts:
    """Derive the input's facts the certificate compares the output with.

    Parameters
    ----------
    mesh : Mesh
        The input as the caller gave it (either orientation of rows).

    Raises
    ------
    VerificationError
        The input itself is not a valid planar triangulation (named).
    """
    pts = np.asarray(mesh.points)
    if pts.ndim == 2 and pts.shape[1] == 2:  # (a copy, in pages from the reserve: hammesh.pages)
        src, pts = pts, fresh(pts.shape, np.float64)
        pts[...] = src
    else:
        pts = np.array(pts, dtype=np.float64, copy=True)
    tri = np.asarray(mesh.triangles)
    if pts.ndim != 2 or pts.shape[1] != 2:
        _bad_input(f"points have shape {pts.shape}, not (n, 2)")
    if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0 or not np.issubdtype(tri.dtype, np.integer):
        _bad_input(f"triangles have shape {tri.shape} and dtype {tri.dtype}, not (m > 0, 3) integers")
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    n, m = len(pts), len(tri)
    if not np.isfinite(pts).all():
        _bad_input(f"point {int(np.argmin(np.isfinite(pts).all(axis=1)))} is not finite")
    # one pass over the rows as given (no counter-clockwise copy: the pairing reads
    # them again with the flips), then the bucket matching; both the certificate's own
    flip = fresh(m, np.bool_, 0)
    used = fresh(n, np.bool_, 0)
    start = fresh(n + 1, np.int64, 0)
    scan = _kernels.scan_input_into(pts, tri, flip, used, start)
    if scan.bad_index >= 0:
        t = scan.bad_index
        _bad_input(f"triangle {t} {tri[t].tolist()} references a vertex outside 0..{n - 1}")
    if scan.bad >= 0:
        t = scan.bad
        _bad_input(f"triangle {t} {tri[t].tolist()} is degenerate (exact orientation test)")
    if not (np.isfinite(scan.min_angle) and np.isfinite(scan.total_area)):
        _bad_input("angles and areas are not finite (coordinates too large or too small)")
    # the constrained edges are looked up in the matching's buckets (no pass of their
    # own); a bad segment array is named after the rows' faults, as before
    segs = np.asarray(mesh.segments)
    segs = np.zeros((0, 2), dtype=np.int64) if segs.size == 0 else segs
    seg_fault = None
    if segs.ndim != 2 or segs.shape[1] != 2 or not np.issubdtype(segs.dtype, np.integer):
        seg_fault = f"segments have shape {segs.shape}, not (s, 2) integers"
    else:
        segs = np.ascontiguousarray(segs, dtype=np.int64)
        if len(segs) and (segs.min() < 0 or segs.max() >= n):
            s = int(np.argmax(((segs < 0) | (segs >= n)).any(axis=1)))
            seg_fault = f"segment {s} {segs[s].tolist()} references a vertex outside 0..{n - 1}"
    seg_keys = undirected_keys(segs, n) if seg_fault is None else np.zeros(0, np.int64)
    want = np.unique(seg_keys)
    found = np.zeros(len(want), np.bool_)
    keys = fresh(3 * m, np.int32 if 2 * n + 1 < 2**31 else np.int64)
    boundary, ok = _kernels.input_boundary_into(tri, flip, start, keys, want, found)
    del keys
    if not ok:  # name the edge: the rows counter-clockwise, paired with half-edge names
        ccw = tri.copy()
        ccw[flip] = ccw[flip][:, ::-1]
        _, dup = _kernels.half_edge_twins(ccw, n)
        t, k = divmod(int(dup), 3)
        _bad_input(
            f"edge ({ccw[t, k]}, {ccw[t, (k + 1) % 3]}) of triangle {t} is shared by more than two "
            "triangles or by two on the same side (non-manifold edge or overlap)"
        )
    if seg_fault is not None:
        _bad_input(seg_fault)
    if len(segs):
        found = found[np.searchsorted(want, seg_keys)]  # (undirected)
        if not found.all():
            s = int(np.argmin(found))
            _bad_input(f"segment {s} {segs[s].tolist()} is not an edge of the mesh")
    return InputFacts(
        points=pts,
        segments=segs,
        used=used,
        min_angle=float(scan.min_angle),
        area=float(scan.total_area),
        boundary=np.sort(boundary),
        triangles=tri,
    )
