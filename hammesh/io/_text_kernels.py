"""numba kernels of the text mesh readers (OBJ, OFF): one pass over the file's bytes.

A million-face OBJ or OFF file is ~1.5 M lines; splitting them in Python cost 5-15 s
(and meshio's OFF reader 2 s).  These kernels find the lines, their fields and the
integers in them at memory speed; floats are left to numpy's C parser
(:func:`hammesh.io.text_records.parse_floats`), which rounds correctly.

* :func:`text_lines_into`: each non-blank line's range with comments and surrounding
  whitespace removed, and its number in the file;
* :func:`first_word_codes_into`: which of a few keywords each line starts with (OBJ's
  ``v f l g usemtl``) and where its fields begin;
* :func:`count_fields_into`: whitespace-separated fields per range;
* :func:`gather_ranges_into`: ranges copied into one buffer, a space after each;
* :func:`index_lists_into`: the vertex indices of OBJ ``f``/``l`` records (``i``,
  ``i/t``, ``i//n``, ``i/t/n``; negative = relative) and of OFF face lines.

numba is loaded lazily by the callers (importing it costs ~1 s).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["text_lines_into", "first_word_codes_into", "count_fields_into", "gather_ranges_into", "index_lists_into",
           "is_blank", "NOT_AN_INTEGER", "NO_SUCH_VERTEX"]

#: Error codes of :func:`index_lists_into` (the bad line's row is returned beside them).
NOT_AN_INTEGER = 1
NO_SUCH_VERTEX = 2


@njit(cache=True, nogil=True, inline="always")
def is_blank(c: np.uint8) -> bool:
    """Space, tab, CR, vertical tab or form feed (the newline ends a line before this)."""
    return c == 32 or c == 9 or c == 13 or c == 11 or c == 12


@njit(cache=True, nogil=True)
def text_lines_into(buf: np.ndarray, comment: np.uint8, starts: np.ndarray, ends: np.ndarray,
                    numbers: np.ndarray) -> int:
    """Fill ``starts``/``ends`` (byte ranges) and ``numbers`` (1-based line numbers) with
    the file's non-blank lines, each cut at its first ``comment`` byte and trimmed of
    whitespace; returns how many.  The arrays need room for every line (newlines + 1)."""
    n = len(buf)
    k = 0
    line = 0
    pos = 0
    while pos < n:
        line += 1
        a = pos
        while pos < n and buf[pos] != 10:
            pos += 1
        b = pos  # the newline (or the end)
        pos += 1
        end = a
        while end < b and buf[end] != comment:
            end += 1
        while a < end and is_blank(buf[a]):
            a += 1
        while end > a and is_blank(buf[end - 1]):
            end -= 1
        if end > a:
            starts[k] = a
            ends[k] = end
            numbers[k] = line
            k += 1
    return k


@njit(cache=True, nogil=True)
def first_word_codes_into(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, words: np.ndarray,
                          word_ends: np.ndarray, codes: np.ndarray, after: np.ndarray) -> None:
    """``codes[i]``: 1 + the number of the keyword (``words[word_ends[w-1]:word_ends[w]]``)
    that line ``i``'s first field equals, 0 if none; ``after[i]``: where the rest begins."""
    for i in range(len(starts)):
        a = starts[i]
        b = a
        while b < ends[i] and not is_blank(buf[b]):
            b += 1
        codes[i] = 0
        after[i] = b
        w0 = 0
        for w in range(len(word_ends)):
            w1 = word_ends[w]
            if w1 - w0 == b - a:
                same = True
                for j in range(b - a):
                    if buf[a + j] != words[w0 + j]:
                        same = False
                        break
                if same:
                    codes[i] = w + 1
                    break
            w0 = w1


@njit(cache=True, nogil=True)
def count_fields_into(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, counts: np.ndarray) -> None:
    """``counts[i]``: the whitespace-separated fields in ``buf[starts[i]:ends[i]]``."""
    for i in range(len(starts)):
        c = 0
        inside = False
        for p in range(starts[i], ends[i]):
            if is_blank(buf[p]):
                inside = False
            elif not inside:
                inside = True
                c += 1
        counts[i] = c


@njit(cache=True, nogil=True)
def gather_ranges_into(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, out: np.ndarray) -> int:
    """Copy every range into ``out``, a space after each; returns the bytes written."""
    q = 0
    for i in range(len(starts)):
        for p in range(starts[i], ends[i]):
            out[q] = buf[p]
            q += 1
        out[q] = 32
        q += 1
    return q


@njit(cache=True, nogil=True)
def index_lists_into(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, skip: int, take: np.ndarray,
                     defined: np.ndarray, flat: np.ndarray, sizes: np.ndarray) -> tuple[int, int]:
    """Parse the vertex indices of each range into ``flat`` (zero-based), one list per range.

    Each range's first ``skip`` fields are passed over; then ``take[i]`` fields are read
    (``-1``: all the rest).  A field is an integer optionally followed by ``/...``
    (OBJ's texture and normal indices, ignored).  ``defined[i] >= 0`` (OBJ, one-based): a
    positive index ``j`` is ``j - 1``, a negative one ``defined[i] + j`` (relative to the
    ``defined[i]`` vertices read so far); ``defined[i] < 0`` (OFF): zero-based, taken as
    is.  ``sizes[i]`` gets the count read; ``flat`` needs room for every field.

    Returns ``(0, -1)`` or ``(error code, row)``: :data:`NOT_AN_INTEGER`,
    :data:`NO_SUCH_VERTEX` (zero, or relative beyond the vertices read).
    """
    q = 0
    for i in range(len(starts)):
        p = starts[i]
        end = ends[i]
        field = 0
        got = 0
        want = take[i]
        one_based = defined[i] >= 0
        while p < end and (want < 0 or got < want):
            while p < end and is_blank(buf[p]):
                p += 1
            if p >= end:
                break
            if field < skip:
                while p < end and not is_blank(buf[p]):
                    p += 1
                field += 1
                continue
            sign = 1
            if buf[p] == 45:  # '-'
                sign = -1
                p += 1
            elif buf[p] == 43:  # '+'
                p += 1
            value = 0
            digits = 0
            while p < end and 48 <= buf[p] <= 57:
                value = value * 10 + (buf[p] - 48)
                digits += 1
                p += 1
                if digits > 18:
                    return NOT_AN_INTEGER, i
            if digits == 0 or (p < end and not is_blank(buf[p]) and buf[p] != 47):  # '/'
                return NOT_AN_INTEGER, i
            while p < end and not is_blank(buf[p]):  # '/t/n': not vertex indices
                p += 1
            value *= sign
            if one_based:
                if value > 0:
                    value -= 1
                elif value < 0 and -value <= defined[i]:
                    value += defined[i]
                else:
                    return NO_SUCH_VERTEX, i
            elif value < 0:
                return NO_SUCH_VERTEX, i
            flat[q] = value
            q += 1
            got += 1
            field += 1
        sizes[i] = got
    return 0, -1
