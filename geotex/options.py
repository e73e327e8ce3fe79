"""Validation of scalar options: the one place that turns a user's value into a number.

Every function takes the value and the name to show in the error (the Python
argument; the command line maps it to its flag), returns a plain ``float`` or
``int`` and raises :class:`~geotex.errors.InputError` with one line naming
both. Booleans are refused wherever a number is expected (``True`` is not a
size).
"""

from __future__ import annotations

import math
from numbers import Integral, Real

from geotex.errors import InputError

__all__ = ["finite_number", "positive_number", "count"]


def finite_number(value, *, name: str) -> float:
    """Return ``value`` as a finite float.

    Parameters
    ----------
    value : real number
    name : str
        Shown in the error.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a real number (booleans and strings included), NaN or infinite.
    """
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise InputError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def positive_number(value, *, name: str) -> float:
    """Return ``value`` as a finite float greater than zero.

    Raises
    ------
    InputError
        Not a real number, not finite, or not above zero.
    """
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) \
            or value <= 0:
        raise InputError(f"{name} must be a positive number, got {value!r}")
    return float(value)


def count(value, *, name: str, minimum: int = 1) -> int:
    """Return ``value`` as an int of at least ``minimum``.

    Raises
    ------
    InputError
        Not an integer (booleans and floats included) or below ``minimum``.
    """
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)
