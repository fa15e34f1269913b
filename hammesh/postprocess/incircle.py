"""Theorem 2.4: a Hamiltonian cycle mesh from any triangulation, by incenters and flips.

Arkin, Held, Mitchell, Skiena, *Hamiltonian Triangulations for Fast Rendering*, Thm 2.4
and the paragraph on conformal meshes after it:

1. put a Steiner point at the incenter of every input triangle and join it to the
   triangle's corners (each triangle becomes three);
2. take a spanning tree of the dual graph and flip every input edge the tree
   crosses: the two incenters become joined (the flip is always legal, Fig. 9);
3. the triangles, walked around the tree, form one Hamiltonian cycle; the minimum
   angle is at least half the input's.

Constrained edges are never flipped. The tree is a minimum spanning forest in which
constrained dual edges cost more (``_kernels.spanning_forest``), so it crosses a
constrained edge only where a closed chain of them separates two regions: exactly
``regions - pieces`` crossings, one per separated region. A crossed constrained edge
keeps its place and gets its midpoint instead of a flip (the paper's conformal
variant); its two input triangles become four triangles around the midpoint.

The cycle is written by one walk around the tree (``_kernels.emit_cycles_into``):
every output triangle is owned by a *slot*, the half-edge ``h = 3 t + k`` of the input
triangle ``t``. Sweeping counter-clockwise around the incenter of ``t``, slot ``h``
holds ``(I_t, a, b)`` if its edge ``ab`` is not in the tree, ``(I_t, a, I_u)`` if it is
flipped (``u`` across), and ``(I_t, a, M)`` plus ``(I_t, M, b)`` if it is split at ``M``.
"""

from __future__ import annotations

from concurrent.futures import Executor, Future

import numpy as np

from hammesh.postprocess import _thm24_kernels as _kernels
from hammesh.postprocess._fishbone_kernels import FISH_LEVELS
from hammesh.errors import VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions
from hammesh.pages import fresh
from hammesh.postprocess.conform import split_segments
from hammesh.halfedge import HalfEdges
from hammesh.verify.stream import RowStream

__all__ = ["incircle_hamiltonian", "incircle_streaming", "incenters", "TREES"]

def incenters(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Incenters of triangles.

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64

    Returns
    -------
    (m, 2) float64
        ``(|BC| A + |CA| B + |AB| C) / (|BC| + |CA| + |AB|)`` for each triangle ABC.
    """
    return _kernels.incenters(
        np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(triangles, dtype=np.int64)
    )


def incircle_hamiltonian(
    mesh: Mesh, he: HalfEdges, is_con: np.ndarray, *, tree: str = "quadtree"
) -> tuple[HamiltonianMesh, np.ndarray]:
    """Build the Thm 2.4 Hamiltonian cycle mesh (unverified; see ``hammesh.hamiltonian``).

    Parameters
    ----------
    mesh : Mesh
        Counter-clockwise, validated (``hammesh.halfedge.prepare_mesh``).
    he : HalfEdges
        Its half-edge adjacency.
    is_con : (3 m,) bool
        Half-edges on constrained edges.
    tree : {"quadtree", "fishbone"}
        The dual spanning tree the cycle walks around (:data:`TREES`).

    Returns
    -------
    HamiltonianMesh
        With ``report`` holding the construction counts only.
    claim : (3 m_out,) int32 (int64 beyond 2**31 half-edges)
        The output's half-edge twins as the construction implies them; the
        certificate checks this claim instead of recomputing the pairing.
    """
    h, claim, _ = incircle_streaming(mesh, he, is_con, None, tree=tree)
    return h, claim


#: The dual spanning trees Thm 2.4's cycle can walk around, by name: the fishbone
#: levels of :func:`~hammesh.postprocess._thm24_kernels.spanning_forest` (docs/partition.md).
#: ``"quadtree"`` (0 levels): the count quadtree, the fastest; its stretches cut
#: 1.5-1.9x METIS's. ``"fishbone"``: kd lines turned to cross the domain shortest, or
#: round the hole of a domain that wraps round one (the ring frame: eight sectors hung
#: from the hole's rim), a compact cycle for ``hammesh.partition`` (1.3-1.5x METIS's on
#: a plate with holes and on a gear) at about +20 % of the incircle construction's
#: first call.
TREES: dict[str, int] = {"quadtree": 0, "fishbone": FISH_LEVELS}

#: Rows the walk writes between two hand-overs to the row checks.
WALK_CHUNK = 1 << 18


def _iota(a: np.ndarray) -> np.ndarray:
    """``a[i] = i`` in place, by cache-sized chunks (no temporary as large as ``a``)."""
    step = 1 << 16
    base = np.arange(min(step, len(a)), dtype=a.dtype)
    for lo in range(0, len(a), step):
        k = min(step, len(a) - lo)
        np.add(base[:k], lo, out=a[lo : lo + k])
    return a


def _inherit(attrs: np.ndarray, parent: np.ndarray) -> np.ndarray:
    """Regional attributes of each output triangle's parent (none: no gather pass)."""
    return attrs[parent] if attrs.shape[1] else np.zeros((len(parent), 0))


def walk_arrays(total: int, nh: int, parent: bool = True, n_points: int | None = None) -> dict[str, np.ndarray]:
    """The walk's output arrays for ``total`` rows and ``nh`` slots, pages touched.

    ``parent=False``: without ``parent`` and ``kind`` (``incircle_streaming(...,
    reuse=True)`` makes them of the input's dead pairing arrays when it can).
    ``n_points``: the input's point count; then also the output's ``points`` for no
    midpoint (``n_points + nh / 3`` rows), used if it fits. (The output's
    ``position`` needs no fresh memory: the walk's ``code`` is dead when it is done.)
    """
    # (page faults taken here, beside other work, not in the walk; the walk writes
    # every row, so only the claim and prim need their starting values)
    arrays = {
        "out": fresh((total, 3), np.int64),
        "claim": fresh(3 * total, _kernels.index_dtype(3 * total), _kernels.UNLINKED),
        "prim": fresh(nh, _kernels.index_dtype(total), -1),
    }
    if parent:
        arrays["parent"] = fresh(total, np.int64)
        arrays["kind"] = fresh(total, np.int8)
    if n_points is not None:
        arrays["points"] = fresh((n_points + nh // 3, 2), np.float64)
    return arrays


def incircle_streaming(
    mesh: Mesh, he: HalfEdges, is_con: np.ndarray, side: Executor | None, ready: Future | None = None,
    *, reuse: bool = False, tree: str = "quadtree",
) -> tuple[HamiltonianMesh, np.ndarray, RowStream | None]:
    """``incircle_hamiltonian`` with a second thread (``side``) working beside the walk.

    While the tree search runs, ``side`` allocates the walk's arrays (taking their
    page faults; with ``walk_arrays(..., n_points=n)`` also those of the output's
    points); while the walk runs, it computes the incenters and then checks the
    finished rows of the output (``hammesh.verify.stream.RowStream``), which is
    returned for the caller to finish (``stream.join()``, then ``stream.result``).
    Without ``side`` it is the plain serial construction and the stream is None.
    ``ready`` may hold ``walk_arrays(3 m, 3 m)`` already submitted (e.g. before the
    input was validated, to use the other core then).

    ``reuse=True`` hands ``he.twin`` and ``is_con`` over: once the spanning forest has
    read them they are dead, and (when no constrained edge is split, ``3 m`` output
    rows) their memory becomes the output's ``parent`` (int64) and ``kind`` (int8)
    instead of 40 MB of fresh pages at 1.5 M triangles (fresh memory is what makes
    the first call slow, docs/benchmarks.md). The caller must not use them after.
    """
    pts = mesh.points
    n, m = mesh.n_points, mesh.n_triangles
    nh = 3 * m
    # most meshes split no constrained edge (total = 3 m): their arrays are made now
    if ready is None and side is not None:
        ready = side.submit(walk_arrays, nh, nh)
    # the walk runs in the tree search's numbering (locality): incenter n + i is that
    # of input triangle order[i]
    tri, code, order, firsts, split = _kernels.spanning_forest(mesh.triangles, he.twin, is_con, pts,
                                                               levels=TREES[tree])
    mid_h, mid_id, mid_a, mid_b = _kernels.split_slots(tri, code, split)
    total = nh + len(mid_h)
    arrays = ready.result() if ready is not None else None
    if arrays is None or len(arrays["out"]) != total:
        arrays = walk_arrays(total, nh, parent=False)
    if "parent" not in arrays:
        twin = he.twin
        if (reuse and total == nh and twin.dtype == np.int64 and twin.shape == (total,) and twin.flags.c_contiguous
                and is_con.dtype == np.bool_ and is_con.shape == (total,) and is_con.flags.c_contiguous):
            arrays["parent"], arrays["kind"] = twin, is_con.view(np.int8)  # dead after the forest
        else:
            arrays["parent"] = fresh(total, np.int64)
            arrays["kind"] = fresh(total, np.int8)
    out, parent, kind, claim, prim = (arrays[k] for k in ("out", "parent", "kind", "claim", "prim"))
    q = len(mid_a)
    points = arrays.get("points")
    if points is None or points.shape != (n + m + q, 2):
        points = np.empty((n + m + q, 2))
    points[:n] = pts
    points[n + m :] = 0.5 * (pts[mid_a] + pts[mid_b])
    lengths = np.zeros(len(firsts), np.int64)
    y2 = np.full(len(mid_h), -1, np.int64)
    state = np.zeros(_kernels.WALK_STATE, np.int64)
    args = (tri, code, firsts, order, n, mid_h, mid_id, out, parent, kind, claim, prim, lengths, y2, state)

    stream = None
    if side is None:
        _kernels.incenters(pts, tri, out=points[n : n + m])
        status = _kernels.emit_cycles_into(*args, total)
    else:
        stream = RowStream(points, out, claim)

        def check() -> None:  # the rows use the incenters: compute them first
            _kernels.incenters(pts, tri, out=points[n : n + m])
            stream.points_final()
            stream.work()

        checking = side.submit(check)
        status = -1
        try:
            while (status := _kernels.emit_cycles_into(*args, int(state[2]) + WALK_CHUNK)) == 0:
                stream.publish(int(state[2]) - 1)  # the last row waits for its link
        finally:  # the checker must never wait for rows that will not come
            if status == 1 and state[2] == total:
                stream.publish(total, final=True)
            else:
                stream.stop()
        stream.attach(checking)  # the caller joins the checks (``stream.join()``)
        if status != 1:
            checking.result()
    if status != 1 or state[2] != total:
        raise VerificationError(
            f"internal error: the tree walk emitted {int(state[2])} of {total} triangles"
        )

    segs, markers = split_segments(mesh.segments, mesh.segment_markers, mid_a, mid_b, n + m, len(points))
    if len(lengths) == 1 and code.shape == (total,) and code.dtype == np.int64 and code.flags.c_contiguous:
        position = _iota(code)  # one cycle: positions 0..total-1, in the walk's dead code array
    else:
        position = cycle_positions(lengths)
    report = {
        "triangles": int(len(out)),
        "vertices": int(len(points)),
        "input_triangles": int(m),
        "input_vertices": int(n),
        "steiner_points": int(m + q),
        "incenters": int(m),
        "midpoints": int(q),
        "flips": int(m - len(lengths) - q),  # tree edges not split at a midpoint
        "components": [int(x) for x in lengths],
    }
    h = HamiltonianMesh(
        points=points,
        triangles=out,
        segments=segs,
        segment_markers=markers,
        components=lengths,
        position=position,
        parent=parent,
        kind=kind,
        triangle_attributes=_inherit(mesh.triangle_attributes, parent),
        report=report,
    )
    return h, claim, stream
