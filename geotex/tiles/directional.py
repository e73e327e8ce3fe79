"""Directional tile sets: one planar set turned to follow a flow over a closed polycube.

An isotropic set (studs, knurl) may put any tile on any quad; a *directional*
texture (scales: every scale has a root and a lifted tail) must keep its
direction. This goes beyond the paper, whose results are isotropic only (it
names anisotropic textures as future work, last section of
``../shared/papers/wang-tile-geometric-texture.md``).

The flow. Every quad of a polycube lies on a chart with outward normal along one
world axis. With ``up`` the world "up" axis (default Z), the flow on a side
chart (normal not along ``up``) runs toward ``-up`` (scales hang down, like roof
tiles or fish scales with gravity), and on the top and bottom charts (normal
along ``up``) toward ``+T`` with ``T = (up + 2) % 3`` (Y for up = Z).

The base set. The directional set is built once as a planar set whose elements
point ``+v`` (:func:`geotex.tiles.build.build_tileset` with ``directional``):
``n`` colours of *across* strips (south/north sides, cut along the exemplar's
x) and ``n`` of *along* strips (west/east sides, along the exemplar's y), plus
one more colour per class, ``n`` itself, the *ridge*: an empty strip, so that no
element crosses a side of that colour.

Turning. A quad of frame ``(a, b)`` (first tile axis ``u`` = world axis ``a``,
second ``v`` = ``b``, see :mod:`geotex.tiles.colors`) takes a base tile turned by
``r`` quarter turns counter-clockwise so that ``+v`` goes to the flow: ``r = 0,
1, 2, 3`` for a flow along ``+v, -u, -v, +u``. The strip a side carries is read
in that side's own strip coordinates ``(t, s)`` (``t`` along the positive world
axis of the edge, ``s = n x t``, the same on both quads of the edge, fold or
not; :func:`geotex.tiles.frame.placed_half`), and its *kind* is the flow in
those coordinates: ``+t, +s, -t, -s`` (codes 0, 1, 2, 3). Two quads may share
an edge's strip only when they give it the same kind; where they do not (on a
box with up = Z: the top rim edges along Y, and the X rim edge upstream of the
top flow, and likewise on the bottom), the edge takes the ridge colour, whose
sides are empty on every tile: no element crosses that edge, like the ridge
or hip line of a roof. Elsewhere, including every fold between two side charts,
the scales run on across the edge.

The turned copies are made in memory (:func:`oriented_tileset`): six groups of
the base tiles, each turned by its group's ``r``, positions turned by exact
formulas (``u' = 1 - v`` etc.), so sides of one kind and colour stay
bit-identical. Files hold the base set only.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.tiles.colors import COMPLETE_GROUPS, EAST, NORTH, SOUTH, WEST
from geotex.tiles.tileset import TileSet

__all__ = ["KIND_NAMES", "flow_of_group", "group_turn", "side_kinds", "turned",
           "oriented_tileset", "ridge_edges", "is_directional"]

#: kind codes of a side: the flow in the side's strip coordinates (t, s)
KIND_NAMES = ("+t", "+s", "-t", "-s")
#: flow in tile coordinates (+v, -u, -v, +u) for r = 0..3 quarter turns
_TURN_OF_FLOW = {(1, +1): 0, (0, -1): 1, (1, -1): 2, (0, +1): 3}


def is_directional(tiles) -> bool:
    """True for a directional set, base or oriented (``metadata["directional"]``)."""
    return bool(tiles.metadata.get("directional"))


def _check_up(up) -> int:
    if isinstance(up, bool) or up not in (0, 1, 2):
        raise InputError(f"up: expected the world axis 0 (X), 1 (Y) or 2 (Z), got {up!r}")
    return int(up)


def flow_of_group(group, *, up: int = 2) -> tuple[int, int]:
    """World flow ``(axis, sign)`` on the quads of tile group ``group``.

    Parameters
    ----------
    group : tuple of 2 int
        Quad frame ``(a, b)``; its chart normal is the third axis.
    up : int
        World up axis.

    Returns
    -------
    tuple (int, int)
        ``(-up)`` on side charts, ``(+T)``, ``T = (up + 2) % 3``, on top and bottom.
    """
    up = _check_up(up)
    a, b = int(group[0]), int(group[1])
    normal = 3 - a - b
    return (up, -1) if normal != up else ((up + 2) % 3, +1)


def group_turn(group, *, up: int = 2) -> int:
    """Quarter turns (counter-clockwise) of the base tiles on quads of ``group``."""
    axis, sign = flow_of_group(group, up=up)
    return _TURN_OF_FLOW[(0 if axis == int(group[0]) else 1, sign)]


def side_kinds(groups: np.ndarray, *, up: int = 2) -> np.ndarray:
    """Kind code of every side of quads (or tiles) of the given groups.

    Parameters
    ----------
    groups : numpy.ndarray, (q, 2) int64
        Frame ``(a, b)`` of each quad.
    up : int

    Returns
    -------
    numpy.ndarray, (q, 4) int64
        Codes (:data:`KIND_NAMES`) of sides south, east, north, west.
    """
    groups = np.asarray(groups, dtype=np.int64).reshape(-1, 2)
    table = {}
    for g in COMPLETE_GROUPS:
        r = group_turn(g, up=up)
        # flow in tile coordinates as (du, dv)
        d = ((0, 1), (-1, 0), (0, -1), (1, 0))[r]
        kinds = []
        for side in (SOUTH, EAST, NORTH, WEST):
            # strip frame of the side: S/N (t, s) = (u, v); W/E (t, s) = (v, -u)
            t, s = (d[0], d[1]) if side in (SOUTH, NORTH) else (d[1], -d[0])
            kinds.append({(1, 0): 0, (0, 1): 1, (-1, 0): 2, (0, -1): 3}[(t, s)])
        table[g] = kinds
    out = np.empty((len(groups), 4), dtype=np.int64)
    for g, kinds in table.items():
        out[(groups == g).all(axis=1)] = kinds
    return out


def turned(V: np.ndarray, r: int) -> np.ndarray:
    """Tile positions turned by ``r`` quarter turns counter-clockwise about the tile centre.

    Exact formulas (``(u, v) -> (1 - v, u)`` for one turn, ...), so that a
    position on a side lands exactly on the turned side.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    r : int

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        A new array.
    """
    V = np.asarray(V, dtype=np.float64)
    u, v = V[:, 0], V[:, 1]
    out = V.copy()
    r = int(r) % 4
    if r == 1:
        out[:, 0], out[:, 1] = 1.0 - v, u
    elif r == 2:
        out[:, 0], out[:, 1] = 1.0 - u, 1.0 - v
    elif r == 3:
        out[:, 0], out[:, 1] = v, 1.0 - u
    return out


def oriented_tileset(tiles: TileSet, *, up: int | None = None) -> TileSet:
    """The six-group set of a directional base set, each group's tiles turned to its flow.

    Parameters
    ----------
    tiles : TileSet
        A directional base set (group (0, 1) only, side colours ``0..n`` with
        ``n`` the ridge). An already oriented set is returned unchanged when
        ``up`` is None or its own.
    up : int, optional
        World up axis (default: the set's ``metadata["directional"]["up"]``, 2).

    Returns
    -------
    TileSet
        ``6 B`` tiles for ``B`` base tiles, groups in
        :data:`~geotex.tiles.colors.COMPLETE_GROUPS` order; side colours
        turned with the tiles; ``n_colors`` ``(n, n, n)``;
        ``metadata["directional"]`` gains ``"oriented": True`` and ``up``.

    Raises
    ------
    InputError
        Not a directional set, or ``up`` not 0, 1 or 2.
    """
    info = tiles.metadata.get("directional")
    if not info:
        raise InputError(f"tile set {tiles.name!r} is not directional")
    up = _check_up(info.get("up", 2) if up is None else up)
    if info.get("oriented"):
        if up == info.get("up", 2):
            return tiles
        raise InputError("oriented_tileset: turn the base set, not an oriented one, to "
                         "another up axis")
    n = int(info["ridge"])
    parts, groups, colors = [], [], []
    base = [tiles.tile(i) for i in range(len(tiles))]
    for g in COMPLETE_GROUPS:
        r = group_turn(g, up=up)
        for i, (V, F) in enumerate(base):
            parts.append((turned(V, r), F))
            groups.append(g)
            # turned side k holds base side (k - r) mod 4
            colors.append(np.roll(tiles.colors[i], r))
    meta = dict(tiles.metadata)
    meta["directional"] = dict(info, oriented=True, up=up)
    return TileSet.from_tiles(parts, groups, colors, n_colors=(n, n, n),
                              height=tiles.height, depth=tiles.depth, name=tiles.name,
                              metadata=meta)


def ridge_edges(quad_axes: np.ndarray, quad_edge: np.ndarray, n_edges: int, *,
                up: int = 2, bare=None) -> np.ndarray:
    """Edges whose quads give their strip different kinds: they take the ridge colour.

    Parameters
    ----------
    quad_axes : numpy.ndarray, (q, 2) int64
        Frame of each quad.
    quad_edge : numpy.ndarray, (q, 4) int64
        Global edge of sides south, east, north, west.
    n_edges : int
    up : int
    bare : numpy.ndarray, (q,) bool, optional
        Quads without a tile; they do not constrain their edges.

    Returns
    -------
    numpy.ndarray, (n_edges,) bool
    """
    kinds = side_kinds(quad_axes, up=up)
    use = np.ones(len(kinds), dtype=bool) if bare is None else ~np.asarray(bare, dtype=bool)
    e = np.asarray(quad_edge, dtype=np.int64)[use].ravel()
    k = kinds[use].ravel()
    lo = np.full(n_edges, 4, dtype=np.int64)
    hi = np.full(n_edges, -1, dtype=np.int64)
    np.minimum.at(lo, e, k)
    np.maximum.at(hi, e, k)
    return (hi >= 0) & (lo != hi)
