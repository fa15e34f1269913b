"""Fresh arrays with their pages faulted in ahead, in small pages (Linux ``madvise``).

The first call of ``hammesh.hamiltonian`` at 1.5 M triangles writes ~600 MB of memory
the process has never used; on this project's VM a third of the call's CPU was the
kernel faulting those pages in (docs/benchmarks.md, "the first call"). Two things make
that cheaper, both measured there:

* *Small pages.* numpy advises transparent huge pages for every array of 4 MiB and
  more; with the machine's ``defrag=madvise`` policy a huge-page fault compacts memory
  first. Arrays written in sequence gain little from huge pages, so
  :func:`fresh` asks for 4 KiB pages (``MADV_NOHUGEPAGE``) on their range.
* *One populate call.* ``MADV_POPULATE_WRITE`` (Linux 5.14) faults the whole range
  in one system call instead of one trap per page; the pages come zeroed.

Both are hints: where ``madvise`` is missing or refuses, the array is touched by
writing it, as before.

*A reserve faulted while the machine waits* (:func:`reserve`). ``quality_mesh`` runs
Triangle in a child process and its parent only waits meanwhile: it loads the kernels
``hamiltonian()`` needs next and then faults in a reserve of pages sized for the mesh
it expects. :func:`fresh` takes its big arrays out of the reserve by ``mremap``, which
moves the pages (already there, zeroed) to a mapping of the array's own: no fault, no
copy, and each array still frees its memory when it dies, as any numpy array.
``hamiltonian()`` drops what is left when it returns (:func:`release`), and a reserve
nobody used is dropped after ``RESERVE_SECONDS``.

*For a construction* (the API): allocate each big array with :func:`fresh` in Python
(a numba kernel's own ``np.empty`` cannot take from the reserve: give the kernel its
output arrays, an ``_into`` kernel) and keep the reserve to what the construction
takes with :func:`trim` as it starts, so that pages it will not take are given back
at once rather than held to its end. ``hammesh.postprocess.RESERVE_TAKEN`` holds each
mode's bytes per input triangle (a mode that takes more arrays raises its entry; the
reserve ``quality_mesh`` faults is ``hammesh.meshing.RESERVE_BYTES_PER_TRIANGLE``).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import mmap
import sys
import threading
import weakref

import numpy as np

from hammesh import threads

__all__ = ["fresh", "advise", "reserve", "release", "reserved", "trim", "MADV_NOHUGEPAGE", "MADV_POPULATE_WRITE",
           "RESERVE_SECONDS", "RESERVE_MIN_ARRAY"]

MADV_NOHUGEPAGE = 15
MADV_POPULATE_WRITE = 23
_MREMAP_MAYMOVE = 1
_MAP_FAILED = ctypes.c_void_p(-1).value

#: a reserve nobody takes from is dropped after this many seconds
RESERVE_SECONDS = 60.0
#: arrays below this many bytes are never taken from the reserve (one mapping each)
RESERVE_MIN_ARRAY = 1 << 20

_PAGE = mmap.PAGESIZE
_libc = None
if sys.platform.startswith("linux"):  # (the advice numbers are Linux's)
    try:
        _libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        _libc.madvise.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int)
        _libc.madvise.restype = ctypes.c_int
        _libc.mmap.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                               ctypes.c_long)
        _libc.mmap.restype = ctypes.c_void_p
        _libc.munmap.argtypes = (ctypes.c_void_p, ctypes.c_size_t)
        _libc.munmap.restype = ctypes.c_int
        _libc.mremap.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t, ctypes.c_int)
        _libc.mremap.restype = ctypes.c_void_p
    except (OSError, AttributeError):  # no libc madvise: plain writes
        _libc = None


def advise(a: np.ndarray, advice: int) -> bool:
    """``madvise(advice)`` over the whole pages inside ``a``'s buffer (e.g. a prefix of a
    work array: :data:`MADV_NOHUGEPAGE`, :data:`MADV_POPULATE_WRITE`); True if the kernel
    agreed (False where ``madvise`` is missing: then nothing happens)."""
    if _libc is None or a.nbytes < 2 * _PAGE:
        return False
    addr = a.ctypes.data
    lo = (addr + _PAGE - 1) // _PAGE * _PAGE
    hi = (addr + a.nbytes) // _PAGE * _PAGE
    return hi > lo and _libc.madvise(lo, hi - lo, advice) == 0


class _Reserve:
    """Pages mapped and faulted in ahead; arrays are moved out of it from the front."""

    def __init__(self, addr: int, size: int) -> None:
        self.addr = addr
        self.size = size
        self.taken = 0  # bytes moved out (the front); the rest is still mapped here

    def take(self, nbytes: int) -> int | None:
        """Address of a new mapping of ``nbytes`` (pages moved out of the reserve)."""
        length = -(-nbytes // _PAGE) * _PAGE
        if self.taken + length > self.size:
            return None
        new = _libc.mremap(self.addr + self.taken, length, length, _MREMAP_MAYMOVE)
        if new is None or new == _MAP_FAILED:
            return None
        self.taken += length
        return new

    def trim(self, keep: int) -> None:
        """Unmap all but ``keep`` bytes (page-rounded) of what is left."""
        keep = -(-max(int(keep), 0) // _PAGE) * _PAGE
        if self.taken + keep < self.size:
            _libc.munmap(self.addr + self.taken + keep, self.size - self.taken - keep)
            self.size = self.taken + keep

    def drop(self) -> None:
        """Unmap what is left (never the front: other mappings may live there now)."""
        if self.taken < self.size:
            _libc.munmap(self.addr + self.taken, self.size - self.taken)
        self.taken = self.size


_lock = threading.Lock()
_reserve: _Reserve | None = None
_timer: threading.Timer | None = None


def reserve(nbytes: int) -> int:
    """Map ``nbytes`` of pages and fault them in now, for :func:`fresh` to take from later.

    Meant for a thread of a process that would otherwise only wait (``quality_mesh``
    while Triangle runs in its child). Replaces any earlier reserve. Returns the bytes
    reserved (0 where the system has no ``mremap``/``madvise``: nothing happens).
    """
    global _reserve, _timer
    release()
    if _libc is None or nbytes < RESERVE_MIN_ARRAY:
        return 0
    size = -(-int(nbytes) // _PAGE) * _PAGE
    prot = mmap.PROT_READ | mmap.PROT_WRITE
    addr = _libc.mmap(None, size, prot, mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS, -1, 0)
    if addr is None or addr == _MAP_FAILED:
        return 0
    _libc.madvise(addr, size, MADV_NOHUGEPAGE)
    if _libc.madvise(addr, size, MADV_POPULATE_WRITE) != 0:
        ctypes.memset(addr, 0, size)  # (kernels before 5.14: fault by writing)
    with _lock:
        if _reserve is not None:  # another thread reserved meanwhile: keep one
            _reserve.drop()
        _reserve = _Reserve(addr, size)
        _timer = threading.Timer(RESERVE_SECONDS, release)
        _timer.daemon = True
        _timer.start()
    return size


def release() -> None:
    """Drop what is left of the reserve (arrays already taken from it stay valid)."""
    global _reserve, _timer
    with _lock:
        if _reserve is not None:
            _reserve.drop()
        _reserve = None
        if _timer is not None:
            _timer.cancel()
        _timer = None


def trim(nbytes: int) -> int:
    """Keep at most ``nbytes`` of the reserve (those a construction will take), give the
    rest back now; returns the bytes left in it. Arrays already taken stay valid."""
    with _lock:
        if _reserve is None:
            return 0
        _reserve.trim(nbytes)
        return _reserve.size - _reserve.taken


def reserved() -> int:
    """Bytes still in the reserve."""
    with _lock:
        return 0 if _reserve is None else _reserve.size - _reserve.taken


def _from_reserve(nbytes: int) -> np.ndarray | None:
    """``nbytes`` of faulted, zeroed memory of its own mapping, or None."""
    if nbytes < RESERVE_MIN_ARRAY:
        return None
    with _lock:
        addr = None if _reserve is None else _reserve.take(nbytes)
    if addr is None:
        return None
    length = -(-nbytes // _PAGE) * _PAGE
    buf = (ctypes.c_char * length).from_address(addr)
    # the array's memory dies with it, given back on the background thread (``threads.later``:
    # off the caller's path)
    weakref.finalize(buf, threads.later, _libc.munmap, addr, length)
    return np.frombuffer(buf, np.uint8, nbytes)


def fresh(shape: int | tuple[int, ...], dtype: type, fill: int | float | None = None) -> np.ndarray:
    """A new array with its pages faulted in now (e.g. on a thread that has time).

    Taken from the reserve (:func:`reserve`) when there is one with room: then the
    pages are there already.

    Parameters
    ----------
    shape, dtype
        As ``np.empty``.
    fill : optional
        Value for every entry; None leaves the contents unspecified (a kernel that
        writes every entry).
    """
    dt = np.dtype(dtype)
    count = int(np.prod(shape, dtype=np.int64))
    raw = _from_reserve(count * dt.itemsize)
    if raw is not None:
        a = raw.view(dt).reshape(shape)
        if fill is not None and fill != 0:  # (the reserve's pages are zeroed)
            a.fill(fill)
        return a
    a = np.empty(shape, dtype)
    advise(a, MADV_NOHUGEPAGE)
    populated = advise(a, MADV_POPULATE_WRITE)
    if fill is not None:
        a.fill(fill)
    elif not populated and a.size:
        a.reshape(-1)[:: max(1, _PAGE // a.itemsize)] = 0  # one write per page
    return a
