"""hammesh.strips.warm: the two-halves encoder's kernels loaded ahead of the first call."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from hammesh.strips.warm import PREPARE_GRID, quad_grid


def test_the_grid_is_a_ccw_mesh_of_two_triangles_a_quad():
    points, triangles = quad_grid(PREPARE_GRID)
    assert triangles.dtype == np.int64 and points.dtype == np.float64
    assert len(triangles) == 2 * PREPARE_GRID**2 and len(points) == (PREPARE_GRID + 1) ** 2
    p = points[triangles]
    area = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])
    assert np.allclose(area, 1.0)  # twice the area of half a unit quad, counter-clockwise
    assert len(np.unique(np.sort(triangles, axis=1), axis=0)) == len(triangles)


_FRESH = r"""
import json
from hammesh.strips import _dual_kernels, _fingerprint_kernels, _greedy_strip_kernels, _halves_kernels
from hammesh.strips.warm import prepare
kernels = [_halves_kernels.vertex_cells_into, _halves_kernels.row_cells_into, _halves_kernels.rows_of_cells_into,
           _dual_kernels.face_flags,
           _halves_kernels.pair_records_into, _greedy_strip_kernels._greedy_strip_into,
           _fingerprint_kernels.rows_fingerprint_into, _fingerprint_kernels.draws_fingerprint, _halves_kernels.shared_edges]
before = [len(k.signatures) for k in kernels]
t = prepare(fast=True)
t.join()
print(json.dumps([before, [len(k.signatures) for k in kernels]]))
"""


def test_prepare_loads_the_fast_paths_kernels_in_a_fresh_process():
    """Before: none of encode(fast=True)'s two-halves kernels is loaded; after the thread: all."""
    out = subprocess.run([sys.executable, "-c", _FRESH], capture_output=True, text=True, check=True).stdout
    before, after = json.loads(out.strip().splitlines()[-1])
    assert before == [0] * len(before) == [0] * 9 and all(n >= 1 for n in after)


def test_the_grid_goes_through_both_halves_in_both_modes():
    """prepare's grid must not be sent to the one-thread path (then the halves' later kernels
    would not be loaded): a verified two-halves buffer in both modes, drawing every triangle."""
    from hammesh.strips import decode_gl_strip
    from hammesh.strips.encode import half_encoder
    from hammesh.strips.gl import RESTART_INDEX
    from hammesh.strips.halves import encode_in_halves

    from .conftest import oriented_set

    points, triangles = quad_grid(PREPARE_GRID)
    for finish in (None, half_encoder(RESTART_INDEX)):
        s = encode_in_halves(points, triangles, RESTART_INDEX, True, 1, finish)
        assert s is not None and s.n_strips >= 2  # the halves' parts, joined by a restart
        assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(triangles)


def test_the_first_large_encoding_of_each_mode_loads_its_kernels_ahead_once(monkeypatch):
    """encode() starts warm.prepare on a thread for the first two-halves call of each mode in a
    process (fast and default apart), never again, and never when one core is allowed."""
    from hammesh import threads
    from hammesh.mesh import Mesh
    from hammesh.strips import encode, warm
    from hammesh.strips.halves import HALVES_FROM

    enc = sys.modules["hammesh.strips.encode"]
    calls = []
    monkeypatch.setattr(enc, "_LOADING", set())
    monkeypatch.setattr(warm, "prepare", lambda background=True, fast=False: calls.append((background, fast)))
    side = int(np.ceil(np.sqrt(HALVES_FROM / 2)))
    mesh = Mesh(*quad_grid(side))
    small = Mesh(*quad_grid(PREPARE_GRID))
    previous = threads.limit(1)
    try:
        encode(mesh, fast=True)  # one thread: no halves, nothing loaded ahead
    finally:
        threads.limit(previous)
    encode(small, fast=True)  # below HALVES_FROM: the one-thread path
    assert calls == []
    if threads.cores() < 2:
        return
    for fast in (True, True, False, False, True):
        s = encode(mesh, fast=fast)
        assert s.n_triangles == len(mesh.triangles)
    assert calls == [(True, True), (True, False)]



def test_prepare_never_takes_the_work_arrays_pool(monkeypatch):
    """prepare's grid brings its own work arrays: encode starts prepare beside a large call,
    which would find the pool emptied (and fault in new arrays) if the grid borrowed it."""
    from hammesh.strips import halves
    from hammesh.strips.warm import prepare

    def refuse():
        raise AssertionError("prepare borrowed the pool")

    monkeypatch.setattr(halves, "borrow", refuse)
    for fast in (True, False):
        prepare(background=False, fast=fast)
