"""Named polygons of the paper used by the tests and the docs."""

from __future__ import annotations

import numpy as np

#: Like Figure 3: monotone, star-shaped, a unique triangulation (a central triangle
#: with three ears), so not Hamiltonian.
FIGURE3 = np.array([(0, 10), (-16, -7), (-9, -5), (14, -10), (9, -5), (2, 17)], dtype=float)


def regular(n: int, r: float = 1.0) -> np.ndarray:
    t = 2 * np.pi * np.arange(n) / n
    return np.c_[r * np.cos(t), r * np.sin(t)]


def comb(teeth: int, width: float = 1.0, gap: float = 1.0, base: float = 1.0,
         height: float = 4.0) -> np.ndarray:
    """Figure 7: a rectilinear comb with ``teeth`` teeth on a base, counter-clockwise."""
    right = teeth * width + (teeth - 1) * gap
    pts = [(0.0, 0.0), (right, 0.0)]
    for i in range(teeth - 1, -1, -1):
        x0 = i * (width + gap)
        pts += [(x0 + width, height), (x0, height)]
        if i > 0:
            pts += [(x0, base), (x0 - gap, base)]
    return np.array(pts, dtype=float)


def star(n: int, seed: int = 0) -> np.ndarray:
    """A random star-shaped polygon (random radii at sorted random angles)."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = rng.uniform(0.3, 1.0, n)
    return np.c_[r * np.cos(t), r * np.sin(t)]


def monotone(n: int, seed: int = 0) -> np.ndarray:
    """A random x-monotone polygon: sorted x, upper and lower chains."""
    rng = np.random.default_rng(seed)
    x = np.sort(rng.uniform(0, 1, n))
    up = rng.random(n) < 0.5
    up[0] = up[-1] = False
    y = rng.uniform(0.05, 1, n)
    y[0] = y[-1] = 0.0  # the chains meet on the x axis: lower below, upper above
    lower = np.c_[x[~up], -y[~up]]
    upper = np.c_[x[up], y[up]][::-1]
    return np.vstack([lower, upper])


def dented(n: int, r: int, seed: int = 0) -> np.ndarray:
    """A convex ``n``-gon on the unit circle with ``r`` vertices pushed in (reflex).

    Counter-clockwise, star-shaped from the origin; the pushed vertices are not adjacent,
    so the polygon has exactly ``r`` reflex vertices when ``n`` is large enough.
    """
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    rad = np.ones(n)
    dents = rng.choice(np.arange(0, n, 2)[: n // 2], size=r, replace=False)
    rad[dents] = rng.uniform(0.4, 0.85, r)
    return np.c_[rad * np.cos(t), rad * np.sin(t)]
