"""The command line: verbs, outputs, exit codes, one-line errors, nothing half-written."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import triangle

import hammesh
from hammesh.cli import main

DATA = Path(triangle.__file__).parent / "data"


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "hammesh", *args], capture_output=True, text=True, cwd=cwd, timeout=300
    )


def test_mesh_writes_all_outputs(tmp_path: Path) -> None:
    out, rep, png = tmp_path / "a.vtu", tmp_path / "a.json", tmp_path / "a.png"
    code = main([
        "mesh", str(DATA / "A.poly"), "--min-angle", "30", "--max-area", "0.05",
        "-o", str(out), "--report", str(rep), "--png", str(png),
    ])
    assert code == 0
    report = json.loads(rep.read_text())
    for key in ("triangles", "vertices", "input_triangles", "steiner_points", "midpoints", "components",
                "min_angle_input_deg", "min_angle_output_deg", "max_angle_output_deg", "verified", "seconds"):
        assert key in report, key
    assert set(report["seconds"]) >= {"mesh", "hamiltonian", "verify"}
    assert sum(report["components"]) == report["triangles"]
    assert report["verified"] is True
    assert report["min_angle_output_deg"] >= 0.5 * report["min_angle_input_deg"] * (1 - 1e-9)
    back = hammesh.read_mesh(out)
    assert back.n_triangles == report["triangles"]
    assert png.stat().st_size > 1000
    assert main(["check", str(out)]) == 0


@pytest.mark.parametrize("suffix", [".vtu", ".msh", ".obj", ".ply", ".ele", ".xdmf"])
def test_check_accepts_every_format_we_write(tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"m{suffix}"
    assert main(["mesh", str(DATA / "double_hex.poly"), "-q", "25", "-o", str(out)]) == 0
    assert main(["check", str(out)]) == 0


def test_mesh_file_input_is_post_processed(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    from scipy.spatial import Delaunay

    pts = rng.random((200, 2))
    src = tmp_path / "in.vtu"
    hammesh.write(hammesh.Mesh(points=pts, triangles=Delaunay(pts).simplices.astype(np.int64)), src)
    out = tmp_path / "out.vtu"
    assert main(["mesh", str(src), "-o", str(out)]) == 0
    assert main(["check", str(out)]) == 0


def test_check_fails_with_exit_3_on_a_broken_cycle(tmp_path: Path, capsys) -> None:
    out = tmp_path / "m.vtu"
    assert main(["mesh", str(DATA / "A.poly"), "-q", "25", "-o", str(out)]) == 0
    m = hammesh.read_mesh(out)
    tri = m.triangles.copy()
    tri[[2, 40]] = tri[[40, 2]]
    bad = tmp_path / "bad.obj"
    hammesh.write(hammesh.Mesh(points=m.points, triangles=tri), bad)
    capsys.readouterr()
    assert main(["check", str(bad)]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "verification failed" in err and "breaks at triangle" in err


def test_check_min_angle_requirement(tmp_path: Path) -> None:
    out = tmp_path / "m.vtu"
    assert main(["mesh", str(DATA / "A.poly"), "-q", "30", "-o", str(out)]) == 0
    assert main(["check", str(out), "--min-angle", "14"]) == 0
    assert main(["check", str(out), "--min-angle", "40"]) == 3


@pytest.mark.parametrize(
    "args, needle",
    [
        (["mesh", "{d}/A.poly", "--min-angle", "40"], "--min-angle=40.0"),
        (["mesh", "{d}/A.poly", "--max-area", "-1"], "--max-area=-1.0"),
        (["mesh", "{t}/missing.poly"], "missing.poly"),
        (["mesh", "{d}/A.poly", "-o", "{t}/out.unknown"], "out.unknown"),
        (["mesh", "{d}/A.poly", "--report", "{t}/r.txt"], "r.txt"),
        (["mesh", "{t}/empty.poly"], "empty.poly"),
        (["mesh", "{t}/garbage.vtu"], "garbage.vtu"),
        (["mesh", "{t}/nan.poly"], "vertex 1"),
        (["check", "{t}/garbage.vtu"], "garbage.vtu"),
        (["mesh", "{d}/A.poly", "--backend", "gmsh"], "backend"),
        (["frobnicate"], "invalid choice"),
    ],
)
def test_bad_input_one_line_exit_2_nothing_written(tmp_path: Path, args: list[str], needle: str) -> None:
    (tmp_path / "empty.poly").write_text("")
    (tmp_path / "garbage.vtu").write_bytes(os.urandom(300))
    (tmp_path / "nan.poly").write_text("3 2 0 0\n1 0 0\n2 nan 0\n3 0 1\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n")
    before = set(os.listdir(tmp_path))
    argv = [a.format(d=DATA, t=tmp_path) for a in args]
    proc = run_cli(*argv, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().count("\n") == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    assert needle in proc.stderr
    assert set(os.listdir(tmp_path)) == before


def test_help_has_examples() -> None:
    proc = run_cli("mesh", "--help")
    assert proc.returncode == 0 and "examples:" in proc.stdout and "--min-angle" in proc.stdout


def test_demo_writes_its_three_files(tmp_path: Path) -> None:
    proc = run_cli("demo", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    d = tmp_path / "hammesh-demo"
    assert sorted(p.name for p in d.iterdir()) == ["cycle.png", "mesh.vtu", "report.json"]
    report = json.loads((d / "report.json").read_text())
    assert report["verified"] and report["midpoints"] >= 1  # the plate has an interface loop
    assert run_cli("check", str(d / "mesh.vtu")).returncode == 0


def test_mesh_strip_is_one_strip_that_decodes_to_the_mesh(tmp_path: Path) -> None:
    from hammesh.strips import decode_gl_strip

    out, strip = tmp_path / "m.vtu", tmp_path / "m.json"
    assert main(["mesh", str(DATA / "A.poly"), "-q", "30", "-o", str(out), "--strip", str(strip)]) == 0
    doc = json.loads(strip.read_text())
    assert doc["primitive"] == "triangle_strip" and doc["strips"] == 1
    m = hammesh.read_mesh(out)
    assert doc["triangles"] == m.n_triangles
    tris = decode_gl_strip(np.array(doc["indices"], dtype=np.int64), doc["restart_index"])

    def canon(t):  # same oriented triangle up to rotation
        i = int(np.argmin(t))
        return tuple(np.roll(t, -i).tolist())

    assert sorted(canon(t) for t in tris) == sorted(canon(t) for t in m.triangles)


def test_poly_output_is_explained_not_just_unknown(tmp_path: Path) -> None:
    out = run_cli("mesh", str(DATA / "A.poly"), "-q", "30", "-o", str(tmp_path / "A.poly"))
    assert out.returncode == 2
    assert ".poly is a domain (input) format" in out.stderr and len(out.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "A.poly").exists()


def test_closed_stdout_ends_quietly_with_the_outputs_written(tmp_path: Path) -> None:
    """``hammesh mesh ... | head -0``: the reader quits; exit 141 (SIGPIPE's), no error line."""
    out = tmp_path / "a.vtu"
    proc = subprocess.Popen([sys.executable, "-m", "hammesh", "mesh", str(DATA / "A.poly"), "-q", "30",
                             "-a", "0.05", "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # before the summary is printed
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == 141
    assert err == "" and out.exists()
    assert main(["check", str(out)]) == 0


@pytest.mark.parametrize("edit", ["clockwise", "repeated"])
def test_check_of_an_edited_mesh_fails_verification(tmp_path: Path, capsys, edit) -> None:
    """A file that reads but is no valid mesh (one triangle turned clockwise, one
    repeated) fails the check: exit 3, not 2 (bad input)."""
    import meshio

    good = tmp_path / "good.vtu"
    assert main(["mesh", str(DATA / "A.poly"), "-q", "30", "-a", "0.05", "-o", str(good)]) == 0
    m = meshio.read(good)
    t = m.cells_dict["triangle"].copy()
    t = np.vstack([t, t[:1]]) if edit == "repeated" else np.vstack([t[:5], t[5:6, ::-1], t[6:]])
    meshio.write(tmp_path / "bad.vtu", meshio.Mesh(m.points, [("triangle", t)]))
    capsys.readouterr()
    assert main(["check", str(tmp_path / "bad.vtu")]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hammesh: verification failed:")


def test_check_of_a_hamiltonian_path_says_so(tmp_path: Path, capsys) -> None:
    """`hammesh points` makes a path for points in convex position: check fails it (a
    path is no cycle) and says it is a path."""
    pts = tmp_path / "sq.txt"
    pts.write_text("0 0\n1 0\n1 1\n0 1\n0.5 1.5\n")
    assert main(["points", str(pts), "-o", str(tmp_path / "p.vtu")]) == 0
    capsys.readouterr()
    assert main(["check", str(tmp_path / "p.vtu")]) == 3
    assert "form a Hamiltonian path, not a cycle" in capsys.readouterr().err


def test_parts_a_format_cannot_hold_are_noted(tmp_path: Path, capsys) -> None:
    rep = tmp_path / "r.json"
    assert main(["mesh", str(DATA / "A.poly"), "-q", "30", "-a", "0.05", "--parts", "4",
                 "-o", str(tmp_path / "p.obj"), "--report", str(rep)]) == 0
    assert "note: not written: cell data 'part' (.obj holds geometry only)" in capsys.readouterr().out
    assert "not written: cell data 'part' (.obj holds geometry only)" in json.loads(rep.read_text())["not_carried"]
