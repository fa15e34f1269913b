"""Point lists in plain files: ``x y`` text (one point a line), ``.npy`` arrays and
Triangle ``.node`` files, read into ``(n, 2) float64`` arrays.

Used by ``hammesh points`` and ``hammesh polygon``; errors are
:class:`~hammesh.errors.FileFormatError` naming the file and line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hammesh.errors import FileFormatError
from hammesh.io.paths import require_file

__all__ = ["read_points"]


def read_points(path: str | Path) -> np.ndarray:
    """Read ``(n, 2)`` points from ``.node``, ``.npy`` or plain ``x y`` text.

    Raises
    ------
    FileFormatError
        Missing or malformed file (the message names file and line).
    """
    path = Path(path)
    require_file(path)
    suffix = path.suffix.lower()
    if suffix == ".node":
        from hammesh.domain import read_node
        from hammesh.io.guard import reading

        with reading(path):
            return np.asarray(read_node(path).vertices, dtype=np.float64)
    if suffix == ".npy":
        try:
            arr = np.load(path, allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 - a corrupt header fails in ast/tokenize: any error
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise FileFormatError(f"{path}: not a numpy array file ({detail})") from None
        if not isinstance(arr, np.ndarray):  # an .npz archive renamed .npy
            raise FileFormatError(f"{path}: not a single numpy array")
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise FileFormatError(f"{path}: expected an (n, 2) array, got shape {arr.shape}")
        if len(arr) == 0:
            raise FileFormatError(f"{path}: no points")
        if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
            # complex would lose its imaginary part, strings/objects are not coordinates
            raise FileFormatError(f"{path}: expected real numbers, got dtype {arr.dtype}")
        arr = np.asarray(arr, dtype=np.float64)
        if not np.isfinite(arr).all():
            i = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
            raise FileFormatError(f"{path}: point {i} is not finite: {arr[i].tolist()}")
        return arr
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    rows = []
    for k, line in enumerate(text.splitlines(), start=1):
        fields = line.split("#", 1)[0].replace(",", " ").split()
        if not fields:
            continue
        if len(fields) != 2:
            raise FileFormatError(f"{path}:{k}: expected two numbers 'x y', got {line.strip()!r}")
        try:
            x, y = float(fields[0]), float(fields[1])
        except ValueError:
            raise FileFormatError(f"{path}:{k}: not a number in {line.strip()!r}") from None
        if not (np.isfinite(x) and np.isfinite(y)):
            raise FileFormatError(f"{path}:{k}: point is not finite: {line.strip()!r}")
        rows.append((x, y))
    if not rows:
        raise FileFormatError(f"{path}: no points")
    return np.array(rows, dtype=np.float64)
