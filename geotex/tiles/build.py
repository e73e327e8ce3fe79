"""Build a geometric Wang tile set from an exemplar.

Steps (``../shared/DESIGN.md`` §5.3): one edge strip per colour of every axis
class (:mod:`geotex.tiles.strips`); for each tile the four strip halves of its
side colours form its frame (:mod:`geotex.tiles.frame`); the interior is then
synthesized around the frame by constrained mesh quilting
(:func:`interior_quilt`, the default) or filled with whole exemplar elements
(:func:`interior_paste`, fast); last, corner squares left emptier than the
rest of the tile get more exemplar elements
(:func:`geotex.tiles.fill.fill_corners`, sets without a lattice).

An *isotropic* set uses one colour class for all three axes: the strips are
cut once per colour and serve the sides of every class, so a side of colour
``c`` is seamless with any other side of colour ``c``. It holds the
``n^4`` tiles of group (0, 1) and covers a closed polycube when the group is
ignored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import GeotexError, InputError
from geotex.exemplars import exemplar as make
from geotex.mesh.topology import compacted
from geotex.progress import report
from geotex.quilting import coverage_fraction, quilt_texture, split_elements
from geotex.tiles.colors import COMPLETE_GROUPS, PLANAR_GROUPS, parse_colors, tile_keys
from geotex.tiles.corners import BAND, corner_merged_frame, merge_totals
from geotex.tiles.fill import ExemplarPixels, fill_corners, fill_gaps
from geotex.tiles.frame import concatenated, frame_of
from geotex.tiles.periodic import periodic_tileset
from geotex.tiles.source import quilted_texture, source_side, strips_along
from geotex.tiles.strips import (GAP, element_boxes, empty_strip, largest_footprint,
                                 lattice_corner, lattice_phase, pick_strips)
from geotex.tiles.strips import corner_patch as cut_corner_patch
from geotex.tiles.tileset import TileSet, tile_rng
from geotex.tiles.verify import side_boundaries

__all__ = ["build_tileset", "plan_tileset", "PlannedSet", "built_tile", "tile_rng", "TilePlan",
           "interior_quilt",
           "interior_paste", "INTERIOR_METHODS", "BUILD_STAGES", "Source"]

INTERIOR_METHODS = ("quilt", "paste", "periodic")
BUILD_STAGES = ("strips", "tiles")
QUILT_WINDOW = 2.0           # side of the exemplar window a tile is quilted from
QUILT_ATTEMPTS = 3           # quilting tries per tile before the paste fallback
CLEAR = 0.5 * GAP            # clearance of interior elements from the tile sides
OVERSIZE = 0.2               # merged elements this much (x largest element) larger are undone
STRIP_AXIS = {0: 0, 1: 1, 2: 0}   # class -> exemplar axis its strips run along


@dataclass(frozen=True)
class Source:
    """An exemplar split into elements, as the builders use it.

    Attributes
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
        Element of every face.
    lo, hi : numpy.ndarray, (E, 3) float64
        Element bounding boxes.
    size : tuple of 2 float
        Exemplar extent ``(lx, ly)``.
    params : dict
        Exemplar parameters (``pitch`` sets the quilting cell when present).
    """

    V: np.ndarray
    F: np.ndarray
    labels: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    size: tuple
    params: dict

    def window(self, origin, extent) -> tuple[np.ndarray, np.ndarray]:
        """The elements lying wholly in the rectangle ``origin + [0, extent]``, moved to 0.

        Returns
        -------
        V : numpy.ndarray, (n, 3) float64
        F : numpy.ndarray, (m, 3) int64
        """
        o = np.asarray(origin, dtype=np.float64)
        inside = ((self.lo[:, :2] >= o) & (self.hi[:, :2] <= o + np.asarray(extent))
                  ).all(axis=1)
        return _subset(self.V, self.F, inside[self.labels], shift=np.r_[o, 0.0])


def _subset(V, F, keep_faces, shift=None):
    Vk, Fk = compacted(V, F[keep_faces])
    return (Vk, Fk) if shift is None else (Vk - shift, Fk)


def _exemplar_arrays(exemplar):
    """(Source, height, depth, recipe) of an exemplar object or name."""
    if isinstance(exemplar, str):
        exemplar = make(exemplar)
    try:
        V = np.asarray(exemplar.vertices, dtype=np.float64)
        F = np.asarray(exemplar.faces, dtype=np.int64)
        size = tuple(float(s) for s in exemplar.size)
    except AttributeError:
        raise InputError("exemplar: expected an Exemplar (vertices, faces, size) or a "
                         "catalog name") from None
    if len(F) == 0:
        raise InputError("exemplar has no faces")
    depth = float(getattr(exemplar, "depth", max(0.0, -V[:, 2].min())))
    params = dict(getattr(exemplar, "params", {}) or {})
    recipe = {"name": getattr(exemplar, "name", ""), "params": params}
    labels, lo, hi = element_boxes(V, F)
    return Source(V, F, labels, lo, hi, size, params), float(V[:, 2].max()), depth, recipe


def interior_paste(src: Source, frame, rng: np.random.Generator, *, pixels=None,
                   lattice=None) -> tuple[tuple[np.ndarray, np.ndarray], dict]:
    """Fill a tile interior with whole exemplar elements that fit between the frame's.

    Elements of random unit windows of the exemplar join where their
    footprint, grown by :data:`~geotex.tiles.strips.GAP`, is free
    (:func:`geotex.tiles.fill.fill_gaps`). They are copied unchanged, so they
    stay closed; the frame is not touched.

    Parameters
    ----------
    src : Source
        The exemplar.
    frame : tuple of (V (n, 3) float64, F (m, 3) int64)
        The tile frame.
    rng : numpy.random.Generator
    pixels : ExemplarPixels, optional
        The exemplar's footprint rasters (built when not given).
    lattice : tuple (pitch, phase_x, phase_y), optional
        Windows on the exemplar's lattice points only.

    Returns
    -------
    tile : tuple of (V, F)
        Frame plus the added elements, in tile coordinates.
    stats : dict
        ``elements`` added.
    """
    pixels = pixels or ExemplarPixels(src.V, src.F, src.labels, src.lo, src.hi)
    added, count = fill_gaps(frame[0], frame[1], pixels, src.size, rng, lattice=lattice)
    return concatenated([frame, added]), {"elements": count}


def interior_quilt(src: Source, frame, frame_boxes: np.ndarray, rng: np.random.Generator,
                   *, window: float = QUILT_WINDOW, attempts: int = QUILT_ATTEMPTS,
                   best_of: int = 1, lattice=None
                   ) -> tuple[tuple[np.ndarray, np.ndarray] | None, dict]:
    """Synthesize a tile around its frame by constrained mesh quilting.

    The tile ``[0, 1]^2`` is the quilting domain of
    :func:`geotex.quilting.quilt_texture`; the frame is its prefilled geometry
    (open only along the tile sides, so its cut vertices are fixed and come
    back bit-exact) and the frame footprints count as occupied. Copies come
    from a random ``window x window`` part of the exemplar (smaller matching
    problems, and every tile draws from a different part). The result is
    accepted only when, after rounding to float32, its open boundary on every
    side is bit-identical to the frame's, every element is a valid solid,
    no vertex leaves the tile, and interior elements keep :data:`CLEAR` from
    the sides (those that do not are dropped); otherwise quilting is retried
    with another seed, ``attempts`` times in all. With ``best_of`` above 1,
    quilting goes on after the first accepted result until ``best_of``
    results were accepted (or the attempts are used up), and the one
    covering most of the tile is kept (the first of equals).

    Parameters
    ----------
    src : Source
    frame : tuple of (V (n, 3) float64, F (m, 3) int64)
        The tile frame (:func:`geotex.tiles.frame.frame_of`).
    frame_boxes : numpy.ndarray, (k, 4) float64
        Its element footprints.
    rng : numpy.random.Generator
    window : float
        Side of the exemplar window copies are taken from.
    attempts : int
        Quilting tries.
    best_of : int
        Accepted results to choose the densest from (1: the first accepted).
    lattice : tuple (pitch, phase_x, phase_y), optional
        Take windows only at the exemplar's lattice points, so that copies
        (placed at multiples of the pitch) stay on the tile's lattice.

    Returns
    -------
    tile : tuple of (V, F) or None
        The whole tile (frame, possibly merged with copies, plus the interior),
        or None when no attempt was accepted.
    stats : dict
        ``elements``, ``attempts``, ``merges`` (stitched + union),
        ``stitched`` and the quilting report's seam figures
        (``seam_gap_max`` relative to the cell, ``seam_normal_jump_mean``,
        ``seam_normal_jump_max`` in degrees; ``nan`` without stitches, and
        counting merges that were undone afterwards) and, on failure, the last
        ``problem``; ``attempts`` counts the tries made, ``accepted`` the
        results compared.
    """
    wx, wy = min(window, src.size[0]), min(window, src.size[1])
    pitch = src.params.get("pitch")
    cell = float(pitch) if isinstance(pitch, (int, float)) and 0 < pitch <= min(wx, wy) \
        else None

    Vf = frame[0].astype(np.float32).astype(np.float64)
    want, _ = side_boundaries(Vf, frame[1])
    # (a directional set's tile with four ridge sides has an empty frame)
    frame_elements = [(e.V, e.F) for e in split_elements(Vf, frame[1])] if len(frame[1]) \
        else []
    max_foot = float((src.hi - src.lo)[:, :2].max())
    occupied = np.clip(np.asarray(frame_boxes, dtype=np.float64).reshape(-1, 4), 0.0, 1.0)
    problem = "no attempt"
    best, accepted = None, 0
    for attempt in range(1, attempts + 1):
        origin = _window_origin(rng, src.size, (wx, wy), lattice)
        seed = int(rng.integers(2 ** 31))
        Vw, Fw = src.window(origin, (wx, wy))
        if len(Fw) == 0:
            problem = "empty exemplar window"
            continue
        try:
            res = quilt_texture(Vw, Fw, size=(wx, wy), out_size=(1.0, 1.0), cell=cell,
                                seed=seed, prefilled=frame, occupied=occupied)
        except GeotexError as exc:
            problem = f"quilting failed: {exc}"
            continue
        if not res.report.valid:
            problem = "quilting gave invalid elements: " + res.report.summary()
            continue
        tile, problem, changes = _accepted(res, want, frame_elements, max_foot)
        if tile is None:
            continue
        accepted += 1
        cover = coverage_fraction(tile[0], tile[1], (0.0, 0.0, 1.0, 1.0), resolution=100) \
            if best_of > 1 else 0.0
        if best is None or cover > best[0]:
            m = res.report.merges
            best = (cover, tile, {"elements": res.report.elements - changes["dropped"],
                                  "reverted": changes["reverted"],
                                  "dropped": changes["dropped"],
                                  "merges": int(m.get("stitched", 0) + m.get("union", 0)),
                                  "stitched": int(m.get("stitched", 0)),
                                  "seam_gap_max": res.report.seam_gap_max,
                                  "seam_normal_jump_mean": res.report.seam_normal_jump_mean,
                                  "seam_normal_jump_max": res.report.seam_normal_jump_max})
        if accepted >= best_of:
            break
    if best is None:
        return None, {"attempts": attempts, "problem": problem}
    return best[1], {**best[2], "attempts": attempt, "accepted": accepted}


def _window_origin(rng, size, extent, lattice):
    """Random origin of an ``extent`` window of the exemplar (on the lattice if given)."""
    room = np.maximum(np.asarray(size) - np.asarray(extent), 0.0)
    if lattice is None:
        return rng.uniform(0.0, 1.0, 2) * room
    p, phase = lattice[0], np.asarray(lattice[1:])
    top = np.maximum(np.floor((room - phase) / p), 0).astype(np.int64)
    k = np.array([rng.integers(0, top[0] + 1), rng.integers(0, top[1] + 1)])
    return np.minimum(phase + k * p, room)


def _accepted(res, want, frame_elements, max_foot):
    """Check a quilted tile (see :func:`interior_quilt`).

    Returns
    -------
    tile : tuple of (V, F) or None
    problem : str
    changes : dict
        ``dropped`` interior elements, ``reverted`` frame elements.
    """
    V = res.vertices.astype(np.float32).astype(np.float64)
    F, eids, fixed = res.faces, res.element_ids, res.fixed
    pre = np.asarray(res.element_prefilled, dtype=bool)
    k = len(pre)
    uv = V[F][:, :, :2]
    lo = np.full((k, 2), np.inf)
    hi = np.full((k, 2), -np.inf)
    np.minimum.at(lo, eids, uv.min(axis=1))
    np.maximum.at(hi, eids, uv.max(axis=1))
    if (lo < 0).any() or (hi > 1).any():
        return None, "an element leaves the tile", {}
    # distance of every element to the south, east, north, west side
    dist = np.stack([lo[:, 1], 1 - hi[:, 0], 1 - hi[:, 1], lo[:, 0]], 1)
    cut = np.zeros((k, 4), dtype=bool)          # sides an element is cut by (frame halves)
    vert_el = np.full(len(V), -1, dtype=np.int64)
    vert_el[F.ravel()] = np.repeat(eids, 3)
    fv = np.flatnonzero(fixed & (vert_el >= 0))
    for s, (axis, value) in enumerate(((1, 0.0), (0, 1.0), (1, 1.0), (0, 0.0))):
        cut[vert_el[fv[V[fv, axis] == value]], s] = True
    # merges of two elements that did not coincide look like two fused elements
    # (or a frame half cut back): undo them, frame elements go back to their
    # frame half (any merge changed them: vertex count or footprint box),
    # interior ones larger than the largest element by OVERSIZE go
    n_pre = int(pre.sum())
    if n_pre != len(frame_elements):
        return None, "frame elements were lost or split", {}
    grown = np.zeros(k, dtype=bool)             # frame elements changed by a merge
    n_vert = np.bincount(eids[np.unique(F.ravel(), return_index=True)[1] // 3],
                         minlength=k) if len(F) else np.zeros(k, dtype=np.int64)
    for i, (Ve, _) in enumerate(frame_elements):
        change = np.r_[Ve[:, :2].min(axis=0) - lo[i], hi[i] - Ve[:, :2].max(axis=0)]
        grown[i] = (np.abs(change).max() > OVERSIZE * max_foot
                    or n_vert[i] != len(Ve))
    oversized = ~pre & ((hi - lo).max(axis=1) > (1.0 + OVERSIZE) * max_foot)
    near = (dist < CLEAR) & ~cut
    if (near.any(axis=1) & pre & ~grown).any():
        return None, "a frame element grew within the side clearance", {}
    drop = ~pre & (near.any(axis=1) | oversized)
    on_side = ((V[:, :2] == 0.0) | (V[:, :2] == 1.0)).any(axis=1) & ~fixed & (vert_el >= 0)
    if (on_side & ~(drop | grown)[np.maximum(vert_el, 0)]).any():
        return None, "a vertex off the frame cut lies on a tile side", {}
    parts = []
    for i in range(k):
        if drop[i]:
            continue
        if grown[i]:
            parts.append(frame_elements[i])
        else:
            parts.append(_subset(V, F, eids == i))
    if grown.any():
        # the restored frame halves must not cut into elements placed beside the merge
        kept = np.flatnonzero(~drop)              # element of every part
        owner = np.concatenate([np.full(len(Fp), j) for j, (_, Fp) in enumerate(parts)])
        pairs = self_intersecting_pairs(*concatenated(parts))
        a, b = kept[owner[pairs[:, 0]]], kept[owner[pairs[:, 1]]]
        cross = (a != b) & (grown[a] | grown[b])
        other = np.unique(np.where(grown[a[cross]], b[cross], a[cross]))
        if pre[other].any():
            return None, "a restored frame element cuts another frame element", {}
        if other.size:
            drop[other] = True
            parts = [p for j, p in enumerate(parts) if not drop[kept[j]]]
    Vt, Ft = concatenated(parts)
    got, stray = side_boundaries(Vt, Ft)
    if stray or any(not np.array_equal(a, b) for a, b in zip(got, want)):
        return None, "the quilted tile's side boundaries differ from its frame's", {}
    return (Vt, Ft), "", {"dropped": int(drop.sum()), "reverted": int(grown.sum())}


def _band_height(corner_merge) -> float:
    """Strip band height ``h_E`` of the ``corner_merge`` option (0: no corner merge)."""
    if corner_merge is True:
        return BAND
    if corner_merge is False or corner_merge is None:
        return 0.0
    if isinstance(corner_merge, (int, float, np.integer, np.floating)) \
            and 0.0 < float(corner_merge) < 0.5:
        return float(corner_merge)
    raise InputError(f"corner_merge: True, False or a strip height between 0 and 0.5 tile, "
                     f"got {corner_merge!r}")


def _lattice(src: Source) -> tuple[float, float, float]:
    """``(pitch, phase_x, phase_y)`` of the exemplar lattice (``lattice=True``)."""
    p = src.params.get("pitch")
    if not isinstance(p, (int, float)) or not p > 0 or abs(1 / p - round(1 / p)) > 1e-9:
        raise InputError(f"lattice: needs an exemplar whose pitch divides the tile "
                         f"(1 / pitch a whole number), got pitch {p!r}")
    phase = lattice_phase(src.lo, src.hi, float(p))
    return (float(p),) + lattice_corner(src.lo, src.hi, float(p), phase)


@dataclass(frozen=True)
class TilePlan:
    """Everything one tile's interior is built from, once the strips are drawn.

    Attributes
    ----------
    src : Source
        The exemplar.
    frames : list of tuple ((V, F), boxes)
        Frame and frame element footprints of every tile
        (:func:`geotex.tiles.frame.frame_of`).
    interior : {"quilt", "paste"}
    lattice : tuple (pitch, phase_x, phase_y) or None
    seed : int
        The set seed; tile ``t`` uses :func:`tile_rng` of it.
    pixels : ExemplarPixels
        The exemplar's footprint rasters (:mod:`geotex.tiles.fill`).
    attempts : int
        Quilting tries per tile before the paste fallback (:func:`interior_quilt`).
    best_of : int
        Accepted quilts per tile to keep the densest of (:func:`interior_quilt`).
    """

    src: Source
    frames: list
    interior: str
    lattice: tuple | None
    seed: int
    pixels: object
    attempts: int = QUILT_ATTEMPTS
    best_of: int = 1


def built_tile(plan: TilePlan, t: int) -> tuple[tuple[np.ndarray, np.ndarray], dict]:
    """Tile ``t`` of a plan: its frame with the interior filled.

    Depends only on the plan and ``t`` (its own generator, :func:`tile_rng`),
    so the tiles of a set may be built in any order or in parallel.

    Parameters
    ----------
    plan : TilePlan
    t : int
        Tile index.

    Returns
    -------
    tile : tuple of (V (n, 3) float64, F (m, 3) int64)
    stats : dict
        ``coverage`` (covered fraction of the tile), ``pasted`` (1 when
        quilting was not accepted and the tile was pasted),
        ``corner_filled`` (elements :func:`geotex.tiles.fill.fill_corners`
        added to the corner squares; sets without a lattice), and for quilted
        tiles ``merges``, ``filled`` (gap-fill elements), ``stitched`` and the
        seam figures of :func:`interior_quilt`.
    """

    rng = tile_rng(plan.seed, t)
    src, grid = plan.src, plan.lattice
    frame, boxes = plan.frames[t]
    tile, stats = None, {"pasted": 0}
    if plan.interior == "quilt":
        tile, q = interior_quilt(src, frame, boxes, rng, lattice=grid,
                                 attempts=plan.attempts, best_of=plan.best_of)
        stats["merges"] = q.get("merges", 0)
        stats["stitched"] = q.get("stitched", 0)
        if stats["stitched"]:
            stats.update({k: q[k] for k in ("seam_gap_max", "seam_normal_jump_mean",
                                            "seam_normal_jump_max")})
        if tile is not None:
            added, count = fill_gaps(tile[0], tile[1], plan.pixels, src.size, rng,
                                     lattice=grid)
            tile = concatenated([tile, added])
            stats["filled"] = count
    if tile is None:
        stats["pasted"] = int(plan.interior == "quilt")
        tile, _ = interior_paste(src, frame, rng, pixels=plan.pixels, lattice=grid)
    if grid is None:
        added, stats["corner_filled"] = fill_corners(tile[0], tile[1], plan.pixels, rng)
        tile = concatenated([tile, added])
    stats["coverage"] = coverage_fraction(tile[0], tile[1], (0.0, 0.0, 1.0, 1.0),
                                          resolution=100)
    return tile, stats


@dataclass(frozen=True)
class PlannedSet:
    """A tile set drawn but not yet built: strips, frames and the plan of every tile.

    Attributes
    ----------
    plan : TilePlan
        What :func:`built_tile` fills the tiles from.
    strips : dict of int -> list of Strip
        Edge strips of every axis class (0, 1, 2; one list shared by all
        classes in an isotropic set), colour by colour.
    groups : numpy.ndarray, (T, 2) int64
    cols : numpy.ndarray, (T, 4) int64
        Axis classes and side colours (south, east, north, west) of every tile.
    n_colors : tuple of 3 int
    height, depth : float
        Exemplar relief height and base depth.
    recipe : dict
        Exemplar name and parameters.
    corner_merges : list of dict or None
        With ``corner_merge``: the :func:`geotex.tiles.corners.merged_corners`
        stats of every tile's frame.
    source : dict or None
        When the strips and interiors come from a texture quilted from the
        exemplar (``quilted_source``): the
        :func:`geotex.tiles.source.quilted_texture` stats (``side``,
        ``elements``, ``coverage``, ``placements``, ``auto``); None when they
        come from the exemplar itself.
    """

    plan: TilePlan
    strips: dict
    groups: np.ndarray
    cols: np.ndarray
    n_colors: tuple
    height: float
    depth: float
    recipe: dict
    corner_merges: list | None = None
    source: dict | None = None


def plan_tileset(exemplar, *, colors=2, planar: bool = False, isotropic: bool = False,
                 lattice: bool = False, seed: int = 0, interior: str = "quilt",
                 directional: bool = False, corner_patch: bool = False,
                 corner_merge: bool | float = False,
                 quilt_attempts: int = QUILT_ATTEMPTS, quilt_best_of: int = 1,
                 quilted_source="auto", progress=None) -> PlannedSet:
    """Draw the strips of a set and place them into the frame of every tile.

    The first half of :func:`build_tileset` (same options, same random
    draws): the strips come from ``default_rng(seed)``, the tiles are then
    independent (:func:`built_tile`). Useful to look at the stages of the
    paper's pipeline (strips, frame, interior; its Fig. 3).

    Returns
    -------
    PlannedSet

    Raises
    ------
    InputError
        As :func:`build_tileset` (not for ``interior="periodic"``, which has
        no strips).
    """
    if interior not in ("quilt", "paste"):
        raise InputError(f"interior: strips and frames are planned for 'quilt' or 'paste', "
                         f"got {interior!r}")
    if isotropic and planar:
        raise InputError("isotropic and planar exclude each other: an isotropic set is "
                         "already the n^4 tiles of the plane, usable on a closed polycube")
    if directional and isotropic:
        raise InputError("directional and isotropic exclude each other")
    if isinstance(exemplar, str):
        exemplar = make(exemplar)
    src, height, depth, recipe = _exemplar_arrays(exemplar)
    n_colors = parse_colors(colors, planar=planar or directional)
    if directional and n_colors[0] != n_colors[1]:
        raise InputError(f"colors: a directional set has one colour count for both strip "
                         f"classes, got {colors!r}")
    if isotropic and len(set(n_colors)) != 1:
        raise InputError(f"colors: an isotropic set has one colour count for all axes, got "
                         f"{colors!r}")
    for key, value in (("quilt_attempts", quilt_attempts), ("quilt_best_of", quilt_best_of)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InputError(f"{key}: a whole number of at least 1, got {value!r}")
    if corner_patch and (not planar or lattice or directional):
        # isotropic, complete and directional sets turn strips or tiles by
        # quarter turns: the patch would have to be symmetric
        raise InputError("corner_patch is for planar sets without a lattice")
    band = _band_height(corner_merge)
    if band and corner_patch:
        raise InputError("corner_merge and corner_patch exclude each other: the patch "
                         "replaces what the strips bring to a corner")
    largest_footprint(src.lo, src.hi)
    side = source_side(quilted_source, src.lo, src.hi, src.size,
                       strips_along(n_colors, isotropic=isotropic), lattice=lattice)
    source = None
    if side:
        # the paper's M_out: a larger texture quilted from the exemplar (geotex.tiles.source)
        Vq, Fq, source = quilted_texture(exemplar, side, seed)
        source["auto"] = isinstance(quilted_source, str)
        labels, lo, hi = element_boxes(Vq, Fq)
        src = Source(Vq, Fq, labels, lo, hi, (side, side), src.params)
        height = float(Vq[:, 2].max())
    rng = np.random.default_rng(seed)
    report(progress, "strips")
    largest_footprint(src.lo, src.hi)
    grid = _lattice(src) if lattice else None
    patch = cut_corner_patch(src.V, src.F, src.size, rng) if corner_patch else None
    strips, taken = {}, set()
    if isotropic:
        strips[0], taken = pick_strips(src.V, src.F, src.size, count=n_colors[0],
                                       along=STRIP_AXIS[0], rng=rng, lattice=grid,
                                       band=band)
    else:
        # colour by colour, the classes in turn: a strip meets only the other
        # classes' strips at a corner, and the first strips chosen keep their
        # corner elements, so no class takes every corner
        strips = {cls: [] for cls in range(3) if n_colors[cls]}
        for k in range(max(n_colors)):
            for cls in strips:
                if k < n_colors[cls]:
                    before = [st for c in strips if c != cls for st in strips[c]]
                    new, taken = pick_strips(src.V, src.F, src.size, count=1,
                                             along=STRIP_AXIS[cls], rng=rng, taken=taken,
                                             lattice=grid, chosen_before=before,
                                             meets_itself=False, corner_patch=patch,
                                             band=band)
                    strips[cls] += new
    if isotropic:
        strips[1] = strips[2] = strips[0]
    if directional:
        # one more colour per class: the ridge, an empty strip (geotex.tiles.directional)
        strips = {cls: strips[cls] + [empty_strip(STRIP_AXIS[cls])] for cls in (0, 1)}
        groups, cols = tile_keys((n_colors[0] + 1, n_colors[1] + 1, 0), PLANAR_GROUPS)
    else:
        groups, cols = tile_keys(n_colors, PLANAR_GROUPS if planar or isotropic
                                 else COMPLETE_GROUPS)

    merges = None
    if band:
        # the merge depends on the tile's four strips only: one per colour combination
        done = {}
        for (a, b), c in zip(groups.tolist(), cols.tolist()):
            key = (a, b, *c)
            if key not in done:
                done[key] = corner_merged_frame((strips[a], strips[b]), c)
        merged = [done[(a, b, *c)] for (a, b), c in zip(groups.tolist(), cols.tolist())]
        frames = [(mesh, boxes) for mesh, boxes, _ in merged]
        merges = [m[2] for m in merged]
    else:
        frames = [frame_of((strips[a], strips[b]), c, patch)
                  for (a, b), c in zip(groups.tolist(), cols.tolist())]
    plan = TilePlan(src=src, frames=frames, interior=interior, lattice=grid, seed=int(seed),
                    pixels=ExemplarPixels(src.V, src.F, src.labels, src.lo, src.hi),
                    attempts=int(quilt_attempts), best_of=int(quilt_best_of))
    return PlannedSet(plan=plan, strips=strips, groups=groups, cols=cols,
                      n_colors=tuple(n_colors), height=height, depth=depth, recipe=recipe,
                      corner_merges=merges, source=source)


def build_tileset(exemplar, *, colors=2, planar: bool = False, isotropic: bool = False,
                  lattice: bool = False, seed: int = 0, interior: str = "quilt",
                  directional: bool = False, name: str | None = None, progress=None,
                  map_tiles=None, corner_patch: bool = False, corner_merge: bool | float = False,
                  quilt_attempts: int = QUILT_ATTEMPTS, quilt_best_of: int = 1,
                  quilted_source="auto") -> TileSet:
    """Build a planar, complete or isotropic geometric Wang tile set.

    Parameters
    ----------
    exemplar : Exemplar or str
        A planar geometric texture whose connected components are closed
        elements, in tile units (one tile is 1 x 1), e.g.
        ``geotex.exemplars.exemplar("studs")``; a name is looked up there.
    colors : int, str or sequence of 3 int
        Colours per axis class: ``N`` or ``(n_x, n_y, n_z)`` (1 to 4 each);
        an isotropic set takes one ``N``.
    planar : bool
        Build only the ``n_x^2 n_y^2`` tiles of the plane (group (0, 1));
        otherwise the complete polycube set of
        ``2 (n_x^2 n_y^2 + n_x^2 n_z^2 + n_y^2 n_z^2)`` tiles.
    isotropic : bool
        One colour class shared by all three axes: ``N`` strips, each used for
        sides of every class, and the ``N^4`` tiles of group (0, 1), which
        cover a closed polycube when the group is ignored (a side of colour
        ``c`` meets any other side of colour ``c``). ``n_colors`` is
        ``(N, N, N)`` and ``metadata["isotropic"]`` is True. Best for
        textures without a preferred direction (strips are turned a quarter
        on the west and east sides).
    directional : bool
        A directional base set (:mod:`geotex.tiles.directional`) for
        textures pointing ``+v`` (scales): the planar group (0, 1) of
        ``(N + 1)^4`` tiles whose extra colour ``N`` per class is the *ridge*
        (an empty strip: no element crosses such a side); ``n_colors`` is
        ``(N, N, 0)`` and ``metadata["directional"]`` holds the ridge colour
        and the default up axis (2). Mapped on a closed polycube it is first
        turned to follow the flow
        (:func:`geotex.tiles.directional.oriented_tileset`).
    corner_patch : bool
        Every tile corner holds the same exemplar patch, cut by the two
        lines through the corner point (:func:`~geotex.tiles.strips.corner_patch`;
        one corner colour), and the strips are pruned against it instead of
        leaving the corners to the strips' ends.  Planar sets without a
        lattice (not directional).
    corner_merge : bool or float
        The paper's corner merge (:mod:`geotex.tiles.corners`): every strip
        also keeps the whole exemplar elements beside its line near its ends
        (within the strip height ``h_E`` of the line and of an end: the value
        given, in tile units, below 0.5; True means
        :data:`~geotex.tiles.corners.BAND`), and in each tile frame
        those of the horizontal and vertical sides' strips are added where
        free, merged with the element they touch where the two correspond
        (the crossing halves' boundary triangles held fixed) and dropped
        otherwise.  ``metadata["corner_merge"]`` counts them
        (:func:`~geotex.tiles.corners.merge_totals`).  Not with
        ``corner_patch``.
    quilt_attempts : int
        Quilting tries per tile (interior ``"quilt"``) before the paste
        fallback; default :data:`QUILT_ATTEMPTS`. Recorded in
        ``metadata["recipe"]`` when not the default.
    quilt_best_of : int
        Quilting goes on, within ``quilt_attempts`` tries, until this many
        results were accepted, and keeps the one covering most of the tile
        (:func:`interior_quilt`); 1 (default) keeps the first. Recorded in
        ``metadata["recipe"]`` when not 1.
    quilted_source : {"auto", True, False} or float
        Cut the strips, the corner patch and the interiors from a larger
        texture quilted from the exemplar first (the paper's ``M_out``,
        :mod:`geotex.tiles.source`): True quilts a square of
        :data:`~geotex.tiles.source.SOURCE_SIDE` tile units, a number is
        the square's side (2 to 12 tile units), False never quilts, and
        ``"auto"`` (default) quilts a :data:`~geotex.tiles.source.SOURCE_SIDE`
        square only when the exemplar offers fewer than
        :data:`~geotex.tiles.source.MIN_SEGMENTS` distinct candidate
        segments per strip along an axis strips are cut along (or is
        shorter than a tile), never for a ``lattice`` set.  The quilt is
        seeded from ``seed``.  When used, ``metadata["recipe"]["quilted_source"]``
        holds the side and ``metadata["quilted_source"]`` the quilting
        figures; otherwise the set is the same, byte for byte, as without
        the option.  Unlike the paper, the interiors are quilted from
        windows of the quilted texture too (the paper quilts them from
        ``M_in``), so that a small exemplar's windows are not its whole self.
    lattice : bool
        For exemplars laid out on a lattice of period ``params["pitch"]``
        (``1 / pitch`` a whole number): strips and quilting windows start
        only on lattice points (phase from :func:`~geotex.tiles.strips.lattice_phase`,
        moved by half a pitch where that puts the tile corners between
        elements, :func:`~geotex.tiles.strips.lattice_corner`), so every tile
        holds the lattice in the same phase, neighbouring elements do not
        collide across the tiles and no lattice site is left empty.
    seed : int
        Random seed; same inputs and seed give the same set, byte for byte.
    interior : {"quilt", "paste", "periodic"}
        How tile interiors are filled: constrained mesh quilting around the
        frame (:func:`interior_quilt`; a tile whose quilting is not accepted
        after ``quilt_attempts`` tries is pasted instead, counted in
        ``metadata["paste_fallbacks"]``), or whole exemplar elements placed
        between the frame's (:func:`interior_paste`, fast). ``"periodic"``
        uses neither strips nor quilting: the tiles are cut from the
        exemplar's own periodic layout kept on its lattice
        (:func:`geotex.tiles.periodic.periodic_tileset`; linked chain mail, weave,
        isotropic sets only, ``lattice`` is not used).
    name : str, optional
        Set name (default: the exemplar's).
    progress : callable, optional
        Called with ``"strips"`` and then ``"tile i/T"`` for every finished tile.
    map_tiles : callable, optional
        ``map_tiles(built_tile, plan, n)`` runs ``built_tile(plan, t)`` for
        ``t`` in ``range(n)`` (in any order, anywhere: the tiles are
        independent given the plan) and yields the pairs ``(t, result)``;
        e.g. :func:`geotex.batch.run.map_tasks` on a Dask cluster. Default:
        one after another in this process. The set is byte-identical either way.

    Returns
    -------
    TileSet

    Notes
    -----
    Randomness: the strips are drawn from ``default_rng(seed)``; tile ``t``
    draws its interior from its own generator,
    ``default_rng(SeedSequence(seed, spawn_key=(t,)))`` (the ``t``-th child
    of ``SeedSequence(seed).spawn``), so it depends only on the seed, the
    strips and its index.

    Raises
    ------
    InputError
        Unknown interior method, bad colours (or unequal colours for an
        isotropic set, or ``planar`` with ``isotropic``), ``corner_merge``
        with ``corner_patch`` or not a height in ``(0, 0.5)``, elements too large
        for a tile, an exemplar with too few distinct strips, ``quilt_attempts``
        or ``quilt_best_of`` below 1, or a ``quilted_source`` that is not
        ``"auto"``, a bool or a side in range (or given with ``lattice`` or
        interior ``"periodic"``).
    GeotexError
        ``map_tiles`` left out a tile, or the quilted source has invalid
        elements.

    Examples
    --------
    >>> from geotex.exemplars import exemplar
    >>> ts = build_tileset(exemplar("studs", size=(3, 3)), colors=1, isotropic=True,
    ...                    interior="paste")
    >>> len(ts), ts.isotropic, ts.n_colors
    (1, True, (1, 1, 1))
    """
    if interior not in INTERIOR_METHODS:
        raise InputError(f"interior: {interior!r} is not one of {', '.join(INTERIOR_METHODS)}")
    if isotropic and planar:
        raise InputError("isotropic and planar exclude each other: an isotropic set is "
                         "already the n^4 tiles of the plane, usable on a closed polycube")
    if interior == "periodic":
        if quilted_source is True or (isinstance(quilted_source, (int, float, np.number))
                                      and not isinstance(quilted_source, bool)):
            raise InputError("quilted_source: interior 'periodic' cuts no strips from the "
                             "exemplar; leave quilted_source at 'auto' or False")
        if not isotropic:
            raise InputError("interior 'periodic' (--interior periodic) builds isotropic "
                             "sets only; use isotropic=True (--isotropic)")
        if isinstance(exemplar, str):
            exemplar = make(exemplar)
        return periodic_tileset(exemplar, n_colors=parse_colors(colors, planar=False),
                                seed=seed, name=name, progress=progress)
    if directional and interior == "periodic":
        raise InputError("a directional set is built with interior 'quilt' or 'paste'")
    planned = plan_tileset(exemplar, colors=colors, planar=planar, isotropic=isotropic,
                           lattice=lattice, seed=seed, interior=interior,
                           directional=directional, corner_patch=corner_patch,
                           corner_merge=corner_merge, quilt_attempts=quilt_attempts,
                           quilt_best_of=quilt_best_of, quilted_source=quilted_source,
                           progress=progress)
    plan, groups, cols = planned.plan, planned.groups, planned.cols
    n_colors, grid, recipe = planned.n_colors, plan.lattice, planned.recipe
    frames = plan.frames
    n = len(frames)
    results = [None] * n
    mapped = map_tiles(built_tile, plan, n) if map_tiles is not None \
        else ((t, built_tile(plan, t)) for t in range(n))
    for done, (t, result) in enumerate(mapped, 1):
        results[t] = result
        report(progress, f"tile {done}/{n}")
    if any(r is None for r in results):
        raise GeotexError("map_tiles did not return every tile")
    tiles = [r[0] for r in results]
    stats = [r[1] for r in results]
    coverage = [s["coverage"] for s in stats]
    fallbacks = sum(s["pasted"] for s in stats)
    merges = sum(s.get("merges", 0) for s in stats)
    filled = sum(s.get("filled", 0) for s in stats)
    seams = [(s["stitched"], s["seam_gap_max"], s["seam_normal_jump_mean"],
              s["seam_normal_jump_max"]) for s in stats if s.get("stitched", 0)]
    meta = {
        "exemplar": recipe,
        "recipe": {"exemplar": recipe, "colors": list(n_colors), "planar": bool(planar),
                   "isotropic": bool(isotropic), "lattice": bool(lattice), "seed": int(seed),
                   "interior": interior},
        **({"directional": {"ridge": int(n_colors[0]), "up": 2}} if directional else {}),
        "isotropic": bool(isotropic),
        "corner_clearance": CLEAR,
        "lattice": None if grid is None else [round(float(g), 9) for g in grid],
        "coverage_mean": round(float(np.mean(coverage)), 6),
    }
    if interior == "quilt":
        meta.update(paste_fallbacks=int(fallbacks), merged_elements=int(merges),
                    gap_fill_elements=int(filled))
        if seams:
            S = np.asarray(seams, dtype=np.float64)
            meta.update(stitched_seams=int(S[:, 0].sum()),
                        seam_gap_max=round(float(np.nanmax(S[:, 1])), 6),
                        seam_normal_jump_mean=round(float(np.nansum(S[:, 0] * S[:, 2])
                                                          / S[:, 0].sum()), 3),
                        seam_normal_jump_max=round(float(np.nanmax(S[:, 3])), 3))
    if directional:
        meta["recipe"]["directional"] = True
    if corner_patch:
        meta["recipe"]["corner_patch"] = True
    if corner_merge:
        meta["recipe"]["corner_merge"] = corner_merge if corner_merge is True \
            else float(corner_merge)
        meta["corner_merge"] = merge_totals(planned.corner_merges)
    if quilt_attempts != QUILT_ATTEMPTS:
        meta["recipe"]["quilt_attempts"] = int(quilt_attempts)
    if quilt_best_of != 1:
        meta["recipe"]["quilt_best_of"] = int(quilt_best_of)
    if planned.source is not None:
        # the side, so that the recipe rebuilds the set whether "auto" chose it or not
        meta["recipe"]["quilted_source"] = planned.source["side"]
        meta["quilted_source"] = dict(planned.source)
    return TileSet.from_tiles(tiles, groups, cols, n_colors=n_colors, height=planned.height,
                              depth=planned.depth, name=name or recipe["name"] or "tileset",
                              metadata=meta)
