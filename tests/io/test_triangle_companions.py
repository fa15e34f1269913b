"""``-o NAME.ele`` writes NAME.node and NAME.poly too: a NAME.poly (or .node) that hammesh
did not write, the user's domain, is never replaced (tester18 r07); hammesh's own
companions from an earlier run are."""

from __future__ import annotations

from pathlib import Path

import pytest

import hammesh
from hammesh.cli import main
from tests.helpers import plate

DOMAIN = "4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n"


@pytest.fixture(scope="module")
def mesh() -> hammesh.Mesh:
    return plate(1, 1, max_area=0.05)


@pytest.mark.parametrize("named, foreign", [("out.ele", ".poly"), ("out.ele", ".node"), ("out.node", ".poly")])
def test_a_foreign_companion_is_never_replaced(tmp_path: Path, mesh, capsys, named: str, foreign: str) -> None:
    users = (tmp_path / named).with_suffix(foreign)
    users.write_text(DOMAIN)
    src = tmp_path / "m.vtu"
    hammesh.write(mesh, src)
    assert main(["mesh", str(src), "-o", str(tmp_path / named)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{users.name}: exists and is not a file hammesh wrote" in err[0]
    with pytest.raises(hammesh.OutputError, match="is not a file hammesh wrote"):
        hammesh.write(mesh, tmp_path / named)
    assert users.read_text() == DOMAIN
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["m.vtu", users.name])  # nothing else written


def test_hammesh_companions_are_replaced(tmp_path: Path, mesh) -> None:
    out = tmp_path / "out.ele"
    hammesh.write(mesh, out)
    first = out.with_suffix(".poly").read_text()
    hammesh.write(mesh, out)  # again: its own triple
    assert out.with_suffix(".poly").read_text() == first
    src = tmp_path / "m.vtu"
    hammesh.write(mesh, src)
    assert main(["mesh", str(src), "-o", str(out)]) == 0
