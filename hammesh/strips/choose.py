"""``hammesh strip``'s policy as a library call: pick the encoding, return it with its facts.

``method="auto"`` encodes greedily and, when the file's rows are stored as dual paths
(a Hamiltonian mesh written by ``hammesh mesh``), also in row order, and keeps the
shorter buffer; ``"christofides"`` is Thm 5.3's 9/4-approximation, which may redraw
triangles (its counts are reported apart).  Moved here from the command line so that
a script gets what the command gets.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hammesh import params
from hammesh.errors import InvalidOptionError
from hammesh.strips.cache import DEFAULT_CACHE, vertex_cache_stats
from hammesh.strips.generalized import GeneralizedStrips
from hammesh.strips.gl import RESTART_INDEX, GLStrip

__all__ = ["StripChoice", "choose_strip", "METHODS", "JOINS", "MAX_RESTART_INDEX"]

METHODS = ("auto", "greedy", "order", "zigzag", "rows", "christofides")
JOINS = ("restart", "stitch")
#: GL index buffers are uint32: the largest restart index there is.
MAX_RESTART_INDEX = 2**32 - 1


@dataclass(frozen=True)
class StripChoice:
    """The encoding chosen and what ``hammesh strip`` reports about it.

    Attributes
    ----------
    strip : GLStrip or GeneralizedStrips
    method : str
        The method that produced ``strip`` (``"auto"`` resolved).
    extra : dict
        Fields added to the written document (``method``; with Christofides the
        mesh's triangle count and its ``indices_per_triangle``).
    """

    strip: GLStrip | GeneralizedStrips
    method: str
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def n_triangles(self) -> int:
        return int(self.extra.get("triangles", self.strip.n_triangles))

    @property
    def indices_per_triangle(self) -> float:
        return float(self.extra.get("indices_per_triangle", self.strip.indices_per_triangle))


def choose_strip(
    mesh: Any,
    *,
    method: str = "auto",
    join: str = "restart",
    restart_index: int = RESTART_INDEX,
    generalized: bool = False,
    cache: int | None = None,
    reorder_vertices: bool = False,
    fast: bool = False,
) -> StripChoice:
    """Encode ``mesh`` as ``hammesh strip`` does (see the module docstring).

    Raises
    ------
    InvalidOptionError
        An unknown method or join, a restart index outside ``[0, 2**32 - 1]``,
        ``generalized`` with Christofides, ``fast`` with anything but a GL strip of
        method auto or greedy without ``cache``.
    """
    from hammesh.strips.christofides import christofides_strip
    from hammesh.strips.encode import encode, encode_generalized

    method = params.choice("method", method, METHODS)
    join = params.choice("join", join, JOINS)
    restart_index = params.integer("restart_index", restart_index, low=0, high=MAX_RESTART_INDEX,
                                   what="GL index buffers are uint32")
    generalized = params.flag("generalized", generalized)
    if generalized and method == "christofides":
        raise InvalidOptionError("generalized strips are not available with method 'christofides'")
    reorder_vertices = params.flag("reorder_vertices", reorder_vertices)
    if cache is not None:
        cache = params.integer("cache", cache, low=3, high=1 << 16, what="FIFO entries")
        if generalized or method not in ("auto", "greedy", "zigzag", "rows"):
            raise InvalidOptionError(
                "a cache-aware encoding is a GL strip of its own paths: method auto, greedy, zigzag or rows only")
    fast = params.flag("fast", fast)
    if fast and (generalized or cache is not None or method not in ("auto", "greedy")):
        raise InvalidOptionError("fast is the greedy cover alone: a GL strip of method auto or greedy, without cache")
    if reorder_vertices and (generalized or method == "christofides"):
        raise InvalidOptionError("reorder_vertices applies to GL strips of method auto, greedy or order")
    extra: dict[str, Any] = {}
    if generalized:
        if method == "auto":
            candidates = [("greedy", encode_generalized(mesh, method="greedy"))]
            try:
                candidates.append(("order", encode_generalized(mesh, method="order")))
            except (InvalidOptionError, ValueError):
                pass  # rows are not stored as dual paths: greedy only
            method, strip = min(candidates, key=lambda c: len(c[1].vertices))
        else:
            strip = encode_generalized(mesh, method=method)
    elif method == "christofides":
        enc = christofides_strip(mesh, join=join, restart_index=restart_index)
        strip = enc.strip
        extra["christofides"] = enc.report()
        # the contract counts mesh triangles; redrawn ones are reported apart
        extra["drawn"] = strip.n_triangles
        extra["triangles"] = enc.n_triangles
        extra["indices_per_triangle"] = len(strip.indices) / enc.n_triangles
    elif cache is not None:
        # auto: the swap-free chains in short pieces; greedy / zigzag / rows: that cover; all in FIFO order
        strip = encode(mesh, method=method, join=join, restart_index=restart_index, cache=cache,
                       reorder_vertices=reorder_vertices)
        method = "cache" if method == "auto" else f"{method}+cache"
    elif fast:
        strip = encode(mesh, method="greedy", join=join, restart_index=restart_index, reorder_vertices=reorder_vertices,
                       fast=True)
        method = "fast"
    elif method == "auto":
        kw = {"join": join, "restart_index": restart_index, "reorder_vertices": reorder_vertices}
        candidates = [("greedy", encode(mesh, method="greedy", **kw)), ("zigzag", encode(mesh, method="zigzag", **kw))]
        if np.asarray(mesh.points).shape[1] == 2:  # rows along the x or y axis: planar meshes
            candidates.insert(0, ("rows", encode(mesh, method="rows", **kw)))
        try:
            candidates.append(("order", encode(mesh, method="order", **kw)))
        except (InvalidOptionError, ValueError):
            pass  # rows are not stored as dual paths: greedy only
        method, strip = min(candidates, key=lambda c: len(c[1].indices))
    else:
        strip = encode(mesh, method=method, join=join, restart_index=restart_index, reorder_vertices=reorder_vertices)
    extra["method"] = method
    if isinstance(strip, GLStrip):
        stats = vertex_cache_stats(strip.indices, strip.restart_index, strip.n_triangles, cache or DEFAULT_CACHE)
        extra.update(stats.to_dict())
    return StripChoice(strip, method, extra)
