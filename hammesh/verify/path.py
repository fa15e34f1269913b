"""The check of a stored Hamiltonian *path* mesh: ``hammesh check --path``.

``hammesh polygon`` (Thm 2.1, 2.3 with ``--steiner path``, 4.4) and ``hammesh points``
for some inputs write triangulations whose triangles, in file order, form a dual
Hamiltonian path: each triangle shares an edge with the next, the last not with the
first. The cycle certificate (:mod:`hammesh.verify.certificate`) refuses those by
design; this module checks what a path mesh promises, the same way:

1. every connected piece of the mesh is stored as one run of consecutive triangles
   (:func:`hammesh.verify.runs.infer_runs_and_pairing`, the certificate's own pairing);
2. inside each run every triangle shares an edge with the next one: the run is a
   Hamiltonian path of its piece's dual graph (it may close: a cycle is a path too);
3. every triangle is strictly counter-clockwise by the exact predicate
   (:func:`hammesh.predicates.orient_many`), and no directed edge is used twice
   (the pairing kernel refuses that);
4. every stored constrained edge is an edge of the triangles.

The caller (``hammesh check``) adds the exact overlap test of the plane. Nothing is
read from the construction: the file's rows are all there is.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hammesh.errors import InvalidMeshError, VerificationError
from hammesh.predicates import orient_many
from hammesh.verify._kernels import angle_area_stats
from hammesh.verify.certificate import has_edges
from hammesh.verify.runs import infer_runs_and_pairing

__all__ = ["verify_stored_path_mesh"]


def verify_stored_path_mesh(
    points: np.ndarray, triangles: np.ndarray, segments: np.ndarray | None = None
) -> tuple[np.ndarray, dict[str, Any], np.ndarray]:
    """Items 1-4 above for a mesh read from a file.

    Returns
    -------
    runs : (c,) int64
        The pieces' run lengths, in file order.
    stats : dict
        ``min_angle_output_deg``, ``max_angle_output_deg``, ``area``, ``closed_runs``
        (how many runs also close into a cycle).
    twin : (3 m,) int64
        The half-edge pairing (-1 on the boundary), for the caller's overlap test.

    Raises
    ------
    VerificationError
        Naming the first triangle, edge or piece at fault.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    if not np.isfinite(pts).all():
        raise VerificationError(f"point {int(np.argmax(~np.isfinite(pts).all(axis=1)))} is not finite", check="input")
    try:
        runs, twin = infer_runs_and_pairing(tri, len(pts))
    except InvalidMeshError as exc:  # (a file's rows that are no valid mesh fail the check)
        raise VerificationError(str(exc), check="input") from None
    m = len(tri)
    # triangle t links to t + 1 when one of its half-edges is paired with one of t + 1's
    neighbour = np.where(twin >= 0, twin // 3, -1).reshape(m, 3)
    links = (neighbour[:-1] == np.arange(1, m)[:, None]).any(axis=1)
    ends = np.cumsum(runs) - 1  # each run's last triangle: no link to the next run needed
    inside = np.ones(max(m - 1, 0), dtype=bool)
    inside[ends[:-1]] = False
    broken = np.flatnonzero(inside & ~links)
    if len(broken):
        t = int(broken[0])
        raise VerificationError(f"path breaks at triangle {t}: it shares no edge with triangle {t + 1}, the next "
                                "of its piece's run", check="cycle")
    sign = orient_many(pts, tri)
    if (sign <= 0).any():
        t = int(np.flatnonzero(sign <= 0)[0])
        what = "degenerate (zero area)" if sign[t] == 0 else "clockwise"
        raise VerificationError(f"triangle {t} {tri[t].tolist()} is {what} by the exact orientation test", check="orientation")
    if segments is not None and len(segments):
        _check_segments(tri, np.asarray(segments, dtype=np.int64), len(pts))
    first = ends - runs + 1
    closed = int(((neighbour[ends] == first[:, None]).any(axis=1) & (ends - first >= 2)).sum())
    stats = angle_area_stats(pts, tri)
    return runs, {
        "min_angle_output_deg": math.degrees(stats.min_angle),
        "max_angle_output_deg": math.degrees(stats.max_angle),
        "area": float(stats.total_area),
        "closed_runs": closed,
    }, twin


def _check_segments(tri: np.ndarray, segments: np.ndarray, n: int) -> None:
    """Every stored constrained edge is an edge of the triangles (either direction)."""
    if segments.ndim != 2 or segments.shape[1] != 2 or (segments < 0).any() or (segments >= n).any():
        raise VerificationError(f"the stored constrained edges are not pairs of vertices 0..{n - 1}", check="input")
    missing = np.flatnonzero(~has_edges(tri, n, segments))
    if len(missing):
        a, b = segments[missing[0]].tolist()
        raise VerificationError(f"constrained edge ({a}, {b}) is not an edge of the triangles", check="domain")
