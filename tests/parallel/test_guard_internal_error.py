"""Triangle's internal error in an in-process call is a MeshingError, never a RuntimeError.

Session 18: the ``triangle`` wrapper (20250106) jumps out of Triangle's C code on its
internal errors (``longjmp`` from ``triexit``/``segmentintersection``) and raises
``RuntimeError``; the guarded in-process call let it through, so a tile's band run that
hit one ended the parallel command with a traceback (exit 1) instead of falling back
to the tile's plain run. The input below (a segment's end within ~1e-15 of another
segment's inside, minimised from 42 such failures in 300 random near-feature PSLGs)
raises it in every run: 45 of 45 forked runs, with and without ``MALLOC_PERTURB_`` and
with a Triangle build whose pool items and stack variables start filled with a
pattern. The call runs in a child (``run_isolated``), so that a crash fails the test
instead of killing pytest.
"""

from __future__ import annotations

import numpy as np
import pytest

from hammesh.errors import MeshingError
from hammesh.meshing.isolate import run_isolated

#: point 3 lies ~1e-15 off the inside of segment (1, 0); point 4 lies on no segment
VERTICES = [[0.6757854289521197, 0.5571632515151308], [0.6492114289370233, -0.11671341773251677],
            [0.07805703551259177, 0.7029980454382135], [0.6698753367097389, 0.40729220188092186], [0.05, 0.0]]
SEGMENTS = [[1, 0], [2, 3]]
SWITCHES = "pq30a0.01YnQ"


def _data() -> dict:
    return {"vertices": np.array(VERTICES), "segments": np.array(SEGMENTS, np.int32)}


def _raw_call() -> str:
    """``triangle.triangulate`` itself: what it raises (the class the guard converts)."""
    import triangle

    try:
        triangle.triangulate(_data(), SWITCHES)
    except RuntimeError as exc:
        return f"RuntimeError: {exc}"
    return "no error"


def _guarded_in_process() -> str:
    """``triangulate_guarded`` with the call kept in this process (the input is flagged
    suspect, which would send it to a child: the flag is switched off here, in the child
    of the test, to reach the in-process path that unflagged input takes)."""
    from hammesh.parallel import guard

    guard.input_fault = lambda vertices, segments: None
    try:
        guard.triangulate_guarded(_data(), SWITCHES, "the test's tile")
    except MeshingError as exc:
        return f"MeshingError: {exc}"
    return "no error"


def test_the_input_makes_triangle_raise_its_internal_error():
    assert run_isolated(_raw_call, (), name="Triangle (raw)", timeout=60).startswith("RuntimeError")


def test_an_in_process_internal_error_is_a_meshing_error_naming_the_call():
    said = run_isolated(_guarded_in_process, (), name="Triangle (guarded)", timeout=60)
    assert said.startswith("MeshingError: Triangle failed on the test's tile"), said


def test_the_flagged_input_fails_in_a_child_as_a_meshing_error():
    from hammesh.parallel.guard import input_fault, triangulate_guarded

    assert input_fault(np.array(VERTICES), np.array(SEGMENTS)) is not None
    with pytest.raises(MeshingError, match="the test's tile"):
        triangulate_guarded(_data(), SWITCHES, "the test's tile")


@pytest.mark.parametrize("change, said", [
    (lambda d: d.update(segment_markers=np.zeros((3, 1), np.int32)), "3 segment markers for 2 segments"),
    (lambda d: d.update(segments=np.array([[1, 0], [2, 5]], np.int32)), "not ending at the 5 vertices"),
    (lambda d: d.update(segments=np.array([[1, 0], [-1, 3]], np.int32)), "not ending at the 5 vertices"),
    (lambda d: d.update(holes=np.zeros((2, 3))), "holes of shape (2, 3)"),
])
def test_a_malformed_input_is_refused_before_triangle_reads_it(change, said):
    """Markers longer than the segments made Triangle read segment ends past the
    segments' array (valgrind: invalid reads in ``formskeleton``): refused, never run."""
    from hammesh.parallel.guard import malformed, triangulate_guarded

    data = _data()
    data["segment_markers"] = np.zeros((2, 1), np.int32)
    assert malformed(data) is None
    change(data)
    assert said in malformed(data)
    with pytest.raises(MeshingError, match="internal error: Triangle's input for the test's tile is malformed"):
        triangulate_guarded(data, SWITCHES, "the test's tile")
