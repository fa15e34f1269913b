"""Hand a mesh to finite-element and visualisation codes: scikit-fem, meshio, pyvista.

The boundary markers and regional attributes become *named sets*, the same names in
memory and in files (:mod:`hammesh.io.tags`):

* ``marker_<k>``: the facets (constrained edges) of segment marker ``k``;
* ``region_<a>``: the elements whose first regional attribute is ``a``.

>>> import hammesh
>>> dom = hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]], ring_markers=[[1, 2, 1, 3]])
>>> h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=0.05))
>>> m = hammesh.to_skfem(h)                                   # doctest: +SKIP
>>> sorted(m.boundaries)                                      # doctest: +SKIP
['marker_1', 'marker_2', 'marker_3']

Element ``i`` of every converted mesh is triangle ``i`` of the input (for a
:class:`~hammesh.mesh.HamiltonianMesh`: the cycle order) and point ``j`` is point
``j``.  scikit-fem and pyvista are optional (``pip install hammesh[fem]``,
``pip install hammesh[vtk]``); without them :func:`to_skfem` / :func:`to_pyvista`
raise :class:`~hammesh.errors.MissingDependencyError`.
"""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np

from hammesh.errors import InvalidMeshError, MissingDependencyError
from hammesh.io import meshio_format, tags
from hammesh.io.validate import validate_mesh
from hammesh.mesh import HamiltonianMesh, Mesh, triangle_neighbors

__all__ = [
    "to_skfem",
    "to_meshio",
    "to_pyvista",
    "boundary_facets",
    "subdomain_elements",
    "dual_graph",
    "neighbors",
]

_EXTRAS = {"skfem": "fem", "pyvista": "vtk"}


def _require(module: str) -> Any:
    """Import an optional dependency or raise a one-line error naming its extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        extra = _EXTRAS[module]
        raise MissingDependencyError(
            f"{module} is not installed: pip install hammesh[{extra}]"
        ) from None


def _check(mesh: Any, *, planar: bool = False) -> Mesh | HamiltonianMesh:
    if not isinstance(mesh, (Mesh, HamiltonianMesh)):
        raise InvalidMeshError(f"expected a hammesh.Mesh or HamiltonianMesh, got {type(mesh).__name__}")
    validate_mesh(mesh)
    if planar and np.shape(mesh.points)[1] != 2:
        raise InvalidMeshError(f"expected a planar mesh (points (n, 2)), got points {np.shape(mesh.points)}")
    return mesh


def neighbors(mesh: Mesh | HamiltonianMesh) -> np.ndarray:
    """``(m, 3) int64`` neighbour array (see :mod:`hammesh.mesh`): the mesh's own if it
    has one (``HamiltonianMesh.neighbors`` is computed once and kept), else computed."""
    _check(mesh)
    nbr = mesh.neighbors
    if nbr is None:
        return triangle_neighbors(mesh.triangles, mesh.n_points)
    return np.asarray(nbr, dtype=np.int64)


def dual_graph(mesh: Mesh | HamiltonianMesh) -> Any:
    """The dual graph: ``scipy.sparse.csr_matrix (m, m)``, 1 where two triangles share an
    edge (symmetric, no diagonal).  Its ``indptr``/``indices`` are what METIS-style
    partitioners take (``xadj``/``adjncy``)."""
    from scipy.sparse import csr_matrix

    nbr = neighbors(mesh)
    m = len(nbr)
    rows = np.repeat(np.arange(m, dtype=np.int64), 3)
    cols = nbr.reshape(-1)
    keep = cols >= 0
    graph = csr_matrix(
        (np.ones(int(keep.sum()), dtype=np.int8), (rows[keep], cols[keep])), shape=(m, m)
    )
    graph.sort_indices()
    return graph


def boundary_facets(mesh: Mesh | HamiltonianMesh) -> dict[str, np.ndarray]:
    """The constrained edges by marker: ``{"marker_<k>": (s_k, 2) int64}``, each in the
    mesh's segment direction and order (a plain-numpy view of :func:`to_skfem`'s
    boundaries)."""
    _check(mesh)
    seg = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    return {tags.boundary_name(k): seg[markers == k] for k in np.unique(markers).tolist()}


def subdomain_elements(mesh: Mesh | HamiltonianMesh) -> dict[str, np.ndarray]:
    """The triangles by first regional attribute: ``{"region_<a>": (m_a,) int64}``
    (ascending); empty without attributes."""
    _check(mesh)
    regions = tags.region_values(mesh)
    if regions is None:
        return {}
    values = np.unique(regions[~np.isnan(regions)])
    return {tags.region_name(v): np.flatnonzero(regions == v) for v in values.tolist()}


def to_skfem(mesh: Mesh | HamiltonianMesh) -> Any:
    """A ``skfem.MeshTri`` with named boundaries and subdomains.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
        Planar; its segments must be edges of its triangles.

    Returns
    -------
    skfem.MeshTri
        ``p`` = ``mesh.points.T``, element ``i`` = triangle ``i`` (skfem sorts each
        element's corners); ``boundaries["marker_<k>"]``: the facet indices of the
        constrained edges of marker ``k`` (boundary *and* interior ones, e.g. the
        interface between two regions), ascending; ``subdomains["region_<a>"]``: the
        element indices of regional attribute ``a``.  ``None`` where there are none
        (scikit-fem's convention).

    Raises
    ------
    MissingDependencyError
        scikit-fem is not installed (``pip install hammesh[fem]``).
    InvalidMeshError
        Not a valid planar mesh, or a segment that is not an edge of the triangles.
    """
    skfem = _require("skfem")
    mesh = _check(mesh, planar=True)
    p = np.ascontiguousarray(np.asarray(mesh.points, dtype=np.float64).T)
    t = np.ascontiguousarray(np.asarray(mesh.triangles, dtype=np.int64).T)
    base = skfem.MeshTri(p, t)
    boundaries = _skfem_boundaries(mesh, base.facets)
    subdomains = subdomain_elements(mesh)
    return skfem.MeshTri(p, t, boundaries or None, subdomains or None)


def _skfem_boundaries(mesh: Mesh | HamiltonianMesh, facets: np.ndarray) -> dict[str, np.ndarray]:
    """``{name: facet indices}`` of the segments, located among skfem's ``facets (2, nf)``."""
    seg = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    if not len(seg):
        return {}
    span = int(max(facets.max(), seg.max())) + 1
    fkeys = np.minimum(facets[0], facets[1]).astype(np.int64) * span + np.maximum(facets[0], facets[1])
    order = np.argsort(fkeys)
    skeys = np.minimum(seg[:, 0], seg[:, 1]) * span + np.maximum(seg[:, 0], seg[:, 1])
    pos = np.searchsorted(fkeys[order], skeys).clip(max=len(order) - 1)
    found = fkeys[order][pos] == skeys
    if not found.all():
        i = int(np.flatnonzero(~found)[0])
        a, b = seg[i].tolist()
        raise InvalidMeshError(f"segments[{i}] = ({a}, {b}) is not an edge of the triangles")
    index = order[pos]
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    return {tags.boundary_name(k): np.unique(index[markers == k]) for k in np.unique(markers).tolist()}


def to_meshio(mesh: Mesh | HamiltonianMesh, *, layout: str = ".vtu") -> Any:
    """The ``meshio.Mesh`` hammesh writes for ``layout`` (a suffix of
    :data:`hammesh.io.FORMATS` handled by meshio).

    ``".vtu"`` (default): triangles only; cell data ``cycle_position cycle_id parent
    kind attribute_<i>``, the constrained edges as ``segment_edges`` / ``edge_marker``
    and scikit-fem's ``skfem:b:marker_<k>`` / ``skfem:s:region_<a>`` (so that
    ``skfem.io.meshio.from_meshio`` finds the named sets); point data
    ``vertex_marker``.  ``".msh"``: Gmsh blocks, physical tags and names.

    Raises
    ------
    InvalidMeshError
        The mesh is not valid.
    FileFormatError
        ``layout`` is not a meshio suffix.
    """
    return meshio_format.as_meshio(_check(mesh), layout)


def to_pyvista(mesh: Mesh | HamiltonianMesh) -> Any:
    """A ``pyvista.UnstructuredGrid`` of the triangles only (planar meshes at ``z = 0``;
    3D surfaces as they are), with the cell
    data of :func:`to_meshio` (without the ``skfem:`` fields) and ``vertex_marker`` as
    point data.

    Raises
    ------
    MissingDependencyError
        pyvista is not installed (``pip install hammesh[vtk]``).
    InvalidMeshError
        The mesh is not valid.
    """
    pv = _require("pyvista")
    out = to_meshio(mesh)
    cells = out.cells[0].data
    if len(out.cells) != 1:  # segments that are not edges: line cells, left out here
        cells = next(block.data for block in out.cells if block.type == "triangle")
    grid = pv.UnstructuredGrid({pv.CellType.TRIANGLE: np.asarray(cells, dtype=np.int64)},
                               np.asarray(out.points, dtype=np.float64))
    for name, blocks in out.cell_data.items():
        if not name.startswith("skfem:") and name != meshio_format.SEGMENT_MARKER:
            grid.cell_data[name] = np.asarray(blocks[0])
    for name, values in out.point_data.items():
        grid.point_data[name] = np.asarray(values)
    return grid
