"""Option errors name the command line's option, not the library's parameter."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

import hammesh
from hammesh.cli import main
from hammesh.errors import InvalidOptionError

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")


@pytest.mark.parametrize("argv, flag, python_name", [
    (["mesh", DEMO, "-q", "50"], "--min-angle=50.0 is not valid", "min_angle"),
    (["mesh", DEMO, "-a", "-1"], "--max-area=-1.0 is not valid", "max_area"),
    (["mesh", DEMO, "-a", "1e-30"], "--max-area=1e-30 would need", "max_area"),
    (["mesh", DEMO, "-q", "30", "--parts", "100000000"], "--parts=100000000 is not valid", "k="),
    (["demo", "--min-angle", "50"], "--min-angle=50.0 is not valid", "min_angle"),
])
def test_bad_option_named_as_given(tmp_path, capsys, argv, flag, python_name):
    out = tmp_path / "o.vtu"
    args = [*argv, "-o", str(out)] if argv[0] == "mesh" else [*argv, "--out", str(tmp_path / "d")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and flag in err
    assert python_name not in err
    assert not out.exists() and not (tmp_path / "d").exists()


def test_library_keeps_its_parameter_names():
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [0, 1]])
    with pytest.raises(InvalidOptionError, match=r"^min_angle=40 is not valid") as info:
        hammesh.quality_mesh(dom, min_angle=40)
    assert info.value.option == "min_angle"
    again = pickle.loads(pickle.dumps(info.value))  # (as a Dask worker hands it back)
    assert type(again) is InvalidOptionError and again.option == "min_angle" and str(again) == str(info.value)


def test_meshing_options_on_a_mesh_are_named_as_given(tmp_path, capsys):
    out = tmp_path / "m.vtu"
    assert main(["mesh", DEMO, "-q", "30", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["mesh", str(out), "-q", "30", "-a", "1", "-o", str(tmp_path / "o.vtu")]) == 2
    err = capsys.readouterr().err
    assert "(--min-angle, --max-area)" in err and "min_angle" not in err
    assert not (tmp_path / "o.vtu").exists()
