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

import heapq
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from hammesh import params
from hammesh.domain import Domain
from hammesh.errors import InvalidOptionError, OutputError
from hammesh.io.tags import VERTEX_MARKER
from hammesh.partition import spread_parts
from hammesh.parallel.markers import given_at, point_markers
from hammesh.parallel.run import (decompose_estimate, default_tiles, domain_marks, finish_args, not_carried, on_holder,
                                  outcome_hamiltonian, progress_bar, run_tiles, since_start, task_clock)

__all__ = ["write_partitioned", "INDEX_NAME", "piece_name", "stretch_parts", "parts_per_cycle", "check_target", "is_output_file",
           "piece_types", "int_type", "spill_wanted", "HELD_BYTES_PER_TRIANGLE", "SPILL_SHARE"]

INDEX_NAME = "mesh.pvtu"

#: bytes a worker holds per triangle of a tile between its task and its piece: an
#: upper bound (the Hamiltonian mesh, incircle's three rows per triangle with parents,
#: kinds and attributes, and its points, is less than a tile task's peak, measured at
#: 350-400 B per triangle at 1.5M-triangle tiles, docs/scale.md "On a cluster")
HELD_BYTES_PER_TRIANGLE = 400
#: share of a worker's memory its held tiles may take before they go to spill files
SPILL_SHARE = 0.5


def spill_wanted(runner, n_workers: int, tiles: int, estimate: float) -> bool:
    """Whether each tile's Hamiltonian mesh waits for the join plan in a file instead
    of its worker's memory: when a worker would hold more tiles than fit in
    ``SPILL_SHARE`` of its memory (``HELD_BYTES_PER_TRIANGLE`` per triangle).

    Why not whenever a worker runs several tiles (before session 12): at 6M triangles
    the four balance tiles (:func:`~hammesh.parallel.run.default_tiles`) on two
    workers hold at most ~1.2 GB each, and pickling them to files and back is work on
    every tile's path that memory does not call for; at 100M (64 tiles, 32 per
    worker) they would hold ~20 GB each, and spill.
    Memory per worker: a running cluster's ``memory_limit`` (the smallest), else
    this machine's memory over the workers (a local cluster's default limit).
    """
    if tiles <= n_workers:
        return False
    held = -(-tiles // n_workers) * (float(estimate) / tiles) * HELD_BYTES_PER_TRIANGLE
    from hammesh.parallel.cluster import Starting

    limit = 0.0
    info = None if isinstance(runner, Starting) else getattr(runner, "scheduler_info", None)
    if info is not None:  # (a cluster of its own: what each worker may use)
        limits = [w.get("memory_limit") or 0 for w in info().get("workers", {}).values()]
        limit = float(min(limits)) if limits and min(limits) > 0 else 0.0
    if limit <= 0:
        try:
            import psutil

            limit = psutil.virtual_memory().total / max(1, n_workers)
        except ImportError:  # pragma: no cover - psutil comes with Dask
            return True
    return held > SPILL_SHARE * limit


def piece_name(tile: int) -> str:
    return f"piece_{tile:04d}.vtu"


def int_type(bound: int) -> str:
    """``Int32`` when every value is in ``[-1, bound)`` and ``bound`` fits, else ``Int64``."""
    return "Int32" if int(bound) < 2**31 else "Int64"


def piece_types(n_points: int, n_rows: int, n_parents: int) -> dict[str, str]:
    """VTK type of the pieces' integer point and cell data, the same in every piece
    (the index lists one type per array): 32-bit while the whole output's point ids,
    rows and parent rows fit, ``kind`` one byte (an index into ``KIND_NAMES``).

    Why: the pieces are our own format (``hammesh.read_mesh``/``hammesh check`` read
    any integer type) and their bytes are the write step's cost: with every integer
    array 64-bit an incircle row took ~81 bytes, with these ~52."""
    rows = int_type(n_rows)
    return {"global_id": int_type(n_points), "global_position": rows, "cycle_id": rows, "cycle_position": rows,
            "part": rows, "parent": int_type(n_parents), "kind": "UInt8"}


def parts_per_cycle(components: np.ndarray, k: int) -> np.ndarray:
    """Parts given to each cycle: at least one each, the largest part as small as
    possible (the rule of :func:`hammesh.partition.partition`); 0 for cycles that go
    whole into a part when ``k`` is below the number of cycles (see :func:`stretch_parts`)."""
    lengths = np.asarray(components, np.int64)
    if k < len(lengths):
        return np.zeros(len(lengths), np.int64)
    return spread_parts(lengths, k)


def stretch_parts(position: np.ndarray, components: np.ndarray, k: int) -> np.ndarray:
    """Part of each row from its global cycle position alone: ``k`` balanced stretches
    of the cycles (``--parts`` with ``--partitioned``; every worker labels its own rows).

    A stretch of a Hamiltonian cycle is edge-connected, so every part is one connected
    piece, sizes within one triangle of each other per cycle. The stretches start at
    ``floor(j n / k)`` (what :func:`hammesh.partition.partition` does with shift 0: its
    search for the shift cutting fewest edges needs the whole mesh). With fewer parts
    than cycles, whole cycles go, largest first, to the lightest part.
    """
    lengths = np.asarray(components, np.int64)
    ends = np.cumsum(lengths)
    cyc = np.searchsorted(ends, position, side="right")
    cpos = position - (ends - lengths)[cyc]
    per = parts_per_cycle(lengths, k)
    if k >= len(lengths):
        base = np.concatenate([[0], np.cumsum(per)[:-1]])
        return base[cyc] + ((cpos + 1) * per[cyc] - 1) // lengths[cyc]
    owner = np.zeros(len(lengths), np.int64)
    load = [(0, j) for j in range(k)]
    for r in np.argsort(-lengths, kind="stable").tolist():
        w, j = heapq.heappop(load)
        owner[r] = j
        heapq.heappush(load, (w + int(lengths[r]), j))
    return owner[cyc]


def _finish_and_write(outcome, args: tuple, path: str, components: np.ndarray, parts: int | None,
                      types: dict[str, str] | None = None, marks: tuple | None = None):
    """On the tile's worker: number its rows globally (its side of the joins), write its
    piece. Returns ``(file name, rows, first global position, attribute width, part sizes)``.

    The piece is written chunk by chunk straight from the tile's Hamiltonian mesh in
    the order :func:`~hammesh.parallel.joins.piece_layout` plans (runs of its cycle,
    forward or backward, and the join rows): no gathered copy of the rows is made
    (at millions of rows such copies, fresh memory each, were most of the finish and
    write steps). The bytes are :func:`~hammesh.io.pvtu.write_piece`'s.
    ``marks``: the input vertices' nonzero markers (:func:`~hammesh.parallel.run.domain_marks`):
    the piece's points get a ``vertex_marker`` array as the serial path's output
    (:func:`~hammesh.parallel.markers.point_markers`); None: none written.
    """
    from hammesh.io.pvtu import VTK_TRIANGLE, write_raw_chunks
    from hammesh.parallel.joins import CHUNK_ROWS, piece_layout

    e0, t0, c0 = time.time(), time.perf_counter(), time.process_time()
    h = outcome_hamiltonian(outcome)
    lay = piece_layout(h, *args)
    t1, c1 = time.perf_counter(), time.process_time()
    m, n, w = len(h.triangles), len(h.points), lay.join_attributes.shape[1]
    tri = np.asarray(h.triangles, dtype=np.int64)
    attrs = np.asarray(h.triangle_attributes, dtype=np.float64).reshape(m, w)
    parent, kind, off = np.asarray(h.parent, dtype=np.int64), np.asarray(h.kind), lay.triangle_offset
    renum = None if lay.keep is None else np.cumsum(lay.keep) - 1
    spans = [(g, r, len(range(*r.indices(m))) if isinstance(r, slice) else 1) for g, r in lay.chunks()]
    ends = np.cumsum(components)
    sizes = None if parts is None else np.zeros(parts, np.int64)

    def rows(values, joins, own=None, both=None):
        """Chunks of a per-row array in piece order (``own`` applied to the tile's
        rows, ``both`` to every chunk)."""
        def gen():
            for _, r, _ in spans:
                c = (values[r] if own is None else own(values[r])) if isinstance(r, slice) else joins[r:r + 1]
                yield c if both is None else both(c)
        return gen

    def by_position(fn):
        def gen():
            for g, _, c in spans:
                yield fn(g + np.arange(c, dtype=np.int64))
        return gen

    def global_parent(p):
        p = p + off
        p[p < off] = -1  # -1 (no parent) stays -1
        return p

    def cycle_id(pos):
        return np.searchsorted(ends, pos, side="right")

    def cycle_position(pos):
        return pos - (ends - components)[cycle_id(pos)]

    def part_of(pos):
        part = stretch_parts(pos, components, parts)
        sizes[:] += np.bincount(part, minlength=parts)
        return part

    keep = lay.keep
    n_points = len(lay.point_ids) if keep is None else int(keep.sum())

    def points(ids: bool):
        def gen():
            for src, base in ((h.points, 0), (lay.join_points, n)):
                for a in range(0, len(src), CHUNK_ROWS):
                    b = min(a + CHUNK_ROWS, len(src))
                    if ids:
                        c = lay.point_ids[base + a:base + b]
                    else:
                        c = np.zeros((b - a, 3))
                        c[:, :2] = src[a:b]
                    yield c if keep is None else c[keep[base + a:base + b]]
        return gen

    def cells(fn):
        def gen():
            for a in range(0, lay.n_rows, CHUNK_ROWS):
                yield fn(a, min(a + CHUNK_ROWS, lay.n_rows))
        return gen

    mr = lay.n_rows
    ty = types or {}
    # (the piece's own point indices and offsets; without ``types`` all Int64, write_piece's bytes)
    local = int_type(max(n_points, 3 * mr + 1)) if types else "Int64"
    arrays = [("PointData", "global_id", ty.get("global_id", "Int64"), 1, n_points, points(True)),
              ("CellData", "global_position", ty.get("global_position", "Int64"), 1, mr, by_position(lambda pos: pos)),
              ("CellData", "parent", ty.get("parent", "Int64"), 1, mr, rows(parent, lay.join_parent, own=global_parent)),
              ("CellData", "kind", ty.get("kind", "Int64"), 1, mr, rows(kind, lay.join_kind))]
    if marks is not None:
        vm = point_markers(len(lay.point_ids), lay.local_segments, lay.segment_markers,
                           given_at(lay.point_ids, len(args[0].vertex_ids), marks))
        vm = vm if keep is None else vm[keep]
        arrays.insert(1, ("PointData", VERTEX_MARKER, "Int32", 1, n_points, lambda: iter([vm.astype(np.int32)])))
    if len(components) > 1:  # (one cycle: all zeros and global_position again, not written)
        arrays[2:2] = [("CellData", "cycle_id", ty.get("cycle_id", "Int64"), 1, mr, by_position(cycle_id)),
                       ("CellData", "cycle_position", ty.get("cycle_position", "Int64"), 1, mr,
                        by_position(cycle_position))]
    if parts is not None:
        arrays.append(("CellData", "part", ty.get("part", "Int64"), 1, mr, by_position(part_of)))
    arrays += [("CellData", f"attribute_{i}", "Float64", 1, mr, rows(attrs[:, i], lay.join_attributes[:, i]))
               for i in range(w)]
    arrays += [("Points", "", "Float64", 3, 3 * n_points, points(False)),
               ("Cells", "connectivity", local, 1, 3 * mr,
                rows(tri, lay.join_triangles, both=None if renum is None else renum.__getitem__)),
               ("Cells", "offsets", local, 1, mr, cells(lambda a, b: 3 * np.arange(a + 1, b + 1, dtype=np.int64))),
               ("Cells", "types", "UInt8", 1, mr, cells(lambda a, b: np.full(b - a, VTK_TRIANGLE, np.uint8)))]
    write_raw_chunks(path, arrays, n_points, mr)
    first = int(lay.items[0][0]) if lay.items else -1
    return (Path(path).name, mr, first, w, sizes,
            {"finish": t1 - t0, "write": time.perf_counter() - t1, "cpu_finish": c1 - c0,
             "cpu_write": time.process_time() - c1, "clock": (e0, time.time(), os.getpid())})


def apex_marks(tiled, args: tuple, marks: tuple | None) -> tuple | None:
    """``marks`` (the input's nonzero vertex markers) plus the markers of the swap
    apexes this tile's piece takes from the other tile (``args``: its
    :func:`~hammesh.parallel.run.finish_args`): such a point is on none of this piece's
    constrained edges, so its marker comes from the tile that holds them (the border
    rows' ``z_mark``), and both pieces give it the same."""
    if marks is None:
        return None
    ids, values = [marks[0]], [marks[1]]
    for ji, (gid, _) in (args[12] or {}).items():
        j = tiled.plan.joins[ji]
        bu = tiled.borders[j.u_tile]
        mark = int(bu.z_mark[int(np.flatnonzero(bu.row == j.u_row)[0])]) if bu.z_mark is not None else 0
        if mark and gid not in set(marks[0].tolist()):
            ids.append(np.array([gid], np.int64))
            values.append(np.array([mark], np.int64))
    return np.concatenate(ids), np.concatenate(values)


def check_target(out: Path, *, force: bool = False, inputs: tuple = ()) -> None:
    """Refuse an output directory that is a file, holds an input, or is not empty
    (unless ``force`` and it holds an earlier partitioned output and nothing else: then
    that is replaced once the new one is complete). The current directory or one above
    it is never replaced (it cannot be renamed away; the run would fail at its end)."""
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out}: --partitioned writes a directory; this is a file")
    target = out.resolve()
    for p in inputs:
        q = Path(p).resolve()
        if q == target or target in q.parents:
            raise OutputError(f"{out}: holds the input {p}; choose another output directory")
    if not (out.is_dir() and any(out.iterdir())):
        return
    if not force:
        raise OutputError(f"{out}: directory exists and is not empty (--force replaces an earlier "
                          "partitioned output)")
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents:
        raise OutputError(f"{out}: is the current directory or holds it; --force cannot replace it")
    foreign = sorted(p.name for p in out.iterdir() if not is_output_file(p))
    if foreign:
        raise OutputError(f"{out}: holds {foreign[0]!r}{f' and {len(foreign) - 1} more' if len(foreign) > 1 else ''}, "
                          "not an earlier partitioned output; --force replaces only mesh.pvtu and piece_*.vtu")


def is_output_file(path: Path) -> bool:
    """A file a partitioned output holds: the index or a piece (what ``--force`` may replace)."""
    import re

    return path.is_file() and not path.is_symlink() and (
        path.name == INDEX_NAME or re.fullmatch(r"piece_\d{4,}\.vtu", path.name) is not None)


def write_partitioned(domain: Domain, directory: str | os.PathLike[str], *, min_angle: float | None = None,
                      max_area: float, tiles: int | None = None, workers: int | None = None, client=None,
                      scheduler: str | None = None, mode: str = "sparse", keep: float = 0.9,
                      parts: int | None = None, force: bool = False, inputs: tuple = (),
                      progress: bool = False, lattice: bool = True, tree: str = "quadtree") -> dict:
    """Mesh ``domain`` on the tiles and write ``DIRECTORY/mesh.pvtu`` + one ``.vtu`` per tile.

    Everything is written into a fresh directory beside ``DIRECTORY`` and renamed onto it
    when complete: a failed or interrupted run leaves nothing behind, and no stale piece
    of an earlier run survives. An existing non-empty ``DIRECTORY`` is refused unless
    ``force`` (then replaced); one holding an ``inputs`` path always.

    ``parts``: a ``part`` cell array of ``parts`` balanced stretches of the cycle
    (:func:`stretch_parts`); the report gains ``"partition"`` (sizes, imbalance).
    ``lattice``: as :func:`~hammesh.parallel.run.parallel_hamiltonian` (``False``: no
    interior lattice, each tile Triangle's own run). ``tree``: incircle mode's spanning
    tree in every tile (:func:`hammesh.hamiltonian`).

    Returns the report (counts, seconds, ``index`` path). Pieces are written by the
    worker that made them; the index lists them in the order the cycle enters them.
    """
    from hammesh.io.pvtu import write_index
    from hammesh.parallel.cluster import runner_for

    out = Path(directory)
    check_target(out, force=force, inputs=inputs)
    if parts is not None and (isinstance(parts, bool) or not isinstance(parts, (int, np.integer)) or parts < 1):
        raise InvalidOptionError(f"parts must be a positive integer, got {parts!r}")
    lattice = params.flag("lattice", lattice)
    t0 = time.perf_counter()
    parent = out.absolute().parent
    made = [d for d in [parent, *parent.parents] if not d.exists()]
    parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".partial", dir=parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(work, 0o777 & ~umask)  # mkdtemp's 0700 would become the output's mode
    spill = work / ".spill"
    try:
        with runner_for(workers=workers, client=client, scheduler=scheduler, mode=mode,
                        background=True) as (runner, n_workers):
            estimate = decompose_estimate(domain, min_angle, max_area)
            if tiles is None:
                tiles = default_tiles(estimate, n_workers)
            # workers whose tiles would not fit in memory keep none until the plan
            spill_dir = None
            if spill_wanted(runner, n_workers, tiles, estimate):
                spill.mkdir()
                spill_dir = spill
            tiled = run_tiles(domain, min_angle=min_angle, max_area=max_area, tiles=tiles, runner=runner,
                              mode=mode, keep=keep, progress=progress_bar(progress, 2), spill_dir=spill_dir,
                              lattice=lattice, tree=tree)
            comps = tiled.plan.components
            if parts is not None and parts > int(comps.sum()):
                raise InvalidOptionError(f"--parts {parts}: more parts than the {int(comps.sum()):,} triangles")
            t1 = time.perf_counter()
            fargs = finish_args(tiled)
            types = piece_types(max((a[11] for a in fargs), default=0), int(comps.sum()),
                                int(tiled.mesh_triangles.sum()))
            marks = domain_marks(domain)
            # (the serial path writes the markers when any is nonzero: any input vertex's or segment's)
            if not (len(marks[0]) or np.any(tiled.decomposition.segment_markers != 0)):
                marks = None
            done = runner.gather([runner.submit(_finish_and_write, h, a, str(work / piece_name(i)), comps, parts,
                                                types, apex_marks(tiled, a, marks), pure=False,
                                                **on_holder(runner, h))
                                  for i, (h, a) in enumerate(zip(tiled.outcomes, fargs))])
            t2 = time.perf_counter()
            worker_rss = peak_rss_workers(runner)
        order = sorted(range(len(done)), key=lambda i: done[i][2])
        write_index(work / INDEX_NAME, [done[i][0] for i in order if done[i][1] > 0], max(d[3] for d in done),
                    cycles=len(comps) > 1, part=parts is not None, types=types,
                    point_arrays=None if marks is None else {VERTEX_MARKER: ("Int32", 1)})
        for i, d in enumerate(done):
            if d[1] == 0:
                (work / d[0]).unlink()
        if spill.exists():
            shutil.rmtree(spill)
        _replace_dir(work, out)
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        for d in made:  # parents this call created, innermost first
            try:
                d.rmdir()
            except OSError:
                break
        raise
    t3 = time.perf_counter()
    d = tiled.decomposition
    report = {
        "index": str(out / INDEX_NAME), "pieces": sum(x[1] > 0 for x in done), "triangles": int(sum(x[1] for x in done)),
        "components": comps.tolist(), "verified": True,
        "parallel": {"tiles": d.n_tiles, "workers": n_workers, "repair_rounds": tiled.rounds,
                     "lattice": lattice, "tree": tree,
                     "joins": len(tiled.plan.joins),
                     "join_swaps": sum(j.swap for j in tiled.plan.joins),
                     "joins_not_whole": tiled.plan.fallback_joins, "tile_cycles": tiled.plan.nodes,
                     "pieces": tiled.plan.pieces, "estimate": d.estimate,
                     "mesh_triangles": int(tiled.mesh_triangles.sum()), "spilled": spill_dir is not None,
                     "seconds": {**tiled.seconds, "pieces": t2 - t1, "index": t3 - t2, "total": t3 - t0},
                     "tile_seconds": {**tiled.tile_seconds,
                                      **{k: sum(x[5][k] for x in done)
                                         for k in ("finish", "write", "cpu_finish", "cpu_write")}},
                     "tile_steps": [{**st, **{k: v for k, v in x[5].items() if k != "clock"},
                                     "piece_at": task_clock(x[5]["clock"], "piece_at")["piece_at"]}
                                    for st, x in zip(tiled.tile_steps, done)],
                     "since_start": {**tiled.since_start, "end": since_start()},
                     "tail_threads": tiled.tail_threads,
                     "driver_cpu": {**tiled.driver_cpu, "end": time.process_time()},
                     "peak_rss_mb": {"driver": peak_rss_mb(), "workers": worker_rss}},
    }
    if not_carried(domain):
        report["not_carried"] = not_carried(domain)
    if parts is not None:
        sizes = np.sum([x[4] for x in done], axis=0)
        report["partition"] = {"k": int(parts), "scheme": "cycle stretches (shift 0)",
                               "size_min": int(sizes.min()), "size_max": int(sizes.max()),
                               "imbalance": float(sizes.max() * parts / sizes.sum())}
    return report


def _replace_dir(work: Path, out: Path) -> None:
    """Rename the finished ``work`` onto ``out``; an existing ``out`` (empty, or
    ``--force``) is moved aside first and removed after."""
    if not out.exists():
        os.rename(work, out)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".old", dir=work.parent))
    old.rmdir()
    os.rename(out, old)
    try:
        os.rename(work, out)
    except BaseException:
        os.rename(old, out)  # put the old content back
        raise
    shutil.rmtree(old, ignore_errors=True)


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
