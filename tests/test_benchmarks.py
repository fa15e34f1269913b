"""The benchmark scripts keep running (tiny sizes; nothing here is timed or compared)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).parent.parent / "benchmarks"


@pytest.mark.slow
@pytest.mark.parametrize(
    "script, args, needle",
    [
        ("bench_core.py", ["--max-area", "0.001", "--repeat", "1", "--fresh", "1"], "ratio ours / triangle"),
        ("bench_polygon.py", ["--sizes", "60"], "60"),
        ("bench_points.py", ["--sizes", "2000"], "uniform"),
        ("bench_io.py", ["--faces", "2000", "--repeat", "1", "--rounds", "1"], "same result: True"),
    ],
)
def test_benchmark_script_runs(script: str, args: list[str], needle: str) -> None:
    proc = subprocess.run(
        [sys.executable, str(BENCH / script), *args], capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert needle in proc.stdout
    if script == "bench_core.py":  # the first call in a fresh process, beside the best of N
        for line in ("quality_mesh (isolated) / raw Triangle", "hamiltonian after quality_mesh / raw Triangle"):
            assert line in proc.stdout


@pytest.mark.slow
def test_bench_sparse_runs() -> None:
    proc = subprocess.run(
        [sys.executable, str(BENCH / "bench_sparse.py"), "--quick", "--repeat", "1"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "worst planar Steiner points per input triangle" in proc.stdout


@pytest.mark.slow
def test_bench_partition_runs() -> None:
    pytest.importorskip("pymetis")  # a benchmark-only peer
    proc = subprocess.run(
        [sys.executable, str(BENCH / "bench_partition.py"), "--target", "4000", "--repeat", "1"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "worst cut ratio" in proc.stdout
    assert "| gear | incircle | rcm |" in proc.stdout


@pytest.mark.slow
def test_bench_partition_trees_averages_over_meshes() -> None:
    pytest.importorskip("pymetis")
    proc = subprocess.run(
        [sys.executable, str(BENCH / "bench_partition.py"), "--trees", "--schemes", "shipped,fishbone_y",
         "--targets", "3000,4000", "--domains", "square", "--ks", "4,8"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "| square | fishbone_y | 2 |" in proc.stdout  # the mean / max table
    assert "cells' cut / cycle cut" in proc.stdout  # the fishbone's own cells at k = 4
