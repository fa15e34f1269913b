"""Strip files: reading any triangle mesh (2D or 3D) and writing index buffers atomically.

Output formats, chosen by suffix:

* ``.json``: the document of :meth:`GLStrip.to_dict` / :meth:`GeneralizedStrips.to_dict`;
* ``.npz``: the same keys as numpy arrays (``indices`` as uint32, ``swap_bits`` as uint8),
  for big meshes.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io import meshio_format, read_mesh
from hammesh.io.atomic import atomic_path, atomic_write_text
from hammesh.mesh import Mesh
from hammesh.strips.generalized import GeneralizedStrips
from hammesh.strips.gl import GLStrip

__all__ = ["read_surface", "write_strip", "STRIP_SUFFIXES"]

#: Suffixes :func:`write_strip` writes.
STRIP_SUFFIXES = (".json", ".npz")


def read_surface(path: str | os.PathLike[str]) -> Mesh:
    """Read a triangle mesh whose points may be 3D (a surface); 2D files as :func:`hammesh.read_mesh`.

    Returns
    -------
    Mesh
        ``points (n, 2)`` for planar files, ``(n, 3)`` otherwise.

    Raises
    ------
    FileFormatError
        Unknown suffix, missing or malformed file, no triangles, index out of range.
    """
    path = Path(path)
    try:
        return read_mesh(path)
    except FileFormatError as exc:
        if "not planar" not in str(exc):
            raise
    # a surface in space: the same guarded meshio reader, keeping z
    raw = meshio_format._meshio_read(path, meshio_format._FORMATS[path.suffix.lower()][0])
    pts = np.ascontiguousarray(raw.points, dtype=np.float64)
    blocks = [np.asarray(b.data, dtype=np.int64).reshape(-1, 3) for b in raw.cells if b.type == "triangle"]
    if not blocks or sum(len(b) for b in blocks) == 0:
        raise FileFormatError(f"{path}: no triangles")
    tri = np.concatenate(blocks)
    if tri.min() < 0 or tri.max() >= len(pts):
        raise FileFormatError(f"{path}: triangle vertex index out of range [0, {len(pts)})")
    if not np.isfinite(pts).all():
        raise FileFormatError(f"{path}: non-finite point coordinates")
    return Mesh(pts, np.ascontiguousarray(tri))


def write_strip(strip: GLStrip | GeneralizedStrips, path: str | os.PathLike[str], extra: dict | None = None) -> None:
    """Write a strip buffer as ``.json`` or ``.npz``, atomically.

    Parameters
    ----------
    strip : GLStrip or GeneralizedStrips
    path : path-like
        Suffix ``.json`` or ``.npz``.
    extra : dict, optional
        More (JSON-able) fields, e.g. the method used.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in STRIP_SUFFIXES:
        raise FileFormatError(f"{path}: strip output must be {' or '.join(STRIP_SUFFIXES)}, got {suffix!r}")
    doc = strip.to_dict()
    doc.update(extra or {})
    if suffix == ".json":  # noqa: SIM108
        atomic_write_text(path, json.dumps(doc, separators=(",", ":")) + "\n")
        return
    arrays = {}
    for key, value in doc.items():
        if key == "indices":
            own = strip.indices if isinstance(strip, GLStrip) else strip.vertices
            arrays[key] = np.asarray(own, dtype=np.uint32)
        elif key == "swap_bits":
            arrays[key] = np.asarray(value, dtype=np.uint8)
        elif key == "strip_starts":
            arrays[key] = np.asarray(value, dtype=np.int64)
        elif value is None:
            arrays[key] = np.array(-1)
        else:
            arrays[key] = np.asarray(value)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, **arrays)
