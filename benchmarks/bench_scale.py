"""Decoupled parallel meshing (issue 15): hammesh on tiles vs one raw Triangle call.

For each size (estimated triangle count of a ``q30 a A`` Triangle run of the bundled
demo plate: holes, a crack, two regions), every run a fresh process (so every figure
is a first call: imports, Dask start, kernel loading included), same run:

* raw: one ``triangle.triangulate(domain, "pq30a<A>")`` call (time of the call, peak
  RSS of its process, triangle count);
* ``hammesh mesh demo.poly -q 30 -a A --workers N --partitioned -o DIR [--mode M]`` for
  each N and mode: the whole command's wall time (Dask start, decomposition, tile
  meshing, per-tile Hamiltonian and certificate, joins, pieces and index written), its
  ratio to the raw call, the over-refinement (the tiles' triangles / the raw call's - 1),
  the peak RSS of the driver and of every worker, and where the time went: the
  driver's stages (``decompose``, ``tiles``: waiting for the tiles' tasks, ``plan``,
  ``pieces``: the workers numbering and writing their pieces, ``other``: imports,
  cluster start and stop, reading the domain) and the workers' summed time per step
  (``mesh``: Triangle + regional attributes, ``ham``: ``hamiltonian()`` with its
  certificate, ``border``, ``finish``, ``write``, ``spill``), and the CPU seconds of
  the whole command (every process: driver, Dask, workers) against the raw call's:
  what a loaded machine does not distort, and on two cores the wall time is at least
  half of it; and the driver's serial part: seconds from its process's start to the
  decomposition, the tiles' submission, their end and the output's end, the close
  and exit after that, and the driver's own CPU seconds to the submission and in all
  (the report's ``since_start`` and ``driver_cpu``).

``--partitioned-only`` skips the raw call at the given sizes (100M triangles need ~30
GB in one Triangle run): the raw count is then extrapolated from two raw runs of the
same domain at 0.4M and 1.5M triangles made in the same invocation (fitted as
``c1 / A + c2 / sqrt(A)``: area term plus boundary band), and the time ratio is not
printed. Tiles: ``--tiles`` (default: hammesh's, one per worker, more past 3M each).

    python benchmarks/bench_scale.py [--sizes 1.5e6,6e6] [--workers 1,2] [--modes sparse,incircle]
    python benchmarks/bench_scale.py --sizes 1e8 --workers 2 --partitioned-only --tiles 64

``--imports-ab R``: the same with the local cluster's thread started before the
driver's imports (``command.START_BEFORE_IMPORTS``, the default since session 13) or
after them.

    python benchmarks/bench_scale.py --sizes 6e6 --workers 2 --modes sparse --imports-ab 4

``--startup R``: the driver's start, A/B: ``R`` rounds of two fresh processes each,
alternating, the local cluster started before reading the domain
(``hammesh.parallel.command.EARLY_START``, the default) or after; per run the seconds
from the process's start to the tiles' submission and to their end, the wall time
and the whole command's CPU (first size, first mode, first worker count).

    python benchmarks/bench_scale.py --sizes 1.5e6 --workers 2 --startup 3

``--tile-ab R``: one tile's work in this process, A/B: the first tile of the first
size's decomposition (``--tiles``, default 2) meshed ``R`` times each way, alternating,
with the lattice's own triangles and Triangle on the band only
(``tile_mesh.LATTICE_BAND``, the default) or Triangle on the lattice's points, then
``hamiltonian()`` of each mesh per mode: process CPU seconds per step, triangles,
min angle (threads capped at 1, as in a worker of a 2-worker cluster on 2 cores).

    python benchmarks/bench_scale.py --sizes 6e6 --tile-ab 3 --modes incircle,sparse

``--order-ab R``: the same for the order of the lattice's blocks
(``tile_mesh.LATTICE_ORDER``): row by row (the default since session 12) against a
Hilbert order of the blocks.

    python benchmarks/bench_scale.py --sizes 6e6 --tiles 4 --order-ab 3 --modes incircle,sparse

``--write-ab R``: one tile's piece (first mode) written ``R`` times each way, with the
32-bit integer arrays (``partitioned.piece_types``) or all 64-bit; CPU and size.

    python benchmarks/bench_scale.py --sizes 6e6 --write-ab 3 --modes incircle

``--tiles-ab R``: the whole command against one raw call, ``R`` rounds per mode of
fresh processes alternating the default tiles (two per worker past 1M triangles,
largest first, each worker taking the next when free) and one tile per worker.

    python benchmarks/bench_scale.py --sizes 6e6 --workers 2 --tiles-ab 2 --modes sparse,incircle

Before measuring, every mode runs once small with ``PYTHONDONTWRITEBYTECODE`` unset
(:func:`cache_bytecode`), so that no measured process compiles its imports from
source (``--source-imports``: measure without it); the first line says whether the
bytecode was cached before.

``--vs-ab R --vs-python PY``: the whole command of this installation against another's
(``PY``: e.g. ``/work/venvs/main/bin/python``, an editable install of ``main``), ``R``
interleaved rounds per mode, a raw call per round, both installations' bytecode cached
first: the submission, the driver's CPU, wall / raw per run and their medians.

    python benchmarks/bench_scale.py --sizes 6e6 --workers 2 --modes sparse,incircle --vs-ab 3 --vs-python /work/venvs/main/bin/python

``--ab R``: the whole command against one raw call, ``R`` rounds per mode of fresh
processes alternating session 10's switches on / off (the early cluster start and
the band tiles; the import changes cannot be switched off), after one uncounted 0.2M
run per mode (numba's compile of anything an edit made stale stays out of the A/B).

    python benchmarks/bench_scale.py --sizes 6e6 --workers 2 --ab 2 --modes incircle,sparse
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "hammesh" / "data" / "demo.poly"

RAW = r"""
import json, resource, sys, time
import numpy as np, triangle
import hammesh
from hammesh.meshing.options import format_number
dom = hammesh.read_domain(sys.argv[1])
data = {"vertices": np.array(dom.vertices), "segments": np.array(dom.segments, dtype=np.int32),
        "holes": np.array(dom.holes)}
reg = np.array(dom.regions); reg[:, 3] = -1.0; data["regions"] = reg
t, c = time.perf_counter(), time.process_time()
out = triangle.triangulate(data, "pq30Aa" + format_number(float(sys.argv[2])))
sec, cpu = time.perf_counter() - t, time.process_time() - c
print(json.dumps({"seconds": sec, "cpu_seconds": cpu, "triangles": int(len(out["triangles"])),
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def cache_bytecode(out_dir: str | None, modes: list[str], python: str | None = None) -> str:
    """Let Python cache the bytecode of every module the command imports (driver and
    workers), by one small run per mode with ``PYTHONDONTWRITEBYTECODE`` unset; what
    it says about the cache before.

    Why: with that variable set (this VM's environment) and an installer that does not
    compile (``uv pip install`` without ``--compile-bytecode``), every fresh process
    compiles numpy, numba, scipy, Dask and hammesh from source: measured 1.9 s of a
    3.1 s driver start at 6M. ``pip install`` compiles at install time, so a user's
    command does not pay it, and the raw call's imports are not timed at all.
    ``--source-imports`` measures without this step. ``python``: another interpreter
    (``--vs-python``: its own installation's modules; "was cached" then speaks of this one's).
    """
    import importlib.util

    spec = importlib.util.find_spec("distributed")
    cached = spec is not None and spec.cached is not None and Path(spec.cached).exists()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    for mode in modes:
        tmp = tempfile.mkdtemp(prefix="bench_scale.", dir=out_dir)
        try:
            subprocess.run([python or sys.executable, "-m", "hammesh", "mesh", str(DEMO), "-q", "30", "-a", "1e-3", "--mode", mode,
                            "--workers", "2", "--partitioned", "-o", str(Path(tmp) / "out")],
                           capture_output=True, text=True, check=True, env=env, cwd=NEUTRAL_CWD)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return (f"bytecode: {'was cached' if cached else 'was NOT cached (imports compiled from source)'}; "
            f"cached now by one small run per mode (PYTHONDONTWRITEBYTECODE "
            f"{'set' if 'PYTHONDONTWRITEBYTECODE' in os.environ else 'unset'} in this environment)")


def max_area_for(triangles: float) -> float:
    """The area bound whose Triangle run has about ``triangles`` triangles (estimate)."""
    import hammesh
    from hammesh.parallel.tiles import decompose

    dom = hammesh.read_domain(DEMO)
    probe = 1e-3
    est = decompose(dom, min_angle=30, max_area=probe, n_tiles=1).estimate
    return probe * est / triangles


#: the measured processes' working directory: not a source tree (``python -c``/``-m``
#: put it first on ``sys.path``, so a checkout there would shadow the installation
#: measured: session 19's first A/B against main, run from this worktree, ran this
#: tree's code on both sides)
NEUTRAL_CWD = tempfile.gettempdir()


def raw(area: float) -> dict:
    out = subprocess.run([sys.executable, "-c", RAW, str(DEMO), repr(area)], capture_output=True, text=True,
                         check=True, cwd=NEUTRAL_CWD)
    return json.loads(out.stdout.strip().splitlines()[-1])


def extrapolated_count(area: float) -> tuple[float, str]:
    """Raw triangle count at ``area`` from two raw runs (0.4M, 1.5M): ``c1/A + c2/sqrt(A)``."""
    import numpy as np

    pts = [(a, raw(a)["triangles"]) for a in (max_area_for(4e5), max_area_for(1.5e6))]
    m = np.array([[1 / a, 1 / np.sqrt(a)] for a, _ in pts])
    c = np.linalg.solve(m, np.array([n for _, n in pts], float))
    note = ", ".join(f"{n:,} at a={a:.3g}" for a, n in pts)
    return float(c[0] / area + c[1] / np.sqrt(area)), note


#: ``python -c`` running the command with ``EARLY_START`` (argv[1]) and
#: ``tile_mesh.LATTICE_BAND`` (argv[2]) set, 0 or 1 (forked workers inherit both)
EARLY = ("import sys; import hammesh.parallel.command as c, hammesh.parallel.tile_mesh as tm; "
         "c.EARLY_START = bool(int(sys.argv[1])); tm.LATTICE_BAND = bool(int(sys.argv[2])); "
         "from hammesh.cli import main; sys.exit(main(sys.argv[3:]))")


#: ``python -c`` running the command with ``command.START_BEFORE_IMPORTS`` (argv[1])
#: set, 0 or 1
#: the command with one switch of hammesh.parallel.cluster set (argv[1]: name, argv[2]: 0/1)
#: ``--switch NAME`` (``hammesh.parallel.cluster.NAME``) or ``module.NAME``
#: (``hammesh.parallel.module.NAME``): a boolean is set on / off; any other value is
#: kept (on) or set to its type's zero (off: ``run.TILE_GRADE`` 0.0, equal tiles)
CLUSTER_SWITCH = ("import sys, importlib; m, _, n = sys.argv[1].rpartition('.'); "
                  "c = importlib.import_module('hammesh.parallel.' + (m or 'cluster')); v = getattr(c, n); "
                  "on = bool(int(sys.argv[2])); "
                  "setattr(c, n, on) if isinstance(v, bool) else (None if on else setattr(c, n, type(v)(0))); "
                  "from hammesh.cli import main; sys.exit(main(sys.argv[3:]))")

IMPORTS_FIRST = ("import sys; import hammesh.parallel.command as c; c.START_BEFORE_IMPORTS = bool(int(sys.argv[1])); "
                 "from hammesh.cli import main; sys.exit(main(sys.argv[2:]))")


def ours(area: float, workers: int, tiles: int | None, mode: str, out_dir: str | None,
         early: bool | None = None, band: bool = True, start_first: bool | None = None,
         switch: tuple[str, bool] | None = None, python: str | None = None) -> dict:
    tmp = tempfile.mkdtemp(prefix="bench_scale.", dir=out_dir)
    try:
        rep = Path(tmp) / "report.json"
        head = ([sys.executable, "-c", CLUSTER_SWITCH, switch[0], str(int(switch[1]))] if switch is not None else
                [sys.executable, "-c", IMPORTS_FIRST, str(int(start_first))] if start_first is not None else
                [python or sys.executable, "-m", "hammesh"] if early is None else
                [sys.executable, "-c", EARLY, str(int(early)), str(int(band))])
        cmd = [*head, "mesh", str(DEMO), "-q", "30", "-a", repr(area), "--mode", mode,
               "--workers", str(workers), "--partitioned", "-o", str(Path(tmp) / "out"), "--report", str(rep)]
        if tiles:
            cmd += ["--tiles", str(tiles)]
        load = os.getloadavg()[0]
        t, before = time.perf_counter(), os.times()
        done = subprocess.run(cmd, capture_output=True, text=True, cwd=NEUTRAL_CWD)
        sec, after = time.perf_counter() - t, os.times()
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
        r = json.loads(rep.read_text())
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    r["wall"] = sec
    # CPU seconds of the whole command: driver, Dask and workers (every process it
    # waited for): on two cores its wall time is at least half of this
    r["tree_cpu"] = (after.children_user + after.children_system) - (before.children_user + before.children_system)
    r["load"] = (load, os.getloadavg()[0])  # 1-minute load average before and after: "quiet" or "loaded"
    return r


STEPS = ("mesh", "hamiltonian", "border", "spill", "finish", "write")


def stages(o: dict, raw_cpu: float) -> str:
    par = o["parallel"]
    s = dict(par["seconds"])
    other = o["wall"] - s.pop("total")
    s.pop("index", None)
    drv = " ".join(f"{k} {v:.1f}" for k, v in s.items()) + f" other {other:.1f}"
    ts = dict(par.get("tile_seconds", {}))
    wrk = " ".join(f"{k[:4]} {ts[k]:.1f}" for k in STEPS if k in ts)
    line = f"driver s: {drv} | workers' wall s (sum): {wrk}"
    if raw_cpu == raw_cpu and all(f"cpu_{k}" in ts for k in ("mesh", "hamiltonian")):
        # CPU seconds / the raw call's CPU seconds: what load does not distort
        cpu = " ".join(f"{k[:4]} {ts[f'cpu_{k}'] / raw_cpu:.2f}" for k in STEPS if f"cpu_{k}" in ts)
        total = sum(ts[f"cpu_{k}"] for k in STEPS if f"cpu_{k}" in ts) / raw_cpu
        line += f"\n{'':22}|   workers' CPU / raw CPU (sum over tiles): {cpu}; all steps {total:.2f}"
    return line


def timeline(o: dict) -> str:
    """The driver's serial part: seconds from the process's start to the
    decomposition, the tiles' submission, their end and the output's end (the report's
    ``since_start``), the close and exit after it (the command's wall time minus the
    end), and the driver process's CPU seconds (every thread) at the submission and in
    all (``driver_cpu``)."""
    s, c = o["parallel"].get("since_start") or {}, o["parallel"].get("driver_cpu") or {}
    if "submitted" not in s or "end" not in s:
        return ""
    line = (f"driver timeline s: decompose from {s['decompose']:.2f}, submitted {s['submitted']:.2f}, "
            f"tiles done {s['tiles_done']:.2f}, output done {s['end']:.2f}, close + exit {o['wall'] - s['end']:.2f}")
    if "submitted" in c and "end" in c:
        line += f"; driver CPU {c['submitted']:.2f} s to the submission, {c['end']:.2f} s in all"
    return line


def workers_timeline(o: dict) -> str:
    """Each worker's tasks on the driver's clock (seconds since its process started):
    every tile's task (Triangle, repair check, ``hamiltonian()`` + certificate, border
    rows) and, with ``--partitioned``, its piece (finish + write), largest first as
    submitted; then each worker's busy and idle seconds between the tiles' submission
    and the output's end (the report's ``tile_steps``' ``at``/``piece_at``/``worker``)."""
    par = o["parallel"]
    steps, s = par.get("tile_steps") or [], par.get("since_start") or {}
    if not steps or "at" not in steps[0] or "submitted" not in s:
        return ""
    by: dict = {}
    for i, st in enumerate(steps):
        by.setdefault(st["worker"], []).append((st["at"][0], st["at"][1], f"tile {i} ({st['triangles'] / 1e6:.2f}M)"))
        if "piece_at" in st:
            by[st["worker"]].append((st["piece_at"][0], st["piece_at"][1], f"piece {i}"))
    lo, hi = s["submitted"], s.get("end", max(b for v in by.values() for _, b, _ in v))
    lines = []
    for w, (pid, tasks) in enumerate(sorted(by.items())):
        tasks.sort()
        busy = sum(min(b, hi) - max(a, lo) for a, b, _ in tasks if b > lo)
        lines.append(f"worker {w}: " + ", ".join(f"{name} {a:.2f}-{b:.2f}" for a, b, name in tasks)
                     + f"; busy {busy:.2f} s, idle {hi - lo - busy:.2f} s of {hi - lo:.2f}")
    return f"\n{'':22}|   ".join(lines)


def per_tile(o: dict) -> str:
    """Each tile's ``hamiltonian()`` (with its certificate): CPU seconds, per million of
    the tile's triangles, and its share of all the workers' CPU (issue 15 asks for it:
    the per-tile Hamiltonian is issues 11/13's code, the rest is this path's)."""
    steps = o["parallel"].get("tile_steps") or []
    if not steps or "cpu_hamiltonian" not in steps[0]:
        return ""
    ham = [s["cpu_hamiltonian"] for s in steps]
    tri = [s["cpu_mesh"] for s in steps]
    per_m = [x / s["triangles"] * 1e6 for x, s in zip(ham, steps)]
    every = sum(v for s in steps for k, v in s.items() if k.startswith("cpu_"))
    # each tile's task (mesh, repair check, hamiltonian, border rows) in wall seconds: the
    # joins wait for the last, so a worker whose tiles are done earlier idles meanwhile
    task = [sum(s.get(k, 0.0) for k in ("mesh", "hamiltonian", "border", "spill")) for s in steps]
    return (f"per tile hamiltonian() CPU s {' / '.join(f'{x:.2f}' for x in ham)} "
            f"({' / '.join(f'{x:.2f}' for x in per_m)} per 1M triangles; "
            f"x{sum(ham) / max(sum(tri), 1e-9):.2f} the tiles' meshing), {100 * sum(ham) / max(every, 1e-9):.0f} % "
            f"of the workers' CPU; tile tasks wall s {' / '.join(f'{x:.1f}' for x in task)} "
            f"(spread {max(task) - min(task):.1f})")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1.5e6,6e6", help="estimated triangle counts, comma separated")
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--modes", default="sparse", help="Hamiltonian modes, comma separated (sparse, incircle)")
    ap.add_argument("--tiles", type=int, help="tiles (default: hammesh's: one per worker, more past 3M)")
    ap.add_argument("--partitioned-only", action="store_true",
                    help="no raw call at these sizes: its triangle count is extrapolated from 0.4M and 1.5M runs")
    ap.add_argument("--out-dir", help="where the pieces go while a run lasts (default: the system's temp dir)")
    ap.add_argument("--big", action="store_true", help="also 25M and 100M (100M: with --partitioned-only)")
    ap.add_argument("--startup", type=int, metavar="ROUNDS",
                    help="A/B of the cluster started before / after reading the domain, ROUNDS rounds")
    ap.add_argument("--imports-ab", type=int, metavar="ROUNDS",
                    help="A/B of the cluster's thread started before / after the driver's imports")
    ap.add_argument("--ab", type=int, metavar="ROUNDS",
                    help="A/B of the whole command, session 10's switches (early cluster, band tiles) on / off")
    ap.add_argument("--tiles-ab", type=int, metavar="ROUNDS",
                    help="A/B of the whole command, the default tiles (balance: 2-3 per worker) / one tile per worker")
    ap.add_argument("--other-tiles", type=int, metavar="N",
                    help="with --tiles-ab: the other arm runs N tiles instead of one per worker")
    ap.add_argument("--write-ab", type=int, metavar="ROUNDS",
                    help="A/B of one piece written with 32-bit / 64-bit integer arrays")
    ap.add_argument("--order-ab", type=int, metavar="ROUNDS",
                    help="A/B of one tile with the lattice's blocks row by row / in a Hilbert order")
    ap.add_argument("--source-imports", action="store_true",
                    help="measure without first caching the imported modules' bytecode (cache_bytecode)")
    ap.add_argument("--tile-ab", type=int, metavar="ROUNDS",
                    help="A/B of one tile meshed with the lattice's own triangles / Triangle on its points")
    ap.add_argument("--switch-ab", type=int, metavar="ROUNDS",
                    help="A/B of the whole command, a boolean of hammesh.parallel.cluster (--switch NAME) on / off")
    ap.add_argument("--switch", default="NO_HUGEPAGE_ADVICE", help="with --switch-ab: the switch's name")
    ap.add_argument("--vs-ab", type=int, metavar="ROUNDS",
                    help="A/B of the whole command, this installation against --vs-python's (e.g. main's venv)")
    ap.add_argument("--vs-python", help="with --vs-ab: the other installation's python")
    a = ap.parse_args(argv)
    if a.vs_ab:
        return vs_ab(a)
    if a.switch_ab:
        return switch_ab(a)
    if a.tile_ab:
        return tile_ab(a)
    if a.order_ab:
        return tile_ab(a, "order")
    if a.ab:
        return whole_ab(a)
    if a.tiles_ab:
        return tiles_ab(a)
    if a.write_ab:
        return write_ab(a)
    if a.startup:
        return startup_ab(a)
    if a.imports_ab:
        return imports_ab(a)
    sizes = [float(s) for s in a.sizes.split(",")] + ([25e6, 100e6] if a.big else [])
    workers = [int(w) for w in a.workers.split(",")]
    modes = a.modes.split(",")
    print(cache_bytecode(a.out_dir, modes) if not a.source_imports else
          f"bytecode not cached first (--source-imports; PYTHONDONTWRITEBYTECODE "
          f"{'set' if 'PYTHONDONTWRITEBYTECODE' in os.environ else 'unset'})")
    print("size    raw s  raw MB  | mode      workers  wall s  /raw  over-ref  driver MB  worker MB (each)  tiles joins")
    sys.stdout.flush()
    for n in sizes:
        area = max_area_for(n)
        if a.partitioned_only:
            count, note = extrapolated_count(area)
            r = {"seconds": float("nan"), "cpu_seconds": float("nan"), "triangles": count,
                 "peak_rss_mb": float("nan")}
            print(f"{n / 1e6:5.1f}M   (no raw call) | raw count {count:,.0f} extrapolated from {note}")
        else:
            r = raw(area)
            print(f"{n / 1e6:5.1f}M  {r['seconds']:6.2f} {r['peak_rss_mb']:7.0f}  | {r['triangles']:,} triangles (raw), "
                  f"CPU {r['cpu_seconds']:.2f} s")
        sys.stdout.flush()
        for mode in modes:
            for w in workers:
                o = ours(area, w, a.tiles, mode, a.out_dir)
                par = o["parallel"]
                over = par["mesh_triangles"] / r["triangles"] - 1
                wrk = "/".join(f"{x:.0f}" for x in par["peak_rss_mb"]["workers"]) or "-"
                ratio = o["wall"] / r["seconds"] if r["seconds"] == r["seconds"] else float("nan")
                print(f"{'':22}| {mode:9} {w:5d}  {o['wall']:7.2f} {ratio:5.2f}  {100 * over:+6.2f} % "
                      f"{par['peak_rss_mb']['driver']:9.0f}  {wrk:>16}  {par['tiles']:5d} {par['joins']:5d}")
                print(f"{'':22}|   {stages(o, r['cpu_seconds'])}\n{'':22}|   ({o['triangles']:,} output triangles, "
                      f"{par['repair_rounds']} repair rounds; load average {o['load'][0]:.1f} -> {o['load'][1]:.1f})")
                if r["cpu_seconds"] == r["cpu_seconds"]:
                    print(f"{'':22}|   whole command's CPU (driver, Dask, workers) / raw CPU: "
                          f"{o['tree_cpu'] / r['cpu_seconds']:.2f} ({o['tree_cpu']:.1f} s)")
                if timeline(o):
                    print(f"{'':22}|   {timeline(o)}")
                if per_tile(o):
                    print(f"{'':22}|   {per_tile(o)}")
                if workers_timeline(o):
                    print(f"{'':22}|   {workers_timeline(o)}")
                sys.stdout.flush()
    return 0


#: ``--tile-ab`` / ``--order-ab``: the ``tile_mesh`` switch and its (default, other) values
TILE_SWITCHES = {"band": ("LATTICE_BAND", True, False), "order": ("LATTICE_ORDER", "rows", "hilbert")}


def tile_ab(a, switch: str = "band") -> int:
    """``--tile-ab`` (``--order-ab``): one tile meshed with ``tile_mesh``'s switch at its
    default and its other value (the band mesh against Triangle on the lattice's points;
    the lattice's blocks row by row against a Hilbert order), same process, alternating;
    then ``hamiltonian()`` of each mesh per mode."""
    import numpy as np

    import hammesh
    import hammesh.parallel.tile_mesh as tm
    from hammesh import threads
    from hammesh.parallel.tiles import decompose
    from hammesh.parallel.union import min_angles_deg
    from hammesh.postprocess import hamiltonian, load_kernels

    name, default, other = TILE_SWITCHES[switch]
    rounds = a.order_ab if switch == "order" else a.tile_ab
    threads.limit(1)
    area = max_area_for(float(a.sizes.split(",")[0]))
    d = decompose(hammesh.read_domain(DEMO), min_angle=30, max_area=area, n_tiles=a.tiles or 2)
    tile, modes = d.tiles[0], a.modes.split(",")
    for mode in modes:
        load_kernels(mode)
    tm.mesh_tile(tile, 30, area)  # (kernels loaded: not the A/B's business)
    cpu: dict = {}
    for r in range(rounds):
        for value in ((default, other) if r % 2 == 0 else (other, default)):
            setattr(tm, name, value)
            c = time.process_time()
            m = tm.mesh_tile(tile, 30, area)
            row = {"mesh": time.process_time() - c}
            for mode in modes:
                c = time.process_time()
                hamiltonian(m, mode=mode)
                row[mode] = time.process_time() - c
            for k, v in row.items():
                cpu.setdefault((value, k), []).append(v)
            print(f"round {r} {switch}={value}: {m.n_triangles:,} triangles, min angle "
                  f"{min_angles_deg(m.points, m.triangles).min():.3f}; CPU s "
                  + ", ".join(f"{k} {v:.3f}" for k, v in row.items()) + f" (load {os.getloadavg()[0]:.1f})")
            sys.stdout.flush()
    setattr(tm, name, default)
    for k in ["mesh", *modes]:
        on, off = (float(np.median(cpu[(v, k)])) for v in (default, other))
        print(f"{k}: {switch} {default} {on:.3f} s, {other} {off:.3f} s (medians), ratio {on / off:.2f}")
    return 0


def write_ab(a) -> int:
    """``--write-ab``: the first tile's piece (first mode) written ``R`` times each way,
    alternating, with ``partitioned.piece_types`` (32-bit integers, ``kind`` one byte)
    or all 64-bit: process CPU seconds of the finish + write step and the file's size."""
    import hammesh
    from hammesh import threads
    from hammesh.parallel.partitioned import _finish_and_write, piece_types
    from hammesh.parallel.run import finish_args, run_tiles

    threads.limit(1)
    area = max_area_for(float(a.sizes.split(",")[0]))
    tiled = run_tiles(hammesh.read_domain(DEMO), min_angle=30, max_area=area, tiles=a.tiles or 2,
                      mode=a.modes.split(",")[0])
    comps, fargs = tiled.plan.components, finish_args(tiled)
    types = piece_types(max(x[11] for x in fargs), int(comps.sum()), int(tiled.mesh_triangles.sum()))
    outcome = tiled.outcomes[0].value
    tmp = tempfile.mkdtemp(prefix="bench_scale.", dir=a.out_dir)
    cpu: dict = {True: [], False: []}
    try:
        for r in range(a.write_ab):
            for narrow in ((True, False) if r % 2 == 0 else (False, True)):
                path = Path(tmp) / f"piece_{int(narrow)}.vtu"
                c = time.process_time()
                _finish_and_write(outcome, fargs[0], str(path), comps, None, types if narrow else None)
                cpu[narrow].append(time.process_time() - c)
                print(f"round {r} 32-bit={int(narrow)}: CPU {cpu[narrow][-1]:.3f} s, {path.stat().st_size / 2**20:.0f} MB "
                      f"(load {os.getloadavg()[0]:.1f})")
                sys.stdout.flush()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    on, off = statistics.median(cpu[True]), statistics.median(cpu[False])
    print(f"piece write: 32-bit {on:.3f} s, 64-bit {off:.3f} s CPU (medians), ratio {on / off:.2f}")
    return 0


def _ab_start(a) -> tuple[float, int, dict]:
    """An A/B's area (first size), worker count (first), and its one raw call (printed),
    after caching the bytecode (:func:`cache_bytecode`) unless ``--source-imports``."""
    area = max_area_for(float(a.sizes.split(",")[0]))
    if not a.source_imports:
        print(cache_bytecode(a.out_dir, a.modes.split(",")))
    r = raw(area)
    print(f"raw: {r['seconds']:.2f} s wall, {r['cpu_seconds']:.2f} s CPU, {r['triangles']:,} triangles "
          f"(load {os.getloadavg()[0]:.1f})")
    return area, int(a.workers.split(",")[0]), r


def whole_ab(a) -> int:
    """``--ab``: one raw call, then per mode ``R`` rounds of the command with session
    10's switches on and off (``EARLY_START``, ``LATTICE_BAND``), alternating."""
    area, w, r = _ab_start(a)
    for mode in a.modes.split(","):
        # a small run first, not counted: numba compiles what an edit made stale in
        # the first run (the workers' lattice kernels were compiled inside the first
        # run's measured mesh step: session 10's incircle A/B, run first, had it)
        o = ours(max_area_for(2e5), w, None, mode, a.out_dir, early=True, band=True)
        print(f"{mode} warm-up (0.2M, not counted): wall {o['wall']:.2f} s, whole CPU {o['tree_cpu']:.2f} s")
        got: dict = {True: [], False: []}
        for k in range(a.ab):
            for on in ((True, False) if k % 2 == 0 else (False, True)):
                o = ours(area, w, a.tiles, mode, a.out_dir, early=on, band=on)
                got[on].append(o)
                ts = o["parallel"]["tile_seconds"]
                print(f"{mode} round {k} new={int(on)}: {_vs_raw(o, r)}, "
                      f"workers' mesh CPU {ts['cpu_mesh']:.2f} s (thread {ts.get('thread_mesh', float('nan')):.2f}), "
                      f"hamiltonian {ts['cpu_hamiltonian']:.2f} s, {o['triangles']:,} triangles")
                sys.stdout.flush()
        for on in (True, False):
            cpu = statistics.median(o["tree_cpu"] for o in got[on])
            wall = statistics.median(o["wall"] for o in got[on])
            print(f"{mode} new={int(on)}: whole CPU / raw CPU median {cpu / r['cpu_seconds']:.2f}, "
                  f"wall / raw median {wall / r['seconds']:.2f} (the first round may include numba's compile)")
    return 0


def tiles_ab(a) -> int:
    """``--tiles-ab``: one raw call, then per mode ``R`` rounds of the command with the
    default tiles (``run.default_tiles``: two per worker past 1M triangles, three past
    4.8M, run largest first, a worker taking the next when free) and with one tile per
    worker (the default before session 12; ``--other-tiles N``: N tiles), alternating; wall and whole CPU against the raw call's,
    and the spread of the workers' ends (their tile tasks' summed wall seconds)."""
    area, w, r = _ab_start(a)
    for mode in a.modes.split(","):
        got: dict = {True: [], False: []}
        for k in range(a.tiles_ab):
            for balanced in ((True, False) if k % 2 == 0 else (False, True)):
                o = ours(area, w, None if balanced else (a.other_tiles or w), mode, a.out_dir)
                got[balanced].append(o)
                par = o["parallel"]
                print(f"{mode} round {k} tiles={par['tiles']}: {_vs_raw(o, r)}, driver tiles stage "
                      f"{par['seconds']['tiles']:.2f} s, workers' busy s {_worker_busy(par['tile_steps'], w)}")
                sys.stdout.flush()
        for balanced in (True, False):
            med = {k: statistics.median(f(o) for o in got[balanced]) for k, f in
                   (("wall", lambda o: o["wall"]), ("cpu", lambda o: o["tree_cpu"]),
                    ("stage", lambda o: o["parallel"]["seconds"]["tiles"]))}
            other = f"{a.other_tiles} tiles" if a.other_tiles else "one per worker"
            print(f"{mode} {'default tiles' if balanced else other}: wall / raw median "
                  f"{med['wall'] / r['seconds']:.2f}, whole CPU / raw CPU median {med['cpu'] / r['cpu_seconds']:.2f}, "
                  f"tiles stage median {med['stage']:.2f} s")
    return 0


def _vs_raw(o: dict, r: dict) -> str:
    """A command's wall and whole CPU seconds, each against the raw call's, and the load."""
    return (f"wall {o['wall']:.2f} s ({o['wall'] / r['seconds']:.2f} x raw), "
            f"whole CPU {o['tree_cpu']:.2f} s ({o['tree_cpu'] / r['cpu_seconds']:.2f} x raw CPU), "
            f"load {o['load'][0]:.1f} -> {o['load'][1]:.1f}")


def _worker_busy(steps: list, workers: int) -> str:
    """The tile tasks' wall seconds (mesh to border rows), by greedy assignment in
    submission order (largest first) to the first free worker: what each worker did."""
    task = sorted((sum(s.get(k, 0.0) for k in ("mesh", "hamiltonian", "border", "spill")) for s in steps), reverse=True)
    busy = [0.0] * workers
    for t in task:
        busy[busy.index(min(busy))] += t
    return " / ".join(f"{b:.1f}" for b in busy)


def _interleaved_ab(rounds: int, name: str, run) -> dict:
    """Fresh processes ``run(True)`` / ``run(False)`` interleaved (the order swapped every
    round); per run the seconds from the process's start to the tiles' submission, the
    driver's CPU to it, the wall time and the whole command's CPU, then the medians;
    returns the reports per arm (``{True: [...], False: [...]}``)."""
    got: dict = {True: [], False: []}
    for r in range(rounds):
        for flag in ((True, False) if r % 2 == 0 else (False, True)):
            o = run(flag)
            s, c = o["parallel"]["since_start"], o["parallel"].get("driver_cpu", {})
            got[flag].append(o)
            steps = o["parallel"].get("tile_steps") or []
            first = min((st["at"][0] for st in steps if "at" in st), default=float("nan"))
            print(f"round {r} {name}={int(flag)}: submitted {s['submitted']:.2f} s after the start "
                  f"(decomposition from {s['decompose']:.2f}; waited {o['parallel']['seconds'].get('start', 0):.2f} s "
                  f"for the cluster; driver CPU {c.get('submitted', float('nan')):.2f} s), first tile started "
                  f"{first:.2f}, tiles done {s['tiles_done']:.2f}, wall {o['wall']:.2f}, whole CPU "
                  f"{o['tree_cpu']:.2f} s, load {o['load'][0]:.1f}")
            if workers_timeline(o):
                print(f"    {workers_timeline(o)}")
            sys.stdout.flush()
    for flag in (True, False):
        sub = statistics.median(o["parallel"]["since_start"]["submitted"] for o in got[flag])
        wall = statistics.median(o["wall"] for o in got[flag])
        cpu = statistics.median(o["tree_cpu"] for o in got[flag])
        print(f"{name}={int(flag)}: submitted median {sub:.2f} s, wall median {wall:.2f}, whole CPU median {cpu:.2f}")
    return got


def imports_ab(a) -> int:
    """``--imports-ab``: the local cluster's thread started before the driver's imports
    (``command.START_BEFORE_IMPORTS``, the default since session 13) or after them
    (first size, first mode, first worker count; both run through ``cli.main`` in a
    ``python -c``, so neither ends by ``cli.fast_exit``)."""
    area = max_area_for(float(a.sizes.split(",")[0]))
    w, mode = int(a.workers.split(",")[0]), a.modes.split(",")[0]
    _interleaved_ab(a.imports_ab, "start_first",
                    lambda first: ours(area, w, a.tiles, mode, a.out_dir, start_first=first))
    return 0


def switch_ab(a) -> int:
    """``--switch-ab R --switch NAME``: interleaved fresh processes with the boolean
    ``hammesh.parallel.cluster.NAME`` on / off (e.g. ``NO_HUGEPAGE_ADVICE``; both run
    through ``cli.main`` in a ``python -c``), or ``module.NAME`` of another parallel
    module (``run.TILE_GRADE``: its default against 0, :data:`CLUSTER_SWITCH`); the
    raw call first, for the ratios."""
    area, w, r = _ab_start(a)
    mode = a.modes.split(",")[0]
    _interleaved_ab(a.switch_ab, a.switch, lambda on: ours(area, w, a.tiles, mode, a.out_dir, switch=(a.switch, on)))
    print(f"raw call: {r['seconds']:.2f} s wall, {r['cpu_seconds']:.2f} s CPU")
    return 0


def vs_ab(a) -> int:
    """``--vs-ab R --vs-python PY``: the whole command of this installation (``this=1``)
    against another's (``this=0``, e.g. ``/work/venvs/main/bin/python``: its editable
    tree), interleaved fresh processes per mode, both run as ``python -m hammesh`` (so
    both end by ``cli.fast_exit``); a raw call per round and the wall / raw ratios.

    Both installations' bytecode is cached first (:func:`cache_bytecode`): with
    ``PYTHONDONTWRITEBYTECODE`` set, the modules a branch edited compile from source in
    every process (session 19: that alone put a branch's start ~0.1 s behind main's).
    """
    if not a.vs_python:
        raise SystemExit("--vs-ab needs --vs-python PYTHON (the other installation's interpreter)")
    area, w = max_area_for(float(a.sizes.split(",")[0])), int(a.workers.split(",")[0])
    if not a.source_imports:
        print(cache_bytecode(a.out_dir, a.modes.split(",")))
        cache_bytecode(a.out_dir, a.modes.split(","), a.vs_python)
    for mode in a.modes.split(","):
        raws: list = []
        calls = [0]

        def run(this: bool, mode=mode) -> dict:
            # a raw call each round, before the first of its pair (whichever side runs
            # first: before session 20 only before this installation's, so a round that
            # began with the other's took the previous round's raw call for it)
            if calls[0] % 2 == 0:
                raws.append(raw(area))
            calls[0] += 1
            o = ours(area, w, a.tiles, mode, a.out_dir, python=None if this else a.vs_python)
            o["ratio"] = o["wall"] / raws[-1]["seconds"]
            return o

        print(f"mode {mode}: this installation (this=1) against {a.vs_python} (this=0)")
        got = _interleaved_ab(a.vs_ab, "this", run)
        ratios = {k: [o["ratio"] for o in v] for k, v in got.items()}
        print(f"  raw calls: {', '.join('%.2f' % r_['seconds'] for r_ in raws)} s wall; wall / raw (the round's "
              f"raw call): this=1 {', '.join('%.3f' % x for x in ratios[True])} (median "
              f"{statistics.median(ratios[True]):.3f}), this=0 {', '.join('%.3f' % x for x in ratios[False])} "
              f"(median {statistics.median(ratios[False]):.3f})")
    return 0


def startup_ab(a) -> int:
    """``--startup``: interleaved fresh processes, early cluster start on / off."""
    area = max_area_for(float(a.sizes.split(",")[0]))
    w, mode = int(a.workers.split(",")[0]), a.modes.split(",")[0]
    _interleaved_ab(a.startup, "early", lambda early: ours(area, w, a.tiles, mode, a.out_dir, early=early, band=True))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
