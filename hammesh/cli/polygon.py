"""``hammesh polygon``: a simple polygon -> Hamiltonian / sequential / Steiner triangulation."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np

from hammesh.domain.validate import point_array
from hammesh.errors import FileFormatError, InvalidDomainError
from hammesh.io.points_text import read_points

HELP = "triangulate a simple polygon so that its triangles form one dual path (Thm 2.1, 2.3, 4.4)"
EXAMPLES = """examples:
  hammesh polygon outline.poly -o outline.json --png outline.png     # Thm 2.1, or fail
  hammesh polygon outline.txt --sequential -o strip.json             # Thm 4.4 (one strip)
  hammesh polygon comb.poly --steiner path -o comb.vtu               # Thm 2.3, k-2 Steiner points
inputs: .poly (one closed chain of segments), .geojson/.json (a Polygon without holes),
        .wkt (POLYGON ((...))), anything else: plain text, one "x y" per line (# comments).
outputs: .json (points, triangles in path order, counts) or any mesh format of hammesh.io."""


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", type=Path, help="polygon file (.poly, .geojson, .wkt or 'x y' text)")
    p.add_argument("-o", "--output", type=Path, help="output (.json or a mesh format: .vtu .msh .obj ...)")
    p.add_argument("--png", type=Path, help="draw polygon, triangles and dual path into this image")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--sequential", action="store_true",
                   help="require alternating turns (one triangle strip, Thm 4.4)")
    g.add_argument("--steiner", choices=["cycle", "path"],
                   help="add Steiner points: k-1 for a cycle, k-2 for a path (Thm 2.3)")


def read_polygon(path: Path) -> np.ndarray:
    """Read an ``(n, 2)`` polygon from ``.poly``, GeoJSON, WKT or plain ``x y`` text.

    A closing vertex equal to the first is dropped.

    Raises
    ------
    FileFormatError
        Missing or malformed file, holes, or several polygons.
    """
    if not path.exists():
        raise FileFormatError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix == ".poly":
        pts = _from_poly(path)
    elif suffix in (".geojson", ".json"):
        pts = _from_geojson(path)
    elif suffix == ".wkt":
        pts = _from_wkt(path)
    else:
        pts = read_points(path)
    if len(pts) > 1 and np.array_equal(pts[0], pts[-1]):
        pts = pts[:-1]
    return pts


def _from_poly(path: Path) -> np.ndarray:
    from hammesh.domain import read_poly

    dom = read_poly(path)
    if len(dom.holes):
        raise FileFormatError(f"{path.name}: holes are not supported by 'hammesh polygon'")
    seg = dom.segments
    if len(seg) == 0:
        return dom.vertices
    nxt = {}
    for a, b in seg.tolist():
        for u, v in ((a, b), (b, a)):
            nxt.setdefault(u, []).append(v)
    if any(len(v) != 2 for v in nxt.values()):
        raise FileFormatError(f"{path.name}: the segments must form one closed chain "
                              "(every vertex on exactly two segments)")
    start = int(seg[0, 0])
    order, prev, cur = [start], -1, start
    while True:
        a, b = nxt[cur]
        step = a if a != prev else b
        if step == start:
            break
        order.append(step)
        prev, cur = cur, step
    if len(order) != len(seg):
        raise FileFormatError(f"{path.name}: the segments form several closed chains "
                              f"(first has {len(order)} of {len(seg)} segments)")
    return dom.vertices[order]


def _from_geojson(path: Path) -> np.ndarray:
    try:
        data = json.loads(path.read_text())
    except ValueError as exc:
        raise FileFormatError(f"{path.name}: not JSON: {exc}") from None
    if data.get("type") == "FeatureCollection":
        if len(data.get("features", [])) != 1:
            raise FileFormatError(f"{path.name}: expected exactly one feature")
        data = data["features"][0]
    if data.get("type") == "Feature":
        data = data.get("geometry") or {}
    if data.get("type") != "Polygon":
        raise FileFormatError(f"{path.name}: expected a GeoJSON Polygon, got {data.get('type')!r}")
    rings = data.get("coordinates") or []
    if len(rings) != 1:
        raise FileFormatError(f"{path.name}: polygons with holes are not supported ({len(rings)} rings)")
    return _array(rings[0], path)


def _from_wkt(path: Path) -> np.ndarray:
    text = path.read_text().strip()
    m = re.fullmatch(r"POLYGON\s*\(\s*\(([^()]*)\)\s*\)", text, flags=re.IGNORECASE)
    if not m:
        raise FileFormatError(f"{path.name}: expected 'POLYGON ((x y, ...))' without holes")
    return _array([c.split() for c in m.group(1).split(",")], path)


def _array(rows, path: Path) -> np.ndarray:
    try:
        return point_array(rows, f"{path.name}: coordinates")
    except InvalidDomainError as exc:  # a file's fault: reported as a file format error
        raise FileFormatError(str(exc)) from None


def run(args: argparse.Namespace) -> int:
    from hammesh import polygon

    pts = read_polygon(args.input)
    n_steiner, k, closed = 0, None, False
    if args.steiner:
        res = polygon.steiner_hamiltonian_result(pts, args.steiner)
        Q, T, n_steiner, k, closed = res.points, res.triangles, res.n_steiner, res.k, args.steiner == "cycle"
        what = f"Hamiltonian {args.steiner} with {n_steiner} Steiner points ({k} convex pieces, {res.method})"
    elif args.sequential:
        T, Q = polygon.sequential_triangulation(pts), pts
        what = "sequential triangulation (one strip)"
        if T is None:
            raise InvalidDomainError(f"{args.input}: the polygon has no sequential triangulation "
                                     "(Thm 4.4); try without --sequential or with --steiner path")
    else:
        T, Q = polygon.hamiltonian_triangulation(pts), pts
        what = "Hamiltonian triangulation"
        if T is None:
            raise InvalidDomainError(f"{args.input}: the polygon has no Hamiltonian triangulation "
                                     "(Thm 2.1); --steiner path adds k-2 Steiner points (Thm 2.3)")
    if args.output is not None:
        _write(args.output, Q, T, n=len(pts), n_steiner=n_steiner, k=k,
               kind=args.steiner or ("sequential" if args.sequential else "hamiltonian"))
    if args.png is not None:
        from hammesh.polygon.plot import plot_polygon_path

        plot_polygon_path(pts, Q, T, args.png, closed=closed, title=f"{args.input.name}: {what}")
    print(f"{len(pts)} vertices: {what}, {len(T)} triangles")
    for label, path in (("triangulation", args.output), ("picture", args.png)):
        if path is not None:
            print(f"wrote {label}: {path}")
    return 0


def _write(path: Path, Q, T, **info) -> None:
    if path.suffix.lower() == ".json":
        from hammesh.io.atomic import atomic_write_text

        doc = {"points": np.asarray(Q).tolist(), "triangles": np.asarray(T).tolist(), **info}
        atomic_write_text(path, json.dumps(doc) + "\n")
        return
    import hammesh

    hammesh.io.write(hammesh.Mesh(np.asarray(Q, dtype=np.float64), np.asarray(T, dtype=np.int64)), path)
