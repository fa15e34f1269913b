"""The workers' threads at the tail of the tiles (``run.gather_widening``, session 17)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import hammesh
from hammesh.cli import main

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")

#: ``hammesh argv[2:]`` in a fresh process with ``cluster.TAIL_THREADS`` = ``argv[1]``
_SWITCHED = ("import sys; import hammesh.parallel.cluster as c; c.TAIL_THREADS = bool(int(sys.argv[1])); "
             "from hammesh.cli import main; sys.exit(main(sys.argv[2:]))")


def _mesh(tmp_path: Path, tail: bool) -> tuple[Path, dict]:
    out, rep = tmp_path / f"out{int(tail)}", tmp_path / f"rep{int(tail)}.json"
    argv = ["mesh", DEMO, "-q", "30", "-a", "5e-4", "--workers", "2", "--tiles", "5", "--partitioned",
            "-o", str(out), "--report", str(rep)]
    p = subprocess.run([sys.executable, "-c", _SWITCHED, str(int(tail)), *argv], capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    return out, json.loads(rep.read_text())


@pytest.mark.slow
def test_the_last_tile_gets_the_idle_cores_and_the_output_is_the_same(tmp_path):
    """Five tiles on two workers: when one tile is left, its worker's threads per pass
    go up to the machine's cores (and back for the pieces: the report says when);
    every piece is byte for byte the one written with the threads kept at one."""
    pytest.importorskip("distributed")
    on, rep_on = _mesh(tmp_path, True)
    off, rep_off = _mesh(tmp_path, False)
    cores = os.cpu_count() or 1
    raises = rep_on["parallel"]["tail_threads"]
    if cores >= 2:
        assert [left for left, _, _ in raises] == [1] and raises[0][1] == cores
    assert rep_off["parallel"]["tail_threads"] == []
    names = sorted(p.name for p in on.iterdir())
    assert names == sorted(p.name for p in off.iterdir()) and len(names) == 6
    for name in names:
        assert (on / name).read_bytes() == (off / name).read_bytes(), name
    assert main(["check", str(on / "mesh.pvtu")]) == 0
