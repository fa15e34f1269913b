"""Quality refinement is bounded: a domain that needs more added points than
``STEINER_BUDGET`` (a thin part, a far vertex) is refused by name after a bounded run,
never meshed until memory is gone; ``max_steiner`` of the caller's lifts it."""

from __future__ import annotations

from pathlib import Path

import pytest

import hammesh
from hammesh.cli import main
from hammesh.meshing import options, triangle_switches
from hammesh.meshing.options import MeshOptions


def wedge(length: float) -> hammesh.Domain:
    """A quadrilateral 1 high whose top-right corner lies ``length`` away: the far corner's
    angle is about 1 / length, and q-refinement needs ~length points to reach it."""
    return hammesh.Domain(vertices=[[0, 0], [1, 0], [length, 1], [0, 1]], segments=[[0, 1], [1, 2], [2, 3], [3, 0]])


def test_switches_carry_the_budget_only_when_refining() -> None:
    dom = wedge(10.0)
    assert f"S{options.STEINER_BUDGET}" in triangle_switches(dom, MeshOptions(min_angle=30))
    assert f"S{options.STEINER_BUDGET}" in triangle_switches(dom, MeshOptions(conforming_delaunay=True))
    assert "S" not in triangle_switches(dom, MeshOptions(max_area=0.1))  # (check_sizes estimates it)
    assert triangle_switches(dom, MeshOptions(min_angle=30, max_steiner=7)).count("S") == 1


@pytest.mark.parametrize("isolate", [False, True])
def test_a_domain_beyond_the_budget_is_refused(monkeypatch, isolate: bool) -> None:
    monkeypatch.setattr(options, "STEINER_BUDGET", 500)
    small = hammesh.quality_mesh(wedge(20.0), min_angle=30, isolate=isolate)  # within the budget
    assert small.n_points - 4 < 500
    with pytest.raises(hammesh.InvalidDomainError, match="more than 500 added points to reach min angle 30"):
        hammesh.quality_mesh(wedge(1e4), min_angle=30, isolate=isolate)
    capped = hammesh.quality_mesh(wedge(1e4), min_angle=30, max_steiner=300, isolate=isolate)
    assert capped.n_points <= 4 + 300  # the caller's own cap: meshed, stopping short


def test_the_command_exits_2_with_one_line(monkeypatch, tmp_path: Path, capsys) -> None:
    monkeypatch.setattr(options, "STEINER_BUDGET", 500)
    poly = tmp_path / "wedge.poly"
    poly.write_text("4 2 0 0\n1 0 0\n2 1 0\n3 1e4 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n")
    out = tmp_path / "w.vtu"
    assert main(["mesh", str(poly), "-q", "30", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "more than 500 added points" in err[0]
    assert not out.exists()
