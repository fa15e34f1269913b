"""Checks run before any mesh is written (or plotted): never hand garbage to a writer.

Always on (not a debug mode): the cost is a few vectorized passes over the arrays.
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidMeshError, InvalidOptionError
from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["validate_mesh"]


def _int_array(name: str, a: object, ndim: int, width: int | None = None) -> np.ndarray:
    arr = np.asarray(a)
    if arr.ndim != ndim or (width is not None and arr.shape[1] != width):
        want = f"(k, {width})" if width is not None else "(k,)"
        raise InvalidMeshError(f"{name} must have shape {want}, got {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise InvalidMeshError(f"{name} must be an integer array, got dtype {arr.dtype}")
    return arr


def _check_indices(name: str, arr: np.ndarray, n: int) -> None:
    if arr.size == 0:
        return
    bad = (arr < 0) | (arr >= n)
    if bad.any():
        row, col = (int(i) for i in np.argwhere(bad)[0])
        value = int(arr[row, col])
        raise InvalidMeshError(
            f"{name}[{row}, {col}] = {value} is out of range [0, {n}) "
            f"(the mesh has {n} points)"
        )


def validate_mesh(mesh: Mesh | HamiltonianMesh) -> None:
    """Raise :class:`~hammesh.errors.InvalidMeshError` unless ``mesh`` can be written.

    Checks: ``points`` is ``(n, 2)`` (or ``(n, 3)``, a surface) and finite; ``triangles`` is a non-empty
    ``(m, 3)`` integer array with indices in ``[0, n)``; ``segments`` is ``(s, 2)``
    with indices in range; ``triangle_attributes`` has ``m`` rows (any values: NaN in a
    user's cell data is data, not an error).
    For a :class:`HamiltonianMesh` also: ``components`` are positive and sum to ``m``;
    ``position``, ``parent`` and ``kind`` have ``m`` entries.

    Examples
    --------
    >>> import numpy as np
    >>> validate_mesh(Mesh(np.zeros((3, 2)), np.array([[0, 1, 3]])))
    Traceback (most recent call last):
    ...
    hammesh.errors.InvalidMeshError: triangles[0, 2] = 3 is out of range [0, 3) (the mesh has 3 points)
    """
    if not isinstance(mesh, (Mesh, HamiltonianMesh)):  # (a Domain, a meshio.Mesh, arrays...)
        raise InvalidOptionError(f"mesh must be a hammesh.Mesh or HamiltonianMesh, got {type(mesh).__name__}")
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise InvalidMeshError(f"points must have shape (n, 2) or (n, 3), got {points.shape}")
    if not np.issubdtype(points.dtype, np.number):
        raise InvalidMeshError(f"points must be numeric, got dtype {points.dtype}")
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        i = int(np.flatnonzero(~finite)[0])
        raise InvalidMeshError(f"points[{i}] = {points[i].tolist()} is not finite")
    n = points.shape[0]

    triangles = _int_array("triangles", mesh.triangles, 2, 3)
    m = triangles.shape[0]
    if m == 0:
        raise InvalidMeshError("the mesh has no triangles")
    _check_indices("triangles", triangles, n)

    segments = _int_array("segments", mesh.segments, 2, 2)
    _check_indices("segments", segments, n)

    attrs = np.asarray(mesh.triangle_attributes)
    if attrs.ndim != 2 or attrs.shape[0] != m:
        raise InvalidMeshError(
            f"triangle_attributes must have shape ({m}, k), got {attrs.shape}"
        )

    if isinstance(mesh, HamiltonianMesh):
        components = _int_array("components", mesh.components, 1)
        if (components <= 0).any():
            c = int(np.flatnonzero(components <= 0)[0])
            raise InvalidMeshError(f"components[{c}] = {int(components[c])} is not positive")
        if int(components.sum()) != m:
            raise InvalidMeshError(
                f"components sum to {int(components.sum())}, expected {m} (the number of triangles)"
            )
        for name in ("position", "parent", "kind"):
            arr = _int_array(name, getattr(mesh, name), 1)
            if arr.shape[0] != m:
                raise InvalidMeshError(f"{name} has {arr.shape[0]} entries, expected {m}")
