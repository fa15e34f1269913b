"""Strip files: writing index buffers atomically (meshes are read by
:func:`hammesh.io.read_mesh` with ``dim=None``: 2D or 3D, whichever the file holds).

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

from hammesh.errors import FileFormatError, InvalidOptionError
from hammesh.io.atomic import atomic_path, atomic_write_text
from hammesh.strips.generalized import GeneralizedStrips
from hammesh.strips.gl import GLStrip

__all__ = ["write_strip", "STRIP_SUFFIXES"]

#: Suffixes :func:`write_strip` writes.
STRIP_SUFFIXES = (".json", ".npz")


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
    restart = getattr(strip, "restart_index", None)
    if restart is not None and not 0 <= int(restart) <= 2**32 - 1:
        raise InvalidOptionError(
            f"restart_index={int(restart)} is not valid: must be an integer >= 0 and <= 4294967295 "
            "(GL index buffers are uint32)"
        )
    own = strip.indices if isinstance(strip, GLStrip) else strip.vertices
    if len(own) and (int(np.min(own)) < 0 or int(np.max(own)) > 2**32 - 1):
        raise InvalidOptionError(f"{path}: strip indices do not fit uint32")
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
