"""``hammesh mesh ... --workers/--scheduler/--tiles/--partitioned``: the parallel path."""

from __future__ import annotations

import argparse
import atexit
import contextlib
import gc
import importlib
import sys
import threading

from hammesh import params
from hammesh.errors import InvalidOptionError

__all__ = ["run_parallel", "check_options", "freeze_at_exit", "early_cluster", "import_driver_modules", "DRIVER_MODULES",
           "EARLY_START", "START_BEFORE_IMPORTS", "prepare", "prepare_beside", "read_source", "PREPARE_IN_CHILD"]

#: ``--workers N`` starts its local cluster before the domain is read (in a thread of
#: its own: importing Dask, forking the workers), not after; False: after (the order
#: before session 10, kept for the A/B in ``benchmarks/bench_scale.py --startup``)
EARLY_START = True
#: the local cluster's thread starts before the driver's imports (it imports Dask
#: meanwhile and forks once they are done); False: after them (session 12's order,
#: kept for the A/B in ``benchmarks/bench_scale.py --imports-ab``)
START_BEFORE_IMPORTS = True
#: ``--workers N`` (a local cluster) reads the domain, estimates it and decomposes it in
#: a child forked once the driver's imports are done (:func:`prepare_beside`); False:
#: the driver reads it and decomposes it beside the cluster's start (session 18)
PREPARE_IN_CHILD = True

_freezing = False


def freeze_at_exit() -> None:
    """Skip the garbage collector's last passes when this interpreter exits.

    At exit Python collects every container object it tracks: after the parallel
    path (numba's kernels, Dask's client and scheduler state) that took 0.3-0.4 s
    of a command's wall time (measured: exit 0.36 s -> 0.08 s). ``gc.freeze()`` run
    by ``atexit`` (after every handler registered later, Dask's included) moves them
    to the permanent generation, which those passes skip; memory goes back to the
    system with the process as before. Nothing here relies on a destructor in a
    reference cycle at exit: every file the command writes is closed (renamed into
    place) before it returns. Registered once per process; in a process that goes
    on (a test calling ``main``), only its exit is concerned.
    """
    global _freezing
    if not _freezing:
        atexit.register(gc.freeze)
        _freezing = True


#: modules the driver's main thread imports before its local cluster may fork the
#: workers (:func:`import_driver_modules`): what reading the domain, estimating and
#: decomposing it, and running the tiles import (tests/parallel/test_startup.py holds
#: that they import nothing more); (name, required)
DRIVER_MODULES = (("hammesh.cli.pipeline", True), ("hammesh.parallel.partitioned", True),
                  ("hammesh.parallel.run", True), ("hammesh.parallel.sizing", True), ("scipy.spatial", True),
                  ("triangle", True), ("psutil", False))


def import_driver_modules() -> None:
    """Import :data:`DRIVER_MODULES` (an optional one may be missing)."""
    for name, required in DRIVER_MODULES:
        try:
            importlib.import_module(name)
        except ImportError:
            if required:
                raise


@contextlib.contextmanager
def early_cluster(args: argparse.Namespace, ready: threading.Event | None = None):
    """The local cluster of ``--workers N``, starting in the background from here on
    (:func:`~hammesh.parallel.cluster.runner_for`), or None (no ``--workers``, a
    ``--scheduler``'s cluster, or :data:`EARLY_START` off). ``ready``: set by the
    caller when its imports are done; the start forks the workers only then.

    Why: the driver's start is serial up to the tiles' submission. The cluster's start
    (importing ``distributed``, ~0.5 s, the scheduler, forking the workers with the
    mode's kernels loaded) used to begin only when the meshing did, after the command
    had read the domain and estimated its size; then (session 10) after the driver's
    own imports (0.4-0.7 s: the options' registries, the pipeline's modules); now as
    soon as the options are checked, beside the driver's imports, reading and
    decomposition. Closed (with the workers) when the command is done.
    """
    if not EARLY_START or args.workers is None:
        yield None
        return
    from hammesh.parallel.cluster import runner_for

    with runner_for(workers=args.workers, mode=args.mode, background=True, ready=ready) as (runner, _):
        yield runner


def prepare(path, strict: bool, min_angle: float | None, max_area: float, tiles: int | None, workers: int):
    """``(domain, decomposition)``: what the parallel path reads and decomposes first
    (``load_input``, the estimate, the default tiles for ``workers``, the
    decomposition: the calls the driver makes, in that order, with the same values),
    or None for an input that is not a domain."""
    from hammesh.cli.pipeline import load_input
    from hammesh.domain import Domain
    from hammesh.parallel.run import decompose_estimate, default_tiles
    from hammesh.parallel.tiles import decompose

    source = load_input(path, strict=strict)
    if not isinstance(source, Domain):
        return None
    if tiles is None:
        tiles = default_tiles(decompose_estimate(source, min_angle, max_area), workers)
    return source, decompose(source, min_angle=min_angle, max_area=max_area, n_tiles=tiles)


@contextlib.contextmanager
def prepare_beside(args: argparse.Namespace, started):
    """A :class:`~hammesh.parallel.forked.Child` running :func:`prepare` for ``--workers
    N``, forked here, or None (:data:`PREPARE_IN_CHILD` off, no local cluster starting
    in this process's background: ``started`` is not a
    :class:`~hammesh.parallel.cluster.Starting` handle still starting, no fork here).
    Killed on the way out unless :func:`read_source` took its result. Called once the
    driver's imports are done (:func:`import_driver_modules`): reading, estimating and
    decomposing then import nothing but numba's own, under its compiler lock, which
    the fork holds (``tests/parallel/test_startup.py``), so the child waits on no
    module lock the cluster's thread (importing Dask) may hold.

    Why: up to the tiles' submission the driver is one interpreter whose threads take
    turns for its lock: its imports and Dask's, then the mode's kernels loaded for the
    workers to inherit and the cluster's start (the cluster's thread) beside reading
    the domain (0.2-0.25 s CPU: the domain's checks load their kernels) and the
    estimate (the main thread), while the machine's other core waited but for the
    decomposition (session 18's child, forked after the reading). This child reads,
    estimates and decomposes on the other core: the driver's thread neither reads nor
    decomposes. (Forked at the command's very start instead, before any thread, it
    made every import a second time: +1.3 s CPU, and under load, with no core
    waiting, later tiles, session 19.) Its output is the driver's own: the same calls
    on the same file (:func:`read_source` hands the decomposition on through
    :func:`~hammesh.parallel.run.offer_decomposition`); where it gives none (bad
    input, a crash) the driver reads the domain itself and raises its error.
    """
    from hammesh.parallel.cluster import Starting
    from hammesh.parallel.forked import Child, can_fork

    child = None
    if PREPARE_IN_CHILD and isinstance(started, Starting) and not started.started() and can_fork():
        from hammesh.parallel.cluster import guard_forks
        from hammesh.parallel.run import DECOMPOSE_MODULES

        for name in DECOMPOSE_MODULES:  # (imported already by the driver's imports: nothing)
            importlib.import_module(name)
        guard_forks()
        child = Child.start(prepare, args.input, args.strict, args.min_angle, args.max_area, args.tiles,
                            started.n_workers)
    try:
        yield child
    finally:
        if child is not None:
            child.close()


def read_source(args: argparse.Namespace, child):
    """The input (``load_input``): the domain :func:`prepare_beside`'s child read,
    its decomposition offered to the tiles' run, or read here (no child, or no result
    from it: this process then meets the input's error first hand)."""
    from hammesh.cli.pipeline import load_input

    if child is not None:
        ok, made = child.result()
        if ok and made is not None:
            from hammesh.parallel.run import offer_decomposition

            domain, decomposition = made
            offer_decomposition(domain, decomposition, min_angle=args.min_angle, max_area=args.max_area,
                                n_tiles=decomposition.n_tiles)
            return domain
    return load_input(args.input, strict=args.strict)


def check_options(args: argparse.Namespace) -> None:
    """Refuse the options the parallel path cannot run with: checks that import no
    library module (made before the local cluster starts)."""
    from hammesh.cli.inputs import DOMAIN_SUFFIXES
    from hammesh.parallel.cluster import DASK_MISSING, dask_installed

    if args.workers is not None:
        params.integer("--workers", args.workers, low=1, high=4096, what="workers")
    if args.tiles is not None:
        params.integer("--tiles", args.tiles, low=1, high=1_000_000, what="tiles")
    if args.workers is not None and args.scheduler is not None:
        raise InvalidOptionError("--workers starts a local cluster, --scheduler uses a running one: give one")
    if (args.workers is not None or args.scheduler is not None) and not dask_installed():
        raise InvalidOptionError(DASK_MISSING)
    if args.input.suffix.lower() not in DOMAIN_SUFFIXES:
        raise InvalidOptionError(f"{args.input}: parallel meshing takes a domain (.poly/.node), not a mesh")
    if args.max_area is None:
        raise InvalidOptionError("parallel meshing needs -a/--max-area (it sets the separators' spacing)")
    if args.backend != "triangle" or args.conforming_delaunay or args.max_steiner is not None:
        raise InvalidOptionError("parallel meshing uses Triangle with -q and -a only "
                                 "(no --backend, --conforming-delaunay, --max-steiner)")
    if args.png is not None or args.strip is not None:
        raise InvalidOptionError("--png and --strip need the whole mesh: not with parallel meshing")
    if args.no_lattice and args.workers is None and args.scheduler is None and args.tiles is None \
            and not args.partitioned:
        raise InvalidOptionError("--no-lattice is for parallel meshing: give --workers, --scheduler, --tiles "
                                 "or --partitioned")
    if args.force and not args.partitioned:
        raise InvalidOptionError("--force replaces an existing --partitioned -o DIRECTORY: give --partitioned")
    if args.parts is not None:
        params.integer("--parts", args.parts, low=1, what="number of parts")
    if args.partitioned:
        if args.output is None:
            raise InvalidOptionError("--partitioned needs -o DIRECTORY")
        if args.renumber is not None:
            raise InvalidOptionError("--renumber needs the whole mesh: not with --partitioned "
                                     "(the pieces keep global ids in cycle order)")


def run_parallel(args: argparse.Namespace) -> int:
    """Check the options, mesh on the tiles, write the outputs (one file or a directory).

    The local cluster of ``--workers`` starts (:func:`early_cluster`) as soon as the
    options are checked; the output paths are checked next (their modules import the
    library), then the domain is read while the cluster starts.
    """
    freeze_at_exit()
    from hammesh.cli import exit_fast

    exit_fast()  # (run as the command: no interpreter teardown after a cluster, hammesh.cli.fast_exit)
    check_options(args)
    from hammesh.parallel import cluster

    if cluster.SINGLE_ARENA and args.workers is not None:
        cluster.single_arena()  # (before the cluster's thread: its forked workers inherit it)
    if cluster.PAUSE_GC and args.workers is not None:
        cluster.pause_gc()  # (until the tiles are submitted: run.run_tiles)
    with contextlib.ExitStack() as stack:
        stack.callback(cluster.resume_gc)  # (an error before the submission)
        ready = threading.Event()
        if not START_BEFORE_IMPORTS:
            import_driver_modules()
        started = stack.enter_context(early_cluster(args, ready))
        import_driver_modules()  # (imported already: nothing)
        child = stack.enter_context(prepare_beside(args, started))  # (before the cluster may fork: not in numba)
        ready.set()
        return _run(args, started, stack, child)


def _run(args: argparse.Namespace, started, stack: contextlib.ExitStack, child=None) -> int:
    """:func:`run_parallel` once the cluster is starting; ``stack`` closes it."""
    from hammesh.cli.mesh import spanning_tree
    from hammesh.cli.pipeline import Outputs
    from hammesh.domain import Domain

    tree = spanning_tree(args)  # (as the serial path: fishbone with --parts unless --tree)
    progress = sys.stderr.isatty()
    if args.partitioned:
        from hammesh.parallel.partitioned import check_target

        inputs = (args.input, args.input.with_suffix(".node"))
        check_target(args.output, force=args.force, inputs=inputs)  # before any work
        from hammesh.io import write_report
        from hammesh.parallel.partitioned import write_partitioned

        Outputs(report=args.report, inputs=(args.input,)).check()
        source = read_source(args, child)
        if not isinstance(source, Domain):
            raise InvalidOptionError(f"{args.input}: parallel meshing takes a domain")
        rep = write_partitioned(source, args.output, min_angle=args.min_angle, max_area=args.max_area,
                                tiles=args.tiles, workers=None if started else args.workers, client=started,
                                scheduler=args.scheduler, mode=args.mode, keep=args.keep, parts=args.parts,
                                force=args.force, inputs=inputs, progress=progress,
                                lattice=not args.no_lattice, tree=tree)
        stack.close()  # (the local cluster: closed once the output is in place)
        if len(source.segments):  # never in silence: the pieces hold no constrained edges yet (tester18 r08)
            from hammesh.io.report import marker_range

            marked = f" and their markers {marker_range(source.segment_markers)}" if source.segment_markers.any() else ""
            rep["not_carried"] = [*rep.get("not_carried", []), (
                f"not written: the constrained edges (the domain's {len(source.segments):,} segments, subdivided)"
                f"{marked}: the partitioned pieces hold no segments yet (a .vtu or a .pvtu without --partitioned "
                "keeps them)")]
        if args.report is not None:
            write_report(rep, args.report)
        par = rep["parallel"]
        print(f"{rep['triangles']:,} triangles in {len(rep['components'])} Hamiltonian cycle(s) over "
              f"{par['tiles']} tiles ({par['joins']} joins), verified per tile and across separators")
        if args.parts is not None:
            p = rep["partition"]
            print(f"{p['k']} parts (cycle stretches): {p['size_min']:,}..{p['size_max']:,} triangles, "
                  f"imbalance {p['imbalance']:.3f}")
        print(f"wrote index: {rep['index']} ({rep['pieces']} pieces)")
        for x in rep.get("not_carried", []):
            print(f"note: {x}")
        return 0
    from hammesh.io import write, write_report
    from hammesh.parallel.cluster import runner_for
    from hammesh.parallel.run import parallel_hamiltonian

    outputs = Outputs(mesh=args.output, report=args.report, inputs=(args.input,))
    outputs.check()
    runner, _ = stack.enter_context(runner_for(scheduler=args.scheduler))
    source = read_source(args, child)
    if not isinstance(source, Domain):
        raise InvalidOptionError(f"{args.input}: parallel meshing takes a domain")
    client = started if started is not None else None if args.scheduler is None else runner
    h = parallel_hamiltonian(source, min_angle=args.min_angle, max_area=args.max_area, tiles=args.tiles,
                             workers=None if client is not None else args.workers, client=client,
                             mode=args.mode, keep=args.keep, progress=progress, lattice=not args.no_lattice,
                             tree=tree)
    stack.close()  # (the clusters: the whole mesh is here)
    if args.parts is not None or args.renumber is not None:
        from hammesh.partition import partitioned

        h = partitioned(h, k=args.parts, renumber=args.renumber)  # the whole mesh is here: as without --workers
    if args.output is not None:
        from hammesh.io import unwritten_data

        # never in silence (as the serial path): what the input brought and the file cannot hold
        lost = [f"not written: {x}" for x in unwritten_data(h, args.output)]
        if lost:
            h.report["not_carried"] = [*h.report.get("not_carried", []), *lost]
        write(h, args.output)
    if args.report is not None:
        write_report(h.report, args.report)
    par = h.report["parallel"]
    print(f"{h.n_triangles:,} triangles in {len(h.components)} Hamiltonian cycle(s) over {par['tiles']} tiles "
          f"({par['joins']} joins), verified; min angle {h.report['min_angle_output_deg']:.2f} deg")
    for label, path in (("mesh", args.output), ("report", args.report)):
        if path is not None:
            print(f"wrote {label}: {path}")
    for x in h.report.get("not_carried", []):
        print(f"note: {x}")
    return 0
