"""Write a run report (counts, angles, timings, verdict) as JSON.

The report is plain JSON: ``indent=2``, sorted keys, a trailing newline, written
atomically.  numpy scalars and arrays become Python numbers and lists, tuples and sets
become lists, paths become strings, and non-finite floats (``nan``, ``inf``) become
``null`` so the file stays standard JSON.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import PurePath
from typing import Any

import numpy as np

from hammesh.io.atomic import atomic_write_text

__all__ = ["write_report", "to_json_value", "collect_repairs", "format_angle", "marker_range"]


def to_json_value(value: Any, where: str = "report") -> Any:
    """``value`` converted to plain JSON types (see the module docstring).

    Raises
    ------
    TypeError
        A value has no JSON form; the message gives its key path.

    Examples
    --------
    >>> to_json_value({"n": np.int64(3), "a": np.array([0.5, np.inf])})
    {'n': 3, 'a': [0.5, None]}
    """
    if isinstance(value, np.ndarray):
        return [to_json_value(v, f"{where}[{i}]") for i, v in enumerate(value.tolist())]
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, complex):
        raise TypeError(f"{where}: complex value {value!r} has no JSON form")
    if isinstance(value, dict):
        return {str(k): to_json_value(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json_value(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, (set, frozenset)):
        return sorted((to_json_value(v, f"{where}{{}}") for v in value), key=repr)
    if isinstance(value, PurePath):
        return str(value)
    if callable(getattr(value, "to_dict", None)):  # records such as hammesh.domain.Repair
        return to_json_value(value.to_dict(), where)
    raise TypeError(f"{where}: {type(value).__name__} value has no JSON form")


def collect_repairs(*sources: Any) -> list[Any]:
    """The repairs recorded by ``sources``, in order, each once.

    A repair is what hammesh changed in a legitimate input to accept it (a quad
    triangulated, a constant ``z`` dropped, a T-junction split...): a string or a
    JSON-able dict.  Each source may carry them as an attribute ``repairs``, or in its
    ``info`` or ``report`` dict under ``"repairs"`` (a :class:`~hammesh.domain.Domain`,
    a :class:`~hammesh.mesh.Mesh`, a :class:`~hammesh.mesh.HamiltonianMesh`).

    Examples
    --------
    >>> class Source:
    ...     info = {"repairs": ["triangulated 1 quad"]}
    >>> collect_repairs(Source(), {"repairs": ["triangulated 1 quad", "dropped z = 5"]})
    ['triangulated 1 quad', 'dropped z = 5']
    """
    found: list[Any] = []
    seen: set[str] = set()
    for source in sources:
        if source is None:
            continue
        lists = [getattr(source, "repairs", None)]
        for holder in (getattr(source, "info", None), getattr(source, "report", None), source):
            if isinstance(holder, dict):
                lists.append(holder.get("repairs"))
        for items in lists:
            if not isinstance(items, (list, tuple)):
                continue
            for item in items:
                item = to_json_value(item)  # a Domain's Repair records become their dicts
                key = json.dumps(item, sort_keys=True)
                if key not in seen:
                    seen.add(key)
                    found.append(item)
    return found


def write_report(report: dict[str, Any], path: str | os.PathLike[str]) -> None:
    """Write ``report`` as JSON to ``path`` (indent 2, sorted keys, atomic).

    Parameters
    ----------
    report : dict
        Nested dicts, lists, numbers, strings, numpy scalars and arrays.
    path : path-like
    """
    text = json.dumps(to_json_value(report), indent=2, sort_keys=True, allow_nan=False)
    atomic_write_text(path, text + "\n")


def format_angle(degrees: float) -> str:
    """An angle for a summary line: two decimals, except where two decimals would call a
    sliver 0.00 or 180.00 (a point set's splitter triangulation has angles of 2e-6 deg):
    ``format_angle(2.4e-06) == "2.4e-06"``, ``format_angle(179.999941) == "179.999941"``.

    >>> format_angle(30.0), format_angle(2.4e-06), format_angle(179.999941), format_angle(0.0)
    ('30.00', '2.4e-06', '179.999941', '0.00')
    """
    if 0 < degrees < 0.005:
        return f"{degrees:.2g}"
    if 179.995 < degrees < 180:  # (decimals down to the second significant digit of 180 - x)
        return f"{degrees:.{min(15, 1 - math.floor(math.log10(180 - degrees)))}f}"
    return f"{degrees:.2f}"


def marker_range(markers: np.ndarray) -> str:
    """``1..5`` (the nonzero markers' range) for a note; at least one marker is nonzero."""
    nz = markers[markers != 0]
    lo, hi = int(nz.min()), int(nz.max())
    return str(lo) if lo == hi else f"{lo}..{hi}"
