"""Work for a core the call leaves idle: a thread of the lowest priority whose
result the caller takes when it needs it, or makes itself.

Why. Sparse mode's construction keeps two cores busy only part of the time; the
certificate's look at the caller's input (:func:`hammesh.verify.reference.input_facts`,
~0.08 s of one core at 1.5 M triangles) has to run somewhere. On the side executor's
thread it was a third runnable thread wherever both cores were busy, and the
scheduler shared the cores out evenly: the construction's main thread waited on the
run queue (20 ms in ``plan_joins`` alone, at a load below 1; docs/sparse.md,
session 22, third round). As an idle thread it takes only what the construction
leaves. Linux's ``SCHED_IDLE`` policy does that best: any normal thread that wakes
preempts it at once, where a nice-19 thread keeps the core until the scheduler's next
decision. Quiet fresh 1.5 M first calls, arms alternating (session 23): the call's
wall 0.756 s with the look on the side executor's thread, 0.741 at nice 19, **0.729**
as ``SCHED_IDLE`` (medians of 10; paired −31 ms, 8 of 10 faster).

The risk of the lowest priority is starvation: under other processes' load the
thread may get almost nothing, and the caller would wait for it. So the caller never
waits long: :meth:`IdleTask.result` returns the thread's result if it is there;
else it gives the thread back its old priority where the system lets a thread raise
its priority (privileged processes) and waits; else it waits at most as long as
the work would take it (the caller's estimate, ``grace``) and then runs the work
itself: it never loses more than the work's own time. Abandoned work runs out on its
daemon thread and its result is dropped (it never holds up the process's exit).

A thread's own scheduling policy and nice value are Linux semantics (the calls name
a thread there, a process elsewhere): :func:`available` is False on other systems,
and callers run the work as before.
"""

from __future__ import annotations

import os
import sys
import threading
from typing import Any, Callable

__all__ = ["IdleTask", "on_idle_core", "available", "IDLE_NICE", "TAKEOVER_GRACE"]

#: the nice value of an idle thread where the system refuses ``SCHED_IDLE``
IDLE_NICE = 19
#: seconds the caller waits for a thread it cannot raise back before it runs the
#: work itself, where it gave no estimate of the work's time
TAKEOVER_GRACE = 0.05


def available() -> bool:
    """True where a thread's scheduling is its own (Linux)."""
    return (sys.platform.startswith("linux") and hasattr(os, "sched_setscheduler")
            and hasattr(os, "setpriority") and hasattr(threading, "get_native_id"))


def _lower(tid: int) -> tuple[str, int] | None:
    """Make thread ``tid`` idle; return how to raise it back, or None where refused."""
    try:
        old = os.sched_getscheduler(tid)  # (the caller's own: a process run under chrt keeps it)
        os.sched_setscheduler(tid, os.SCHED_IDLE, os.sched_param(0))
        return ("policy", old)
    except (OSError, AttributeError):
        pass
    try:
        nice = os.getpriority(os.PRIO_PROCESS, tid)
        os.setpriority(os.PRIO_PROCESS, tid, max(nice, IDLE_NICE))
        return ("nice", nice)
    except OSError:  # (a sandbox may refuse both: the work runs at the old priority)
        return None


def _raise(tid: int, how: tuple[str, int]) -> bool:
    """Undo :func:`_lower` (False where this process may not raise a thread's priority)."""
    kind, old = how
    try:
        if kind == "policy":
            os.sched_setscheduler(tid, old, os.sched_param(0))
        else:
            os.setpriority(os.PRIO_PROCESS, tid, old)
    except OSError:  # (unprivileged: RLIMIT_NICE keeps a lowered thread low)
        return False
    return True


class IdleTask:
    """``fn(*args)`` on a daemon thread of the lowest priority (see :func:`on_idle_core`)."""

    def __init__(self, fn: Callable[..., Any], args: tuple, grace: float = TAKEOVER_GRACE) -> None:
        self._fn, self._args, self._grace = fn, args, float(grace)
        self._done = threading.Event()
        self._lock = threading.Lock()  # guards _tid, _how, _abandoned
        self._tid: int | None = None
        self._how: tuple[str, int] | None = None  # how to raise the thread back
        self._abandoned = False
        self._value: Any = None
        self._error: BaseException | None = None
        #: who made the result: "idle" (the thread), "raised" (the thread, raised back
        #: while the caller waited) or "caller" (taken over); None before result()
        self.made_by: str | None = None
        self._thread = threading.Thread(target=self._run, name="hammesh-idle", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        tid = threading.get_native_id()
        how = _lower(tid)
        with self._lock:
            self._tid, self._how = tid, how
            if self._abandoned:  # (the caller took over before this thread ran)
                return
        try:
            self._value = self._fn(*self._args)
        except BaseException as exc:  # (raised again in the caller by result())
            self._error = exc
        finally:
            self._done.set()

    def _raise_back(self) -> bool:
        with self._lock:
            tid, how = self._tid, self._how
        return tid is not None and how is not None and _raise(tid, how)

    def _outcome(self, made_by: str) -> Any:
        self.made_by = made_by
        if self._error is not None:
            raise self._error
        return self._value

    def done(self) -> bool:
        """True once the thread has finished the work."""
        return self._done.is_set()

    def result(self) -> Any:
        """The work's result (its exception raised), now: see the module's docstring."""
        if self._done.is_set():
            return self._outcome("idle")
        if self._raise_back():
            self._done.wait()
            return self._outcome("raised")
        if self._done.wait(self._grace):
            return self._outcome("idle")
        with self._lock:
            self._abandoned = True
        self.made_by = "caller"
        return self._fn(*self._args)


def on_idle_core(fn: Callable[..., Any], *args: Any, grace: float = TAKEOVER_GRACE) -> IdleTask:
    """Start ``fn(*args)`` on a thread of its own at the lowest priority.

    ``fn`` must be safe to run twice at once on the same arguments (the caller may take
    over while the thread still runs): it must not write to them. ``grace``: about the
    seconds ``fn`` takes on a core of its own (the longest :meth:`IdleTask.result`
    waits for a thread it cannot raise back). Call only where :func:`available`.
    """
    return IdleTask(fn, args, grace)
