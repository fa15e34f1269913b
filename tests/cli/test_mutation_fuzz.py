"""Valid files of every format a subcommand reads, mutated at random (bytes flipped,
cut, inserted; lines deleted or repeated; a number replaced by an extreme one), through
the CLI in-process (every subcommand but ``demo``): the exit is 0, 2 (bad input: one line, nothing written) or, for
``check``, 3 (a mesh read but not Hamiltonian/valid); never a traceback, never another
code, never a changed input.

The hand-made cases of ``test_fuzz_inputs.py`` name what each reader must refuse; this
finds what nobody thought of (it found 3D inputs with coordinates near 1e300, which
overflowed inside the construction and failed the certificate instead of being refused, and
``.npy`` headers that fail in ``tokenize``: exit 1).
"""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
import hammesh.io
from hammesh.cli import main

#: numbers a mutation puts in place of a token
EXTREMES = [b"0", b"-1", b"1e308", b"nan", b"inf", b"-0", b"99999999999999999999", b"3.5", b"-7", b"1e-320"]

#: subcommand -> argv after the input
COMMANDS = {"points": ["-o", "{out}/o.vtu"], "polygon": ["-o", "{out}/o.json"], "check": [], "mesh": ["-o", "{out}/o.vtu"], "surface": ["-o", "{out}/o.vtu"],
            "strip": ["-o", "{out}/o.json"], "partition": ["-k", "2", "-o", "{out}/o.vtu"]}


@pytest.fixture(scope="module")
def seeds(tmp_path_factory) -> dict[str, bytes]:
    """One small valid file per format and encoding."""
    d = tmp_path_factory.mktemp("seeds")
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, max_area=0.05), mode="incircle")
    pts3 = np.column_stack([h.points, np.zeros(len(h.points))])
    tags = {"mat": [np.arange(len(h.triangles), dtype=np.float64)]}
    for name, kw, data in [
        ("a.vtu", dict(binary=False), True), ("b.vtu", dict(binary=True), True),
        ("a.vtk", dict(binary=False), True), ("b.vtk", dict(binary=True), True),
        ("a.msh", dict(file_format="gmsh22", binary=False), False), ("b.msh", dict(file_format="gmsh", binary=True), False),
        ("a.obj", {}, False), ("a.off", {}, False), ("a.ply", dict(binary=False), False),
        ("b.ply", dict(binary=True), False), ("a.stl", dict(binary=False), False), ("b.stl", dict(binary=True), False),
    ]:
        mesh = meshio.Mesh(pts3, [("triangle", h.triangles.astype(np.int32))], cell_data=tags if data else {})
        with contextlib.redirect_stderr(io.StringIO()):
            meshio.write(d / name, mesh, **kw)
    hammesh.io.write(h, d / "h.vtu")
    hammesh.io.write(h, d / "h.vtp")
    (d / "a.node").write_text(f"{len(h.points)} 2 0 0\n"
                              + "".join(f"{i + 1} {x!r} {y!r}\n" for i, (x, y) in enumerate(h.points.tolist())))
    (d / "a.ele").write_text(f"{len(h.triangles)} 3 0\n"
                             + "".join(f"{i + 1} {a + 1} {b + 1} {c + 1}\n" for i, (a, b, c) in enumerate(h.triangles.tolist())))
    (d / "sq.poly").write_text("4 2 0 1\n1 0 0 1\n2 1 0 1\n3 1 1 1\n4 0 1 1\n4 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n0\n")
    np.save(d / "p.npy", np.random.default_rng(0).random((40, 2)))
    (d / "p.txt").write_text("".join(f"{x!r} {y!r}\n" for x, y in np.random.default_rng(1).random((40, 2)).tolist()))
    (d / "q.wkt").write_text("POLYGON ((0 0, 4 0, 4 3, 2 1, 0 3, 0 0), (0.5 0.5, 1 0.5, 1 0.8, 0.5 0.5))")
    (d / "q.geojson").write_text('{"type": "Polygon", "coordinates": [[[0, 0], [4, 0], [4, 3], [2, 1], [0, 3], [0, 0]]]}')
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def _mutate(data: bytes, ops: list[tuple[int, float, int]]) -> bytes:
    b = bytearray(data)
    for kind, where, value in ops:
        if not b:
            break
        i = int(where * (len(b) - 1))
        lines = bytes(b).split(b"\n")
        j = int(where * (len(lines) - 1))
        if kind == 0:
            b[i] = value
        elif kind == 1:
            del b[i:i + 1 + value % 64]
        elif kind == 2:
            b = b[:i]
        elif kind == 3:
            b[i:i] = bytes([value]) * (1 + value % 8)
        elif kind == 4:
            lines.insert(j, lines[j])
            b = bytearray(b"\n".join(lines))
        elif kind == 5:
            del lines[j]
            b = bytearray(b"\n".join(lines))
        else:
            toks = lines[j].split(b" ")
            toks[value % len(toks)] = EXTREMES[value % len(EXTREMES)]
            lines[j] = b" ".join(toks)
            b = bytearray(b"\n".join(lines))
    return bytes(b)


NAMES = ["a.vtu", "b.vtu", "a.vtk", "b.vtk", "a.msh", "b.msh", "a.obj", "a.off", "a.ply", "b.ply",
         "a.stl", "b.stl", "h.vtu", "h.vtp", "a.node", "a.ele", "sq.poly", "p.npy", "p.txt", "q.wkt", "q.geojson"]
#: the subcommands that read point sets and polygons, and the files only they read
POINTS_POLYGONS = {"p.npy": ("points", "polygon"), "p.txt": ("points", "polygon"), "q.wkt": ("polygon",),
                   "q.geojson": ("polygon",), "sq.poly": ("mesh", "polygon"), "a.node": ("points", "check", "mesh")}


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(name=st.sampled_from(NAMES), cmd=st.sampled_from(sorted(COMMANDS)),
       ops=st.lists(st.tuples(st.integers(0, 6), st.floats(0, 1), st.integers(0, 255)), min_size=1, max_size=3))
def test_mutated_files_exit_0_2_or_3_cleanly(seeds, tmp_path_factory, name, cmd, ops):
    if name in POINTS_POLYGONS:
        allowed = POINTS_POLYGONS[name]
        cmd = cmd if cmd in allowed else allowed[sorted(COMMANDS).index(cmd) % len(allowed)]
    elif cmd in ("points", "polygon") or (cmd == "surface" and name.endswith(".ele")):
        cmd = "check"
    root = tmp_path_factory.mktemp("fuzz")
    src, out = root / "in", root / "out"
    src.mkdir()
    out.mkdir()
    data = _mutate(seeds[name], ops)
    f = src / name
    f.write_bytes(data)
    if name == "a.ele":
        (src / "a.node").write_bytes(seeds["a.node"])
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main([cmd, str(f), *(a.format(out=out) for a in COMMANDS[cmd])])
    message = err.getvalue()
    assert "Traceback" not in message, message
    assert code in ((0, 2, 3) if cmd == "check" else (0, 2)), message
    if code == 2:
        assert len(message.strip().splitlines()) == 1, message
        assert os.listdir(out) == [], "an output was left behind"
    assert Path(f).read_bytes() == data, "the input changed"
