"""Point lists in plain files: ``x y`` text (one point a line), ``.npy`` arrays and
Triangle ``.node`` files, read into ``(n, 2) float64`` arrays.

Used by ``hammesh points`` and ``hammesh polygon``; errors are
:class:`~hammesh.errors.FileFormatError` naming the file and line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError

__all__ = ["read_points"]


def read_points(path: str | Path) -> np.ndarray:
    """Read ``(n, 2)`` points from ``.node``, ``.npy`` or plain ``x y`` text.

    Raises
    ------
    FileFormatError
        Missing or malformed file (the message names file and line).
    """
    path = Path(path)
    if not path.exists():
        raise FileFormatError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix == ".node":
        from hammesh.domain import read_node

        return np.asarray(read_node(path).vertices, dtype=np.float64)
    if suffix == ".npy":
        try:
            arr = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise FileFormatError(f"{path.name}: not a numpy array file ({exc})") from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise FileFormatError(f"{path.name}: expected an (n, 2) array, got shape {arr.shape}")
        return np.asarray(arr, dtype=np.float64)
    rows = []
    for k, line in enumerate(path.read_text().splitlines(), start=1):
        text = line.split("#", 1)[0].replace(",", " ").split()
        if not text:
            continue
        if len(text) != 2:
            raise FileFormatError(f"{path.name}:{k}: expected two numbers 'x y', got {line.strip()!r}")
        try:
            rows.append((float(text[0]), float(text[1])))
        except ValueError:
            raise FileFormatError(f"{path.name}:{k}: not a number in {line.strip()!r}") from None
    if not rows:
        raise FileFormatError(f"{path.name}: no points")
    return np.array(rows, dtype=np.float64)
