"""Edge colours and tile keys of geometric Wang tile sets.

A tile is the unit square ``[0, 1]^2`` of texture space (``u`` along the tile's
first axis, ``v`` along its second, ``w`` the height). Its sides are numbered

    0 = south (v = 0), 1 = east (u = 1), 2 = north (v = 1), 3 = west (u = 0),

and every side runs in the +u (south, north) or +v (west, east) direction.

On a polycube every quad edge is parallel to one axis, its *class* (0 = X,
1 = Y, 2 = Z); each class has its own colours. A tile *group* ``(a, b)`` holds
the tiles whose south/north sides are of class ``a`` and whose west/east sides
are of class ``b``. A quad on a chart with outward normal ``+Z`` has its first
axis along +X and its second along +Y, so it takes a tile of group (0, 1); a
``-Z`` quad has first axis +Y and second +X (right-handed with its normal), so
group (1, 0); and likewise for the other four chart directions (see
:data:`CHART_FRAMES`). A planar set is group (0, 1) alone: ``n_x^2 n_y^2``
tiles. A complete set holds all six groups:
``2 (n_x^2 n_y^2 + n_x^2 n_z^2 + n_y^2 n_z^2)`` tiles. An isotropic set uses
one colour class for every axis: its ``n^4`` tiles of group (0, 1) serve
every quad of a polycube, the group ignored.
"""

from __future__ import annotations

import itertools

import numpy as np

from geotex.errors import InputError

__all__ = ["SOUTH", "EAST", "NORTH", "WEST", "PLANAR_GROUPS", "COMPLETE_GROUPS",
           "CHART_FRAMES", "side_classes", "tile_keys", "parse_colors", "tile_count"]

SOUTH, EAST, NORTH, WEST = 0, 1, 2, 3
AXIS_NAMES = "XYZ"
PLANAR_GROUPS = ((0, 1),)
COMPLETE_GROUPS = ((0, 1), (1, 0), (0, 2), (2, 0), (1, 2), (2, 1))

#: chart outward normal (axis, sign) -> (first axis, second axis) of its quads; both
#: run along the positive coordinate direction and first x second = the normal.
CHART_FRAMES = {
    (2, +1): (0, 1), (2, -1): (1, 0),
    (0, +1): (1, 2), (0, -1): (2, 1),
    (1, +1): (2, 0), (1, -1): (0, 2),
}


def side_classes(group: tuple[int, int]) -> np.ndarray:
    """Return the axis class of sides south, east, north, west of a tile group.

    Returns
    -------
    numpy.ndarray, (4,) int64
    """
    a, b = group
    return np.array([a, b, a, b], dtype=np.int64)


def tile_keys(n_colors: tuple[int, int, int], groups) -> tuple[np.ndarray, np.ndarray]:
    """Enumerate every tile of a set.

    Parameters
    ----------
    n_colors : tuple of 3 int
        Colours of the X, Y and Z classes.
    groups : sequence of (int, int)
        Tile groups, e.g. :data:`PLANAR_GROUPS` or :data:`COMPLETE_GROUPS`.

    Returns
    -------
    group_of : numpy.ndarray, (T, 2) int64
        The group of every tile.
    colors : numpy.ndarray, (T, 4) int64
        Colours of sides south, east, north, west.
    """
    rows_g, rows_c = [], []
    for a, b in groups:
        na, nb = n_colors[a], n_colors[b]
        for s, e, n, w in itertools.product(range(na), range(nb), range(na), range(nb)):
            rows_g.append((a, b))
            rows_c.append((s, e, n, w))
    return (np.array(rows_g, dtype=np.int64).reshape(-1, 2),
            np.array(rows_c, dtype=np.int64).reshape(-1, 4))


def tile_count(n_colors: tuple[int, int, int], *, planar: bool,
               isotropic: bool = False) -> int:
    """Number of tiles of a planar, complete or isotropic set.

    ``n_x^2 n_y^2`` (planar), ``2 (n_x^2 n_y^2 + n_x^2 n_z^2 + n_y^2 n_z^2)``
    (complete) or ``n^4`` (isotropic, ``n = n_x``).
    """
    nx, ny, nz = n_colors
    if isotropic:
        return nx ** 4
    if planar:
        return nx * nx * ny * ny
    return 2 * (nx * nx * ny * ny + nx * nx * nz * nz + ny * ny * nz * nz)


def parse_colors(spec, *, planar: bool) -> tuple[int, int, int]:
    """Colours per class from ``N``, ``"N"``, ``"NX,NY,NZ"`` or a 3-sequence.

    Raises
    ------
    InputError
        Not one or three positive integers (at most 4 each).
    """
    if isinstance(spec, str):
        parts = [p.strip() for p in spec.split(",")]
        try:
            values = [int(p) for p in parts]
        except ValueError:
            raise InputError(f"colors: {spec!r} is not N or NX,NY,NZ") from None
    elif np.isscalar(spec):
        values = [int(spec)]
    else:
        values = [int(v) for v in spec]
    if len(values) == 1:
        values = values * 3
    # a planar set has no Z colours: its recorded (n_x, n_y, 0) is accepted back
    checked = values[:2] if planar and len(values) == 3 and values[2] == 0 else values
    if len(values) != 3 or any(v < 1 or v > 4 for v in checked):
        raise InputError(f"colors: expected 1 to 4 colours per axis class, got {spec!r}")
    if planar:
        values[2] = 0
    return tuple(values)
