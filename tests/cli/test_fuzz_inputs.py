"""Malformed inputs through every subcommand: exit 2, one stderr line, no traceback, no
stray file, the input unchanged (issue 12: "never exit 1 on bad input").

The fast part calls :func:`hammesh.cli.main` in-process (one interpreter for all
cases); the slow part runs a sample in real subprocesses, where a crash of the
interpreter or a stray print would show.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hammesh.cli import main

SQUARE_POLY = "4 2 0 1\n1 0 0 1\n2 1 0 1\n3 1 1 1\n4 0 1 1\n4 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n0\n"


def _npy(arr: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


#: name -> bytes: files no reader may accept
MALFORMED: dict[str, bytes] = {
    "empty.poly": b"",
    "garbage.poly": b"\x00\xff\xfe garbage\n",
    "huge_count.poly": b"99999999999999 2 0 0\n1 0 0\n",
    "int64_overflow.poly": b"4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n99999999999999999999 0\n0\n",
    "nan.node": b"3 2 0 0\n1 nan 0\n2 1 0\n3 0 1\n",
    "huge_count.ele": b"100000000000 3 0\n1 1 2 3\n",
    "truncated.vtu": b"<?xml version='1.0'?><VTKFile type='UnstructuredGrid'><Unstruc",
    "text.vtu": "no xml here \u00e9".encode(),
    "empty.obj": b"",
    "bad_index.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    "bad_relative.obj": b"v 0 0 0\nf -1 -2 -3\n",
    "bad_number.obj": b"v 0 0 x\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "header_only.ply": b"ply\nformat ascii 1.0\nelement vertex 3\n",
    "header_only.off": b"OFF\n",
    "polydata_truncated.vtk": b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0\n",
    "polydata_bad_cells.vtk": (
        b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
        b"POLYGONS 1 4\n3 0 1 7\n"
    ),
    "empty.npy": _npy(np.zeros((0, 2))),
    "strings.npy": _npy(np.array([["a", "b"], ["c", "d"], ["e", "f"]])),
    "complex.npy": _npy(np.array([[0, 0], [1, 0], [0, 1j]])),
    "nan.npy": _npy(np.array([[0, 0], [1, 0], [0, np.nan]])),
    "not_npy.npy": b"not a numpy file",
    "open_header.npy": _npy(np.zeros((3, 2))).replace(b"}", b"(", 1),  # tokenize: EOF in multi-line
    "latin1.wkt": "POLYGON ((0 0, 1 0, 0 1)) \u00e9".encode("latin-1"),
    "hole_crossing.wkt": b"POLYGON ((0 0, 1 0, 0 1), (0.5 0.5, 2 0.5, 0.5 2))",  # holes are read now
    "list.geojson": b"[1, 2, 3]",
    "null.geojson": b"null",
    "number_ring.geojson": b'{"type": "Polygon", "coordinates": [5]}',
    "number_point.geojson": b'{"type": "Polygon", "coordinates": [[1, 2, 3]]}',
    "deep.geojson": b"[" * 100_000 + b"]" * 100_000,
    "text_points.txt": b"0 0\n1 x\n",
    "one_point.txt": b"0 0\n",
}

#: subcommand -> (argv before the input, argv after it, the suffixes it reads)
COMMANDS = {
    "mesh": (["mesh"], ["-o", "{out}/o.vtu"], (".poly", ".node", ".ele", ".vtu", ".obj", ".ply", ".off", ".vtk")),
    "check": (["check"], [], (".ele", ".vtu", ".obj", ".ply", ".off", ".vtk")),
    "strip": (["strip"], ["-o", "{out}/o.json"], (".ele", ".vtu", ".obj", ".ply", ".off", ".vtk")),
    "surface": (["surface"], ["-o", "{out}/o.vtu"], (".vtu", ".obj", ".ply", ".off", ".vtk")),
    "points": (["points"], ["-o", "{out}/o.vtu"], (".node", ".npy", ".txt")),
    "polygon": (["polygon"], ["-o", "{out}/o.json"], (".poly", ".wkt", ".geojson", ".txt", ".npy")),
    "partition": (["partition"], ["-k", "2", "-o", "{out}/o.vtu"], (".ele", ".vtu", ".obj", ".ply", ".off", ".vtk")),
}

CASES = [
    (cmd, name)
    for cmd, (_, _, suffixes) in COMMANDS.items()
    for name in MALFORMED
    if Path(name).suffix in suffixes
]


def _setup(tmp_path: Path, cmd: str, name: str) -> tuple[list[str], Path, Path, bytes]:
    src = tmp_path / "in"
    out = tmp_path / "out"
    src.mkdir()
    out.mkdir()
    f = src / name
    f.write_bytes(MALFORMED[name])
    if f.suffix == ".ele":  # its .node sibling, valid
        f.with_suffix(".node").write_text("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n")
    before, after, _ = COMMANDS[cmd]
    argv = [*before, str(f), *(a.format(out=out) for a in after)]
    return argv, src, out, MALFORMED[name]


def _assert_clean(src: Path, out: Path, name: str, data: bytes) -> None:
    assert os.listdir(out) == [], "an output was left behind"
    assert (src / name).read_bytes() == data, "the input changed"
    assert sorted(p.name for p in src.iterdir() if p.name.startswith(".")) == []


@pytest.mark.parametrize("cmd, name", CASES)
def test_malformed_input_exit_2_one_line(tmp_path, capsys, cmd, name):
    argv, src, out, data = _setup(tmp_path, cmd, name)
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("hammesh: error:"), err
    assert "Traceback" not in err
    _assert_clean(src, out, name, data)


BAD_OPTIONS = [
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--timeout", "inf"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--timeout", "1e300"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--timeout", "nan"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--min-angle", "nan"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--max-area", "-1"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--max-steiner", "-5"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--report", "{out}/nodir/r.json"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--png", "{out}/nodir/r.png"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--strip", "{out}/nodir/s.json"],
    ["mesh", "{sq}", "-o", "{out}/o.vtu", "--report", "{out}/x.json", "--strip", "{out}/x.json"],
    ["mesh", "{sq}", "-o", "{out}/o.unknown"],
    ["mesh", "{sq}", "-o", "{out}"],
    ["mesh", "{sq}", "-o", "{sq}"],
    ["points", "{pts}", "-o", "{out}/o.vtu", "--seed", "-1"],
    ["points", "{pts}", "-o", "{out}/nodir/o.vtu"],
    ["points", "{pts}", "-o", "{out}/o.unknown"],
    ["polygon", "{pts}", "-o", "{out}/o.unknown"],
    ["polygon", "{pts}", "--png", "{out}/o.jpg"],
    ["polygon", "{pts}", "-o", "{out}/nodir/o.json"],
    ["demo", "--out", "{out}/demo", "--max-area", "0"],
    ["demo", "--out", "{out}/demo", "--min-angle", "nan"],
]


@pytest.mark.parametrize("argv", BAD_OPTIONS, ids=lambda a: " ".join(a[2:]).replace("{", "").replace("}", ""))
def test_bad_option_exit_2_nothing_written(tmp_path, capsys, argv):
    src, out = tmp_path / "in", tmp_path / "out"
    src.mkdir()
    out.mkdir()
    sq = src / "sq.poly"
    sq.write_text(SQUARE_POLY)
    pts = src / "pts.txt"
    pts.write_text("0 0\n1 0\n1 1\n0 1\n0.5 0.4\n")
    before = {p.name: p.read_bytes() for p in src.iterdir()}
    code = main([a.format(sq=sq, out=out, pts=pts) for a in argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert os.listdir(out) == []
    assert {p.name: p.read_bytes() for p in src.iterdir()} == before


@pytest.mark.slow
@pytest.mark.parametrize("cmd, name", CASES[::5])
def test_malformed_input_in_a_subprocess(tmp_path, cmd, name):
    argv, src, out, data = _setup(tmp_path, cmd, name)
    proc = subprocess.run([sys.executable, "-m", "hammesh", *argv], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and "Traceback" not in proc.stderr, proc.stderr
    _assert_clean(src, out, name, data)


def test_every_subcommand_is_fuzzed():
    from hammesh.cli import COMMANDS as ALL

    assert set(ALL) - {"demo"} == set(COMMANDS)
    assert {c for c, _ in CASES} == set(COMMANDS)
    json.dumps(CASES)  # plain data, so the ids stay readable
