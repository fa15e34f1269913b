"""Simple polygons in files: Triangle ``.poly`` (one closed chain), GeoJSON, WKT, ``x y`` text.

Moved here from the command line so that every reader lives in :mod:`hammesh.io`; every
malformed file (not UTF-8, JSON of the wrong shape or nested too deep, a ring that is
not a list of coordinate pairs) is a :class:`~hammesh.errors.FileFormatError` naming it.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from hammesh.domain.validate import point_array
from hammesh.errors import FileFormatError, InvalidDomainError
from hammesh.io.guard import reading
from hammesh.io.paths import require_file
from hammesh.io.points_text import read_points

__all__ = ["read_polygon", "read_polygon_rings", "write_triangulation", "POLYGON_SUFFIXES"]

#: suffixes with a reader of their own; anything else is read as ``x y`` text
POLYGON_SUFFIXES = (".poly", ".geojson", ".json", ".wkt")


def read_polygon(path: str | Path) -> np.ndarray:
    """Read an ``(n, 2)`` polygon from ``.poly``, GeoJSON, WKT or plain ``x y`` text.

    A closing vertex equal to the first is dropped.

    Raises
    ------
    FileFormatError
        Missing or malformed file, holes, or several polygons.
    """
    outer, holes = read_polygon_rings(path)
    if holes:
        raise FileFormatError(f"{path}: polygons with holes are not supported here "
                              f"({len(holes)} holes)")
    return outer


def read_polygon_rings(path: str | Path) -> tuple[np.ndarray, list[np.ndarray]]:
    """Read a polygon with holes: the outer ring and the hole rings, each ``(k, 2)``.

    ``.poly``: the closed chains of segments, the one of largest area outside (hole
    points are not needed); GeoJSON ``Polygon``: its rings; WKT ``POLYGON ((...), (...))``;
    plain ``x y`` text: one ring.  A closing vertex equal to the first is dropped.

    Raises
    ------
    FileFormatError
        Missing or malformed file, or several polygons.
    """
    path = Path(path)
    require_file(path)
    suffix = path.suffix.lower()
    with reading(path):
        if suffix == ".poly":
            rings = _from_poly(path)
        elif suffix in (".geojson", ".json"):
            rings = _from_geojson(path)
        elif suffix == ".wkt":
            rings = _from_wkt(path)
        else:
            rings = [read_points(path)]
    rings = [r[:-1] if len(r) > 1 and np.array_equal(r[0], r[-1]) else r for r in rings]
    return rings[0], rings[1:]


def _text(path: Path) -> str:
    try:
        return path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{path}: not UTF-8 text (byte {exc.start})") from None


def _from_poly(path: Path) -> list[np.ndarray]:
    from hammesh.domain import read_poly

    dom = read_poly(path)
    seg = dom.segments
    if len(seg) == 0:
        return [dom.vertices]
    nxt: dict[int, list[int]] = {}
    for a, b in seg.tolist():
        for u, v in ((a, b), (b, a)):
            nxt.setdefault(u, []).append(v)
    if any(len(v) != 2 for v in nxt.values()):
        raise FileFormatError(f"{path}: the segments must form closed chains "
                              "(every vertex on exactly two segments)")
    rings, seen = [], set()
    for start in sorted(nxt):
        if start in seen:
            continue
        order, prev, cur = [start], -1, start
        seen.add(start)
        while True:
            a, b = nxt[cur]
            step = a if a != prev else b
            if step == start:
                break
            order.append(step)
            seen.add(step)
            prev, cur = cur, step
        rings.append(dom.vertices[order])

    def area(r):
        x, y = r[:, 0], r[:, 1]
        return abs(float(x @ np.roll(y, -1) - np.roll(x, -1) @ y))

    rings.sort(key=area, reverse=True)   # the outer ring encloses the others
    return rings


def _get(obj: Any, key: str) -> Any:
    return obj.get(key) if isinstance(obj, dict) else None


def _from_geojson(path: Path) -> list[np.ndarray]:
    try:
        data = json.loads(_text(path))
    except RecursionError:
        raise FileFormatError(f"{path}: JSON nested too deeply") from None
    except ValueError as exc:
        raise FileFormatError(f"{path}: not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise FileFormatError(f"{path}: expected a GeoJSON object, got a JSON {type(data).__name__}")
    if data.get("type") == "FeatureCollection":
        features = data.get("features")
        if not isinstance(features, list) or len(features) != 1:
            raise FileFormatError(f"{path}: expected exactly one feature")
        data = features[0]
    if _get(data, "type") == "Feature":
        data = _get(data, "geometry") or {}
    kind = _get(data, "type")
    if kind != "Polygon":
        raise FileFormatError(f"{path}: expected a GeoJSON Polygon, got {kind!r}")
    rings = data.get("coordinates")
    if not isinstance(rings, list):
        raise FileFormatError(f"{path}: Polygon coordinates must be a list of rings")
    if not rings:
        raise FileFormatError(f"{path}: a Polygon needs at least one ring")
    out = []
    for ring in rings:
        if not isinstance(ring, list) or not all(
            isinstance(p, list) and len(p) >= 2 and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in p[:2])
            for p in ring
        ):
            raise FileFormatError(f"{path}: a ring must be a list of [x, y] number pairs")
        out.append(_array([p[:2] for p in ring], path))
    return out


def _from_wkt(path: Path) -> list[np.ndarray]:
    text = _text(path).strip()
    m = re.fullmatch(r"POLYGON\s*\(\s*(\([^()]*\)(?:\s*,\s*\([^()]*\))*)\s*\)", text, flags=re.IGNORECASE)
    if not m:
        raise FileFormatError(f"{path}: expected 'POLYGON ((x y, ...), (hole ...), ...)'")
    out = []
    for body in re.findall(r"\(([^()]*)\)", m.group(1)):
        rows = [c.split() for c in body.split(",")]
        if len({len(r) for r in rows}) > 1:
            raise FileFormatError(f"{path}: each WKT coordinate must be 'x y'")
        out.append(_array(rows, path))
    return out


def _array(rows: Any, path: Path) -> np.ndarray:
    try:
        return point_array(rows, f"{path}: coordinates")
    except InvalidDomainError as exc:  # a file's fault: reported as a file format error
        raise FileFormatError(str(exc)) from None
    except (ValueError, TypeError, OverflowError):
        raise FileFormatError(f"{path}: coordinates are not numbers") from None


def write_triangulation(path: str | Path, points: Any, triangles: Any, **info: Any) -> None:
    """Write a polygon's triangulation: ``.json`` (``points``, ``triangles`` in path order
    and ``info``) or any mesh format of :mod:`hammesh.io`, atomically."""
    path = Path(path)
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    if path.suffix.lower() == ".json":
        from hammesh.io.atomic import atomic_write_text
        from hammesh.io.report import to_json_value

        doc = {"points": points.tolist(), "triangles": triangles.tolist(), **to_json_value(info)}
        atomic_write_text(path, json.dumps(doc) + "\n")
        return
    from hammesh.io import write
    from hammesh.mesh import Mesh

    write(Mesh(points, triangles), path)
