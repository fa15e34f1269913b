"""benchmarks/bench_scale.py keeps running (tiny sizes; nothing timed or compared)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).parents[2] / "benchmarks" / "bench_scale.py"


@pytest.mark.slow
@pytest.mark.parametrize("extra, needle", [([], "triangles (raw), CPU"),
                                           (["--partitioned-only"], "extrapolated from")])
def test_bench_scale_runs(extra, needle):
    pytest.importorskip("distributed")
    proc = subprocess.run([sys.executable, str(BENCH), "--sizes", "3e4", "--workers", "1", "--modes", "sparse",
                           *extra], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert needle in proc.stdout
    assert proc.stdout.startswith("bytecode: was ")  # (cached by a small run first, and said so)
    assert "workers' CPU / raw CPU" in proc.stdout or "--partitioned-only" in extra
    assert "whole command's CPU" in proc.stdout or "--partitioned-only" in extra
    assert "sparse" in proc.stdout and "driver s:" in proc.stdout
    assert "load average" in proc.stdout and "per tile hamiltonian() CPU s" in proc.stdout
    assert "tile tasks wall s" in proc.stdout
    assert "driver timeline s: decompose from" in proc.stdout and "to the submission" in proc.stdout


@pytest.mark.slow
@pytest.mark.parametrize("extra, needles", [
    (["--startup", "1"], ["early=1: submitted median", "early=0: submitted median"]),
    (["--imports-ab", "1"], ["start_first=1: submitted median", "start_first=0: submitted median"]),
    (["--ab", "1"], ["raw:", "sparse warm-up (0.2M, not counted)", "sparse new=1: whole CPU / raw CPU median",
                     "sparse new=0: whole CPU / raw CPU median"]),
    (["--tile-ab", "1"], ["mesh: band", "sparse: band"]),
    (["--order-ab", "1"], ["mesh: order rows", "sparse: order rows"]),
    (["--tiles-ab", "1", "--workers", "2"], ["sparse default tiles: wall / raw median",
                                             "sparse one per worker: wall / raw median"]),
    (["--switch-ab", "1", "--switch", "PAUSE_GC"], ["PAUSE_GC=1: submitted median", "PAUSE_GC=0: submitted median"]),
    (["--vs-ab", "1", "--vs-python", sys.executable], ["this=1: submitted median", "this=0: submitted median",
                                                       "wall / raw (the round's raw call): this=1"])])
def test_bench_scale_ab_modes_run(extra, needles):
    """The A/B modes (session 10's switches on / off, session 12's tiles) keep running
    at a tiny size (without caching the bytecode first: ``--source-imports``)."""
    pytest.importorskip("distributed")
    proc = subprocess.run([sys.executable, str(BENCH), "--sizes", "3e4", "--workers", "1", "--modes", "sparse",
                           "--source-imports", *extra], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    for needle in needles:
        assert needle in proc.stdout


def test_bench_scale_vs_ab_needs_the_other_python():
    proc = subprocess.run([sys.executable, str(BENCH), "--vs-ab", "1"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1 and "--vs-python" in proc.stderr
