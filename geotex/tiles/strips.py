"""Edge strips: the elements that cross a tile side, cut in two.

For every colour of every axis class one strip is taken from the exemplar: the
elements that cross a unit-length line segment and stay :data:`CLEAR` inside
the perpendicular lines through its ends (no element straddles a tile
corner). A strip lives in its own coordinates ``(t, s, w)``: ``t`` runs along
the segment (``0..1``), ``s`` across it, ``w`` is the height. It is cut once
at ``s = 0``; the tile on one side of an edge of that colour receives the
``s >= 0`` half, its neighbour the ``s <= 0`` half, and the two share their
cut vertices bit for bit.

Corners. Elements may cross a side right up to the tile corner. Around a
corner point the four quadrants each hold the ends of two strips (one per
side through the corner), both in the tile of that quadrant: one along its
horizontal side, one along its vertical side. Any strip of the horizontal
side's class can meet any strip of the vertical side's class there, in some
tiling; the classes differ, except in an isotropic set, where every strip
meets every strip and itself. The strips are chosen so that those overlaps
hold no colliding elements: every strip end's half-footprints are rasterized
in the corner's quadrant coordinates (:func:`corner_footprints`) and the
element sets are pruned, strip by strip, until the footprints of every
possible pair of strip ends at every quadrant are disjoint (one pixel apart,
:func:`corner_conflicts`). The quadrants are (``X`` the strip along the
horizontal side, ``Y`` the one along the vertical side, ``^T`` swapping the
quadrant axes)::

    NE: X.above_start & Y.below_start^T     SE: X.below_start & Y.below_far^T
    SW: X.below_far   & Y.above_far^T       NW: X.above_far   & Y.above_start^T

which follows from the placements of :func:`geotex.tiles.frame.placed_half`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.mesh.geometry import group_boxes
from geotex.mesh.topology import compacted, face_components
from geotex.tiles.clip import split_by_plane
from geotex.tiles.fill import GAP, PIXEL, footprint_pixels, grown_heights, pixel_heights

__all__ = ["Strip", "CornerPatch", "corner_patch", "empty_strip", "element_boxes", "pick_strips", "largest_footprint", "lattice_phase",
           "lattice_corner", "corner_footprints", "corner_conflicts",
           "corner_correspondences", "distinct_segments", "from_strip"]

CLEAR = 0.5 * GAP   # clearance of strip elements from the perpendicular tile sides
CANDIDATES = 96     # random segment positions tried per colour
SHORTLIST = 24      # best candidates (by covered length) pruned and compared
END = 0.3           # length near a segment end whose coverage counts twice
SEGMENT_GRID = 32   # segment starts per direction counted by distinct_segments
EXACT = 12          # strips with at most this many elements in play are pruned exactly
MATCH_BONUS = 0.25  # band strips: score per element pair lying on each other at a corner
PATCH = 0.12        # corner patch: elements within this of the patch centre (both axes)
PATCH_NUDGES = [(0.0, 0.0)] + [(r * np.cos(a), r * np.sin(a)) for r in (0.003, 0.006, 0.009)
                               for a in np.arange(8) * np.pi / 4 + 0.3]
PATCH_SNAP = 2e-4   # corner patch: least distance of a vertex off a cut line from it


@dataclass(frozen=True)
class Strip:
    """One colour's edge strip, cut at ``s = 0``.

    Attributes
    ----------
    below, above : tuple of (V, F)
        The ``s <= 0`` and ``s >= 0`` halves in strip coordinates ``(t, s, w)``.
    origin : tuple of float
        Exemplar point where the segment starts.
    along : int
        Exemplar axis (0 = x, 1 = y) the segment runs along.
    boxes : numpy.ndarray, (k, 4) float64
        Footprints ``(t0, s0, t1, s1)`` of the strip's elements.
    corners : dict
        :func:`corner_footprints` of the strip's elements.
    band : tuple of (V, F), optional
        With ``band`` of :func:`pick_strips` (the paper's strip of height
        ``h_E``): the whole exemplar elements beside the line near the
        segment ends, ``(below, above)`` (``s < 0`` and ``s > 0``), which the
        corner merge (:mod:`geotex.tiles.corners`) matches with the other
        side's strip in the corner squares; None without.
    band_boxes : numpy.ndarray, (b, 4) float64, optional
        Footprints ``(t0, s0, t1, s1)`` of the band elements (both sides).
    """

    below: tuple
    above: tuple
    origin: tuple
    along: int
    boxes: np.ndarray
    corners: dict
    band: tuple | None = None
    band_boxes: np.ndarray | None = None


@dataclass(frozen=True)
class CornerPatch:
    """The elements every tile corner of a set holds (one corner colour).

    Attributes
    ----------
    pieces : dict of str -> tuple (V, F)
        The patch cut by the two lines through its centre, in coordinates
        relative to the centre: ``"ne"`` (``x, y >= 0``), ``"nw"``, ``"sw"``,
        ``"se"``; pieces share their cut vertices bit for bit.
    as_x, as_y : dict
        :func:`corner_footprints`-style images of the patch seen as the end
        of a strip along a horizontal (``as_x``) or vertical side
        (``as_y``), for :func:`corner_conflicts`.
    origin : tuple of float
        Exemplar point at the patch centre.
    """

    pieces: dict
    as_x: dict
    as_y: dict
    origin: tuple


def corner_patch(V: np.ndarray, F: np.ndarray, size, rng: np.random.Generator,
                 *, radius: float = PATCH) -> CornerPatch:
    """Cut the patch that every tile corner holds from the exemplar.

    A Wang tile set leaves the tile corners to whatever the strips of the
    two sides bring, and strips of different classes must not collide
    there, so the ends of the strips chosen last are pruned (with elements
    as long as a third of a side, scales, whole corner squares stay bare).
    Here every corner point of every tiling gets the same exemplar
    neighbourhood instead: around an exemplar point drawn with ``rng`` (an
    element's centre, inside the exemplar by at least half a side), every
    element whose box comes within ``radius`` of it along both axes,
    including the elements straddling the point, cut by the two lines
    through it (the second cut ``ordered``, so the four pieces agree on
    the shared cut vertices; the point is nudged by 0.003 to 0.009 where a
    vertex would lie within :data:`PATCH_SNAP` of a line and be snapped into
    a sliver: the first of :data:`PATCH_NUDGES` that leaves no vertex that
    close, or else the one whose closest vertex is farthest).  A
    tile's corner gets the piece on its side of both lines; the strips are
    then pruned against the patch (``corner_patch`` of
    :func:`pick_strips`).  The corners of a tiling repeat (one corner
    colour, as in corner-based Wang tiles), the sides stay random.  This is
    not the paper's corner merge (strips overlapping at the corner with
    corresponding elements deformed together): the strips here hold only
    the elements crossing their line, so two strips' elements at a corner
    are different elements and cannot be merged.

    Returns
    -------
    CornerPatch

    Raises
    ------
    InputError
        No element centre lies far enough inside the exemplar.
    """
    labels, lo, hi = element_boxes(V, F)
    centre = 0.5 * (lo[:, :2] + hi[:, :2])
    inside = np.flatnonzero(((centre >= 0.5) & (centre <= np.asarray(size) - 0.5)).all(axis=1))
    if inside.size == 0:
        raise InputError("corner patch: no element lies half a tile inside the exemplar")
    centre0 = centre[int(inside[rng.integers(inside.size)])]
    # the cuts snap vertices within 1e-4 of a line onto it; a vertex that close
    # (of the element or of the first cut) leaves a sliver at the corner, so
    # the centre is nudged, by a few thousandths, until none is within PATCH_SNAP
    best = None
    for nudge in PATCH_NUDGES:
        p0 = centre0 + np.asarray(nudge)
        near = np.flatnonzero(((lo[:, :2] <= p0 + radius)
                               & (hi[:, :2] >= p0 - radius)).all(axis=1))
        keep = np.isin(labels, near)
        Fc = F[keep]
        used = np.unique(Fc)
        remap = np.full(len(V), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        Vc = V[used].copy()
        Vc[:, :2] -= p0
        Fc = remap[Fc]
        lab = np.searchsorted(near, labels[keep])
        west, east = split_by_plane(Vc, Fc, axis=0, value=0.0, snap=1e-4)
        pieces = {}
        for side, half in (("w", west), ("e", east)):
            south, north = split_by_plane(*half, axis=1, value=0.0, snap=1e-4, ordered=True)
            pieces["s" + side], pieces["n" + side] = south, north
        xy = np.abs(np.concatenate([Vp[:, :2] for Vp, _ in pieces.values()]))
        off = xy[xy != 0.0]
        gap = float(off.min()) if off.size else np.inf
        if best is None or gap > best[0]:
            best = (gap, p0, Vc, Fc, lab, near, pieces)
        if gap >= PATCH_SNAP:
            break
    _, p0, Vc, Fc, lab, near, pieces = best
    images = {}
    for along in (0, 1):
        P = _to_strip(Vc, (0.0, 0.0), along)
        start = corner_footprints(P, Fc, lab, len(near))
        P[:, 0] += 1.0
        far = corner_footprints(P, Fc, lab, len(near))
        images[along] = {"above_start": start["above_start"],
                         "below_start": start["below_start"],
                         "above_far": far["above_far"], "below_far": far["below_far"]}
    return CornerPatch(pieces, images[0], images[1], (float(p0[0]), float(p0[1])))


def empty_strip(along: int) -> Strip:
    """A strip with no element: its sides are crossed by nothing (a directional set's ridge).

    Parameters
    ----------
    along : int
        Exemplar axis it stands for (0 = x, 1 = y); recorded only.

    Returns
    -------
    Strip
    """
    none = (np.zeros((0, 3), dtype=np.float64), np.zeros((0, 3), dtype=np.int64))
    corners = corner_footprints(none[0], none[1], np.zeros(0, dtype=np.int64), 0)
    return Strip(none, none, (float("nan"), float("nan")), int(along),
                 np.zeros((0, 4), dtype=np.float64), corners)


def element_boxes(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Element (connected component) of every face and each element's bounding box.

    Returns
    -------
    labels : numpy.ndarray, (m,) int64
    lo, hi : numpy.ndarray, (E, 3) float64
    """
    n, labels = face_components(F, len(V))
    vlab = np.full(len(V), -1, dtype=np.int64)
    vlab[F[:, 0]], vlab[F[:, 1]], vlab[F[:, 2]] = labels, labels, labels
    lo, hi = group_boxes(V, vlab, n)
    return labels, lo, hi


def largest_footprint(lo: np.ndarray, hi: np.ndarray) -> float:
    """Width of the widest element footprint, checked against the tile size.

    Raises
    ------
    InputError
        Elements too large for a unit tile (an element crossing a side must
        fit between the tile corners with room to spare).
    """
    width = float(np.max(hi[:, :2] - lo[:, :2]))
    if 0.5 * width + GAP > 0.4:
        raise InputError(f"exemplar elements are {width:.2f} wide; a tile is 1 x 1, so "
                         "elements must be under 0.76 wide (scale the exemplar down)")
    return width


def lattice_phase(lo: np.ndarray, hi: np.ndarray, pitch: float) -> tuple[float, float]:
    """Phase of the exemplar's element lattice of period ``pitch`` in x and y.

    The element centres (of their boxes) taken modulo ``pitch``; the phase is
    the circular mean of the largest cluster (the centres within
    ``pitch / 5`` of the centre with most such neighbours, on the torus).

    Parameters
    ----------
    lo, hi : numpy.ndarray, (E, 3) float64
        Element bounding boxes.
    pitch : float

    Returns
    -------
    tuple of 2 float
        ``(phase_x, phase_y)`` in ``[0, pitch)``.
    """
    c = (0.5 * (lo[:, :2] + hi[:, :2])) % pitch
    d = np.abs(c[:, None, :] - c[None, :, :])
    d = np.minimum(d, pitch - d)
    close = np.hypot(d[..., 0], d[..., 1]) < pitch / 5
    members = close[int(np.argmax(close.sum(axis=1)))]
    z = np.exp(2j * np.pi * c[members] / pitch).mean(axis=0)
    phase = (np.angle(z) / (2 * np.pi) * pitch) % pitch
    return float(phase[0]), float(phase[1])


def _to_strip(P: np.ndarray, origin, along: int) -> np.ndarray:
    """Exemplar points -> strip coordinates (a rotation, never a mirror)."""
    d = P[..., :2] - np.asarray(origin)
    out = np.array(P, dtype=np.float64)
    if along == 0:
        out[..., 0], out[..., 1] = d[..., 0], d[..., 1]
    else:
        out[..., 0], out[..., 1] = d[..., 1], 0.0 - d[..., 0]
    return out


def from_strip(P: np.ndarray, origin, along: int) -> np.ndarray:
    """Strip coordinates ``(t, s, w)`` -> exemplar points (inverse of the strip's rotation).

    Parameters
    ----------
    P : numpy.ndarray, (..., 3) float64
        Points in the coordinates of a strip (:class:`Strip`).
    origin : tuple of 2 float
        The strip's ``origin``.
    along : int
        The strip's ``along`` (0 = x, 1 = y).

    Returns
    -------
    numpy.ndarray, (..., 3) float64
        A new array; ``w`` is kept as the height.
    """
    out = np.array(P, dtype=np.float64)
    t, s = out[..., 0].copy(), out[..., 1].copy()
    if along == 0:
        out[..., 0], out[..., 1] = t + origin[0], s + origin[1]
    else:
        out[..., 0], out[..., 1] = origin[0] - s, origin[1] + t
    return out


CORNER_WINDOW = 0.5   # extent (tile units) of the corner quadrant images
QUADRANTS = (("above_start", "below_start"), ("below_start", "below_far"),
             ("below_far", "above_far"), ("above_far", "above_start"))


def corner_footprints(Vs: np.ndarray, Fs: np.ndarray, labels: np.ndarray, k: int
                      ) -> dict:
    """Half-footprints of a strip's elements near its two ends, as quadrant images.

    Parameters
    ----------
    Vs : numpy.ndarray, (n, 3) float64
        Strip elements in strip coordinates ``(t, s, w)``.
    Fs : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
        Element (``0..k-1``) of every face.
    k : int
        Number of elements.

    Returns
    -------
    dict
        ``above_start``, ``below_start``, ``above_far``, ``below_far``: pairs
        ``(low, high)`` of float arrays ``(k, n, n)`` over
        ``[0, CORNER_WINDOW]^2`` with axes (distance from the strip end along
        ``t``, distance from the cut line): the lowest and highest height of
        the faces of each element at the centre of each pixel (``+inf`` / ``-inf`` where
        the element is absent). The vertical cut makes a half's footprint the
        element's footprint on its side of the line.
    """
    n = int(round(CORNER_WINDOW / PIXEL))
    t, s = Vs[:, 0], Vs[:, 1]
    maps = {"above_start": (t, s), "below_start": (t, -s),
            "above_far": (1.0 - t, s), "below_far": (1.0 - t, -s)}
    out = {}
    for key, (a, b) in maps.items():
        low = np.full((k, n, n), np.inf)
        high = np.full((k, n, n), -np.inf)
        if len(Fs):
            P = np.c_[a, b, Vs[:, 2]]
            ii, jj, f = footprint_pixels(P, Fs, pixel=PIXEL, shape=(n, n))
            z = pixel_heights(P, Fs, ii, jj, f, pixel=PIXEL)
            np.minimum.at(low, (labels[f], ii, jj), z)
            np.maximum.at(high, (labels[f], ii, jj), z)
        out[key] = (low, high)
    return out


def corner_conflicts(x: dict, y: dict) -> np.ndarray:
    """Element pairs of strip ``x`` (horizontal side) and ``y`` (vertical side) that collide.

    Two halves collide when, at some pixel of a corner quadrant (``x``'s
    images grown by a pixel), both are present and their height ranges
    overlap or come closer than :data:`CLEAR`; elements that only overlap in
    projection, one above the other (overlapping scales), do not.

    Parameters
    ----------
    x, y : dict
        :func:`corner_footprints` of the two strips.

    Returns
    -------
    numpy.ndarray, (kx, ky) bool
        True when the two elements' halves may touch in a quadrant of a
        corner where ``x`` runs along the horizontal side and ``y`` along the
        vertical one.
    """
    kx, ky = len(x["above_start"][0]), len(y["above_start"][0])
    out = np.zeros((kx, ky), dtype=bool)
    if kx == 0 or ky == 0:
        return out
    for kx_key, ky_key in QUADRANTS:
        xl, xh = grown_heights(*x[kx_key])
        yl = y[ky_key][0].transpose(0, 2, 1)
        yh = y[ky_key][1].transpose(0, 2, 1)
        both = np.isfinite(xl).any(axis=0) & np.isfinite(yl).any(axis=0)
        if not both.any():
            continue
        xl, xh, yl, yh = xl[:, both], xh[:, both], yl[:, both], yh[:, both]
        touch = (np.maximum(xl[:, None], yl[None]) <= np.minimum(xh[:, None], yh[None]) + CLEAR)
        out |= touch.any(axis=2)
    return out


def lattice_corner(lo: np.ndarray, hi: np.ndarray, pitch: float, phase) -> tuple[float, float]:
    """Lattice phase moved so that tile corners straddle the fewest elements.

    Of the phase and its shifts by half a pitch in x, y or both, the one whose
    lattice points lie inside the fewest element boxes (ties: most elements
    crossing the lines through those points, then this order).

    Returns
    -------
    tuple of 2 float
    """
    best = None
    for k, (dx, dy) in enumerate(((0.5, 0.0), (0.0, 0.5), (0.0, 0.0), (0.5, 0.5))):
        px = (phase[0] + dx * pitch) % pitch
        py = (phase[1] + dy * pitch) % pitch
        # offsets of the box corners from the nearest lattice line below them
        bx = np.floor((hi[:, 0] - px) / pitch) > np.floor((lo[:, 0] - px) / pitch)
        by = np.floor((hi[:, 1] - py) / pitch) > np.floor((lo[:, 1] - py) / pitch)
        key = (int((bx & by).sum()), -int((bx | by).sum()), k)
        if best is None or key < best[0]:
            best = (key, (float(px), float(py)))
    return best[1]


def pick_strips(V: np.ndarray, F: np.ndarray, size, *, count: int, along: int,
                rng: np.random.Generator, taken=(), lattice=None,
                chosen_before=(), meets_itself: bool = True,
                corner_patch: CornerPatch | None = None, band: float = 0.0
                ) -> tuple[list[Strip], set]:
    """Choose ``count`` distinct edge strips from an exemplar.

    Every candidate segment keeps its crossing elements that stay
    :data:`CLEAR` inside the segment's end lines, minus those that would
    collide at a tile corner with themselves (``meets_itself``) or with any
    strip that can meet them there chosen before
    (:func:`corner_conflicts`, both ways round): of the sets of elements
    that collide nowhere, the one covering most (as below) is kept
    (:data:`EXACT`). Of the :data:`SHORTLIST` candidates covering
    most of the segment, the one whose kept elements cover most (the
    :data:`END` parts near the tile corners counted twice) is taken, then the
    next colour is picked the same way against all strips so far.

    Parameters
    ----------
    V, F : numpy.ndarray
        Exemplar mesh; elements are its connected components.
    size : tuple of 2 float
        Exemplar extent.
    count : int
        Number of colours to make.
    along : int
        Exemplar axis the segments run along (0 = x, 1 = y).
    rng : numpy.random.Generator
    taken : iterable of frozenset
        Element sets already used by other strips; not reused.
    lattice : tuple (pitch, phase_x, phase_y), optional
        Segments start only on the exemplar's lattice points
        ``phase + (i, j) pitch`` (see :func:`lattice_phase`,
        :func:`lattice_corner`); otherwise anywhere.
    chosen_before : sequence of Strip
        Strips of other classes; the new strips must not collide with them at
        any corner.
    meets_itself : bool
        Whether strips of this class meet each other (and themselves) at a
        tile corner, one along the horizontal side and one along the vertical
        side: only in an isotropic set, where one class serves every side.
        Otherwise a corner pairs strips of two different classes, and the new
        strips are checked against ``chosen_before`` only.
    corner_patch : CornerPatch, optional
        The patch every tile corner holds (:func:`corner_patch`); elements
        that would collide with it at a corner go too (a planar set: strips
        along ``x`` on horizontal sides, along ``y`` on vertical ones).

    Returns
    -------
    strips : list of Strip
    used : set of frozenset
        ``taken`` plus the element sets of the new strips.

    Raises
    ------
    InputError
        Exemplar shorter than a tile along ``along``, or too few distinct strips.
    """
    labels, lo, hi = element_boxes(V, F)
    lx, ly = size
    span = (lx, ly)[along]
    if span < 1.0:
        raise InputError(f"exemplar is {span:g} long along {'xy'[along]}; an edge strip "
                         "needs at least one tile length (1.0)")
    width = (ly, lx)[along]
    half = 0.5 * float(np.max(hi[:, :2] - lo[:, :2]))
    if lattice is None:
        a0 = rng.uniform(0.0, span - 1.0, CANDIDATES)
        a1 = rng.uniform(half, width - half, CANDIDATES)
    else:
        p, ph_along, ph_across = lattice[0], lattice[1 + along], lattice[2 - along]
        k = np.arange(np.ceil(-ph_along / p), np.floor((span - 1.0 - ph_along) / p) + 1)
        j = np.arange(np.ceil((half - ph_across) / p),
                      np.floor((width - half - ph_across) / p) + 1)
        K, J = np.meshgrid(k, j, indexing="ij")
        pick = rng.permutation(K.size)[:CANDIDATES]
        a0 = ph_along + K.ravel()[pick] * p
        a1 = ph_across + J.ravel()[pick] * p
    origin = np.stack([a0, a1], 1) if along == 0 else np.stack([a1, a0], 1)
    if band > 0 and lattice is None and chosen_before:
        origin = _in_phase(origin, lo, hi, [st.origin for st in chosen_before], rng,
                           np.array([0.0, half] if along == 0 else [half, 0.0]),
                           np.array([span - 1.0, width - half] if along == 0
                                    else [width - half, span - 1.0]))
    t0, s0, t1, s1, crossing = _segment_boxes(lo, hi, origin, along)
    cover = np.where(crossing, t1 - t0, 0.0).sum(axis=1)
    rank = cover
    if band > 0 and chosen_before:
        # shortlist candidates whose corners lie on those of the strips before
        match = np.zeros(len(cover))
        for c in np.flatnonzero(cover > 0):
            b = np.stack([t0[c], s0[c], t1[c], s1[c]], 1)
            mine = np.r_[b[crossing[c]], b[np.concatenate(_band_of(b, band))]]
            match[c] = _correspondences(mine, list(chosen_before), along, False)
        rank = cover + MATCH_BONUS * match
    order = [int(c) for c in np.argsort(-rank, kind="stable") if cover[c] > 0]
    strips: list[Strip] = []
    used = set(taken)
    before = list(chosen_before)
    while len(strips) < count:
        # the best SHORTLIST candidates after pruning, by covered length with
        # the parts near the segment ends counted twice
        best = None
        for c in order[:SHORTLIST]:
            cand = np.flatnonzero(crossing[c])
            a, b = t0[c, cand], t1[c, cand]
            value = (b - a + np.clip(np.minimum(b, END), 0, None)
                     - np.clip(np.minimum(a, END), 0, None)
                     + np.clip(np.maximum(b, 1 - END), None, 1)
                     - np.clip(np.maximum(a, 1 - END), None, 1))
            members = _without_corner_conflicts(V, F, labels, cand, tuple(origin[c]), along,
                                                before + strips if meets_itself else before,
                                                own=meets_itself, value=value,
                                                patch=corner_patch)
            key = frozenset(members.tolist())
            if not key or key in used:
                continue
            score = float(value[np.isin(cand, members)].sum())
            if band > 0:
                # the paper's "pick them so that the overlaps hold corresponding
                # elements": a bonus per element pair lying on each other at a corner
                mine = np.stack([t0[c], s0[c], t1[c], s1[c]], 1)
                mine = np.r_[mine[members], mine[np.concatenate(_band_of(mine, band))]]
                score += MATCH_BONUS * _correspondences(mine, before + strips if meets_itself
                                                        else before, along, meets_itself)
            if best is None or score > best[0]:
                best = (score, c, key)
        if best is None:
            break
        _, c, key = best
        order.remove(c)
        used.add(key)
        boxes = np.stack([t0[c], s0[c], t1[c], s1[c]], 1)
        ends = _band_of(boxes, band) if band > 0 else None
        strips.append(_make_strip(V, F, labels, sorted(key), tuple(origin[c]), along,
                                  boxes[sorted(key)], ends, boxes))
    if len(strips) < count:
        raise InputError(f"the exemplar has only {len(strips)} distinct edge strips along "
                         f"{'xy'[along]} for {count} colours; use fewer colours, a larger "
                         "exemplar or a larger quilted source (quilted_source, "
                         "--quilted-source)")
    return strips, used


def _segment_boxes(lo, hi, origin, along):
    """Element boxes in the strip coordinates of every candidate segment, and which cross it.

    Parameters
    ----------
    lo, hi : numpy.ndarray, (E, 3) float64
        Element bounding boxes.
    origin : numpy.ndarray, (c, 2) float64
        Segment starts in the exemplar.
    along : int

    Returns
    -------
    t0, s0, t1, s1 : numpy.ndarray, (c, E) float64
    crossing : numpy.ndarray, (c, E) bool
        The element crosses the segment's line and stays :data:`CLEAR`
        inside its end lines.
    """
    if along == 0:
        t0 = lo[None, :, 0] - origin[:, 0:1]
        t1 = hi[None, :, 0] - origin[:, 0:1]
        s0 = lo[None, :, 1] - origin[:, 1:2]
        s1 = hi[None, :, 1] - origin[:, 1:2]
    else:
        t0 = lo[None, :, 1] - origin[:, 1:2]
        t1 = hi[None, :, 1] - origin[:, 1:2]
        s0 = origin[:, 0:1] - hi[None, :, 0]
        s1 = origin[:, 0:1] - lo[None, :, 0]
    crossing = (s0 < -GAP / 4) & (s1 > GAP / 4) & (t0 >= CLEAR) & (t1 <= 1.0 - CLEAR)
    return t0, s0, t1, s1, crossing


def distinct_segments(lo: np.ndarray, hi: np.ndarray, size, *, along: int,
                      grid: int = SEGMENT_GRID) -> int:
    """How many distinct edge strips the exemplar offers along an axis, before pruning.

    The unit segments along ``along`` that :func:`pick_strips` draws its
    candidates from (start anywhere along the axis, the line at least half
    the widest element inside the exemplar across it) are laid on a regular
    ``grid x grid`` lattice of starts, and the distinct non-empty sets of
    elements crossing them (as :func:`pick_strips` counts crossing) are
    counted.  Deterministic (no random draw).

    Parameters
    ----------
    lo, hi : numpy.ndarray, (E, 3) float64
        Element bounding boxes (:func:`element_boxes`).
    size : tuple of 2 float
        Exemplar extent.
    along : int
        Exemplar axis (0 = x, 1 = y).
    grid : int
        Segment starts per direction.

    Returns
    -------
    int
        0 when the exemplar is shorter than a tile along ``along`` or has no
        room across it.
    """
    span, width = (size[0], size[1]) if along == 0 else (size[1], size[0])
    half = 0.5 * float(np.max(hi[:, :2] - lo[:, :2])) if len(lo) else 0.0
    if span < 1.0 or width < 2.0 * half or not len(lo):
        return 0
    a0 = np.linspace(0.0, span - 1.0, grid)
    a1 = np.linspace(half, width - half, grid)
    A0, A1 = np.meshgrid(a0, a1, indexing="ij")
    origin = (np.stack([A0.ravel(), A1.ravel()], 1) if along == 0
              else np.stack([A1.ravel(), A0.ravel()], 1))
    crossing = _segment_boxes(lo, hi, origin, along)[4]
    rows = np.unique(crossing[crossing.any(axis=1)], axis=0)
    return int(len(rows))


def _without_corner_conflicts(V, F, labels, members, origin, along, others, own=True,
                              value=None, patch=None):
    """The elements of ``members`` to keep so that the strip collides at no corner.

    An element colliding with a strip of ``others`` (either way round) goes;
    with ``own`` (the strip along both sides through a corner), so does an
    element colliding with itself, and of two colliding elements at most one
    stays. Among the sets left, the one of largest total ``value`` (one per
    member; default 1) is kept: found exactly when at most :data:`EXACT`
    elements are in play, otherwise by dropping the element with most
    collisions until none is left.
    """
    keep = np.isin(labels, members)
    face_el = np.searchsorted(members, labels[keep])
    Vs = _to_strip(V, origin, along)
    imgs = corner_footprints(Vs, F[keep], face_el, len(members))
    n = len(members)
    value = np.ones(n) if value is None else np.asarray(value, dtype=np.float64)
    clash = np.zeros((n, n), dtype=bool)
    if own and n:
        clash = corner_conflicts(imgs, imgs)
        clash = clash | clash.T
    banned = np.diag(clash).copy()
    for other in others:
        banned |= corner_conflicts(imgs, other.corners).any(axis=1)
        banned |= corner_conflicts(other.corners, imgs).any(axis=0)
    if patch is not None and n:
        # the patch meets a strip along x as the end of a vertical strip, and
        # one along y as the end of a horizontal strip
        banned |= (corner_conflicts(imgs, patch.as_y).any(axis=1) if along == 0
                   else corner_conflicts(patch.as_x, imgs).any(axis=0))
    free = np.flatnonzero(~banned)
    m = len(free)
    if m <= EXACT:
        pick = (np.arange(2 ** m)[:, None] >> np.arange(m)[None, :]) & 1 == 1
        sub = clash[np.ix_(free, free)]
        bad = (pick[:, :, None] & pick[:, None, :] & sub[None]).any(axis=(1, 2))
        score = np.where(bad, -np.inf, pick @ value[free])
        return members[free[pick[int(np.argmax(score))]]]
    alive = ~banned
    while alive.any():
        hits = (clash[np.ix_(alive, alive)]).sum(axis=1)
        if not hits.any():
            break
        alive[np.flatnonzero(alive)[int(np.argmax(hits))]] = False
    return members[alive]


def _make_strip(V, F, labels, members, origin, along, boxes, ends=None,
                all_boxes=None) -> Strip:
    keep = np.isin(labels, members)
    Fs = F[keep]
    used = np.unique(Fs)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    Vs = _to_strip(V[used], origin, along)
    corners = corner_footprints(Vs, remap[Fs], np.searchsorted(members, labels[keep]),
                                len(members))
    below, above = split_by_plane(Vs, remap[Fs], axis=1, value=0.0, snap=1e-4)
    band = band_boxes = None
    if ends is not None:
        band = tuple(_element_subset(V, F, labels, sel, origin, along) for sel in ends)
        band_boxes = all_boxes[np.concatenate(ends)]
    return Strip(below, above, tuple(float(o) for o in origin), along, boxes, corners, band,
                 band_boxes)


def _in_phase(origin, lo, hi, others, rng, lo_bound, hi_bound) -> np.ndarray:
    """Candidate origins, every second one moved in phase with a strip chosen before.

    The paper picks strips "so that the overlaps hold corresponding
    elements".  An exemplar repeats (nearly) where a translation maps one
    element onto another, so a candidate starting at another strip's origin
    moved by the offset between the element nearest that origin and a random
    element sees the same neighbourhood at the corners, wherever the
    exemplar has that translation as a (near) period.  Moved origins outside
    ``[lo_bound, hi_bound]`` keep their random draw.
    """
    centre = 0.5 * (lo[:, :2] + hi[:, :2])
    O = np.asarray([o for o in others if np.isfinite(o).all()], dtype=np.float64)
    if not len(O):
        return origin
    m = len(origin) // 2
    which = O[rng.integers(len(O), size=m)]
    near = np.argmin(((which[:, None, :] - centre[None]) ** 2).sum(axis=2), axis=1)
    moved = which + centre[rng.integers(len(centre), size=m)] - centre[near]
    ok = ((moved >= lo_bound) & (moved <= hi_bound)).all(axis=1)
    out = origin.copy()
    out[1::2][:m][ok] = moved[ok]
    return out


def _band_of(boxes: np.ndarray, band: float) -> tuple[np.ndarray, np.ndarray]:
    """Band elements (below, above the line) among element boxes ``(t0, s0, t1, s1)``."""
    t0, s0, t1, s1 = boxes.T
    inside = (t0 >= CLEAR) & (t1 <= 1.0 - CLEAR) & ((t0 < band) | (t1 > 1.0 - band))
    return (np.flatnonzero(inside & (s1 <= -CLEAR) & (s0 >= -band)),
            np.flatnonzero(inside & (s0 >= CLEAR) & (s1 <= band)))


def _quadrant_boxes(boxes: np.ndarray, key: str) -> np.ndarray:
    """Element boxes in a corner quadrant image's coordinates (see :func:`corner_footprints`).

    ``(a0, b0, a1, b1)``: distance from the strip end along ``t``, distance
    from the line on the key's side (clipped at the line: the half there);
    boxes with nothing on that side within :data:`CORNER_WINDOW` of the end
    are left out.
    """
    t0, s0, t1, s1 = boxes.T
    a0, a1 = (t0, t1) if key.endswith("start") else (1.0 - t1, 1.0 - t0)
    b0, b1 = (s0, s1) if key.startswith("above") else (-s1, -s0)
    keep = (b1 > 0) & (a0 < CORNER_WINDOW)
    return np.stack([a0, np.maximum(b0, 0.0), a1, b1], 1)[keep]


def corner_correspondences(x: np.ndarray, y: np.ndarray) -> int:
    """Element pairs of two strips that lie on each other at a tile corner.

    Strip ``x`` along a horizontal side, ``y`` along a vertical one (their
    element boxes, crossing and band elements); in every quadrant
    (:data:`QUADRANTS`) the footprints of ``x``'s elements and the
    transposed ones of ``y``'s are compared, and a pair counts when every
    box side of one lies within a quarter of the pair's narrow width of the
    other's (the shift :func:`geotex.quilting.merge.merge_elements` accepts
    for corresponding elements).

    Parameters
    ----------
    x, y : numpy.ndarray, (k, 4) float64
        Boxes ``(t0, s0, t1, s1)`` in strip coordinates.

    Returns
    -------
    int
    """
    count = 0
    for kx, ky in QUADRANTS:
        X = _quadrant_boxes(x, kx)
        Y = _quadrant_boxes(y, ky)[:, [1, 0, 3, 2]]
        if not len(X) or not len(Y):
            continue
        wx = np.minimum(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
        wy = np.minimum(Y[:, 2] - Y[:, 0], Y[:, 3] - Y[:, 1])
        diff = np.abs(X[:, None, :] - Y[None, :, :]).max(axis=2)
        count += int((diff <= 0.25 * np.minimum(wx[:, None], wy[None, :])).sum())
    return count


def _correspondences(mine: np.ndarray, others, along: int, own: bool) -> int:
    """:func:`corner_correspondences` of a candidate strip with the strips it meets."""
    def boxes(st):
        return st.boxes if st.band_boxes is None else np.r_[st.boxes, st.band_boxes]
    total = corner_correspondences(mine, mine) if own else 0
    for other in others:
        theirs = boxes(other)
        if own or along == 0:
            total += corner_correspondences(mine, theirs)
        if own or along == 1:
            total += corner_correspondences(theirs, mine)
    return total


def _element_subset(V, F, labels, members, origin, along):
    """The whole elements ``members`` of the exemplar, in strip coordinates."""
    Vk, Fk = compacted(V, F[np.isin(labels, members)])
    return _to_strip(Vk, origin, along), Fk
