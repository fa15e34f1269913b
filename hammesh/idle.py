"""Work for a core the call leaves idle: a thread of the lowest priority whose
result the caller takes when it needs it, or makes itself.

Why. Sparse mode's construction keeps two cores busy only part of the time; the
certificate's look at the caller's input (:func:`hammesh.verify.reference.input_facts`,
~0.1 s of one core at 1.5 M triangles) has to run somewhere. On the side executor's
thread it was a third runnable thread wherever both cores were busy, and the
scheduler shared the cores out evenly: the construction's main thread waited on the
run queue (20 ms in ``plan_joins`` alone, at a load below 1; docs/sparse.md,
session 22, third round). At nice 19 the same thread takes only what the
construction leaves: measured on fresh 1.5 M calls, 19 each way, the call's wall went
from 0.788 to 0.767 s (median; the paired median −30 ms).

The risk of the lowest priority is starvation: under other processes' load the
thread may get almost nothing, and the caller would wait for it. So the caller never
waits long: :meth:`IdleTask.result` returns the thread's result if it is there;
else it gives the thread back its old priority where the system lets a thread raise
its priority (privileged processes) and waits; else it waits at most as long as
the work would take it (the caller's estimate, ``grace``) and then runs the work
itself: it never loses more than the work's own time. Abandoned work runs out on its
daemon thread, at nice 19, and its result is dropped (it never holds up the
process's exit).

A thread's own nice value is Linux semantics (``setpriority(PRIO_PROCESS, tid)``
names a thread there; elsewhere it names a process): :func:`available` is False on
other systems, and callers run the work as before.
"""

from __future__ import annotations

import os
import sys
import threading
from typing import Any, Callable

__all__ = ["IdleTask", "on_idle_core", "available", "IDLE_NICE", "TAKEOVER_GRACE"]

#: the thread's nice value (the lowest priority a normal thread may have)
IDLE_NICE = 19
#: seconds the caller waits for a thread it cannot raise back before it runs the
#: work itself, where it gave no estimate of the work's time
TAKEOVER_GRACE = 0.05
#: "nice" (nice 19) or "sched_idle" (Linux's SCHED_IDLE: preempted at once by any
#: thread that wakes) -- session 23's experiment
POLICY = "nice"


def available() -> bool:
    """True where a thread's nice value is its own (Linux)."""
    return sys.platform.startswith("linux") and hasattr(os, "setpriority") and hasattr(threading, "get_native_id")


class IdleTask:
    """``fn(*args)`` on a daemon thread at nice :data:`IDLE_NICE` (see :func:`on_idle_core`)."""

    def __init__(self, fn: Callable[..., Any], args: tuple, grace: float = TAKEOVER_GRACE) -> None:
        self._fn, self._args, self._grace = fn, args, float(grace)
        self._done = threading.Event()
        self._lock = threading.Lock()  # guards _tid, _nice, _abandoned
        self._tid: int | None = None
        self._nice: int | None = None  # the thread's priority before it was lowered
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
        try:
            nice = os.getpriority(os.PRIO_PROCESS, tid)
            if POLICY == "sched_idle":
                os.sched_setscheduler(tid, os.SCHED_IDLE, os.sched_param(0))
            else:
                os.setpriority(os.PRIO_PROCESS, tid, max(nice, IDLE_NICE))
        except OSError:  # (a sandbox may refuse: the work runs at the old priority)
            nice = None
        with self._lock:
            self._tid, self._nice = tid, nice
            if self._abandoned:  # (the caller took over before this thread ran)
                return
        try:
            self._value = self._fn(*self._args)
        except BaseException as exc:  # (raised again in the caller by result())
            self._error = exc
        finally:
            self._done.set()

    def _raise_back(self) -> bool:
        """Give the thread its old priority back (True), where this process may."""
        with self._lock:
            tid, nice = self._tid, self._nice
        if tid is None or nice is None:
            return False
        try:
            if POLICY == "sched_idle":
                os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
            else:
                os.setpriority(os.PRIO_PROCESS, tid, nice)
        except OSError:  # (unprivileged: a thread's priority cannot be raised again)
            return False
        return True

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
