"""The human summary of `hammesh mesh` says where sparse mode's local quality rule was
not kept (issue 13: "take the best one available and count it in the report")."""

from __future__ import annotations

import hammesh
from hammesh.cli.pipeline import summary


def _box() -> hammesh.Domain:
    return hammesh.Domain.from_polygon([[0, 0], [3, 0], [3, 2], [0, 2]])


def test_summary_names_triangles_below_the_parent_rule_only_when_there_are_some():
    m = hammesh.quality_mesh(_box(), max_area=0.1, min_angle=30)
    seen = set()
    for keep in (0.0, 0.9, 1.0):  # keep=0 cannot be broken; a split breaks keep=1
        h = hammesh.hamiltonian(m, mode="sparse", keep=keep)
        below = h.report["below_parent_rule"]
        text = summary(h)
        assert ("below" in text) == (below > 0), text
        if below:
            assert f"{below:,} new triangle(s) below {keep:g} x" in text
        seen.add(below > 0)
    assert seen == {True, False}  # both lines were looked at


def test_summary_says_what_the_input_needed(tmp_path, capsys):
    import meshio
    import numpy as np

    from hammesh.cli import main

    pts = np.array([[0, 0, 5], [1, 0, 5], [1, 1, 5], [0, 1, 5.0]])
    meshio.Mesh(pts, [("quad", np.array([[0, 1, 2, 3]]))]).write(tmp_path / "q.vtu")
    assert main(["mesh", str(tmp_path / "q.vtu"), "-o", str(tmp_path / "o.vtu")]) == 0
    out = capsys.readouterr().out
    lines = [x for x in out.splitlines() if x.startswith("repaired: ")]
    assert len(lines) == 1 and "z = 5" in lines[0] and "(written at z = 0)" in lines[0]
    assert "and 1 more (the report's 'repairs')" in lines[0]  # (the quad split)
    m = hammesh.quality_mesh(_box(), max_area=0.5)
    assert "repaired" not in summary(hammesh.hamiltonian(m))
