"""The input checks of the whole package: one place, one convention.

Each check names the argument, what was expected and what came, so a mistake in a notebook cell
points at its cause instead of surfacing as a NaN three calls later. The convention, everywhere:
``TypeError`` for a value of the wrong type (a string where a number goes, ``1`` where a boolean
option goes, a float where a count goes), ``ValueError`` for a value of the right type that is
wrong (a negative count, an alpha of 1.5, an array of the wrong shape, NaN).
"""

from __future__ import annotations

import numbers

import numpy as np


class UnknownKeyError(KeyError):
    """A ``KeyError`` whose message reads as written: ``str(KeyError("x"))`` would quote it."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def is_real(value) -> bool:
    """Whether ``value`` is a real number: int, float, numpy floats and ints, ... but not a
    ``bool`` (``True`` is an int to Python, never a quantity to us) nor a string."""
    return isinstance(value, (numbers.Real, np.floating, np.integer)) and not isinstance(value, bool)


def _describe(value) -> str:
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    return f"{type(value).__name__} {value!r}"[:120]


def as_float_array(name: str, value, *, ndim=None, shape=None, finite: bool = True) -> np.ndarray:
    """Converts ``value`` to a float64 array and checks its dimensions, shape and finiteness.

    Args:
        name: the argument's name, used in the error message.
        value: anything ``np.asarray`` accepts.
        ndim: an int or a tuple of allowed numbers of dimensions.
        shape: the expected shape; ``None`` entries match any length. Compared against the
            trailing axes when the array has more dimensions than ``shape`` (a batch).
        finite: refuse NaN and infinity.

    Returns:
        The checked float64 array (a view when ``value`` already was one).
    """
    if value is None:   # np.asarray would make it a NaN
        raise TypeError(f"{name}: expected an array of numbers, got None")
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        try:
            kind = np.asarray(value).dtype.kind
        except (TypeError, ValueError):   # ragged nesting: numbers, but no array shape
            kind = "f"
        wrong = ValueError if kind in "biufc" else TypeError   # text or objects: a wrong type
        raise wrong(f"{name}: expected an array of numbers, got {_describe(value)}") from error
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if array.ndim not in allowed:
            wanted = " or ".join(str(n) for n in allowed)
            raise ValueError(f"{name}: expected {wanted} dimensions, got shape {array.shape}")
    if shape is not None:
        tail = array.shape[array.ndim - len(shape):] if array.ndim >= len(shape) else None
        if tail is None or any(want is not None and want != got for want, got in zip(shape, tail)):
            wanted = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
            raise ValueError(f"{name}: expected shape {wanted} (trailing axes), got {array.shape}")
    # A sum is one cheap pass; only when it is not finite (NaN, inf, or an overflow of huge
    # finite values) is the element-wise check needed.
    if finite and not np.isfinite(array.sum()) and not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: expected finite numbers, got NaN or infinity in an array of shape {array.shape}")
    return array


def as_finite(name: str, value) -> float:
    """Checks a finite real scalar (not a bool, NaN or infinity)."""
    if not is_real(value):
        raise TypeError(f"{name}: expected a real number, got {_describe(value)}")
    number = float(value)
    if not np.isfinite(number):
        raise ValueError(f"{name}: expected a finite number, got {number!r}")
    return number


def as_fraction(name: str, value) -> float:
    """Checks a number strictly between 0 and 1 (a significance level, a power, a confidence)."""
    if not is_real(value):
        raise TypeError(f"{name}: expected a number strictly between 0 and 1, got {_describe(value)}")
    if not 0 < float(value) < 1:
        raise ValueError(f"{name}: expected a number strictly between 0 and 1, got {_describe(value)}")
    return float(value)


def as_positive(name: str, value, *, allow_zero: bool = False) -> float:
    """Checks a real scalar that must be positive (or non-negative with ``allow_zero``)."""
    if not is_real(value):
        raise TypeError(f"{name}: expected a real number, got {_describe(value)}")
    number = float(value)
    if not np.isfinite(number) or number < 0 or (number == 0 and not allow_zero):
        wanted = "a non-negative" if allow_zero else "a positive"
        raise ValueError(f"{name}: expected {wanted} finite number, got {number!r}")
    return number


def as_count(name: str, value, *, minimum: int = 1) -> int:
    """Checks an integer count of at least ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral, np.integer)):
        raise TypeError(f"{name}: expected a whole number, got {_describe(value)}")
    if value < minimum:
        raise ValueError(f"{name}: expected a whole number >= {minimum}, got {value}")
    return int(value)


def as_bool(name: str, value, *, allow_none: bool = False) -> bool | None:
    """Checks a boolean option: only ``True`` or ``False`` (not 0, 1, None or a string).

    Args:
        name: the argument's name, used in the error message.
        value: the option.
        allow_none: also accept ``None`` (an option whose default is decided later).
    """
    if value is None and allow_none is True:
        return None
    if not isinstance(value, bool):
        wanted = "True, False or None" if allow_none is True else "True or False"
        raise TypeError(f"{name}: expected {wanted}, got {_describe(value)}")
    return value
