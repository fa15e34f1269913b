"""One option set for every meshing backend, validated before any C code runs."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hammesh import params
from hammesh.errors import InvalidOptionError

__all__ = ["MeshOptions", "MAX_MIN_ANGLE", "MAX_TRIANGLES", "STEINER_BUDGET", "format_number", "hull_area",
           "region_areas", "check_sizes"]

#: Triangle provably terminates for min angles up to 20.7 degrees and in practice up
#: to about 33.8; above ~34 it loops forever (and ignores Ctrl-C).
MAX_MIN_ANGLE = 34.0
#: Refusing a run whose area bound implies more triangles than this (memory: ~200 B
#: per triangle through the whole pipeline).
MAX_TRIANGLES = 50_000_000
#: Quality refinement (``-q``, ``-D``) without a ``max_steiner`` of the caller's stops after
#: this many added points (Triangle's ``-S``): a domain whose thin part or far vertex needs
#: more (a 1e-9 wedge needs ~1e9) is refused after a bounded run instead of meshing until
#: memory is gone. An area bound that passes ``check_sizes`` needs at most ~0.8 points per
#: ``area / max_area``, 40 M: below the budget.
STEINER_BUDGET = MAX_TRIANGLES


def format_number(x: float) -> str:
    """A switch-safe decimal: Triangle reads ``a1e-05`` as 1.0 and ``a1E-05`` as garbage."""
    return np.format_float_positional(float(x), trim="-")


@dataclass(frozen=True)
class MeshOptions:
    """Quality-meshing options shared by all backends.

    Parameters
    ----------
    min_angle : float or None
        Minimum angle in degrees, ``0 <= min_angle <= 34``; None: no quality refinement.
    max_area : float or None
        Global maximum triangle area, ``> 0``; None: no global limit.
    conforming_delaunay : bool
        Every triangle Delaunay (Triangle's ``-D``), not only constrained Delaunay.
    max_steiner : int or None
        Upper bound on added Steiner points (``-S``); None: unlimited.
    """

    min_angle: float | None = None
    max_area: float | None = None
    conforming_delaunay: bool = False
    max_steiner: int | None = None

    def __post_init__(self) -> None:
        if self.min_angle is not None:
            params.number("min_angle", self.min_angle, low=0.0, high=MAX_MIN_ANGLE,
                          what="degrees; Triangle does not terminate above ~34")
        if self.max_area is not None:
            params.number("max_area", self.max_area, low=0.0, low_open=True, what="area; omit it for no limit")
        if self.max_steiner is not None:
            params.integer("max_steiner", self.max_steiner, low=0, what="added Steiner points")

    def check_size(self, domain_area: float) -> None:
        """Refuse an area bound that would need more than ``MAX_TRIANGLES`` triangles."""
        if self.max_area is not None and domain_area / self.max_area > MAX_TRIANGLES:
            raise InvalidOptionError(
                f"max_area={self.max_area!r} would need about "
                f"{domain_area / self.max_area:.3g} triangles for a domain of area "
                f"{domain_area:.3g} (limit {MAX_TRIANGLES:,})", option="max_area"
            )


def hull_area(vertices: np.ndarray) -> float:
    """Area of the convex hull of ``vertices (n, 2)``, computed in a local frame.

    Translated to the bounding box's corner and scaled by a power of two (both exact
    for the differences that matter), so a 1e-6 square at offset 1e9 is no problem for
    Qhull; a hull Qhull still calls flat has (near) zero area: its bounding box's area
    is returned, an upper bound.
    """
    from scipy.spatial import ConvexHull, QhullError

    v = np.asarray(vertices, dtype=np.float64)
    lo = v.min(axis=0)
    ext = v.max(axis=0) - lo
    scale = float(ext.max())
    if not scale > 0:
        return 0.0
    k = math.frexp(scale)[1]  # 2**k > scale: exact rescale
    local = np.ldexp(v - lo, -k)
    try:
        area = float(ConvexHull(local).volume)
    except (QhullError, ValueError):
        area = float(np.ldexp(ext[0], -k) * np.ldexp(ext[1], -k))
    return math.ldexp(area, 2 * k)


def region_areas(domain) -> np.ndarray:
    """Area of the face each of ``domain.regions`` claims, as Triangle assigns them.

    One unrefined constrained triangulation (Triangle ``pA``, regions numbered by row)
    of the validated domain; a region whose point lies in a hole, outside, or in a face
    another region claims gets 0.
    """
    import triangle

    r = len(domain.regions)
    if r == 0:
        return np.zeros(0)
    lo = domain.vertices.min(axis=0)
    data = {"vertices": np.asarray(domain.vertices - lo, dtype=np.float64)}
    if len(domain.segments):
        data["segments"] = np.asarray(domain.segments, dtype=np.int32)
    if len(domain.holes):
        data["holes"] = np.asarray(domain.holes - lo, dtype=np.float64)
    reg = np.zeros((r, 4))
    reg[:, :2] = domain.regions[:, :2] - lo
    reg[:, 2] = np.arange(r)
    reg[:, 3] = -1.0
    data["regions"] = reg
    out = triangle.triangulate(data, ("p" if len(domain.segments) else "pc") + "AQ")
    tri = np.asarray(out.get("triangles", np.zeros((0, 3), np.int64)))
    if len(tri) == 0:
        return np.zeros(r)
    p = np.asarray(out["vertices"])[tri]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))
    owner = np.asarray(out["triangle_attributes"]).reshape(-1).round().astype(np.int64)
    return np.bincount(owner, weights=area, minlength=r)[:r]


def check_sizes(domain, opts: MeshOptions) -> None:
    """Refuse global or regional area bounds that imply more than ``MAX_TRIANGLES``.

    The global bound against the convex hull's area (:meth:`MeshOptions.check_size`);
    each regional bound (``domain.regions[:, 3]``, a ``.poly`` region's last column)
    against the area of the face the region claims (:func:`region_areas`, computed
    only when the hull's area says the bound might be too small). Both are estimates
    of Triangle's count (about area / bound triangles), checked before it runs:
    Triangle itself would run until memory is gone.

    Raises
    ------
    InvalidOptionError
        Naming the region (row, point), its bound and the estimated count.
    """
    regions = np.asarray(domain.regions)
    if opts.max_area is None and not np.isfinite(regions[:, 3]).any():
        return  # no bound at all: nothing to estimate (and no hull to compute)
    # the bounding box's area bounds the hull's: when the box passes, so does the hull,
    # and scipy.spatial (0.2 s to import) is not needed (speed's shortcut, kept here)
    ext = np.ptp(np.asarray(domain.vertices, dtype=np.float64), axis=0)
    box = float(ext[0] * ext[1])
    finite = regions[:, 3][np.isfinite(regions[:, 3])].tolist()
    tightest = min(finite + ([opts.max_area] if opts.max_area is not None else []))
    if np.isfinite(box) and box / tightest <= MAX_TRIANGLES:
        return
    hull = hull_area(domain.vertices)
    opts.check_size(hull)
    if len(regions) == 0:
        return
    bound = regions[:, 3].copy()
    if opts.max_area is not None:  # Triangle applies the smaller of the two
        bound = np.fmin(bound, opts.max_area)
    limited = np.isfinite(bound)
    if not limited.any() or hull / bound[limited].min() <= MAX_TRIANGLES:
        return
    areas = region_areas(domain)
    with np.errstate(divide="ignore", invalid="ignore"):
        count = np.where(limited, areas / np.where(limited, bound, 1.0), 0.0)
    total = float(count.sum())
    if total > MAX_TRIANGLES:
        i = int(np.argmax(count))
        x, y = regions[i, :2]
        raise InvalidOptionError(
            f"region {i} at ({format_number(x)}, {format_number(y)}) has max_area "
            f"{float(regions[i, 3])!r}, which would need about {count[i]:.3g} triangles for its "
            f"area {areas[i]:.3g} ({total:.3g} in all regions; limit {MAX_TRIANGLES:,})"
        )
