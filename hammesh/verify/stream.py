"""The certificate's row checks, run on the rows a construction has finished while it goes on.

A construction that writes its output rows in order (the Thm 2.4 walk) publishes how
far it is (:meth:`RowStream.publish`); one or more threads check the finished rows in
chunks (:meth:`RowStream.work`, the kernel releases the GIL) and the construction
joins them when it is done. The checks are exactly those of
``hammesh.verify.certificate`` (``_kernels.certify_row_range``), with two things
left for the end because they need the cycle lengths, which are known only then:

* consecutive rows: every row is compared with the next (the last with the first);
  a row that fails is marked, and at the end the marked rows must be exactly run
  ends, each of which must close onto the first row of its run;
* runs joined by a pairing: checked over the whole pairing at the end when there is
  more than one run.

The pairing (the construction's claim) is checked from the higher half-edge of each
pair, when both of its rows are final; entries not written yet read ``UNLINKED`` and
are skipped, and the final count ``2 links + unpaired = 3 m`` proves that every
half-edge was covered. Any failure only makes the caller run the full certificate
(which names the fault); the stream never passes what the full certificate fails.
"""

from __future__ import annotations

import threading
from concurrent.futures import Future

import numpy as np

from hammesh.verify import _kernels
from hammesh.verify._kernels import UNLINKED, RowChecks
from hammesh.verify.certificate import combine_rows, points_digest

__all__ = ["RowStream", "UNLINKED"]


class RowStream:
    """Row checks over a cycle-ordered output that is still being written.

    Parameters
    ----------
    points : (n, 2) float64
        Output points; no row is checked before :meth:`points_final` is called.
    triangles : (m, 3) int64
        Output rows, written in order.
    claim : (3 m,) int64
        Claimed half-edge pairing, initialised to ``UNLINKED``.
    chunk : int
        Rows per kernel call.
    """

    def __init__(self, points: np.ndarray, triangles: np.ndarray, claim: np.ndarray, chunk: int = 1 << 16):
        self.points = points
        self.triangles = triangles
        self.claim = claim
        self.chunk = int(chunk)
        m = len(triangles)
        self.used = np.zeros(len(points), dtype=np.bool_)
        self._cons_fail = np.zeros(m, dtype=np.bool_)  # written only where a row fails
        self._one_run = np.array([m], dtype=np.int64)
        self._cond = threading.Condition()
        self._ready = 0  # rows that may be checked
        self._final = False
        self._stopped = False
        self._points = False
        self._next = 0  # first row not handed out yet
        self._points_digest = 0
        self._parts: list[tuple] = []
        self._workers: list[Future] = []

    def points_final(self) -> None:
        """Every point the rows use is written: checking may start (see the class).

        The points' digest is taken now; the certificate compares it with the final
        points' (a point rewritten after the rows using it were checked is caught).
        """
        self._points_digest = points_digest(self.points)
        with self._cond:
            self._points = True
            self._cond.notify_all()

    def publish(self, ready: int, final: bool = False) -> None:
        """Rows below ``ready`` are final (``final``: all rows are written)."""
        with self._cond:
            self._ready = len(self.triangles) if final else max(self._ready, int(ready))
            self._final = final
            self._cond.notify_all()

    def stop(self) -> None:
        """The construction failed: workers return without checking more."""
        with self._cond:
            self._stopped = True
            self._cond.notify_all()

    def _take(self) -> tuple[int, int] | None:
        with self._cond:
            while True:
                if self._stopped:
                    return None
                lo = self._next
                if not self._points:
                    self._cond.wait()
                    continue
                if self._final and lo >= self._ready:
                    return None
                if self._ready - lo >= self.chunk or (self._final and self._ready > lo):
                    hi = min(self._ready, lo + self.chunk)
                    self._next = hi
                    return lo, hi
                self._cond.wait()

    def attach(self, worker: Future) -> None:
        """A thread running :meth:`work` that :meth:`join` waits for."""
        self._workers.append(worker)

    def join(self) -> None:
        """Check rows here too until all are checked, then wait for the attached workers."""
        self.work()
        for w in self._workers:
            w.result()

    def work(self) -> None:
        """Check published rows until all are checked (blocks while rows are pending)."""
        while (span := self._take()) is not None:
            res = _kernels.certify_row_range(
                self.points, self.triangles, self._one_run, self.claim, span[0], span[1],
                self.used, self._cons_fail,
            )
            with self._cond:
                self._parts.append(res)

    def result(self, runs: np.ndarray) -> RowChecks:
        """The row results for the run lengths ``runs``, as ``certify_row_range`` gives them.

        Call after every :meth:`work` has returned and the construction published
        ``final``.
        """
        runs = np.asarray(runs, dtype=np.int64)
        rows = combine_rows(self._parts)
        starts = np.cumsum(runs) - runs
        ends = starts + runs - 1
        marked = np.flatnonzero(self._cons_fail)
        stray = np.setdiff1d(marked, ends)  # breaks inside a run
        short = starts[runs < 3]
        bad = [int(stray[0])] if len(stray) else []
        if len(short):
            bad.append(int(short[0]))
        close = int(_kernels.runs_close(self.triangles, runs))
        if close >= 0:
            bad.append(close)
        cross = -1
        if len(runs) > 1 and rows.bad_pair < 0:  # pairs between runs (the claim is complete)
            cross = int(_kernels.first_cross_run_edge(self.claim, runs))
        return rows._replace(bad_consecutive=min(bad) if bad else -1, cross_run=cross,
                             points_digest=self._points_digest)
