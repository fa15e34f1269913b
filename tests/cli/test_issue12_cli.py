"""Issue 12 regressions on the command line: one test (or more) per defect, named after it."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.io import vtu

SQUARE = "4 2 0 1\n1 0 0 1\n2 1 0 1\n3 1 1 1\n4 0 1 1\n4 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n0\n"


@pytest.fixture
def sq(tmp_path: Path) -> Path:
    f = tmp_path / "sq.poly"
    f.write_text(SQUARE)
    return f


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("hammesh: "), err
    return lines[0]


# defect 1: the input is overwritten -----------------------------------------------------


@pytest.mark.parametrize("out", ["sq.ele", "sq.node", "SQ.ELE" if sys.platform == "darwin" else "sq.ele"])
def test_defect1_output_sibling_never_overwrites_the_poly_input(tmp_path, sq, capsys, out):
    assert main(["mesh", str(sq), "-o", str(tmp_path / out)]) == 2
    assert "is an input file" in _one_error_line(capsys)
    assert sq.read_text() == SQUARE
    assert sorted(os.listdir(tmp_path)) == ["sq.poly"]


def test_defect1_node_input_with_ele_output(tmp_path, capsys):
    node = tmp_path / "pts.node"
    node.write_text("4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n")
    assert main(["mesh", str(node), "-o", str(tmp_path / "pts.ele")]) == 2
    assert "pts.node: is an input file" in _one_error_line(capsys)
    assert node.read_text().startswith("4 2 0 0")


def test_defect1_hard_link_to_the_input_is_refused(tmp_path, sq, capsys):
    os.link(sq, tmp_path / "alias.vtu")
    assert main(["mesh", str(sq), "-o", str(tmp_path / "alias.vtu")]) == 2
    assert "is an input file" in _one_error_line(capsys)
    assert sq.read_text() == SQUARE


def test_defect1_mesh_input_is_not_its_own_output(tmp_path, sq, capsys):
    out = tmp_path / "m.vtu"
    assert main(["mesh", str(sq), "-o", str(out)]) == 0
    data = out.read_bytes()
    capsys.readouterr()
    assert main(["mesh", str(out), "-o", str(tmp_path / "." / "m.vtu")]) == 2
    assert "is an input file" in _one_error_line(capsys)
    assert out.read_bytes() == data


# defect 2: quads silently dropped ------------------------------------------------------


def _quad_and_triangles(path: Path) -> float:
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0.0]])
    meshio.write(path, meshio.Mesh(pts, [("triangle", np.array([[1, 4, 5], [1, 5, 2]])), ("quad", np.array([[0, 1, 2, 3]]))]))
    return 2.0  # total area


@pytest.mark.parametrize("suffix", [".vtu", ".obj"])
def test_defect2_quads_are_triangulated_and_reported(tmp_path, capsys, suffix):
    src = tmp_path / f"mixed{suffix}"
    area = _quad_and_triangles(src)
    out, rep = tmp_path / "o.vtu", tmp_path / "r.json"
    assert main(["mesh", str(src), "-o", str(out), "--report", str(rep)]) == 0
    m = hammesh.read_mesh(out)
    a, b, c = (m.points[m.triangles[:, i]] for i in range(3))
    got = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])).sum()
    assert got == pytest.approx(area, rel=1e-12)
    assert json.loads(rep.read_text())["repairs"] == ["triangulated 1 quad (2 triangles)"]


def test_defect2_strict_refuses_the_quad(tmp_path, capsys):
    src = tmp_path / "mixed.vtu"
    _quad_and_triangles(src)
    assert main(["mesh", str(src), "-o", str(tmp_path / "o.vtu"), "--strict"]) == 2
    assert "strict" in _one_error_line(capsys)
    assert not (tmp_path / "o.vtu").exists()


def test_defect2_check_does_not_pass_a_stray_quad(tmp_path, sq, capsys):
    good = tmp_path / "good.vtu"
    assert main(["mesh", str(sq), "-o", str(good)]) == 0
    m = meshio.read(good)
    tri = m.cells_dict["triangle"]
    n = len(m.points)
    pts = np.vstack([m.points, [[5, 5, 0], [6, 5, 0], [6, 6, 0], [5, 6, 0]]])
    meshio.write(tmp_path / "stray.vtu", meshio.Mesh(pts, [("triangle", tri), ("quad", np.array([[n, n + 1, n + 2, n + 3]]))]))
    capsys.readouterr()
    assert main(["check", str(tmp_path / "stray.vtu")]) == 3  # its two triangles are a second piece, not a cycle


# defect 3: restart index wraps in .npz ---------------------------------------------------


@pytest.mark.parametrize("restart", ["4294967299", "-1", str(2**40)])
def test_defect3_restart_index_outside_uint32_is_refused(tmp_path, sq, capsys, restart):
    mesh = tmp_path / "m.vtu"
    assert main(["mesh", str(sq), "-o", str(mesh)]) == 0
    capsys.readouterr()
    out = tmp_path / "o.npz"
    assert main(["strip", str(mesh), "--restart-index", restart, "-o", str(out)]) == 2
    assert "restart-index" in _one_error_line(capsys)
    assert not out.exists()


def test_defect3_largest_restart_index_round_trips(tmp_path, sq):
    mesh = tmp_path / "m.vtu"
    assert main(["mesh", str(sq), "-o", str(mesh)]) == 0
    out = tmp_path / "o.npz"
    assert main(["strip", str(mesh), "--restart-index", str(2**32 - 1), "-o", str(out)]) == 0
    with np.load(out) as z:
        assert int(z["restart_index"]) == 2**32 - 1
        assert z["indices"].dtype == np.uint32


# defect 4: markers beyond 32 bits -----------------------------------------------------------


def test_defect4_marker_beyond_int32_is_refused_not_changed(tmp_path, capsys):
    f = tmp_path / "m.poly"
    f.write_text(SQUARE.replace("1 1 2 1\n", f"1 1 2 {2**40}\n"))
    assert main(["mesh", str(f), "-o", str(tmp_path / "o.vtu")]) == 2
    assert str(2**40) in _one_error_line(capsys)


# defect 5: exit 1 on malformed files and options (more in test_fuzz_inputs.py) ---------------


def test_defect5_tiny_square_far_out_prints_no_qhull_text(tmp_path, capsys):
    f = tmp_path / "tiny.poly"
    o = 1e9
    f.write_text(f"4 2 0 0\n1 {o!r} {o!r}\n2 {o + 1e-6!r} {o!r}\n3 {o + 1e-6!r} {o + 1e-6!r}\n4 {o!r} {o + 1e-6!r}\n"
                 "4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n")
    code = main(["mesh", str(f), "-o", str(tmp_path / "o.vtu")])
    err = capsys.readouterr().err
    assert code in (0, 2)  # meshed and verified, or the resolution named; never exit 3
    assert "Qhull" not in err and len(err.splitlines()) <= 1
    if code == 2:
        assert "ulps" in err and not (tmp_path / "o.vtu").exists()


# defect 6: outputs left behind after exit 2 --------------------------------------------------


@pytest.mark.parametrize("flag, name", [("--report", "r.json"), ("--png", "p.png"), ("--strip", "s.json")])
def test_defect6_bad_second_output_leaves_nothing(tmp_path, sq, capsys, flag, name):
    assert main(["mesh", str(sq), "-o", str(tmp_path / "out.vtu"), flag, str(tmp_path / "nodir" / name)]) == 2
    assert "does not exist" in _one_error_line(capsys)
    assert sorted(os.listdir(tmp_path)) == ["sq.poly"]


def test_defect6_demo_bad_option_leaves_no_folder(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "d"), "--max-area", "0"]) == 2
    _one_error_line(capsys)
    assert os.listdir(tmp_path) == []


# defect 8: SIGTERM / SIGKILL leave temp files ------------------------------------------------


def test_defect8_sigterm_during_a_write_removes_the_temp_file(tmp_path, sq, capsys, monkeypatch):
    real_write = vtu.write  # hammesh's own .vtu writer

    def write_then_terminated(path, *args, **kwargs):
        real_write(path, *args, **kwargs)  # a complete temp file exists now
        os.kill(os.getpid(), signal.SIGTERM)  # what `timeout` sends
        time.sleep(1)  # the handler raises here

    monkeypatch.setattr(vtu, "write", write_then_terminated)
    code = main(["mesh", str(sq), "-o", str(tmp_path / "out.vtu")])
    assert code == 128 + signal.SIGTERM
    assert "terminated" in _one_error_line(capsys)
    assert sorted(os.listdir(tmp_path)) == ["sq.poly"]
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handler restored


def test_defect8_temp_of_a_killed_writer_is_removed_on_the_next_run(tmp_path, sq):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stray = tmp_path / f".out.vtu.tmp-{dead.pid}-0123abcd.vtu"
    stray.write_bytes(b"x" * 1000)
    alive = tmp_path / f".out.vtu.tmp-{os.getpid()}-0123abcd.vtu"  # a live writer's
    alive.write_bytes(b"y")
    assert main(["mesh", str(sq), "-o", str(tmp_path / "out.vtu")]) == 0
    assert not stray.exists() and alive.exists()


@pytest.mark.slow
def test_defect8_real_sigterm_to_the_command(tmp_path, sq):
    out = tmp_path / "out"
    out.mkdir()
    log = tmp_path / "stderr.txt"
    with open(log, "w") as err:  # a file, not a pipe: a lingering grandchild cannot block the read
        proc = subprocess.Popen(
            [sys.executable, "-m", "hammesh", "mesh", str(sq), "-a", "2e-6", "-q", "30", "-o", str(out / "big.vtu")],
            stderr=err,
        )
        time.sleep(6)
        proc.send_signal(signal.SIGTERM)
        code = proc.wait(timeout=120)
    text = log.read_text()
    if code == 0:  # a fast machine finished first: nothing to clean up
        return
    assert code in (128 + signal.SIGTERM, -signal.SIGTERM), text  # -15: still importing
    assert "Traceback" not in text
    # the signal came mid-work (nothing written) or after the atomic rename (a whole file,
    # the command's last step done): never a half-written or stray file
    left = os.listdir(out)
    assert left in ([], ["big.vtu"]), left
    if left:
        check = subprocess.run([sys.executable, "-m", "hammesh", "check", str(out / "big.vtu")],
                               capture_output=True, text=True)
        assert check.returncode == 0, check.stdout + check.stderr


# defect 9: misleading messages ------------------------------------------------------------


def test_defect9_missing_directory_names_the_target_not_the_temp(tmp_path, capsys):
    from hammesh.io import write
    from hammesh.mesh import Mesh

    target = tmp_path / "nodir" / "out.vtu"
    with pytest.raises(hammesh.HammeshError, match=r"nodir/out\.vtu") as info:
        write(Mesh(np.eye(3)[:, :2], np.array([[0, 1, 2]])), target)
    assert ".tmp-" not in str(info.value)


def test_defect9_full_disk_names_the_output(tmp_path, sq, capsys, monkeypatch):
    import errno

    def no_space(path, *args, **kwargs):
        Path(path).write_bytes(b"half")
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(vtu, "write", no_space)  # hammesh's own .vtu writer
    assert main(["mesh", str(sq), "-o", str(tmp_path / "out.vtu")]) == 2
    line = _one_error_line(capsys)
    assert line == f"hammesh: error: {tmp_path / 'out.vtu'}: cannot write (No space left on device)"
    assert sorted(os.listdir(tmp_path)) == ["sq.poly"]


def test_defect9_constant_z_is_planar(tmp_path, capsys):
    pts = np.array([[0, 0, 5], [1, 0, 5], [1, 1, 5], [0, 1, 5.0]])
    src = tmp_path / "z5.vtu"
    meshio.write(src, meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2], [0, 2, 3]]))]))
    rep = tmp_path / "r.json"
    assert main(["mesh", str(src), "-o", str(tmp_path / "o.vtu"), "--report", str(rep)]) == 0
    assert json.loads(rep.read_text())["repairs"] == ["all points at z = 5: read as a planar mesh (written at z = 0)"]


def test_defect9_points_scaled_by_1e200_are_not_called_collinear(tmp_path, capsys):
    f = tmp_path / "p.npy"
    np.save(f, np.random.default_rng(1).random((10, 2)) * 1e200)
    assert main(["points", str(f), "-o", str(tmp_path / "o.vtu")]) == 2
    line = _one_error_line(capsys)
    assert "one line" not in line and "overflow" in line


def test_defect9_newline_in_a_file_name_stays_one_line(tmp_path, capsys):
    f = tmp_path / "bad\nname.poly"
    f.write_text("garbage")
    assert main(["mesh", str(f), "-o", str(tmp_path / "o.vtu")]) == 2
    assert "bad\\nname.poly" in _one_error_line(capsys)


def test_defect9_long_output_name_works(tmp_path, sq):
    out = tmp_path / ("x" * 246 + ".vtu")  # 250 bytes: valid on ext4, its temp name must fit too
    assert main(["mesh", str(sq), "-o", str(out)]) == 0
    assert out.exists()
    assert sorted(os.listdir(tmp_path)) == sorted(["sq.poly", out.name])


# defect 10: invalid input accepted ------------------------------------------------------------


def test_defect10_check_refuses_overlapping_triangles(tmp_path, capsys):
    """Two hexagon fans, each a valid cycle, one on top of the other: not a planar mesh."""
    ring = np.exp(2j * np.pi * np.arange(6) / 6)
    fans, tris = [], []
    for k, centre in enumerate((0.0, 0.3 + 0.2j)):
        z = np.concatenate([[centre], centre + ring])
        fans.append(np.column_stack([z.real, z.imag, np.zeros(7)]))
        i = np.arange(1, 7)
        tris.append(np.column_stack([np.zeros(6, int), i, i % 6 + 1]) + 7 * k)
    src = tmp_path / "two.vtu"
    meshio.write(src, meshio.Mesh(np.vstack(fans), [("triangle", np.vstack(tris))]))
    assert main(["check", str(src)]) == 3
    assert "overlap" in _one_error_line(capsys)
    one = tmp_path / "one.vtu"
    meshio.write(one, meshio.Mesh(fans[0], [("triangle", tris[0])]))
    assert main(["check", str(one)]) == 0


def test_defect10_check_min_angle_nan_is_refused(tmp_path, sq, capsys):
    out = tmp_path / "m.vtu"
    assert main(["mesh", str(sq), "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["check", str(out), "--min-angle", "nan"]) == 2
    assert "--min-angle=nan" in _one_error_line(capsys)


@pytest.mark.parametrize("fold", ["nan", "-10", "inf"])
def test_defect10_surface_max_fold_out_of_range(tmp_path, capsys, fold):
    src = tmp_path / "s.obj"
    src.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n")
    assert main(["surface", str(src), "-o", str(tmp_path / "o.vtu"), "--swaps", "--max-fold", fold]) == 2
    assert "--max-fold" in _one_error_line(capsys)


def test_defect10_complex_npy_is_refused(tmp_path, capsys):
    f = tmp_path / "c.npy"
    np.save(f, np.array([[0, 0], [1, 0], [0, 1], [1, 1 + 1j]]))
    assert main(["points", str(f), "-o", str(tmp_path / "o.vtu")]) == 2
    assert "complex" in _one_error_line(capsys)


def test_defect10_report_and_strip_on_one_file(tmp_path, sq, capsys):
    assert main(["mesh", str(sq), "--report", str(tmp_path / "x.json"), "--strip", str(tmp_path / "x.json")]) == 2
    assert "given twice" in _one_error_line(capsys)
    assert sorted(os.listdir(tmp_path)) == ["sq.poly"]


# file formats -----------------------------------------------------------------------------


def test_obj_with_relative_indices_meshes(tmp_path):
    src = tmp_path / "rel.obj"
    src.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf 1 -2 -1\n")
    out = tmp_path / "o.vtu"
    assert main(["mesh", str(src), "-o", str(out)]) == 0
    assert hammesh.read_mesh(out).n_triangles > 2


def test_defect8_sigterm_inside_a_compiled_kernel_is_a_termination(monkeypatch, capsys):
    """numba reports a signal handler's exception as SystemError with it as context."""
    import argparse

    import hammesh.cli as cli
    from hammesh.errors import Terminated

    def run(args):
        try:
            raise Terminated(15)
        except Terminated as exc:
            raise SystemError("CPUDispatcher(<function half_edge_twins>) returned a result with an exception set") from exc

    class Parser:
        def parse_args(self, argv):
            return argparse.Namespace(_run=run)

    monkeypatch.setattr(cli, "build_parser", lambda command=None: Parser())
    assert cli.main([]) == 143
    assert capsys.readouterr().err.strip() == "hammesh: terminated by signal 15"


def test_report_lists_the_domain_repairs_of_a_t_junction(tmp_path):
    """A .poly with a vertex on a segment: meshed, the split reported in the JSON, check passes."""
    f = tmp_path / "tj.poly"
    f.write_text("5 2 0 0\n1 0 0\n2 2 0\n3 2 1\n4 0 1\n5 1 0\n5 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 5 3\n0\n")
    out, rep = tmp_path / "tj.vtu", tmp_path / "tj.json"
    assert main(["mesh", str(f), "-q", "30", "-a", "0.01", "-o", str(out), "--report", str(rep)]) == 0
    repairs = json.loads(rep.read_text())["repairs"]
    assert [r["kind"] for r in repairs] == ["vertex_on_segment"]
    assert main(["check", str(out)]) == 0
