"""Partitions of a Hamiltonian cycle mesh: contiguous pieces of its cycles (issue 14).

A :class:`~hammesh.mesh.HamiltonianMesh` stores its triangles in cycle order, so cutting
each cycle into ``k`` stretches of consecutive rows gives parts that are connected
(consecutive rows share an edge) and balanced to one triangle, in linear time. How
short the cut is depends on how compact a stretch of the cycle is: Thm 2.4's walk
around a depth-first spanning tree gives finger-like stretches (edge cuts 12-40x
METIS's), so the tree is a *fishbone* (``_thm24_kernels.spanning_forest``,
``_fishbone_kernels``): cells cut by count-median lines, each child hanging from its
parent's line by one edge, so that the walk visits every cell whole and the stretches
of ``k = 4^j`` or ``2 4^j`` parts are cells or half cells.

What is left to choose is where the ``k`` stretches start. With sizes fixed (exact
balance), the starts are ``s + floor(j n / k)``, and the cut is the number of dual
edges whose two rows lie in different stretches; an edge whose rows are ``x < y``
apart along the cycle is cut by a start in ``(x, y]``. Summing, per cycle position,
the edges it would cut (a difference array over the short side of each edge) gives
the cut of every shift ``s`` at once; the best one is taken. Each connected piece
of the domain (one cycle each) is cut separately, the ``k`` parts spread over the
pieces so that the largest part is as small as possible.

Examples
--------
>>> import hammesh
>>> dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
>>> h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=0.01))
>>> p = partition(h, 4)
>>> int(p.sizes.max() - p.sizes.min()) <= 1, p.connected
(True, True)
"""

from __future__ import annotations

import dataclasses
import heapq
import time
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from hammesh import params
from hammesh.errors import InvalidMeshError, VerificationError
from hammesh.halfedge import half_edges
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions

__all__ = [
    "spread_parts",
    "Partition",
    "PartitionedMesh",
    "partition",
    "partitioned",
    "as_cycle_mesh",
    "dual_edges",
    "edge_cut",
    "part_components",
    "cycle_runs",
    "rows_share_an_edge",
]


@dataclass(frozen=True, eq=False)
class Partition:
    """``k`` parts of a mesh's triangles.

    Attributes
    ----------
    part : (m,) int64
        Part of each triangle (row), ``0..k-1``; the parts of one cycle follow its order.
    k : int
    sizes : (k,) int64
        Triangles per part.
    edge_cut : int
        Interior edges between triangles of different parts (the dual graph's edge cut).
    components : (k,) int64
        Connected pieces of each part (edge-connected), checked on the mesh.
    report : dict
        ``edge_cut``, ``imbalance`` (largest part / (m / k)), ``connected``, sizes,
        parts per piece and seconds (see ``docs/partition.md``).
    """

    part: np.ndarray
    k: int
    sizes: np.ndarray
    edge_cut: int
    components: np.ndarray
    report: dict[str, Any] = field(default_factory=dict)

    @property
    def connected(self) -> bool:
        """Every part is one edge-connected piece."""
        return bool((self.components == 1).all())

    @property
    def imbalance(self) -> float:
        """Largest part over the mean part size (1.0: exact)."""
        return float(self.sizes.max() * self.k / self.sizes.sum()) if self.k else 1.0


def dual_edges(triangles: np.ndarray, n_points: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The interior edges of a triangle mesh as pairs of triangles ``(a, b)``, ``a < b``.

    Found by sorting the edges' vertex pairs (independent of the constructions'
    half-edge code); an edge of more than two triangles raises
    :class:`~hammesh.errors.InvalidMeshError`.
    """
    tri = np.asarray(triangles, dtype=np.int64)
    m = len(tri)
    if m == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    u = tri.reshape(-1)
    v = tri[:, [1, 2, 0]].reshape(-1)
    lo = np.minimum(u, v)
    hi = np.maximum(u, v)
    n = int(n_points) if n_points is not None else int(tri.max()) + 1
    key = lo * n + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    same = ks[1:] == ks[:-1]
    if (same[1:] & same[:-1]).any():
        raise InvalidMeshError("an edge is shared by more than two triangles")
    i = np.flatnonzero(same)
    a = order[i] // 3
    b = order[i + 1] // 3
    return np.minimum(a, b), np.maximum(a, b)


def _interior_edges(tri: np.ndarray, n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`dual_edges` by the compiled half-edge matching (oriented meshes)."""
    try:
        twin = half_edges(tri, n_points).twin
    except InvalidMeshError:  # inconsistently oriented (a file): the sorting way
        return dual_edges(tri, n_points)
    h = np.flatnonzero(twin > np.arange(len(twin)))
    return h // 3, twin[h] // 3


def edge_cut(part: np.ndarray, a: np.ndarray, b: np.ndarray) -> int:
    """Edges ``(a, b)`` whose triangles lie in different parts."""
    return int(np.count_nonzero(part[a] != part[b]))


def part_components(part: np.ndarray, k: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Edge-connected pieces of each of the ``k`` parts (0 for an empty part).

    Union-find over the edges ``(a, b)`` inside a part; it shares nothing with how
    the parts were made.
    """
    return _check_parts(
        np.ascontiguousarray(part, dtype=np.int64), int(k), np.ascontiguousarray(a, dtype=np.int64),
        np.ascontiguousarray(b, dtype=np.int64),
    ).components


class _Stretches(NamedTuple):
    """Result of :func:`_cut_cycles_into`."""

    cut: int  #: dual edges between different parts (exact), -1: an edge joins two cycles
    bad_edge: int  #: that edge's index (else -1)


@njit(cache=True, nogil=True)
def _cut_cycles_into(run_start, lengths, per, base, a, b, part, shifts, sizes):
    """Cut every cycle into its stretches at the best shift, in one pass (all pieces).

    Cycle r holds rows ``run_start[r] .. + lengths[r]`` and gets ``per[r]`` parts
    numbered from ``base[r]``; stretch j of it starts at ``s + floor(j n / k)`` (n rows,
    k parts, shift ``s < n // k``). An edge whose rows are ``x < y`` apart by ``d`` the
    short way round is cut by a shift iff a start falls on that short side: never two
    (starts are at least ``n // k`` apart) when ``d <= n // k``, always one when ``d``
    is larger (they are at most ``ceil(n / k)`` apart), and the long side always holds
    one. So a difference array over the short sides of the short edges gives, per
    row, the edges a start there cuts, and the sum over the ``k`` starts of a shift is
    that shift's exact cut, less the long edges: the best shift is exact, and its cut
    is the partition's. Fills ``part``, ``shifts`` and ``sizes``.
    """
    m = part.shape[0]
    n_runs = lengths.shape[0]
    diff = np.zeros(m + 1, np.int64)
    always = 0
    for e in range(a.shape[0]):
        x = min(a[e], b[e])
        y = max(a[e], b[e])
        r = 0
        if n_runs > 1:
            r = np.searchsorted(run_start, x, side="right") - 1
            if y >= run_start[r] + lengths[r]:
                return _Stretches(-1, e)
        n = lengths[r]
        k = per[r]
        if k <= 1:
            continue
        s0 = run_start[r]
        d = y - x
        short = min(d, n - d)
        if short > n // k:
            always += 1
        elif 2 * d <= n:  # rows x+1 .. y
            diff[x + 1] += 1
            diff[y + 1] -= 1
        else:  # rows y+1 .. end and start .. x
            diff[y + 1] += 1
            diff[s0 + n] -= 1
            diff[s0] += 1
            diff[x + 1] -= 1
    run = 0
    for p in range(m):  # depth, in place: edges a start at row p would cut
        run += diff[p]
        diff[p] = run
    cut = always
    cost = np.empty(0, np.int64)
    for r in range(n_runs):
        n = lengths[r]
        k = per[r]
        s0 = run_start[r]
        q = n // k
        best = 0
        if k > 1:
            if cost.shape[0] < q:
                cost = np.empty(q, np.int64)
            cost[:q] = 0
            for j in range(k):
                at = s0 + (j * n) // k
                for s in range(q):
                    cost[s] += diff[at + s]
            for s in range(1, q):
                if cost[s] < cost[best]:
                    best = s
            cut += cost[best]
        shifts[r] = best
        for j in range(k):  # stretch j: shifted rows floor(j n / k) .. floor((j+1) n / k) - 1
            lo = (j * n) // k
            hi = ((j + 1) * n) // k
            sizes[base[r] + j] = hi - lo
            for pos in range(lo, hi):
                p = pos + best
                if p >= n:
                    p -= n
                part[s0 + p] = base[r] + j
    return _Stretches(cut, -1)


class _Check(NamedTuple):
    """Result of :func:`_check_parts`."""

    components: np.ndarray  #: (k,) edge-connected pieces of each part
    cut: int  #: edges between different parts, counted


@njit(cache=True, nogil=True)
def _check_parts(part, k, a, b):
    """Union-find over the edges inside each part, counting the others (the cut)."""
    m = part.shape[0]
    uf = np.arange(m)
    cut = 0
    for e in range(a.shape[0]):
        x = a[e]
        y = b[e]
        if part[x] != part[y]:
            cut += 1
            continue
        while uf[x] != x:  # path halving
            uf[x] = uf[uf[x]]
            x = uf[x]
        while uf[y] != y:
            uf[y] = uf[uf[y]]
            y = uf[y]
        if x != y:
            uf[max(x, y)] = min(x, y)
    count = np.zeros(k, np.int64)
    for t in range(m):
        if uf[t] == t:
            count[part[t]] += 1
    return _Check(count, cut)


def rows_share_an_edge(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Whether rows ``x[i]`` and ``y[i]`` have two corners (an edge) in common."""
    return (x[:, :, None] == y[:, None, :]).any(axis=2).sum(axis=1) >= 2


def cycle_runs(triangles: np.ndarray) -> np.ndarray:
    """Run lengths of the cycles of triangles stored in cycle order.

    A run ends where the next row shares no edge with it; each run must close (its
    last row shares an edge with its first), else
    :class:`~hammesh.errors.InvalidMeshError` (the rows are not in cycle order).
    """
    tri = np.asarray(triangles, dtype=np.int64)
    m = len(tri)
    if m == 0:
        return np.zeros(0, np.int64)
    shared = rows_share_an_edge
    link = shared(tri[:-1], tri[1:])
    ends = np.concatenate([np.flatnonzero(~link), [m - 1]])
    starts = np.concatenate([[0], ends[:-1] + 1])
    lengths = ends - starts + 1
    closes = (lengths < 3) | shared(tri[starts], tri[ends])
    if not closes.all():
        r = int(np.flatnonzero(~closes)[0])
        raise InvalidMeshError(
            f"rows {int(starts[r])}..{int(ends[r])} do not form a closed cycle: the triangles are not in "
            "Hamiltonian cycle order (write the mesh with hammesh)"
        )
    return lengths.astype(np.int64)


def spread_parts(lengths: np.ndarray, k: int) -> np.ndarray:
    """Parts per cycle (``k >=`` the number of cycles): at least one each, the largest
    part as small as possible."""
    c = len(lengths)
    per = np.ones(c, np.int64)
    heap = [(-int(n), i) for i, n in enumerate(lengths)]
    heapq.heapify(heap)
    for _ in range(k - c):
        _, i = heapq.heappop(heap)
        per[i] += 1
        heapq.heappush(heap, ((-int(lengths[i])) // int(per[i]), i))  # -ceil(n / parts)
    return per


def partition(
    h: HamiltonianMesh | Mesh, k: int, *, check: bool = True, edges: tuple[np.ndarray, np.ndarray] | None = None
) -> Partition:
    """Cut the cycles of a Hamiltonian cycle mesh into ``k`` contiguous, balanced parts.

    Parameters
    ----------
    h : HamiltonianMesh, or a Mesh whose triangles are in cycle order (e.g. read
        back from a file hammesh wrote: the runs are found by :func:`cycle_runs`)
    k : int
        Number of parts, ``1 <= k <= triangles``.
    check : bool
        Count each part's connected pieces on the mesh (an independent check of what
        contiguity promises); False skips it (``components`` then all 1).
    edges : (a, b), optional
        The dual graph's edges (:func:`dual_edges`) if already at hand (as METIS is
        handed its graph); found from the triangles otherwise.

    Returns
    -------
    Partition
        Parts of each cycle (connected piece of the domain) are consecutive stretches
        of it; within a cycle sizes differ by at most one, and ``k`` is spread over the
        pieces so that the largest part is smallest. With fewer parts than pieces,
        whole pieces share parts (not connected then).

    Raises
    ------
    InvalidOptionError
        ``k`` not an integer in range.
    InvalidMeshError
        A plain mesh whose rows are not in cycle order.
    """
    params.instance("h", h, (Mesh, HamiltonianMesh), "a hammesh.HamiltonianMesh")
    t0 = time.perf_counter()
    tri = np.asarray(h.triangles, dtype=np.int64)
    m = len(tri)
    k = params.integer("k", k, low=1, high=max(1, m), what="parts, at most the number of triangles")
    if m == 0:
        raise InvalidMeshError("the mesh has no triangles to partition")
    lengths = np.asarray(h.components, dtype=np.int64) if isinstance(h, HamiltonianMesh) else cycle_runs(tri)
    a, b = _interior_edges(tri, len(h.points)) if edges is None else edges
    a = np.ascontiguousarray(a, dtype=np.int64)
    b = np.ascontiguousarray(b, dtype=np.int64)
    run_start = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    part = np.empty(m, np.int64)
    shifts = np.zeros(len(lengths), np.int64)
    sizes = np.zeros(k, np.int64)
    fewer = k < len(lengths)  # fewer parts than pieces: whole pieces share parts
    per = np.ones(len(lengths), np.int64) if fewer else spread_parts(lengths, k)
    base = np.concatenate([[0], np.cumsum(per)[:-1]]).astype(np.int64)
    cut, bad = _cut_cycles_into(
        run_start, lengths, per, base, a, b, part, shifts, np.zeros(int(per.sum()), np.int64) if fewer else sizes
    )
    if cut < 0:
        raise InvalidMeshError(
            f"two cycles share an edge (triangles {int(a[bad])} and {int(b[bad])}): the triangles are not in "
            "Hamiltonian cycle order (one cycle per piece)"
        )
    if fewer:  # largest piece first onto the lightest part (part = piece so far)
        load = [(0, j) for j in range(k)]
        owner = np.empty(len(lengths), np.int64)
        for r in np.argsort(-lengths, kind="stable").tolist():  # per piece, not per triangle
            w, j = heapq.heappop(load)
            owner[r] = j
            heapq.heappush(load, (w + int(lengths[r]), j))
        part = owner[part]
        sizes[:] = np.bincount(part, minlength=k)
        per = np.zeros(len(lengths), np.int64)
        cut = -1
    t1 = time.perf_counter()
    if check or cut < 0:
        comps, counted = _check_parts(part, k, a, b)
        if check and cut >= 0 and counted != cut:
            raise VerificationError(f"internal error: the parts cut {counted} edges, the shift's count said {cut}")
        cut = int(counted)
        if not check:
            comps = np.ones(k, np.int64)
    else:
        comps = np.ones(k, np.int64)
    cut = int(cut)
    t2 = time.perf_counter()
    report = {
        "k": int(k),
        "edge_cut": cut,
        "imbalance": float(sizes.max() * k / m),
        "size_min": int(sizes.min()),
        "size_max": int(sizes.max()),
        "connected": bool((comps == 1).all()) if check else None,
        "part_components_max": int(comps.max()),
        "pieces": int(len(lengths)),
        "parts_per_piece": [] if fewer else [int(x) for x in per],
        "shifts": [int(x) for x in shifts],
        "seconds": {"partition": t1 - t0, "check": t2 - t1},
    }
    return Partition(part=part, k=int(k), sizes=sizes, edge_cut=cut, components=comps, report=report)


@dataclass(frozen=True, eq=False)
class PartitionedMesh(HamiltonianMesh):
    """A :class:`~hammesh.mesh.HamiltonianMesh` with the part of each triangle.

    Writers store ``part`` as a cell array named ``part`` (``hammesh.write``), next to
    the cycle fields.
    """

    part: np.ndarray | None = None


def as_cycle_mesh(mesh: Mesh | HamiltonianMesh) -> HamiltonianMesh:
    """``mesh`` as a HamiltonianMesh: a plain mesh whose rows are in cycle order (read
    from a file) gets its runs from :func:`cycle_runs`; parents unknown (-1)."""
    if isinstance(mesh, HamiltonianMesh):
        return mesh
    params.instance("mesh", mesh, Mesh, "a hammesh.Mesh or HamiltonianMesh")
    runs = cycle_runs(mesh.triangles)
    m = mesh.n_triangles
    h = HamiltonianMesh.from_order(mesh.points, mesh.triangles, report={"source": "file"})
    changes: dict[str, Any] = {
        "segments": np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2),
        "segment_markers": np.asarray(mesh.segment_markers, dtype=np.int64),
        "components": runs,
        "position": cycle_positions(runs) if m else np.zeros(0, np.int64),
        "triangle_attributes": np.asarray(mesh.triangle_attributes, dtype=np.float64).reshape(m, -1),
        "attribute_names": tuple(getattr(mesh, "attribute_names", ())),  # (never lose a file's data)
        "point_data": dict(getattr(mesh, "point_data", {})),
    }
    if hasattr(mesh, "vertex_markers") and "vertex_markers" in {f.name for f in dataclasses.fields(h)}:
        changes["vertex_markers"] = mesh.vertex_markers
    return dataclasses.replace(h, **changes)


def partitioned(
    h: HamiltonianMesh | Mesh, k: int | None = None, *, renumber: str | None = None
) -> HamiltonianMesh:
    """``h`` with its vertices renumbered and/or its triangles partitioned.

    Parameters
    ----------
    h : HamiltonianMesh, or a Mesh in cycle order
    k : int, optional
        Parts (:func:`partition`); the result is a :class:`PartitionedMesh` and its
        report gains ``"partition"`` (edge cut, balance, connectivity).
    renumber : {"cycle", "rcm", "hilbert"}, optional
        Vertex numbering (:func:`hammesh.numbering.renumber`); the report gains
        ``"numbering"`` (bandwidth and profile before and after).
    """
    from hammesh.numbering import renumber as renumber_vertices

    out = as_cycle_mesh(h)
    if renumber is not None:
        out, _ = renumber_vertices(out, renumber)
    if k is not None:
        p = partition(out, k)
        fields = {f.name: getattr(out, f.name) for f in dataclasses.fields(out) if f.init}
        fields["report"] = {**out.report, "partition": p.report}
        out = PartitionedMesh(**fields, part=p.part)
    return out
