"""Partitioned output: every worker writes its tile's piece; the driver writes the index.

The driver never holds the mesh: it gets the decomposition, the tiles' small border
summaries and, per piece, a file name and a few counts. What is certified, and by whom:

* each tile's Hamiltonian mesh passes the independent certificate against the tile's
  mesh (:func:`hammesh.hamiltonian`, on the worker): cycles closed, same domain and
  boundary, constrained edges kept, angles >= half the tile's input minimum;
* the tiles conform: every separator edge is held by exactly two tiles' triangles, in
  opposite directions (:func:`~hammesh.parallel.joins.plan_joins`), and the tiles'
  areas add up to the domain's (the coarse constrained triangulation's);
* the joins form a spanning forest of the tiles' cycles (one cycle per piece) and
  every triangle a join makes is checked on its worker (exact orientation, angle floor);

so the union is an edge-manifold triangulation of the domain (tiles glued along their
common boundary edges) whose rows, by ``global_position``, are one closed cycle per
piece. ``hammesh check DIR/mesh.pvtu`` re-verifies the stitched mesh independently
(it needs the whole mesh in memory).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from hammesh.domain import Domain
from hammesh.errors import OutputError
from hammesh.parallel.run import decompose_estimate, default_tiles, finish_all, run_tiles, progress_bar

__all__ = ["write_partitioned", "INDEX_NAME", "piece_name"]

INDEX_NAME = "mesh.pvtu"


def piece_name(tile: int) -> str:
    return f"piece_{tile:04d}.vtu"


def _write_piece(piece, path: str, components: np.ndarray) -> tuple[str, int, int, int]:
    from hammesh.io.pvtu import write_piece

    ends = np.cumsum(components)
    cid = np.searchsorted(ends, piece.position, side="right")
    cpos = piece.position - (ends - components)[cid]
    write_piece(path, piece.point_ids, piece.points, piece.triangles, piece.position, cid, cpos, piece.parent,
                piece.kind, piece.triangle_attributes)
    first = int(piece.position[0]) if len(piece.position) else -1
    width = piece.triangle_attributes.shape[1] if piece.triangle_attributes.ndim == 2 else 0
    return Path(path).name, len(piece.triangles), first, width


def write_partitioned(domain: Domain, directory: str | os.PathLike[str], *, min_angle: float | None = None,
                      max_area: float, tiles: int | None = None, workers: int | None = None, client=None,
                      scheduler: str | None = None, mode: str = "sparse", keep: float = 0.9,
                      progress: bool = False) -> dict:
    """Mesh ``domain`` on the tiles and write ``DIRECTORY/mesh.pvtu`` + one ``.vtu`` per tile.

    Returns the report (counts, seconds, ``index`` path). Pieces are written by the
    worker that made them; the index lists them in the order the cycle enters them.
    """
    from hammesh.io.pvtu import write_index
    from hammesh.parallel.cluster import runner_for

    out = Path(directory)
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out}: --partitioned writes a directory; this is a file")
    t0 = time.perf_counter()
    written: list[Path] = []
    created = not out.exists()
    try:
        with runner_for(workers=workers, client=client, scheduler=scheduler) as (runner, n_workers):
            if tiles is None:
                tiles = default_tiles(decompose_estimate(domain, min_angle, max_area), n_workers)
            tiled = run_tiles(domain, min_angle=min_angle, max_area=max_area, tiles=tiles, runner=runner,
                              mode=mode, keep=keep, progress=progress_bar(progress, 3))
            out.mkdir(parents=True, exist_ok=True)
            pieces = finish_all(tiled, runner)
            paths = [out / piece_name(i) for i in range(len(pieces))]
            written += paths
            done = runner.gather([runner.submit(_write_piece, p, str(path), tiled.plan.components)
                                  for p, path in zip(pieces, paths)])
            worker_rss = peak_rss_workers(runner)
        order = sorted(range(len(done)), key=lambda i: done[i][2])
        index = out / INDEX_NAME
        written.append(index)
        write_index(index, [done[i][0] for i in order if done[i][1] > 0], max(d[3] for d in done))
    except BaseException:
        for p in written:
            for q in (p, p.with_name(p.name + ".part")):
                if q.exists():
                    q.unlink()
        if created and out.is_dir() and not any(out.iterdir()):
            out.rmdir()
        raise
    t1 = time.perf_counter()
    d = tiled.decomposition
    return {
        "index": str(index), "pieces": len(done), "triangles": int(sum(x[1] for x in done)),
        "components": tiled.plan.components.tolist(), "verified": True,
        "parallel": {"tiles": d.n_tiles, "workers": n_workers, "repair_rounds": tiled.rounds,
                     "joins": len(tiled.plan.joins), "join_swaps": sum(j.swap for j in tiled.plan.joins),
                     "joins_not_whole": tiled.plan.fallback_joins, "tile_cycles": tiled.plan.nodes,
                     "pieces": tiled.plan.pieces, "estimate": d.estimate,
                     "mesh_triangles": int(tiled.mesh_triangles.sum()),
                     "seconds": {**tiled.seconds, "total": t1 - t0},
                     "peak_rss_mb": {"driver": peak_rss_mb(), "workers": worker_rss}},
    }


def peak_rss_mb() -> float:
    """This process's peak resident set size (MB; Linux reports kB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def peak_rss_workers(runner) -> list[float]:
    """Every Dask worker's peak RSS (MB); [] when the tiles ran in this process."""
    run = getattr(runner, "run", None)
    if run is None:
        return []
    return sorted(float(v) for v in run(peak_rss_mb).values())
