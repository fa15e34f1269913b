"""Headless pictures of meshes and Hamiltonian cycles (matplotlib imported lazily)."""

from __future__ import annotations

from hammesh.plot.cycle import plot_cycle, plot_mesh

__all__ = ["plot_cycle", "plot_mesh"]
