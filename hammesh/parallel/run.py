"""The driver: tiles meshed, made Hamiltonian and joined, on this process or a Dask cluster.

The driver holds the decomposition and small per-tile summaries; the tiles' meshes and
Hamiltonian meshes stay where they were made (Dask futures on the workers). Only
:func:`parallel_hamiltonian` (one mesh in memory) gathers them; the partitioned output
(:mod:`hammesh.parallel.partitioned`) has each worker write its own piece.
"""

from __future__ import annotations

import os
import pickle
import sys
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from hammesh import params
from hammesh.domain import Domain
from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions
from hammesh.parallel.decoupled import (MAX_ROUNDS, bad_corner_vertices, coarse_min_angle, repair_rows,
                                        small_angle_vertices)
from hammesh.parallel.joins import BorderRows, Plan, TilePiece, border_rows, finish_tile, plan_joins
from hammesh.parallel.markers import input_vertex_markers, marked_inputs, point_markers
from hammesh.parallel.tile_mesh import mesh_tile
from hammesh.parallel.tiles import MIN_TILE_TRIANGLES, Decomposition, check_bounds, decompose, split_segments
from hammesh.parallel.union import assemble, check_union

__all__ = ["domain_marks", "LocalRunner", "Tiled", "TileOutcome", "tile_task", "run_tiles", "finish_args", "finish_outcome", "finish_all",
           "outcome_hamiltonian", "parallel_hamiltonian", "default_tiles", "TRIANGLES_PER_TILE", "progress_bar", "since_start", "decompose_beside", "DECOMPOSE_IN_CHILD", "DECOMPOSE_MODULES",
           "register_sizeof", "BALANCE_TILES", "MIN_BALANCED_TILE", "MORE_BALANCE_TILES", "MIN_THIRD_TILE",
           "MOST_BALANCE_TILES", "MIN_FOURTH_TILE",
           "not_carried", "SUMMARIES_WITH_TILES", "task_clock", "gather_widening"]

#: each tile's summary submitted with the tile (False: gathered after the last tile is done)
SUMMARIES_WITH_TILES = True
#: tiles beyond one per worker when the estimate is large (memory per task ~ 1 GB)
TRIANGLES_PER_TILE = 3_000_000
#: tiles per worker for balance (several workers, tiles of at least ``MIN_BALANCED_TILE``)
BALANCE_TILES = 2
#: estimated triangles per tile below which no tile is added for balance
MIN_BALANCED_TILE = 500_000
#: tiles per worker for balance when each still keeps ``MIN_THIRD_TILE`` triangles
MORE_BALANCE_TILES = 3
#: estimated triangles per tile below which the third tile per worker is not made
MIN_THIRD_TILE = 800_000
#: tiles per worker for balance when each still keeps ``MIN_FOURTH_TILE`` triangles
#: (session 17; ``MOST_BALANCE_TILES = 3`` restores session 13's rule)
MOST_BALANCE_TILES = 4
#: estimated triangles per tile below which the fourth tile per worker is not made
MIN_FOURTH_TILE = 700_000


class _Done:
    def __init__(self, value: Any) -> None:
        self.value = value

    def result(self) -> Any:
        return self.value


class LocalRunner:
    """Runs every task at once in this process (the ``submit``/``gather`` of a Dask client)."""

    #: Dask's scheduling keywords, meaningless here
    DASK_KEYWORDS = frozenset({"pure", "workers", "allow_other_workers", "key", "priority", "resources", "retries"})

    def submit(self, fn: Callable, *args: Any, **kw: Any) -> _Done:
        args = tuple(a.value if isinstance(a, _Done) else a for a in args)
        return _Done(fn(*args, **{k: v for k, v in kw.items() if k not in self.DASK_KEYWORDS}))

    def gather(self, futures: list) -> list:
        return [f.value for f in futures]


def default_tiles(estimate: float, workers: int) -> int:
    """Tiles for ``workers``: a multiple of them (3 tiles on 2 workers take as long as
    4), more when a tile would exceed ``TRIANGLES_PER_TILE`` by more than 20 %, and
    with several workers at least ``BALANCE_TILES`` per worker while a tile keeps
    ``MIN_BALANCED_TILE`` triangles.

    Why the balance tiles: tiles of equal triangle counts do not cost the same. On
    the 6M demo's two tiles sparse ``hamiltonian()`` took 2.3 and 3.5-3.8 s CPU (the
    second's cover and fans 1.3 and 0.6-0.8 s against 0.55 and 0.03 s); the command
    waits for the slower while the other worker idles. Four tiles took 1.62 / 1.31 /
    1.37 / 1.27 s (5.6 s in all against 5.9): run largest first, each worker taking
    the next when free (:data:`~hammesh.parallel.cluster.TILE_QUEUE`), by those
    figures the workers end 0.2 s apart instead of 1.3 s. Three per worker
    (``MORE_BALANCE_TILES``, session 13) while each keeps ``MIN_THIRD_TILE``: at 6M
    the four tile tasks still took 1.54-1.86 s and the last one's end decided the
    tiles' stage; six tiles of 1M ended it sooner, with less CPU in all (interleaved
    fresh runs, wall 5.22 s against 5.40 s median). At 3M six tiles of 0.5M were
    slower than four (3.88 s against 3.62 s): docs/scale.md. Four per worker
    (``MOST_BALANCE_TILES``, session 17) while each keeps ``MIN_FOURTH_TILE``: the 6M
    demo's eight tiles cost 0.75-0.95 s CPU each against 0.90-1.39 s for six (the
    tile tasks' sum 6.47-6.73 s against 6.70-6.80 s, one process, interleaved), and
    the workers ended together (busy 6.3 / 6.3, 6.4 / 6.3, 4.0 / 4.0 s against 6.0 /
    5.6, 6.6 / 6.0, 5.5 / 5.1 s with six; whole CPU the same, 1.81 x raw).
    """
    w = max(1, int(workers))
    per = max(1, int(np.ceil(estimate / (w * TRIANGLES_PER_TILE) - 0.2)))
    if w > 1 and estimate >= BALANCE_TILES * w * MIN_BALANCED_TILE:
        per = max(per, BALANCE_TILES)
    if w > 1 and estimate >= MORE_BALANCE_TILES * w * MIN_THIRD_TILE:
        per = max(per, MORE_BALANCE_TILES)
    if w > 1 and estimate >= MOST_BALANCE_TILES * w * MIN_FOURTH_TILE:
        per = max(per, MOST_BALANCE_TILES)
    # never more than the domain holds (``decompose`` refuses tiles of fewer than
    # MIN_TILE_TRIANGLES): a small domain with ``--workers 2`` was refused, exit 2, where
    # the serial command meshes it (session 20: Triangle's ``A`` at -a 0.02, ~7 triangles);
    # the estimate is ``decompose``'s own up to rounding, hence the margin
    return max(1, min(w * per, int(estimate * (1.0 - 1e-9) // MIN_TILE_TRIANGLES)))


@dataclass(frozen=True, eq=False)
class TileOutcome:
    """What one tile's task made: its Triangle mesh's counts, the bad corners that call
    for a repair round (then nothing else), or its Hamiltonian mesh's border rows.

    ``mesh`` / ``ham`` stay on the worker (a Dask future holds them) and are None in the
    summary the driver gathers (:meth:`small`); ``spill`` names a file holding ``ham``
    instead, when a worker would otherwise keep several tiles' meshes in memory until
    the joins are planned. ``seconds``: the worker's time per step.
    """

    tile: int
    bad: np.ndarray
    n_mesh_points: int
    n_mesh_triangles: int
    border: BorderRows | None
    seconds: dict
    mesh: Mesh | None = None
    ham: HamiltonianMesh | None = None
    spill: str | None = None
    #: the task's wall clock (``time.time()``) at its start and end, and its worker's
    #: process id: the report's timeline of the workers (``tile_steps``' ``at``, ``worker``)
    clock: tuple = ()

    def small(self) -> "TileOutcome":
        return replace(self, mesh=None, ham=None)


def tile_task(tile, n_input: int, min_angle: float | None, max_area: float, mode: str, keep: float,
              keep_mesh: bool = False, spill: str | None = None, check: bool = True,
              lattice: bool = True, tree: str = "quadtree", ignore: np.ndarray | None = None) -> TileOutcome:
    """Mesh one tile, check its prescribed corners, make it Hamiltonian (certified), take
    its border rows: one task, so a worker goes from Triangle to the cycle without
    waiting for the other tiles (a repair round is rare: then only the mesh's counts
    and the bad corners come back). ``check=False``: no repair check (last round).
    ``lattice=False``: Triangle alone, no interior lattice (:func:`mesh_tile`); ``tree``:
    the spanning tree (incircle) or the opt-in compact cover (sparse, issue 14) (:func:`hammesh.hamiltonian`);
    ``ignore``: vertices the repair check never reports (the small input angles)."""
    from hammesh.postprocess import hamiltonian

    register_sizeof()
    e0 = time.time()
    t0, c0, h0 = time.perf_counter(), time.process_time(), time.thread_time()
    mesh = mesh_tile(tile, min_angle, max_area, lattice=lattice)
    t1, c1, h1 = time.perf_counter(), time.process_time(), time.thread_time()
    bad = bad_corner_vertices(tile.vertex_ids, n_input, mesh, min_angle, ignore) if check else np.zeros(0, np.int64)
    # wall seconds per step, and this process's CPU seconds (what a loaded machine does
    # not distort: the steps' cost against a raw Triangle call's CPU time)
    # (and this thread's: the worker's other threads, Dask's, are not the mesh's)
    sec = {"mesh": t1 - t0, "cpu_mesh": c1 - c0, "thread_mesh": h1 - h0}
    if len(bad):
        return TileOutcome(tile=tile.index, bad=bad, n_mesh_points=mesh.n_points, n_mesh_triangles=mesh.n_triangles,
                           border=None, seconds=sec, clock=(e0, time.time(), os.getpid()))
    ham = hamiltonian(mesh, mode=mode, keep=keep, tree=tree)
    t2, c2 = time.perf_counter(), time.process_time()
    border = border_rows(ham, tile, tile.index)
    t3, c3 = time.perf_counter(), time.process_time()
    if spill is not None:
        with open(spill, "wb") as f:  # read back by finish_outcome on a worker (our own file)
            pickle.dump(ham, f, protocol=pickle.HIGHEST_PROTOCOL)
        ham = None
    sec.update(hamiltonian=t2 - t1, border=t3 - t2, spill=time.perf_counter() - t3,
               cpu_hamiltonian=c2 - c1, cpu_border=c3 - c2, cpu_spill=time.process_time() - c3)
    return TileOutcome(tile=tile.index, bad=bad, n_mesh_points=mesh.n_points, n_mesh_triangles=mesh.n_triangles,
                       border=border, seconds=sec, mesh=mesh if keep_mesh else None, ham=ham, spill=spill,
                       clock=(e0, time.time(), os.getpid()))


def _outcome_nbytes(outcome: TileOutcome) -> int:
    """Bytes a tile's outcome holds (Dask's ``sizeof``: without it Dask takes the
    dataclass for ~100 bytes and may run the next task on another worker, moving the
    whole mesh there).

    Only arrays the meshes hold are counted: ``HamiltonianMesh.neighbors`` is computed
    on first use, and asking for it here (``hasattr``) made it, on every tile, after
    the task: ~1.3 s CPU and 216 MB more per 9M-row incircle tile, unused."""
    total = 1000
    for m in (outcome.mesh, outcome.ham):
        if m is not None:
            held = vars(m)  # (fields and computed values already kept; computes nothing)
            total += sum(held[f].nbytes for f in ("points", "triangles", "position", "parent", "kind",
                                                  "triangle_attributes", "neighbors")
                         if isinstance(held.get(f), np.ndarray))
    return total


_sizeof_registered = False


def register_sizeof() -> None:
    """Tell Dask an outcome's size (:func:`_outcome_nbytes`), once per process; a no-op
    without Dask. Called by every tile's task, in the process that holds its outcome
    (where Dask asks), and at import where Dask is already loaded (a worker): not at
    the driver's import, where ``dask`` would cost ~0.2-0.4 s of the command's serial
    start (it imports jinja2 among others); a local cluster imports it in its own thread."""
    global _sizeof_registered
    if _sizeof_registered or "dask" not in sys.modules:  # (no Dask here: nobody asks)
        return
    try:
        from dask.sizeof import sizeof as _dask_sizeof
    except ImportError:  # pragma: no cover - without Dask there is no scheduler to tell
        return
    _dask_sizeof.register(TileOutcome)(_outcome_nbytes)
    _sizeof_registered = True


if "dask" in sys.modules:
    register_sizeof()


def on_holder(runner, handle) -> dict:
    """``submit`` keywords that run a task on the worker holding ``handle`` (a Dask
    future): the tile's meshes stay where they were made. Nothing for the local runner."""
    who_has = getattr(runner, "who_has", None)
    if who_has is None or not hasattr(handle, "key"):
        return {}
    where = who_has([handle]).get(handle.key) or []
    return {"workers": list(where), "allow_other_workers": True} if where else {}


def wait_for(runner, handles: list) -> None:
    """Wait until Dask futures are done (without moving their results); no-op locally."""
    if hasattr(runner, "who_has"):
        from distributed import wait

        wait(handles)
        bad = [h for h in handles if h.status == "error"]
        if bad:
            bad[0].result()  # raises the task's exception here


def _small(outcome: TileOutcome) -> TileOutcome:
    return outcome.small()


def _outcome_mesh(outcome: TileOutcome) -> Mesh:
    return outcome.mesh


def outcome_hamiltonian(outcome: TileOutcome, drop_spill: bool = True) -> HamiltonianMesh:
    """The tile's Hamiltonian mesh: held by the outcome, or read from its spill file
    (removed after reading when ``drop_spill``)."""
    if outcome.ham is not None:
        return outcome.ham
    with open(outcome.spill, "rb") as f:
        h = pickle.load(f)
    if drop_spill:
        os.unlink(outcome.spill)
    return h


@dataclass
class Tiled:
    """What the driver knows after :func:`run_tiles`: the plan and handles to the tiles' results."""

    decomposition: Decomposition
    outcomes: list  # handles (futures) to the tiles' TileOutcome (mesh / Hamiltonian mesh on the worker)
    plan: Plan
    mesh_points: np.ndarray
    mesh_triangles: np.ndarray
    ham_points: np.ndarray
    rounds: int
    seconds: dict
    borders: list
    tile_seconds: dict
    #: per tile: its Triangle mesh's triangle count and its task's seconds per step
    tile_steps: list = field(default_factory=list)
    #: seconds from this process's start to the decomposition's start, the tiles'
    #: submission and their end (:func:`since_start`): the driver's serial start
    since_start: dict = field(default_factory=dict)
    #: this process's CPU seconds (every thread: the main one, the cluster's start,
    #: Dask's scheduler and client) at the same points
    driver_cpu: dict = field(default_factory=dict)
    #: the workers' threads per pass raised at the tail (:func:`gather_widening`):
    #: ``[tiles left, threads, seconds since this process started]`` per raise
    tail_threads: list = field(default_factory=list)


def task_clock(clock: tuple, key: str = "at") -> dict:
    """A task's ``(start, end, pid)`` (wall clock, :class:`TileOutcome`'s ``clock``) as
    ``{key: [start, end], "worker": pid}``, the times in seconds since this process
    started (the driver's :func:`since_start`): the workers' timeline beside the driver's."""
    if not clock:
        return {}
    zero = time.time() - since_start()
    return {key: [clock[0] - zero, clock[1] - zero], "worker": int(clock[2])}


def since_start() -> float:
    """Wall seconds since this process started (NaN where unknown): the driver's
    timeline in the report, imports and reading the domain included.

    On Linux from ``/proc``: the process's start in clock ticks since boot against the
    seconds since boot (both the kernel's boot clock). ``psutil``'s ``create_time``
    (the fallback) adds the ticks to the boot time in whole seconds, which drifts from
    the wall clock: measured 0.9 s off on this VM (every figure of the timeline late
    by as much)."""
    try:
        with open("/proc/self/stat") as f:
            ticks = int(f.read().rsplit(")", 1)[1].split()[19])  # field 22, after the command's name
        with open("/proc/uptime") as f:
            up = float(f.read().split()[0])
        return up - ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, AttributeError):
        pass
    try:
        import psutil  # (a dependency of Dask's distributed)

        return time.time() - psutil.Process().create_time()
    except Exception:  # pragma: no cover - no psutil, or no such process information
        return float("nan")


def gather_widening(run, summaries: list, raises: list | None = None) -> list:
    """``run.gather(summaries)``; on a local cluster (:func:`~hammesh.parallel.cluster.local_workers`)
    with :data:`~hammesh.parallel.cluster.TAIL_THREADS`, each time a tile ends with
    fewer tiles left than workers, the workers' threads per pass go up to the cores
    over the tiles left, and back to their share once all are done; each raise is
    appended to ``raises`` as ``[tiles left, threads, seconds since the start]``.

    Why: tiles of equal triangle counts do not cost the same (the 6M demo's sparse
    ``hamiltonian()`` 0.8-1.35 s CPU per 1M-triangle tile, nothing in the
    decomposition predicts which), so one worker ends its last tile first and idles
    while the other finishes its own (0.2-1.2 s in the runs of session 16). With two
    threads a tile's sparse ``hamiltonian()`` runs its threaded passes and the
    certificate's side work beside its main thread: measured on two 1M tiles of the
    6M demo, in one process, main thread CPU 0.89 -> 0.60 s and 1.32 -> 1.02-1.23 s,
    process CPU +7-13 %. The output does not depend on the thread count.
    """
    from hammesh.parallel.cluster import TAIL_THREADS, local_workers, set_threads, worker_threads

    workers = local_workers(run)
    if not TAIL_THREADS or workers is None or workers < 2 or not summaries:
        return run.gather(summaries)
    from distributed import as_completed

    share, raised, left = worker_threads(workers), None, len(summaries)
    for _ in as_completed(summaries):
        left -= 1
        if 0 < left < workers:
            k = max(share, (os.cpu_count() or 1) // left)
            if k != (raised or share):
                try:
                    run.run(set_threads, k)
                except Exception:  # noqa: BLE001 - optional: a worker gone is the gather's to report
                    continue
                raised = k
                if raises is not None:
                    raises.append([left, k, since_start()])
    small = run.gather(summaries)
    if raised is not None:
        try:
            run.run(set_threads, share)  # (the pieces run on every worker again)
        except Exception:  # noqa: BLE001 - as above; the pieces' tasks report a worker gone
            pass
    return small


def run_tiles(domain: Domain, *, min_angle: float | None, max_area: float, tiles: int, runner=None,
              mode: str = "sparse", keep: float = 0.9, progress: Callable[[str, int], None] | None = None,
              keep_meshes: bool = False, spill_dir: str | os.PathLike[str] | None = None,
              lattice: bool = True, tree: str = "quadtree") -> Tiled:
    """Decompose, run every tile's task (mesh, repair check, Hamiltonian), repair, plan the joins.

    ``keep_meshes``: the workers keep the tile meshes (for the union certificate);
    ``spill_dir``: the workers write each tile's Hamiltonian mesh there instead of
    keeping it in memory until the plan is made; ``lattice=False``: the tiles are
    meshed by Triangle alone, without the interior lattice (docs/scale.md); ``tree``:
    as :func:`hammesh.hamiltonian` takes it, in every tile.
    """
    from hammesh.parallel.cluster import Starting, resume_gc
    from hammesh.postprocess.incircle import TREES

    params.choice("tree", tree, TREES)  # (here, not in every tile's task)
    run = runner or LocalRunner()
    note = progress or (lambda what, n: None)

    t0, s0, p0 = time.perf_counter(), since_start(), time.process_time()
    starting = isinstance(run, Starting)  # (a local cluster starting beside the decomposition)
    # (the futures are held until the tiles are done: Dask forgets a task nobody holds)
    warming = [] if starting else warm_workers(run, mode)
    decomp = decompose_beside(run, domain, min_angle=min_angle, max_area=max_area, n_tiles=tiles)
    t1 = time.perf_counter()
    if starting:
        run.tiles_coming()  # (no prefault task before the tiles now)
        warming = warm_workers(run, mode)
    t1b = time.perf_counter()
    # largest first (longest processing time first: the last tile to start is a small one)
    rank = np.argsort(np.argsort([-t.estimate for t in decomp.tiles], kind="stable"))
    ignore = small_angle_vertices(decomp)

    def submit(i: int, check: bool = True):
        spill = None if spill_dir is None else os.path.join(str(spill_dir), f"tile_{i:06d}.pickle")
        return run.submit(tile_task, decomp.tiles[i], decomp.n_input, min_angle, max_area, mode, keep, keep_meshes,
                          spill, check, lattice, tree, ignore, pure=False, priority=int(decomp.n_tiles - rank[i]))

    handles = [submit(i) for i in np.argsort(rank).tolist()]
    handles = [handles[r] for r in rank.tolist()]  # (tile order again)
    # each tile's summary is asked for with the tile: Dask runs it on the worker that
    # holds the outcome as soon as the tile is done, not in a round after the last one
    summaries = [run.submit(_small, h, pure=False) for h in handles] if SUMMARIES_WITH_TILES else None
    s1, p1 = since_start(), time.process_time()
    resume_gc()  # (the command's serial start is over: cluster.pause_gc)
    raises: list = []
    if summaries is None:
        wait_for(run, handles)  # done: their holders are known
        small = run.gather([run.submit(_small, h, pure=False, **on_holder(run, h)) for h in handles])
    else:
        small = gather_widening(run, summaries, raises)  # (a tile's error is raised here)
    del warming, summaries
    rounds = 0
    while any(len(o.bad) for o in small):
        ids = np.unique(np.concatenate([o.bad for o in small]))
        rows = repair_rows(decomp, ids)
        rounds += 1
        changed = np.zeros(0, np.int64)
        if len(rows):  # (none: a bad corner at a lone vertex; its tile is made as it is)
            decomp, changed = split_segments(decomp, rows)
        redo = sorted(set(changed.tolist()) | {i for i, o in enumerate(small) if len(o.bad)})
        for i in redo:
            handles[i] = submit(i, check=rounds < MAX_ROUNDS and len(rows) > 0)
        wait_for(run, [handles[i] for i in redo])
        again = run.gather([run.submit(_small, handles[i], pure=False, **on_holder(run, handles[i])) for i in redo])
        for i, o in zip(redo, again):
            small[i] = o
    note("tiles", len(small))
    t2, p2 = time.perf_counter(), time.process_time()
    borders = [o.border for o in small]
    plan = plan_joins(borders, len(decomp.vertices), keep=keep, n_separators=int(decomp.separator.sum()))
    area = sum(b.area for b in borders)
    if abs(area - decomp.area) > 1e-9 * abs(decomp.area) * max(1.0, np.sqrt(sum(b.n_triangles for b in borders))):
        raise VerificationError(f"the tiles' area {area!r} differs from the domain's {decomp.area!r}")
    mesh_points = np.array([o.n_mesh_points for o in small], np.int64)
    mesh_triangles = np.array([o.n_mesh_triangles for o in small], np.int64)
    ham_points = np.array([b.n_points for b in borders], np.int64)
    t3 = time.perf_counter()
    tile_seconds: dict = {}
    for o in small:
        for k, v in o.seconds.items():
            tile_seconds[k] = tile_seconds.get(k, 0.0) + v
    return Tiled(decomposition=decomp, outcomes=handles, plan=plan, mesh_points=mesh_points,
                 mesh_triangles=mesh_triangles, ham_points=ham_points, rounds=rounds, borders=borders,
                 seconds={"decompose": t1 - t0, "start": t1b - t1, "tiles": t2 - t1b, "plan": t3 - t2},
                 tile_seconds=tile_seconds,
                 tile_steps=[{"triangles": int(o.n_mesh_triangles), **o.seconds, **task_clock(o.clock)}
                             for o in small],
                 since_start={"decompose": s0, "submitted": s1, "tiles_done": s0 + (t2 - t0)},
                 driver_cpu={"decompose": p0, "submitted": p1, "tiles_done": p2}, tail_threads=raises)


#: while a local cluster starts in this process's background, the domain is decomposed
#: in a forked child (:func:`decompose_beside`); False: in this thread
DECOMPOSE_IN_CHILD = True
#: the modules :func:`~hammesh.parallel.tiles.decompose` imports on first use: imported
#: before the child is forked. A child forked while another thread (the cluster's
#: start, which imports ``scipy.spatial`` too) was inside the import of a module
#: would wait for ever on that module's lock if it imported it.
DECOMPOSE_MODULES = ("scipy.spatial", "triangle", "hammesh.parallel.guard", "hammesh.parallel._kernels",
                     "hammesh.meshing.isolate")


def decompose_beside(run, domain: Domain, **kw) -> Decomposition:
    """:func:`~hammesh.parallel.tiles.decompose` of ``domain``; in a forked child
    (:func:`hammesh.parallel.forked.in_child`) while ``run`` is a local cluster still
    starting in this process (a :class:`~hammesh.parallel.cluster.Starting` handle).

    Why: the cluster's start (importing Dask, loading the mode's kernels for the
    workers to inherit, the scheduler) runs in a thread of this process, and the
    decomposition in its main thread took turns with it for the interpreter's lock
    while the machine's other core waited (measured at 6M: the driver's CPU to the
    tiles' submission about equal to its wall time). The child's decomposition is
    the same (the same code on the same input); where no child could make it (no
    fork here, an error, a crash) this thread makes it, and raises its error.
    """
    from hammesh.parallel.cluster import Starting, guard_forks
    from hammesh.parallel.forked import can_fork, in_child

    if DECOMPOSE_IN_CHILD and isinstance(run, Starting) and not run.started() and can_fork():
        import importlib

        for name in DECOMPOSE_MODULES:  # (here, waiting for another thread's import of one to end)
            importlib.import_module(name)
        guard_forks()
        ok, decomp = in_child(decompose, domain, **kw)
        if ok:
            return decomp
    return decompose(domain, **kw)


def finish_args(tiled: Tiled) -> list[tuple]:
    """Per tile, the arguments of :func:`~hammesh.parallel.joins.finish_tile` after its
    Hamiltonian mesh (global numbering offsets, its blocks of the plan, its joins)."""
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
    floor = 0.5 * min(b.input_min_angle for b in tiled.borders)
    blocks_of: dict[int, list] = {i: [] for i in range(d.n_tiles)}
    starts_of: dict[int, list] = {i: [] for i in range(d.n_tiles)}
    for bk, s in zip(tiled.plan.blocks, tiled.plan.start.tolist()):
        blocks_of[bk[0]].append(bk)
        starts_of[bk[0]].append(s)
    joins_of: dict[int, list] = {i: [] for i in range(d.n_tiles)}
    for j in tiled.plan.joins:
        joins_of[j.t_tile].append(j)
        if j.u_tile != j.t_tile:
            joins_of[j.u_tile].append(j)
    out = []
    for i, t in enumerate(d.tiles):
        out.append((t, i, blocks_of[i], np.array(starts_of[i], np.int64), joins_of[i], int(mesh_off[i]),
                    int(tiled.mesh_points[i]), int(ham_off[i]), join_base, int(tri_off[i]), sep, n_global,
                    {ji: v for ji, v in apex.items() if tiled.plan.joins[ji].t_tile == i}, floor))
    return out


def finish_outcome(outcome: TileOutcome, *args) -> TilePiece:
    """:func:`~hammesh.parallel.joins.finish_tile` of a tile's outcome (on its worker)."""
    return finish_tile(outcome_hamiltonian(outcome), *args)


def finish_all(tiled: Tiled, runner=None) -> list:
    """Handles to every tile's :class:`~hammesh.parallel.joins.TilePiece` (global numbering)."""
    run = runner or LocalRunner()
    return [run.submit(finish_outcome, h, *a, pure=False, **on_holder(run, h))
            for h, a in zip(tiled.outcomes, finish_args(tiled))]


def parallel_hamiltonian(domain: Domain, *, min_angle: float | None = None, max_area: float, tiles: int | None = None,
                         workers: int | None = None, client=None, mode: str = "sparse", keep: float = 0.9,
                         verify: bool = True, progress: bool = False, lattice: bool = True,
                         tree: str = "quadtree") -> HamiltonianMesh:
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
    mode, keep, tree : as :func:`hammesh.hamiltonian`, per tile.
    verify : bool
        Run the union certificate (``hammesh.verify`` of the output against the union
        of the tile meshes) on top of the per-tile certificates and the union check.
    lattice : bool
        Give each tile's Triangle run an equilateral lattice of points in its interior
        (the default: Triangle then refines only the band along the segments, ~0.65x
        its CPU, every triangle still Triangle's with the same bounds, the interior
        mesh structured). ``False``: each tile is Triangle's own run of its PSLG.

    Returns
    -------
    HamiltonianMesh
        One cycle per connected piece; ``report["parallel"]`` has the tiles' figures.
    """
    from hammesh.parallel.cluster import runner_for

    lattice = params.flag("lattice", lattice)
    t0 = time.perf_counter()
    with runner_for(workers=workers, client=client, mode=mode, background=True) as (runner, n_workers):
        if tiles is None:
            est = decompose_estimate(domain, min_angle, max_area)
            tiles = default_tiles(est, n_workers)
        tiled = run_tiles(domain, min_angle=min_angle, max_area=max_area, tiles=tiles, runner=runner,
                          mode=mode, keep=keep, progress=progress_bar(progress, 1), keep_meshes=verify,
                          lattice=lattice, tree=tree)
        t1 = time.perf_counter()
        pieces = runner.gather(finish_all(tiled, runner))
        meshes = runner.gather([runner.submit(_outcome_mesh, h, pure=False, **on_holder(runner, h))
                                for h in tiled.outcomes]) if verify else None
    h = _join_pieces(tiled, pieces)
    t2 = time.perf_counter()
    report = dict(h.report)
    if verify:
        from hammesh.verify import verify as certificate

        union = assemble(tiled.decomposition, meshes)
        # (at a small input angle Triangle's own run of the whole domain, the coarse one
        # whose shells the tiles keep, misses the bound too: the union is held to that)
        facts = check_union(tiled.decomposition, union, single_run_min_angle=coarse_min_angle(tiled.decomposition))
        stats = certificate(h, union)
        report.update({"verified": True, "min_angle_input_deg": stats["min_angle_input_deg"],
                       "min_angle_output_deg": stats["min_angle_output_deg"],
                       "max_angle_output_deg": stats["max_angle_output_deg"],
                       "union": {"triangles": facts.triangles, "area": facts.area,
                                 "min_angle_deg": facts.min_angle_deg, "separator_edges": facts.separator_edges}})
    t3 = time.perf_counter()
    report["parallel"] = {
        "tiles": tiled.decomposition.n_tiles, "workers": n_workers, "repair_rounds": tiled.rounds,
        "lattice": lattice, "tree": tree,
        "joins": len(tiled.plan.joins), "joins_not_whole": tiled.plan.fallback_joins,
        "join_swaps": sum(j.swap for j in tiled.plan.joins),
        "tile_cycles": tiled.plan.nodes, "pieces": tiled.plan.pieces,
        "estimate": tiled.decomposition.estimate, "mesh_triangles": int(tiled.mesh_triangles.sum()),
        "seconds": {**tiled.seconds, "finish": t2 - t1, "verify": t3 - t2, "total": t3 - t0},
        "tile_seconds": tiled.tile_seconds, "tile_steps": tiled.tile_steps, "since_start": tiled.since_start,
        "driver_cpu": {**tiled.driver_cpu, "end": time.process_time()},
    }
    report["triangles"] = int(len(h.triangles))
    if not_carried(domain):
        report["not_carried"] = not_carried(domain)
    ids, marks = domain_marks(domain)  # (the output's first points are the input's, in order)
    vmarks = point_markers(len(h.points), h.segments, h.segment_markers, (ids, marks))
    return HamiltonianMesh(points=h.points, triangles=h.triangles, segments=h.segments,
                           segment_markers=h.segment_markers, components=h.components, position=h.position,
                           parent=h.parent, kind=h.kind, triangle_attributes=h.triangle_attributes, report=report,
                           vertex_markers=vmarks)


def domain_marks(domain: Domain) -> tuple[np.ndarray, np.ndarray]:
    """The input vertices' nonzero markers as the serial path gives them
    (:func:`~hammesh.parallel.markers.input_vertex_markers`): ``(ids, markers)``."""
    return marked_inputs(input_vertex_markers(domain.vertex_markers, domain.segments, domain.segment_markers))


def not_carried(domain: Domain) -> list[str]:
    """What the domain brings that the tiles' output does not hold, one line each (the
    report's ``not_carried``, printed by the command as ``note:`` lines, as the serial
    path does): its vertex attributes (``Domain.vertex_attributes``, from a ``.node``
    or ``.poly``), which the serial Triangle backend interpolates to every output
    point but the tiles do not take. (Its vertex markers are carried since session 16:
    :mod:`hammesh.parallel.markers`.)"""
    out = []
    va = getattr(domain, "vertex_attributes", None)
    k = int(np.shape(va)[-1]) if va is not None and np.ndim(va) == 2 else 0
    if k:
        out.append(f"vertex attributes ({k} per vertex): parallel meshing does not interpolate them "
                   "(hammesh mesh without --workers/--tiles/--partitioned does)")
    return out


def decompose_estimate(domain: Domain, min_angle, max_area) -> float:
    """Estimated triangle count of a Triangle run: the domain's area (one constrained
    triangulation, no refinement) over ``AREA_FILL x max_area``."""
    from hammesh.parallel.guard import triangulate_guarded

    check_bounds(min_angle, max_area)  # (before the estimate divides by it)

    from hammesh.parallel.sizing import AREA_FILL

    data = {"vertices": np.array(domain.vertices)}
    if len(domain.segments):
        data["segments"] = np.array(domain.segments, dtype=np.int32)
    if len(domain.holes):
        data["holes"] = np.array(domain.holes)
    out = triangulate_guarded(data, ("p" if len(domain.segments) else "pc") + "Q", "the domain's area")
    p, t = np.asarray(out["vertices"]), np.asarray(out.get("triangles", np.zeros((0, 3), int)))
    e1, e2 = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]
    area = float(np.abs(0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])).sum())
    return area / (AREA_FILL * float(max_area))


def _warm(mode: str) -> None:
    from hammesh.postprocess import load_kernels

    load_kernels(mode)


def warm_workers(runner, mode: str = "sparse") -> list:
    """Load the compiled kernels (of ``mode``) on every Dask worker now, beside the
    decomposition on the driver."""
    info = getattr(runner, "scheduler_info", None)
    if info is None:
        return []
    return [runner.submit(_warm, mode, workers=[addr], pure=False, allow_other_workers=False)
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
    tri = np.concatenate([p.point_ids[p.triangles] for p in pieces])[order]
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
