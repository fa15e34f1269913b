"""Triangle's input checked before an in-process call: what crashes it runs in a child.

Session 17: once in CI a tile's ``triangle.triangulate`` crashed the interpreter
(SIGSEGV). Triangle reads memory it never wrote on input with two points (nearly) at
one place, or a point (nearly) on a segment's inside; whether that kills the process
depends on its heap (the same input crashed 1-6 of 8 cases per fresh interpreter, none
in another). The parallel path calls Triangle in its own process (a Dask worker, the
driver) for speed; :func:`triangulate_guarded` keeps those calls, and sends only
suspect input to :func:`hammesh.meshing.isolate.run_isolated`, as the serial path
sends every call.
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import MeshingError

__all__ = ["NEAR_RELATIVE", "ISOLATED_SECONDS", "input_fault", "malformed", "triangulate_guarded"]

#: Triangle's input is suspect when two of its points, or a point and the inside of a
#: segment, are closer than this times the input's extent (:func:`input_fault`).
#: Measured (session 17, ``pq30a..Yn`` on a square with an inner loop and a hole, 60
#: random cases per distance): two points 0 / 1e-16 / 1e-15 / 1e-14 / 1e-13 apart
#: crashed Triangle (SIGSEGV) in 60 / 12 / 1 / 1 / 0 cases, hung past 10 s in 0 / 5 /
#: 4 / 0 / 1; a point 1e-16 / 1e-15 off a segment crashed it in 6 / 1; from 1e-12 on
#: none. An exact duplicate point a segment uses crashed it in all 60 (a process
#: that had imported only ``triangle`` and numpy, each case in a forked child); in
#: other processes 0-6 of 8 such cases (the read lands on the heap: whether it
#: faults depends on the process; the ``triangle`` package's issues #68 and #70 report
#: "random" segfaults on such input).
NEAR_RELATIVE = 1e-11
#: a suspect tile input runs in a child process (:func:`triangulate_guarded`), stopped
#: after this many seconds (Triangle loops without end on some such inputs)
ISOLATED_SECONDS = 120.0


def input_fault(vertices: np.ndarray, segments: np.ndarray) -> str | None:
    """What makes Triangle's input suspect, or None: two points, or a point and the
    inside of a segment, closer than :data:`NEAR_RELATIVE` times the input's extent.

    Why: such input crashes Triangle (SIGSEGV, the interpreter with it: a Dask worker
    dies, a command exits -11) or makes it loop for ever (measured at
    :data:`NEAR_RELATIVE`). A tile's own input never has it (the cuts keep clear of
    every vertex, ``tiles.CUT_TOUCH``; lattice points keep steps away from every
    segment), so this is the guard for what no rule foresaw. ~1-5 ms per tile (one
    sort and a sweep, :func:`~hammesh.parallel._kernels.near_feature`).
    """
    from hammesh.parallel._kernels import near_feature

    v = np.ascontiguousarray(vertices, dtype=np.float64)
    if len(v) < 2:
        return None
    extent = float(np.ptp(v, axis=0).max())
    tol = NEAR_RELATIVE * max(extent, float(np.abs(v).max()))
    kind, i, j = near_feature(v, np.lexsort((v[:, 1], v[:, 0])), np.ascontiguousarray(segments, dtype=np.int64), tol)
    if kind == 0:
        return f"points {i} and {j} lie {float(np.hypot(*(v[i] - v[j]))):.3g} apart"
    if kind == 1:
        return f"point {i} lies within {tol:.3g} of the inside of segment {j}"
    return None


def malformed(data: dict) -> str | None:
    """What makes Triangle's input dict inconsistent, or None: vertices not ``(n, 2)``,
    a segment end not a vertex, segment markers not one per segment, holes not
    ``(h, 2)`` (values are the domain's validation's: ``hammesh.domain.validate``).

    Why: the ``triangle`` wrapper takes each count from the array it sets last
    (``segment_markers`` after ``segments``): markers longer than the segments make
    Triangle read segment ends past the segments' array (``formskeleton``; valgrind:
    invalid reads, session 18), i.e. whatever the heap holds there, a crash or a
    stray segment depending on the process. Cheap (a few reductions), so every call
    checks it; the tiles' own inputs never have it (5,567 band and plain inputs of the
    random-domain tests' generator, session 18).
    """
    v = np.asarray(data["vertices"])
    if v.ndim != 2 or v.shape[1] != 2:
        return f"vertices of shape {v.shape} (not (n, 2))"
    s = np.asarray(data.get("segments", np.zeros((0, 2), np.int64)))
    if s.size and (s.ndim != 2 or s.shape[1] != 2 or int(s.min()) < 0 or int(s.max()) >= len(v)):
        return f"segments of shape {s.shape} not ending at the {len(v)} vertices"
    markers = data.get("segment_markers")
    if markers is not None and len(markers) != len(s.reshape(-1, 2)):
        return f"{len(markers)} segment markers for {len(s.reshape(-1, 2))} segments"
    h = np.asarray(data.get("holes", np.zeros((0, 2))))
    if h.size and (h.ndim != 2 or h.shape[1] != 2):
        return f"holes of shape {h.shape} (not (h, 2))"
    return None


def _triangulate_plain(data: dict, switches: str) -> dict:
    import triangle

    return dict(triangle.triangulate(data, switches))


def triangulate_guarded(data: dict, switches: str, what: str, seconds: float | None = None,
                        isolate: bool = False) -> dict:
    """Triangle's ``triangulate(data, switches)`` (of a tile, or the driver's coarse
    mesh of the whole domain: ``what`` names it in messages): in this process, unless
    :func:`input_fault` finds the input suspect; then in a child process
    (:func:`hammesh.meshing.isolate.run_isolated`), where a crash or a hang becomes a
    :class:`~hammesh.errors.MeshingError` naming ``what`` instead of taking this
    process (a Dask worker, the command) down.

    Why not always a child: per tile the fork, the pipe and the copy-on-write faults
    cost ~0.01-0.02 s CPU of a worker of ~700 MB (measured, session 17), ~1 % of the
    6M command's CPU over its tiles, for inputs the decomposition never makes.
    ``seconds``: the child's time limit (default :data:`ISOLATED_SECONDS`). ``isolate``:
    a child whatever the input (the lattice band: see ``tile_mesh.mesh_band``).
    Triangle's internal error in this process (the ``triangle`` wrapper's
    ``RuntimeError``) is a :class:`~hammesh.errors.MeshingError` too.
    """
    wrong = malformed(data)
    if wrong is not None:  # (our own bug: no run of Triangle, here or in a child, reads it right)
        raise MeshingError(f"internal error: Triangle's input for {what} is malformed: {wrong}")
    fault = input_fault(data["vertices"], data.get("segments", np.zeros((0, 2), np.int64)))
    if fault is None and not isolate:
        try:
            return _triangulate_plain(data, switches)
        except RuntimeError as exc:
            # Triangle's internal error ("Topological inconsistency", "Unable to
            # locate PSLG vertex", ...): the ``triangle`` wrapper (20250106) jumps out
            # of the C code (``longjmp``) and raises RuntimeError; said as a
            # MeshingError as the child's is, so the band falls back to the plain run
            # and a command says one line, not a traceback (session 18)
            raise MeshingError(f"Triangle failed on {what}: {exc}") from None
    fault = fault or "isolated"
    from hammesh.meshing.isolate import run_isolated

    try:
        return run_isolated(_triangulate_plain, (data, switches), name=f"Triangle ({what}: {fault})",
                            timeout=ISOLATED_SECONDS if seconds is None else seconds)
    except MeshingError:
        raise
    except Exception as exc:  # (Triangle's own failure in the child: said as one)
        raise MeshingError(f"Triangle failed on {what} ({fault}): {exc}") from None
