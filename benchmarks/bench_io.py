"""Reading OBJ, OFF and PLY: hammesh's vectorised readers against meshio's, same run.

A torus of ``--faces`` triangles is written by meshio as ``.obj``, ``.off`` and ``.ply``
(ASCII and binary); each
reader reads it in a fresh process (the first call: what ``hammesh mesh big.obj``
gets, kernels loaded from numba's cache; imports not counted) and then ``--repeat``
more times in that process (best).  The peers, in alternation with ours: meshio's
``read`` (its OFF reader reads triangles only and drops colours, its OBJ reader
misreads relative indices, its PLY reader fails on VTK's face colours).  Printed: seconds and the ratio ours / meshio; both readers' results
are compared (points and faces equal).

    python benchmarks/bench_io.py [--faces 1000000] [--repeat 3] [--rounds 3]
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


def _run(reader: str, path: Path, repeat: int) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, reader, str(path), str(repeat)],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--faces", type=float, default=1e6)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=3, help="fresh processes per reader (alternating)")
    args = ap.parse_args()
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
