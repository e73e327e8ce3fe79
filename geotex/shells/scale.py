"""A shell at another scale (for example at print size in millimetres)."""

from __future__ import annotations

import dataclasses

import numpy as np

from geotex.errors import InputError

__all__ = ["scaled_shell"]


def scaled_shell(shell, factor: float):
    """Return ``shell`` with every world length multiplied by ``factor``.

    The polycube's tile units, the map's topology and its distortion
    (dimensionless) are unchanged; the base, the fitted surface, the tile
    size, the origin and the safe height scale.

    Parameters
    ----------
    shell : Shell
    factor : float
        Positive, finite.

    Returns
    -------
    Shell

    Raises
    ------
    InputError
        ``factor`` not a positive finite number.
    """
    try:
        f = float(factor)
    except (TypeError, ValueError):
        raise InputError(f"scale factor must be a positive number, got {factor!r}") from None
    if not np.isfinite(f) or f <= 0:
        raise InputError(f"scale factor must be a positive number, got {factor!r}")
    pc = shell.polycube
    voxels = dict(pc.diagnostics.voxels)
    if "cell" in voxels:
        voxels["cell"] = voxels["cell"] * f
    search = dict(pc.diagnostics.tile_search)
    if "attempts" in search:
        search["attempts"] = [dict(a, tile_size=a["tile_size"] * f) if "tile_size" in a else a
                              for a in search["attempts"]]
    pc = dataclasses.replace(pc, tile_size=pc.tile_size * f, origin=pc.origin * f, Y=pc.Y * f,
                             diagnostics=dataclasses.replace(pc.diagnostics, voxels=voxels,
                                                             tile_search=search))
    return dataclasses.replace(shell, polycube=pc, max_height=shell.max_height * f,
                               base_vertices=shell.base_vertices * f)
