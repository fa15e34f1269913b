"""A planar input whose triangles overlap without sharing an edge is refused (exit 2)."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.cli import main
from hammesh.errors import InvalidMeshError

SQUARE = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1]], dtype=float)
FAN = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])


def with_triangle(corners: np.ndarray) -> hammesh.Mesh:
    """The fan square plus one counter-clockwise triangle with corners of its own."""
    pts = np.vstack([SQUARE, corners])
    return hammesh.Mesh(pts, np.vstack([FAN, [[5, 6, 7]]]))


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_triangle_touching_at_a_vertex_and_overlapping_is_refused(mode):
    pts = np.vstack([SQUARE, [[3, 1.2], [3, 0.8]]])
    m = hammesh.Mesh(pts, np.vstack([FAN, [[4, 6, 5]]]))  # shares vertex 4 only, lies over [1, 2, 4]
    with pytest.raises(InvalidMeshError, match=r"triangles 1 and 4 overlap"):
        hammesh.hamiltonian(m, mode=mode)


@settings(max_examples=60, deadline=None)
@given(st.floats(-1.0, 3.0), st.floats(-1.0, 3.0), st.floats(0.05, 1.5))
def test_a_separate_triangle_is_refused_exactly_when_it_overlaps(x, y, s):
    corners = np.array([[x, y], [x + s, y], [x, y + s]])
    # the square [0, 2]^2 and the triangle's interiors meet iff their boxes overlap and the
    # triangle's hypotenuse x + y < x0 + y0 + s passes above the square's corner (0, 0)
    overlaps = x < 2 and y < 2 and x + s > 0 and y + s > 0 and (x + y + s) > 0
    if overlaps:
        with pytest.raises(InvalidMeshError, match="overlap"):
            hammesh.hamiltonian(with_triangle(corners))
    else:
        h = hammesh.hamiltonian(with_triangle(corners))
        assert len(h.components) == 2


def test_cli_refuses_overlap_one_line_no_output(tmp_path, capsys):
    pts = np.vstack([SQUARE, [[3, 1.2], [3, 0.8]]])
    src = tmp_path / "overlap.vtu"
    meshio.write(src, meshio.Mesh(np.c_[pts, np.zeros(len(pts))], [("triangle", np.vstack([FAN, [[4, 6, 5]]]))]))
    out = tmp_path / "out.vtu"
    assert main(["mesh", str(src), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "overlap" in err
    assert not out.exists()


def test_triangles_own_mesh_is_not_tested_again(monkeypatch):
    from hammesh import postprocess

    calls = []
    monkeypatch.setattr(postprocess, "refuse_overlap", lambda *a: calls.append(a))
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.01)
    hammesh.hamiltonian(m)
    assert calls == []
    hammesh.hamiltonian(hammesh.Mesh(m.points, m.triangles, segments=m.segments))
    assert len(calls) == 1
