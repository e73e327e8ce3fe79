"""Which tile goes on which polycube quad.

Every global quad edge gets a random colour from its axis class; a quad with
frame ``(a1, a2)`` takes the tile of group ``(a1, a2)`` whose side colours are
the colours of its south, east, north and west edges (an isotropic set has one
colour class for all axes and ignores the group). Neighbouring quads read the
same colour on their shared edge, so their tiles are seam-compatible.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.tiles.directional import quad_turns, ridge_edges, tile_turns
from geotex.tiles.tileset import TileSet

__all__ = ["edge_colors", "tiles_for_quads"]


def edge_colors(edge_axis: np.ndarray, n_colors, *, seed: int = 0) -> np.ndarray:
    """Random colour of every global edge within its axis class.

    Parameters
    ----------
    edge_axis : numpy.ndarray, (E,) int64
        Axis class of each edge (0 X, 1 Y, 2 Z).
    n_colors : tuple of 3 int
        Colours per class.
    seed : int

    Returns
    -------
    numpy.ndarray, (E,) int64
    """
    rng = np.random.default_rng(seed)
    n = np.asarray(n_colors, dtype=np.int64)[edge_axis]
    if np.any(n < 1):
        missing = sorted({"XYZ"[a] for a in np.unique(edge_axis[n < 1])})
        raise InputError(f"the tile set has no colours for {', '.join(missing)} edges; a "
                         "complete (non-planar) set is needed on a closed shape")
    return np.floor(rng.random(len(edge_axis)) * n).astype(np.int64)


def tiles_for_quads(tiles: TileSet, quad_axes: np.ndarray, quad_edge: np.ndarray,
                    colors: np.ndarray, *, bare=None) -> np.ndarray:
    """The tile of every quad.

    Parameters
    ----------
    tiles : TileSet
        A complete set (one group per quad frame), an isotropic set
        (``tiles.isotropic``: one colour class shared by all axes, so the
        group is ignored), or an oriented directional set
        (:func:`geotex.tiles.directional.oriented_tileset`: each quad's turn is
        chosen by :func:`geotex.tiles.directional.quad_turns`, and edges where
        the flow does not run on across take its ridge colour instead of theirs).
    quad_axes : numpy.ndarray, (q, 2) int64
        In-plane axes ``(a1, a2)`` of each quad's frame (its tile group).
    quad_edge : numpy.ndarray, (q, 4) int64
        Global edge of sides south, east, north, west.
    colors : numpy.ndarray, (E,) int64
        Colour of every global edge.
    bare : numpy.ndarray, (q,) bool, optional
        Quads that get no tile (``-1``).

    Returns
    -------
    numpy.ndarray, (q,) int64

    Raises
    ------
    InputError
        The set lacks a needed tile (e.g. a planar set on a closed shape).
    """
    info = tiles.metadata.get("directional") or {}
    if info:
        if not info.get("oriented"):
            raise InputError(f"tile set {tiles.name!r} is a directional base set; turn it to "
                             "the flow first (geotex.tiles.directional.oriented_tileset)")
        up = info.get("up", 2)
        turns = quad_turns(quad_axes, quad_edge, len(colors), up=up, bare=bare)
        ridge = ridge_edges(quad_axes, quad_edge, len(colors), up=up, bare=bare, turns=turns)
        colors = np.where(ridge, int(info["ridge"]), colors)
    side = colors[quad_edge]                                    # (q, 4)
    if getattr(tiles, "isotropic", False):
        keys, table = side, tiles.colors
    elif info:
        # the turn is part of the key: (group, turn, colours)
        keys = np.hstack([quad_axes, turns[:, None], side])
        table = np.hstack([tiles.groups, tile_turns(tiles)[:, None], tiles.colors])
    else:
        keys = np.hstack([quad_axes, side])
        table = np.hstack([tiles.groups, tiles.colors])
    weights = 5 ** np.arange(keys.shape[1] - 1, -1, -1, dtype=np.int64)
    code_t = table @ weights
    code_q = keys @ weights
    order = np.argsort(code_t, kind="stable")
    pos = np.clip(np.searchsorted(code_t[order], code_q), 0, len(order) - 1)
    found = code_t[order][pos] == code_q
    out = order[pos].astype(np.int64)
    if bare is not None:
        out[np.asarray(bare, dtype=bool)] = -1
        found |= np.asarray(bare, dtype=bool)
    if not found.all():
        k = keys[np.argmin(found)]
        what = (f"group {tuple(k[:2])} with colours {tuple(k[-4:])}" if k.size >= 6
                else f"colours {tuple(k)}")
        raise InputError(f"tile set {tiles.name!r} has no tile for {what}; a closed shape "
                         "needs a complete or isotropic set, not a planar one")
    return out
