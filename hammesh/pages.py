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
"""

from __future__ import annotations

import ctypes
import ctypes.util
import mmap
import sys

import numpy as np

__all__ = ["fresh", "MADV_NOHUGEPAGE", "MADV_POPULATE_WRITE"]

MADV_NOHUGEPAGE = 15
MADV_POPULATE_WRITE = 23

_PAGE = mmap.PAGESIZE
_libc = None
if sys.platform.startswith("linux"):  # (the advice numbers are Linux's)
    try:
        _libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        _libc.madvise.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int)
        _libc.madvise.restype = ctypes.c_int
    except (OSError, AttributeError):  # no libc madvise: plain writes
        _libc = None


def _advise(a: np.ndarray, advice: int) -> bool:
    """``madvise`` over the whole pages inside ``a``'s buffer; True if the kernel agreed."""
    if _libc is None or a.nbytes < 2 * _PAGE:
        return False
    addr = a.ctypes.data
    lo = (addr + _PAGE - 1) // _PAGE * _PAGE
    hi = (addr + a.nbytes) // _PAGE * _PAGE
    return hi > lo and _libc.madvise(lo, hi - lo, advice) == 0


def fresh(shape: int | tuple[int, ...], dtype: type, fill: int | float | None = None) -> np.ndarray:
    """A new array with its pages faulted in now (e.g. on a thread that has time).

    Parameters
    ----------
    shape, dtype
        As ``np.empty``.
    fill : optional
        Value for every entry; None leaves the contents unspecified (a kernel that
        writes every entry).
    """
    a = np.empty(shape, dtype)
    _advise(a, MADV_NOHUGEPAGE)
    populated = _advise(a, MADV_POPULATE_WRITE)
    if fill is not None:
        a.fill(fill)
    elif not populated and a.size:
        a.reshape(-1)[:: max(1, _PAGE // a.itemsize)] = 0  # one write per page
    return a
