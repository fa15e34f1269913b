"""Run a C mesher in a child process, so that no input can take the caller down.

Triangle and meshpy can crash the interpreter (SIGSEGV) or loop forever on inputs
that slip past validation. ``run_isolated`` forks a child (on platforms with
``fork``; else spawns one), lets it compute, and hands the result back. A crash
becomes :class:`~hammesh.errors.MeshingError` naming the signal, an overrun of
``timeout`` kills the child, and the child dies with its parent (Linux:
``PR_SET_PDEATHSIG``; elsewhere a thread watching the parent's pipe).

The result's arrays do not go through the pipe. Before the fork the parent makes an
anonymous memory file (``memfd_create``); the child allocates its big output arrays
in that file (:class:`SharedArena`, handed to ``func`` as ``alloc``) and copies any
other array there, and sends only a small pickle (protocol 5, the arrays out of
band) naming where each array lies. The parent maps the file once, closes it, and
the arrays become views of the mapping, without a copy; it is unmapped when the last
of them is gone. The file has no name (nothing in ``/dev/shm`` can be left behind)
and the kernel frees it when the last descriptor and mapping are gone: on a crash, a
timeout or a kill of either process alike. Without
``memfd_create`` or ``fork`` the result is pickled through the pipe as before.
"""

from __future__ import annotations

import ctypes
import faulthandler
import math
import mmap
import multiprocessing as mp
import os
import pickle
import signal
import sys
import tempfile
import threading
import warnings
import weakref
from typing import Any, Callable

import numpy as np

from hammesh.errors import HammeshError, MeshingError

__all__ = ["run_isolated", "SharedArena", "SHARED_MEMORY", "limit_memory", "MEMORY_FRACTION"]

#: Whether results come back through shared memory (Linux and other systems with
#: ``memfd_create`` and ``fork``); else they are pickled through a pipe.
SHARED_MEMORY = hasattr(os, "memfd_create") and "fork" in mp.get_all_start_methods()

#: Arrays smaller than this are neither allocated in the file nor copied to it: they
#: travel inside the pickle (a page-aligned block per tiny array would cost more, and
#: the parent would keep the whole mapping alive for a small array it still holds).
ARENA_MIN_BYTES = 1 << 16

_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


class SharedArena:
    """Arrays allocated in a memory file that the parent process maps afterwards.

    Each array of at least ``ARENA_MIN_BYTES`` gets its own page-aligned block of
    the file (the file grows with ``ftruncate``); smaller ones are ordinary arrays.
    :meth:`place` tells where a buffer lies in the file, copying it to the end of
    the file if it is not one of the blocks.

    Parameters
    ----------
    fd : int
        A memory file (``os.memfd_create``) shared with the parent.
    """

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.size = 0
        self._blocks: list[tuple[int, int, int]] = []  # (address, bytes, offset in file)

    def _grow(self, nbytes: int) -> int:
        off = self.size
        self.size = off + -(-max(nbytes, 1) // mmap.PAGESIZE) * mmap.PAGESIZE
        _extend(self.fd, off, self.size - off)
        return off

    def empty(self, shape: int | tuple[int, ...], dtype: Any = np.float64) -> np.ndarray:
        """Like ``np.empty``, in the shared file if the array is big."""
        shape = (shape,) if isinstance(shape, (int, np.integer)) else tuple(shape)
        dt = np.dtype(dtype)
        count = math.prod(shape)
        nbytes = count * dt.itemsize
        if nbytes < ARENA_MIN_BYTES:
            return np.empty(shape, dt)
        off = self._grow(nbytes)
        block = mmap.mmap(self.fd, nbytes, offset=off)
        arr = np.frombuffer(block, dtype=dt, count=count).reshape(shape)
        self._blocks.append((arr.ctypes.data, nbytes, off))
        return arr

    def place(self, buf: memoryview) -> tuple[int, int]:
        """``(offset, length)`` of the bytes of ``buf`` in the file (copied if needed)."""
        n = buf.nbytes
        if n == 0:
            return 0, 0
        addr = np.frombuffer(buf, dtype=np.uint8).ctypes.data
        for start, size, off in self._blocks:
            if start <= addr and addr + n <= start + size:
                return off + (addr - start), n
        off = self._grow(n)
        done = 0
        while done < n:  # one write is capped at ~2 GiB
            done += os.pwrite(self.fd, buf[done:], off + done)
        return off, n


def _extend(fd: int, offset: int, length: int) -> None:
    """Make ``fd`` hold the bytes ``offset .. offset + length``, never shrinking it.

    ``posix_fallocate`` allocates the pages in one call (those the parent allocated
    ahead, ``run_isolated(prefault=)``, are kept as they are) and never cuts the file,
    which the parent may be growing at the same time; ``ftruncate`` where it is missing.
    """
    if hasattr(os, "posix_fallocate"):
        try:
            os.posix_fallocate(fd, offset, length)
            return
        except OSError:  # (a file system without it: grow as before)
            pass
    if os.fstat(fd).st_size < offset + length:
        os.ftruncate(fd, offset + length)


def _allocate_ahead(fd: int, nbytes: int) -> None:
    """Allocate the first ``nbytes`` of the result file now (a thread of the parent)."""
    try:
        os.posix_fallocate(fd, 0, nbytes)
    except (OSError, AttributeError):  # optional: the child allocates what it uses
        pass


#: The child's address space is capped at what it has at the start plus this share of the
#: memory the machine has available (``MemAvailable``): a runaway refinement (Triangle
#: splitting a sliver without end took ~20 GB on a 24 GB machine) then fails in the child
#: ("out of memory") instead of taking the machine into swap or the OOM killer.
MEMORY_FRACTION = 0.9


def _proc_kb(path: str, key: str) -> int:
    """A ``key:   <n> kB`` line of ``/proc/...`` in kB."""
    with open(path) as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    raise ValueError(f"{key} not in {path}")


def limit_memory(fraction: float | None = None, *, extra: int | None = None) -> int | None:
    """Cap this process's address space (``RLIMIT_AS``) at its size now plus ``fraction``
    (default :data:`MEMORY_FRACTION`) of the available memory, or plus ``extra`` bytes;
    the limit set, or None where there is no ``/proc`` or ``resource`` (not Linux), or a
    tighter one is set."""
    try:
        import resource

        share = MEMORY_FRACTION if fraction is None else fraction
        more = int(share * _proc_kb("/proc/meminfo", "MemAvailable") * 1024) if extra is None else int(extra)
        limit = _proc_kb("/proc/self/status", "VmSize") * 1024 + more
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        if hard != resource.RLIM_INFINITY:
            limit = min(limit, hard)
        if soft != resource.RLIM_INFINITY and soft <= limit:
            return None
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
        return limit
    except (ImportError, OSError, ValueError):
        return None


def _die_with_parent() -> None:
    """Make sure this child cannot outlive the process that forked it.

    Linux: the kernel sends SIGKILL when the parent's forking thread ends (also when
    the child is inside C code that holds the GIL). Elsewhere a daemon thread waits
    for the end of the parent's pipe (works while the child runs Python or C code
    that released the GIL).
    """
    parent = mp.parent_process()
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):
            pass
        # the parent may have died before prctl: then the signal will never come
        if parent is not None and os.getppid() != parent.pid:
            os._exit(1)
    elif parent is not None and parent.sentinel is not None:
        from multiprocessing.connection import wait

        def watch() -> None:
            wait([parent.sentinel])
            os._exit(1)

        threading.Thread(target=watch, daemon=True).start()


def _c_output(log: Any) -> str:
    """The last line the C code printed (Triangle explains failures on stdout)."""
    try:
        log.flush()
        log.seek(0)
        lines = [ln.strip() for ln in log.read().decode(errors="replace").splitlines()]
        lines = [ln for ln in lines if ln]
        return " | ".join(lines[-3:])
    except OSError:
        return ""


def _child(conn: Any, func: Callable[..., Any], args: tuple[Any, ...], fd: int | None, alloc: bool,
           log: Any = None) -> None:
    _die_with_parent()
    limit_memory()
    # the C library prints to file descriptors 1/2 directly: keep that out of the
    # caller's terminal and use it to explain a failure instead (``log``: the parent's
    # file when forked, so that it can read why a child ended without an answer)
    faulthandler.disable()  # a crash is reported by the parent (signal name), not dumped
    log = tempfile.TemporaryFile() if log is None else log
    os.dup2(log.fileno(), 1)
    os.dup2(log.fileno(), 2)
    try:
        if fd is None:
            conn.send(("ok", func(*args, alloc=np.empty) if alloc else func(*args)))
        else:
            arena = SharedArena(fd)
            result = func(*args, alloc=arena.empty) if alloc else func(*args)
            buffers: list[pickle.PickleBuffer] = []

            def out_of_band(buf: pickle.PickleBuffer) -> bool:
                # small arrays travel in the pickle: they must not keep the mapping alive
                if buf.raw().nbytes < ARENA_MIN_BYTES:
                    return True
                buffers.append(buf)
                return False

            head = pickle.dumps(result, protocol=5, buffer_callback=out_of_band)
            spans = [arena.place(b.raw()) for b in buffers]
            conn.send(("shared", head, spans, arena.size))
    except HammeshError as exc:  # keep hammesh's own errors as they are
        conn.send(("hammesh", exc))
    except BaseException as exc:  # noqa: BLE001 - reported to the parent, one line
        said = _c_output(log)
        conn.send(("error", f"{type(exc).__name__}: {exc}" + (f" ({said})" if said else "")))
    finally:
        conn.close()


def _quietly(work: Callable[[], Any]) -> None:
    try:
        work()
    except Exception:  # noqa: BLE001 - optional work; the caller's own call reports
        pass


def _reap(proc: Any) -> int | None:
    """Wait for a child that has answered or been killed; its exit code."""
    proc.join(5)
    if proc.is_alive():
        proc.kill()
        proc.join()
    return proc.exitcode


def _libc() -> ctypes.CDLL:
    libc = ctypes.CDLL(None, use_errno=True)
    libc.mmap.restype = ctypes.c_void_p
    libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_long]
    libc.munmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t]
    return libc


def _map_file(fd: int, size: int) -> memoryview:
    """Map ``size`` bytes of ``fd``, shared; unmapped when no array uses them anymore.

    Not ``mmap.mmap``: that keeps a duplicate of the descriptor open for as long as
    the mapping lives, one per mesh held (and processes have ~1024).
    """
    libc = _libc()
    flags = mmap.MAP_SHARED | getattr(mmap, "MAP_POPULATE", 0)  # one call maps it all
    addr = libc.mmap(None, size, mmap.PROT_READ | mmap.PROT_WRITE, flags, fd, 0)
    if addr in (None, ctypes.c_void_p(-1).value):
        err = ctypes.get_errno()
        raise MeshingError(f"cannot map the mesher's result ({size} bytes): {os.strerror(err)}")
    block = type("SharedResult", (ctypes.c_char * size,), {}).from_address(addr)
    done = weakref.finalize(block, libc.munmap, addr, size)
    done.atexit = False  # at exit the process goes anyway; arrays may still be in use
    return memoryview(block).cast("B")


def _unpack(fd: int, head: bytes, spans: list[tuple[int, int]], size: int) -> Any:
    """The child's result, its arrays mapped from the shared file (no copy)."""
    view = _map_file(fd, size) if size else memoryview(b"")
    return pickle.loads(head, buffers=[view[o : o + n] if n else bytearray() for o, n in spans])


def run_isolated(
    func: Callable[..., Any],
    args: tuple[Any, ...],
    *,
    name: str,
    timeout: float | None,
    alloc: bool = False,
    meanwhile: Callable[[], Any] | None = None,
    prefault: int = 0,
) -> Any:
    """Call ``func(*args)`` in a child process and return its result.

    Parameters
    ----------
    func : picklable callable (module-level function)
    args : tuple
    name : str
        What runs, for messages ("Triangle").
    timeout : float or None
        Seconds before the child is killed; None waits forever.
    alloc : bool
        Call ``func(*args, alloc=empty)`` with an ``np.empty``-like allocator whose
        arrays the parent receives without a copy (:class:`SharedArena`): let
        ``func`` allocate its big outputs with it.
    meanwhile : callable, optional
        Work for this process while the child computes, run in a thread started
        after the fork (so the child inherits no lock it holds); its result and
        errors are dropped (e.g. loading the kernels the caller needs next). The
        thread is not a daemon: the interpreter waits for it at exit, because a
        daemon thread still inside numba's compiler when the interpreter finalizes
        aborts the process (seen as SIGABRT after a script's last line).
    prefault : int
        Bytes of the result the child is expected to allocate (``alloc``): a thread of
        this process allocates them in the shared file while the child computes, so
        that the child, which the caller waits for, writes its arrays into pages that
        are there already (at 1.5 M triangles: ~95 MB, 0.05-0.1 s of the child's time
        on this project's VM, where a fresh page costs a host fault). The file is cut
        to what the child used before it is mapped. Ignored without shared memory.

    Raises
    ------
    MeshingError
        The child crashed, was killed, timed out or raised a non-hammesh error.
    HammeshError
        Re-raised as the child raised it.
    """
    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    ctx = mp.get_context(method)
    # anonymous, freed with its last descriptor or mapping; inherited by the fork
    fd = os.memfd_create("hammesh-result", getattr(os, "MFD_CLOEXEC", 0)) if SHARED_MEMORY else None
    ahead = None
    log = tempfile.TemporaryFile() if method == "fork" else None  # (the child's C output)
    try:
        recv, send = ctx.Pipe(duplex=False)
        proc = ctx.Process(target=_child, args=(send, func, args, fd, alloc, log), daemon=True)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)  # fork with threads (3.12+)
            proc.start()
        send.close()
        if fd is not None and alloc and prefault > 0 and hasattr(os, "posix_fallocate"):
            ahead = threading.Thread(target=_allocate_ahead, args=(fd, int(prefault)), name="hammesh-prefault",
                                     daemon=True)
            ahead.start()
        if meanwhile is not None:
            threading.Thread(target=_quietly, args=(meanwhile,), name="hammesh-meanwhile", daemon=False).start()
        msg = None
        try:
            if not recv.poll(timeout):
                raise MeshingError(f"{name} did not finish within {timeout:g} s and was stopped")
            try:
                msg = recv.recv()
            except (EOFError, OSError):  # the child ended without an answer
                pass
        except BaseException:  # the timeout, also Ctrl-C while waiting: the child goes
            proc.kill()
            _reap(proc)
            proc = None  # its pipe descriptors go now, not when the traceback goes
            raise
        finally:
            recv.close()
        if msg is None:
            code = _reap(proc)
            proc = None
            if code is not None and code < 0:
                try:
                    sig = signal.Signals(-code).name
                except ValueError:
                    sig = f"signal {-code}"
                raise MeshingError(f"{name} crashed ({sig}) on this input")
            said = _c_output(log) if log is not None else ""
            raise _failure(name, f"exited (code {code}) without a result" + (f": {said}" if said else ""))
        if msg[0] in ("shared", "ok"):
            # the child exits by itself now; its teardown (tens of ms for a big address
            # space) need not delay the caller: a daemon thread reaps it
            threading.Thread(target=_reap, args=(proc,), name="hammesh-reap", daemon=True).start()
        else:
            _reap(proc)
            proc = None
        if msg[0] == "shared":
            if ahead is not None:  # what was allocated ahead and not used goes now
                ahead.join()
                ahead = None
                os.ftruncate(fd, msg[3])
            return _unpack(fd, *msg[1:])
    finally:
        if ahead is not None:  # (it uses ``fd``: closed only after it)
            ahead.join()
        if fd is not None:
            os.close(fd)  # the mapping (if any) keeps the memory alive, nothing else
        if log is not None:
            log.close()
    if msg[0] == "ok":
        return msg[1]
    if msg[0] == "hammesh":
        raise msg[1]
    raise _failure(name, f"failed: {msg[1]}")


def _failure(name: str, what: str) -> MeshingError:
    """The error of a child that ended without a result; running out of memory (the
    address-space cap of :func:`limit_memory`, or the machine's) is said as such."""
    if "out of memory" in what.lower() or "memoryerror" in what.lower():
        return MeshingError(f"{name} ran out of memory ({what}): the mesh asked for needs more than this "
                            "machine has available (a larger max area; or a sliver Triangle refines without end)")
    return MeshingError(f"{name} {what}")
