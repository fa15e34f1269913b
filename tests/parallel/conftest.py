"""Support for the parallel tests: nothing here may hang the suite.

A local Dask cluster forks worker processes; a process forked while another thread
held a lock the child needs never starts (seen once under pytest-xdist, whose worker
processes run threads of their own). The cluster's start has a deadline
(``cluster.START_TIMEOUT``); the commands that start one run in a fresh process with
a timeout (:func:`run_cli`); and every test here has a watchdog that ends its
process, with every thread's traceback on stderr, if it runs past ``WATCHDOG_S``
(xdist reports the test failed and starts another worker).
"""

from __future__ import annotations

import faulthandler
import json
import subprocess
import sys

import pytest

#: seconds any one test of tests/parallel may take (the slowest, loaded: ~2 min)
WATCHDOG_S = 900

#: a fresh interpreter running ``hammesh`` with the given arguments, then printing the
#: names of the cluster-starting threads still alive (none once the command returned)
_RUN = ("import json, sys, threading; from hammesh.cli import main; rc = main(sys.argv[1:]); "
        "print(json.dumps([t.name for t in threading.enumerate() if t.name.startswith('hammesh-cluster')])); "
        "sys.exit(rc)")


@pytest.fixture(autouse=True)
def _watchdog():
    faulthandler.dump_traceback_later(WATCHDOG_S, exit=True)
    yield
    faulthandler.cancel_dump_traceback_later()


@pytest.fixture
def run_cli():
    """``run_cli(argv, timeout=600) -> (exit code, stdout lines, stderr, cluster threads left)``:
    ``hammesh argv`` in a fresh process (fails the test on timeout, never waits for ever)."""

    def run(argv: list[str], timeout: float = 600.0):
        try:
            p = subprocess.run([sys.executable, "-c", _RUN, *map(str, argv)], capture_output=True, text=True,
                               timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            pytest.fail(f"hammesh {' '.join(map(str, argv))} did not end within {timeout:g} s: {exc.stderr!r}")
        lines = p.stdout.splitlines()
        left = json.loads(lines[-1]) if lines and lines[-1].startswith("[") else None
        return p.returncode, lines[:-1] if left is not None else lines, p.stderr, left

    return run
