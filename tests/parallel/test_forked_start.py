"""The driver's start, session 18: the decomposition in a forked child beside the
cluster's start (``run.decompose_beside``, ``hammesh.parallel.forked``), and the side
executor that takes a thread once the cap is raised (``threads.LaterThreadExecutor``)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import Future
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh import threads
from hammesh.cli import main
from hammesh.errors import InvalidOptionError
from hammesh.parallel import forked, run
from hammesh.parallel.cluster import Starting
from hammesh.parallel.tiles import decompose

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")

needs_fork = pytest.mark.skipif(not forked.can_fork(), reason="no fork here: in_child runs nothing")


def _pid() -> int:
    return os.getpid()


def _boom() -> None:
    raise InvalidOptionError("made up")


def _die() -> None:
    os.kill(os.getpid(), signal.SIGKILL)  # (as a crash in a C library would end it)


def _unpicklable():
    return threading.Lock()


@needs_fork
def test_in_child_computes_in_another_process_and_sends_the_result_back():
    ok, pid = forked.in_child(_pid)
    assert ok and pid != os.getpid()
    ok, arr = forked.in_child(np.arange, 1_000_003)  # (more than a pipe's buffer)
    assert ok and np.array_equal(arr, np.arange(1_000_003))


@needs_fork
@pytest.mark.parametrize("fn", [_boom, _die, _unpicklable])
def test_in_child_says_so_when_no_result_came_back(fn):
    """An error, a dead child, a result that does not pickle: ``(False, None)``, and
    the caller runs the function itself (its error first hand); no child is left."""
    assert forked.in_child(fn) == (False, None)
    with pytest.raises(ChildProcessError):
        os.waitpid(-1, os.WNOHANG)  # (reaped)


@needs_fork
def test_an_error_while_waiting_kills_the_child():
    """An exception in the parent while it waits for the child (``Terminated`` on
    SIGTERM, Ctrl-C) kills and reaps the child before it propagates."""

    class Stop(Exception):
        pass

    def stop(*_):
        raise Stop

    old = signal.signal(signal.SIGALRM, stop)
    t0 = time.perf_counter()
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.3)
        with pytest.raises(Stop):
            forked.in_child(time.sleep, 60)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert time.perf_counter() - t0 < 30
    with pytest.raises(ChildProcessError):
        os.waitpid(-1, os.WNOHANG)


class _Booting(Starting):
    """A local cluster's handle whose start never ends (only ``started`` is asked)."""

    def __init__(self) -> None:
        super().__init__(Future(), 2)


@needs_fork
def test_decompose_beside_a_starting_cluster_runs_in_a_child_and_is_the_same(monkeypatch):
    dom = hammesh.read_domain(DEMO)
    kw = dict(min_angle=30, max_area=2e-4, n_tiles=5)
    here = decompose(dom, **kw)
    there = run.decompose_beside(_Booting(), dom, **kw)
    assert there.n_tiles == here.n_tiles == 5
    for name in ("vertices", "separator", "segment_markers"):
        assert np.array_equal(getattr(here, name), getattr(there, name)), name
    for a, b in zip(here.tiles, there.tiles):
        assert np.array_equal(a.vertex_ids, b.vertex_ids) and a.estimate == b.estimate
    # where it ran: a child while the cluster starts, this process otherwise
    monkeypatch.setattr(run, "decompose", lambda domain, **kw: os.getpid())
    assert run.decompose_beside(_Booting(), dom, **kw) != os.getpid()
    assert run.decompose_beside(run.LocalRunner(), dom, **kw) == os.getpid()
    monkeypatch.setattr(run, "DECOMPOSE_IN_CHILD", False)
    assert run.decompose_beside(_Booting(), dom, **kw) == os.getpid()


@needs_fork
def test_decompose_beside_raises_the_decompositions_own_error():
    """Bad input found by the decomposition (a regional area bound): the child has no
    result, this process decomposes and raises the error itself."""
    square = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    dom = hammesh.Domain(vertices=square.vertices, segments=square.segments, regions=[[0.5, 0.5, 1.0, 0.01]])
    with pytest.raises(InvalidOptionError, match="regional area bounds"):
        run.decompose_beside(_Booting(), dom, min_angle=30, max_area=1e-3, n_tiles=2)


def test_the_decomposition_imports_nothing_beyond_its_listed_modules(tmp_path):
    """A Python caller's first decomposition (a fresh process: only the domain read
    and ``run.DECOMPOSE_MODULES`` imported) imports no module but numba's own, which it
    loads under numba's compiler lock (held across forks): the child forked for it
    never waits on a module lock another thread held at the fork."""
    code = (f"import sys, importlib; import hammesh; from hammesh.parallel import run; "
            f"[importlib.import_module(n) for n in run.DECOMPOSE_MODULES]; "
            f"from hammesh.parallel.tiles import decompose; d = hammesh.read_domain({DEMO!r}); "
            f"before = set(sys.modules); decompose(d, min_angle=30, max_area=1e-4, n_tiles=4); "
            f"print(sorted(m for m in set(sys.modules) - before if m.split('.')[0] != 'numba' and m != 'cmath'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


#: ``hammesh argv[2:]`` in a fresh process with ``run.DECOMPOSE_IN_CHILD`` = ``argv[1]``
_SWITCHED = ("import sys; import hammesh.parallel.run as r; r.DECOMPOSE_IN_CHILD = bool(int(sys.argv[1])); "
             "from hammesh.cli import main; sys.exit(main(sys.argv[2:]))")


@pytest.mark.slow
def test_the_command_writes_the_same_pieces_with_the_decomposition_in_a_child(tmp_path):
    pytest.importorskip("distributed")
    outs = []
    for on in (1, 0):
        out = tmp_path / f"out{on}"
        argv = ["mesh", DEMO, "-q", "30", "-a", "5e-4", "--workers", "2", "--partitioned", "-o", str(out),
                "--report", str(tmp_path / f"r{on}.json")]
        p = subprocess.run([sys.executable, "-c", _SWITCHED, str(on), *argv], capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 0, p.stderr[-2000:]
        outs.append(out)
    names = sorted(p.name for p in outs[0].iterdir())
    assert names == sorted(p.name for p in outs[1].iterdir()) and "mesh.pvtu" in names
    for name in names:
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name
    assert main(["check", str(outs[0] / "mesh.pvtu")]) == 0


@pytest.mark.slow
def test_an_error_of_the_decomposition_closes_the_cluster_and_leaves_no_file(tmp_path, run_cli):
    """A regional area bound (refused by the decomposition, made beside the cluster's
    start): one line, exit 2, no output, no partial directory, no thread of the
    cluster's start left, no child process left behind."""
    pytest.importorskip("distributed")
    poly = tmp_path / "regional.poly"
    poly.write_text("4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n1\n1 0.5 0.5 1 0.01\n")
    rc, _, err, left = run_cli(["mesh", str(poly), "-q", "30", "-a", "1e-3", "--workers", "2", "--partitioned",
                                "-o", str(tmp_path / "o")])
    assert rc == 2, err
    assert len(err.strip().splitlines()) == 1 and "regional area bounds" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["regional.poly"]
    assert left == []


def test_later_thread_executor_runs_inline_until_the_cap_is_raised():
    old = threads.limit(1)
    try:
        side = threads.side_executor()
        assert isinstance(side, threads.LaterThreadExecutor) and isinstance(side, threads.InlineExecutor)
        with side:
            here = threading.get_ident()
            assert side.submit(threading.get_ident).result() == here  # (inline: a cap of 1)
            threads.limit(2)
            f = side.submit(threading.get_ident)
            g = side.submit(threading.get_ident)
            threads.limit(1)  # (once there, the work stays on its thread: the order kept)
            h = side.submit(threading.get_ident)
            assert f.result() != here and f.result() == g.result() == h.result()
            boom = side.submit(_boom)
            with pytest.raises(InvalidOptionError):
                boom.result()
        assert not any(t.name.startswith("hammesh-side") and t.is_alive() for t in threading.enumerate())
    finally:
        threads.limit(old)


def test_hamiltonian_is_the_same_when_the_cap_is_raised_while_it_runs(monkeypatch):
    """Sparse mode's side work (the certificate's look at the input) submitted after
    the cap went up runs on a thread; the output is the same as under the cap."""
    mesh = hammesh.quality_mesh(hammesh.read_domain(DEMO), min_angle=30, max_area=2e-4)
    old = threads.limit(1)
    try:
        ref = hammesh.hamiltonian(mesh, mode="sparse")
        used: list = []
        real = threads.LaterThreadExecutor.submit

        def submit(self, fn, *a, **k):
            threads.limit(2)  # (as a tail raise would, in the middle of the run)
            f = real(self, fn, *a, **k)
            used.append(self._pool is not None)
            return f

        monkeypatch.setattr(threads.LaterThreadExecutor, "submit", submit)
        got = hammesh.hamiltonian(mesh, mode="sparse")
    finally:
        threads.limit(old)
    assert used and all(used)
    assert np.array_equal(ref.triangles, got.triangles) and np.array_equal(ref.points, got.points)
    assert np.array_equal(ref.position, got.position)


#: a one-worker local cluster whose driver loads no kernel before the fork
#: (``KERNELS_BEFORE_FORK`` off): the worker's own loading task runs first of its tasks
WORKER_LOADS = """
import json
import hammesh.parallel.cluster as cl
cl.KERNELS_BEFORE_FORK = False

def held():
    from hammesh.parallel import _kernels as k
    names = ("lattice_mark_inside_into", "lattice_triangles_into", "lattice_mesh_into")
    return {n: len(getattr(k, n).signatures) for n in names}

if __name__ == "__main__":
    with cl.runner_for(workers=1, mode="sparse") as (c, _):
        worker = c.submit(held, pure=False).result()
    print(json.dumps({"method": cl.start_method(), "driver": held(), "worker": worker}))
"""


@pytest.mark.slow
def test_without_kernels_before_the_fork_each_worker_loads_them_first(tmp_path):
    """``cluster.KERNELS_BEFORE_FORK`` off: the driver loads no kernel for its workers,
    and each worker's first task loads them (before any tile: priority)."""
    pytest.importorskip("distributed")
    script = tmp_path / "loads.py"
    script.write_text(WORKER_LOADS)
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert all(v >= 1 for v in got["worker"].values()), got
    assert all(v == 0 for v in got["driver"].values()), got
