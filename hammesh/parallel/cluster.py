"""Dask (``dask.distributed``) as the optional runner of the tiles (``pip install hammesh[dask]``)."""

from __future__ import annotations

import contextlib
import threading
from typing import Iterator

from hammesh.errors import HammeshError, InvalidOptionError

__all__ = ["runner_for", "start_method", "worker_threads", "worker_setup", "local_workers", "set_threads", "TAIL_THREADS", "retain_freed_memory", "no_hugepage_advice", "NO_HUGEPAGE_ADVICE", "Starting",
           "prefault", "PREFAULT", "PREFAULT_MB", "PREFAULT_BLOCK_MB", "single_arena", "SINGLE_ARENA", "KERNELS_BEFORE_FORK", "load_worker_kernels", "guard_forks",
           "dask_installed", "DASK_MISSING", "pause_gc", "resume_gc", "PAUSE_GC", "quiet_llvm_lock", "QUIET_LLVM_LOCK", "QUIET_CLUSTER", "TILE_QUEUE", "START_TIMEOUT", "ClusterError"]

DASK_MISSING = "parallel meshing on workers needs Dask: pip install hammesh[dask]"


class ClusterError(HammeshError, RuntimeError):
    """A local Dask cluster did not start (within :data:`START_TIMEOUT`)."""


def _distributed():
    try:
        import distributed
    except ImportError:
        raise InvalidOptionError(DASK_MISSING) from None
    return distributed


def dask_installed() -> bool:
    """Whether ``import distributed`` would find it, without importing it (~0.6 s:
    a local cluster imports it in its starting thread, beside the driver's work)."""
    import importlib.util
    import sys

    if "distributed" in sys.modules:
        return sys.modules["distributed"] is not None
    try:
        return importlib.util.find_spec("distributed") is not None
    except (ImportError, ValueError):
        return False


def start_method() -> str:
    """How a local cluster's worker processes start: ``fork`` on Linux, else ``spawn``.

    A spawned worker is a fresh interpreter: it imports hammesh (numba, scipy, every
    kernel module) and loads its compiled kernels again, ~3 s quiet, ~20 s for two
    workers under load, and its nanny takes ~4 s to stop it. A forked worker starts
    with the driver's modules and kernels already in memory (measured loaded on this
    2-core VM: cluster start + kernels 2.5 s instead of 28 s, close 0.3 s instead of 4.4 s).
    macOS's fork is unsafe with system frameworks: spawn there.
    """
    import sys

    return "fork" if sys.platform.startswith("linux") else "spawn"


@contextlib.contextmanager
def runner_for(*, workers: int | None = None, client=None, scheduler: str | None = None,
               mode: str | None = None, background: bool = False,
               ready: threading.Event | None = None) -> Iterator[tuple[object, int]]:
    """``(runner, n_workers)``: a Dask client (given, connected to ``scheduler``, or a
    local cluster of ``workers`` processes started here and closed on exit), or the
    in-process :class:`~hammesh.parallel.run.LocalRunner` when none is asked for.

    ``mode``: load that Hamiltonian mode's compiled kernels in this process before a
    local cluster forks its workers (:func:`start_method`), so they start with them.
    ``background``: a local cluster starts in a thread of its own while the caller goes
    on (reading and splitting the domain: the cluster's start, ~1 s, and the driver's
    decomposition then overlap); the runner is then a :class:`Starting` handle whose
    first use waits for the start. ``ready`` (with ``background``): the starting thread
    imports Dask, then waits until the caller sets it before it forks the workers (the
    caller sets it once its own imports are done: a fork in the middle of another
    thread's import would leave that module half made and locked in the workers); set
    on the way out in any case.
    """
    if isinstance(client, Starting):  # a local cluster the caller started in the background
        yield client, client.n_workers
        return
    if client is not None:
        yield client, max(1, len(client.scheduler_info().get("workers", {})))
        return
    if scheduler is not None:
        distributed = _distributed()
        with distributed.Client(scheduler) as c:
            yield c, max(1, len(c.scheduler_info().get("workers", {})))
        return
    if workers is None:
        from hammesh.parallel.run import LocalRunner

        yield LocalRunner(), 1
        return
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidOptionError(f"workers must be a positive integer, got {workers!r}")
    if not dask_installed():
        raise InvalidOptionError(DASK_MISSING)
    if not background:
        with contextlib.ExitStack() as stack:
            yield _start_local(stack, workers, mode), workers
        return
    from concurrent.futures import ThreadPoolExecutor

    with contextlib.ExitStack() as stack, ThreadPoolExecutor(1, thread_name_prefix="hammesh-cluster") as pool:
        submitting = threading.Event()
        started = pool.submit(_start_local, stack, workers, mode, FORK_AFTER_IMPORTING, ready, submitting)
        failed = False
        try:
            yield Starting(started, workers, submitting), workers
        except BaseException:
            failed = True
            raise
        finally:
            if ready is not None:
                ready.set()  # (the caller failed before its imports were done: the start goes on, then closes)
            # the cluster is closed (by the stack) only once it is up; a start that
            # failed is reported unless the caller's own error is on its way
            try:
                started.result()
            except BaseException:
                if not failed:
                    raise


#: modules the driver imports while it decomposes (scipy.spatial: its KD-tree): a
#: cluster starting beside it imports them before it forks, so that no fork happens in
#: the middle of the driver's import of one (a child would inherit that module half
#: initialised, its import lock held by a thread the child does not have). (``hammesh
#: mesh`` also reads the domain meanwhile: it imports what that needs first, and the
#: reading's own imports are numba's, made under its compiler lock, which the fork
#: holds: :func:`_hold_numba_lock_across_fork`.)
FORK_AFTER_IMPORTING = ("scipy.spatial",)


#: Dask settings of a local cluster this command starts: no statistical profiler
#: (every worker sampled every thread's stack each 10 ms), no GIL monitor, the event
#: loop's watchdog tick and the system and memory monitors at 1-2 s instead of
#: 20-500 ms. They feed the dashboard, which a local cluster here does not serve.
#: Measured on this 2-core VM (two workers, one CPU-bound task each): the task's
#: process used 15 % more CPU than its thread (1.28 -> 1.48 s) with Dask's defaults,
#: 1.5 % with these; the idle cluster 0.11 CPU s per second against 0.014.
QUIET_CLUSTER = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.gil.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
}


#: seconds a local cluster's start may take (each worker process's start, the client's
#: connection, the workers' setup) before it fails with :class:`~hammesh.errors.ClusterError`
#: instead of waiting for ever: a forked worker that inherited a lock held by another
#: thread of the driver would never start (seen once under pytest-xdist)
START_TIMEOUT = 120.0


#: Dask's scheduler sends a worker its next tile only when it is free (root tasks
#: queued on the scheduler, ``worker-saturation`` 1.0; Dask's default 1.1 sends each
#: one-thread worker two at once, fixing which worker runs which tile up front): with
#: more tiles than workers (:func:`~hammesh.parallel.run.default_tiles`) a worker done
#: early takes the next tile instead of idling while another still has two.
TILE_QUEUE = {"distributed.scheduler.worker-saturation": 1.0}


def _start_local(stack: contextlib.ExitStack, workers: int, mode: str | None, modules: tuple = (),
                 ready: threading.Event | None = None, submitting: threading.Event | None = None):
    """Start a local cluster of ``workers`` processes and its client, both closed by
    ``stack`` (Dask imported first; then, if given, wait for ``ready``; ``modules``
    imported before the fork, see :data:`FORK_AFTER_IMPORTING`). ``submitting``: set
    once the caller has its tiles to submit; then no :func:`prefault` task is queued
    before them."""
    import importlib
    import logging

    import dask

    distributed = _distributed()
    if ready is not None:
        ready.wait()
    for name in modules:
        importlib.import_module(name)
    _hold_numba_lock_across_fork()
    method = start_method()
    if mode is not None and method == "fork" and KERNELS_BEFORE_FORK:
        load_worker_kernels(mode)
    # one process per worker, one thread each: Triangle and the kernels hold their core;
    # Dask's shutdown chatter (nanny warnings) is not the user's business
    with dask.config.set({"distributed.worker.multiprocessing-method": method, **QUIET_CLUSTER, **TILE_QUEUE}):
        # no dashboard; the scheduler's HTTP server on a free local port (its default,
        # 8787, warns on stderr when another cluster has it)
        # (death_timeout: a nanny whose worker process is not up by then kills it and
        # fails the start, which the stack then closes)
        try:
            cluster = stack.enter_context(distributed.LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                # (CRITICAL: a worker's "failed to communicate with scheduler during heartbeat"
                # ERROR and its 30-line traceback raced the shutdown of a successful run, 1 in
                # ~20; a task's failure reaches the driver through its future, not the log)
                silence_logs=logging.CRITICAL, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                death_timeout=START_TIMEOUT))
            # (closed by the stack, not entered as a context: a client entered in the starting
            # thread could not be left in the caller's, its "current client" is per context)
            c = distributed.Client(cluster, timeout=START_TIMEOUT)
            stack.callback(c.close)
            _local_clients.append((c, workers))
            stack.callback(_local_clients.remove, (c, workers))
            # the workers share this machine's cores: each threaded pass of a worker gets its
            # share, not every core (N workers x C threads on C cores only thrash)
            kept = c.run(worker_setup, worker_threads(workers), callback_timeout=START_TIMEOUT)
            if mode is not None and not (method == "fork" and KERNELS_BEFORE_FORK):
                # each worker loads its kernels itself, first of its tasks, on its own core
                # (the futures are held until the cluster closes)
                loading = [c.submit(load_worker_kernels, mode, workers=[addr], allow_other_workers=False,
                                    pure=False, priority=1 << 21) for addr in kept]
                stack.callback(loading.clear)
            # (only while the driver is still decomposing: once its tiles are ready the
            # prefault would only delay them, session 16)
            if PREFAULT and kept and all(kept.values()) and not (submitting is not None and submitting.is_set()):
                # a task on each worker (its executor's thread: the tiles' arena), not
                # waited for: the workers fault their memory in while the driver decomposes
                # (the futures are held until the cluster closes: Dask drops a task nobody holds)
                held = [c.submit(prefault, PREFAULT_MB << 20, workers=[addr], allow_other_workers=False,
                                 pure=False, priority=1 << 20) for addr in kept]
                stack.callback(held.clear)
        except (TimeoutError, OSError) as exc:  # (asyncio's and Dask's timeouts are TimeoutError)
            raise ClusterError(f"the local Dask cluster of {workers} workers did not start within "
                               f"{START_TIMEOUT:g} s ({type(exc).__name__}: {exc})") from exc
    return c


#: a local cluster's forked workers start with the mode's kernels loaded by the driver
#: before the fork (:func:`load_worker_kernels` in the cluster's thread); False: the
#: driver forks without them and each worker loads them in a task of its own, queued
#: before the tiles
KERNELS_BEFORE_FORK = True


def load_worker_kernels(mode: str) -> None:
    """Load the compiled kernels a tile's task runs (``hamiltonian()``'s of ``mode``,
    the lattice's) into this process."""
    from hammesh.parallel.tile_mesh import load_tile_kernels
    from hammesh.postprocess import load_kernels

    load_kernels(mode)
    load_tile_kernels()  # (the lattice's: each worker loaded them in its first tile, ~0.25 s CPU)


#: when fewer tiles are left running than a local cluster has workers, the workers'
#: threads per pass are raised to the cores over the tiles left (:func:`set_threads`,
#: ``run.run_tiles``), and set back before the pieces; False: the share stays fixed
TAIL_THREADS = True

_local_clients: list = []  # (the clients of the local clusters started here, while they live)


def local_workers(runner) -> int | None:
    """The worker count of a local cluster this process started (``runner``: its
    client, or a :class:`Starting` handle), None for any other runner: only there do
    the workers share this machine's cores in the way :func:`worker_threads` assumes."""
    if isinstance(runner, Starting):
        return runner.n_workers
    for c, n in _local_clients:
        if c is runner:
            return n
    return None


def set_threads(n: int) -> int | None:
    """On a worker: cap its threads per pass at ``n`` (:func:`hammesh.threads.limit`);
    run by ``Client.run`` in the worker's event loop, beside a running tile task,
    whose next passes take it (a pass reads the cap when it starts)."""
    from hammesh import threads

    return threads.limit(int(n))


def worker_setup(n_threads: int) -> bool:
    """On a local cluster's worker: cap its threads per pass at ``n_threads``
    (:func:`hammesh.threads.limit`), keep freed memory for reuse
    (:func:`retain_freed_memory`; returns its answer) and collect garbage again if
    the driver forked it while its start paused the collector (:func:`resume_gc`)."""
    from hammesh import threads

    resume_gc()
    threads.limit(n_threads)
    if NO_HUGEPAGE_ADVICE:
        no_hugepage_advice()
    return retain_freed_memory()


#: ``hammesh mesh --workers`` pauses Python's garbage collector over its serial start
#: (:func:`pause_gc`)
PAUSE_GC = True
_gc_paused = False


def pause_gc() -> None:
    """Pause Python's cyclic garbage collector until :func:`resume_gc` (the command's
    serial start: its imports, Dask's, the mode's kernels, the cluster's start).

    Why: the start allocates some million container objects (modules, numba's types
    and compiled libraries, Dask's configuration) and keeps nearly all of them, and
    the collector runs every ~700 allocations, its older generations scanning what
    the start has made so far again and again for cycles that are not there.
    Measured in one process (imports + Dask + the sparse kernels, three alternating
    rounds, load ~3): 1.65-1.74 s CPU with the collector, 1.25-1.50 s without
    (session 19); the driver's start is serial up to the tiles' submission. The
    processes forked meanwhile inherit the pause: the workers end it in
    :func:`worker_setup`, the decomposition's child exits within its task.
    (The ``gc`` module's documentation advises ``gc.freeze`` after such a start.)
    """
    global _gc_paused
    import gc

    if gc.isenabled():
        gc.disable()
        _gc_paused = True


def resume_gc() -> None:
    """End :func:`pause_gc`'s pause (nothing if this process did not pause): what the
    start made moves to the permanent generation (``gc.freeze``: never scanned again,
    nor copied into a forked child by a scan), then the collector runs as before."""
    global _gc_paused
    import gc

    if _gc_paused:
        _gc_paused = False
        gc.freeze()
        gc.enable()


#: ``hammesh mesh --workers`` drops numba's event hooks on llvmlite's lock in its
#: process (:func:`quiet_llvm_lock`) before its kernels load
QUIET_LLVM_LOCK = True


def quiet_llvm_lock() -> int:
    """Drop numba's event hooks on llvmlite's lock in this process (and the processes
    it forks later); returns how many were dropped (0 where llvmlite keeps them
    elsewhere: nothing done).

    Why: loading a compiled kernel from numba's cache makes some 230 calls into LLVM
    (parsing the kernel's bitcode, listing the symbols it defines), each taking
    llvmlite's lock, and numba hooks two events on every take and release of that
    lock (``numba:llvm_lock``, ``numba.core.base``): Python objects made and
    broadcast to no listener, ~8 us a call. The mode's kernels loaded before the
    workers fork are on the command's serial start: measured (the sparse mode's 81
    kernels and the lattice's, fresh processes, three alternating rounds, load ~4):
    0.68-0.83 s CPU with the hooks, 0.52-0.64 s without. Their one use is the lock's
    time in a dispatcher's compile metadata (``get_metadata()['timers']``), which is
    then 0; nothing else listens. Not done for a Python caller's process.
    """
    try:
        import numba.core.base  # noqa: F401  (registers the hooks at its import)
        from llvmlite.binding import ffi

        hooks = list(ffi.lib._lock._cblist)
    except (ImportError, AttributeError):
        return 0
    dropped = 0
    for acquire, release in hooks:
        if getattr(acquire, "__module__", None) == "numba.core.base":
            ffi.unregister_lock_callback(acquire, release)
            dropped += 1
    return dropped


#: a local cluster's workers fault in ``PREFAULT_MB`` of heap at their start (:func:`prefault`)
PREFAULT = True
#: about one 1M-triangle tile task's peak beyond the worker's own ~300 MB (sparse mode)
PREFAULT_MB = 384
#: in blocks of this size: a thread's glibc arena maps a bigger one apart and unmaps it when freed
PREFAULT_BLOCK_MB = 48


def prefault(nbytes: int) -> None:
    """Touch ``nbytes`` of fresh heap once (blocks of ``PREFAULT_BLOCK_MB``) and free it:
    with :func:`retain_freed_memory` the pages stay in this thread's arena for the
    first tile's arrays.

    Why: a worker's first tile ran 0.15-0.2 s longer than its later ones (session 13,
    6M sparse: the kernel zeroing and mapping each page on first touch); the workers
    are idle while the driver decomposes the domain (0.3-0.5 s), so they take those
    faults then, not on the tiles' critical path. Session 16: only while the driver
    is still decomposing (:meth:`Starting.tiles_coming`): at 6M the local cluster was
    up 0.5-0.7 s after the decomposition (loaded), the prefault task then ran first and
    the first tile started 0.6-1.0 s after its submission (none without it: interleaved,
    whole CPU the same). Submitted
    right after :func:`worker_setup` (only where glibc keeps freed memory), as a task:
    the tiles' tasks run in the same thread of the worker's executor, hence the same arena.
    """
    import numpy as np

    step = PREFAULT_BLOCK_MB << 20
    blocks = []
    for _ in range(max(1, int(nbytes) // step)):
        blocks.append(np.empty(step, np.uint8))
        blocks[-1][::4096] = 1  # one write per page faults it in
    del blocks


#: a local cluster's workers ask numpy not to advise huge pages (:func:`no_hugepage_advice`)
NO_HUGEPAGE_ADVICE = True


def no_hugepage_advice() -> bool:
    """Stop numpy advising huge pages (``madvise(MADV_HUGEPAGE)``) for its big arrays
    in this process; returns whether it had been on (False where numpy has no switch).

    Why: numpy advises huge pages for every array of 4 MB or more, and where the
    kernel's transparent huge pages are ``defrag = madvise`` (this VM; a common
    default), a first touch of such an array may compact memory synchronously to find
    a 2 MB page. A worker's tile touches ~0.6 GB of fresh arrays in its mesh step
    alone: measured on the 6M demo's first 3M tile, first ``mesh_tile`` in a fresh
    process, 1.18-2.42 s thread CPU (system 0.65-1.89 s, varying with the machine's
    memory state) with the advice against 0.93-1.08 s (system 0.38-0.45 s) without
    it, the same user time. numpy's own switch (``NUMPY_MADVISE_HUGEPAGE=0`` at its
    import; the workers are forked after it, hence the call).
    """
    try:
        from numpy._core.multiarray import _set_madvise_hugepage
    except ImportError:  # (numpy 1.x spells it numpy.core)
        try:
            from numpy.core.multiarray import _set_madvise_hugepage
        except ImportError:
            return False
    return bool(_set_madvise_hugepage(False))


#: glibc ``mallopt`` parameters (malloc.h)
_M_TRIM_THRESHOLD, _M_MMAP_MAX, _M_ARENA_MAX = -1, -4, -8
#: ``hammesh mesh --workers`` makes its process use one glibc arena before any thread
#: starts (:func:`single_arena`), so that its forked workers' task threads do too
SINGLE_ARENA = True


def single_arena() -> bool:
    """Make every thread of this process (and of the processes it forks) allocate from
    glibc's main arena (``mallopt(M_ARENA_MAX, 1)``); True if glibc agreed.

    Why: Dask runs each task in a thread of the worker's executor, and a thread's own
    arena serves a block too big for its 64 MB heaps by ``mmap`` whatever
    ``M_MMAP_MAX`` says, and unmaps it when freed (glibc's ``sysmalloc``), so
    :func:`retain_freed_memory` kept none of the tiles' big arrays: every one faulted
    its pages in again (measured in a local cluster's workers: 24k page faults per
    100 MB array, every time; with one arena, none after the first, in the next
    tasks too). A forked child gets its parent's arenas (all but the forking
    thread's on the free list, which new threads take first), so it must be set in
    the driver before its first thread: the command does it before the cluster's
    thread starts. Not done for a Python caller's process (it is theirs: one arena
    for all its threads is a process-wide choice).
    """
    import ctypes
    import ctypes.util
    import sys

    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL(ctypes.util.find_library("c") or None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(mallopt(_M_ARENA_MAX, 1))


def retain_freed_memory() -> bool:
    """Make glibc's ``malloc`` keep the memory this process frees, for its next
    allocations, instead of giving it back to the system; True if it agreed.

    Why: a tile's task allocates and frees a few GB in big blocks (Triangle's run, its
    output arrays, ``hamiltonian()``'s arrays and certificate, the piece's chunks).
    glibc serves every block above its mmap threshold (at most 32 MiB) with a fresh
    ``mmap`` and unmaps it when freed, so each new array faults its pages in again
    (zeroed by the kernel): on a 3M-triangle incircle tile, 1.2-1.5 s of system
    time and ~400k page faults (measured, one tile in one process). With mmap off
    (``M_MMAP_MAX`` 0) and no trimming of the heap's top (``M_TRIM_THRESHOLD``), the
    freed blocks are reused: 0.76-0.84 s and ~313k faults (those left are the first
    touches of the task's peak), the same user time. (glibc's ``mallopt(3)``;
    the same settings as ``MALLOC_MMAP_MAX_=0 MALLOC_TRIM_THRESHOLD_=...``.)

    Only for a worker process that lives for the tiles' tasks: its memory stays at its
    peak until it exits (a local cluster's workers exit with the command). A no-op
    (False) where the C library has no ``mallopt`` (not glibc).
    """
    import ctypes
    import ctypes.util
    import sys

    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    # (Dask runs every task in a thread of its executor, whose own glibc arena serves
    # a block too big for its 64 MB heaps by mmap whatever M_MMAP_MAX says, and unmaps
    # it when freed: measured in a thread, 24k page faults per 100 MB array every
    # time, 0 after the first at 50 MB and below. A 1M-triangle tile's arrays are
    # below that; M_ARENA_MAX set here comes too late, the thread has its arena)
    return bool(mallopt(_M_MMAP_MAX, 0)) and bool(mallopt(_M_TRIM_THRESHOLD, 2**31 - 1))


class Starting:
    """A Dask client still starting in another thread: any use (``submit``,
    ``gather``, ...) waits until it is up (or raises the start's error).
    ``n_workers``: the workers it starts, known at once."""

    def __init__(self, future, n_workers: int, submitting: threading.Event | None = None) -> None:
        self._future = future
        self.n_workers = n_workers
        self._submitting = submitting

    def started(self) -> bool:
        """Whether the start is over (up, or failed)."""
        return self._future.done()

    def tiles_coming(self) -> None:
        """The caller has its tiles to submit: the starting thread queues no
        :func:`prefault` before them (a worker faults its memory in only while the
        driver is still decomposing; once the tiles are ready it would delay them)."""
        if self._submitting is not None:
            self._submitting.set()

    def __getattr__(self, name: str):
        return getattr(self._future.result(), name)


_fork_guarded = False
_fork_guard_lock = threading.Lock()


def guard_forks() -> None:
    """Make every later ``os.fork`` of this process wait while another thread is inside
    numba's compiler or writes a log record (:func:`_hold_numba_lock_across_fork`):
    before forking a child beside the cluster's start (:mod:`hammesh.parallel.forked`)."""
    _hold_numba_lock_across_fork()


def _hold_numba_lock_across_fork() -> None:
    """Fork only while no thread is inside numba's compiler (``global_compiler_lock``).

    A forked child has only the forking thread: a lock another thread held at the
    fork stays held in the child forever, and numba takes that lock to compile or to
    load a kernel from its cache. With the cluster starting in a thread while the
    driver decomposes (and may load a kernel), the fork therefore waits for the lock
    and the child releases its copy (the standard ``os.register_at_fork`` pattern).
    Logging's handlers likewise (:func:`_take_log_handlers`).
    """
    global _fork_guarded
    import os

    from numba.core.compiler_lock import global_compiler_lock

    with _fork_guard_lock:  # (the main thread and the cluster's may both ask: hooks once)
        if _fork_guarded:
            return
        os.register_at_fork(before=global_compiler_lock.acquire, after_in_parent=global_compiler_lock.release,
                            after_in_child=global_compiler_lock.release)
        os.register_at_fork(before=_take_log_handlers, after_in_parent=_give_log_handlers,
                            after_in_child=_give_log_handlers)
        _fork_guarded = True


_held_handlers: list = []


def _take_log_handlers() -> None:
    """Before a fork: take every logging handler's lock, so that no thread is in the
    middle of writing a record. Dask forks its workers from a thread of its own while
    the scheduler's thread logs; logging renews its handlers' locks in the child, but
    not the lock of the stream a handler was writing to (a file's buffer): a child
    forked mid-write hangs at its first log line (seen under pytest, whose handlers
    take every record). A thread emits through one handler at a time, so taking them
    in turn cannot deadlock."""
    import logging

    for ref in list(getattr(logging, "_handlerList", [])):
        h = ref()
        if h is not None and getattr(h, "lock", None) is not None:
            h.lock.acquire()
            _held_handlers.append(h)


def _give_log_handlers() -> None:
    while _held_handlers:
        try:
            _held_handlers.pop().lock.release()
        except RuntimeError:  # (a child: logging renewed that lock already)
            pass


def worker_threads(workers: int) -> int:
    """Threads per pass for each of ``workers`` local worker processes: their share of the cores."""
    import os

    return max(1, (os.cpu_count() or 1) // max(1, workers))
