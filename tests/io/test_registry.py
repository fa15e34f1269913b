"""hammesh.io: the FORMATS registry, validation before writing, write_report."""

from __future__ import annotations

import dataclasses
import json
import os

import meshio
import numpy as np
import pytest

import hammesh.io as hio
from hammesh.io import vtu
from hammesh.errors import FileFormatError, InvalidMeshError

ALL = [".vtu", ".vtk", ".msh", ".xdmf", ".obj", ".ply", ".stl", ".off", ".vtp", ".ele", ".node", ".pvtu"]


def test_registry_is_explicit_and_complete():
    assert list(hio.FORMATS) == ALL
    for reader, writer in hio.FORMATS.values():
        assert callable(reader) and callable(writer)
    assert hio.__all__ == [
        "FORMATS", "read_mesh", "read_points", "read_polygon", "write", "write_report", "check_outputs",
        "supported_suffixes", "DATA_SUFFIXES", "unwritten_data",
    ]
    assert hio.DATA_SUFFIXES <= set(ALL)
    assert hio.supported_suffixes() == tuple(ALL)


@pytest.mark.parametrize("suffix", ALL)
def test_every_format_round_trips_points_and_order(tmp_path, hmesh, suffix, assert_cycle_order):
    path = tmp_path / f"mesh{suffix}"
    hio.write(hmesh, path)
    back = hio.read_mesh(path)
    np.testing.assert_allclose(back.points, hmesh.points, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(back.triangles, hmesh.triangles)
    assert_cycle_order(back.triangles, hmesh.components)
    assert not [p for p in os.listdir(tmp_path) if ".tmp-" in p]


def test_suffix_is_case_insensitive(tmp_path, hexagon):
    hio.write(hexagon, tmp_path / "UP.VTU")
    assert hio.read_mesh(tmp_path / "UP.VTU").n_triangles == 6


@pytest.mark.parametrize("name", ["mesh.xyz", "mesh", "mesh.vtu.bak"])
def test_unknown_suffix_lists_supported(tmp_path, hexagon, name):
    with pytest.raises(FileFormatError, match=r"unknown mesh format.*\.vtu .*\.ele \.node") as info:
        hio.write(hexagon, tmp_path / name)
    assert name in str(info.value)
    with pytest.raises(FileFormatError, match="supported"):
        hio.read_mesh(tmp_path / name)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("suffix", ALL)
def test_missing_file(tmp_path, suffix):
    with pytest.raises(FileFormatError, match=f"nope{suffix}|nope.ele"):
        hio.read_mesh(tmp_path / f"nope{suffix}")


def _broken(mesh, **changes):
    return dataclasses.replace(mesh, **changes)


BROKEN = {
    "nan point": (lambda m: _broken(m, points=np.where(np.arange(m.n_points)[:, None] == 3, np.nan, m.points)),
                  r"points\[3\] .* not finite"),
    "index too big": (lambda m: _broken(m, triangles=np.where(m.triangles == 5, 99, m.triangles)),
                      r"triangles\[3, 2\] = 99 is out of range \[0, 7\)"),
    "negative index": (lambda m: _broken(m, triangles=np.where(m.triangles == 0, -1, m.triangles)),
                       r"triangles\[0, 0\] = -1 is out of range"),
    "float triangles": (lambda m: _broken(m, triangles=m.triangles.astype(float)), "integer"),
    "4 columns": (lambda m: _broken(m, points=np.c_[m.points, np.ones((m.n_points, 2))]), r"\(n, 2\) or \(n, 3\)"),
    "no triangles": (lambda m: _broken(m, triangles=np.zeros((0, 3), np.int64), components=np.zeros(0, np.int64),
                                       position=np.zeros(0, np.int64), parent=np.zeros(0, np.int64),
                                       kind=np.zeros(0, np.int8), triangle_attributes=np.zeros((0, 1))),
                     "no triangles"),
    "segment index": (lambda m: _broken(m, segments=np.array([[0, 70]])), r"segments\[0, 1\] = 70"),
    "components sum": (lambda m: _broken(m, components=np.array([5])), "components sum to 5, expected 6"),
    "short position": (lambda m: _broken(m, position=m.position[:-1]), "position has 5 entries, expected 6"),
}


@pytest.mark.parametrize("suffix", [".vtu", ".ele", ".stl"])
@pytest.mark.parametrize("case", list(BROKEN))
def test_invalid_meshes_are_rejected_before_any_io(tmp_path, monkeypatch, hexagon, suffix, case):
    make, pattern = BROKEN[case]

    def never(*args, **kwargs):
        raise AssertionError("meshio.write called with an invalid mesh")

    monkeypatch.setattr(meshio, "write", never)
    monkeypatch.setattr(vtu, "write", never)
    with pytest.raises(InvalidMeshError, match=pattern):
        hio.write(make(hexagon), tmp_path / f"m{suffix}")
    assert os.listdir(tmp_path) == []


def test_write_report_converts_numpy_and_sorts_keys(tmp_path):
    report = {
        "z": np.int64(3),
        "a": {"angles": np.array([30.0, 45.5]), "ok": np.bool_(True), "nan": float("nan")},
        "counts": (np.int32(1), 2),
        "inf": np.float64(np.inf),
        "path": tmp_path,
    }
    hio.write_report(report, tmp_path / "r.json")
    text = (tmp_path / "r.json").read_text()
    assert text.endswith("}\n")
    assert text.index('"a"') < text.index('"counts"') < text.index('"z"')
    assert '\n  "a": {\n    "angles": [\n      30.0,' in text
    data = json.loads(text)
    assert data == {
        "z": 3,
        "a": {"angles": [30.0, 45.5], "ok": True, "nan": None},
        "counts": [1, 2],
        "inf": None,
        "path": str(tmp_path),
    }
    assert type(data["z"]) is int and type(data["a"]["ok"]) is bool
