"""Parameter specifications of the exemplar kinds and their validation."""

from __future__ import annotations

import math
from dataclasses import dataclass

from geotex.errors import InputError

__all__ = ["Param", "resolve_params", "parse_value"]


@dataclass(frozen=True)
class Param:
    """One recipe parameter of an exemplar kind.

    Attributes
    ----------
    name : str
    default : float, int or str
    help : str
        One line for listings.
    lo, hi : float, optional
        Inclusive bounds for numbers.
    choices : tuple of str, optional
        Allowed values of a text parameter.
    integer : bool
        The value must be an integer.
    """

    name: str
    default: object
    help: str
    lo: float | None = None
    hi: float | None = None
    choices: tuple | None = None
    integer: bool = False

    def describe(self) -> str:
        """Return ``name=default`` with the allowed range."""
        if self.choices:
            return f"{self.name}={self.default} ({'|'.join(self.choices)})"
        lo = "" if self.lo is None else f"{self.lo:g}"
        hi = "" if self.hi is None else f"{self.hi:g}"
        return f"{self.name}={self.default} [{lo}..{hi}]"

    def check(self, value, kind: str):
        """Return ``value`` converted to the parameter's type.

        Raises
        ------
        InputError
            If the value has the wrong type or lies outside the bounds.
        """
        where = f"exemplar {kind!r}: parameter {self.name}"
        if self.choices:
            if not isinstance(value, str) or value not in self.choices:
                raise InputError(f"{where} must be one of {', '.join(self.choices)}, "
                                 f"got {value!r}")
            return value
        if isinstance(value, (bool, str, bytes)):
            raise InputError(f"{where} must be a number, got {value!r}")
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise InputError(f"{where} must be a number, got {value!r}") from None
        if not math.isfinite(v):
            raise InputError(f"{where} must be finite, got {value!r}")
        if self.integer:
            if v != round(v):
                raise InputError(f"{where} must be an integer, got {value!r}")
            v = int(round(v))
        if (self.lo is not None and v < self.lo) or (self.hi is not None and v > self.hi):
            raise InputError(f"{where} must lie in [{self.lo:g}, {self.hi:g}], got {value!r}")
        return v


def parse_value(param: Param, text: str):
    """Convert command-line text to a value for ``param`` (checked later)."""
    if param.choices:
        return text
    try:
        return int(text) if param.integer else float(text)
    except ValueError:
        kind = "an integer" if param.integer else "a number"
        raise InputError(f"parameter {param.name} must be {kind}, got {text!r}") from None


def resolve_params(kind: str, specs: tuple, given: dict) -> dict:
    """Fill in defaults and validate ``given`` against ``specs``.

    Returns
    -------
    dict
        Every parameter of the kind, in spec order, with checked values.

    Raises
    ------
    InputError
        On an unknown parameter (the message lists the valid ones) or a bad value.
    """
    names = [p.name for p in specs]
    unknown = [k for k in given if k not in names]
    if unknown:
        raise InputError(f"exemplar {kind!r} has no parameter {unknown[0]!r}; valid "
                         f"parameters: size, seed, {', '.join(names)}")
    return {p.name: p.check(given.get(p.name, p.default), kind) for p in specs}
