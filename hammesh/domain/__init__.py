"""The input side of hammesh: planar straight-line graphs and Triangle's file formats.

>>> from hammesh.domain import Domain, read_domain, write_poly
"""

from __future__ import annotations

import os
from pathlib import Path

from hammesh import params
from hammesh.domain.pslg import Domain
from hammesh.domain.repair import REPAIR_KINDS, Repair, repair_graph
from hammesh.domain.triangle_files import read_node, read_poly, write_poly
from hammesh.domain.validate import validate_domain
from hammesh.errors import FileFormatError

__all__ = ["Domain", "Repair", "REPAIR_KINDS", "repair_graph", "validate_domain", "read_domain",
           "read_node", "read_poly", "write_poly", "READERS"]

#: File suffix -> reader returning a :class:`Domain`.
READERS = {".poly": read_poly, ".node": read_node}


def read_domain(path, *, strict: bool = False) -> Domain:
    """Read a domain file, choosing the reader from the suffix (see :data:`READERS`).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.poly`` or ``.node`` file (suffix case-insensitive).
    strict : bool
        Refuse what Triangle would repair instead of repairing it (``Domain.repairs``
        lists what was repaired otherwise).

    Raises
    ------
    FileFormatError
        Unknown suffix (the message lists the known ones) or malformed file.
    """
    params.instance("path", path, (str, os.PathLike), "a file path (str or os.PathLike)")
    path = Path(path)
    reader = READERS.get(path.suffix.lower())
    if reader is None:
        known = ", ".join(sorted(READERS))
        if path.exists() and not path.is_file():  # (the whole path, and what it is: tester18 r11)
            why = "is a directory" if path.is_dir() else "not a regular file"
            raise FileFormatError(f"{path}: {why}; a domain is a file (known: {known})")
        raise FileFormatError(f"{path}: unknown domain file suffix {path.suffix!r} (known: {known})")
    return reader(path, strict=strict)
