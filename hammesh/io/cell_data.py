"""Per-triangle data written next to a :class:`~hammesh.mesh.HamiltonianMesh`.

Names are shared by every writer that can store per-cell values (meshio's VTU, VTK,
Gmsh and XDMF; Triangle's ``.ele`` attributes), so a file opened in ParaView, Gmsh or
read back by hammesh shows the same fields.
"""

from __future__ import annotations

import re

import numpy as np

from hammesh.mesh import HamiltonianMesh, Mesh, attribute_name

__all__ = ["cycle_ids", "triangle_cell_data", "ATTRIBUTE_PREFIX", "CYCLE_FIELDS", "split_components", "join_components"]

#: Cell-data name of column ``i`` of ``triangle_attributes`` is ``f"attribute_{i}"``.
ATTRIBUTE_PREFIX = "attribute_"
#: The per-triangle fields hammesh writes about a Hamiltonian mesh (and a partition's
#: ``part``); a reader of hammesh's output skips them, so a user's field never takes
#: these names in such a file.
CYCLE_FIELDS = ("cycle_position", "cycle_id", "parent", "kind", "part")


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
    ``kind`` (all ``(m,) int64``); for any mesh: each column of
    ``triangle_attributes`` ``(m,) float64`` under its name (``attribute_names``, a
    mesh file's field names, else ``attribute_<i>``); columns named ``v[0]``,
    ``v[1]``, ... are one ``(m, c)`` field ``v``, as they were read.  A user's field
    named like one of hammesh's (``kind``, ``parent``...) is written as ``input_<name>``,
    never over hammesh's.
    """
    data: dict[str, np.ndarray] = {}
    # a Hamiltonian mesh's file reserves every cycle field name (its reader skips them)
    reserved = set(CYCLE_FIELDS) if isinstance(mesh, HamiltonianMesh) else set()
    if isinstance(mesh, HamiltonianMesh):
        data["cycle_position"] = np.asarray(mesh.position, dtype=np.int64)
        data["cycle_id"] = cycle_ids(mesh.components)
        data["parent"] = np.asarray(mesh.parent, dtype=np.int64)
        data["kind"] = np.asarray(mesh.kind, dtype=np.int64)
    if getattr(mesh, "part", None) is not None:  # hammesh.partition.PartitionedMesh
        data["part"] = np.asarray(mesh.part, dtype=np.int64)
    attrs = np.asarray(mesh.triangle_attributes, dtype=np.float64)
    names = tuple(getattr(mesh, "attribute_names", ()))
    k = attrs.shape[1] if attrs.ndim == 2 else 0
    i = 0
    while i < k:
        name = attribute_name(names, i)
        base, index = _component(name)
        if index == 0:  # columns base[0], base[1], ...: one array of that many components
            c = 1
            while i + c < k and _component(attribute_name(names, i + c)) == (base, c):
                c += 1
            data[_free_name(data, reserved, base)] = np.ascontiguousarray(attrs[:, i:i + c])
            i += c
            continue
        data[_free_name(data, reserved, name)] = np.ascontiguousarray(attrs[:, i])
        i += 1
    return data


def _free_name(data: dict[str, np.ndarray], reserved: set[str], name: str) -> str:
    """``name``, or ``input_<name>`` (``input_input_<name>``...) if taken or reserved."""
    while name in data or name in reserved:
        name = f"input_{name}"
    return name


_COMPONENT_RE = re.compile(r"^(.*)\[(\d+)\]$")


def _component(name: str) -> tuple[str, int | None]:
    """``("v", 2)`` for a column named ``v[2]`` (a component of the vector field ``v``),
    ``(name, None)`` otherwise."""
    match = _COMPONENT_RE.match(name)
    return (match.group(1), int(match.group(2))) if match else (name, None)


def split_components(data: dict[str, np.ndarray], allowed: tuple[int, ...]) -> dict[str, np.ndarray]:
    """``data`` with each ``(k, c)`` array whose ``c`` is not in ``allowed`` split into
    scalar arrays ``name[0]``, ``name[1]``, ... (Gmsh stores 1, 3 or 9 components only);
    :func:`join_components` undoes it.

    >>> sorted(split_components({"v": np.zeros((4, 2)), "s": np.zeros(4)}, (1, 3, 9)))
    ['s', 'v[0]', 'v[1]']
    """
    out: dict[str, np.ndarray] = {}
    for name, values in data.items():
        values = np.asarray(values)
        if values.ndim == 2 and values.shape[1] not in allowed:
            out.update({f"{name}[{j}]": np.ascontiguousarray(values[:, j]) for j in range(values.shape[1])})
        else:
            out[name] = values
    return out


def join_components(data: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Scalar arrays ``v[0]``, ``v[1]``, ... (consecutive, from 0) as one ``(k, c)`` array ``v``.

    >>> {k: v.shape for k, v in join_components({"v[0]": np.zeros(4), "v[1]": np.ones(4)}).items()}
    {'v': (4, 2)}
    """
    names = list(data)
    out: dict[str, np.ndarray] = {}
    j = 0
    while j < len(names):
        base, index = _component(names[j])
        c = 1
        if index == 0 and np.ndim(data[names[j]]) == 1:
            while j + c < len(names) and _component(names[j + c]) == (base, c) and np.ndim(data[names[j + c]]) == 1:
                c += 1
            out[base] = np.column_stack([data[names[j + i]] for i in range(c)])
        else:
            out[names[j]] = data[names[j]]
        j += c
    return out
