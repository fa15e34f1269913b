"""Row checks run beside the walk (hammesh.verify.stream): the same verdicts as the full pass."""

from __future__ import annotations

import threading
from dataclasses import replace

import numpy as np
import pytest

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.postprocess import _thm24_kernels as _kernels
from hammesh.verify import _kernels as cert_kernels
from hammesh.postprocess import incircle
from hammesh.verify.certificate import certify
from hammesh.verify.reference import input_facts
from hammesh.verify.certificate import _certify_rows
from hammesh.verify.stream import RowStream
from tests.helpers import assert_certificate, plate


def streamed(h: hammesh.HamiltonianMesh, claim: np.ndarray, steps: int, workers: int) -> tuple:
    """Publish ``h``'s rows in ``steps`` steps to ``workers`` threads, as the walk does."""
    stream = RowStream(h.points, h.triangles, claim, chunk=7)
    stream.points_final()
    threads = [threading.Thread(target=stream.work) for _ in range(workers)]
    for t in threads:
        t.start()
    m = h.n_triangles
    for s in range(1, steps):
        stream.publish(m * s // steps)
    stream.publish(m, final=True)
    for t in threads:
        t.join()
    return stream.result(h.components), stream.used


@pytest.fixture(scope="module")
def built() -> tuple[hammesh.HamiltonianMesh, np.ndarray]:
    clean, he, is_con = prepare_mesh(plate(2, 3))
    h, claim = incircle.incircle_hamiltonian(clean, he, is_con)
    assert len(h.components) == 3 and h.report["midpoints"] == 2
    return h, claim


def full(h: hammesh.HamiltonianMesh, tri: np.ndarray, claim: np.ndarray) -> tuple:
    used = np.zeros(len(h.points), dtype=bool)
    return _certify_rows(h.points, tri, h.components, claim, used)[0], used


@pytest.mark.parametrize("steps, workers", [(1, 1), (5, 2), (40, 3)])
def test_stream_equals_full_pass(built, steps: int, workers: int) -> None:
    h, claim = built
    (rows, used), (ref, ref_used) = streamed(h, claim, steps, workers), full(h, h.triangles, claim)
    assert np.array_equal(used, ref_used)
    assert rows[:4] == ref[:4] == (-1, -1, -1, -1)  # bad index, consecutive, pair, cross run
    for name in ("argmin", "argmax", "bad_orientation", "links", "unpaired"):
        assert getattr(rows, name) == getattr(ref, name), name
    assert np.isclose(rows.total_area, ref.total_area, rtol=1e-12)
    assert 2 * rows.links + rows.unpaired == 3 * h.n_triangles  # every half-edge paired or boundary


@pytest.mark.parametrize("where", ["middle", "run_end", "run_start"])
def test_stream_finds_the_same_broken_row(built, where: str) -> None:
    """Breaks inside a run are marked and reported at the same row as the full pass;
    run ends, which the stream cannot tell apart while it runs, are checked at the end."""
    h, claim = built
    ends = np.cumsum(h.components) - 1
    i = {"middle": int(ends[0]) // 2, "run_end": int(ends[1]), "run_start": int(ends[0]) + 1}[where]
    j = i - 7 if where == "run_end" else i + 7  # same run
    tri = h.triangles.copy()
    tri[[i, j]] = tri[[j, i]]
    rows, _ = streamed(replace(h, triangles=tri), claim, 6, 2)
    ref, _ = full(h, tri, claim)
    assert rows.bad_consecutive == ref.bad_consecutive >= 0
    with pytest.raises(hammesh.VerificationError, match=f"breaks at triangle {ref.bad_consecutive}"):
        certify(replace(h, triangles=tri), None, rows=(rows, np.ones(len(h.points), bool)))


def test_unwritten_claim_entries_are_counted(built) -> None:
    h, claim = built
    c = claim.copy()
    c[[5, int(claim[5])]] = _kernels.UNLINKED  # a pair the walk "never wrote"
    rows, _ = streamed(h, c, 4, 2)
    assert rows.bad_pair == -1 and 2 * rows.links + rows.unpaired == 3 * h.n_triangles - 2
    # the certificate then does not believe the claim but still proves the good mesh
    certify(h, input_facts(plate(2, 3)), claim=c, rows=rows_used(h, c))  # (the mesh itself is fine)


def rows_used(h: hammesh.HamiltonianMesh, claim: np.ndarray) -> tuple:
    return streamed(h, claim, 3, 2)


@pytest.mark.parametrize("n_loops, pieces", [(0, 1), (3, 1), (2, 3)])
def test_hamiltonian_pipelined_in_small_steps(monkeypatch, n_loops: int, pieces: int) -> None:
    """The walk handing over every few rows gives the serial walk's output, verified."""
    m = plate(n_loops, pieces)
    clean, he, is_con = prepare_mesh(m)
    ref, ref_claim = incircle.incircle_hamiltonian(clean, he, is_con)
    monkeypatch.setattr(incircle, "WALK_CHUNK", 5)
    monkeypatch.setattr(RowStream.__init__, "__defaults__", (3,))
    h = hammesh.hamiltonian(m, mode="incircle")
    assert h.report["verified"] and h.report["midpoints"] == n_loops
    np.testing.assert_array_equal(h.triangles, ref.triangles)
    np.testing.assert_array_equal(h.points, ref.points)
    assert h.components.tolist() == ref.components.tolist()
    assert_certificate(m, h)


def test_walk_resumes_where_it_paused(built) -> None:
    """Paused after every row, the resumable walk writes exactly the one-call output."""
    h, claim = built
    clean, he, is_con = prepare_mesh(plate(2, 3))
    tri, code, order, firsts, _ = _kernels.spanning_forest(clean.triangles, he.twin, is_con)
    mid_h, mid_id, _, _ = _kernels.split_slots(tri, code)
    total = len(code) + len(mid_h)

    def walk(step: int) -> tuple[int, int, tuple]:
        """Walk with a pause every ``step`` rows: (status, pauses, arrays)."""
        # the arrays (and dtypes: int32 claim and slots) hamiltonian() hands the walk, so
        # that the suite compiles no second signature of it
        arrays = incircle.walk_arrays(total, len(code))
        out, parent, kind, c, prim = (arrays[k] for k in ("out", "parent", "kind", "claim", "prim"))
        lengths = np.zeros(len(firsts), np.int64)
        y2 = np.full(len(mid_h), -1, np.int64)
        state = np.zeros(_kernels.WALK_STATE, np.int64)
        calls = 0
        while (st := _kernels.emit_cycles_into(tri, code, firsts, order, clean.n_points, mid_h, mid_id, out, parent,
                                               kind, c, prim, lengths, y2, state, int(state[2]) + step)) == 0:
            calls += 1
        return st, calls, (out, parent, kind, lengths, c)

    st0, calls0, ref = walk(total)  # one call
    st, calls, got = walk(1)
    assert st0 == st == 1 and calls0 == 0
    assert calls >= total - len(mid_h) - len(firsts)  # a pause at every slot
    for a, b in zip(got, ref):
        np.testing.assert_array_equal(a, b)


def test_no_row_is_checked_before_the_points_are_final(built) -> None:
    """Workers wait for ``points_final`` (the incenters) even when rows are published."""
    h, claim = built
    pts = np.zeros_like(h.points)  # not written yet: every row degenerate
    stream = RowStream(pts, h.triangles, claim, chunk=7)
    stream.publish(h.n_triangles, final=True)
    worker = threading.Thread(target=stream.work)
    worker.start()
    worker.join(0.2)
    assert worker.is_alive() and not stream._parts  # waiting, nothing checked
    pts[:] = h.points
    stream.points_final()
    worker.join()
    rows = stream.result(h.components)
    assert rows.bad_orientation == -1 and rows.bad_consecutive == -1


def test_claim_index_width() -> None:
    """Claims and slot rows are int32 while they fit (half the memory), int64 beyond."""
    assert _kernels.index_dtype(3 * 10**8) == np.int32
    assert _kernels.index_dtype(2**31) == np.int64
    m = plate(1, 1)
    clean, he, is_con = prepare_mesh(m)
    h, claim = incircle.incircle_hamiltonian(clean, he, is_con)
    assert claim.dtype == np.int32
    twin, bad = cert_kernels.half_edge_twins(h.triangles, h.n_points)
    assert bad == -1
    np.testing.assert_array_equal(claim, twin)
    # the certificate takes either width
    certify(h, input_facts(m), claim=claim.astype(np.int64))


def test_hamiltonian_from_several_threads_at_once(monkeypatch) -> None:
    """Each call has its own helper thread and stream: concurrent calls do not mix."""
    from concurrent.futures import ThreadPoolExecutor

    monkeypatch.setattr(incircle, "WALK_CHUNK", 11)
    meshes = [plate(n_loops, pieces) for n_loops, pieces in [(0, 1), (2, 1), (1, 3), (3, 2)]]
    with ThreadPoolExecutor(4) as pool:
        outs = list(pool.map(lambda m: hammesh.hamiltonian(m, mode="incircle"), meshes))
    for m, h in zip(meshes, outs):
        assert h.report["verified"] and h.n_triangles == 3 * m.n_triangles + 2 * h.report["midpoints"]
        assert_certificate(m, h)


def _python_mix(a: int, b: int) -> int:
    """The digest hash in plain Python integers (mod 2**64): the kernels' reference."""
    mask = (1 << 64) - 1
    x = ((a * 0x1E3779B97F4A7C15) & mask) ^ ((b + 0x2545F4914F6CDD1D) & mask)
    x ^= x >> 29
    return (x * 0x3F58476D1CE4E5B9) & mask


@pytest.mark.parametrize("dtype", [np.int32, np.int64])
def test_digests_equal_a_python_reference(dtype) -> None:
    """Both digest kernels equal the hash summed in Python, for either claim width.

    Regression: numba lowers signed ``+``/``*`` with LLVM's ``nsw`` (overflow is
    undefined), and LLVM turned the hash's arithmetic shift into a logical one in
    ``certify_row_range`` on int32 claims, so the streamed and final digests differed.
    """
    rng = np.random.default_rng(7)
    m = 50
    tri = rng.integers(0, 40, size=(m, 3)).astype(np.int64)
    pair = rng.integers(-1, 3 * m, size=3 * m).astype(dtype)
    want_rows = sum(_python_mix(i, _python_mix(int(a), _python_mix(int(b), int(c)))) for i, (a, b, c) in enumerate(tri))
    want_pairs = sum(_python_mix(h, int(g)) for h, g in enumerate(pair))
    d_rows, d_pairs = cert_kernels.digest_range(tri, pair, 0, m)
    assert d_rows % (1 << 64) == want_rows % (1 << 64)
    assert d_pairs % (1 << 64) == want_pairs % (1 << 64)


@pytest.mark.parametrize("dtype", [np.int32, np.int64])
def test_streamed_pair_digest_equals_the_final_one(built, dtype) -> None:
    """The row checks' pair digest (summed per checked pair) equals ``digest_range``'s
    over the same claim, whatever its width, in one pass and streamed."""
    from hammesh.verify.certificate import _final_digests, _wrap

    h, claim = built
    c = claim.astype(dtype)
    d_rows, d_pairs = _final_digests(np.ascontiguousarray(h.triangles), c)
    one, _ = full(h, h.triangles, c)
    streamed_rows, _ = streamed(h, c, 5, 2)
    assert _wrap(one.pair_digest) == _wrap(streamed_rows.pair_digest) == d_pairs
    assert _wrap(one.row_digest) == _wrap(streamed_rows.row_digest) == d_rows
    wide, _ = _final_digests(np.ascontiguousarray(h.triangles), claim.astype(np.int64))
    assert wide == d_rows


def test_hamiltonian_takes_the_claim_without_a_second_pass(monkeypatch) -> None:
    """mode="incircle" certifies its (int32) claim from the streamed checks alone: the
    whole-claim re-check (kept for a claim rewritten after its check) does not run."""
    from hammesh.verify import certificate

    def no_second_pass(*args, **kw):
        raise AssertionError("the claim was checked twice")

    monkeypatch.setattr(certificate, "_certify_rows", no_second_pass)
    h = hammesh.hamiltonian(plate(2, 3), mode="incircle")
    assert h.report["verified"]


def test_claim_rewritten_after_its_check_is_checked_again(built, monkeypatch) -> None:
    """A claim entry changed after the stream checked it is caught by the digest, and the
    certificate then checks the final claim whole (here: no longer a pairing, so the
    certificate finds the pairing itself and still proves the good mesh)."""
    from hammesh.verify import certificate

    h, claim = built
    c = claim.copy()
    rows = streamed(h, c, 4, 2)
    c[[0, 1]] = c[[1, 0]]  # rewritten after the check
    calls = []
    real = certificate._certify_rows
    monkeypatch.setattr(certificate, "_certify_rows", lambda *a, **k: calls.append(1) or real(*a, **k))
    certify(h, input_facts(plate(2, 3)), claim=c, rows=rows)
    assert calls == [1]
