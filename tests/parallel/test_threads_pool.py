"""hammesh.threads.run_all's shared pool: results in order, the caller's thread works too,
no thread started per pass, errors after every call is done, a fresh pool after fork."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from hammesh import threads


@pytest.fixture
def two_cores(monkeypatch):
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    old = threads.limit(None)
    yield
    threads.limit(old)


def test_passes_reuse_the_pool_and_the_callers_thread(two_cores):
    def who(i):
        return lambda: (i, threading.get_ident())

    threads.run_all([who(0), who(1)])  # (the pool's thread started once)
    before = threading.active_count()
    seen = set()
    for _ in range(20):
        got = threads.run_all([who(0), who(1)])
        assert [g[0] for g in got] == [0, 1]
        assert got[0][1] == threading.get_ident()  # (the first call in the caller's thread)
        seen.add(got[1][1])
    assert threading.active_count() == before
    assert threading.get_ident() not in seen


def test_an_error_is_raised_after_the_other_calls_are_done(two_cores):
    done = []

    def slow():
        time.sleep(0.05)
        done.append(1)

    def bad():
        raise ValueError("boom")

    with pytest.raises(ValueError, match="boom"):
        threads.run_all([bad, slow])
    assert done == [1]
    with pytest.raises(KeyError):
        threads.run_all([lambda: 1, lambda: {}["x"]])


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork only")
def test_a_forked_child_makes_its_own_pool(two_cores):
    threads.run_all([lambda: 0, lambda: 1])  # (the parent's pool exists)
    pid = os.fork()
    if pid == 0:  # child: its pool's threads did not survive the fork
        signal.alarm(20)  # (a pool without threads would wait for ever: killed, a failure)
        ok = threads.run_all([lambda: 0, lambda: 1]) == [0, 1]
        os._exit(0 if ok else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0


def test_run_beside_runs_on_the_pool_or_inline(two_cores):
    """``run_beside``: the call on a pool thread, its future; with one thread allowed, in
    the caller's thread, done when returned."""
    f = threads.run_beside(lambda x: (x, threading.get_ident()), 7)
    value, ident = f.result()
    assert value == 7 and ident != threading.get_ident()
    threads.limit(1)
    f = threads.run_beside(lambda x: (x, threading.get_ident()), 8)
    assert f.done() and f.result() == (8, threading.get_ident())
