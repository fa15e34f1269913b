"""Core benchmark (issues 2 and 11): hammesh's core calls against raw Triangle, first call and best of N.

Meshes the unit square with a centred square hole (side 0.2) at ``max_area`` (default
1e-6, about 1.5 M triangles, min angle 30) and compares, as ratios against raw
``triangle.triangulate`` (same input, same switches) measured in the same run:

* ``hammesh.quality_mesh`` with its default isolation (Triangle in a child process,
  the arrays handed back through shared memory; meanwhile the parent loads the
  kernels and faults in the pages ``hamiltonian`` will take, ``hammesh.pages.reserve``);
* ``hammesh.hamiltonian`` (validation, Thm 2.4 construction and the full certificate).

Two ways, both printed:

1. **First call in a fresh process** (what a CLI user gets): each measurement runs in
   a new interpreter (``python bench_core.py --child ...``): raw Triangle's first call
   in one; ``quality_mesh`` then ``hamiltonian`` (the CLI's pipeline) in another; and
   ``hamiltonian`` on the same mesh read from an ``.npz`` file (no ``quality_mesh``
   before it, so its compiled kernels are loaded cold) in a third. Repeated
   ``--fresh`` times, alternating; every ratio is printed and the median compared.
2. **Best of ``--repeat``** in one warmed-up process (steady state).

    python benchmarks/bench_core.py [--max-area 1e-6] [--repeat 5] [--fresh 3] [--mode incircle|sparse]

**Same-run A/Bs** of sparse mode (session 10; wall times on a loaded machine mean
little, so each arm alternates with the other in one process and the report's
per-step process CPU is compared, median of ``--rounds``):

    python benchmarks/bench_core.py --ab locality [--rounds 6]       # renumbering off / on
    python benchmarks/bench_core.py --ab output-threads [--rounds 6] # walk + gather: 1 / 2 threads

``locality`` calls ``hamiltonian`` with ``sparse.LOCAL_MIN_TRIANGLES`` above the mesh
(off) and at its default (on); the cover's step CPU holds the certificate's look at
the input and the page reserve, made beside it on the other thread (both arms alike).
``output-threads`` calls ``hamiltonian`` with the walk from both ends, the gather and
the pinned edges on two threads (default) or on one, and prints each phase's critical
path (the busiest thread's ``time.thread_time`` in its compiled calls).

**Critical path of a first call** (session 14; a figure the load on a shared machine
moves little, where wall times mean nothing):

    python benchmarks/bench_core.py --mode sparse --critical 5

``--critical N`` runs N fresh ``quality_mesh`` + ``hamiltonian`` first calls and prints,
per step, the main thread's CPU outside the threaded passes plus each pass's largest
call's thread CPU (``hammesh.threads.run_all``), plus the time the main thread waits on
the cover swap tests' other thread beyond its own share (``sparse._SwapTests``): about
what the call's wall time is on two free cores. Compare two trees by running it in
each, alternating. Beside it (session 17) each sparse step's process CPU (the report's
``step_cpu_seconds``) and ``idle`` = 2 x critical - CPU: the other core's idle time in
that step on two free cores (negative: more than two threads' work, e.g. the
certificate's look at the input beside the improvement).

**Thin strips** (session 16; one triangle wide, the dual a path, every triangle
uncovered): sparse against incircle, process CPU per size, in one process:

    python benchmarks/bench_core.py --thin 25 50 100 200

The children inherit the environment: ``NUMPY_MADVISE_HUGEPAGE=0 python
benchmarks/bench_core.py`` measures without numpy's transparent-huge-page advice.

Targets (issues 2 and 11): hamiltonian / Triangle <= 0.30 (first call and best of N);
quality_mesh (isolated) / Triangle <= 1.10 on the first call; <= 1 GiB extra peak memory.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

HOLE = [[[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]]]
SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]


def _peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _cpu(who: int = resource.RUSAGE_SELF) -> float:
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def _sys(who: int = resource.RUSAGE_SELF) -> float:
    """System CPU seconds (page faults on fresh memory are most of it, docs/benchmarks.md)."""
    return resource.getrusage(who).ru_stime


def _domain():
    import hammesh

    return hammesh.Domain.from_polygon(SQUARE, holes=HOLE)


def _raw_triangle_input(dom, min_angle: float, max_area: float) -> tuple[dict, str]:
    """What ``quality_mesh`` hands Triangle, built without hammesh's wrapper."""
    from hammesh.meshing import MeshOptions, triangle_switches

    data = {
        "vertices": np.array(dom.vertices, dtype=np.float64),
        "segments": np.array(dom.segments, dtype=np.int32),
        "segment_markers": np.array(dom.segment_markers, dtype=np.int32)[:, None],
        "holes": np.array(dom.holes, dtype=np.float64),
    }
    return data, triangle_switches(dom, MeshOptions(min_angle=min_angle, max_area=max_area))


def child(what: str, min_angle: float, max_area: float, path: str, mode: str = "incircle",
          cross_angles: int | None = None, local_min: int | None = None) -> dict:
    """One first-call measurement in this (fresh) interpreter."""
    import hammesh

    if local_min is not None:  # (sparse mode renumbers its input from this many triangles)
        from hammesh.postprocess import sparse

        sparse.LOCAL_MIN_TRIANGLES = local_min

    if cross_angles is not None:  # (the incircle forest's quadtree rotations tried: 1 = none)
        from hammesh.postprocess import _thm24_kernels

        _thm24_kernels.CROSS_ANGLES = cross_angles

    dom = _domain()
    if what == "triangle":
        import triangle

        data, switches = _raw_triangle_input(dom, min_angle, max_area)
        t, c = time.perf_counter(), _cpu()
        out = triangle.triangulate(data, switches)
        return {"triangle": time.perf_counter() - t, "triangle_cpu": _cpu() - c, "triangles": len(out["triangles"])}
    if what == "pipeline":  # the CLI's: quality_mesh (isolated), then hamiltonian
        import triangle

        # resolved before the clock starts, as Triangle's peer imports ``triangle``
        # before its clock: the import of hammesh.meshing is printed on its own
        t = time.perf_counter()
        quality_mesh = hammesh.quality_mesh
        t_import = time.perf_counter() - t
        # Triangle's own time inside the isolated call (the forked child inherits this
        # wrapper and writes the time to a file of this process's own, never beside
        # ``path``, which may be empty): the peer measured in the same process
        fd, inside = tempfile.mkstemp(prefix="bench_core-", suffix=".triangle")
        os.close(fd)
        try:
            return _pipeline(dom, quality_mesh, min_angle, max_area, path, mode, inside, t_import)
        finally:
            os.unlink(inside)
    if what == "critical":
        return _critical_child(dom, min_angle, max_area, mode)
    if what == "file":  # hamiltonian on a mesh read from a file: kernels loaded cold
        with np.load(path) as f:
            mesh = hammesh.Mesh(**{k: f[k] for k in f.files})
        t = time.perf_counter()
        h = hammesh.hamiltonian(mesh, mode=mode)
        return {"hamiltonian_cold": time.perf_counter() - t, "verified": bool(h.report["verified"])}
    raise ValueError(what)


def _pipeline(dom, quality_mesh, min_angle: float, max_area: float, path: str, mode: str, inside: str,
              t_import: float) -> dict:
    """The ``pipeline`` child's measurement (``inside``: the file Triangle's time goes to)."""
    import triangle

    import hammesh

    real, parent = triangle.triangulate, os.getpid()

    def timed(*a, **k):
        t = time.perf_counter()
        out = real(*a, **k)
        if os.getpid() != parent:  # the child's call only (the parent's thread that
            with open(inside, "w") as f:  # loads the kernels meshes a tiny square)
                f.write(repr(time.perf_counter() - t))
        return out

    triangle.triangulate = timed
    t, c, cc = time.perf_counter(), _cpu(), _cpu(resource.RUSAGE_CHILDREN)
    mesh = quality_mesh(dom, min_angle=min_angle, max_area=max_area)
    t_mesh = time.perf_counter() - t
    c_mesh = _cpu() - c
    for th in threading.enumerate():  # (untimed) the child reaped, the kernels loaded
        if th.name in ("hammesh-reap", "hammesh-meanwhile"):
            th.join()
    c_mesh += _cpu(resource.RUSAGE_CHILDREN) - cc
    from hammesh import pages

    reserve = pages.reserved()  # faulted in by quality_mesh while Triangle ran
    triangle.triangulate = real
    with open(inside) as f:
        t_inside = float(f.read())
    t, c, k = time.perf_counter(), _cpu(), _sys()
    h = hammesh.hamiltonian(mesh, mode=mode)
    t_ham, c_ham, k_ham = time.perf_counter() - t, _cpu() - c, _sys() - k
    if path:  # for the "file" run: the same mesh, saved
        np.savez(path, points=mesh.points, triangles=mesh.triangles, neighbors=mesh.neighbors,
                 segments=mesh.segments, segment_markers=mesh.segment_markers)
    return {"quality_mesh": t_mesh, "hamiltonian": t_ham, "triangle_inside": t_inside,
            "quality_mesh_cpu": c_mesh, "hamiltonian_cpu": c_ham, "hamiltonian_sys": k_ham,
            "triangles": mesh.n_triangles, "reserve_mib": reserve / 2**20,
            "verified": bool(h.report["verified"]), "import_meshing": t_import}


def _critical_child(dom, min_angle: float, max_area: float, mode: str) -> dict:
    """``--critical``'s measurement of one first call (see the module's docstring)."""
    import hammesh
    from hammesh import threads
    from hammesh.postprocess import sparse

    mesh = hammesh.quality_mesh(dom, min_angle=min_angle, max_area=max_area)
    for th in threading.enumerate():  # (untimed) the child reaped, the kernels loaded
        if th.name in ("hammesh-reap", "hammesh-meanwhile"):
            th.join()
    real, caller = threads.run_all, threading.get_ident()
    acc = {"inside": 0.0, "largest": 0.0}

    def run_all(calls):
        if threading.get_ident() != caller:
            return real(calls)
        cpu = [0.0] * len(calls)

        def timed(i, c):
            def call():
                t = time.thread_time()
                out = c()
                cpu[i] = time.thread_time() - t
                return out
            return call

        t = time.thread_time()
        out = real([timed(i, c) for i, c in enumerate(calls)])
        acc["inside"] += time.thread_time() - t
        acc["largest"] += max(cpu)
        return out

    for name, module in list(sys.modules.items()):
        if name.startswith("hammesh") and getattr(module, "run_all", None) is real:
            module.run_all = run_all
    tests: list = []
    swap = getattr(sparse, "_SwapTests", None)
    if swap is not None:  # (the caller's CPU per task and the other thread's)
        init, run, stop = swap.__init__, swap._run, swap.stop

        def s_init(self, *a, **k):
            self.bench = [time.thread_time(), None, 0.0]
            tests.append(self)
            init(self, *a, **k)

        def s_run(self):
            t = time.thread_time()
            run(self)
            self.bench[2] = time.thread_time() - t

        def s_stop(self):
            if self.bench[1] is None:
                self.bench[1] = time.thread_time() - self.bench[0]
            stop(self)

        swap.__init__, swap._run, swap.stop = s_init, s_run, s_stop

    def waited() -> float:
        return sum(max(0.0, x.bench[2] - (x.bench[1] or 0.0)) for x in tests)

    marks = []

    def mark(name: str) -> None:
        marks.append((name, time.thread_time() - acc["inside"] + acc["largest"] + waited()))

    done = sparse._Steps.done

    def step_done(self, name):
        mark(name)
        return done(self, name)

    sparse._Steps.done = step_done
    post = sys.modules["hammesh.postprocess"]
    certify, build = post.certify, post.sparse_hamiltonian

    def timed_certify(*a, **k):
        mark("mapping back, the mesh")
        out = certify(*a, **k)
        mark("certificate")
        return out

    def timed_build(*a, **k):
        mark("validation")
        return build(*a, **k)

    post.certify, post.sparse_hamiltonian = timed_certify, timed_build
    t, c = time.perf_counter(), _cpu()
    mark("<start>")
    h = hammesh.hamiltonian(mesh, mode=mode)
    mark("<end>")
    t, c = time.perf_counter() - t, _cpu() - c
    steps = {b[0]: b[1] - a[1] for a, b in zip(marks, marks[1:]) if b[0] != "<end>"}
    return {"wall": t, "cpu": c, "critical": marks[-1][1] - marks[0][1], "steps": steps,
            "step_cpu": dict(h.report.get("step_cpu_seconds", {})),
            "verified": bool(h.report["verified"]), "load": os.getloadavg()[0]}


def critical_paths(args: argparse.Namespace) -> None:
    """``--critical``: fresh first calls, the critical-path estimate per step."""
    runs = []
    for _ in range(args.critical):
        r = _fresh("critical", args)
        assert r["verified"]
        runs.append(r)
        print(f"  critical path {r['critical']:.3f} s, wall {r['wall']:.3f} s, CPU {r['cpu']:.3f} s, "
              f"load {r['load']:.1f}", flush=True)
    print(f"first call, mode={args.mode}: critical-path estimate per step, median of {len(runs)} (CPU s); "
          f"the step's process CPU (sparse steps) and the other core's idle time there (2 x critical - CPU)")
    for k in runs[0]["steps"]:
        crit = statistics.median(r["steps"].get(k, 0.0) for r in runs)
        line = f"  {k:<26}{crit:8.3f}"
        # (input_angles' critical path holds the renumbering, whose CPU the report counts
        # with the mapping back under "locality": no CPU column there)
        if k != "input_angles" and all(k in r.get("step_cpu", {}) for r in runs):
            cpu = statistics.median(r["step_cpu"][k] for r in runs)
            idle = statistics.median(2 * r["steps"].get(k, 0.0) - r["step_cpu"][k] for r in runs)
            line += f"   CPU {cpu:6.3f}  idle {idle:6.3f}"
        print(line)
    for k in ("critical", "wall", "cpu"):
        v = [r[k] for r in runs]
        print(f"  {'whole call: ' + k:<26}{statistics.median(v):8.3f}  ({min(v):.3f}-{max(v):.3f})")


def _fresh(what: str, args: argparse.Namespace, path: str = "") -> dict:
    cmd = [sys.executable, os.path.abspath(__file__), "--child", what, "--max-area", repr(args.max_area),
           "--min-angle", repr(args.min_angle), "--path", path, "--mode", args.mode]
    if args.cross_angles is not None:
        cmd += ["--cross-angles", str(args.cross_angles)]
    if args.local_min is not None:
        cmd += ["--local-min", str(args.local_min)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def first_calls(args: argparse.Namespace) -> None:
    rows, cpus, imports = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "mesh.npz")
        for i in range(args.fresh):
            # alternate the order so that a load change hits both sides alike
            if i % 2 == 0:
                tri = _fresh("triangle", args)
                pipe = _fresh("pipeline", args, path)
            else:
                pipe = _fresh("pipeline", args, path)
                tri = _fresh("triangle", args)
            cold = _fresh("file", args, path)
            assert pipe["verified"] and cold["verified"] and pipe["triangles"] == tri["triangles"]
            rows.append((tri["triangle"], pipe["quality_mesh"], pipe["hamiltonian"], cold["hamiltonian_cold"],
                         pipe["triangle_inside"]))
            imports.append(pipe["import_meshing"])
            cpus.append((tri["triangle_cpu"], pipe["quality_mesh_cpu"], pipe["hamiltonian_cpu"], pipe["hamiltonian_sys"],
                         pipe["reserve_mib"]))
    hp = os.environ.get("NUMPY_MADVISE_HUGEPAGE", "numpy's default")
    print(f"first call in a fresh process, mode={args.mode}, NUMPY_MADVISE_HUGEPAGE={hp}, {args.fresh} runs")
    print("(each a new interpreter; seconds, and ratios to raw Triangle's first call")
    print("in its own fresh process; in brackets: to Triangle's time inside that quality_mesh call, same process)")
    print(f"  {'run':>3}  {'triangle':>8}  {'quality_mesh':>12} {'ratio':>15}  {'hamiltonian':>11} {'ratio':>15}  {'ham. cold':>9} {'ratio':>6}")
    for i, (t, q, h, c, ti) in enumerate(rows):
        print(f"  {i:>3}  {t:8.3f}  {q:12.3f} {q / t:6.3f} [{q / ti:6.3f}]  {h:11.3f} {h / t:6.3f} [{h / ti:6.3f}]  {c:9.3f} {c / t:6.3f}")

    def summary(label: str, k: int, peer: int, target: str) -> None:
        r = [row[k] / row[peer] for row in rows]
        print(f"  {label:68s} {statistics.median(r):6.3f}  (runs {min(r):.3f}-{max(r):.3f}){target}")

    print("first-call ratios (median of the runs)")
    summary("quality_mesh (isolated) / raw Triangle, own process", 1, 0, "; target <= 1.10")
    summary("quality_mesh (isolated) / Triangle inside it", 1, 4, "")
    summary("hamiltonian after quality_mesh / raw Triangle, own process", 2, 0,
            f"; target <= {TARGETS[args.mode]} (issue {TARGET_ISSUES[args.mode]})")
    summary("hamiltonian after quality_mesh / Triangle inside quality_mesh", 2, 4, "")
    summary("hamiltonian on a mesh read from a file (kernels cold) / raw Triangle", 3, 0, "")
    print(f"  (import of hammesh.meshing before quality_mesh's clock, as the peer imports triangle before its own:"
          f" {min(imports):.3f}-{max(imports):.3f} s)")
    print("first-call CPU seconds (all threads, and the meshing child): triangle / quality_mesh / hamiltonian"
          " (of it system time); the page reserve quality_mesh faulted in while Triangle ran (hammesh.pages)")
    for i, (t, q, h, k, r) in enumerate(cpus):
        print(f"  {i:>3}  {t:8.3f}  {q:8.3f} ({q / t:.3f})  {h:8.3f} ({h / t:.3f}; system {k:.3f})  reserve {r:.0f} MiB")


def best_of(args: argparse.Namespace) -> None:
    import triangle

    import hammesh

    # warm the kernels on a small mesh so that the timing below is steady-state
    from hammesh.postprocess import load_kernels

    load_kernels()
    dom = _domain()
    data, switches = _raw_triangle_input(dom, args.min_angle, args.max_area)
    rss0 = _peak_rss_mib()
    t_tri, t_iso = [], []
    mesh = None
    for _ in range(args.repeat):  # interleaved: a load change hits both alike
        t = time.perf_counter()
        triangle.triangulate(data, switches)
        t_tri.append(time.perf_counter() - t)
        t = time.perf_counter()
        mesh = hammesh.quality_mesh(dom, min_angle=args.min_angle, max_area=args.max_area)
        t_iso.append(time.perf_counter() - t)
    rss1 = _peak_rss_mib()
    t_hams = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        h = hammesh.hamiltonian(mesh, mode=args.mode)
        t_hams.append(time.perf_counter() - t0)
        if len(t_hams) == 1:
            rss2 = _peak_rss_mib()
    t_mesh, t_ham, t_qm = min(t_tri), min(t_hams), min(t_iso)
    rep = h.report
    print(f"best of {args.repeat} in one process (after hammesh.postprocess.load_kernels())")
    print(f"input triangles        {mesh.n_triangles:>12,d}")
    print(f"output triangles       {h.n_triangles:>12,d}  (cycles: {len(h.components)})")
    print("all runs               triangle " + " ".join(f"{t:.2f}" for t in t_tri)
          + " | quality_mesh " + " ".join(f"{t:.2f}" for t in t_iso)
          + " | ours " + " ".join(f"{t:.2f}" for t in t_hams))
    print(f"triangle meshing       {t_mesh:12.3f} s   (peer: raw triangle.triangulate)")
    print(f"quality_mesh isolated  {t_qm:12.3f} s   (ratio {t_qm / t_mesh:.3f}; target <= 1.10)")
    print(f"hamiltonian + verify   {t_ham:12.3f} s   (build {rep['seconds']['hamiltonian']:.3f} s, verify {rep['seconds']['verify']:.3f} s)")
    print(f"ratio ours / triangle  {t_ham / t_mesh:12.3f}     (target <= {TARGETS[args.mode]})")
    print(f"peak RSS after meshing {rss1:12.0f} MiB (+{rss1 - rss0:.0f})")
    print(f"extra peak for ours    {rss2 - rss1:12.0f} MiB   (target <= 1024)")
    print(f"min angle in / out     {rep['min_angle_input_deg']:.3f} / {rep['min_angle_output_deg']:.3f} deg")


def same_run_ab(args: argparse.Namespace) -> None:
    """``--ab``: two arms alternating in this process, per-step process CPU medians."""
    import hammesh
    from hammesh.postprocess import _improve_kernels, _sparse_kernels, load_kernels, sparse

    load_kernels("sparse")
    mesh = hammesh.quality_mesh(_domain(), min_angle=args.min_angle, max_area=args.max_area, isolate=False)
    if args.ab == "locality":
        default = sparse.LOCAL_MIN_TRIANGLES

        def arm(on: bool):
            sparse.LOCAL_MIN_TRIANGLES = default if on else 1 << 62
            try:
                return hammesh.hamiltonian(mesh)
            finally:
                sparse.LOCAL_MIN_TRIANGLES = default

        names = ("input order", "renumbered")
    else:
        orig = (_sparse_kernels.WALK_TWO_ENDS_MIN_ROWS, _sparse_kernels.row_ranges, _improve_kernels.row_ranges)
        # the critical path: each compiled call of the walk, the gather and the pinned
        # edges timed in the thread that runs it (time.thread_time), per phase the
        # busiest thread's sum (the one-thread walk calls _walk_all, the two-ended one
        # _walk_one_into and _walk_rest from Python)
        spent: dict = {}
        phases = [(_sparse_kernels, n, "walk") for n in ("_walk_all", "_walk_one_into", "_walk_rest")]
        phases += [(_sparse_kernels, n, "gather") for n in ("_runs_in_order_into", "_row_positions_into",
                                                             "_gather_rows_into")]
        phases += [(_improve_kernels, "_pinned_output_edges_into", "pinned")]
        for mod, name, phase in phases:
            def timed(*a, _real=getattr(mod, name), _phase=phase):
                c = time.thread_time()
                out = _real(*a)
                key = (_phase, threading.get_ident())
                spent[key] = spent.get(key, 0.0) + time.thread_time() - c
                return out

            setattr(mod, name, timed)

        def arm(two: bool):
            if two:
                _sparse_kernels.WALK_TWO_ENDS_MIN_ROWS, _sparse_kernels.row_ranges, _improve_kernels.row_ranges = orig
            else:
                one = lambda m, _: [(0, m)]  # noqa: E731
                _sparse_kernels.WALK_TWO_ENDS_MIN_ROWS, _sparse_kernels.row_ranges, _improve_kernels.row_ranges = (
                    1 << 62, one, one)
            spent.clear()
            try:
                return hammesh.hamiltonian(mesh)
            finally:
                (_sparse_kernels.WALK_TWO_ENDS_MIN_ROWS, _sparse_kernels.row_ranges,
                 _improve_kernels.row_ranges) = orig

        names = ("one thread", "two threads")
    rows: dict[bool, list[dict]] = {False: [], True: []}
    for i in range(args.rounds):
        for on in ((False, True) if i % 2 == 0 else (True, False)):
            t, c = time.perf_counter(), time.process_time()
            h = arm(on)
            r = h.report
            row = {f"{k} (CPU)": v for k, v in r["step_cpu_seconds"].items()}
            sec = r["seconds"]
            row["validation etc. (wall)"] = sec["hamiltonian"] - sum(r["step_seconds"].values())
            row["certificate (wall)"] = sec["verify"]
            row.update({f"{k} (wall)": r["step_seconds"][k] for k in ("output_rows", "improve") if k in r["step_seconds"]})
            row["whole call (wall)"], row["whole call (CPU)"] = time.perf_counter() - t, time.process_time() - c
            if args.ab == "output-threads":
                for phase in ("walk", "gather", "pinned"):
                    mine = [v for (ph, _), v in spent.items() if ph == phase]
                    row[f"{phase}: critical path"] = max(mine, default=0.0)
                row["3 phases: all threads"] = sum(spent.values())
            rows[on].append(row)
            print(f"  {names[on]:>12}: {row['whole call (wall)']:.3f} s wall, {row['whole call (CPU)']:.3f} s CPU, "
                  f"{r['steiner_points']} Steiner points, load {os.getloadavg()[0]:.1f}", flush=True)
    keys = list(dict.fromkeys(k for arm_rows in rows.values() for row in arm_rows for k in row))
    print(f"{mesh.n_triangles:,} triangles, median of {args.rounds} rounds (s)")
    print(f"  {'step':<28}{names[0]:>14}{names[1]:>14}")
    for k in keys:
        print(f"  {k:<28}" + "".join(f"{statistics.median(r.get(k, 0.0) for r in rows[on]):>14.3f}" for on in (False, True)))


def thin_strips(args: argparse.Namespace) -> None:
    """``--thin``: one-triangle-wide strips (L x 0.01, q30; session 16): sparse against
    incircle, process CPU in one process (kernels loaded by a first call), per size."""
    import hammesh

    def cpu_of(f) -> float:
        c = _cpu()
        f()
        return _cpu() - c

    print("thin strips L x 0.01, min angle 30: process CPU s (best of 2), sparse / incircle, steps over 0.01 s")
    for length in args.thin:
        dom = hammesh.Domain.from_polygon([[0, 0], [length, 0], [length, 0.01], [0, 0.01]])
        mesh = hammesh.quality_mesh(dom, min_angle=args.min_angle, isolate=False)
        hammesh.hamiltonian(mesh)  # (kernels loaded)
        h = []
        sp = min(cpu_of(lambda: h.append(hammesh.hamiltonian(mesh))) for _ in range(2))
        inc = min(cpu_of(lambda: hammesh.hamiltonian(mesh, mode="incircle")) for _ in range(2))
        r = h[-1].report
        steps = ", ".join(f"{k} {v:.3f}" for k, v in r["step_cpu_seconds"].items() if v > 0.01)
        print(f"  L {length:>6g}: {mesh.n_triangles:>7,} triangles  sparse {sp:.3f}  incircle {inc:.3f}  "
              f"ratio {sp / max(inc, 1e-9):6.1f}  {1e3 * sp / mesh.n_triangles:.3f} ms/triangle  "
              f"Steiner/triangle {r['steiner_per_input_triangle']:.3f}  ({steps})")


#: hamiltonian() / raw Triangle targets by mode: incircle issues 2 and 11, sparse issue 13
TARGETS = {"incircle": 0.30, "sparse": 0.5}
TARGET_ISSUES = {"incircle": "2, 11", "sparse": "13"}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-area", type=float, default=1e-6)
    ap.add_argument("--min-angle", type=float, default=30.0)
    ap.add_argument("--repeat", type=int, default=5, help="runs of each step in one process; the best is compared")
    ap.add_argument("--fresh", type=int, default=3, help="fresh-process first-call runs (0: skip)")
    ap.add_argument("--mode", default="incircle", choices=["incircle", "sparse"],
                    help="hamiltonian() mode; incircle (Thm 2.4) is what the issue-2/11 targets are about, "
                    "sparse (the default of hamiltonian()) is measured by bench_sparse.py")
    ap.add_argument("--cross-angles", type=int, help="first calls: the incircle forest tries this many quadtree "
                    "rotations (_thm24_kernels.CROSS_ANGLES; 1: none, the A/B of session 10)")
    ap.add_argument("--local-min", type=int, help="first calls: sparse.LOCAL_MIN_TRIANGLES (a huge value: no "
                    "renumbering, the A/B of session 10)")
    ap.add_argument("--ab", choices=["locality", "output-threads"], help="a same-run A/B of sparse mode (see above)")
    ap.add_argument("--rounds", type=int, default=6, help="--ab: rounds, each arm once a round")
    ap.add_argument("--critical", type=int, default=0,
                    help="fresh first calls measured by the critical-path estimate (see above)")
    ap.add_argument("--thin", type=float, nargs="+",
                    help="one-triangle-wide strips of these lengths (x 0.01): sparse / incircle CPU (session 16)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--path", default="", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.child, args.min_angle, args.max_area, args.path, args.mode, args.cross_angles,
                                     args.local_min)))
        return 0

    if args.ab:
        same_run_ab(args)
        return 0
    if args.critical:
        critical_paths(args)
        return 0
    if args.thin:
        thin_strips(args)
        return 0
    # numba cold start: compile (or load the cache) in a fresh interpreter, measured
    cold = time.perf_counter()
    subprocess.run([sys.executable, "-c", f"from hammesh.postprocess import load_kernels; load_kernels({args.mode!r})"], check=True)
    cold = time.perf_counter() - cold
    print(f"numba cold start (fresh interpreter: import + the kernels of hamiltonian() on a tiny mesh) {cold:.2f} s")
    if args.fresh > 0:
        first_calls(args)
    if args.repeat > 0:
        best_of(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
