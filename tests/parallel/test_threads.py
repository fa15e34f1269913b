"""hammesh.threads: the per-process cap, and the local cluster's workers sharing the cores."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from hammesh import threads


@pytest.fixture
def no_cap():
    old = threads.limit(None)
    yield
    threads.limit(old)


@pytest.mark.parametrize("cpus, cap, expect", [(8, None, 8), (8, 3, 3), (2, 5, 2), (1, 1, 1), (4, 1, 1)])
def test_cores_is_the_machine_capped(monkeypatch, no_cap, cpus, cap, expect):
    monkeypatch.setattr(threads.os, "cpu_count", lambda: cpus)
    threads.limit(cap)
    assert threads.cores() == expect
    # a pass over many rows gets exactly that many ranges, covering every row once
    spans = threads.row_ranges(10_000, 10)
    assert len(spans) == expect
    assert spans[0][0] == 0 and spans[-1][1] == 10_000
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:]))


def test_limit_returns_the_old_cap_and_refuses_nonsense(no_cap):
    assert threads.limit(2) is None
    assert threads.limit(None) == 2
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError):
            threads.limit(bad)


def test_run_all_never_runs_more_calls_at_once_than_the_cap(monkeypatch, no_cap):
    import threading
    import time

    monkeypatch.setattr(threads.os, "cpu_count", lambda: 8)
    threads.limit(2)
    lock, now, peak = threading.Lock(), [0], [0]

    def call():
        with lock:
            now[0] += 1
            peak[0] = max(peak[0], now[0])
        time.sleep(0.02)
        with lock:
            now[0] -= 1
        return 1

    assert threads.run_all([call] * 6) == [1] * 6
    assert peak[0] == 2


def test_run_all_under_a_cap_of_one_runs_in_the_callers_thread_in_order(monkeypatch, no_cap):
    import threading

    monkeypatch.setattr(threads.os, "cpu_count", lambda: 8)
    threads.limit(1)
    seen = []
    calls = [lambda i=i: seen.append((i, threading.get_ident())) or i for i in range(3)]
    assert threads.run_all(calls) == [0, 1, 2]
    assert seen == [(i, threading.get_ident()) for i in range(3)]


@pytest.mark.parametrize("value, capped", [("1", True), ("junk", False), ("0", False), ("", False)])
def test_environment_sets_the_cap_of_a_new_process(value, capped):
    env = {**os.environ, "HAMMESH_THREADS": value}
    out = subprocess.run([sys.executable, "-c", "import os, hammesh.threads as t; print(t.cores(), os.cpu_count())"],
                         env=env, capture_output=True, text=True, check=True)
    got, cpus = map(int, out.stdout.split())
    assert got == (1 if capped else cpus)


@pytest.mark.slow
def test_local_cluster_workers_share_the_cores():
    pytest.importorskip("distributed")
    from hammesh.parallel import cluster
    from hammesh.parallel.cluster import runner_for, worker_threads

    import dask

    with runner_for(workers=2) as (client, n):
        got = client.run(threads.cores)
        profiled = client.run(dask.config.get, "distributed.worker.profile.enabled")
        retained = client.run(cluster.retain_freed_memory)
    assert n == 2 and len(got) == 2
    assert set(got.values()) == {worker_threads(2)} == {max(1, (os.cpu_count() or 1) // 2)}
    # the workers run no statistical profiler (cluster.QUIET_CLUSTER), keep freed memory (glibc)
    assert set(profiled.values()) == {False}
    assert set(retained.values()) == {sys.platform.startswith("linux")}


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_hamiltonian_side_thread_respects_the_cap(monkeypatch, no_cap, mode):
    """Under a cap of one thread, ``hamiltonian()`` starts no thread (its certificate's
    side work runs inline) and makes the same verified mesh as with its side thread."""
    import threading

    import numpy as np

    import hammesh

    mesh = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]]), min_angle=30,
                                max_area=2e-3, isolate=False)
    started = []
    real_start = threading.Thread.start

    def start(self):
        started.append(self.name)
        return real_start(self)

    monkeypatch.setattr(threading.Thread, "start", start)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    threads.limit(1)
    alone = hammesh.hamiltonian(mesh, mode=mode)
    assert started == []
    threads.limit(None)
    beside = hammesh.hamiltonian(mesh, mode=mode)
    assert len(started) >= 1  # the side thread, when two may run
    assert alone.report["verified"] and beside.report["verified"]
    assert np.array_equal(alone.triangles, beside.triangles) and np.array_equal(alone.points, beside.points)


def test_inline_executor_keeps_errors_for_result():
    with threads.InlineExecutor() as ex:
        ok = ex.submit(lambda a, b=1: a + b, 2, b=3)
        bad = ex.submit(lambda: 1 / 0)
    assert ok.done() and ok.result() == 5
    with pytest.raises(ZeroDivisionError):
        bad.result()


def test_side_executor_is_inline_under_a_cap_of_one(monkeypatch, no_cap):
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 4)
    threads.limit(1)
    assert isinstance(threads.side_executor(), threads.InlineExecutor)
    threads.limit(2)
    with threads.side_executor() as side:
        assert not isinstance(side, threads.InlineExecutor)
        assert side.submit(lambda: 7).result() == 7


@pytest.mark.slow
def test_local_cluster_started_in_the_background():
    """``background=True``: the caller goes on while the cluster starts; the first use
    of the runner waits for it, the workers are capped, the cluster closes on exit."""
    pytest.importorskip("distributed")
    from hammesh.parallel.cluster import Starting, runner_for, worker_threads

    with runner_for(workers=2, background=True) as (runner, n):
        assert isinstance(runner, Starting) and n == 2  # known before the cluster is up
        assert runner.submit(sum, [1, 2, 3]).result() == 6
        got = runner.run(threads.cores)
        address = runner.scheduler.address
    assert set(got.values()) == {worker_threads(2)}
    import distributed

    with pytest.raises(OSError):  # closed: nothing listens there any more
        distributed.Client(address, timeout="2s")


@pytest.mark.slow
def test_background_start_closes_the_cluster_when_the_caller_fails():
    pytest.importorskip("distributed")
    import threading

    from hammesh.parallel.cluster import runner_for

    before = {t.name for t in threading.enumerate()}
    with pytest.raises(ZeroDivisionError):
        with runner_for(workers=1, background=True):
            1 / 0  # before the cluster is even used
    assert not [t for t in threading.enumerate() if t.name.startswith("hammesh-cluster") and t.name not in before]


def test_retained_memory_is_reused_without_faults():
    """After ``retain_freed_memory`` (a local cluster's workers call it), a freed big
    array's pages serve the next one: far fewer page faults than the first time."""
    code = (
        "import resource, numpy as np\n"
        "from hammesh.parallel.cluster import retain_freed_memory\n"
        "ok = retain_freed_memory()\n"
        "def faults():\n"
        "    f = resource.getrusage(resource.RUSAGE_SELF).ru_minflt\n"
        "    a = np.empty(100_000_000 // 8); a[::512] = 1.0\n"  # every 4 kB page written
        "    del a\n"
        "    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f\n"
        "print(ok, faults(), faults())\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    ok, first, second = out.stdout.split()
    if ok != "True":
        pytest.skip("no glibc mallopt here")
    assert int(first) > 20 and int(second) * 4 < int(first)


_THREAD_FAULTS = (
    "import resource, sys, threading, numpy as np\n"
    "from hammesh.parallel.cluster import retain_freed_memory, single_arena\n"
    "one = single_arena() if sys.argv[1] == '1' else True\n"
    "ok = retain_freed_memory() and one\n"
    "def faults():\n"
    "    f = resource.getrusage(resource.RUSAGE_SELF).ru_minflt\n"
    "    a = np.empty(100_000_000 // 8); a[::512] = 1.0\n"
    "    del a\n"
    "    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f\n"
    "got = []\n"
    "t = threading.Thread(target=lambda: got.extend([faults(), faults()])); t.start(); t.join()\n"
    "print(ok, *got)\n")


@pytest.mark.parametrize("one_arena", [True, False])
def test_a_thread_reuses_freed_big_blocks_only_with_one_arena(one_arena):
    """A thread (where Dask runs every task) has its own glibc arena, which maps a
    block over its 64 MB heaps apart and unmaps it when freed: ``retain_freed_memory``
    alone keeps nothing there (every 100 MB array faults its pages in again); with
    ``single_arena`` set before the thread starts, the second array faults nothing."""
    import os

    # (numpy's huge-page advice off, as in the workers: 4 kB pages to count)
    env = {**os.environ, "NUMPY_MADVISE_HUGEPAGE": "0"}
    out = subprocess.run([sys.executable, "-c", _THREAD_FAULTS, str(int(one_arena))], capture_output=True,
                         text=True, check=True, env=env)
    ok, first, second = out.stdout.split()
    if ok != "True":
        pytest.skip("no glibc mallopt here")
    assert int(first) > 20_000  # (100 MB of 4 kB pages)
    if one_arena:
        assert int(second) * 100 < int(first)
    else:
        assert int(second) * 2 > int(first)  # (what the one arena is for: if glibc changes, say so)


def test_the_command_s_workers_reuse_big_blocks_across_tasks():
    """With the driver's one arena (``hammesh mesh --workers`` sets it before the
    cluster's thread), a local cluster's forked workers reuse a freed 100 MB block in
    their next tasks: no page faults after each worker's first."""
    pytest.importorskip("distributed")  # (the [dask] extra; CI runs without it)
    code = (
        "import resource\n"
        "from hammesh.parallel import cluster\n"
        "cluster.PREFAULT = False\n"
        "assert cluster.single_arena()\n"
        "def task(i):\n"
        "    import numpy as np, resource\n"
        "    f = resource.getrusage(resource.RUSAGE_SELF).ru_minflt\n"
        "    a = np.empty(100_000_000 // 8); a[::512] = 1.0\n"
        "    del a\n"
        "    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f\n"
        "with cluster.runner_for(workers=2, mode=None, background=True) as (run, n):\n"
        "    got = run.gather([run.submit(task, i, pure=False) for i in range(6)])\n"
        "print(*got)\n")
    import platform

    if platform.system() != "Linux":
        pytest.skip("glibc only")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=240)
    got = [int(x) for x in out.stdout.split()]
    # each worker faults its first block in; the other tasks reuse it (before: all ~24k)
    assert sum(g > 10_000 for g in got) <= 2, got
    assert sorted(got)[:4] == [g for g in sorted(got)[:4] if g < 1_000], got


def test_parallel_command_freezes_the_collector_at_exit(tmp_path):
    """``hammesh mesh --tiles ...`` skips the collector's passes at exit (gc.freeze by
    atexit): checked by a handler that runs after the command's."""
    from pathlib import Path

    import hammesh

    demo = str(Path(hammesh.__file__).parent / "data" / "demo.poly")
    code = (
        "import atexit, gc, sys\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 0, flush=True))\n"
        "from hammesh.cli import main\n"
        f"rc = main(['mesh', {demo!r}, '-q', '30', '-a', '4e-3', '--tiles', '2', '-o', {str(tmp_path / 'o.vtu')!r}])\n"
        "print('rc', rc, flush=True)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "rc 0" in out.stdout and "frozen True" in out.stdout
