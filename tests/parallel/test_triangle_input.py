"""Triangle's input in tile meshing: the class that crashes it, and the guard.

Session 17: once in CI a tile's in-process ``triangle.triangulate`` crashed the
interpreter (SIGSEGV). Two points closer than ~1e-13 of the input's extent (an exact
duplicate used by a segment always), or a point ~1e-15 off a segment's inside, crash
Triangle or make it loop. ``guard.triangulate_guarded`` sends such input to a child
process (a crash becomes a MeshingError); the decomposition never makes it
(``tiles.CUT_TOUCH``). Every call that might crash runs in a forked child here, so a
regression fails a test instead of killing pytest.
"""

from __future__ import annotations

import os
import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.errors import MeshingError
from hammesh.parallel import decompose
from hammesh.parallel._kernels import near_feature
from hammesh.parallel.guard import NEAR_RELATIVE, input_fault, triangulate_guarded
from hammesh.parallel.tile_mesh import lattice_grid, mesh_tile

SWITCHES = "pq30a0.002YnQ"


def _band_like(rng: np.random.Generator) -> dict:
    """A tile-band-like PSLG: a square of 48 subsegments, a hexagon loop inside it
    with a hole point (the lattice's outline and its hole point)."""
    t = np.linspace(0, 1, 12, endpoint=False)
    sq = np.concatenate([np.c_[t, 0 * t], np.c_[1 + 0 * t, t], np.c_[1 - t, 1 + 0 * t], np.c_[0 * t, 1 - t]])
    m = len(sq)
    ang = np.linspace(0, 2 * np.pi, 7)[:-1] + rng.uniform(0, 1)
    c = rng.uniform(0.35, 0.65, 2)
    hexa = c + rng.uniform(0.15, 0.3) * np.c_[np.cos(ang), np.sin(ang)]
    segs = [[i, (i + 1) % m] for i in range(m)] + [[m + i, m + (i + 1) % 6] for i in range(6)]
    return {"vertices": np.concatenate([sq, hexa]), "segments": np.array(segs), "holes": np.array([c])}


def _in_child(fn) -> tuple[str, object]:
    """Run ``fn()`` in a forked child: ("ok", its result), ("error", message) or
    ("signal", number)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        os.close(r)
        try:
            out = ("ok", fn())
        except Exception as exc:  # noqa: BLE001 - reported to the parent
            out = ("error", f"{type(exc).__name__}: {exc}")
        with os.fdopen(w, "wb") as f:
            pickle.dump(out, f)
        os._exit(0)
    os.close(w)
    with os.fdopen(r, "rb") as f:
        data = f.read()
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        return "signal", os.WTERMSIG(status)
    return pickle.loads(data)


def _moved(data: dict, rng: np.random.Generator, kind: str, gap: float) -> dict:
    """``data`` with one hexagon point moved to ``gap`` from a square point (``near``)
    or from the inside of a square subsegment (``on``)."""
    v = data["vertices"].copy()
    k, j = 48 + int(rng.integers(6)), int(rng.integers(48))
    if kind == "near":
        d = rng.normal(size=2)
        v[k] = v[j] + gap * d / np.linalg.norm(d)
    else:
        a, b = v[j], v[(j + 1) % 48]
        n = np.array([a[1] - b[1], b[0] - a[0]]) / np.linalg.norm(b - a)
        v[k] = (a + b) / 2 + gap * n * rng.choice([-1, 1])
    return {**data, "vertices": v}


def _triangles(out: dict) -> int:
    return len(out["triangles"])


def test_an_exact_duplicate_is_flagged_and_the_guard_keeps_the_process():
    """An exact duplicate point used by a segment: Triangle reads memory it never
    wrote there, and dies or not with the process's heap (measured: in fresh
    interpreters that had imported ``hammesh.parallel.tile_mesh``, 1-6 of these 8 cases
    died of SIGSEGV per interpreter, 0 in one that had not; none in pytest's process).
    The guard flags every case, and the call meshes it or says MeshingError naming the
    tile, in this process."""
    cases = [_moved(_band_like(np.random.default_rng(a)), np.random.default_rng(a + 1), "near", 0.0) for a in range(8)]
    assert all(input_fault(c["vertices"], c["segments"]) is not None for c in cases)
    for data in cases[:3]:
        try:
            out = triangulate_guarded(data, SWITCHES, "tile 7", seconds=30)
        except MeshingError as exc:
            assert "tile 7" in str(exc)
        else:  # (a mesh is fine too: the point is that this process lives)
            assert _triangles(out) > 0


@pytest.mark.slow
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(["near", "on"]),
       gap=st.sampled_from([0.0, 1e-17, 1e-16, 3e-16, 1e-15, 1e-14, 1e-13]))
def test_close_points_never_take_the_process_down(seed, kind, gap):
    """Over the class (points 0-1e-13 apart, a point that close to a segment's inside):
    the guarded call flags the input (except a point exactly on a segment, which
    Triangle handles) and ends with a mesh or a MeshingError, never a signal."""
    rng = np.random.default_rng(seed)
    data = _moved(_band_like(rng), rng, kind, gap)
    fault = input_fault(data["vertices"], data["segments"])
    assert fault is not None or (kind == "on" and gap == 0.0)
    status, value = _in_child(lambda: _triangles(triangulate_guarded(data, SWITCHES, "tile 1", seconds=5)))
    assert status in ("ok", "error"), (status, value)
    if status == "error":
        assert value.startswith("MeshingError") and "tile 1" in value, value


@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 30), seed=st.integers(0, 2**32 - 1), snap=st.booleans())
def test_near_feature_agrees_with_brute_force(n, seed, snap):
    """The kernel's sweep finds a close pair exactly when a brute-force search does
    (points on a coarse grid, so that ties and duplicates happen)."""
    rng = np.random.default_rng(seed)
    p = rng.integers(0, 6, size=(n, 2)).astype(float) / 5 if snap else rng.uniform(0, 1, (n, 2))
    segs = rng.integers(0, n, size=(max(1, n // 2), 2))
    tol = 0.05
    kind, i, j = near_feature(p, np.lexsort((p[:, 1], p[:, 0])), segs, tol)
    close = [(a, b) for a in range(n) for b in range(a + 1, n)
             if abs(p[a, 0] - p[b, 0]) <= tol and abs(p[a, 1] - p[b, 1]) <= tol]
    near_seg = []
    for s, (a, b) in enumerate(segs):
        d = p[b] - p[a]
        if a == b or not d.any():
            continue
        for k in range(n):
            if k in (a, b):
                continue
            t = ((p[k, 0] - p[a, 0]) * d[0] + (p[k, 1] - p[a, 1]) * d[1]) / (d @ d)
            cross = (p[k, 0] - p[a, 0]) * d[1] - (p[k, 1] - p[a, 1]) * d[0]
            if 0 < t < 1 and cross * cross <= tol * tol * (d @ d):
                near_seg.append((k, s))
    if close:
        assert kind == 0 and (min(i, j), max(i, j)) in close
    elif near_seg:
        assert kind == 1 and (i, j) in near_seg
    else:
        assert kind == -1


@pytest.mark.parametrize("area, n_tiles", [(1e-3, 2), (3e-4, 6)])
def test_no_real_tile_input_is_suspect(area, n_tiles):
    """No false alarm: the demo's tiles, and their band inputs, go to Triangle in this
    process (a child per tile would cost ~1 % of the 6M command)."""
    import hammesh.parallel.tile_mesh as tm

    dom = hammesh.read_domain("hammesh/data/demo.poly")
    d = decompose(dom, min_angle=30, max_area=area, n_tiles=n_tiles)
    seen = []
    real = tm.triangulate_guarded

    def spy(data, switches, what, seconds=None, isolate=False):
        seen.append(input_fault(data["vertices"], data["segments"]))
        return real(data, switches, what, seconds, isolate)

    tm.triangulate_guarded = spy
    try:
        for t in d.tiles:
            assert input_fault(t.vertices, t.segments) is None
            assert lattice_grid(t, area) is not None
            m = mesh_tile(t, 30, area)
            assert m.info.get("lattice") == "band"
    finally:
        tm.triangulate_guarded = real
    assert seen == [None] * len(d.tiles)


def test_the_relative_tolerance_scales_with_the_input():
    """The same shape at 1e6 times the size is judged the same (the tolerance is
    relative to the input's extent)."""
    data = _moved(_band_like(np.random.default_rng(5)), np.random.default_rng(6), "near", 1e-14)
    assert input_fault(data["vertices"], data["segments"]) is not None
    assert input_fault(data["vertices"] * 1e6, data["segments"]) is not None
    far = _moved(_band_like(np.random.default_rng(5)), np.random.default_rng(6), "near", 1e3 * NEAR_RELATIVE)
    assert input_fault(far["vertices"], far["segments"]) is None
    assert input_fault(far["vertices"] * 1e6, far["segments"]) is None


def test_a_domain_with_points_1e16_apart_ends_in_a_meshing_error(monkeypatch):
    """The driver's own Triangle calls (the domain's area, the coarse mesh) go through
    the guard too: a user's domain with two vertices 1e-16 apart, both used by a
    segment, gives the serial path's kind of error, and this process lives (Triangle
    refines this one without end in its child: stopped after 3 s here)."""
    import hammesh.parallel.guard as guard
    from hammesh.parallel import parallel_hamiltonian

    monkeypatch.setattr(guard, "ISOLATED_SECONDS", 3.0)
    v = [[0, 0], [1, 0], [1, 1], [0, 1], [0.3, 0.3], [0.3 + 1e-16, 0.3], [0.6, 0.6]]
    dom = hammesh.Domain(vertices=v, segments=[[0, 1], [1, 2], [2, 3], [3, 0], [4, 6], [5, 6]])
    assert input_fault(np.array(dom.vertices), np.array(dom.segments)) is not None
    status, value = _in_child(lambda: parallel_hamiltonian(dom, min_angle=30, max_area=1e-3, tiles=2).n_triangles)
    assert status in ("ok", "error"), (status, value)
    if status == "error":
        assert value.startswith("MeshingError") and "1.11e-16 apart" in value, value


def test_a_small_tiles_band_runs_in_a_child_and_a_big_ones_here(monkeypatch):
    """The band's Triangle call of a tile below ``BAND_ISOLATED_BELOW`` estimated
    triangles runs in a child (it crashed the interpreter twice on clean checkouts),
    a bigger tile's here (a child per 0.75M band cost the 6M command 1.05 -> 1.53x)."""
    import hammesh.parallel.tile_mesh as tm

    dom = hammesh.read_domain("hammesh/data/demo.poly")
    d = decompose(dom, min_angle=30, max_area=1e-3, n_tiles=2)
    asked = []
    real = tm.triangulate_guarded

    def spy(data, switches, what, seconds=None, isolate=False):
        asked.append(isolate)
        return real(data, switches, what, seconds, isolate)

    monkeypatch.setattr(tm, "triangulate_guarded", spy)
    t = d.tiles[0]
    assert mesh_tile(t, 30, 1e-3).info.get("lattice") == "band" and asked == [True]
    monkeypatch.setattr(tm, "BAND_ISOLATED_BELOW", 0)
    assert mesh_tile(t, 30, 1e-3).info.get("lattice") == "band" and asked == [True, False]
