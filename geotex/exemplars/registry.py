"""The registry of exemplar kinds and :func:`exemplar`, the one entry point."""

from __future__ import annotations

import math

import numpy as np

from geotex.errors import InputError
from geotex.exemplars import bark, chainmail, knurl, scales, studs, weave
from geotex.exemplars.params import resolve_params
from geotex.exemplars.record import Exemplar

__all__ = ["EXEMPLAR_KINDS", "exemplar", "describe", "kind_parameters"]

_KINDS = {"studs": studs, "scales": scales, "knurl": knurl, "weave": weave,
          "chainmail": chainmail, "bark": bark}

#: Names of the procedural exemplar kinds, in gallery order.
EXEMPLAR_KINDS = tuple(_KINDS)


def _module(name):
    if not isinstance(name, str) or name not in _KINDS:
        raise InputError(f"unknown exemplar {name!r}; valid names: {', '.join(EXEMPLAR_KINDS)}")
    return _KINDS[name]


def describe(name: str) -> str:
    """Return a one-line description of an exemplar kind.

    Raises
    ------
    InputError
        If ``name`` is not one of :data:`EXEMPLAR_KINDS`.
    """
    return _module(name).DESCRIPTION


def kind_parameters(name: str) -> tuple:
    """Return the :class:`~geotex.exemplars.params.Param` specs of a kind (size and seed aside)."""
    return _module(name).PARAMS


def _size(size, name) -> tuple[float, float]:
    try:
        lx, ly = (float(s) for s in size)
    except (TypeError, ValueError):
        raise InputError(f"exemplar {name!r}: size must be two positive numbers (lx, ly), "
                         f"got {size!r}") from None
    if not (math.isfinite(lx) and math.isfinite(ly) and 0 < lx <= 1e3 and 0 < ly <= 1e3):
        raise InputError(f"exemplar {name!r}: size must be two positive numbers up to 1000, "
                         f"got {size!r}")
    return lx, ly


def _seed(seed, name) -> int:
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) \
            or seed < 0:
        raise InputError(f"exemplar {name!r}: seed must be a non-negative integer, "
                         f"got {seed!r}")
    return int(seed)


def exemplar(name: str, *, size=(4.0, 4.0), seed: int = 0, **params) -> Exemplar:
    """Build a procedural exemplar geometric texture.

    Parameters
    ----------
    name : str
        One of :data:`EXEMPLAR_KINDS`: ``studs``, ``scales``, ``knurl``,
        ``weave``, ``chainmail``, ``bark``.
    size : tuple of float, optional
        Patch extent ``(lx, ly)``; one Wang tile is 1 x 1.
    seed : int, optional
        Seed of the random jitter: the same seed gives byte-identical arrays.
    **params
        Kind parameters (``pitch``, ``height``, ``depth``, ``jitter``,
        ``resolution``, ...); see :func:`kind_parameters` or
        ``geotex exemplar --list``.  Missing ones take their defaults.

    Returns
    -------
    Exemplar
        ``params`` holds size, seed and every kind parameter, so
        ``exemplar(ex.name, **ex.params)`` rebuilds it; ``period`` is the
        lattice of the layout for kinds whose pattern repeats in two
        different steps (chain mail, scales), else None (the pitch serves).

    Raises
    ------
    InputError
        On an unknown name or parameter (the message lists the valid ones), a
        value out of range, or a patch too small for one element.

    Examples
    --------
    >>> from geotex.exemplars import exemplar
    >>> ex = exemplar("studs", size=(2, 2), seed=1)
    >>> ex.n_elements
    16
    """
    module = _module(name)
    lx, ly = _size(size, name)
    seed = _seed(seed, name)
    resolved = resolve_params(name, module.PARAMS, params)
    rng = np.random.default_rng(seed)
    V, F = module.build((lx, ly), rng, resolved)
    if F.shape[0] == 0:
        raise InputError(f"exemplar {name!r}: no element fits a {lx:g} x {ly:g} patch with "
                         "these parameters; use a larger size or a smaller pitch")
    recipe = {"size": [lx, ly], "seed": seed, **resolved}
    period = module.period((lx, ly), resolved) if hasattr(module, "period") else None
    return Exemplar(V, F, size=(lx, ly), height=float(V[:, 2].max()),
                    depth=float(-V[:, 2].min()), name=name, params=recipe, period=period)
