"""Strip encoders for any triangle mesh (paper §5): long dual paths, one index buffer.

Without Steiner points a mesh is rarely Hamiltonian (deciding it is NP-complete, §5), so
the scalable encoder covers the dual graph with few long paths, turn-aware so that few
swaps are needed, and joins them into one buffer:

* a :class:`~hammesh.mesh.HamiltonianMesh` (rows in cycle order, ``components`` run
  lengths) is sent as exactly one strip per cycle, cut where it saves the most swaps;
* any other mesh is covered greedily (:func:`greedy_paths`, O(m) numba), seeds with the
  fewest free neighbours first, each path grown both ways, preferring neighbours with
  few free neighbours and then the alternating turn; then a few sweeps of local moves
  at the path ends (join two ends, Posa rotation, tunnelling into a neighbouring path)
  keep every change that shortens the buffer;
* each path is sent in the direction that needs fewer swaps at its ends.

Cost of a buffer: ``T + 2 S + swaps`` plus ``S - 1`` restarts or ``2 (S - 1)`` stitches.
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidOptionError
from hammesh.mesh import HamiltonianMesh
from hammesh.strips import _kernels
from hammesh.strips.dual import DualMesh, MeshLike, dual_mesh
from hammesh.strips.generalized import GeneralizedStrips, generalized_from_turns
from hammesh.strips.gl import RESTART_INDEX, GLStrip, gl_strip_from_turns, verify_gl_strip
from hammesh.strips.paths import PathTurns, path_turns

__all__ = ["METHODS", "greedy_paths", "cycle_paths", "mesh_paths", "encode", "encode_generalized"]

#: How the dual paths are found: ``"auto"`` is ``"order"`` for a HamiltonianMesh and
#: ``"greedy"`` otherwise.
METHODS = ("auto", "greedy", "order")

#: Weight of a swap against a neighbour's remaining degree in the greedy choice.
_SWAP_WEIGHT = 1

#: Sweeps of :func:`~hammesh.strips._kernels.improve_paths` over the path ends (each
#: sweep is O(m); most of the gain comes in the first three).
_IMPROVE_PASSES = 4


def greedy_paths(dual: DualMesh, improve: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Cover the dual graph with paths, greedily, then improve the cover locally.

    Parameters
    ----------
    dual : DualMesh
    improve : bool
        After the greedy pass, join paths whose ends are neighbours, rotate path ends
        and tunnel into neighbouring paths wherever the buffer gets shorter
        (:func:`~hammesh.strips._kernels.improve_paths`, a few O(m) sweeps).

    Returns
    -------
    order : (m,) int64
        Every triangle once, path after path.
    starts : (S + 1,) int64
        Path offsets.  Paths never cross dual components.
    """
    m = dual.n_triangles
    order, starts = _kernels.greedy_paths(dual.triangles, dual.twin, _SWAP_WEIGHT, np.arange(m - 1, -1, -1))
    if improve:
        order, starts = _kernels.improve_paths(dual.triangles, dual.twin, order, starts, _IMPROVE_PASSES)
    return order, starts


def _cut_cycle(tri: np.ndarray, twin: np.ndarray, run: np.ndarray) -> np.ndarray:
    """Rotate one cycle so that opening it removes the most swaps."""
    k = len(run)
    if k < 4:
        return run
    nb = twin[3 * run[-1] : 3 * run[-1] + 3]
    if not np.any((nb >= 0) & (nb // 3 == run[0])):
        return run  # an open path: nothing to choose
    ext = np.r_[run[-1], run, run[0]]
    turns = path_turns(tri, twin, ext, [0, k + 2])
    piv = turns.pivot[1 : k + 1]  # cyclic pivots of run[0..k-1]
    f = (piv == np.roll(piv, 1)).astype(np.int64)  # f[j]: swap at j in the cycle
    # opening at c drops the swaps at c, c + 1 (start) and c - 1 (end)
    gain = f + np.roll(f, -1) + np.roll(f, 1)
    c = int(np.argmax(gain))
    return np.roll(run, -c)


def cycle_paths(dual: DualMesh, components: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One path per cycle of a mesh stored in Hamiltonian-cycle order.

    Parameters
    ----------
    dual : DualMesh
        Of the cycle-ordered triangles.
    components : (c,) int
        Run lengths of the cycles (:attr:`HamiltonianMesh.components`).
    """
    comp = np.asarray(components, dtype=np.int64)
    starts = np.r_[0, np.cumsum(comp)].astype(np.int64)
    if starts[-1] != dual.n_triangles or np.any(comp <= 0):
        raise InvalidOptionError(
            f"cycle run lengths {comp.tolist()[:6]} do not add up to {dual.n_triangles} triangles"
        )
    order = np.concatenate(
        [_cut_cycle(dual.triangles, dual.twin, np.arange(a, b)) for a, b in zip(starts[:-1], starts[1:])]
    )
    return order, starts


def _orient(dual: DualMesh, order: np.ndarray, starts: np.ndarray) -> PathTurns:
    """Turns of the paths, each path reversed where that needs fewer swaps.

    Interior pivots (and so interior swaps) do not depend on the direction; only the
    swap after the first triangle does, so the reversed count comes from the forward
    turns at the path's last two triangles.
    """
    fwd = path_turns(dual.triangles, dual.twin, order, starts)
    a, b = starts[:-1], starts[1:] - 1
    long = b - a >= 2
    sf = np.zeros(len(a), dtype=bool)
    sf[long] = fwd.swap[a[long] + 1]
    sb = np.zeros(len(a), dtype=bool)
    bl = b[long]
    sb[long] = dual.triangles[order[bl], fwd.entry[bl]] == fwd.pivot[bl - 1]
    flip = sf & ~sb
    if not flip.any():
        return fwd
    lengths = np.diff(starts)
    path_id = np.repeat(np.arange(len(lengths)), lengths)
    pos = np.arange(len(order)) - starts[path_id]
    idx = np.where(flip[path_id], starts[path_id] + lengths[path_id] - 1 - pos, np.arange(len(order)))
    return path_turns(dual.triangles, dual.twin, order[idx], starts)


def _stored_runs(dual: DualMesh) -> np.ndarray:
    """Run lengths of a plain mesh stored piece after piece (as hammesh writes cycles)."""
    label = dual.component
    starts = np.r_[0, np.flatnonzero(np.diff(label) != 0) + 1]
    if len(starts) != dual.n_components:
        raise InvalidOptionError(
            "method 'order' needs each connected piece stored as one consecutive run of rows"
        )
    return np.diff(np.r_[starts, dual.n_triangles])


def mesh_paths(mesh: MeshLike, method: str = "auto") -> tuple[DualMesh, PathTurns]:
    """Validate ``mesh``, cover its dual with paths and analyse their turns.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
    method : {"auto", "greedy", "order"}
        ``"order"`` takes the rows as given: a HamiltonianMesh's cycles, or a plain mesh
        whose pieces are stored as consecutive runs of rows, each a dual path or cycle
        (a Hamiltonian mesh read back from a file).

    Returns
    -------
    dual : DualMesh
    turns : PathTurns
    """
    if method not in METHODS:
        raise InvalidOptionError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    dual = dual_mesh(mesh)
    if method == "auto":
        method = "order" if isinstance(mesh, HamiltonianMesh) else "greedy"
    if method == "order":
        if isinstance(mesh, HamiltonianMesh):
            comps = np.asarray(mesh.components)
        else:
            comps = _stored_runs(dual)
        order, starts = cycle_paths(dual, comps)
    else:
        order, starts = greedy_paths(dual)
    return dual, _orient(dual, order, starts)


def encode(
    mesh: MeshLike,
    *,
    join: str = "restart",
    restart_index: int | None = RESTART_INDEX,
    method: str = "auto",
    verify: bool = True,
) -> GLStrip:
    """One GL_TRIANGLE_STRIP index buffer drawing every triangle of ``mesh`` once.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
        Planar ``(n, 2)`` or surface ``(n, 3)`` points; windings are kept.
    join : {"restart", "stitch"}
    restart_index : int
        Used with ``join="restart"`` (default ``0xFFFFFFFF``).
    method : {"auto", "greedy", "order"}
        See :func:`mesh_paths`.  A HamiltonianMesh gives exactly one strip per cycle.
    verify : bool
        Decode the buffer with OpenGL's rules and compare with the mesh
        (:func:`~hammesh.strips.gl.verify_gl_strip`); O(m log m).

    Returns
    -------
    GLStrip
        ``n_strips`` counts the dual paths (at least one per connected piece).

    Raises
    ------
    InvalidMeshError
        Bad input mesh (see :func:`~hammesh.strips.dual.dual_mesh`).
    VerificationError
        The buffer does not decode to the mesh (a bug; never returned silently).

    Examples
    --------
    >>> import hammesh
    >>> m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.05)
    >>> s = encode(m)
    >>> s.n_triangles == m.n_triangles, s.indices_per_triangle < 2
    (True, True)
    """
    dual, turns = mesh_paths(mesh, method)
    strip = gl_strip_from_turns(turns, join=join, restart_index=restart_index)
    if verify:
        verify_gl_strip(dual.triangles, strip.indices, strip.restart_index)
    return strip


def encode_generalized(mesh: MeshLike, *, method: str = "auto") -> GeneralizedStrips:
    """Generalized (IRIS GL) strips of ``mesh``: one vertex and one turn bit per triangle.

    Same paths as :func:`encode`; see :mod:`hammesh.strips.generalized`.
    """
    _, turns = mesh_paths(mesh, method)
    return generalized_from_turns(turns)
