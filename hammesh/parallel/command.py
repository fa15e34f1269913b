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
           "EARLY_START", "START_BEFORE_IMPORTS"]

#: ``--workers N`` starts its local cluster before the domain is read (in a thread of
#: its own: importing Dask, forking the workers), not after; False: after (the order
#: before session 10, kept for the A/B in ``benchmarks/bench_scale.py --startup``)
EARLY_START = True
#: the local cluster's thread starts before the driver's imports (it imports Dask
#: meanwhile and forks once they are done); False: after them (session 12's order,
#: kept for the A/B in ``benchmarks/bench_scale.py --imports-ab``)
START_BEFORE_IMPORTS = True

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
        if cluster.QUIET_LLVM_LOCK and args.workers is not None:
            cluster.quiet_llvm_lock()  # (before any kernel loads: the cluster's thread waits for ``ready``)
        ready.set()
        return _run(args, started, stack)


def _run(args: argparse.Namespace, started, stack: contextlib.ExitStack) -> int:
    """:func:`run_parallel` once the cluster is starting; ``stack`` closes it."""
    from hammesh.cli.mesh import spanning_tree
    from hammesh.cli.pipeline import Outputs, load_input
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
        source = load_input(args.input, strict=args.strict)
        if not isinstance(source, Domain):
            raise InvalidOptionError(f"{args.input}: parallel meshing takes a domain")
        rep = write_partitioned(source, args.output, min_angle=args.min_angle, max_area=args.max_area,
                                tiles=args.tiles, workers=None if started else args.workers, client=started,
                                scheduler=args.scheduler, mode=args.mode, keep=args.keep, parts=args.parts,
                                force=args.force, inputs=inputs, progress=progress,
                                lattice=not args.no_lattice, tree=tree)
        stack.close()  # (the local cluster: closed once the output is in place)
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
    source = load_input(args.input, strict=args.strict)
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
    from hammesh.io.paths import wrote_text  # (a .ele output's .node/.poly named too)

    for label, path in (("mesh", args.output), ("report", args.report)):
        if path is not None:
            print(f"wrote {label}: {wrote_text(path) if label == 'mesh' else path}")
    for x in h.report.get("not_carried", []):
        print(f"note: {x}")
    return 0
