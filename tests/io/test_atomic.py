"""hammesh.io.atomic: no half-written output, ever."""

from __future__ import annotations

import os
import stat
import threading

import meshio
import pytest

import hammesh.io as hio
from hammesh.io import obj_format, off_format, stl_format, triangle_format, vtu, xdmf_format
from hammesh.io.atomic import atomic_path, atomic_paths, atomic_write_text


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_temp_path_is_a_hidden_sibling_with_the_same_suffix(tmp_path):
    target = tmp_path / "plate.vtu"
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path
        assert tmp.name.startswith(f".plate.vtu.tmp-{os.getpid()}-")
        assert tmp.suffix == ".vtu"
        assert tmp.exists() and not target.exists()
        tmp.write_text("done")
    assert target.read_text() == "done"
    assert os.listdir(tmp_path) == ["plate.vtu"]


def test_new_file_permissions_follow_the_umask(tmp_path):
    target = tmp_path / "a.txt"
    atomic_write_text(target, "x")
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~_umask()


def test_exception_removes_temp_and_keeps_no_target(tmp_path):
    target = tmp_path / "a.txt"
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert os.listdir(tmp_path) == []


def test_keyboard_interrupt_also_cleans_up(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(tmp_path / "a.txt") as tmp:
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert os.listdir(tmp_path) == []


def test_failed_rewrite_leaves_existing_target_untouched(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with pytest.raises(ValueError):
        with atomic_path(target) as tmp:
            tmp.write_text("new but broken")
            raise ValueError
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_atomic_paths_replaces_all_or_nothing(tmp_path):
    a, b = tmp_path / "m.node", tmp_path / "m.ele"
    a.write_text("old node")
    with pytest.raises(OSError):
        with atomic_paths([a, b]) as (ta, tb):
            ta.write_text("new node")
            raise OSError("disk full")
    assert a.read_text() == "old node" and not b.exists()
    assert sorted(os.listdir(tmp_path)) == ["m.node"]
    with atomic_paths([a, b]) as (ta, tb):
        ta.write_text("new node")
        tb.write_text("new ele")
    assert a.read_text() == "new node" and b.read_text() == "new ele"
    assert sorted(os.listdir(tmp_path)) == ["m.ele", "m.node"]


def test_concurrent_writers_to_one_target_leave_one_complete_file(tmp_path):
    target = tmp_path / "a.txt"
    texts = [f"writer {i} " * 1000 for i in range(8)]
    threads = [threading.Thread(target=atomic_write_text, args=(target, t)) for t in texts]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert target.read_text() in texts
    assert os.listdir(tmp_path) == ["a.txt"]


def _partial_then_raise(filename, mesh, *args, **kwargs):
    with open(filename, "w") as f:
        f.write("<VTKFile half written")
    raise OSError("simulated crash in meshio.write")


@pytest.mark.parametrize("suffix", [".vtu", ".msh", ".xdmf", ".obj", ".off", ".stl"])
def test_meshio_crash_leaves_nothing(tmp_path, monkeypatch, hexagon, suffix):
    monkeypatch.setattr(meshio, "write", _partial_then_raise)
    monkeypatch.setattr(vtu, "write", _partial_then_raise)  # hammesh's own .vtu writer
    for module, name in ((obj_format, "write_obj"), (off_format, "write_off"), (stl_format, "write_stl"),
                         (xdmf_format, "write_xdmf")):  # and its text writers
        monkeypatch.setattr(module, name, _partial_then_raise)
    target = tmp_path / f"out{suffix}"
    with pytest.raises(OSError, match="simulated"):
        hio.write(hexagon, target)
    assert os.listdir(tmp_path) == []


def test_meshio_crash_keeps_previous_output(tmp_path, monkeypatch, hexagon, two_cycles):
    target = tmp_path / "out.vtu"
    hio.write(hexagon, target)
    before = target.read_bytes()
    monkeypatch.setattr(vtu, "write", _partial_then_raise)
    with pytest.raises(OSError):
        hio.write(two_cycles, target)
    assert target.read_bytes() == before
    assert os.listdir(tmp_path) == ["out.vtu"]
    assert hio.read_mesh(target).n_triangles == hexagon.n_triangles


def test_triangle_writer_crash_midway_leaves_old_triple(tmp_path, monkeypatch, hexagon, two_cycles):
    hio.write(hexagon, tmp_path / "m.ele")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert sorted(before) == ["m.ele", "m.node", "m.poly"]
    real = triangle_format.write_rows
    calls = []

    def flaky(f, columns, **kw):
        calls.append(1)
        if len(calls) == 3:  # the .ele rows, after .node and .poly are complete
            f.write("0 0 1")
            raise OSError("simulated crash")
        real(f, columns, **kw)

    monkeypatch.setattr(triangle_format, "write_rows", flaky)
    with pytest.raises(OSError, match="simulated"):
        hio.write(two_cycles, tmp_path / "m.ele")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_triangle_writer_crash_on_fresh_target_leaves_nothing(tmp_path, monkeypatch, hexagon):
    def boom(f, columns, **kw):
        f.write("1 2")
        raise OSError("simulated crash")

    monkeypatch.setattr(triangle_format, "write_rows", boom)
    with pytest.raises(OSError):
        hio.write(hexagon, tmp_path / "m.node")
    assert os.listdir(tmp_path) == []


def test_write_report_failure_keeps_previous_report(tmp_path):
    target = tmp_path / "report.json"
    hio.write_report({"a": 1}, target)
    with pytest.raises(TypeError, match="report.bad"):
        hio.write_report({"a": 2, "bad": object()}, target)
    assert target.read_text() == '{\n  "a": 1\n}\n'
    assert os.listdir(tmp_path) == ["report.json"]
