"""``hammesh.pages.fresh``: arrays faulted in ahead, in small pages (issue 11, first call)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from hammesh.pages import fresh


@pytest.mark.parametrize("shape, dtype, fill", [((1000, 3), np.int64, 0), (5_000_000, np.int32, -2),
                                                ((7,), np.int8, None), (0, np.float64, 1.5)])
def test_fresh_has_the_shape_dtype_and_fill(shape, dtype, fill) -> None:
    a = fresh(shape, dtype, fill)
    assert a.shape == np.empty(shape).shape and a.dtype == dtype and a.flags.c_contiguous
    if fill is not None:
        assert (a == fill).all()


def _vma(addr: int) -> dict[str, str]:
    """The /proc/self/smaps entry of the mapping holding ``addr``."""
    entry: dict[str, str] = {}
    inside = False
    with open("/proc/self/smaps") as f:
        for line in f:
            head = line.split()[0]
            if "-" in head and not head.endswith(":"):
                lo, hi = (int(x, 16) for x in head.split("-"))
                if inside:
                    break
                inside = lo <= addr < hi
                continue
            if inside:
                key, _, value = line.partition(":")
                entry[key] = value.strip()
    return entry


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="madvise and /proc/self/smaps are Linux's")
def test_fresh_pages_are_small_and_resident_before_any_write() -> None:
    """64 MB without a fill: resident already (populated by the kernel), advised
    ``nohugepage`` (VmFlags ``nh``), no huge page in the range."""
    a = fresh(8 << 20, np.int64)
    vma = _vma(a.ctypes.data + a.nbytes // 2)
    assert "nh" in vma["VmFlags"].split()
    assert int(vma["AnonHugePages"].split()[0]) == 0
    assert int(vma["Rss"].split()[0]) * 1024 >= 0.99 * a.nbytes
