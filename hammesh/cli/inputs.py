"""Which input files are domains: a light module (no library import), so that the
parallel path can refuse a mesh input before its local cluster starts."""

from __future__ import annotations

__all__ = ["DOMAIN_SUFFIXES"]

#: inputs read as domains (meshed first); anything else is read as a finished mesh
DOMAIN_SUFFIXES = (".poly", ".node")
