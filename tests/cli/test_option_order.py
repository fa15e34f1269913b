"""Options are refused before any input is read or meshed (a bad --keep must not wait
for a minute of Triangle), on the serial and the parallel path alike."""

from __future__ import annotations

import pytest

import hammesh.cli.pipeline as pipeline
import hammesh.parallel.command as command
from hammesh.cli import main

SQUARE = "4 2 0 1\n1 0 0 1\n2 1 0 1\n3 1 1 1\n4 0 1 1\n4 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n0\n"


@pytest.fixture
def no_work(monkeypatch):
    """Reading the input or starting the parallel path fails the test."""

    def refuse(*_a, **_k):
        raise AssertionError("work started before the options were checked")

    monkeypatch.setattr(pipeline, "load_input", refuse)
    monkeypatch.setattr(command, "run_parallel", refuse)


@pytest.mark.parametrize("keep", ["1.5", "-0.1", "nan", "inf"])
@pytest.mark.parametrize("parallel", [[], ["--workers", "1"]])
def test_bad_keep_refused_before_reading(tmp_path, capsys, no_work, keep, parallel):
    src = tmp_path / "sq.poly"
    src.write_text(SQUARE)
    out = tmp_path / "out.vtu"
    code = main(["mesh", str(src), "-a", "1e-9", "--keep", keep, "-o", str(out), *parallel])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "--keep" in err[0] and "Traceback" not in err[0]
    assert not out.exists() and src.read_text() == SQUARE


@pytest.mark.parametrize("keep", ["0", "0.5", "1"])
def test_good_keep_reaches_the_work(tmp_path, capsys, no_work, keep):
    src = tmp_path / "sq.poly"
    src.write_text(SQUARE)
    code = main(["mesh", str(src), "--keep", keep, "-o", str(tmp_path / "o.vtu")])
    # (the CLI reports the fixture's AssertionError as an internal error, exit 1)
    assert code == 1 and "work started" in capsys.readouterr().err
