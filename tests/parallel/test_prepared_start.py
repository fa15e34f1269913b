"""The driver's start, session 19: ``hammesh mesh --workers N`` reads, estimates and
decomposes the domain in a child forked at the command's start
(``command.prepare_beside``, ``forked.Child``, ``run.offer_decomposition``)."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import Future
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.errors import FileFormatError
from hammesh.parallel import command, forked, run
from hammesh.parallel.cluster import Starting
from hammesh.parallel.tiles import decompose

DEMO = Path(hammesh.__file__).parent / "data" / "demo.poly"

needs_fork = pytest.mark.skipif(not forked.can_fork(), reason="no fork here: no child is started")


def _args(path=DEMO, **kw) -> argparse.Namespace:
    base = dict(input=Path(path), strict=False, min_angle=30.0, max_area=2e-4, tiles=None, workers=2)
    base.update(kw)
    return argparse.Namespace(**base)


def _same_decomposition(a, b) -> None:
    assert a.n_tiles == b.n_tiles
    for name in ("vertices", "segments", "separator", "segment_markers"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for s, t in zip(a.tiles, b.tiles):
        assert np.array_equal(s.vertex_ids, t.vertex_ids) and s.estimate == t.estimate


class _Booting(Starting):
    """A local cluster's handle whose start never ends (only ``started`` and ``n_workers`` are asked)."""

    def __init__(self, n: int = 2) -> None:
        super().__init__(Future(), n)


@needs_fork
@pytest.mark.parametrize("tiles", [None, 3])
def test_the_child_reads_and_decomposes_as_the_driver_would(monkeypatch, tiles):
    """The domain and decomposition from the child are the driver's own (the same
    calls: default tiles for 2 workers, or --tiles), made in another process; the
    tiles' run takes the offered decomposition instead of decomposing again."""
    args = _args(tiles=tiles)
    here = hammesh.read_domain(DEMO)
    with command.prepare_beside(args, _Booting()) as child:
        assert child is not None
        domain = command.read_source(args, child)
    assert np.array_equal(domain.vertices, here.vertices) and np.array_equal(domain.segments, here.segments)
    n = tiles or run.default_tiles(run.decompose_estimate(here, 30.0, 2e-4), 2)
    mine = decompose(here, min_angle=30.0, max_area=2e-4, n_tiles=n)
    monkeypatch.setattr(run, "decompose", lambda *a, **k: pytest.fail("decomposed again"))
    offered = run.decompose_beside(run.LocalRunner(), domain, min_angle=30.0, max_area=2e-4, n_tiles=n)
    _same_decomposition(offered, mine)


def test_an_offer_is_taken_only_for_its_own_domain_and_keywords(monkeypatch):
    dom = hammesh.read_domain(DEMO)
    other = hammesh.read_domain(DEMO)
    d = decompose(dom, min_angle=30, max_area=1e-3, n_tiles=2)
    calls = []
    monkeypatch.setattr(run, "decompose", lambda domain, **kw: calls.append(kw) or "made here")
    kw = dict(min_angle=30, max_area=1e-3, n_tiles=2)
    for domain, asked in ((other, kw), (dom, {**kw, "n_tiles": 3}), (dom, {**kw, "max_area": 2e-3})):
        run.offer_decomposition(dom, d, **kw)
        assert run.decompose_beside(run.LocalRunner(), domain, **asked) == "made here"
    run.offer_decomposition(dom, d, **kw)
    assert run.decompose_beside(run.LocalRunner(), dom, **kw) is d
    assert run.decompose_beside(run.LocalRunner(), dom, **kw) == "made here"  # (used once)
    assert len(calls) == 4


@needs_fork
def test_bad_input_read_in_the_child_is_raised_by_the_driver_itself(tmp_path):
    bad = tmp_path / "bad.poly"
    bad.write_text("4 2 0 0\n1 0 0\n2 1 x\n")
    args = _args(bad)
    with command.prepare_beside(args, _Booting()) as child:
        assert child is not None
        with pytest.raises(FileFormatError, match="bad.poly"):
            command.read_source(args, child)


def test_no_child_without_a_local_cluster_starting_or_with_the_switch_off(monkeypatch):
    """Only for a local cluster still starting in this process (its worker count sets
    the default tiles; a cluster given by ``--scheduler`` or already up: the driver
    reads the domain itself)."""
    done = Future()
    done.set_result(None)
    for started in (None, run.LocalRunner(), Starting(done, 2)):
        with command.prepare_beside(_args(), started) as child:
            assert child is None
    monkeypatch.setattr(command, "PREPARE_IN_CHILD", False)
    with command.prepare_beside(_args(), _Booting()) as child:
        assert child is None


def _sleep_then(value):
    time.sleep(60)
    return value


@needs_fork
def test_a_child_whose_result_nobody_asked_for_is_killed_and_reaped():
    """An error of the driver before it reads the child's result (a bad output path,
    SIGTERM): leaving the context kills the child, no process is left."""
    t0 = time.perf_counter()
    child = forked.Child.start(_sleep_then, 1)
    pid = child._pid
    child.close()
    assert time.perf_counter() - t0 < 30
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)
    assert child.result() == (False, None)


@needs_fork
def test_a_child_result_is_read_once_and_kept():
    child = forked.Child.start(np.arange, 300_001)  # (more than a pipe's buffer)
    ok, a = child.result()
    assert ok and np.array_equal(a, np.arange(300_001))
    ok2, b = child.result()
    assert ok2 and b is a
    child.close()  # (nothing left to do)


#: ``hammesh argv[2:]`` in a fresh process with ``command.PREPARE_IN_CHILD`` = ``argv[1]``
_SWITCHED = ("import sys; import hammesh.parallel.command as c; c.PREPARE_IN_CHILD = bool(int(sys.argv[1])); "
             "from hammesh.cli import main; sys.exit(main(sys.argv[2:]))")


@pytest.mark.slow
def test_the_command_writes_the_same_pieces_with_the_domain_prepared_in_a_child(tmp_path):
    """The whole command (a local cluster: needs Dask) with the child and without it:
    the same files byte for byte, the index checked; the report shows no
    decomposition in the driver with the child (it was offered)."""
    pytest.importorskip("distributed")
    import json

    outs, reps = [], []
    for on in (1, 0):
        out = tmp_path / f"out{on}"
        argv = ["mesh", str(DEMO), "-q", "30", "-a", "5e-4", "--workers", "2", "--partitioned", "-o", str(out),
                "--report", str(tmp_path / f"r{on}.json")]
        p = subprocess.run([sys.executable, "-c", _SWITCHED, str(on), *argv], capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 0, p.stderr[-2000:]
        outs.append(out)
        reps.append(json.loads((tmp_path / f"r{on}.json").read_text())["parallel"])
    names = sorted(p.name for p in outs[0].iterdir())
    assert names == sorted(p.name for p in outs[1].iterdir()) and "mesh.pvtu" in names
    for name in names:
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name
    assert main(["check", str(outs[0] / "mesh.pvtu")]) == 0
    assert reps[0]["seconds"]["decompose"] < 0.05  # (offered: taken, not made)
