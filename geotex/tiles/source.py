"""The texture a tile set's strips and interiors are cut from: the exemplar or a quilted one.

The paper (seed 004, §3.1): "when ``M_in`` is too small, we can first
synthesize a larger geometric texture ``M_out`` from ``M_in`` with Zhou et
al.'s method [mesh quilting] and then pick the required strips from
``M_out``".  A small exemplar offers few distinct unit segments to cut edge
strips from: its strips then repeat the same few elements (a 1.3 x 1.3 studs
exemplar gives one stud per strip), or :func:`~geotex.tiles.strips.pick_strips`
finds fewer distinct strips than colours and the build fails.  Here the
exemplar is first quilted (:func:`geotex.quilting.quilt_texture`, the one
quilter of geotex) into a square of side :data:`SOURCE_SIDE` tile units, and
that texture replaces the exemplar for the strips, the corner patch, the
interior quilting windows and the gap fills.  That last part differs from
the paper, which synthesizes the tile interiors from ``M_in`` itself: a
small exemplar's quilting window (2 x 2 tiles) would be the whole exemplar
for every tile, and the frames' elements, being quilted copies, match the
windows of ``M_out`` as well as the exemplar's.

When (``quilted_source`` of :func:`geotex.tiles.build.build_tileset`):
``"auto"`` (the default) quilts when, along an axis strips are cut along,
the exemplar offers fewer than :data:`MIN_SEGMENTS` distinct candidate
segments per strip needed there (:func:`~geotex.tiles.strips.distinct_segments`:
distinct sets of crossing elements over a 32 x 32 lattice of segment
starts), which includes an exemplar shorter than a tile; never for a
lattice set (quilted copies are moved off the lattice by ICP).  The
catalog's exemplars cut into strips (4 x 4 tiles) offer 106 (studs) to 711
(scales) such segments, so their sets are built from the exemplar as
before; the catalog studs exemplar cropped to 1.3 x 1.3 offers 4 along x
for the 2 strips of a 2-colour isotropic set.
"""

from __future__ import annotations

import numbers

import numpy as np

from geotex.errors import GeotexError, InputError
from geotex.quilting import quilt_texture
from geotex.tiles.strips import distinct_segments

__all__ = ["SOURCE_SIDE", "MIN_SEGMENTS", "SIDE_RANGE", "SOURCE_STREAM", "source_side",
           "strips_along", "quilted_texture"]

SOURCE_SIDE = 4.0          # side (tile units) of a quilted source: the catalog exemplars'
MIN_SEGMENTS = 8           # "auto": distinct candidate segments wanted per strip
SIDE_RANGE = (2.0, 12.0)   # accepted sides of a quilted source
SOURCE_STREAM = 2 ** 31    # spawn key of the quilting seed (beyond every tile index)


def strips_along(n_colors, *, isotropic: bool) -> tuple[int, int]:
    """Edge strips a set cuts along the exemplar's x and y axes.

    Classes 0 and 2 run along x, class 1 along y
    (:data:`geotex.tiles.build.STRIP_AXIS`); an isotropic set cuts its ``N``
    strips once, along x.

    Returns
    -------
    tuple of 2 int
    """
    if isotropic:
        return int(n_colors[0]), 0
    return int(n_colors[0]) + int(n_colors[2]), int(n_colors[1])


def source_side(option, lo: np.ndarray, hi: np.ndarray, size, needed, *,
                lattice: bool = False) -> float:
    """Side of the quilted source to build, or 0.0 to cut from the exemplar itself.

    Parameters
    ----------
    option : {"auto", True, False} or float
        ``quilted_source`` of :func:`~geotex.tiles.build.build_tileset`:
        ``"auto"`` quilts a :data:`SOURCE_SIDE` source when the exemplar
        offers fewer than :data:`MIN_SEGMENTS` distinct segments per strip
        along an axis (never with ``lattice``); True always quilts one of
        :data:`SOURCE_SIDE`; a number is the side, in tile units, within
        :data:`SIDE_RANGE`; False never quilts.
    lo, hi : numpy.ndarray, (E, 3) float64
        The exemplar's element boxes.
    size : tuple of 2 float
        Exemplar extent.
    needed : tuple of 2 int
        Strips cut along x and along y (:func:`strips_along`).
    lattice : bool
        The set keeps the exemplar's lattice.

    Returns
    -------
    float

    Raises
    ------
    InputError
        An option that is none of the above, or a quilted source asked for
        a lattice set.
    """
    if isinstance(option, str):
        if option != "auto":
            raise InputError(f"quilted_source: 'auto', True, False or a side in tile units, "
                             f"got {option!r}")
        if lattice:
            return 0.0
        short = any(n and distinct_segments(lo, hi, size, along=axis) < MIN_SEGMENTS * n
                    for axis, n in enumerate(needed))
        return SOURCE_SIDE if short else 0.0
    if option is False or option is None:
        return 0.0
    if option is True:
        side = SOURCE_SIDE
    elif isinstance(option, numbers.Real) and not isinstance(option, bool):
        side = float(option)
        if not (SIDE_RANGE[0] <= side <= SIDE_RANGE[1]):
            raise InputError(f"quilted_source: a side between {SIDE_RANGE[0]:g} and "
                             f"{SIDE_RANGE[1]:g} tile units, got {option!r}")
    else:
        raise InputError(f"quilted_source: 'auto', True, False or a side in tile units, "
                         f"got {option!r}")
    if lattice:
        raise InputError("quilted_source and lattice exclude each other: quilted copies "
                         "are moved off the exemplar's lattice by ICP")
    return side


def quilted_texture(exemplar, side: float, seed: int) -> tuple[np.ndarray, np.ndarray, dict]:
    """Quilt a ``side x side`` texture from an exemplar (seeded, deterministic).

    :func:`geotex.quilting.quilt_texture` with its defaults (cell: the
    exemplar's period or pitch; elements that would leave the square are
    dropped, so every element stays whole and inside it), seeded by the
    child :data:`SOURCE_STREAM` of ``SeedSequence(seed)`` (independent of the
    strips' generator and of every tile's).

    Parameters
    ----------
    exemplar : Exemplar or exemplar-like
        With ``vertices``, ``faces``, ``size`` (and optionally ``params``,
        ``period``).
    side : float
        Side of the square, tile units.
    seed : int
        The set's seed.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Closed elements over ``[0, side]^2``.
    stats : dict
        ``side``, ``elements``, ``coverage`` (fraction of the square under an
        element, from the quilting report), ``placements``.

    Raises
    ------
    GeotexError
        The quilted texture has invalid elements.
    InputError
        As :func:`~geotex.quilting.quilt_texture` (e.g. an exemplar smaller than one
        quilting cell).
    """
    qseed = int(np.random.default_rng(np.random.SeedSequence(
        int(seed), spawn_key=(SOURCE_STREAM,))).integers(2 ** 31))
    res = quilt_texture(exemplar, out_size=(side, side), seed=qseed)
    if not res.report.valid:
        raise GeotexError("quilted source: quilting gave invalid elements: "
                          + res.report.summary())
    rep = res.report
    return res.vertices, res.faces, {"side": float(side), "elements": int(rep.elements),
                                     "coverage": round(float(rep.coverage), 6),
                                     "placements": int(rep.placements)}
