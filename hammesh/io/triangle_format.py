"""Read and write Jonathan Shewchuk's Triangle files: ``.node`` + ``.ele`` (+ ``.poly``).

A mesh ``foo`` is three files, written together and atomically (each through a
temporary sibling; the targets are replaced only once all three are complete):

* ``foo.node``: ``<n> 2 0 1`` then ``<i> <x> <y> <marker>`` (zero-based, ``%.17g`` so
  floats round-trip exactly; the points' boundary markers, ``vertex_markers``);
* ``foo.poly``: the constrained edges, as Triangle's ``-p`` output writes them
  (``0 2 0 1``: vertices are in ``foo.node``; ``<s> 1``; ``<i> <a> <b> <marker>``;
  ``0`` holes).  Always written, possibly with no segments, so a stale ``.poly`` from an
  earlier mesh can never be paired with the new ``.node``;
* ``foo.ele``: ``<m> 3 <k>`` then ``<i> <a> <b> <c> <attributes>``, triangles in row
  (for a :class:`~hammesh.mesh.HamiltonianMesh`: cycle) order.  The attributes are
  the columns of ``triangle_attributes`` then, for a Hamiltonian mesh, ``cycle_id``,
  ``cycle_position``, ``kind``, ``parent`` (and a partitioned mesh's ``part``); a
  comment ``# attributes: <names>`` names them.

Reading follows Triangle's rules: ``#`` starts a comment, blank lines are skipped, the
first vertex number in ``.node`` (0 or 1) fixes the numbering of every file.  A
``.poly`` next to the ``.ele`` is optional; if present its segments are read.  When the
``# attributes:`` comment is present it names the columns (``attribute_names``) and the
cycle fields are left out of ``triangle_attributes``; otherwise every attribute column
is an attribute.  The ``.node`` file's vertex attributes are the mesh's ``point_data``
(written back the same way, named by a ``# attributes:`` comment of the ``.node`` file;
a vector field ``v`` is the columns ``v[0]``, ``v[1]``, ...).  Names are one token:
white space in a name is written as ``_``.

Reference: https://www.cs.cmu.edu/~quake/triangle.node.html (and ``.ele``, ``.poly``).
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

from urllib.parse import unquote

import numpy as np

from hammesh.errors import FileFormatError, InvalidMeshError
from hammesh.io.atomic import atomic_paths
from hammesh.io.cell_data import ATTRIBUTE_PREFIX, CYCLE_FIELDS, join_components, triangle_cell_data
from hammesh.io.paths import refuse_foreign_companions, require_file
from hammesh.io.text_rows import header_token, write_rows
from hammesh.io.validate import validate_mesh
from hammesh.mesh import HamiltonianMesh, Mesh, attribute_name

__all__ = ["read_ele", "write", "SUFFIXES"]

#: Suffixes handled by this module (either names the same pair of files).
SUFFIXES: tuple[str, ...] = (".ele", ".node")

#: Order of the cycle fields among the ``.ele`` attributes (after ``attribute_<i>``).
#: The Hamiltonian mesh's own columns after the attributes, in file order (``parent``
#: and ``part``, a partitioned mesh's, came later: files without them read the same).
_CYCLE_FIELDS = ("cycle_id", "cycle_position", "kind", "parent", "part")
_ATTRIBUTES_COMMENT = "# attributes:"


def _siblings(path: str | os.PathLike[str]) -> tuple[Path, Path, Path]:
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise FileFormatError(f"{path}: expected a .ele or .node path")
    return path.with_suffix(".node"), path.with_suffix(".poly"), path.with_suffix(".ele")


def write(mesh: Mesh | HamiltonianMesh, path: str | os.PathLike[str]) -> None:
    """Write ``mesh`` as ``<stem>.node``, ``<stem>.poly`` and ``<stem>.ele``, atomically.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
        Validated first (:func:`hammesh.io.validate.validate_mesh`).
    path : path-like
        ``<stem>.ele`` or ``<stem>.node``; both name the same three files.

    Raises
    ------
    OutputError
        A companion file (the two not named) exists and is not one hammesh wrote: the
        user's domain ``<stem>.poly`` is never replaced by a mesh's segment file.
    """
    node_path, poly_path, ele_path = _siblings(path)
    refuse_foreign_companions(path)
    validate_mesh(mesh)
    if np.shape(mesh.points)[1] != 2:
        raise InvalidMeshError(
            f"{Path(path).name}: Triangle's .node/.ele files hold planar meshes; "
            "write a 3D surface as .vtu .vtk .obj .ply .stl or .off"
        )
    points = np.asarray(mesh.points, dtype=np.float64)
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    segments = np.asarray(mesh.segments, dtype=np.int64).reshape(-1, 2)
    markers = np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1)
    if len(markers) != len(segments):
        markers = np.zeros(len(segments), dtype=np.int64)
    n, m, s = len(points), len(triangles), len(segments)

    data = triangle_cell_data(mesh)
    attrs = np.asarray(mesh.triangle_attributes, dtype=np.float64).reshape(m, -1)
    given = tuple(getattr(mesh, "attribute_names", ()))
    names = [header_token(attribute_name(given, j)) for j in range(attrs.shape[1])]
    columns = [attrs[:, j] for j in range(attrs.shape[1])]
    if isinstance(mesh, HamiltonianMesh):
        # a user's column named like a cycle field keeps its data under another name
        names = [f"input_{name}" if name in CYCLE_FIELDS else name for name in names]
        own = [k for k in _CYCLE_FIELDS if k in data]
        names += own
        columns += [data[k] for k in own]
    point_names, point_columns = [], []
    for name, values in getattr(mesh, "point_data", {}).items():
        values = np.asarray(values, dtype=np.float64).reshape(n, -1)
        one = values.shape[1] == 1
        point_names += [header_token(name if one else f"{name}[{j}]") for j in range(values.shape[1])]
        point_columns += [values[:, j] for j in range(values.shape[1])]
    kind = "Hamiltonian mesh (triangles in cycle order)" if isinstance(mesh, HamiltonianMesh) else "mesh"

    with atomic_paths([node_path, poly_path, ele_path]) as (tmp_node, tmp_poly, tmp_ele):
        with open(tmp_node, "w", encoding="utf-8", newline="\n") as f:
            f.write(f"# hammesh {kind}: Triangle .node file, zero-based\n")
            if point_names:
                f.write(f"{_ATTRIBUTES_COMMENT} {' '.join(point_names)}\n")
            f.write("# <# of vertices> <dimension> <# of attributes> <# of boundary markers>\n")
            f.write(f"{n} 2 {len(point_names)} 1\n")
            f.write("# <vertex #> <x> <y> <attributes> <boundary marker>\n")
            vmarks = np.asarray(getattr(mesh, "vertex_markers", np.zeros(0)), dtype=np.int64).reshape(-1)
            if len(vmarks) != n:
                vmarks = np.zeros(n, dtype=np.int64)
            write_rows(f, [np.arange(n), points[:, 0], points[:, 1], *point_columns, vmarks])

        with open(tmp_poly, "w", encoding="utf-8", newline="\n") as f:
            f.write(f"# hammesh {kind}: Triangle .poly file, zero-based; vertices in {node_path.name}\n")
            f.write("0 2 0 1\n")
            f.write("# <# of segments> <# of boundary markers>\n")
            f.write(f"{s} 1\n")
            f.write("# <segment #> <endpoint> <endpoint> <boundary marker>\n")
            write_rows(f, [np.arange(s), segments[:, 0], segments[:, 1], markers])
            f.write("# <# of holes>\n0\n")

        with open(tmp_ele, "w", encoding="utf-8", newline="\n") as f:
            f.write(f"# hammesh {kind}: Triangle .ele file, zero-based\n")
            f.write(f"{_ATTRIBUTES_COMMENT} {' '.join(names)}\n")
            f.write("# <# of triangles> <nodes per triangle> <# of attributes>\n")
            f.write(f"{m} 3 {len(names)}\n")
            f.write("# <triangle #> <node> <node> <node> <attributes>\n")
            # the cycle fields are integers (``%d``), the user's attributes floats
            values = [np.asarray(c, np.int64 if k in _CYCLE_FIELDS else np.float64) for k, c in zip(names, columns)]
            write_rows(f, [np.arange(m), *triangles.T, *values])


class _Tokens:
    """A cursor over the records (non-blank, non-comment lines) of a Triangle file.

    :meth:`row` reads one record as tokens (exact messages: file and line);
    :meth:`table` reads many records at once with :func:`numpy.loadtxt` (a million
    triangles in a fraction of a second) and leaves a bad file to :meth:`row`, whose
    message then names the line.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        require_file(path)
        try:
            text = path.read_text(encoding="utf-8").removeprefix("\ufeff")  # (a BOM is no data)
        except UnicodeDecodeError:
            raise FileFormatError(f"{path}: not a text file") from None
        except OSError as exc:
            raise FileFormatError(f"{path}: cannot read ({exc.strerror})") from None
        self.lines = text.splitlines()
        self.comments = ["#" + line.partition("#")[2] for line in self.lines if "#" in line]
        self._line = 0  # index of the next line to look at
        self.lineno = 0
        self._skip = 0  # records a table read and the cursor has not moved past yet

    def _records_left(self, at_least: int) -> int:
        """How many records are left, counted up to ``at_least`` (a line is at most one)."""
        self._catch_up()
        left = len(self.lines) - self._line
        if left < at_least:
            return sum(1 for line in self.lines[self._line:] if line.partition("#")[0].strip())
        return left

    def check_count(self, count: int, what: str) -> None:
        """A declared count must not exceed the records left (no allocation for it otherwise)."""
        left = self._records_left(count)
        if count > left:
            raise self.error(f"declares {count} {what}, the file has only {left} more records")

    def position(self) -> tuple[int, int]:
        self._catch_up()
        return self._line, self.lineno

    def rewind(self, position: tuple[int, int]) -> None:
        self._line, self.lineno = position
        self._skip = 0

    def _catch_up(self) -> None:
        """Move past the records the last :meth:`table` read (only when something reads
        on: a table is mostly a file's last section, and this is a Python loop per line)."""
        seen, count, self._skip = 0, self._skip, 0
        if count == 0:
            return
        for i in range(self._line, len(self.lines)):
            if self.lines[i].partition("#")[0].strip():
                seen += 1
                if seen == count:
                    self._line = self.lineno = i + 1
                    return

    def table(self, count: int, width: int) -> np.ndarray | None:
        """The next ``count`` records' first ``width`` numbers, ``(count, width) float64``, or
        None (nothing consumed) if one is short, not a number or missing."""
        self._catch_up()
        if count == 0:
            return np.zeros((0, width))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # (loadtxt warns of an empty input)
                values = np.loadtxt(self.lines[self._line:], comments="#", max_rows=count,
                                    usecols=range(width), ndmin=2, dtype=np.float64)
        except (ValueError, IndexError, OverflowError):
            return None
        if values.shape != (count, width):
            return None
        self._skip = count  # (the cursor moves past them when something reads on)
        return values

    def error(self, message: str, lineno: int | None = None) -> FileFormatError:
        where = self.lineno if lineno is None else lineno
        return FileFormatError(f"{self.path}:{where}: {message}" if where else f"{self.path}: {message}")

    def row(self, what: str, min_tokens: int) -> list[str]:
        self._catch_up()
        tokens: list[str] = []
        while not tokens:
            if self._line >= len(self.lines):
                raise FileFormatError(f"{self.path}: unexpected end of file (expected {what})")
            tokens = self.lines[self._line].partition("#")[0].split()
            self._line += 1
        self.lineno = self._line
        if len(tokens) < min_tokens:
            raise self.error(f"expected {min_tokens} numbers ({what}), got {len(tokens)}")
        return tokens

    def as_int(self, token: str, what: str) -> int:
        try:
            return int(token)
        except ValueError:
            raise self.error(f"{what} is not an integer: {token!r}") from None

    def as_float(self, token: str, what: str) -> float:
        try:
            return float(token)
        except ValueError:
            raise self.error(f"{what} is not a number: {token!r}") from None

    def as_count(self, token: str, what: str) -> int:
        value = self.as_int(token, what)
        if value < 0:
            raise self.error(f"{what} is negative: {value}")
        return value


def _read_node(path: Path) -> tuple[np.ndarray, int, np.ndarray]:
    tok = _Tokens(path)
    head = tok.row("header '<# of vertices> <dimension> <# of attributes> <# of boundary markers>'", 2)
    n = tok.as_count(head[0], "number of vertices")
    dim = tok.as_int(head[1], "dimension")
    if dim != 2:
        raise tok.error(f"dimension is {dim}, only 2 is supported")
    n_attr = tok.as_count(head[2], "number of attributes") if len(head) > 2 else 0
    n_mark = tok.as_count(head[3], "number of boundary markers") if len(head) > 3 else 0
    if n == 0:
        raise tok.error("no vertices")
    tok.check_count(n, "vertices")
    start = tok.position()
    fast = _node_table(tok.table(n, 3 + n_attr + n_mark), n_attr, n_mark)
    if fast is not None:
        points, base, vmarks, values = fast
    else:  # row by row: the message names the line
        tok.rewind(start)
        points, base, vmarks, values = _node_rows(tok, n, n_attr, n_mark)
    names = _comment_names(tok, n_attr) or [f"{ATTRIBUTE_PREFIX}{j}" for j in range(n_attr)]
    return points, base, vmarks, join_components({name: values[:, j] for j, name in enumerate(names)})


def _integral(values: np.ndarray) -> bool:
    """Whether float64 ``values`` are integers read exactly (below 2**53)."""
    return bool(np.all(values == np.round(values)) and np.all(np.abs(values) < 2.0**53))


def _node_table(table: np.ndarray | None, n_attr: int,
                n_mark: int) -> tuple[np.ndarray, int, np.ndarray, np.ndarray] | None:
    """Points, base, markers and attributes of a ``.node`` table, or None if a row is wrong."""
    if table is None or not _integral(table[:, 0]) or (n_mark and not _integral(table[:, 3 + n_attr])):
        return None
    base = int(table[0, 0])
    points = np.ascontiguousarray(table[:, 1:3])
    if base not in (0, 1) or not np.array_equal(table[:, 0], base + np.arange(len(table))):
        return None
    if not np.isfinite(points).all():
        return None
    vmarks = table[:, 3 + n_attr].astype(np.int64) if n_mark else np.zeros(len(table), dtype=np.int64)
    return points, base, vmarks, np.ascontiguousarray(table[:, 3:3 + n_attr])


def _node_rows(tok: "_Tokens", n: int, n_attr: int, n_mark: int) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """:func:`_node_table` row by row, raising at the first wrong row."""
    points = np.empty((n, 2), dtype=np.float64)
    vmarks = np.zeros(n, dtype=np.int64)
    values = np.empty((n, n_attr), dtype=np.float64)
    base = 0
    for i in range(n):
        row = tok.row(f"vertex {i + 1} of {n}", 3 + n_attr + n_mark)
        number = tok.as_int(row[0], "vertex number")
        if i == 0:
            if number not in (0, 1):
                raise tok.error(f"first vertex number must be 0 or 1, got {number}")
            base = number
        elif number != base + i:
            raise tok.error(f"vertex number {number}, expected {base + i}")
        x, y = tok.as_float(row[1], "x"), tok.as_float(row[2], "y")
        if not (np.isfinite(x) and np.isfinite(y)):
            raise tok.error(f"vertex {number} is not finite")
        points[i] = x, y
        for j in range(n_attr):
            values[i, j] = tok.as_float(row[3 + j], f"attribute {j + 1}")
        if n_mark:
            vmarks[i] = tok.as_int(row[3 + n_attr], "boundary marker")
    return points, base, vmarks, values


def _comment_names(tok: "_Tokens", k: int) -> list[str] | None:
    """The names of the last ``# attributes:`` comment, if it names ``k`` columns."""
    names = None
    for comment in tok.comments:
        if comment.startswith(_ATTRIBUTES_COMMENT):
            names = [unquote(w) for w in comment[len(_ATTRIBUTES_COMMENT):].split()]  # (text_rows.header_token)
    return names if names is not None and len(names) == k else None


def _vertex(tok: _Tokens, token: str, base: int, n: int) -> int:
    value = tok.as_int(token, "vertex index")
    if not base <= value < base + n:
        raise tok.error(f"vertex index {value} out of range [{base}, {base + n})")
    return value - base


def _read_poly_segments(path: Path, base: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    tok = _Tokens(path)
    head = tok.row("header '<# of vertices> <dimension> <# of attributes> <# of boundary markers>'", 1)
    nv = tok.as_count(head[0], "number of vertices")
    n_attr = tok.as_count(head[2], "number of attributes") if len(head) > 2 else 0
    n_mark = tok.as_count(head[3], "number of boundary markers") if len(head) > 3 else 0
    tok.check_count(nv, "vertices")
    for i in range(nv):  # vertices listed in the .poly itself: Triangle keeps them first in .node
        tok.row(f"vertex {i + 1} of {nv}", 3 + n_attr + n_mark)
    head = tok.row("segment header '<# of segments> <# of boundary markers>'", 1)
    s = tok.as_count(head[0], "number of segments")
    tok.check_count(s, "segments")
    has_marker = len(head) > 1 and tok.as_int(head[1], "number of boundary markers") > 0
    segments = np.empty((s, 2), dtype=np.int64)
    markers = np.zeros(s, dtype=np.int64)
    for i in range(s):
        row = tok.row(f"segment {i + 1} of {s}", 3 + int(has_marker))
        segments[i] = _vertex(tok, row[1], base, n), _vertex(tok, row[2], base, n)
        if has_marker:
            marker = tok.as_int(row[3], "boundary marker")
            if not -(2**63) <= marker < 2**63:
                raise tok.error(f"boundary marker {marker} does not fit 64 bits")
            markers[i] = marker
    return segments, markers


def read_ele(path: str | os.PathLike[str]) -> Mesh:
    """Read ``<stem>.ele`` with its ``<stem>.node`` (and ``<stem>.poly`` if present).

    Parameters
    ----------
    path : path-like
        ``<stem>.ele`` or ``<stem>.node``.

    Returns
    -------
    Mesh
        Zero-based, triangles in file order.  Second-order elements (6 nodes) keep
        their 3 corners.

    Raises
    ------
    FileFormatError
        A file is missing, not text, truncated or malformed; an index is out of range.
        The message names the file and, where it applies, the line.
    """
    node_path, poly_path, ele_path = _siblings(path)
    require_file(ele_path)
    require_file(node_path, needed_by=ele_path.name)
    points, base, vmarks, point_data = _read_node(node_path)
    n = len(points)

    tok = _Tokens(ele_path)
    head = tok.row("header '<# of triangles> <nodes per triangle> <# of attributes>'", 1)
    m = tok.as_count(head[0], "number of triangles")
    per = tok.as_int(head[1], "nodes per triangle") if len(head) > 1 else 3
    if per not in (3, 6):
        raise tok.error(f"nodes per triangle is {per}, expected 3 or 6")
    k = tok.as_count(head[2], "number of attributes") if len(head) > 2 else 0
    if m == 0:
        raise tok.error("no triangles")
    tok.check_count(m, "triangles")
    if k > 1_000_000:
        raise tok.error(f"declares {k} attributes per triangle")
    start = tok.position()
    table = tok.table(m, 1 + per + k)
    corners = None if table is None else table[:, 1:4] - base
    if table is not None and _integral(table[:, :4]) and (corners >= 0).all() and (corners < n).all():
        triangles = corners.astype(np.int64)
        attrs = np.ascontiguousarray(table[:, 1 + per:])
    else:  # row by row: the message names the line
        tok.rewind(start)
        triangles = np.empty((m, 3), dtype=np.int64)
        attrs = np.empty((m, k), dtype=np.float64)
        for i in range(m):
            row = tok.row(f"triangle {i + 1} of {m}", 1 + per + k)
            tok.as_int(row[0], "triangle number")
            triangles[i] = [_vertex(tok, t, base, n) for t in row[1:4]]
            for j in range(k):
                attrs[i, j] = tok.as_float(row[1 + per + j], f"attribute {j + 1}")

    names = _comment_names(tok, k)
    attribute_names: tuple[str, ...] = ()
    info: dict = {}
    if names is not None:  # a Hamiltonian mesh's cycle fields are the output's, not attributes
        hamiltonian = "cycle_position" in names
        kept = [j for j, name in enumerate(names) if not (hamiltonian and name in _CYCLE_FIELDS)]
        if hamiltonian:  # (kept aside: `hammesh check` compares them with the rows)
            info["cycle_fields"] = {name: attrs[:, j].copy() for j, name in enumerate(names) if name in _CYCLE_FIELDS}
        attrs = attrs[:, kept]
        attribute_names = tuple(names[j] for j in kept)

    segments = np.zeros((0, 2), dtype=np.int64)
    markers = np.zeros(0, dtype=np.int64)
    if poly_path.is_file():
        segments, markers = _read_poly_segments(poly_path, base, n)

    return Mesh(
        points=points,
        triangles=triangles,
        segments=segments,
        segment_markers=markers,
        triangle_attributes=np.ascontiguousarray(attrs),
        vertex_markers=vmarks,
        attribute_names=attribute_names,
        point_data=point_data,
        info=info,
    )
