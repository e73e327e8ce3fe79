"""Build a geometric Wang tile set from an exemplar.

Steps (``../shared/DESIGN.md`` §5.3): one edge strip per colour of every axis
class (:mod:`geotex.tiles.strips`); for each tile the four strip halves of its
side colours form its frame (:mod:`geotex.tiles.frame`); the interior is then
filled from the exemplar (:func:`interior_paste`).
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.progress import report
from geotex.tiles.colors import COMPLETE_GROUPS, PLANAR_GROUPS, parse_colors, tile_keys
from geotex.tiles.frame import concatenated, frame_of
from geotex.tiles.strips import GAP, corner_margin, element_boxes, pick_strips
from geotex.tiles.tileset import TileSet

__all__ = ["build_tileset", "interior_paste", "INTERIOR_METHODS", "BUILD_STAGES"]

INTERIOR_METHODS = ("paste",)
BUILD_STAGES = ("strips", "tiles")
WINDOWS = 64                 # exemplar windows tried per pass
PASTE_PASSES = 4             # interior passes: the bulk, then gap filling
STRIP_AXIS = {0: 0, 1: 1, 2: 0}   # class -> exemplar axis its strips run along


def _exemplar_arrays(exemplar):
    """(V, F, size, height, depth, name, recipe) of an exemplar object or name."""
    if isinstance(exemplar, str):
        from geotex.exemplars import exemplar as make
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
    recipe = {"name": getattr(exemplar, "name", ""),
              "params": dict(getattr(exemplar, "params", {}) or {})}
    return V, F, size, float(V[:, 2].max()), depth, recipe


def interior_paste(V: np.ndarray, F: np.ndarray, labels: np.ndarray, lo: np.ndarray,
                   hi: np.ndarray, size, frame_boxes: np.ndarray,
                   rng: np.random.Generator) -> tuple[tuple[np.ndarray, np.ndarray], dict]:
    """Fill a tile interior with exemplar elements that fit between the frame's.

    In each of :data:`PASTE_PASSES` passes, tries :data:`WINDOWS` random unit
    windows of the exemplar and adds the elements of the best one: those lying
    wholly inside the tile and clear (by :data:`~geotex.tiles.strips.GAP`) of the
    footprint of every element placed so far; the best window adds the most
    footprint area. The first pass lays down the bulk, later passes fill gaps.
    Elements are copied unchanged, so they stay closed.

    Returns
    -------
    mesh : tuple of (V, F)
        The added elements in tile coordinates.
    stats : dict
        ``elements`` added and ``coverage`` (their footprint area / tile area).
    """
    lx, ly = size
    placed = np.asarray(frame_boxes, dtype=np.float64).reshape(-1, 4)
    parts, n_added, covered = [], 0, 0.0
    for _ in range(PASTE_PASSES):
        ox = rng.uniform(0.0, lx - 1.0, WINDOWS)
        oy = rng.uniform(0.0, ly - 1.0, WINDOWS)
        u0 = lo[None, :, 0] - ox[:, None]
        u1 = hi[None, :, 0] - ox[:, None]
        v0 = lo[None, :, 1] - oy[:, None]
        v1 = hi[None, :, 1] - oy[:, None]
        inside = (u0 >= GAP) & (v0 >= GAP) & (u1 <= 1 - GAP) & (v1 <= 1 - GAP)
        pb = placed
        clash = ((u0[..., None] < pb[:, 2] + GAP) & (u1[..., None] > pb[:, 0] - GAP)
                 & (v0[..., None] < pb[:, 3] + GAP) & (v1[..., None] > pb[:, 1] - GAP)
                 ).any(-1)
        ok = inside & ~clash
        area = np.where(ok, (u1 - u0) * (v1 - v0), 0.0).sum(axis=1)
        best = int(np.argmax(area))
        members = np.flatnonzero(ok[best])
        if members.size == 0:
            break
        keep = np.isin(labels, members)
        Fk = F[keep]
        used = np.unique(Fk)
        remap = np.full(len(V), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        parts.append((V[used] - np.array([ox[best], oy[best], 0.0]), remap[Fk]))
        placed = np.vstack([placed, np.stack([u0[best, members], v0[best, members],
                                              u1[best, members], v1[best, members]], 1)])
        n_added += int(members.size)
        covered += float(area[best])
    return concatenated(parts), {"elements": n_added, "coverage": covered}


def build_tileset(exemplar, *, colors=2, planar: bool = False, seed: int = 0,
                  interior: str = "paste", name: str | None = None,
                  progress=None) -> TileSet:
    """Build a planar or complete geometric Wang tile set.

    Parameters
    ----------
    exemplar : Exemplar or str
        A planar geometric texture whose connected components are closed
        elements, in tile units (one tile is 1 x 1), e.g.
        ``geotex.exemplars.exemplar("studs")``; a name is looked up there.
    colors : int, str or sequence of 3 int
        Colours per axis class: ``N`` or ``(n_x, n_y, n_z)`` (1 to 4 each).
    planar : bool
        Build only the ``n_x^2 n_y^2`` tiles of the plane (group (0, 1));
        otherwise the complete polycube set of
        ``2 (n_x^2 n_y^2 + n_x^2 n_z^2 + n_y^2 n_z^2)`` tiles.
    seed : int
        Random seed; same inputs and seed give the same set, byte for byte.
    interior : {"paste"}
        How tile interiors are filled.
    name : str, optional
        Set name (default: the exemplar's).
    progress : callable, optional
        Called with each stage name of :data:`BUILD_STAGES`.

    Returns
    -------
    TileSet

    Raises
    ------
    InputError
        Unknown interior method, bad colours, elements too large for a tile,
        or an exemplar with too few distinct strips.
    """
    if interior not in INTERIOR_METHODS:
        raise InputError(f"interior: {interior!r} is not one of {', '.join(INTERIOR_METHODS)}")
    V, F, size, height, depth, recipe = _exemplar_arrays(exemplar)
    n_colors = parse_colors(colors, planar=planar)
    rng = np.random.default_rng(seed)
    report(progress, "strips")
    labels, lo, hi = element_boxes(V, F)
    margin = corner_margin(lo, hi)
    strips, taken = {}, set()
    for cls in range(3):
        if n_colors[cls]:
            strips[cls], taken = pick_strips(V, F, size, count=n_colors[cls],
                                             along=STRIP_AXIS[cls], rng=rng, margin=margin,
                                             taken=taken)
    report(progress, "tiles")
    groups, cols = tile_keys(n_colors, PLANAR_GROUPS if planar else COMPLETE_GROUPS)
    tiles, coverage = [], []
    for (a, b), c in zip(groups.tolist(), cols.tolist()):
        frame, boxes = frame_of((strips[a], strips[b]), c)
        inner, stats = interior_paste(V, F, labels, lo, hi, size, boxes, rng)
        tiles.append(concatenated([frame, inner]))
        fb = np.clip(boxes, 0.0, 1.0)
        coverage.append(stats["coverage"] + float(((fb[:, 2] - fb[:, 0])
                                                   * (fb[:, 3] - fb[:, 1])).sum()))
    meta = {
        "exemplar": recipe,
        "recipe": {"exemplar": recipe, "colors": list(n_colors), "planar": bool(planar),
                   "seed": int(seed), "interior": interior},
        "corner_margin": margin,
        "footprint_coverage_mean": round(float(np.mean(coverage)), 6),
    }
    ts = TileSet.from_tiles(tiles, groups, cols, n_colors=n_colors, height=height,
                            depth=depth, name=name or recipe["name"] or "tileset",
                            metadata=meta)
    return ts
