"""The driver: tiles meshed, made Hamiltonian and joined, on this process or a Dask cluster.

The driver holds the decomposition and small per-tile summaries; the tiles' meshes and
Hamiltonian meshes stay where they were made (Dask futures on the workers). Only
:func:`parallel_hamiltonian` (one mesh in memory) gathers them; the partitioned output
(:mod:`hammesh.parallel.partitioned`) has each worker write its own piece.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from hammesh.domain import Domain
from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions
from hammesh.parallel.decoupled import MAX_ROUNDS, bad_corner_vertices
from hammesh.parallel.joins import Plan, border_rows, finish_tile, plan_joins
from hammesh.parallel.tile_mesh import mesh_tile
from hammesh.parallel.tiles import Decomposition, decompose, split_segments
from hammesh.parallel.union import assemble, check_union

__all__ = ["LocalRunner", "Tiled", "run_tiles", "parallel_hamiltonian", "default_tiles", "TRIANGLES_PER_TILE", "progress_bar"]

#: tiles beyond one per worker when the estimate is large (memory per task ~ 1 GB)
TRIANGLES_PER_TILE = 3_000_000


class _Done:
    def __init__(self, value: Any) -> None:
        self.value = value

    def result(self) -> Any:
        return self.value


class LocalRunner:
    """Runs every task at once in this process (the ``submit``/``gather`` of a Dask client)."""

    def submit(self, fn: Callable, *args: Any, **kw: Any) -> _Done:
        args = tuple(a.value if isinstance(a, _Done) else a for a in args)
        return _Done(fn(*args, **kw))

    def gather(self, futures: list) -> list:
        return [f.value for f in futures]


def default_tiles(estimate: float, workers: int) -> int:
    """One tile per worker, more when a tile would exceed ``TRIANGLES_PER_TILE``."""
    return max(int(workers), int(np.ceil(estimate / TRIANGLES_PER_TILE)))


def _tile_stats(mesh: Mesh, vertex_ids: np.ndarray, n_input: int, min_angle):
    return bad_corner_vertices(vertex_ids, n_input, mesh, min_angle), mesh.n_points, mesh.n_triangles


def _tile_hamiltonian(mesh: Mesh, mode: str, keep: float) -> HamiltonianMesh:
    from hammesh.postprocess import hamiltonian

    return hamiltonian(mesh, mode=mode, keep=keep)


def _n_points(h: HamiltonianMesh) -> int:
    return len(h.points)


@dataclass
class Tiled:
    """What the driver knows after :func:`run_tiles`: the plan and handles to the tiles' results."""

    decomposition: Decomposition
    meshes: list  # handles (futures) to the tile meshes
    hams: list  # handles to the tile Hamiltonian meshes
    plan: Plan
    mesh_points: np.ndarray
    mesh_triangles: np.ndarray
    ham_points: np.ndarray
    rounds: int
    seconds: dict
    borders: list


def run_tiles(domain: Domain, *, min_angle: float | None, max_area: float, tiles: int, runner=None,
              mode: str = "sparse", keep: float = 0.9, progress: Callable[[str, int], None] | None = None) -> Tiled:
    """Decompose, mesh every tile (with repair rounds), make each Hamiltonian, plan the joins."""
    run = runner or LocalRunner()
    note = progress or (lambda what, n: None)
    t0 = time.perf_counter()
    warming = warm_workers(run)  # noqa: F841  (kept alive while the tiles run)
    decomp = decompose(domain, min_angle=min_angle, max_area=max_area, n_tiles=tiles)
    t1 = time.perf_counter()
    meshes = [run.submit(mesh_tile, t, min_angle, max_area) for t in decomp.tiles]
    stats = [run.submit(_tile_stats, m, t.vertex_ids, decomp.n_input, min_angle) for m, t in zip(meshes, decomp.tiles)]
    results = run.gather(stats)
    note("meshed", len(results))
    rounds = 0
    while rounds < MAX_ROUNDS:
        ids = np.unique(np.concatenate([r[0] for r in results]))
        if len(ids) == 0:
            break
        rows = np.flatnonzero(np.isin(decomp.segments, ids).any(axis=1))
        decomp, changed = split_segments(decomp, rows)
        rounds += 1
        for i in changed.tolist():
            meshes[i] = run.submit(mesh_tile, decomp.tiles[i], min_angle, max_area)
        again = run.gather([run.submit(_tile_stats, meshes[i], decomp.tiles[i].vertex_ids, decomp.n_input, min_angle)
                            for i in changed.tolist()])
        results = list(results)
        for i, r in zip(changed.tolist(), again):
            results[i] = r
        results = [r if i in set(changed.tolist()) else (np.zeros(0, np.int64),) + tuple(r[1:])
                   for i, r in enumerate(results)]
    t2 = time.perf_counter()
    hams = [run.submit(_tile_hamiltonian, m, mode, keep) for m in meshes]
    borders = run.gather([run.submit(border_rows, h, t, i) for i, (h, t) in enumerate(zip(hams, decomp.tiles))])
    note("hamiltonian", len(borders))
    t3 = time.perf_counter()
    plan = plan_joins(borders, len(decomp.vertices), keep=keep, n_separators=int(decomp.separator.sum()))
    area = sum(b.area for b in borders)
    if abs(area - decomp.area) > 1e-9 * abs(decomp.area) * max(1.0, np.sqrt(sum(b.n_triangles for b in borders))):
        raise VerificationError(f"the tiles' area {area!r} differs from the domain's {decomp.area!r}")
    mesh_points = np.array([r[1] for r in results], np.int64)
    mesh_triangles = np.array([r[2] for r in results], np.int64)
    ham_points = np.array([b.n_points for b in borders], np.int64)
    t4 = time.perf_counter()
    return Tiled(decomposition=decomp, meshes=meshes, hams=hams, plan=plan, mesh_points=mesh_points,
                 mesh_triangles=mesh_triangles, ham_points=ham_points, rounds=rounds, borders=borders,
                 seconds={"decompose": t1 - t0, "mesh": t2 - t1, "hamiltonian": t3 - t2, "plan": t4 - t3})


def finish_all(tiled: Tiled, runner=None) -> list:
    """Handles to every tile's :class:`~hammesh.parallel.joins.TilePiece` (global numbering)."""
    run = runner or LocalRunner()
    d = tiled.decomposition
    k = np.array([len(t.vertex_ids) for t in d.tiles], np.int64)
    n0 = len(d.vertices)
    mesh_extra = tiled.mesh_points - k
    mesh_off = n0 + np.concatenate([[0], np.cumsum(mesh_extra)[:-1]])
    ham_extra = tiled.ham_points - tiled.mesh_points
    base = n0 + int(mesh_extra.sum())
    ham_off = base + np.concatenate([[0], np.cumsum(ham_extra)[:-1]])
    join_base = base + int(ham_extra.sum())
    tri_off = np.concatenate([[0], np.cumsum(tiled.mesh_triangles)[:-1]])
    n_global = join_base + 2 * sum(not j.swap for j in tiled.plan.joins)

    def global_id(tile: int, z: int) -> int:
        kk = len(d.tiles[tile].vertex_ids)
        if z < kk:
            return int(d.tiles[tile].vertex_ids[z])
        if z < tiled.mesh_points[tile]:
            return int(mesh_off[tile] + z - kk)
        return int(ham_off[tile] + z - tiled.mesh_points[tile])

    apex = {}  # a swap's far apex d, for the t tile
    for j in tiled.plan.joins:
        if j.swap:
            bu = tiled.borders[j.u_tile]
            r = int(np.flatnonzero(bu.row == j.u_row)[0])
            apex[j.index] = (global_id(j.u_tile, int(bu.z_local[r])), tuple(bu.xyz[r][2].tolist()))
    sep = np.sort(d.segments[d.separator], axis=1) @ np.array([n_global, 1])
    pieces = []
    for i, t in enumerate(d.tiles):
        mine = [bk for bk in tiled.plan.blocks if bk[0] == i]
        starts = np.array([s for bk, s in zip(tiled.plan.blocks, tiled.plan.start.tolist()) if bk[0] == i], np.int64)
        joins = [j for j in tiled.plan.joins if i in (j.t_tile, j.u_tile)]
        pieces.append(run.submit(finish_tile, tiled.hams[i], t, i, mine, starts, joins, int(mesh_off[i]),
                                 int(tiled.mesh_points[i]), int(ham_off[i]), join_base, int(tri_off[i]), sep, n_global,
                                 {ji: v for ji, v in apex.items() if tiled.plan.joins[ji].t_tile == i},
                                 0.5 * min(b.input_min_angle for b in tiled.borders)))
    return pieces


def parallel_hamiltonian(domain: Domain, *, min_angle: float | None = None, max_area: float, tiles: int | None = None,
                         workers: int | None = None, client=None, mode: str = "sparse", keep: float = 0.9,
                         verify: bool = True, progress: bool = False) -> HamiltonianMesh:
    """Mesh ``domain`` as decoupled tiles, make each Hamiltonian, join them; one mesh back.

    Parameters
    ----------
    domain : Domain
    min_angle, max_area : float
        As :func:`hammesh.quality_mesh` (``max_area`` required).
    tiles : int, optional
        Number of tiles (default: :func:`default_tiles`).
    workers : int, optional
        Start a local Dask cluster with this many worker processes (``pip install
        hammesh[dask]``); ``client``: use this ``dask.distributed.Client`` instead.
        Neither: every tile in this process, one after the other.
    mode, keep : as :func:`hammesh.hamiltonian`, per tile.
    verify : bool
        Run the union certificate (``hammesh.verify`` of the output against the union
        of the tile meshes) on top of the per-tile certificates and the union check.

    Returns
    -------
    HamiltonianMesh
        One cycle per connected piece; ``report["parallel"]`` has the tiles' figures.
    """
    from hammesh.parallel.cluster import runner_for

    t0 = time.perf_counter()
    with runner_for(workers=workers, client=client) as (runner, n_workers):
        if tiles is None:
            est = decompose_estimate(domain, min_angle, max_area)
            tiles = default_tiles(est, n_workers)
        tiled = run_tiles(domain, min_angle=min_angle, max_area=max_area, tiles=tiles, runner=runner,
                          mode=mode, keep=keep, progress=progress_bar(progress, 3))
        t1 = time.perf_counter()
        pieces = runner.gather(finish_all(tiled, runner))
        meshes = runner.gather(tiled.meshes) if verify else None
    h = _join_pieces(tiled, pieces)
    t2 = time.perf_counter()
    report = dict(h.report)
    if verify:
        from hammesh.verify import verify as certificate

        union = assemble(tiled.decomposition, meshes)
        facts = check_union(tiled.decomposition, union)
        stats = certificate(h, union)
        report.update({"verified": True, "min_angle_input_deg": stats["min_angle_input_deg"],
                       "min_angle_output_deg": stats["min_angle_output_deg"],
                       "max_angle_output_deg": stats["max_angle_output_deg"],
                       "union": {"triangles": facts.triangles, "area": facts.area,
                                 "min_angle_deg": facts.min_angle_deg, "separator_edges": facts.separator_edges}})
    t3 = time.perf_counter()
    report["parallel"] = {
        "tiles": tiled.decomposition.n_tiles, "workers": n_workers, "repair_rounds": tiled.rounds,
        "joins": len(tiled.plan.joins), "joins_not_whole": tiled.plan.fallback_joins,
        "join_swaps": sum(j.swap for j in tiled.plan.joins),
        "tile_cycles": tiled.plan.nodes, "pieces": tiled.plan.pieces,
        "estimate": tiled.decomposition.estimate, "mesh_triangles": int(tiled.mesh_triangles.sum()),
        "seconds": {**tiled.seconds, "finish": t2 - t1, "verify": t3 - t2, "total": t3 - t0},
    }
    report["triangles"] = int(len(h.triangles))
    return HamiltonianMesh(points=h.points, triangles=h.triangles, segments=h.segments,
                           segment_markers=h.segment_markers, components=h.components, position=h.position,
                           parent=h.parent, kind=h.kind, triangle_attributes=h.triangle_attributes, report=report)


def decompose_estimate(domain: Domain, min_angle, max_area) -> float:
    """Estimated triangle count of a Triangle run: the domain's area (one constrained
    triangulation, no refinement) over ``AREA_FILL x max_area``."""
    import triangle

    from hammesh.parallel.sizing import AREA_FILL

    data = {"vertices": np.array(domain.vertices)}
    if len(domain.segments):
        data["segments"] = np.array(domain.segments, dtype=np.int32)
    if len(domain.holes):
        data["holes"] = np.array(domain.holes)
    out = triangle.triangulate(data, ("p" if len(domain.segments) else "pc") + "Q")
    p, t = np.asarray(out["vertices"]), np.asarray(out.get("triangles", np.zeros((0, 3), int)))
    e1, e2 = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]
    area = float(np.abs(0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])).sum())
    return area / (AREA_FILL * float(max_area))


def _warm() -> None:
    from hammesh.postprocess import load_kernels

    load_kernels("sparse")
    load_kernels("incircle")


def warm_workers(runner) -> list:
    """Load the compiled kernels on every Dask worker now, beside the decomposition."""
    info = getattr(runner, "scheduler_info", None)
    if info is None:
        return []
    return [runner.submit(_warm, workers=[addr], pure=False, allow_other_workers=False)
            for addr in info().get("workers", {})]


def progress_bar(on: bool, total: int):
    """A progress callback ``note(stage, n_tiles)`` over ``total`` stages (tqdm on stderr), or None when off."""
    if not on:
        return None
    import sys

    from tqdm import tqdm

    bar = tqdm(total=total, file=sys.stderr, leave=False, unit="step")

    def note(what: str, n: int) -> None:
        bar.set_description(f"{what} ({n} tiles)")
        bar.update(1)

    return note


def _join_pieces(tiled: Tiled, pieces: list) -> HamiltonianMesh:
    """One HamiltonianMesh from the tiles' pieces (rows by global cycle position)."""
    d = tiled.decomposition
    n = int(max(int(p.point_ids.max()) for p in pieces if len(p.point_ids)) + 1)
    n = max(n, len(d.vertices))
    points = np.zeros((n, 2))
    points[: len(d.vertices)] = d.vertices
    for p in pieces:
        points[p.point_ids] = p.points
    pos = np.concatenate([p.position for p in pieces])
    order = np.argsort(pos, kind="stable")
    if not np.array_equal(pos[order], np.arange(len(pos))):
        raise InvalidOptionError("internal: the tiles' cycle positions do not cover 0..m-1")
    tri = np.concatenate([p.triangles for p in pieces])[order]
    kind = np.concatenate([p.kind for p in pieces])[order]
    parent = np.concatenate([p.parent for p in pieces])[order]
    width = max(p.triangle_attributes.shape[1] if p.triangle_attributes.ndim == 2 else 0 for p in pieces)
    attr = np.concatenate([p.triangle_attributes.reshape(len(p.triangles), -1) if width else
                           np.zeros((len(p.triangles), 0)) for p in pieces])[order]
    segs = np.concatenate([p.segments for p in pieces])
    marks = np.concatenate([p.segment_markers for p in pieces])
    keys = np.sort(segs, axis=1) @ np.array([n, 1])
    _, first = np.unique(keys, return_index=True)
    first = np.sort(first)
    comps = tiled.plan.components
    return HamiltonianMesh(points=points, triangles=tri, segments=segs[first], segment_markers=marks[first],
                           components=comps, position=cycle_positions(comps), parent=parent, kind=kind,
                           triangle_attributes=attr, report={"mode": "parallel"})
