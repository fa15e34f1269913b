"""The garbage collector paused over ``hammesh mesh --workers``'s serial start
(session 19: ``cluster.pause_gc`` / ``cluster.resume_gc``)."""

from __future__ import annotations

import gc
import json
import subprocess
import sys

import pytest

from hammesh.parallel import cluster


@pytest.fixture
def gc_state():
    """Whatever a test does to the collector, it is as before afterwards."""
    was = gc.isenabled()
    yield
    cluster._gc_paused = False
    gc.unfreeze()
    (gc.enable if was else gc.disable)()


def test_pause_then_resume_collects_again_and_freezes_the_start(gc_state):
    gc.enable()
    cluster.pause_gc()
    assert not gc.isenabled()
    made = [[] for _ in range(1000)]  # (what the start makes and keeps)
    frozen = gc.get_freeze_count()
    cluster.resume_gc()
    assert gc.isenabled() and gc.get_freeze_count() >= frozen + len(made)
    cluster.resume_gc()  # (once)
    assert gc.isenabled()


def test_a_collector_off_before_is_left_off(gc_state):
    """A Python caller who switched the collector off keeps it off: only a pause made
    here is ended here."""
    gc.disable()
    cluster.pause_gc()
    cluster.resume_gc()
    assert not gc.isenabled()


#: a local cluster started during the pause: its forked workers collect garbage once
#: set up, and the driver collects again when it resumes
_WORKERS = """
import gc, json, threading
from hammesh.parallel import cluster
cluster.pause_gc()
ready = threading.Event()
ready.set()
with cluster.runner_for(workers=2, background=True, ready=ready) as (c, n):
    workers = sorted(c.run(gc.isenabled).values())
    frozen = min(c.run(gc.get_freeze_count).values())
    driver = gc.isenabled()
    cluster.resume_gc()
print(json.dumps([workers, frozen > 0, driver, gc.isenabled()]))
"""


@pytest.mark.slow
def test_workers_forked_during_the_pause_collect_garbage():
    pytest.importorskip("distributed")
    out = subprocess.run([sys.executable, "-c", _WORKERS], capture_output=True, text=True, timeout=600, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [[True, True], True, False, True]
