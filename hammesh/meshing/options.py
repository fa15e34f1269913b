"""One option set for every meshing backend, validated before any C code runs."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hammesh.errors import InvalidOptionError

__all__ = ["MeshOptions", "MAX_MIN_ANGLE", "MAX_TRIANGLES", "format_number"]

#: Triangle provably terminates for min angles up to 20.7 degrees and in practice up
#: to about 33.8; above ~34 it loops forever (and ignores Ctrl-C).
MAX_MIN_ANGLE = 34.0
#: Refusing a run whose area bound implies more triangles than this (memory: ~200 B
#: per triangle through the whole pipeline).
MAX_TRIANGLES = 50_000_000


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
            a = _number("min_angle", self.min_angle)
            if not 0.0 <= a <= MAX_MIN_ANGLE:
                raise InvalidOptionError(
                    f"min_angle must be between 0 and {MAX_MIN_ANGLE} degrees, got {a!r} "
                    "(Triangle does not terminate above ~34 degrees)"
                )
        if self.max_area is not None:
            a = _number("max_area", self.max_area)
            if not a > 0.0:
                raise InvalidOptionError(
                    f"max_area must be positive, got {a!r} (use None for no limit)"
                )
        if self.max_steiner is not None:
            if isinstance(self.max_steiner, bool) or not isinstance(
                self.max_steiner, (int, np.integer)
            ):
                raise InvalidOptionError(
                    f"max_steiner must be a non-negative integer, got {self.max_steiner!r}"
                )
            if self.max_steiner < 0:
                raise InvalidOptionError(
                    f"max_steiner must be a non-negative integer, got {self.max_steiner!r}"
                )

    def check_size(self, domain_area: float) -> None:
        """Refuse an area bound that would need more than ``MAX_TRIANGLES`` triangles."""
        if self.max_area is not None and domain_area / self.max_area > MAX_TRIANGLES:
            raise InvalidOptionError(
                f"max_area={self.max_area!r} would need about "
                f"{domain_area / self.max_area:.3g} triangles for a domain of area "
                f"{domain_area:.3g} (limit {MAX_TRIANGLES:,})"
            )


def _number(name: str, x: object) -> float:
    try:
        v = float(x)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidOptionError(f"{name} must be a number, got {x!r}") from None
    if not math.isfinite(v):
        raise InvalidOptionError(f"{name} must be finite, got {x!r}")
    return v
