"""Seamlessness check of a tile set: every legal neighbour pair welds shut.

Two tile sides may meet whenever they carry the same axis class and colour
(on the plane and across polycube edges alike); in an isotropic set, whenever
they carry the same colour, whatever their classes. Each side's open boundary is
summarised in edge coordinates ``(t, w)`` (``t`` along the side, ``w`` the
height); the set is seamless when every tile's open boundary lies on its sides
and all sides of one class and colour carry bit-identical boundaries, which
makes the check exhaustive over all pairs of such sides.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from geotex.errors import InputError
from geotex.mesh.topology import edge_topology
from geotex.tiles.directional import oriented_tileset, side_kinds, tile_turns
from geotex.tiles.fill import footprint_pixels
from geotex.tiles.tileset import TileSet

__all__ = ["SeamReport", "check_seams", "side_boundaries", "CornerDensity", "corner_density"]

_SIDE_NAMES = ("south", "east", "north", "west")


@dataclass(frozen=True)
class SeamReport:
    """Outcome of :func:`check_seams`.

    Attributes
    ----------
    ok : bool
    pairs_checked : int
        Ordered pairs of tile sides that may meet (all compared).
    problems : list of str
        One line per problem, naming the tiles and sides.
    """

    ok: bool
    pairs_checked: int
    problems: list = field(default_factory=list)


def side_boundaries(V: np.ndarray, F: np.ndarray) -> tuple[list, int]:
    """Open boundary segments of a tile per side, in edge coordinates.

    Returns
    -------
    sides : list of 4 numpy.ndarray, (k, 4) float64
        Rows ``(t_a, w_a, t_b, w_b)`` with endpoints ordered, rows sorted.
    stray : int
        Boundary edges that lie on no side (must be 0).
    """
    topo = edge_topology(F, len(V))
    e = topo.edges[topo.boundary]
    a, b = V[e[:, 0]], V[e[:, 1]]
    tests = ((1, 0.0, 0), (0, 1.0, 1), (1, 1.0, 0), (0, 0.0, 1))  # (coord, value, t-axis)
    sides, on_any = [], np.zeros(len(e), dtype=bool)
    for coord, value, t_axis in tests:
        on = (a[:, coord] == value) & (b[:, coord] == value)
        on_any |= on
        pa = np.stack([a[on, t_axis], a[on, 2]], 1)
        pb = np.stack([b[on, t_axis], b[on, 2]], 1)
        swap = (pa[:, 0] > pb[:, 0]) | ((pa[:, 0] == pb[:, 0]) & (pa[:, 1] > pb[:, 1]))
        lo = np.where(swap[:, None], pb, pa)
        hi = np.where(swap[:, None], pa, pb)
        rows = np.hstack([lo, hi]) + 0.0
        rows = rows[np.lexsort(rows.T[::-1])] if len(rows) else rows.reshape(0, 4)
        sides.append(rows)
    return sides, int((~on_any).sum())


def check_seams(tiles: TileSet) -> SeamReport:
    """Check every pair of tile sides that may meet, exhaustively.

    Sides are grouped by ``(axis class, colour)``, or by colour alone for an
    isotropic set (:attr:`TileSet.isotropic`), so there the cross-class
    pairs (a south side of class X against a west side of class Y, ...) are
    compared too. Every tile must also be open only along its sides and be
    edge-manifold; an isotropic set must hold group (0, 1) only.

    A directional set (:mod:`geotex.tiles.directional`) is checked twice: its
    base tiles as a planar set (the ridge colour is one more colour per class),
    and its oriented form (six groups, turned), whose sides are grouped by
    ``(kind, colour)`` (the strip as both quads of an edge read it), all ridge
    sides in one group whatever their kind (they must all be empty).

    Parameters
    ----------
    tiles : TileSet

    Returns
    -------
    SeamReport
    """
    info = tiles.metadata.get("directional") or {}
    if info and not info.get("oriented"):
        base = _check(tiles, _class_keys(tiles))
        oriented = oriented_tileset(tiles)
        turned = _check(oriented, _kind_keys(oriented))
        return SeamReport(base.ok and turned.ok, base.pairs_checked + turned.pairs_checked,
                          base.problems + [f"oriented: {p}" for p in turned.problems])
    return _check(tiles, _kind_keys(tiles) if info else _class_keys(tiles))


def _class_keys(tiles: TileSet) -> np.ndarray:
    """(T, 4, 2) grouping keys: (axis class or 0 when isotropic, colour)."""
    classes = tiles.groups[:, [0, 1, 0, 1]]
    if tiles.isotropic:
        classes = np.zeros_like(classes)
    return np.stack([classes, tiles.colors], -1)


def _kind_keys(tiles: TileSet) -> np.ndarray:
    """(T, 4, 2) grouping keys of an oriented directional set: (kind, colour), ridge (4, 0)."""
    info = tiles.metadata["directional"]
    kinds = side_kinds(tiles.groups, up=info.get("up", 2), turns=tile_turns(tiles))
    ridge = tiles.colors == int(info["ridge"])
    return np.stack([np.where(ridge, 4, kinds), np.where(ridge, 0, tiles.colors)], -1)


def _check(tiles: TileSet, keys_of: np.ndarray) -> SeamReport:
    problems = []
    iso = tiles.isotropic
    if iso and np.any(tiles.groups != [0, 1]):
        problems.append("isotropic set holds tiles outside group (0, 1)")
    first = {}                      # key -> (digest, tile, side)
    for i in range(len(tiles)):
        V, F = tiles.tile(i)
        sides, stray = side_boundaries(V, F)
        topo = edge_topology(F, len(V))
        if stray:
            problems.append(f"tile {i}: {stray} open boundary edges away from its sides")
        if topo.non_manifold.any():
            problems.append(f"tile {i}: {int(topo.non_manifold.sum())} non-manifold edges")
        for s in range(4):
            key = tuple(int(k) for k in keys_of[i, s])
            digest = hashlib.sha1(np.ascontiguousarray(sides[s]).tobytes()).hexdigest()
            if key not in first:
                first[key] = (digest, i, s)
            elif first[key][0] != digest:
                d0, i0, s0 = first[key]
                problems.append(f"tiles {i0} ({_SIDE_NAMES[s0]}) and {i} ({_SIDE_NAMES[s]}) "
                                f"share {_shared(tiles, key)} but their boundaries differ")
    _, counts = np.unique(keys_of.reshape(-1, 2), axis=0, return_counts=True)
    pairs = int((counts * (counts - 1)).sum())
    return SeamReport(not problems, pairs, problems)


def _shared(tiles: TileSet, key) -> str:
    if tiles.metadata.get("directional"):
        return "the ridge" if key[0] == 4 else \
            f"strip kind {('+t', '+s', '-t', '-s')[key[0]]} colour {key[1]}"
    return f"colour {key[1]}" if tiles.isotropic else \
        f"axis class {'XYZ'[key[0]]} colour {key[1]}"


@dataclass(frozen=True)
class CornerDensity:
    """Outcome of :func:`corner_density`.

    Attributes
    ----------
    corner : float
        Fraction of the corner squares covered by relief (projected area of the
        faces above the tile plane).
    elsewhere : float
        The same fraction over the rest of the tiling.
    ratio : float
        ``corner / elsewhere`` (the issue #14 target is at least 0.85).
    """

    corner: float
    elsewhere: float
    ratio: float


def corner_density(V: np.ndarray, F: np.ndarray, grid, *, quarter: float = 0.25,
                   pixel: float = 1.0 / 40.0) -> CornerDensity:
    """Relief density in the squares around tile corners against the rest.

    The faces above the tile plane (``w > 0`` at their centroid; what stands
    above the slab of a printed tiling) are rasterized by their projection on
    the plane; a pixel belongs to a *corner square* when it lies within
    ``quarter`` (in tile units, along both axes) of a grid point of the
    tiling, the tiling's outer corners included.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
        A planar tiling in tile units (:func:`geotex.tiles.tiling.planar_tiling`).
    F : numpy.ndarray, (m, 3) int64
    grid : tuple of 2 int
        Tiling size ``(W, H)``; the tiling covers ``[0, W] x [0, H]``.
    quarter : float
        Half side of a corner square (a quarter tile by default).
    pixel : float
        Raster pixel size in tile units.

    Returns
    -------
    CornerDensity

    Raises
    ------
    InputError
        Grid smaller than 1 x 1, or ``quarter`` outside ``(0, 0.5)``.
    """
    w, h = (int(g) for g in grid)
    if w < 1 or h < 1:
        raise InputError(f"grid must be at least 1 x 1, got {grid!r}")
    if not 0.0 < quarter < 0.5:
        raise InputError(f"quarter must lie in (0, 0.5), got {quarter!r}")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    up = F[V[F][:, :, 2].mean(axis=1) > 0.0]
    nx, ny = int(round(w / pixel)), int(round(h / pixel))
    covered = np.zeros((nx, ny), dtype=bool)
    if len(up):
        ii, jj, _ = footprint_pixels(V, up, pixel=pixel, shape=(nx, ny))
        covered[ii, jj] = True
    cx = (np.arange(nx) + 0.5) * pixel
    cy = (np.arange(ny) + 0.5) * pixel
    near_x = np.abs(cx - np.round(cx)) < quarter
    near_y = np.abs(cy - np.round(cy)) < quarter
    corner = near_x[:, None] & near_y[None, :]
    c = float(covered[corner].mean())
    e = float(covered[~corner].mean())
    return CornerDensity(c, e, c / e if e > 0 else float("nan"))
