"""``--keep`` is sparse mode's option: given with ``--mode incircle`` it is refused (it
used to be ignored silently), and its CLI default is the library's."""

from __future__ import annotations

import subprocess
import sys

from hammesh.cli import mesh


def test_the_cli_default_is_the_librarys():
    from hammesh.postprocess.sparse import KEEP

    assert mesh.KEEP == KEEP


def test_keep_with_incircle_mode_exits_2_naming_the_option(tmp_path):
    out = tmp_path / "out.vtu"
    p = subprocess.run([sys.executable, "-m", "hammesh", "mesh", "no-such.poly", "--mode", "incircle", "--keep", "0.5",
                        "-o", str(out)], capture_output=True, text=True)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "--keep" in lines[0] and "sparse" in lines[0]
    assert not out.exists()


def test_keep_with_sparse_mode_is_checked(tmp_path):
    p = subprocess.run([sys.executable, "-m", "hammesh", "mesh", "no-such.poly", "--keep", "1.5"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "--keep" in p.stderr and len(p.stderr.strip().splitlines()) == 1
