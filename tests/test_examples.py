"""The examples are run by the tests (scikit-fem's habit): they must keep working."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.py"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs(path: Path, tmp_path: Path) -> None:
    if "import skfem" in path.read_text() or "from skfem" in path.read_text():
        pytest.importorskip("skfem")  # the optional extra [fem]
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    h = module.main(tmp_path)
    assert h.report["verified"] is True
    assert any(tmp_path.iterdir())
