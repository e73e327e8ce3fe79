"""Tile sets from a periodic exemplar layout kept on its lattice: chain mail, weave.

Linked rings cannot go through the strip-and-quilt pipeline of
:mod:`geotex.tiles.build`: it picks elements one by one, so a ring taken alone
is no longer linked to anything. Here the tiles are cut from one periodic
layout instead, the diagonal European 4-in-1 of
:func:`geotex.exemplars.chainmail.diagonal_layout` (rows along the tile
diagonal, period 1 along both tile axes, its own mirror image across the
diagonal ``x = y``), so every ring keeps its four linked neighbours in every
tiling, across tile sides too.

Every ring whose footprint (grown by the jitter) reaches into the tile is
classed by the tile lines its footprint crosses:

* *interior* rings cross none; their small random shift comes from the
  tile's own generator;
* *side* rings cross one tile side; they form the edge strip of that side's
  colour, built once per colour in the coordinates of a south side
  (``t = x``, ``s = y``), shifted from the colour's generator and cut at
  ``s = 0`` (:func:`geotex.tiles.clip.split_by_plane`). The south side takes
  the ``s >= 0`` half, the north side the ``s <= 0`` half moved by 1; west
  and east take the same halves mirrored across ``x = y``, which is where the
  layout puts them (a mirror, not the quarter turn of
  :func:`geotex.tiles.frame.placed_half`: the 4-in-1 has no quarter-turn
  symmetry);
* *corner* rings cross two tile lines; they are never shifted and are cut
  into four quadrants (ordered cuts, so the quadrants are mirror images bit
  for bit), one for each tile around a corner.

A side of colour ``c`` then carries the same cut whichever side it is, bit
for bit, so the set is isotropic (:func:`geotex.tiles.verify.check_seams`).
Shifts stay within 0.4 of the free clearance, so linked rings never touch.

The plain weave (:class:`WeaveLayout`, :func:`weave_tileset`) is cut the same
way but needs no cut at all: its strands run straight across the tile, ``n``
along x and ``n`` along y (``n = 1 / pitch``, even, so the over-under pattern
has period 1), and every tile side meets them at mid height, square to the
side. Each colour is a vector of sideways strand offsets drawn from
``default_rng(seed)``; a tile's strands run from the offsets of one side's
colour to those of the opposite side's, with a mid-tile sway from the tile's
own generator (:func:`geotex.exemplars.weave.tile_strands`). The strands along
y are the strands along x mirrored across ``x = y``, so a side of colour
``c`` carries the same cross-sections, bit for bit, whichever side it is, and
the set is isotropic. Strands are open tubes ending on the tile sides: a
tiling welds them into strands as long as the tiling
(:func:`geotex.tiles.tiling.planar_tiling` caps them at its outer border).
"""

from __future__ import annotations

import numpy as np

from geotex.errors import GeotexError, InputError
from geotex.exemplars.chainmail import (DIAGONAL_STEP, diagonal_layout, ring_meshes,
                                        wire_slack)
from geotex.exemplars.weave import GAP as WEAVE_GAP
from geotex.exemplars.weave import crossing_clearance, strand_geometry, tile_strands
from geotex.mesh.topology import concatenated, face_components
from geotex.progress import report
from geotex.quilting import coverage_fraction
from geotex.tiles.clip import split_by_plane
from geotex.tiles.colors import PLANAR_GROUPS, tile_keys
from geotex.tiles.tileset import TileSet, tile_rng

__all__ = ["periodic_tileset", "PeriodicLayout", "WeaveLayout", "weave_tileset", "layout_of",
           "SUPPORTED"]

SUPPORTED = ("chainmail", "weave")
SHIFT = 0.4          # largest random ring shift, as a fraction of the free clearance x jitter
MARGIN = 1e-3        # added to a ring's reach when classing it by the lines it crosses
OFFSETS = 32         # layout shifts along the diagonal tried (one row step in all)


class PeriodicLayout:
    """The diagonal ring layout of a chain mail parameter set, fitted to the unit tile.

    Attributes
    ----------
    n : int
        Rings per row in one period (even); spacings ``1 / (n sqrt 2)``.
    radius : float
        Ring radius actually used: the exemplar radius rounded so that the
        spacings (:data:`~geotex.exemplars.chainmail.DIAGONAL_STEP` radii)
        divide the tile.
    shift : float
        Largest random ring shift.
    reach : float
        Largest distance, along x or y, from a ring's centre to its surface,
        plus ``shift`` and :data:`MARGIN`.
    offset : float
        Shift of the layout along the diagonal: of :data:`OFFSETS` candidates
        whose corner rings no face crosses both tile lines through, the one
        that leaves the fewest ring pieces not reaching below ``z = 0`` when
        the rings are cut at the tile sides (such a piece is held only by its
        continuation on the neighbour tile; where a polycube seam pairs two
        sides that do not continue each other, it would float), then the one
        whose wires keep farthest from the tile corner.
    loose_pieces : int
        Those pieces left with the chosen offset (per strip and corner, once).
    corner_clearance : float
        Distance from the tile corner line to the nearest ring vertex.
    params : dict
        Wire, depth, resolution (for :func:`~geotex.exemplars.chainmail.ring_meshes`).
    """

    def __init__(self, params: dict):
        R0, k = float(params["radius"]), int(params["resolution"])
        self.n = max(2, 2 * int(round(1.0 / (np.sqrt(2.0) * DIAGONAL_STEP * R0) / 2.0)))
        self.radius = 1.0 / (self.n * np.sqrt(2.0) * DIAGONAL_STEP)
        slack = wire_slack(self.radius, float(params["wire"]), k, (DIAGONAL_STEP,) * 2,
                           what="periodic chain mail")
        self.shift = SHIFT * float(params["jitter"]) * slack
        self.params = {"radius": self.radius, "wire": float(params["wire"]),
                       "depth": float(params["depth"]), "resolution": k}
        V, _ = ring_meshes(np.zeros((2, 2)), np.array([1.0, -1.0]), **self.params)
        self.reach = float(np.abs(V[:, :2]).max()) + self.shift + MARGIN
        if self.reach >= 0.5:
            raise InputError(f"periodic chain mail: rings reach {self.reach:.3g} from their "
                             "centres, more than half a tile; use a thinner wire")
        best = None
        for j in range(OFFSETS):
            off = j / (2 * self.n * OFFSETS)
            Vc, Fc = self.mesh(*self.centres("corner", off))
            if _straddles_corner(Vc, Fc):
                continue
            pieces = _cut_pieces(self.mesh(*self.centres("side", off)), (Vc, Fc))
            loose = sum(_loose(p) for p in pieces)
            clear = float(np.hypot(Vc[:, 0], Vc[:, 1]).min())
            if best is None or (loose, -clear) < (best[0], -best[1]):
                best = (loose, clear, off)
        if best is None:
            raise InputError("periodic chain mail: every layout puts a wire across a tile "
                             "corner; change the radius or the resolution")
        self.loose_pieces, self.corner_clearance, self.offset = best

    def centres(self, kind: str, offset=None):
        """Centres ``(E, 2)`` and tilts ``(E,)`` of one class of rings.

        ``kind``: ``"corner"`` (within :attr:`reach` of both lines through the
        origin), ``"side"`` (within reach of ``y = 0`` only, centre between
        ``x = reach`` and ``x = 1 - reach``) or ``"interior"`` (centre at
        least reach inside the unit square).
        """
        off = self.offset if offset is None else offset
        r = self.reach
        _, C, sign = diagonal_layout(self.n, off, -r, 1.0 + r)
        x, y = C[:, 0], C[:, 1]
        inner_x = (x >= r) & (x <= 1.0 - r)
        if kind == "corner":
            keep = (np.abs(x) < r) & (np.abs(y) < r)
        elif kind == "side":
            keep = inner_x & (np.abs(y) < r)
        else:
            keep = inner_x & (y >= r) & (y <= 1.0 - r)
        return C[keep], sign[keep]

    def jittered(self, C, rng):
        """Centres moved by up to :attr:`shift` in random directions (as the exemplar)."""
        if self.shift == 0.0 or len(C) == 0:
            return C
        E = len(C)
        ang = rng.uniform(0, 2 * np.pi, E)
        return C + self.shift * rng.uniform(0, 1, E)[:, None] * np.stack(
            [np.cos(ang), np.sin(ang)], -1)

    def mesh(self, C, sign):
        """Rings at centres ``C`` with tilts ``sign`` as one mesh."""
        return ring_meshes(C, sign, **self.params)


class WeaveLayout:
    """The plain weave of a weave parameter set, fitted to the unit tile.

    Attributes
    ----------
    n : int
        Strands along each axis per tile (even): ``1 / pitch`` rounded to an
        even number.
    pitch : float
        Strand spacing actually used, ``1 / n``.
    geom : dict
        Half width, half thickness, centre height, amplitude
        (:func:`~geotex.exemplars.weave.strand_geometry`).
    shift : float
        Largest sideways offset of a strand from its lattice line: ``jitter``
        times half the room left between parallel strands once the gap is
        kept. Side offsets and the mid-tile sway take at most half each.
    clearance : float
        Smallest vertical gap between crossing strands moved by up to
        :attr:`shift` (:func:`~geotex.exemplars.weave.crossing_clearance`).
    resolution, stations : int
        Points around a strand; cross-sections per pitch.
    """

    def __init__(self, params: dict):
        pitch0 = float(params["pitch"])
        self.n = max(2, 2 * int(round(1.0 / (2.0 * pitch0))))
        self.pitch = 1.0 / self.n
        self.geom = strand_geometry(params, pitch=self.pitch)
        self.shift = float(params["jitter"]) * 0.5 * self.geom["free"]
        self.clearance = crossing_clearance(self.geom, self.pitch, self.shift)
        if self.clearance < 2 * WEAVE_GAP:
            raise InputError(f"periodic weave: crossing strands come {self.clearance:.3g} "
                             f"apart (need {2 * WEAVE_GAP:g}); lower the jitter or the "
                             "thickness, or raise the height")
        self.resolution = int(params["resolution"])
        self.stations = max(8, self.resolution)

    def side_offsets(self, rng: np.random.Generator) -> np.ndarray:
        """Sideways offsets ``(n,)`` of the strands crossing one side colour."""
        return 0.5 * self.shift * rng.uniform(-1.0, 1.0, self.n)

    def strands(self, start, end, rng: np.random.Generator, first_over: bool):
        """Strands along x from offsets ``start`` (x = 0) to ``end`` (x = 1), sway from ``rng``.

        ``first_over``: strand 0 passes over the first crossing (strands along
        x); the strands along y, mirrored, pass under it.
        """
        bump = self.side_offsets(rng)
        sign = np.where(np.arange(self.n) % 2 == 0, 1.0, -1.0)
        return tile_strands(start, end, bump, sign if first_over else -sign, geom=self.geom,
                            resolution=self.resolution, stations=self.stations)


def layout_of(exemplar):
    """The layout of an exemplar (:data:`SUPPORTED` kinds only): a
    :class:`PeriodicLayout` for chain mail, a :class:`WeaveLayout` for the weave.

    Raises
    ------
    InputError
        Another exemplar kind, or parameters that do not fit a tile.
    """
    name = getattr(exemplar, "name", None)
    if name not in SUPPORTED:
        raise InputError(f"interior 'periodic' (--interior periodic) needs an exemplar with a "
                         f"periodic tile layout ({', '.join(SUPPORTED)}), got {name!r}")
    if name == "weave":
        return WeaveLayout(dict(exemplar.params))
    return PeriodicLayout(dict(exemplar.params))


def _quadrants(corner):
    """The corner rings cut by both lines through the origin (ordered cuts, so the
    quadrants are mirror images across ``x = y`` bit for bit): ``(x-y-, x-y+, x+y-, x+y+)``."""
    left, right = split_by_plane(*corner, axis=0, value=0.0, ordered=True)
    ll, lu = split_by_plane(*left, axis=1, value=0.0, ordered=True)
    rl, ru = split_by_plane(*right, axis=1, value=0.0, ordered=True)
    return ll, lu, rl, ru


def _cut_pieces(side, corner):
    """The two halves of the side rings and the four quadrants of the corner rings."""
    return split_by_plane(*side, axis=1, value=0.0) + _quadrants(corner)


def _loose(mesh) -> int:
    """Connected pieces of a cut mesh that do not reach below ``z = 0`` (not anchored)."""
    V, F = mesh
    if len(F) == 0:
        return 0
    n, label = face_components(F, len(V))
    low = np.full(n, np.inf)
    np.minimum.at(low, label, V[F][:, :, 2].min(axis=1))
    return int((low >= 0.0).sum())


def _straddles_corner(V, F) -> bool:
    """True when a face crosses both lines ``x = 0`` and ``y = 0``."""
    P = V[F]
    lo, hi = P[:, :, :2].min(axis=1), P[:, :, :2].max(axis=1)
    return bool(((lo < 0) & (hi > 0)).all(axis=1).any())


def _swapped(mesh, dx=0.0):
    """Mirror across ``x = y`` (faces reversed to stay outward), then move by ``dx`` in x."""
    V, F = mesh
    W = V[:, [1, 0, 2]].copy()
    if dx:
        W[:, 0] += dx
    return W, F[:, ::-1].copy()


def _moved(mesh, d):
    V, F = mesh
    return V + np.array([d[0], d[1], 0.0]), F


def periodic_tileset(exemplar, *, n_colors, seed: int = 0, name: str | None = None,
                     progress=None) -> TileSet:
    """Build an isotropic tile set cut from the periodic layout of ``exemplar``.

    Parameters
    ----------
    exemplar : Exemplar
        A kind in :data:`SUPPORTED` (its parameters are used; its mesh is not).
    n_colors : tuple of 3 int
        Equal colour counts (isotropic set of ``N^4`` tiles).
    seed : int
        Colour strips draw their shifts from ``default_rng(seed)``, colour by
        colour; tile ``t`` its interior shifts from
        ``default_rng(SeedSequence(seed, spawn_key=(t,)))``.
    name : str, optional
    progress : callable, optional
        Called with ``"strips"`` and ``"tile i/T"``.

    Returns
    -------
    TileSet

    Raises
    ------
    InputError
        Unsupported exemplar, unequal colour counts, rings that do not fit.
    GeotexError
        A corner ring would be cut by both tile lines in one face.
    """
    if len(set(n_colors)) != 1 or n_colors[0] < 1:
        raise InputError(f"colors: interior 'periodic' builds isotropic sets, one colour count "
                         f"for all axes, got {tuple(n_colors)!r}")
    lay = layout_of(exemplar)
    if isinstance(lay, WeaveLayout):
        return weave_tileset(exemplar, lay, n_colors=n_colors, seed=seed, name=name,
                             progress=progress)
    N = int(n_colors[0])
    report(progress, "strips")
    rng = np.random.default_rng(seed)
    strips = []
    C, sign = lay.centres("side")
    corner = lay.mesh(*lay.centres("corner"))
    if _straddles_corner(*corner):
        raise GeotexError("periodic chain mail: a corner ring face crosses both tile lines")
    for _ in range(N):
        strips.append(split_by_plane(*lay.mesh(lay.jittered(C, rng), sign), axis=1,
                                     value=0.0))
    ll, lu, rl, ru = _quadrants(corner)
    corners = [ru, _moved(lu, (1.0, 0.0)), _moved(rl, (0.0, 1.0)), _moved(ll, (1.0, 1.0))]
    C_in, sign_in = lay.centres("interior")

    groups, cols = tile_keys((N, N, N), PLANAR_GROUPS)
    tiles, coverage = [], []
    for t, (cs, ce, cn, cw) in enumerate(cols.tolist()):
        inner = lay.mesh(lay.jittered(C_in, tile_rng(seed, t)), sign_in)
        south = strips[cs][1]
        north = _moved(strips[cn][0], (0.0, 1.0))
        west = _swapped(strips[cw][1])
        east = _swapped(strips[ce][0], 1.0)
        tile = concatenated([inner, south, east, north, west] + corners)
        tiles.append(tile)
        coverage.append(coverage_fraction(tile[0], tile[1], (0.0, 0.0, 1.0, 1.0),
                                          resolution=100))
        report(progress, f"tile {t + 1}/{len(cols)}")
    periodic = {"layout": "diagonal 4-in-1", "rings_per_row": lay.n,
                "radius": round(float(lay.radius), 9), "shift_max": round(lay.shift, 9),
                "offset": round(lay.offset, 9), "rings_per_tile": 2 * lay.n ** 2,
                "corner_wire_clearance": round(lay.corner_clearance, 6),
                "unanchored_pieces": lay.loose_pieces}
    return _assembled(exemplar, tiles, coverage, groups, cols, N=N, seed=seed, name=name,
                      periodic=periodic)

def weave_tileset(exemplar, layout: WeaveLayout, *, n_colors, seed: int = 0,
                  name: str | None = None, progress=None) -> TileSet:
    """Build the isotropic plain-weave set (see the module notes).

    Parameters
    ----------
    exemplar : Exemplar
        A ``weave`` exemplar (its parameters are recorded).
    layout : WeaveLayout
    n_colors : tuple of 3 int
        Equal colour counts.
    seed : int
        Colours draw their offsets from ``default_rng(seed)``, colour by
        colour; tile ``t`` its mid-tile sway from
        ``default_rng(SeedSequence(seed, spawn_key=(t,)))``.
    name : str, optional
    progress : callable, optional
        Called with ``"strips"`` and ``"tile i/T"``.

    Returns
    -------
    TileSet
        ``metadata["tiling_border"]`` is ``"cap"``: strands run across the
        whole of a tiling, so its outer border caps them instead of dropping them.
    """
    lay = layout
    N = int(n_colors[0])
    report(progress, "strips")
    rng = np.random.default_rng(seed)
    side = [lay.side_offsets(rng) for _ in range(N)]
    groups, cols = tile_keys((N, N, N), PLANAR_GROUPS)
    tiles, coverage = [], []
    for t, (cs, ce, cn, cw) in enumerate(cols.tolist()):
        trng = tile_rng(seed, t)
        along_x = lay.strands(side[cw], side[ce], trng, True)
        along_y = _swapped(lay.strands(side[cs], side[cn], trng, False))
        tile = concatenated([along_x, along_y])
        tiles.append(tile)
        coverage.append(coverage_fraction(tile[0], tile[1], (0.0, 0.0, 1.0, 1.0),
                                          resolution=100))
        report(progress, f"tile {t + 1}/{len(cols)}")
    periodic = {"layout": "plain weave", "strands_per_axis": lay.n,
                "pitch": round(lay.pitch, 9), "shift_max": round(lay.shift, 9),
                "crossing_clearance": round(lay.clearance, 6)}
    return _assembled(exemplar, tiles, coverage, groups, cols, N=N, seed=seed, name=name,
                      periodic=periodic, extra={"tiling_border": "cap"})


def _assembled(exemplar, tiles, coverage, groups, cols, *, N, seed, name, periodic,
               extra=None) -> TileSet:
    """The isotropic periodic :class:`TileSet` of ``tiles`` with its recipe and metadata."""
    params = dict(exemplar.params)
    recipe = {"name": exemplar.name, "params": params}
    meta = {
        "exemplar": recipe,
        "recipe": {"exemplar": recipe, "colors": [N, N, N], "planar": False,
                   "isotropic": True, "lattice": False, "seed": int(seed),
                   "interior": "periodic"},
        "isotropic": True,
        "lattice": None,
        "periodic": periodic,
        **(extra or {}),
        "coverage_mean": round(float(np.mean(coverage)), 6),
    }
    height = max(float(V[:, 2].max()) for V, _ in tiles)
    return TileSet.from_tiles(tiles, groups, cols, n_colors=(N, N, N), height=height,
                              depth=float(params["depth"]), name=name or exemplar.name,
                              metadata=meta)
