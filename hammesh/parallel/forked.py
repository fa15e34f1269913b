"""A function's result computed in a forked child process (the driver's second core).

Why: ``hammesh mesh --workers N`` starts its local cluster in a thread while the main
thread decomposes the domain, and both are Python: one interpreter lock for the
cluster's start (importing Dask, loading the mode's compiled kernels for the forked
workers, the scheduler) and the decomposition, while the machine's other cores wait
for the tiles. Computed in a forked child, the decomposition runs on another core
beside the cluster's start instead of taking turns with it.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
from typing import Any, Callable

__all__ = ["in_child", "can_fork"]


def can_fork() -> bool:
    """Whether :func:`in_child` forks here (Linux: ``os.fork``; macOS's fork is unsafe
    with its system frameworks, Windows has none)."""
    return sys.platform.startswith("linux") and hasattr(os, "fork")


def in_child(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[bool, Any]:
    """``(True, fn(*args, **kwargs))`` computed in a forked child of this process and
    sent back by pickle through a pipe, or ``(False, None)`` when that did not happen:
    no fork here (:func:`can_fork`), ``fn`` raised, the child died (a crash in a C
    library), or its result did not pickle. The caller then runs ``fn`` itself, in
    this process, and gets its result or its exception first hand (a failure costs
    the child's time twice; a success its pickle, ~12 ms for the 6M demo's 4.4 MB
    decomposition).

    The child has only the forking thread: ``fn`` must need nothing another thread
    holds (the cluster's fork hooks, ``cluster._hold_numba_lock_across_fork``, make
    the fork wait while another thread is inside numba's compiler or writes a log
    record). It ends by ``os._exit``: no ``atexit`` handler, no flush of this
    process's buffers. An exception in this process while it waits (``Terminated``
    on SIGTERM, Ctrl-C) kills and reaps the child before it propagates.
    """
    if not can_fork():
        return False, None
    r, w = os.pipe()
    try:
        pid = os.fork()
    except OSError:
        os.close(r)
        os.close(w)
        return False, None
    if pid == 0:  # the child
        code = 1
        try:
            os.close(r)
            signal.signal(signal.SIGINT, signal.SIG_DFL)  # (the parent handles the user's Ctrl-C)
            data = pickle.dumps(fn(*args, **kwargs), protocol=pickle.HIGHEST_PROTOCOL)
            with os.fdopen(w, "wb") as f:
                f.write(data)
            code = 0
        except BaseException:  # noqa: BLE001 - the parent runs fn itself and sees the error
            pass
        finally:
            os._exit(code)
    os.close(w)
    done = False
    try:
        with os.fdopen(r, "rb") as f:
            data = f.read()  # (until the child closes its end: done or dead; the GIL is released)
        _, status = os.waitpid(pid, 0)
        done = True
    finally:
        if not done:
            try:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            except OSError:
                pass
    if not (os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0) or not data:
        return False, None
    try:
        return True, pickle.loads(data)
    except Exception:  # noqa: BLE001 - (the caller runs fn itself)
        return False, None
