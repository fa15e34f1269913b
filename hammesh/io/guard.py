"""One boundary between a reader's Python errors and the file that caused them.

A reader fed a hostile file (a count of 10^20, a number that overflows int64, JSON
nested 100,000 deep) can fail deep inside numpy or the standard library with a
``ValueError``, ``OverflowError``, ``MemoryError`` or ``RecursionError``.  Those are the
file's fault, so :func:`reading` turns them into a
:class:`~hammesh.errors.FileFormatError` naming the file; hammesh's own errors pass
through unchanged.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

from hammesh.errors import FileFormatError, HammeshError

__all__ = ["reading"]

_FILE_FAULTS = (ValueError, TypeError, OverflowError, IndexError, KeyError, MemoryError, RecursionError,
                UnicodeError, EOFError)


@contextlib.contextmanager
def reading(path: str | os.PathLike[str]) -> Iterator[None]:
    """Run a reader on ``path``; its low-level errors become one :class:`FileFormatError`.

    Examples
    --------
    >>> with reading("x.poly"):
    ...     int("99x")
    Traceback (most recent call last):
    ...
    hammesh.errors.FileFormatError: x.poly: malformed file (ValueError: invalid literal for int() with base 10: '99x')
    """
    try:
        yield
    except HammeshError:
        raise
    except MemoryError:
        raise FileFormatError(f"{path}: sizes beyond this machine's memory (corrupt counts?)") from None
    except RecursionError:
        raise FileFormatError(f"{path}: nested too deeply") from None
    except _FILE_FAULTS as exc:
        text = str(exc).strip()
        detail = text.splitlines()[0] if text else ""
        raise FileFormatError(f"{path}: malformed file ({type(exc).__name__}: {detail})") from None
