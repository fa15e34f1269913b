"""Per-triangle data written next to a :class:`~hammesh.mesh.HamiltonianMesh`.

Names are shared by every writer that can store per-cell values (meshio's VTU, VTK,
Gmsh and XDMF; Triangle's ``.ele`` attributes), so a file opened in ParaView, Gmsh or
read back by hammesh shows the same fields.
"""

from __future__ import annotations

import numpy as np

from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["cycle_ids", "triangle_cell_data", "ATTRIBUTE_PREFIX"]

#: Cell-data name of column ``i`` of ``triangle_attributes`` is ``f"attribute_{i}"``.
ATTRIBUTE_PREFIX = "attribute_"


def cycle_ids(components: np.ndarray) -> np.ndarray:
    """Cycle index of each triangle, from the run lengths of the cycles.

    Parameters
    ----------
    components : (c,) int
        Run lengths (see :attr:`HamiltonianMesh.components`).

    Returns
    -------
    (sum(components),) int64

    Examples
    --------
    >>> cycle_ids(np.array([3, 2])).tolist()
    [0, 0, 0, 1, 1]
    """
    components = np.asarray(components, dtype=np.int64)
    return np.repeat(np.arange(len(components), dtype=np.int64), components)


def triangle_cell_data(mesh: Mesh | HamiltonianMesh) -> dict[str, np.ndarray]:
    """Per-triangle arrays, in triangle (cycle) order, keyed by their file name.

    For a :class:`HamiltonianMesh`: ``cycle_position``, ``cycle_id``, ``parent``,
    ``kind`` (all ``(m,) int64``); for any mesh: ``attribute_<i>`` ``(m,) float64``
    for each column of ``triangle_attributes``.
    """
    data: dict[str, np.ndarray] = {}
    if isinstance(mesh, HamiltonianMesh):
        data["cycle_position"] = np.asarray(mesh.position, dtype=np.int64)
        data["cycle_id"] = cycle_ids(mesh.components)
        data["parent"] = np.asarray(mesh.parent, dtype=np.int64)
        data["kind"] = np.asarray(mesh.kind, dtype=np.int64)
    if getattr(mesh, "part", None) is not None:  # hammesh.partition.PartitionedMesh
        data["part"] = np.asarray(mesh.part, dtype=np.int64)
    attrs = np.asarray(mesh.triangle_attributes, dtype=np.float64)
    for i in range(attrs.shape[1] if attrs.ndim == 2 else 0):
        data[f"{ATTRIBUTE_PREFIX}{i}"] = np.ascontiguousarray(attrs[:, i])
    return data
