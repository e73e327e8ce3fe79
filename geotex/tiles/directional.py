"""Directional tile sets: one planar set turned to follow a flow over a closed polycube.

An isotropic set (studs, knurl) may put any tile on any quad; a *directional*
texture (scales: every scale has a root and a lifted tail) must keep its
direction. This goes beyond the paper, whose results are isotropic only (it
names anisotropic textures as future work, last section of
``../shared/papers/wang-tile-geometric-texture.md``).

The flow. Every quad of a polycube lies on a chart with outward normal along one
world axis. With ``up`` the world "up" axis (default Z), the flow on a side
chart (normal not along ``up``) runs toward ``-up`` (scales hang down, like roof
tiles or fish scales with gravity). The top and bottom charts (normal along
``up``) have no down: each of their quads takes the one of four axis
directions that makes fewest ridges (:func:`quad_turns`), so a top chart's
scales run out over its rims and on down the sides, a bottom chart's run in
from its rims. (Before, every top and bottom quad flowed toward ``+T``, ``T =
(up + 2) % 3``, :func:`flow_of_group`, which left ridges on three of a top
chart's four rims; ``quad_turns(..., optimise=False)`` still gives that rule.)

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
an edge's strip only when they give it the same kind; where they do not, the
edge takes the ridge colour, whose sides are empty on every tile: no element
crosses that edge, like the ridge or hip line of a roof. Elsewhere, including
every fold between two side charts, the scales run on across the edge. How many
ridges the hanging sides force depends on the charts: on a box with a ``k x
k`` top, ``3 k`` per top and bottom whatever the turns (an integer program
agrees: a uniform flow, two halves flowing apart, or four quarters flowing out
all cost as much), so there :func:`quad_turns` gains nothing; on the organic
catalog polycubes, with many small top and bottom charts, it removes a third.

The turned copies are made in memory (:func:`oriented_tileset`): six groups of
the base tiles, each turned by the turns its group allows (one on side
charts, four on top and bottom), positions turned by exact
formulas (``u' = 1 - v`` etc.), so sides of one kind and colour stay
bit-identical. Files hold the base set only.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.tiles.colors import COMPLETE_GROUPS, EAST, NORTH, SOUTH, WEST
from geotex.tiles.tileset import TileSet

__all__ = ["KIND_NAMES", "flow_of_group", "group_turn", "side_kinds", "turn_kinds", "turned",
           "oriented_tileset", "allowed_turns", "tile_turns",
           "quad_turns", "ridge_edges", "is_directional"]

#: kind codes of a side: the flow in the side's strip coordinates (t, s)
KIND_NAMES = ("+t", "+s", "-t", "-s")
#: flow in tile coordinates (+v, -u, -v, +u) for r = 0..3 quarter turns
_TURN_OF_FLOW = {(1, +1): 0, (0, -1): 1, (1, -1): 2, (0, +1): 3}
#: flow (du, dv) in tile coordinates of a base tile turned r quarter turns
_FLOW_OF_TURN = ((0, 1), (-1, 0), (0, -1), (1, 0))


def _kind_table() -> np.ndarray:
    out = np.empty((4, 4), dtype=np.int64)
    for r, d in enumerate(_FLOW_OF_TURN):
        for side in (SOUTH, EAST, NORTH, WEST):
            # strip frame of the side: S/N (t, s) = (u, v); W/E (t, s) = (v, -u)
            t, s = (d[0], d[1]) if side in (SOUTH, NORTH) else (d[1], -d[0])
            out[r, side] = {(1, 0): 0, (0, 1): 1, (-1, 0): 2, (0, -1): 3}[(t, s)]
    return out


#: kind code of side k (south, east, north, west) of a tile turned r times: [r, k]
_KIND_OF_TURN = _kind_table()


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


def turn_kinds(turns: np.ndarray) -> np.ndarray:
    """Kind code of every side of tiles turned by ``turns`` quarter turns.

    The kind depends on the turn only: the flow ``+v`` of the base tile turned
    ``r`` times, read in each side's strip frame (south/north ``(t, s) = (u,
    v)``, west/east ``(t, s) = (v, -u)``).

    Parameters
    ----------
    turns : numpy.ndarray, (q,) int64
        Quarter turns 0..3.

    Returns
    -------
    numpy.ndarray, (q, 4) int64
        Codes (:data:`KIND_NAMES`) of sides south, east, north, west.
    """
    return _KIND_OF_TURN[np.asarray(turns, dtype=np.int64) % 4]


def side_kinds(groups: np.ndarray, *, up: int = 2, turns=None) -> np.ndarray:
    """Kind code of every side of quads (or tiles) of the given groups.

    Parameters
    ----------
    groups : numpy.ndarray, (q, 2) int64
        Frame ``(a, b)`` of each quad.
    up : int
    turns : numpy.ndarray, (q,) int64, optional
        Quarter turns of each quad's tile (:func:`quad_turns`); default: the
        turn of its group (:func:`group_turn`).

    Returns
    -------
    numpy.ndarray, (q, 4) int64
        Codes (:data:`KIND_NAMES`) of sides south, east, north, west.
    """
    groups = np.asarray(groups, dtype=np.int64).reshape(-1, 2)
    if turns is None:
        turns = _group_turns(groups, up=up)
    return turn_kinds(turns)


def _group_turns(groups: np.ndarray, *, up: int) -> np.ndarray:
    """:func:`group_turn` of every row of ``groups`` (q, 2)."""
    out = np.zeros(len(groups), dtype=np.int64)
    for g in COMPLETE_GROUPS:
        out[(groups == g).all(axis=1)] = group_turn(g, up=up)
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


def allowed_turns(group, *, up: int = 2) -> tuple[int, ...]:
    """Quarter turns a quad of ``group`` may take.

    A side chart (normal not along ``up``) takes only the turn that makes its
    scales hang toward ``-up`` (:func:`group_turn`); a top or bottom chart
    (normal along ``up``) has no down, so any of the four turns, chosen per
    quad by :func:`quad_turns`.
    """
    up = _check_up(up)
    normal = 3 - int(group[0]) - int(group[1])
    return (0, 1, 2, 3) if normal == up else (group_turn(group, up=up),)


def oriented_tileset(tiles: TileSet, *, up: int | None = None) -> TileSet:
    """The six-group set of a directional base set, its tiles turned as each group allows.

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
        Blocks of the ``B`` base tiles, one block per group of
        :data:`~geotex.tiles.colors.COMPLETE_GROUPS` and turn of
        :func:`allowed_turns` (four groups with one turn, the two top/bottom
        groups with four: ``12 B`` tiles), in that order; side colours turned
        with the tiles; ``n_colors`` ``(n, n, n)``; ``metadata["directional"]``
        gains ``"oriented": True``, ``up`` and ``"turns"`` (the turn of every
        block, :func:`tile_turns`).

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
    parts, groups, colors, blocks = [], [], [], []
    base = [tiles.tile(i) for i in range(len(tiles))]
    for g in COMPLETE_GROUPS:
        for r in allowed_turns(g, up=up):
            blocks.append(int(r))
            for i, (V, F) in enumerate(base):
                parts.append((turned(V, r), F))
                groups.append(g)
                # turned side k holds base side (k - r) mod 4
                colors.append(np.roll(tiles.colors[i], r))
    meta = dict(tiles.metadata)
    meta["directional"] = dict(info, oriented=True, up=up, turns=blocks)
    return TileSet.from_tiles(parts, groups, colors, n_colors=(n, n, n),
                              height=tiles.height, depth=tiles.depth, name=tiles.name,
                              metadata=meta)


def tile_turns(tiles: TileSet) -> np.ndarray:
    """Quarter turns of every tile of an oriented directional set.

    Returns
    -------
    numpy.ndarray, (T,) int64

    Raises
    ------
    InputError
        Not an oriented directional set.
    """
    info = tiles.metadata.get("directional") or {}
    if not info.get("oriented"):
        raise InputError(f"tile set {tiles.name!r} is not an oriented directional set")
    blocks = np.asarray(info["turns"], dtype=np.int64)
    return np.repeat(blocks, len(tiles) // len(blocks))


def _edge_sides(quad_edge: np.ndarray, n_edges: int, use: np.ndarray):
    """Pairs (quad, side) of every edge with two used quads: (m, 2) quads, (m, 2) sides."""
    q = np.repeat(np.arange(len(quad_edge), dtype=np.int64), 4)
    k = np.tile(np.arange(4, dtype=np.int64), len(quad_edge))
    e = np.asarray(quad_edge, dtype=np.int64).ravel()
    keep = use[q]
    q, k, e = q[keep], k[keep], e[keep]
    order = np.lexsort((q, e))
    q, k, e = q[order], k[order], e[order]
    count = np.bincount(e, minlength=n_edges)
    first = np.flatnonzero(count[e] == 2)[::2]
    return np.stack([q[first], q[first + 1]], 1), np.stack([k[first], k[first + 1]], 1)


def _local_moves(turns, order, known, sweeps, disagreements):
    """Each quad of ``order`` in turn takes the turn with fewest disagreeing sides (ties kept)."""
    turns = turns.copy()
    for _ in range(int(sweeps)):
        changed = False
        for q in order:
            cost = disagreements(turns, np.array([q]), known)[0]
            best = int(np.argmin(cost))
            if cost[best] < cost[turns[q]]:
                turns[q] = best
                changed = True
        if not changed:
            break
    return turns


def quad_turns(quad_axes: np.ndarray, quad_edge: np.ndarray, n_edges: int, *, up: int = 2,
               bare=None, optimise: bool = True, sweeps: int = 20) -> np.ndarray:
    """Quarter turns of every quad's tile: down on the sides, few ridges on top and bottom.

    Side quads take the one turn of :func:`allowed_turns`. A top or bottom
    quad (chart normal along ``up``) may take any turn; with ``optimise`` the
    turns are chosen to make few ridge edges (edges whose two quads read
    different strip kinds, :func:`ridge_edges`). Six starts: one spread from
    the side charts inward (each quad, in rounds of growing distance from a
    fixed quad, takes the turn agreeing with most of its already turned
    neighbours, so a top chart's scales run out over its rims and down the
    sides, a bottom chart's run in from its rims), the group rule, and the
    four uniform turns; each is improved by local moves (each free quad in
    index order takes the turn with fewest disagreeing sides, ties kept) until
    a sweep changes nothing or ``sweeps`` have run, and the start with fewest
    ridges wins (the first on a tie), so never more than the group rule. This
    is a local optimum, not a proven minimum (on the catalog shells 1-13%
    above the minimum an integer program finds); a top chart whose rims all
    want outward flow must still have ridges where its flow parts (like the
    hips of a roof).

    Parameters
    ----------
    quad_axes : numpy.ndarray, (q, 2) int64
    quad_edge : numpy.ndarray, (q, 4) int64
        Global edge of sides south, east, north, west.
    n_edges : int
    up : int
    bare : numpy.ndarray, (q,) bool, optional
        Quads without a tile: they neither constrain nor take a turn (0).
    optimise : bool
        False: every quad takes its group's turn (:func:`group_turn`: flow
        along ``+T`` on top and bottom), the rule before the optimisation.
    sweeps : int
        Most local-move sweeps.

    Returns
    -------
    numpy.ndarray, (q,) int64
        Turns 0..3. Deterministic: same input, same turns.
    """
    up = _check_up(up)
    quad_axes = np.asarray(quad_axes, dtype=np.int64).reshape(-1, 2)
    nq = len(quad_axes)
    turns = _group_turns(quad_axes, up=up)
    use = np.ones(nq, dtype=bool) if bare is None else ~np.asarray(bare, dtype=bool)
    if not optimise:
        return np.where(use, turns, 0)
    free = use & ((3 - quad_axes.sum(axis=1)) == up)
    pairs, sides = _edge_sides(quad_edge, n_edges, use)
    # neighbour lists: for quad q, side k: the neighbour quad and its side (-1: none)
    nb_q = np.full((nq, 4), -1, dtype=np.int64)
    nb_k = np.full((nq, 4), -1, dtype=np.int64)
    for a, b in ((0, 1), (1, 0)):
        nb_q[pairs[:, a], sides[:, a]] = pairs[:, b]
        nb_k[pairs[:, a], sides[:, a]] = sides[:, b]
    has = nb_q >= 0
    nbq, nbk = np.where(has, nb_q, 0), np.where(has, nb_k, 0)

    def disagreements(turns, q, known):
        """(len(q), 4) count of known neighbours disagreeing, per candidate turn."""
        theirs = _KIND_OF_TURN[turns[nbq[q]], nbk[q]]               # (m, 4 sides)
        mask = has[q] & known[nbq[q]]
        mine = _KIND_OF_TURN[:, None, :]                            # (4 turns, 1, 4 sides)
        return ((mine != theirs[None]) & mask[None]).sum(axis=2).T  # (m, 4 turns)

    fixed = use & ~free
    known = use.copy()
    starts = []
    # start 1: spread inward from the fixed quads, one ring at a time
    spread, seen = turns.copy(), fixed.copy()
    while True:
        ring = np.flatnonzero(free & ~seen & (has & seen[nbq]).any(axis=1))
        if ring.size == 0:
            break
        spread[ring] = np.argmin(disagreements(spread, ring, seen), axis=1)
        seen[ring] = True
    starts.append(spread)
    # starts 2-5: the group rule, and every free quad turned alike (0..3)
    starts.append(turns.copy())
    for r in range(4):
        starts.append(np.where(free, r, turns))
    order = np.flatnonzero(free)
    best, best_count = None, None
    for t in starts:
        t = _local_moves(t, order, known, sweeps, disagreements)
        count = int((_KIND_OF_TURN[t[pairs[:, 0]], sides[:, 0]]
                     != _KIND_OF_TURN[t[pairs[:, 1]], sides[:, 1]]).sum())
        if best_count is None or count < best_count:
            best, best_count = t, count
    turns = best
    return np.where(use, turns, 0)


def ridge_edges(quad_axes: np.ndarray, quad_edge: np.ndarray, n_edges: int, *,
                up: int = 2, bare=None, turns=None) -> np.ndarray:
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
    turns : numpy.ndarray, (q,) int64, optional
        Quarter turns of each quad's tile (:func:`quad_turns`); default: its
        group's turn (:func:`group_turn`).

    Returns
    -------
    numpy.ndarray, (n_edges,) bool
    """
    kinds = side_kinds(quad_axes, up=up, turns=turns)
    use = np.ones(len(kinds), dtype=bool) if bare is None else ~np.asarray(bare, dtype=bool)
    e = np.asarray(quad_edge, dtype=np.int64)[use].ravel()
    k = kinds[use].ravel()
    lo = np.full(n_edges, 4, dtype=np.int64)
    hi = np.full(n_edges, -1, dtype=np.int64)
    np.minimum.at(lo, e, k)
    np.maximum.at(hi, e, k)
    return (hi >= 0) & (lo != hi)
