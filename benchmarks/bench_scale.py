"""Decoupled parallel meshing (issue 15): hammesh on tiles vs one raw Triangle call.

For each size (estimated triangle count of a ``q30 a A`` Triangle run of the bundled
demo plate: holes, a crack, two regions), in fresh processes, same run:

* raw: one ``triangle.triangulate(domain, "pq30a<A>")`` call (time of the call, peak
  RSS of its process, triangle count);
* ``hammesh mesh demo.poly -q 30 -a A --workers N --partitioned -o DIR`` for N = 1, 2:
  the whole command (Dask start, decomposition, tile meshing, per-tile Hamiltonian and
  certificate, joins, pieces and index written) wall time, its ratio to the raw call,
  the peak RSS of the driver and of each worker (from the report), and the
  over-refinement: the tiles' triangles / the raw call's triangles - 1.

Sizes default to 1.5M and 6M; ``--big`` adds 25M and 100M (memory: ~1.6 GB per 6M
triangles for the raw call alone; run those only on a machine you have to yourself).

    python benchmarks/bench_scale.py [--sizes 1.5e6,6e6] [--workers 1,2] [--big] [--tiles T]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "hammesh" / "data" / "demo.poly"

RAW = r"""
import json, resource, sys, time
import numpy as np, triangle
import hammesh
from hammesh.meshing.options import format_number
dom = hammesh.read_domain(sys.argv[1])
data = {"vertices": np.array(dom.vertices), "segments": np.array(dom.segments, dtype=np.int32),
        "holes": np.array(dom.holes)}
reg = np.array(dom.regions); reg[:, 3] = -1.0; data["regions"] = reg
t = time.perf_counter()
out = triangle.triangulate(data, "pq30Aa" + format_number(float(sys.argv[2])))
sec = time.perf_counter() - t
print(json.dumps({"seconds": sec, "triangles": int(len(out["triangles"])),
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def max_area_for(triangles: float) -> float:
    """The area bound whose Triangle run has about ``triangles`` triangles (estimate)."""
    import hammesh
    from hammesh.parallel.tiles import decompose

    dom = hammesh.read_domain(DEMO)
    probe = 1e-3
    est = decompose(dom, min_angle=30, max_area=probe, n_tiles=1).estimate
    return probe * est / triangles


def raw(area: float) -> dict:
    out = subprocess.run([sys.executable, "-c", RAW, str(DEMO), repr(area)], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def ours(area: float, workers: int, tiles: int | None) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        rep = Path(tmp) / "report.json"
        cmd = [sys.executable, "-m", "hammesh", "mesh", str(DEMO), "-q", "30", "-a", repr(area),
               "--workers", str(workers), "--partitioned", "-o", str(Path(tmp) / "out"), "--report", str(rep)]
        if tiles:
            cmd += ["--tiles", str(tiles)]
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        sec = time.perf_counter() - t
        r = json.loads(rep.read_text())
    r["wall"] = sec
    return r


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1.5e6,6e6", help="estimated triangle counts, comma separated")
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--tiles", type=int, help="tiles (default: hammesh's: one per worker, more past 3M)")
    ap.add_argument("--big", action="store_true", help="also 25M and 100M (needs ~40 GB: not on a shared VM)")
    a = ap.parse_args(argv)
    sizes = [float(s) for s in a.sizes.split(",")] + ([25e6, 100e6] if a.big else [])
    workers = [int(w) for w in a.workers.split(",")]
    print("size      raw s  raw MB  | workers  wall s  /raw   over-ref  driver MB  worker MB (max)  tiles joins")
    for n in sizes:
        area = max_area_for(n)
        r = raw(area)
        print(f"{n / 1e6:5.1f}M  {r['seconds']:7.2f} {r['peak_rss_mb']:7.0f}  | {r['triangles']:,} triangles (raw)")
        for w in workers:
            o = ours(area, w, a.tiles)
            par = o["parallel"]
            over = par["mesh_triangles"] / r["triangles"] - 1
            wrk = max(par["peak_rss_mb"]["workers"] or [0.0])
            print(f"{'':17}|  {w:5d}  {o['wall']:7.2f} {o['wall'] / r['seconds']:5.2f}  {100 * over:+7.2f} % "
                  f"{par['peak_rss_mb']['driver']:9.0f}  {wrk:10.0f}        {par['tiles']:5d} {par['joins']:5d}")
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
