"""The parallel command's start: what the driver imports and when the cluster starts."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import hammesh
from hammesh.cli import main

DEMO = "hammesh/data/demo.poly"


def test_building_the_command_imports_neither_dask_nor_scipy_sparse():
    """``hammesh mesh``'s options and the parallel path's modules load without Dask
    (a local cluster imports it in its own thread) and without scipy.sparse (only
    ``--renumber rcm`` needs it): both were on the command's serial start."""
    code = ("import sys; from hammesh.cli import build_parser; import hammesh.parallel.command, hammesh.numbering; "
            "build_parser(); "
            "print(sorted(m for m in ('dask', 'distributed', 'scipy.sparse') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_rcm_numbering_still_works_without_the_module_level_import():
    from hammesh.numbering import bandwidth_profile, renumber

    h = hammesh.hamiltonian(hammesh.quality_mesh(hammesh.read_domain(DEMO), min_angle=30, max_area=5e-3))
    r, _ = renumber(h, "rcm")
    assert np.array_equal(np.sort(r.points, axis=0), np.sort(h.points, axis=0))  # the same points, renamed
    assert bandwidth_profile(r.triangles, len(r.points))[0] < bandwidth_profile(h.triangles, len(h.points))[0]


def test_outcome_size_is_registered_by_the_task_where_dask_runs():
    """The task registers the outcome's size with Dask in its own process (a worker
    imports Dask before any task), so Dask's ``sizeof`` counts the meshes held."""
    sizeof = pytest.importorskip("dask.sizeof").sizeof
    from hammesh.parallel.run import _outcome_nbytes, tile_task
    from hammesh.parallel.tiles import decompose

    d = decompose(hammesh.read_domain(DEMO), min_angle=30, max_area=4e-3, n_tiles=2)
    out = tile_task(d.tiles[0], d.n_input, 30, 4e-3, "sparse", 0.9)
    assert sizeof(out) == _outcome_nbytes(out) > out.ham.triangles.nbytes


@pytest.mark.slow
@pytest.mark.parametrize("partitioned", [True, False])
def test_early_cluster_start_runs_and_reports_the_driver_timeline(tmp_path, capsys, partitioned, run_cli):
    """``--workers``: the cluster starts before the domain is read; the output is the
    same checked mesh, and the report's timeline is in order. (In a fresh process, as
    the command runs: forking workers from a pytest-xdist worker once hung.)"""
    pytest.importorskip("distributed")
    out = tmp_path / ("parts" if partitioned else "o.vtu")
    rep = tmp_path / "r.json"
    argv = ["mesh", DEMO, "-q", "30", "-a", "2e-3", "--workers", "2", "-o", str(out), "--report", str(rep)]
    rc, _, err, left = run_cli(argv + (["--partitioned"] if partitioned else []))
    assert rc == 0 and err == "", err
    assert left == []  # no thread of the cluster's start outlives the command
    par = json.loads(rep.read_text())["parallel"]
    s, c = par["since_start"], par["driver_cpu"]
    assert 0 < s["decompose"] <= s["submitted"] <= s["tiles_done"]
    assert 0 < c["decompose"] <= c["submitted"] <= c["tiles_done"] <= c["end"]  # (the driver's CPU seconds)
    if partitioned:
        assert s["tiles_done"] <= s["end"]
    assert main(["check", str(out / "mesh.pvtu" if partitioned else out)]) == 0


@pytest.mark.slow
def test_bad_domain_with_an_early_cluster_exits_2_and_closes_it(tmp_path, run_cli):
    """A domain that cannot be read, found while the cluster starts: one line, exit 2,
    the cluster closed (no thread of its start left)."""
    pytest.importorskip("distributed")
    bad = tmp_path / "bad.poly"
    bad.write_text("3 2 0 0\n1 0 0\n2 1 0\n")  # promises 3 vertices, gives 2
    rc, _, err, left = run_cli(["mesh", str(bad), "-q", "30", "-a", "1e-2", "--workers", "1", "--partitioned",
                                "-o", str(tmp_path / "o")])
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "bad.poly" in err
    assert not (tmp_path / "o").exists()
    assert left == []


#: a fresh driver starts a one-worker local cluster and asks the worker which of the
#: lattice's kernels it holds compiled (before any tile ran there) and whether numpy
#: still advised huge pages there (switching the advice off answers its former state)
FORKED_WORKER = """
import json
from hammesh.parallel.cluster import runner_for, start_method

def held():
    from hammesh.parallel import _kernels as k
    from hammesh.parallel.cluster import no_hugepage_advice
    names = ("lattice_mark_inside_into", "lattice_clear_near_segments_into", "lattice_triangles_into",
             "lattice_mesh_into", "label_pieces_into")
    return {"kernels": {n: len(getattr(k, n).signatures) for n in names}, "advice_was_on": no_hugepage_advice()}

if __name__ == "__main__":
    from hammesh.parallel.cluster import no_hugepage_advice
    with runner_for(workers=1, mode="incircle") as (c, _):
        worker = list(c.run(held).values())[0]
    print(json.dumps({"method": start_method(), "driver_advice_was_on": no_hugepage_advice(), **worker}))
"""


@pytest.fixture(scope="module")
def forked_worker(tmp_path_factory):
    pytest.importorskip("distributed")
    script = tmp_path_factory.mktemp("forked") / "held.py"
    script.write_text(FORKED_WORKER)
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    if got["method"] != "fork":
        pytest.skip("spawned workers (not Linux) import and load everything themselves")
    return got


def test_forked_workers_start_with_the_lattice_kernels_loaded(forked_worker):
    """The driver loads the tile mesh's kernels before the fork (``load_tile_kernels``):
    each worker used to load them (~0.25 s CPU) or, with a stale cache, compile them
    inside its first tile's measured mesh step."""
    held = forked_worker["kernels"]
    assert held and all(v >= 1 for v in held.values()), held


def test_workers_do_not_advise_huge_pages_but_the_driver_still_does(forked_worker):
    """``worker_setup`` switches numpy's huge page advice off in the workers only
    (their fresh arrays' first touches cost 2-3x the system time with it here); the
    driver's process keeps numpy's default."""
    default = subprocess.run([sys.executable, "-c", "from hammesh.parallel.cluster import no_hugepage_advice as f; "
                              "print(f())"], capture_output=True, text=True, check=True).stdout.strip()
    assert forked_worker["advice_was_on"] is False
    assert str(forked_worker["driver_advice_was_on"]) == default  # (numpy's default: on for Linux >= 4.6)


def test_the_cluster_module_imports_no_library_module():
    """``--workers`` starts its cluster right after the options are checked: importing
    :mod:`hammesh.parallel.cluster` (and the package) loads neither numba nor the
    parallel path's other modules (the package's names are imported on first use)."""
    code = ("import sys; import hammesh.parallel.cluster; import hammesh.parallel as p; "
            "print(sorted(m for m in ('numba', 'scipy', 'hammesh.domain', 'hammesh.parallel.run', "
            "'hammesh.parallel.tiles', 'dask') if m in sys.modules), p.decompose.__module__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["[]", "hammesh.parallel.tiles"]


def test_driver_steps_after_its_imports_import_only_numba_under_its_lock(tmp_path):
    """After :func:`~hammesh.parallel.command.import_driver_modules` (the cluster may
    fork from then on), reading the domain, checking the outputs, estimating and
    decomposing import no module but numba's own (loaded by its first kernel under its
    compiler lock, which the fork holds): a fork in the middle of another import
    would leave that module half made and locked in the workers."""
    code = f"""
import sys
from pathlib import Path
from hammesh.parallel.command import import_driver_modules
import_driver_modules()
before = set(sys.modules)
from hammesh.cli.pipeline import Outputs, load_input
from hammesh.parallel.partitioned import check_target, spill_wanted
from hammesh.parallel.run import LocalRunner, decompose_estimate, default_tiles, since_start
from hammesh.parallel.tiles import decompose
from hammesh.io import write_report
Outputs(report=Path({str(tmp_path / 'r.json')!r}), inputs=(Path({DEMO!r}),)).check()
check_target(Path({str(tmp_path / 'out')!r}), inputs=(Path({DEMO!r}),))
d = load_input(Path({DEMO!r}))
est = decompose_estimate(d, 30, 1e-4)
n = default_tiles(est, 2)
spill_wanted(LocalRunner(), 2, n, est)
since_start()
decompose(d, min_angle=30, max_area=1e-4, n_tiles=n)
print(sorted(m for m in set(sys.modules) - before if m.split('.')[0] != 'numba'))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] in ("[]", "['cmath']"), out.stdout  # (cmath: numba's, same lock)


def test_since_start_is_the_process_age():
    """The report's timeline counts from the process's start (``/proc``): a fresh
    process's start found from it lies between the parent's launch and its reply
    (psutil's ``create_time`` was 0.9 s off on this VM)."""
    import time

    t0 = time.time()
    out = subprocess.run([sys.executable, "-c", "import time; from hammesh.parallel.run import since_start; "
                          "print(repr(time.time() - since_start()))"], capture_output=True, text=True, check=True)
    t1 = time.time()
    started = float(out.stdout.strip())
    assert t0 - 0.05 <= started <= t1  # (the start is known to 10 ms: one clock tick)


READY_GATE = """
import json, sys, threading, time
import psutil
from hammesh.parallel.cluster import runner_for

ready = threading.Event()
with runner_for(workers=1, background=True, ready=ready) as (runner, n):
    time.sleep(float(sys.argv[1]))
    before = len(psutil.Process().children(recursive=True))
    ready.set()
    after = len(runner.scheduler_info()["workers"])
print(json.dumps({"children_before_ready": before, "workers_after": after,
                  "left": [t.name for t in threading.enumerate() if t.name.startswith("hammesh-cluster")]}))
"""


@pytest.mark.slow
def test_the_local_cluster_forks_only_once_the_driver_is_ready(tmp_path):
    """``runner_for(background=True, ready=event)`` imports Dask and then waits: no
    worker process exists before the event is set (the driver imports meanwhile), and
    the cluster is up once it is."""
    pytest.importorskip("distributed")
    script = tmp_path / "gate.py"
    script.write_text(READY_GATE)
    out = subprocess.run([sys.executable, str(script), "3"], capture_output=True, text=True, timeout=600,
                         check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got == {"children_before_ready": 0, "workers_after": 1, "left": []}, got


@pytest.mark.slow
def test_a_failure_before_ready_does_not_leave_the_start_waiting():
    """The caller's error before it sets ``ready``: leaving ``runner_for`` sets it, the
    start goes on and the cluster is closed (no thread left, no hang)."""
    pytest.importorskip("distributed")
    code = ("import json, threading; from hammesh.parallel.cluster import runner_for\n"
            "ready = threading.Event()\n"
            "try:\n"
            "    with runner_for(workers=1, background=True, ready=ready):\n"
            "        raise KeyError('before ready')\n"
            "except KeyError:\n"
            "    pass\n"
            "print(json.dumps([ready.is_set(), [t.name for t in threading.enumerate() "
            "if t.name.startswith('hammesh-cluster')]]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [True, []]


@pytest.mark.slow
def test_the_parallel_command_ends_its_process_fast_and_whole(tmp_path):
    """``python -m hammesh mesh ... --workers 2 --partitioned`` (the command as the
    process's entry: it ends by ``cli.fast_exit``): exit 0, every line on a piped
    stdout, the report and the checked index in place, and no process of the run left
    (forked workers carry the command line, hence the output's path)."""
    pytest.importorskip("distributed")
    import psutil

    out, rep = tmp_path / "fast_out", tmp_path / "r.json"
    p = subprocess.run([sys.executable, "-m", "hammesh", "mesh", DEMO, "-q", "30", "-a", "2e-3", "--workers", "2",
                        "--partitioned", "-o", str(out), "--report", str(rep)], capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 0 and p.stderr == "", p.stderr
    lines = p.stdout.splitlines()  # (and the notes of what the pieces do not hold: the segments, until they do)
    assert len(lines) >= 2 and lines[0].endswith("verified per tile and across separators")
    assert lines[1].startswith("wrote index:") and all(x.startswith("note: ") for x in lines[2:]), lines
    assert json.loads(rep.read_text())["pieces"] >= 1
    assert main(["check", str(out / "mesh.pvtu")]) == 0
    left = [q.pid for q in psutil.process_iter(["cmdline"]) if str(out) in " ".join(q.info["cmdline"] or [])]
    assert left == []
