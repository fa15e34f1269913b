"""hammesh.idle: work on a thread of the lowest priority, taken over by a caller that cannot wait."""

from __future__ import annotations

import os
import threading
import time

import pytest

import hammesh
from hammesh import idle
from tests.helpers import bundled_domain, hull_area

pytestmark = pytest.mark.skipif(not idle.available(), reason="a thread's own nice value is Linux semantics")


def _own_priority() -> tuple[int, int]:
    """The calling thread's scheduling policy and nice value."""
    return os.sched_getscheduler(0), os.getpriority(os.PRIO_PROCESS, threading.get_native_id())


def _may_raise_priority() -> bool:
    """Whether this process may give an idle thread its normal priority back (privileged)."""
    out = []

    def probe() -> None:
        tid = threading.get_native_id()
        try:
            os.sched_setscheduler(tid, os.SCHED_IDLE, os.sched_param(0))
            os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
            out.append(True)
        except OSError:
            out.append(False)

    t = threading.Thread(target=probe)
    t.start()
    t.join()
    return out[0]


def test_the_work_runs_at_the_lowest_priority_and_leaves_the_caller_as_it_was() -> None:
    before = _own_priority()
    task = idle.on_idle_core(_own_priority)
    while not task.done():
        time.sleep(0.001)
    policy, nice = task.result()
    assert policy == os.SCHED_IDLE or nice == idle.IDLE_NICE
    assert task.made_by == "idle"
    assert _own_priority() == before  # (the caller's thread is not the one lowered)


def test_an_exception_of_the_work_is_raised_in_the_caller() -> None:
    def fails(x: int) -> int:
        raise ValueError(f"bad {x}")

    task = idle.on_idle_core(fails, 7)
    with pytest.raises(ValueError, match="bad 7"):
        task.result()


def _blocked_on_the_idle_thread(release: threading.Event, started: threading.Event | None = None):
    def work(x: int) -> str:
        if threading.current_thread().name == "hammesh-idle":
            if started is not None:
                started.set()
            release.wait(10)  # (a thread that gets no core: starved by other processes)
            return f"thread {x}"
        return f"caller {x}"

    return work


def test_a_caller_that_cannot_raise_the_thread_back_takes_the_work_over(monkeypatch) -> None:
    real_nice, real_policy = os.setpriority, os.sched_setscheduler

    def unprivileged_nice(which: int, who: int, prio: int) -> None:  # (no thread's priority goes up)
        if prio < os.getpriority(which, who):
            raise PermissionError(13, "Permission denied")
        real_nice(which, who, prio)

    def unprivileged_policy(who: int, policy: int, param) -> None:  # (RLIMIT_NICE 0: no way out of SCHED_IDLE)
        if os.sched_getscheduler(who) == os.SCHED_IDLE and policy != os.SCHED_IDLE:
            raise PermissionError(1, "Operation not permitted")
        real_policy(who, policy, param)

    monkeypatch.setattr(os, "setpriority", unprivileged_nice)
    monkeypatch.setattr(os, "sched_setscheduler", unprivileged_policy)
    release = threading.Event()
    task = idle.on_idle_core(_blocked_on_the_idle_thread(release), 3, grace=0.2)
    t = time.perf_counter()
    try:
        assert task.result() == "caller 3"
        assert task.made_by == "caller"
        assert 0.2 <= time.perf_counter() - t < 5  # (it waited the grace, not for the thread)
        assert not task.done()
    finally:
        release.set()


@pytest.mark.skipif(not _may_raise_priority(), reason="this process may not raise a thread's priority")
def test_a_privileged_caller_raises_the_thread_back_and_waits_for_it() -> None:
    release, started = threading.Event(), threading.Event()
    task = idle.on_idle_core(_blocked_on_the_idle_thread(release, started), 5)
    assert started.wait(10)  # (its priority lowered before the work starts)
    timer = threading.Timer(2 * idle.TAKEOVER_GRACE, release.set)  # (longer than the grace)
    timer.start()
    assert task.result() == "thread 5"  # (it waited past the grace: it did not take over)
    assert task.made_by == "raised"
    timer.join()


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_the_certificates_look_comes_from_the_idle_core(monkeypatch, mode: str) -> None:
    made = []
    real = idle.on_idle_core

    def spy(fn, *args, grace):
        task = real(fn, *args, grace=grace)
        made.append((fn, args, task, grace))
        return task

    monkeypatch.setattr(idle, "on_idle_core", spy)
    dom = bundled_domain("face")
    mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 2000)
    h = hammesh.hamiltonian(mesh, mode=mode)
    assert h.report["verified"]
    ours = [(fn, task, grace) for fn, args, task, grace in made if args[0] is mesh]  # (not the kernel loading's)
    assert [fn.__qualname__ for fn, _, _ in ours] == ["input_facts"]
    assert ours[0][1].made_by in ("idle", "raised", "caller")
    assert 0 < ours[0][2] < 0.01  # (a small mesh: a caller never waits long for its look)
    assert list(h.components) == [len(h.triangles)]  # (one cycle: the rows in walk order)


@pytest.mark.skipif(not _may_raise_priority(), reason="this process may not raise a thread's priority")
def test_a_thread_raised_back_gets_its_callers_policy_not_a_higher_one() -> None:
    """A caller run as a batch job (``chrt -b``) hands its idle work back at batch policy."""
    release, started, out = threading.Event(), threading.Event(), []

    def work() -> int:
        started.set()
        release.wait(10)
        return os.sched_getscheduler(0)

    def batch_caller() -> None:
        os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))
        task = idle.on_idle_core(work)
        assert started.wait(10)
        threading.Timer(0.05, release.set).start()
        out.append((task.result(), task.made_by))

    t = threading.Thread(target=batch_caller)
    t.start()
    t.join(30)
    assert out == [(os.SCHED_BATCH, "raised")]
