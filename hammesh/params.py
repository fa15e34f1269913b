"""One validator for option values of every public function (cf. shapely's ``ParamEnum``).

Each check returns the value converted to its plain Python type, or raises
:class:`~hammesh.errors.InvalidOptionError` with one message of one shape::

    timeout=inf is not valid: must be a finite number > 0 (seconds)
    mode='x' is not valid: must be one of 'incircle', 'sparse'

so a caller (or the command line, which passes its option names) always learns the
option, the value it gave and the values that are accepted.

Examples
--------
>>> choice("mode", "sparse", ("incircle", "sparse"))
'sparse'
>>> number("timeout", float("inf"), low=0, low_open=True, what="seconds")
Traceback (most recent call last):
...
hammesh.errors.InvalidOptionError: timeout=inf is not valid: must be a finite number > 0 (seconds)
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np

from hammesh.errors import InvalidOptionError

__all__ = ["MAX_SECONDS", "choice", "number", "integer", "flag", "instance", "invalid"]


#: Largest time limit accepted (about 24 days): waits take milliseconds as C ints.
MAX_SECONDS = 2_147_483.0


def invalid(name: str, value: Any, must: str) -> InvalidOptionError:
    """The error for ``name=value``; ``must`` says what is accepted."""
    shown = repr(value)
    if "\n" in shown or isinstance(value, type):
        shown = f"<{value.__name__ if isinstance(value, type) else type(value).__name__}>"
    if len(shown) > 80:
        shown = shown[:77] + "..."
    return InvalidOptionError(f"{name}={shown} is not valid: must be {must}", option=name)


def choice(name: str, value: Any, valid: Iterable[str]) -> str:
    """``value`` if it is one of ``valid`` (strings), else the error listing them."""
    options = tuple(valid)
    if isinstance(value, str) and value in options:
        return value
    raise invalid(name, value, "one of " + ", ".join(repr(v) for v in options))


def _bounds(low: float | None, high: float | None, low_open: bool, high_open: bool) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:.10g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:.10g}")
    return " and ".join(parts)


def number(
    name: str,
    value: Any,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    what: str = "",
) -> float:
    """``value`` as a finite float in the given range, else the error.

    Booleans, strings, complex numbers, NaN and infinities are refused.
    """
    must = " ".join(filter(None, ["a finite number", _bounds(low, high, low_open, high_open)]))
    if what:
        must += f" ({what})"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise invalid(name, value, must)
    try:
        x = float(value)
    except (OverflowError, ValueError, TypeError):
        raise invalid(name, value, must) from None
    if not math.isfinite(x):
        raise invalid(name, value, must)
    if low is not None and (x <= low if low_open else x < low):
        raise invalid(name, value, must)
    if high is not None and (x >= high if high_open else x > high):
        raise invalid(name, value, must)
    return x


def integer(
    name: str, value: Any, *, low: int | None = None, high: int | None = None, what: str = ""
) -> int:
    """``value`` as an int in ``[low, high]``, else the error (floats and booleans refused)."""
    must = " ".join(filter(None, ["an integer", _bounds(low, high, False, False)]))
    if what:
        must += f" ({what})"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise invalid(name, value, must)
    n = int(value)
    if (low is not None and n < low) or (high is not None and n > high):
        raise invalid(name, value, must)
    return n


def flag(name: str, value: Any) -> bool:
    """``value`` if it is a bool (or numpy bool), else the error."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise invalid(name, value, "True or False")


def instance(name: str, value: Any, types: type | tuple[type, ...], what: str) -> Any:
    """``value`` if it is an instance of ``types``, else the error (``what`` names them)."""
    if isinstance(value, types):
        return value
    raise invalid(name, value, what)
