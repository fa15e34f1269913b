"""The local cluster's workers forked by a zygote that loads their kernels beside the
driver's start (session 20: ``cluster.start_zygote``, ``cluster.ZYGOTE``)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import hammesh
from hammesh.cli import main
from hammesh.parallel import cluster

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")

needs_zygote = pytest.mark.skipif(cluster.start_method() != "fork" or cluster._forkserver_state() is None,
                                  reason="no fork, or a fork server this does not know: the workers fork as before")

#: a two-worker local cluster with the sparse mode's kernels: who forked the workers,
#: which process holds the lattice's kernels, and what is left after the close
_CLUSTER = """
import json, os
import hammesh.parallel.cluster as cl
from multiprocessing import forkserver

def held():
    from hammesh.parallel import _kernels as k
    return min(len(getattr(k, n).signatures) for n in ("lattice_mark_inside_into", "lattice_mesh_into"))

def parent():
    return os.getppid()

if __name__ == "__main__":
    with cl.runner_for(workers=2, mode="sparse") as (c, _):
        zygote = forkserver._forkserver._forkserver_pid
        parents = sorted(set(c.run(parent).values()))
        workers = sorted(c.run(held).values())
        driver = held()
    try:
        os.kill(zygote, 0)
        alive = True
    except ProcessLookupError:
        alive = False
    print(json.dumps({"driver_pid": os.getpid(), "zygote": zygote, "parents": parents, "workers": workers,
                      "driver": driver, "zygote_alive": alive, "left": forkserver._forkserver._forkserver_pid}))
"""


@needs_zygote
@pytest.mark.slow
def test_workers_come_from_a_zygote_that_loaded_their_kernels(tmp_path):
    """The workers' parent is the zygote, not the driver; they hold the kernels and the
    driver does not (it never loaded them); the zygote ends with the cluster and the
    fork server is forgotten (a later cluster makes its own)."""
    pytest.importorskip("distributed")
    script = tmp_path / "zygote.py"
    script.write_text(_CLUSTER)
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["zygote"] not in (None, got["driver_pid"]) and got["parents"] == [got["zygote"]], got
    assert got["workers"] == [1, 1] and got["driver"] == 0, got
    assert not got["zygote_alive"] and got["left"] is None, got
    assert "Traceback" not in out.stderr, out.stderr[-2000:]


def test_no_zygote_while_another_fork_server_runs(monkeypatch):
    """A fork server the caller started is left alone: no zygote, the workers fork as before."""
    import contextlib

    fs = cluster._forkserver_state()
    if fs is None:
        pytest.skip("a fork server this does not know")
    monkeypatch.setattr(fs, "_forkserver_pid", 12345)
    with contextlib.ExitStack() as stack:
        assert cluster.start_zygote(stack, "sparse") is False


#: ``hammesh argv[2:]`` in a fresh process with ``cluster.ZYGOTE`` = ``argv[1]``
_SWITCHED = ("import sys; import hammesh.parallel.cluster as c; c.ZYGOTE = bool(int(sys.argv[1])); "
             "from hammesh.cli import main; sys.exit(main(sys.argv[2:]))")


@pytest.mark.slow
def test_the_command_writes_the_same_pieces_with_the_zygote(tmp_path):
    pytest.importorskip("distributed")
    outs = []
    for on in (1, 0):
        out = tmp_path / f"out{on}"
        argv = ["mesh", DEMO, "-q", "30", "-a", "5e-4", "--workers", "2", "--partitioned", "-o", str(out),
                "--report", str(tmp_path / f"r{on}.json")]
        p = subprocess.run([sys.executable, "-c", _SWITCHED, str(on), *argv], capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 0 and p.stderr == "", p.stderr[-2000:]
        outs.append(out)
    names = sorted(p.name for p in outs[0].iterdir())
    assert names == sorted(p.name for p in outs[1].iterdir()) and "mesh.pvtu" in names
    for name in names:
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name
    assert main(["check", str(outs[0] / "mesh.pvtu")]) == 0
