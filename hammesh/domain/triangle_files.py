"""Readers and a writer for Triangle's ``.node`` and ``.poly`` files.

Format (https://www.cs.cmu.edu/~quake/triangle.node.html, ``triangle.poly.html``):

``.node``
    ``<#vertices> <dimension (2)> <#attributes> <#boundary markers (0|1)>`` then one
    line per vertex ``<index> <x> <y> [attributes...] [marker]``.
``.poly``
    a ``.node`` section (with ``#vertices == 0`` the vertices come from the sibling
    ``<stem>.node``), then ``<#segments> <#markers (0|1)>`` and lines
    ``<index> <a> <b> [marker]``, then ``<#holes>`` and lines ``<index> <x> <y>``, then
    optionally ``<#regions>`` and lines ``<index> <x> <y> <attribute> <max area>``.

Details followed from Triangle's reader: ``#`` starts a comment anywhere, blank lines
are ignored, every record is one line; trailing header fields may be omitted (dimension
2, no attributes, no markers); vertices are numbered consecutively from 0 or 1 and the
segments use the same base (we shift everything to zero-based); a region line with a
single value after x, y uses it both as attribute and max area; a max area <= 0 means
"no limit" (stored as NaN).  Vertex attributes are kept (``Domain.vertex_attributes``):
Triangle interpolates them at the points it inserts.
This reader is stricter than Triangle in one way: a record with the wrong number of
fields, or data after the last section, is an error instead of being ignored.
"""

from __future__ import annotations

import os
import re
import uuid
from pathlib import Path

import numpy as np

from hammesh.domain.pslg import Domain
from hammesh.errors import FileFormatError, InvalidDomainError

__all__ = ["read_node", "read_poly", "write_poly"]

_INT = re.compile(r"[+-]?\d+\Z")


class _Lines:
    """Data lines of a file: ``(line number, tokens)`` with comments and blanks removed."""

    def __init__(self, path: Path):
        self.name = path.name
        from hammesh.io.paths import require_file  # (here: hammesh.io loads meshio, 0.15 s)

        require_file(path)  # (a device or a pipe: /dev/zero would be read without end)
        try:
            text = path.read_text(encoding="utf-8").removeprefix("\ufeff")  # (a BOM, as Windows editors save, is no data)
        except FileNotFoundError:
            raise FileFormatError(f"{path}: no such file") from None
        except UnicodeDecodeError:
            raise FileFormatError(f"{path}: not a text file (invalid UTF-8)") from None
        except OSError as exc:
            raise FileFormatError(f"{path}: cannot read ({exc.strerror or exc})") from None
        self.rows = []
        for number, line in enumerate(text.splitlines(), start=1):
            tokens = line.split("#", 1)[0].split()
            if tokens:
                self.rows.append((number, tokens))
        if not self.rows:
            raise FileFormatError(f"{self.name}: file is empty (no data lines)")
        self.pos = 0
        self.last = self.rows[-1][0]

    def error(self, line, message):
        return FileFormatError(f"{self.name} line {line}: {message}")

    def next(self, what):
        if self.pos >= len(self.rows):
            raise FileFormatError(
                f"{self.name} line {self.last}: file ends early, expected {what}")
        row = self.rows[self.pos]
        self.pos += 1
        return row

    def at_end(self):
        return self.pos >= len(self.rows)

    def int(self, line, token, what):
        if not _INT.match(token):
            raise self.error(line, f"{what} must be an integer, got {token!r}")
        return int(token)

    def float(self, line, token, what):
        try:
            if "_" in token:
                raise ValueError
            return float(token)
        except ValueError:
            raise self.error(line, f"{what} must be a number, got {token!r}") from None

    def header(self, what, names, defaults):
        """A header line: first field required, trailing ones default."""
        line, tok = self.next(f"the {what} header")
        if len(tok) > len(names):
            raise self.error(line, f"{what} header has {len(tok)} fields, expected at most "
                                   f"{len(names)} ({', '.join(names)})")
        values = [self.int(line, t, n) for t, n in zip(tok, names)]
        values += defaults[len(values) - 1:]
        return line, values

    def record(self, n_fields, what):
        line, tok = self.next(what)
        if len(tok) != n_fields:
            raise self.error(line, f"{what}: expected {n_fields} numbers, got {len(tok)}")
        return line, tok


def _zero_or_one(lines, line, value, what):
    if value not in (0, 1):
        raise lines.error(line, f"number of {what} must be 0 or 1, got {value}")


def _read_vertices(lines):
    """Read a node section; returns ``(vertices, markers, base, count, attributes)``
    (count may be 0; ``attributes (n, k)``)."""
    line, (n, dim, nattr, nmark) = lines.header(
        "vertex", ["number of vertices", "dimension", "number of attributes",
                   "number of boundary markers"], [2, 0, 0])
    if n < 0:
        raise lines.error(line, f"number of vertices must be >= 0, got {n}")
    if dim != 2:
        raise lines.error(line, f"dimension must be 2, got {dim}")
    if nattr < 0:
        raise lines.error(line, f"number of attributes must be >= 0, got {nattr}")
    _zero_or_one(lines, line, nmark, "vertex boundary markers")
    vertices = np.empty((n, 2), np.float64)
    markers = np.zeros(n, np.int64)
    attributes = np.empty((n, nattr), np.float64)
    base = 0
    for i in range(n):
        line, tok = lines.record(3 + nattr + nmark, f"vertex {i + 1} of {n}")
        index = lines.int(line, tok[0], "vertex index")
        if i == 0:
            if index not in (0, 1):
                raise lines.error(line, f"the first vertex must be numbered 0 or 1, got {index}")
            base = index
        elif index != base + i:
            raise lines.error(line, f"vertex index {index} out of sequence, expected {base + i}")
        vertices[i, 0] = lines.float(line, tok[1], "x coordinate")
        vertices[i, 1] = lines.float(line, tok[2], "y coordinate")
        for j, t in enumerate(tok[3:3 + nattr]):
            attributes[i, j] = lines.float(line, t, "vertex attribute")
        if nmark:
            markers[i] = lines.int(line, tok[-1], "boundary marker")
    return vertices, markers, base, n, attributes


def _expect_end(lines, section):
    if not lines.at_end():
        line, _ = lines.rows[lines.pos]
        raise lines.error(line, f"unexpected data after the {section} section")


def _make_domain(name, base, strict, **arrays):
    try:
        return Domain(**arrays, strict=strict)
    except InvalidDomainError as exc:
        # (only where the message numbers something: tester18 r11 saw it after "spans only 1e-299")
        numbered = re.search(r"\b(?:vertex|vertices|segments?|point|region|hole)\s+\d", str(exc)) is not None
        note = " (indices zero-based; the file numbers from 1)" if base == 1 and numbered else ""
        raise InvalidDomainError(f"{name}: {exc}{note}") from None


def read_node(path, *, strict: bool = False) -> Domain:
    """Read a Triangle ``.node`` file as a :class:`Domain` without segments.

    Parameters
    ----------
    path : str or os.PathLike
    strict : bool
        Refuse duplicate vertices instead of merging them (``Domain.repairs``).

    Returns
    -------
    Domain
        ``vertices (n, 2)`` and ``vertex_markers (n,)`` (zeros if the file has none);
        the mesher triangulates the convex hull.

    Raises
    ------
    FileFormatError
        Missing, empty, truncated or malformed file (message names file and line).
    InvalidDomainError
        Well-formed file whose vertices are not a valid domain (e.g. duplicates).
    """
    path = Path(path)
    lines = _Lines(path)
    vertices, markers, base, _, attributes = _read_vertices(lines)
    _expect_end(lines, "vertex")
    return _make_domain(path.name, base, strict, vertices=vertices, vertex_markers=markers,
                        vertex_attributes=attributes)


def read_poly(path, *, strict: bool = False) -> Domain:
    """Read a Triangle ``.poly`` file as a :class:`Domain`.

    Parameters
    ----------
    path : str or os.PathLike
        If the file declares 0 vertices, they are read from ``<stem>.node`` next to it.
    strict : bool
        Refuse what Triangle would repair (duplicate vertices, T-junctions, overlapping
        or crossing segments) instead of repairing it; see ``Domain.repairs``.

    Returns
    -------
    Domain
        Zero-based; segments without markers get marker 1; regional max area <= 0
        (Triangle's "no limit") becomes NaN.

    Raises
    ------
    FileFormatError
        Missing, empty, truncated or malformed file (message names file and line).
    InvalidDomainError
        Well-formed file that is not a valid domain, or (``strict``) needs a repair
        (message starts with the file name).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "tri.poly"
    >>> _ = p.write_text("3 2 0 0\\n1 0 0\\n2 1 0\\n3 0 1\\n3 0\\n1 1 2\\n2 2 3\\n3 3 1\\n0\\n")
    >>> read_poly(p).segments.tolist()
    [[0, 1], [1, 2], [2, 0]]
    """
    path = Path(path)
    lines = _Lines(path)
    node_line = lines.rows[0][0]
    vertices, vmarkers, base, n, attributes = _read_vertices(lines)
    if n == 0:
        node_path = path.with_suffix(".node")
        if not node_path.exists():
            raise lines.error(node_line, f"0 vertices declared but {node_path.name} "
                                         "(where they should be) does not exist")
        node_lines = _Lines(node_path)
        vertices, vmarkers, base, _, attributes = _read_vertices(node_lines)
        _expect_end(node_lines, "vertex")

    line, (s, smark) = lines.header("segment", ["number of segments",
                                                "number of boundary markers"], [0])
    if s < 0:
        raise lines.error(line, f"number of segments must be >= 0, got {s}")
    _zero_or_one(lines, line, smark, "segment boundary markers")
    segments = np.empty((s, 2), np.int64)
    smarkers = np.ones(s, np.int64)
    for i in range(s):
        line, tok = lines.record(3 + smark, f"segment {i + 1} of {s}")
        lines.int(line, tok[0], "segment index")
        segments[i, 0] = lines.int(line, tok[1], "segment endpoint") - base
        segments[i, 1] = lines.int(line, tok[2], "segment endpoint") - base
        if smark:
            smarkers[i] = lines.int(line, tok[3], "boundary marker")

    line, (h,) = lines.header("hole", ["number of holes"], [])
    if h < 0:
        raise lines.error(line, f"number of holes must be >= 0, got {h}")
    holes = np.empty((h, 2), np.float64)
    for i in range(h):
        line, tok = lines.record(3, f"hole {i + 1} of {h}")
        lines.int(line, tok[0], "hole index")
        holes[i] = [lines.float(line, t, "hole coordinate") for t in tok[1:]]

    regions = np.empty((0, 4), np.float64)
    if lines.at_end():  # the region section is optional
        _expect_end(lines, "hole")
    else:
        line, (r,) = lines.header("region", ["number of regions"], [])
        if r < 0:
            raise lines.error(line, f"number of regions must be >= 0, got {r}")
        regions = np.empty((r, 4), np.float64)
        for i in range(r):
            line, tok = lines.next(f"region {i + 1} of {r}")
            if len(tok) not in (4, 5):
                raise lines.error(line, f"region {i + 1} of {r}: expected 4 or 5 numbers "
                                        f"(index x y attribute [max area]), got {len(tok)}")
            lines.int(line, tok[0], "region index")
            x, y, attr = (lines.float(line, t, "region value") for t in tok[1:4])
            area = lines.float(line, tok[4], "region max area") if len(tok) == 5 else attr
            regions[i] = [x, y, attr, area if area > 0 else np.nan]
    _expect_end(lines, "region")

    return _make_domain(path.name, base, strict, vertices=vertices, segments=segments, holes=holes,
                        regions=regions, segment_markers=smarkers, vertex_markers=vmarkers,
                        vertex_attributes=attributes)


def write_poly(domain: Domain, path) -> None:
    """Write ``domain`` to a Triangle ``.poly`` file, atomically.

    Zero-based numbering, floats written with ``repr`` so that :func:`read_poly` gives
    back identical arrays; a NaN regional max area is written as ``-1`` (no limit).
    The file is written to a temporary file in the same directory and moved into place
    with :func:`os.replace`, so readers never see a partial file.

    Parameters
    ----------
    domain : Domain
    path : str or os.PathLike
    """
    if not isinstance(domain, Domain):
        raise TypeError(f"write_poly needs a Domain, got {type(domain).__name__}")
    path = Path(path)
    f = repr
    out = [f"# {path.name}: written by hammesh (Triangle .poly, zero-based)",
           f"{len(domain.vertices)} 2 0 1"]
    out += [f"{i} {f(float(x))} {f(float(y))} {int(m)}"
            for i, ((x, y), m) in enumerate(zip(domain.vertices, domain.vertex_markers))]
    out.append(f"{len(domain.segments)} 1")
    out += [f"{i} {int(a)} {int(b)} {int(m)}"
            for i, ((a, b), m) in enumerate(zip(domain.segments, domain.segment_markers))]
    out.append(f"{len(domain.holes)}")
    out += [f"{i} {f(float(x))} {f(float(y))}" for i, (x, y) in enumerate(domain.holes)]
    out.append(f"{len(domain.regions)}")
    out += [f"{i} {f(float(x))} {f(float(y))} {f(float(a))} "
            f"{'-1' if np.isnan(area) else f(float(area))}"
            for i, (x, y, a, area) in enumerate(domain.regions)]
    data = ("\n".join(out) + "\n").encode("utf-8")

    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
