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
from hammesh.mesh import Mesh

__all__ = ["verify_stored_mesh"]


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
    return runs, stats, triangles
