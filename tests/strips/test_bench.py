"""benchmarks/bench_strips.py keeps running (tiny sizes; nothing here is timed or compared).

The timeouts are generous: at load 17 on two cores the --quick run took over 600 s.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).parent.parent.parent / "benchmarks" / "bench_strips.py"


@pytest.mark.slow
def test_bench_strips_quick_runs():
    proc = subprocess.run(
        [sys.executable, str(BENCH), "--quick", "--repeat", "1"], capture_output=True, text=True, timeout=1800
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    for needle in ("square a=1e-3", "Christofides (Thm 5.3)", "Lemma 5.1 (tree dual)", "Issue 16", "meshopt vcache", "in a fresh process"):
        assert needle in proc.stdout
    if importlib.util.find_spec("meshoptimizer") is not None:  # the peer of the cache target
        assert "cache target on" in proc.stdout


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("meshoptimizer") is None, reason="the speed target's peer is meshoptimizer")
def test_bench_strips_speed_quick_runs():
    proc = subprocess.run(
        [sys.executable, str(BENCH), "--speed", "--quick", "--repeat", "1"], capture_output=True, text=True, timeout=1800
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "q30 square 10k" in proc.stdout and "interleaved calls" in proc.stdout
    assert "fast 1st" in proc.stdout and "failed" not in proc.stdout
    assert "modes interleaved per round" in proc.stdout


@pytest.mark.slow
def test_bench_strips_cache_bound_quick_runs():
    proc = subprocess.run(
        [sys.executable, str(BENCH), "--cache-bound", "--quick"], capture_output=True, text=True, timeout=1800
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "same-direction rows of  6 quads" in proc.stdout and "snake in bands of  7 quads" in proc.stdout
    assert "method=zigzag" in proc.stdout


@pytest.mark.slow
def test_bench_strips_cache_table_quick_runs():
    proc = subprocess.run(
        [sys.executable, str(BENCH), "--cache-table", "--quick"], capture_output=True, text=True, timeout=1800
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "hammesh --cache 32 zigzag (FIFO order)" in proc.stdout and "q30 A 12k" in proc.stdout
    if importlib.util.find_spec("meshoptimizer") is not None:
        assert "target ACMR <=" in proc.stdout
