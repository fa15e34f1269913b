"""Plain threads for compiled kernels that release the GIL (``nogil=True``).

The machine's cores share a pass over row ranges; a kernel call holds no Python
state, so threads need no more than a pool. Below ``min_rows`` rows per thread the
pass runs in the calling thread (thread start-up would cost more than it saves).

How many threads: one per core (``os.cpu_count()``), at most :func:`limit`'s cap. A
process that shares the machine with others doing the same work (the ``N`` workers
of a local Dask cluster on ``C`` cores) caps itself at ``C // N``: ``N`` processes each
starting ``C`` threads would run ``N x C`` threads on ``C`` cores, every threaded pass
then paying for context switches and cache thrash instead of gaining. The
``HAMMESH_THREADS`` environment variable sets the cap of a new process (workers of a
cluster started elsewhere: ``HAMMESH_THREADS=1 dask worker ... --nworkers K``).
"""

from __future__ import annotations

import os
import queue
import sys
import threading
import time
from concurrent.futures import Executor, Future, ThreadPoolExecutor, wait
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["row_ranges", "run_all", "run_beside", "cores", "limit", "side_executor", "InlineExecutor", "LaterThreadExecutor", "THREAD_MIN_ROWS", "later",
           "wait_later", "later_held", "LATER_HOLD_MAX"]

#: Rows per thread below which a row pass runs in one call (tests lower it to exercise
#: the threaded paths on small meshes).
THREAD_MIN_ROWS = 200_000


def _env_cap() -> int | None:
    raw = os.environ.get("HAMMESH_THREADS", "").strip()
    try:
        value = int(raw)
    except ValueError:  # unset or not a number: no cap (a bad value must not stop an import)
        return None
    return value if value >= 1 else None


_cap: int | None = _env_cap()


def limit(n: int | None) -> int | None:
    """Cap this process's threads per pass at ``n`` (None: one per core); returns the old cap."""
    global _cap
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
        raise ValueError(f"hammesh.threads.limit: a positive integer or None, got {n!r}")
    old, _cap = _cap, n
    return old


def cores() -> int:
    """Threads a pass may use: the machine's cores, at most the cap (:func:`limit`)."""
    n = os.cpu_count() or 1
    return n if _cap is None else max(1, min(n, _cap))


def row_ranges(m: int, min_rows: int) -> list[tuple[int, int]]:
    """Split ``range(m)`` into one contiguous range per core, each >= ``min_rows``."""
    k = max(1, min(cores(), m // max(1, min_rows)))
    cuts = [m * i // k for i in range(k + 1)]
    return [(cuts[i], cuts[i + 1]) for i in range(k)]


#: threads the shared pool may start (it starts one only where no idle one waits; a
#: pass takes at most ``cores() - 1`` of them, more only where passes run at once)
POOL_THREADS = 32
_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def _shared_pool() -> ThreadPoolExecutor:
    global _pool
    with _pool_lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(POOL_THREADS, thread_name_prefix="hammesh-pass")
        return _pool


def _forget_pool() -> None:  # (a forked child has none of its parent's threads)
    global _pool, _later, _later_lock, _gate, _holds, _draining
    _pool = None
    _later = None  # (work its parent had queued is the parent's)
    _later_lock = threading.Lock()  # (another thread may have held it at the fork)
    _gate, _holds, _draining = threading.Condition(), 0, 0  # (the parent's holds are its own)


os.register_at_fork(after_in_child=_forget_pool)


def run_all(calls: list[Callable[[], Any]]) -> list[Any]:
    """Results of ``calls``, run side by side (in the caller's thread if just one).

    Up to :func:`cores` calls: the first in the caller's thread, the others on a pool
    kept for the process (a new pool per pass cost ~0.3 ms of thread starts, and a
    sparse ``hamiltonian()`` makes ~40 passes). More calls than that: a pool of
    :func:`cores` threads for this call, so that no more run at once. Where this
    process may use one thread (:func:`cores` is 1), one after the other in the
    caller's: no thread is started.
    """
    if len(calls) == 1 or cores() < 2:
        return [c() for c in calls]
    if len(calls) > cores():
        with ThreadPoolExecutor(cores()) as pool:
            return [f.result() for f in [pool.submit(c) for c in calls]]
    rest = [_shared_pool().submit(c) for c in calls[1:]]
    try:
        first = calls[0]()
    except BaseException:
        wait(rest)  # (the others write the caller's arrays too: done before it sees the error)
        raise
    return [first] + [f.result() for f in rest]


def run_beside(fn: Callable[..., Any], *args: Any) -> Future:
    """``fn(*args)`` started now on the pool :func:`run_all` uses; its future. For work
    the caller needs later, beside its own (``fn`` must not need the caller's thread,
    nor write what the caller reads). In the caller's thread, done when returned, where
    this process may use one thread (:func:`cores` is 1)."""
    if cores() < 2:
        return InlineExecutor().submit(fn, *args)
    return _shared_pool().submit(fn, *args)


class InlineExecutor(Executor):
    """An executor that runs every call at ``submit``, in the caller's thread.

    Its futures are done when returned; an exception is kept in the future (raised by
    ``result()``), as a pool thread's would be, so the caller sees its errors in the
    same order as with a thread.
    """

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        f: Future = Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001  (handed to the caller through result())
            f.set_exception(exc)
        return f


class LaterThreadExecutor(InlineExecutor):
    """An :class:`InlineExecutor` that turns into one thread once the process may use
    two (:func:`cores` read at each ``submit``, not when it was made).

    Why: a local cluster's worker caps its threads at its share of the cores and
    raises the cap at the tail, when fewer tiles are left than workers
    (``cluster.TAIL_THREADS``). ``hamiltonian()`` chose its side executor when it
    started, so a tile that had started under a cap of 1 ran its certificate's side
    work inline to the end, beside an idle core (session 17: no effect of the raise
    could be measured). Work submitted after the raise now goes to a thread of its
    own; once there, every later call goes there too (one thread: the order kept).
    It is still an :class:`InlineExecutor` to callers that check: those made their
    serial choice at the start (a row stream) and keep it.
    """

    def __init__(self) -> None:
        self._pool: ThreadPoolExecutor | None = None
        self._lock = threading.Lock()

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        if self._pool is None and cores() < 2:
            return super().submit(fn, *args, **kwargs)
        with self._lock:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(1, thread_name_prefix="hammesh-side")
        return self._pool.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def side_executor() -> Executor:
    """One thread for work beside the caller's (``hammesh()``'s certificate and page
    faults), or, when this process may use one thread only (:func:`cores` is 1: one
    core, or a cap of 1, e.g. a local cluster with a worker per core), a
    :class:`LaterThreadExecutor`: the side work then runs in the caller's thread and
    the process never has two threads computing, unless the cap is raised before the
    work is submitted. Use it as a context manager, like a pool. A caller whose side
    work waits for its own (a row stream) must check ``isinstance(side,
    InlineExecutor)`` and run serially instead.
    """
    return ThreadPoolExecutor(1) if cores() > 1 else LaterThreadExecutor()


_later: queue.SimpleQueue | None = None
_later_lock = threading.Lock()
#: :func:`later_held`'s state: blocks open, since when some block has been open, and
#: :func:`wait_later` calls under way (they let the queue run through a hold: a caller
#: inside one must not wait forever)
_gate = threading.Condition()
_holds = 0
_held_since = 0.0
_draining = 0
#: the longest :func:`later_held` keeps the background work waiting (seconds): blocks
#: of several threads that overlap without end must not keep a process's dead pages
LATER_HOLD_MAX = 1.0


def later(fn: Callable[..., Any], *args: Any) -> None:
    """Run ``fn(*args)`` on the process's background thread, after what was handed to
    it before, or now where this process may use one thread (:func:`cores` is 1) or
    is shutting down.

    For work nobody waits for, whose cost should leave the caller's path: a dead
    array's pages given back to the system (``hammesh.pages``: at 1.5 M triangles a
    sparse ``hamiltonian()`` unmaps ~540 MB in ~44 pieces as its arrays die, 36 ms of
    the main thread's CPU, ~0.1 s of its wall time under load; docs/sparse.md,
    session 17). The background thread is started when first needed (a daemon: work
    still queued at exit is dropped; a forked child starts its own). Errors are not
    raised (there is no caller to raise them to).
    """
    global _later
    if cores() < 2 or sys.is_finalizing():
        fn(*args)
        return
    with _later_lock:
        q = _later
        if q is None:
            q = queue.SimpleQueue()
            try:
                threading.Thread(target=_run_later, args=(q,), name="hammesh-later", daemon=True).start()
            except RuntimeError:  # (no new threads: the interpreter is going down)
                q = None
            _later = q
    if q is None:
        fn(*args)
    else:
        q.put((fn, args))


def wait_later() -> None:
    """Return once everything handed to :func:`later` so far has run (also inside a
    :func:`later_held` block: the queue runs while this waits)."""
    global _draining
    with _later_lock:
        q = _later
    if q is not None:
        done = threading.Event()
        with _gate:
            _draining += 1
            _gate.notify_all()
        try:
            q.put((done.set, ()))
            done.wait()
        finally:
            with _gate:
                _draining -= 1


@contextmanager
def later_held() -> Iterator[None]:
    """Work handed to :func:`later` waits until the block ends (the piece under way
    finishes first); it is queued as before and runs, in order, afterwards.

    For a stretch whose threads want every core, where the background thread's work
    would take one from them: at 1.5 M triangles the arrays a sparse construction drops
    as it ends are ~290 MB, ~25-30 ms of ``munmap`` CPU that ran beside the
    certificate's two row threads (docs/sparse.md, session 21). Holds nest and may
    overlap between threads; the work waits while any is open, at most
    ``LATER_HOLD_MAX`` seconds from when the first of them opened.
    """
    global _holds, _held_since
    with _gate:
        if _holds == 0:
            _held_since = time.monotonic()
        _holds += 1
    try:
        yield
    finally:
        with _gate:
            _holds = max(0, _holds - 1)
            _gate.notify_all()


def _run_later(q: queue.SimpleQueue) -> None:
    while True:
        fn, args = q.get()
        with _gate:  # (a hold open: wait for its end, unless someone waits for the queue)
            while _holds and not _draining:
                left = _held_since + LATER_HOLD_MAX - time.monotonic()
                if left <= 0:  # (held too long: on, until no block is open)
                    break
                _gate.wait(left)
        try:
            fn(*args)
        except Exception:  # noqa: BLE001  (no caller to tell; the next work still runs)
            pass
