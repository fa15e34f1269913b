"""Reading OBJ, OFF and PLY: hammesh's vectorised readers against meshio's, same run.

A torus of ``--faces`` triangles is written by meshio as ``.obj``, ``.off`` and ``.ply``
(ASCII and binary); each
reader reads it in a fresh process (the first call: what ``hammesh mesh big.obj``
gets, kernels loaded from numba's cache; imports not counted) and then ``--repeat``
more times in that process (best).  The peers, in alternation with ours: meshio's
``read`` (its OFF reader reads triangles only and drops colours, its OBJ reader
misreads relative indices, its PLY reader fails on VTK's face colours).  Printed: seconds and the ratio ours / meshio; both readers' results
are compared (points and faces equal).

``--write``: writing instead.  A planar Hamiltonian mesh of about ``--faces`` triangles
(demo domain, sparse mode, its cycle fields and tags as cell data) is written as
``.vtu .obj .off .stl .xdmf`` by ``hammesh.write`` (own writers: ``.vtu`` zlib level 1 on
every core, the text formats vectorised,
:mod:`hammesh.io.text_rows`) and by ``meshio.write`` of the same ``meshio.Mesh``
(``hammesh.to_meshio``; ``.xdmf`` inline XML as hammesh writes it), and as ``.ele`` by
hammesh against ``np.savetxt`` of the same ``.node`` and ``.ele`` rows (hammesh's
writer before; it also writes the ``.poly`` of the segments); each writer in a fresh process,
alternating, then ``--repeat`` more times (best).

    python benchmarks/bench_io.py [--faces 1000000] [--repeat 3] [--rounds 3] [--write]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

_CHILD = r"""
import json, sys, time
reader, path, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
if reader == "meshio":
    import meshio
    read = meshio.read
else:
    from hammesh.io.obj_format import read_obj
    from hammesh.io.off_format import read_off
    from hammesh.io.ply_format import read_ply
    read = {"obj": read_obj, "off": read_off, "ply": read_ply}[path.rsplit(".", 1)[1]]
times = []
for _ in range(1 + repeat):
    t = time.perf_counter()
    got = read(path)
    times.append(time.perf_counter() - t)
faces = sum(len(b.data) for b in got.cells)
print(json.dumps({"first": times[0], "best": min(times[1:] or times), "faces": faces}))
"""


_WRITE_CHILD = r"""
import json, pickle, sys, time
writer, mesh_file, path, repeat = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
with open(mesh_file, "rb") as f:
    mesh = pickle.load(f)
if writer == "meshio":
    import meshio
    import numpy as np
    from hammesh import to_meshio
    if path.endswith(".ele"):
        from hammesh.io.cell_data import triangle_cell_data
        def write(mesh, path):  # the .node and .ele rows hammesh writes, by np.savetxt
            n, m = len(mesh.points), len(mesh.triangles)
            np.savetxt(path[:-4] + ".node", np.column_stack([np.arange(n), mesh.points, np.zeros(n)]),
                       fmt=["%d", "%.17g", "%.17g", "%d"])
            data = triangle_cell_data(mesh)
            cycle = [data[k] for k in ("cycle_id", "cycle_position", "kind")]
            np.savetxt(path, np.column_stack([np.arange(m), mesh.triangles, *cycle]), fmt="%d")
    else:
        out = to_meshio(mesh)
        kw = {"data_format": "XML"} if path.endswith(".xdmf") else {}
        write = lambda mesh, path: meshio.write(path, out, **kw)
else:
    from hammesh import write
times = []
for _ in range(1 + repeat):
    t = time.perf_counter()
    write(mesh, path)
    times.append(time.perf_counter() - t)
print(json.dumps({"first": times[0], "best": min(times[1:] or times)}))
"""


def _write_bench(args: argparse.Namespace) -> None:
    """``--write``: hammesh's writers against meshio's (see the module docstring)."""
    import pickle

    import numpy as np

    import hammesh

    domain = hammesh.read_domain(Path(hammesh.__file__).parent / "data" / "demo.poly")
    area = 3e-5 * 361_395 / args.faces  # (the demo domain: 361k triangles at 3e-5)
    h = hammesh.hamiltonian(hammesh.quality_mesh(domain, min_angle=30, max_area=area))
    with tempfile.TemporaryDirectory() as tmp:
        mesh_file = Path(tmp) / "mesh.pkl"
        mesh_file.write_bytes(pickle.dumps(h))
        print(f"{len(h.triangles):,} triangles, {len(h.points):,} points")
        for suffix in (".vtu", ".obj", ".off", ".stl", ".xdmf", ".ele"):
            rows: dict[str, list[dict]] = {"hammesh": [], "meshio": []}
            for _ in range(args.rounds):
                for writer in ("meshio", "hammesh"):
                    out = subprocess.run([sys.executable, "-c", _WRITE_CHILD, writer, str(mesh_file),
                                          str(Path(tmp) / f"{writer}{suffix}"), str(args.repeat)],
                                         check=True, capture_output=True, text=True).stdout
                    rows[writer].append(json.loads(out.strip().splitlines()[-1]))
            first = {r: float(np.median([x["first"] for x in v])) for r, v in rows.items()}
            best = {r: min(x["best"] for x in v) for r, v in rows.items()}
            peer = "np.savetxt" if suffix == ".ele" else "meshio"
            print(f"{suffix:6s} first call (median of {args.rounds}): hammesh {first['hammesh']:.2f} s, "
                  f"{peer} {first['meshio']:.2f} s, ratio {first['hammesh'] / first['meshio']:.3f}; "
                  f"best of {args.repeat}: {best['hammesh']:.2f} s vs {best['meshio']:.2f} s, "
                  f"ratio {best['hammesh'] / best['meshio']:.3f}", flush=True)


def _run(reader: str, path: Path, repeat: int) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, reader, str(path), str(repeat)],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--faces", type=float, default=1e6)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=3, help="fresh processes per reader (alternating)")
    ap.add_argument("--write", action="store_true", help="benchmark the writers instead")
    args = ap.parse_args()
    if args.write:
        _write_bench(args)
        return
    import meshio
    import numpy as np

    from hammesh.io.obj_format import read_obj
    from hammesh.io.off_format import read_off
    from hammesh.io.ply_format import read_ply
    from hammesh.surface.shapes import torus

    nu = int(round(np.sqrt(args.faces / 2 * 1.25)))
    points, triangles = torus(nu, max(3, int(args.faces / 2 / nu)))
    with tempfile.TemporaryDirectory() as tmp:
        for label, suffix, ours, options in ((".obj", ".obj", read_obj, {}), (".off", ".off", read_off, {}),
                                             (".ply ascii", ".ply", read_ply, {"binary": False}),
                                             (".ply binary", ".ply", read_ply, {"binary": True})):
            path = Path(tmp) / f"torus{suffix}"
            meshio.write(path, meshio.Mesh(points, [("triangle", triangles)]), **options)
            mine, peer = ours(path), meshio.read(path)
            same = np.array_equal(mine.points, peer.points) and np.array_equal(
                np.concatenate([b.data for b in mine.cells]), peer.cells[0].data)
            rows = {"hammesh": [], "meshio": []}
            for _ in range(args.rounds):
                for reader in ("meshio", "hammesh"):
                    rows[reader].append(_run(reader, path, args.repeat))
            first = {r: sorted(x["first"] for x in v) for r, v in rows.items()}
            best = {r: min(x["best"] for x in v) for r, v in rows.items()}
            med = {r: v[len(v) // 2] for r, v in first.items()}
            print(f"{label} {len(triangles):,} triangles, {path.stat().st_size / 1e6:.0f} MB, same result: {same}")
            print(f"  first call (fresh process, median of {args.rounds}): hammesh {med['hammesh']:.3f} s "
                  f"[{first['hammesh'][0]:.3f}-{first['hammesh'][-1]:.3f}], meshio {med['meshio']:.3f} s "
                  f"[{first['meshio'][0]:.3f}-{first['meshio'][-1]:.3f}], ratio {med['hammesh'] / med['meshio']:.2f}")
            print(f"  best of {args.repeat} in process: hammesh {best['hammesh']:.3f} s, meshio {best['meshio']:.3f} s, "
                  f"ratio {best['hammesh'] / best['meshio']:.2f}")


if __name__ == "__main__":
    main()
