"""tester18 r11: messages that left something out (session 19)."""

from __future__ import annotations

import errno
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.errors import FileFormatError, OutputError

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")


@pytest.mark.parametrize("suffix, also", [(".ele", ["plate.node", "plate.poly"]), (".pvtu", ["plate.0.vtu"]),
                                          (".vtu", [])])
def test_the_wrote_line_names_every_file_written(tmp_path, capsys, suffix, also):
    out = tmp_path / f"plate{suffix}"
    assert main(["mesh", DEMO, "-q", "30", "-a", "0.05", "-o", str(out)]) == 0
    line = [x for x in capsys.readouterr().out.splitlines() if x.startswith("wrote mesh:")]
    assert len(line) == 1
    for name in also:
        assert str(tmp_path / name) in line[0] and (tmp_path / name).is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name, *also])


def test_read_domain_of_a_directory_names_the_path_and_what_it_is(tmp_path):
    d = tmp_path / "inputs"
    d.mkdir()
    with pytest.raises(FileFormatError, match=rf"^{d}: is a directory"):
        hammesh.read_domain(d)
    with pytest.raises(FileFormatError, match=r"^/dev/null: not a regular file"):
        hammesh.read_domain("/dev/null")
    with pytest.raises(FileFormatError, match=rf"^{tmp_path / 'x.txt'}: unknown domain file suffix"):
        hammesh.read_domain(tmp_path / "x.txt")


def test_the_verify_subpackage_imports_in_both_spellings():
    """``hammesh.verify`` is the function; ``import hammesh.verify.certificate as C``
    failed ("cannot import name 'certificate' from 'verify'")."""
    code = ("import types, hammesh, hammesh.verify.certificate as C, hammesh.verify.stored as S; "
            "from hammesh.verify import runs; import hammesh.verify.runs as R; "
            "assert C.__name__ == 'hammesh.verify.certificate' and S.verify_stored_mesh and R is runs; "
            "assert isinstance(hammesh.verify, types.FunctionType) and hammesh.verify is C.verify")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_pvtu_that_cannot_be_written_names_the_file_and_leaves_nothing(tmp_path, monkeypatch):
    from hammesh.io import vtu

    h = hammesh.hamiltonian(hammesh.quality_mesh(hammesh.read_domain(DEMO), min_angle=30, max_area=0.05,
                                                 isolate=False))

    def full(*args, **kw):
        raise OSError(errno.EFBIG, "File too large")

    monkeypatch.setattr(vtu, "write_raw", full)
    with pytest.raises(OutputError, match=rf"^{tmp_path / 'm.0.vtu'}: cannot write \(File too large\)"):
        hammesh.write(h, tmp_path / "m.pvtu")
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    hammesh.write(h, tmp_path / "m.pvtu")
    assert np.array_equal(hammesh.read_mesh(tmp_path / "m.pvtu").triangles, h.triangles)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.0.vtu", "m.pvtu"]


def test_the_one_based_note_only_where_the_message_numbers_something(tmp_path):
    tiny = tmp_path / "tiny.poly"
    tiny.write_text("3 2 0 0\n1 0 0\n2 1e-299 0\n3 0 1e-299\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n")
    with pytest.raises(hammesh.InvalidDomainError) as info:
        hammesh.read_domain(tiny)
    assert "spans only" in str(info.value) and "zero-based" not in str(info.value)
    cross = tmp_path / "x.poly"
    cross.write_text("4 2 0 0\n1 0 0\n2 1 1\n3 1 0\n4 0 1\n2 0\n1 1 2\n2 3 4\n0\n")
    with pytest.raises(hammesh.InvalidDomainError, match=r"segments 0 and 1 cross .*\(indices zero-based"):
        hammesh.read_domain(cross, strict=True)
