"""The certificate of a mesh read from a file, with no input to compare it with:
``hammesh check``, and ``hammesh partition`` before it cuts a file's cycles.

:func:`verify_stored_mesh` picks the certificate the mesh's points ask for: planar
(:func:`hammesh.verify.certificate.verify_stored_cycle_mesh`, or with ``path`` the path
check of :mod:`hammesh.verify.path`) plus the exact overlap test of the plane
(:func:`hammesh.planar_overlap.find_overlap`), or for 3D points the surface certificate
(:mod:`hammesh.verify.surface`) on the points welded as ``hammesh surface`` welds them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.mesh import KIND_NAMES, Mesh

__all__ = ["verify_stored_mesh", "check_stored_fields"]


def _number(value) -> str:
    """A stored value as a file shows it: 7, not np.float64(7.0)."""
    v = float(value)
    return str(int(v)) if v.is_integer() else repr(v)


def check_stored_fields(fields: dict[str, np.ndarray] | None, runs: np.ndarray, n_kinds: int) -> None:
    """Compare the cycle fields a file stores beside its rows with what the rows are.

    A viewer sorts by ``cycle_position`` and colours by ``cycle_id`` (docs/report.md), so
    they must say what the certificate derived from the rows' order: ``cycle_position``
    the row's place in its piece's run (0 at the run's first row), ``cycle_id`` the
    run's number; ``kind`` one of the ``n_kinds`` kinds, ``parent`` and ``part`` whole
    numbers (``parent`` -1 where no input triangle is the parent). Derived here from
    ``runs`` alone.

    Raises
    ------
    VerificationError
        Naming the field and the first row that disagrees.
    """
    if not fields:
        return
    runs = np.asarray(runs, dtype=np.int64)
    m = int(runs.sum())
    starts = np.repeat(np.cumsum(runs) - runs, runs)
    derived = {"cycle_position": np.arange(m) - starts, "cycle_id": np.repeat(np.arange(len(runs)), runs)}
    for name, values in fields.items():
        values = np.asarray(values)
        if values.shape != (m,):
            raise VerificationError(f"stored {name} has {values.size} values for {m} triangles", check="input")
        whole = np.isfinite(values) & (values == np.round(values)) if values.dtype.kind == "f" else np.ones(m, bool)
        if name in derived:
            bad = np.flatnonzero(~whole | (values != derived[name]))
            if len(bad):
                i = int(bad[0])
                raise VerificationError(f"stored {name} of triangle {i} is {_number(values[i])}; its place in the "
                                        f"rows says {int(derived[name][i])}", check="cycle")
        else:
            low = {"kind": 0, "parent": -1}.get(name, 0)
            high = n_kinds - 1 if name == "kind" else np.inf
            bad = np.flatnonzero(~whole | (values < low) | (values > high))
            if len(bad):
                i = int(bad[0])
                raise VerificationError(f"stored {name} of triangle {i} is {_number(values[i])}, not a whole number in "
                                        f"{low}..{'' if high == np.inf else int(high)}", check="input")


def verify_stored_mesh(mesh: Mesh, *, path: bool = False) -> tuple[np.ndarray, dict[str, Any], np.ndarray]:
    """``(runs, figures, triangles)`` of the certificate of a read mesh (planar or 3D).

    Parameters
    ----------
    mesh : Mesh
        As read (``hammesh.io.read_mesh(..., dim=None)``: 3D points only where z varies,
        or ``dim=3`` to ask for the surface certificate).
    path : bool
        Each piece a Hamiltonian path instead of a cycle (planar meshes only).

    Returns
    -------
    runs : (c,) int64
        The pieces' run lengths in file order.
    figures : dict
        The certificate's figures (angles, area, ...).
    triangles : (m, 3) int64
        The rows checked (a surface's after welding).

    Raises
    ------
    VerificationError
        Naming the fault (``InvalidMeshError`` where the rows are no valid mesh).
    """
    from hammesh.planar_overlap import find_overlap
    from hammesh.verify.certificate import verify_stored_cycle_mesh
    from hammesh.verify.path import verify_stored_path_mesh

    if path and mesh.points.shape[1] == 3:
        raise InvalidOptionError("--path checks planar meshes (`hammesh surface` writes cycles)")
    if mesh.points.shape[1] == 3:  # a 3D surface: the surface certificate (angles in 3D)
        from hammesh.surface.files import weld_surface
        from hammesh.verify.surface import infer_surface_runs, verify_surface

        # coincident points merged as `hammesh surface` merges them: only where their data
        # agree (a cylinder's cap and side meet at the rim with other normals: two points)
        welded = weld_surface(mesh.points, mesh.triangles, mesh.point_data)
        points, triangles = welded.points, welded.triangles
        try:
            runs = infer_surface_runs(triangles, len(points))
            stats = verify_surface(points, triangles, runs)
        except VerificationError:
            if len(points) == len(mesh.points):
                raise
            # the file's own numbering where welding changed it: a double-sided face
            # keeps both sides, and its two Steiner points lie at one place (the
            # incenter) as two vertices; welded, the sides' rows run into each other
            points, triangles = mesh.points, mesh.triangles
            runs = infer_surface_runs(triangles, len(points))
            stats = verify_surface(points, triangles, runs)
    else:
        triangles = mesh.triangles
        # the half-edges are paired once (the certificate's kernel), for all three checks
        verify_stored = verify_stored_path_mesh if path else verify_stored_cycle_mesh
        runs, stats, twin = verify_stored(mesh.points, triangles, segments=mesh.segments)
        pair = find_overlap(mesh.points, triangles, twin=twin)  # no input to compare with: test the plane
        if pair is not None:
            raise VerificationError(f"triangles {pair[0]} and {pair[1]} overlap", check="overlap")
    check_stored_fields((mesh.info or {}).get("cycle_fields"), runs, len(KIND_NAMES))
    return runs, stats, triangles
