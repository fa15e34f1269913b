"""Lines, fields, floats and vertex indices of a text mesh file, vectorised.

The OBJ and OFF readers (:mod:`hammesh.io.obj_format`, :mod:`hammesh.io.off_format`)
are built on these: the numba kernels of :mod:`hammesh.io._text_kernels` find the
lines and parse the integers; floats go through numpy's C parser
(``numpy.fromstring(..., sep=" ")``: ``strtod``, correctly rounded), all fields of
the chosen lines in one call.  A file of 1 M faces is read in well under a second
(`benchmarks/bench_io.py`), where a Python loop over its lines took 5-15 s.
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

__all__ = ["Lines", "IndexLists", "BadRecord", "text_lines", "first_word_codes", "field_counts", "parse_floats", "index_lists",
           "as_bytes"]


class Lines(NamedTuple):
    """The non-blank lines of a text: byte ranges (comment and whitespace removed) and
    1-based line numbers, all ``int64``."""

    starts: np.ndarray
    ends: np.ndarray
    numbers: np.ndarray


class IndexLists(NamedTuple):
    """Vertex index lists, one per line: ``flat`` (zero-based) and ``sizes``."""

    flat: np.ndarray
    sizes: np.ndarray


class BadRecord(ValueError):
    """A line whose fields are not what the format says (``row``: its row in the :class:`Lines`)."""

    def __init__(self, row: int, what: str) -> None:
        super().__init__(what)
        self.row = row
        self.what = what


def as_bytes(data: bytes) -> np.ndarray:
    """The file's bytes as a read-only ``uint8`` array (no copy)."""
    return np.frombuffer(data, dtype=np.uint8)


def text_lines(buf: np.ndarray, comment: bytes = b"#") -> Lines:
    """The non-blank lines of ``buf``, each cut at ``comment`` and trimmed."""
    from hammesh.io._text_kernels import text_lines_into

    room = int(np.count_nonzero(buf == 10)) + 1
    starts = np.empty(room, np.int64)
    ends = np.empty(room, np.int64)
    numbers = np.empty(room, np.int64)
    k = text_lines_into(buf, np.uint8(comment[0]), starts, ends, numbers)
    return Lines(starts[:k], ends[:k], numbers[:k])


def first_word_codes(buf: np.ndarray, lines: Lines, words: tuple[bytes, ...]) -> tuple[np.ndarray, np.ndarray]:
    """For every line: ``1 + `` the index in ``words`` of its first field (0: none of
    them), and the position where its other fields begin."""
    from hammesh.io._text_kernels import first_word_codes_into

    table = np.frombuffer(b"".join(words), dtype=np.uint8)
    word_ends = np.cumsum([len(w) for w in words]).astype(np.int64)
    codes = np.empty(len(lines.starts), np.int64)
    after = np.empty(len(lines.starts), np.int64)
    first_word_codes_into(buf, lines.starts, lines.ends, table, word_ends, codes, after)
    return codes, after


def field_counts(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, at_least: int = 0,
                 what: str = "") -> np.ndarray:
    """Whitespace-separated fields in each range, ``int64``.

    Raises
    ------
    BadRecord
        A range has fewer than ``at_least`` fields (``what`` says what it needs).
    """
    from hammesh.io._text_kernels import count_fields_into

    counts = np.empty(len(starts), np.int64)
    count_fields_into(buf, np.ascontiguousarray(starts), np.ascontiguousarray(ends), counts)
    short = np.flatnonzero(counts < at_least)
    if len(short):
        raise BadRecord(int(short[0]), what)
    return counts


def parse_floats(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Every field of the ranges as ``float64``, in order (``counts``: fields per range).

    Raises
    ------
    BadRecord
        A field is not a number (the row of the first such range).
    """
    from hammesh.io._text_kernels import gather_ranges_into

    starts = np.ascontiguousarray(starts)
    ends = np.ascontiguousarray(ends)
    out = np.empty(int((ends - starts).sum()) + len(starts), np.uint8)
    q = gather_ranges_into(buf, starts, ends, out)
    total = int(counts.sum())
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns (then stops) at the first non-number
        try:
            values = np.fromstring(out[:q].tobytes(), dtype=np.float64, sep=" ")
        except (ValueError, DeprecationWarning):
            values = None
    if values is None or len(values) != total:
        row = _first_bad_row(buf, starts, ends)
        raise BadRecord(row, "a field is not a number")
    return values


def _first_bad_row(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> int:
    """The first range with a field ``float()`` refuses (the error path only)."""
    for i in range(len(starts)):
        for field in buf[starts[i]:ends[i]].tobytes().split():
            try:
                float(field)
            except ValueError:
                return i
    return len(starts) - 1


def index_lists(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, counts: np.ndarray, *,
                skip: int = 0, take: np.ndarray | None = None, defined: np.ndarray | None = None) -> IndexLists:
    """The vertex indices of each range (:func:`hammesh.io._text_kernels.index_lists_into`).

    ``counts``: fields per range (room); ``skip``: fields passed over first; ``take``:
    how many to read per range (default all); ``defined``: OBJ's vertices read before
    each range (one-based, negative = relative), default zero-based indices (OFF).

    Raises
    ------
    BadRecord
        A field is not an integer, or refers to no vertex.
    """
    from hammesh.io._text_kernels import NOT_AN_INTEGER, index_lists_into

    n = len(starts)
    take = np.full(n, -1, np.int64) if take is None else np.ascontiguousarray(take, dtype=np.int64)
    defined = np.full(n, -1, np.int64) if defined is None else np.ascontiguousarray(defined, dtype=np.int64)
    flat = np.empty(int(np.maximum(counts - skip, 0).sum()), np.int64)
    sizes = np.empty(n, np.int64)
    code, row = index_lists_into(buf, np.ascontiguousarray(starts), np.ascontiguousarray(ends), skip, take,
                                 defined, flat, sizes)
    if code:
        raise BadRecord(int(row), _bad_index(buf[starts[row]:ends[row]].tobytes().split()[skip:],
                                             int(defined[row]), code == NOT_AN_INTEGER))
    return IndexLists(flat[: int(sizes.sum())], sizes)


def _bad_index(fields: list[bytes], defined: int, not_integer: bool) -> str:
    """The message for the first bad index field of a line (the error path only)."""
    for field in fields:
        head = field.split(b"/", 1)[0].decode(errors="replace")
        try:
            i = int(head)
        except ValueError:
            if not_integer:
                return f"vertex index is not an integer: {head!r}"
            continue
        if defined < 0 and i < 0:
            return f"vertex index {i} refers to no vertex"
        if defined >= 0 and (i == 0 or -i > defined):
            return f"vertex index {i} refers to no vertex ({defined} defined so far)"
    return "a vertex index is not an integer" if not_integer else "a vertex index refers to no vertex"
