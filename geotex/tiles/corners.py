"""The paper's corner merge: strips of the two axes meet in the corner squares.

Wang et al. (§3.1-3.2; ``../shared/DESIGN.md`` §5.3 steps 2-3) take strips
of height ``h_E``, so that the strips of a horizontal and a vertical side
overlap at the tile corner they share, and in each tile frame they *deform
and merge the corresponding elements of the overlap*, holding the tile
boundary fixed.  Here a strip keeps, besides the elements crossing its line,
the whole exemplar elements beside the line near its ends (its *band*,
:attr:`geotex.tiles.strips.Strip.band`); in a tile frame the four strips'
halves are placed as before and then every band element, side by side, is

- added where it touches nothing,
- merged into the one element it touches when the two *correspond*
  (:func:`geotex.quilting.merge.merge_elements` with
  ``corresponding_only``: an ICP shift of at most a quarter of the narrow
  width and 85 % of the surface of each on or inside the other over the
  common box; then the weld or Laplacian pull toward the midpoints and
  the graph cut of eq. 8),
- dropped where it touches an element it does not correspond to, or more
  than one.

The crossing halves keep what :func:`geotex.tiles.strips.pick_strips` chose
(a tile's neighbour holds their other halves).  The vertices of every
triangle of a crossing half that touches the tile side it was cut by (the
paper's boundary triangles of ``B(C)``, §3.3.5) are held fixed: a merge
moves the band element onto the crossing half, never the half, and the
side boundaries come back bit for bit (checked; a frame whose sides would
change is left unmerged).  A merged element that comes within
:data:`~geotex.tiles.strips.CLEAR` of a side it is not cut by, or leaves
the tile, is undone (the band element goes).
"""

from __future__ import annotations

import numpy as np

from geotex.mesh.topology import compacted
from geotex.quilting import Element, concatenate_elements, split_elements
from geotex.quilting.elements import capped
from geotex.quilting.merge import merge_elements
from geotex.quilting.placement import coincides, touching
from geotex.tiles.colors import EAST, NORTH, SOUTH, WEST
from geotex.tiles.frame import frame_of, placed_band
from geotex.tiles.strips import CLEAR, element_boxes
from geotex.tiles.verify import side_boundaries

__all__ = ["BAND", "corner_merged_frame", "merged_corners", "merge_totals"]

BAND = 0.45         # largest strip height h_E beside the line (and reach from its ends)
DOMAIN = (0.0, 0.0, 1.0, 1.0)
STATUSES = ("added", "absorbed", "stitched", "union", "dropped", "undone")


def corner_merged_frame(strips_ab, colors) -> tuple[tuple[np.ndarray, np.ndarray],
                                                      np.ndarray, dict]:
    """The frame of one tile with its strips' band elements merged in at the corners.

    Parameters
    ----------
    strips_ab : tuple of (list of Strip, list of Strip)
        Strips of the south/north class and of the west/east class, picked
        with a ``band`` (:func:`geotex.tiles.strips.pick_strips`).
    colors : sequence of 4 int
        Colours of sides south, east, north, west.

    Returns
    -------
    mesh : tuple of (V (n, 3) float64, F (m, 3) int64)
    boxes : numpy.ndarray, (k, 4) float64
        Element footprints ``(u0, v0, u1, v1)``.
    stats : dict
        :func:`merged_corners` counts and seams.
    """
    frame, boxes = frame_of(strips_ab, colors)
    sn, we = strips_ab
    bands = [placed_band(strip, side) for side, strip in
             ((SOUTH, sn[colors[0]]), (EAST, we[colors[1]]), (NORTH, sn[colors[2]]),
              (WEST, we[colors[3]]))]
    if not any(len(F) for _, F in bands):
        # nothing beside the lines (a lattice whose next row is beyond h_E): the plain frame
        stats = {k: 0 for k in STATUSES}
        stats.update(seams=[], moved=[], kept_unmerged=0)
        return frame, boxes, stats
    return merged_corners(frame, bands)


def merged_corners(frame, bands) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray, dict]:
    """Add, merge or drop band elements against a tile frame (see the module docstring).

    Parameters
    ----------
    frame : tuple of (V (n, 3) float64, F (m, 3) int64)
        The crossing halves, open only along the tile sides of ``[0, 1]^2``.
    bands : sequence of tuple (V, F)
        Closed band elements in tile coordinates, tried in this order
        (element by element, in order of their first face).

    Returns
    -------
    mesh : tuple of (V (n, 3) float64, F (m, 3) int64)
        The frame, open along the same side cuts, bit for bit.
    boxes : numpy.ndarray, (k, 4) float64
        Element footprints.
    stats : dict
        How many band elements were ``added``, ``absorbed`` (a copy of the
        element already there), ``stitched`` or ``union`` (merged),
        ``dropped`` (not corresponding, or touching several) or ``undone``
        (merged, then too near a side); ``seams``: ``(gap, jump_max,
        jump_mean)`` of every stitched merge (gap in tile units, angles in
        degrees); ``kept_unmerged`` 1 when the merged frame's sides differed
        and the frame was returned as given; ``moved``: how far (tile units)
        the kept element of every absorbed pair moved (half the alignment
        shift; 0 for a copy in place or when it is a held crossing half).
    """
    V0, F0 = frame
    stats = {k: 0 for k in STATUSES}
    stats.update(seams=[], moved=[], kept_unmerged=0)
    elements, cut = [], []
    for e in (split_elements(V0, F0, prefilled=True) if len(F0) else []):
        F2, cap, on_cut = capped(e.V, e.F, DOMAIN)
        # boundary triangles (paper §3.3.5): every vertex of a face touching the cut
        fixed = np.zeros(len(e.V), dtype=bool)
        fixed[F2[~cap][on_cut[F2[~cap]].any(axis=1)].ravel()] = True
        elements.append(Element(e.V, F2, fixed, True, cap))
        cut.append(_cut_sides(e.V[on_cut]))
    for Vb, Fb in bands:
        if not len(Fb):
            continue
        for p in split_elements(Vb, Fb):
            status, seam = _placed(p, elements, cut)
            stats[status] += 1
            if seam is not None and seam[0] == "moved":
                stats["moved"].append(seam[1])
            elif seam is not None:
                stats["seams"].append(seam)
    V, F, _, _ = concatenate_elements(elements)
    V, F = compacted(V, F)
    want, _ = side_boundaries(V0, F0)
    got, stray = side_boundaries(V, F)
    if stray or any(not np.array_equal(a, b) for a, b in zip(got, want)):
        stats["kept_unmerged"] = 1
        V, F = V0, F0
    return (V, F), _footprints(V, F), stats


def _cut_sides(P: np.ndarray) -> np.ndarray:
    """Sides (south, east, north, west) on which any of the points ``P`` lie."""
    return np.array([(P[:, 1] == 0.0).any(), (P[:, 0] == 1.0).any(),
                     (P[:, 1] == 1.0).any(), (P[:, 0] == 0.0).any()])


def _clear_of_sides(e: Element, sides: np.ndarray) -> bool:
    """Inside the tile and :data:`CLEAR` from every side not in ``sides``."""
    lo, hi = e.lo, e.hi
    if lo[0] < 0.0 or lo[1] < 0.0 or hi[0] > 1.0 or hi[1] > 1.0:
        return False
    dist = np.array([lo[1], 1.0 - hi[0], 1.0 - hi[1], lo[0]])
    return not ((dist < CLEAR) & ~sides).any()


def _placed(p: Element, elements: list, cut: list):
    """Place one band element into ``elements`` (in place); ``(status, seam or None)``."""
    partners = [k for k, e in enumerate(elements) if touching(e, p)]
    if not partners:
        if not _clear_of_sides(p, np.zeros(4, dtype=bool)):
            return "dropped", None
        elements.append(p)
        cut.append(np.zeros(4, dtype=bool))
        return "added", None
    if len(partners) > 1:
        return "dropped", None
    k = partners[0]
    e = elements[k]
    if coincides(e, p):
        return "absorbed", ("moved", 0.0)
    r = merge_elements(e.V, e.F, p.V, p.F, fixed_a=e.fixed, domain=DOMAIN,
                       corresponding_only=True, cap_a=e.cap)
    if r.status not in ("stitched", "union", "absorbed"):
        return "dropped", None
    merged = Element(r.vertices, r.faces, r.fixed, e.prefilled, r.cap)
    if not _clear_of_sides(merged, cut[k]):
        return "undone", None
    others = [o for i, o in enumerate(elements) if i != k]
    if any(touching(o, merged) for o in others):
        return "undone", None
    elements[k] = merged
    if r.status == "stitched":
        return r.status, (float(r.seam_gap), float(r.seam_normal_jump),
                          float(r.seam_normal_jump_mean))
    if r.status == "absorbed" and r.vertices.shape == e.V.shape:
        # no seam: the element kept moved half way toward its partner (or not at all)
        return r.status, ("moved", float(np.linalg.norm(r.vertices - e.V, axis=1).max()))
    return r.status, None


def _footprints(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Footprint boxes ``(u0, v0, u1, v1)`` of the connected elements of a mesh."""
    if not len(F):
        return np.zeros((0, 4), dtype=np.float64)
    _, lo, hi = element_boxes(V, F)
    return np.c_[lo[:, :2], hi[:, :2]]


def merge_totals(stats: list) -> dict:
    """Sum the :func:`merged_corners` stats of many frames (seam figures pooled).

    Returns
    -------
    dict
        The counts of :data:`STATUSES`, ``merged`` (absorbed + stitched +
        union), ``kept_unmerged``, ``absorbed_moved_max`` (largest move of
        an absorbed pair's kept element, tile units), and over the stitched merges
        ``seam_gap_max`` (tile units), ``seam_normal_jump_mean`` (mean of
        the per-merge mean angle) and ``seam_normal_jump_max`` (degrees),
        None without stitches.
    """
    out = {k: int(sum(s[k] for s in stats)) for k in STATUSES}
    out["merged"] = out["absorbed"] + out["stitched"] + out["union"]
    out["kept_unmerged"] = int(sum(s["kept_unmerged"] for s in stats))
    seams = np.array([x for s in stats for x in s["seams"]], dtype=np.float64).reshape(-1, 3)
    has = len(seams) > 0
    out["seam_gap_max"] = round(float(np.nanmax(seams[:, 0])), 6) if has else None
    out["seam_normal_jump_mean"] = round(float(np.nanmean(seams[:, 2])), 3) if has else None
    out["seam_normal_jump_max"] = round(float(np.nanmax(seams[:, 1])), 3) if has else None
    moved = [x for s in stats for x in s.get("moved", [])]
    out["absorbed_moved_max"] = round(float(max(moved)), 6) if moved else None
    return out
