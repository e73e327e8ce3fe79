"""
Corner merge of geometric Wang tiles: strips, frame with merged corners, interior
=================================================================================

The paper's Fig. 3 with its corner step (§3.1-3.2): strips of the two axes
overlap at the tile corners, the overlaps are meant to hold corresponding
elements, and those are merged in the frame with the tile boundary held
fixed. Built here from the ``scales-planar`` recipe with
``corner_merge=True`` instead of its corner patch (the option no catalog
set uses; see ``benchmarks/results/tiles_corners.md``), for the tile whose
frame merged most corner pairs:

1. **Strips placed**: the four strip halves crossing the tile sides
   (coloured by side: south/north red shades, west/east blue shades) and
   every strip's *band*, the whole exemplar elements beside its line near
   its ends (lighter), all drawn side by side as placed, before the merge:
   in the corner squares the bands of a horizontal and a vertical side lie
   on each other.
2. **Frame after the corner merge**: band elements that touched nothing are
   kept (light), those that corresponded to the element they touched are
   merged into it (moved half way, or onto a crossing half, which is held;
   yellow where the result is neither of the two unchanged), the others
   dropped.
3. **Interior**: the rest of the tile quilted around that frame, then gaps
   and corner squares filled (green).

Run:  python examples/tiles_corner_merge.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from functools import partial
from pathlib import Path

import numpy as np

from geotex.exemplars import exemplar
from geotex.mesh.primitives import box
from geotex.mesh.topology import face_components
from geotex.render import labelled_panel, labelled_parts, render_panels
from geotex.tiles.build import built_tile, plan_tileset
from geotex.tiles.catalog import recipes
from geotex.tiles.colors import EAST, NORTH, SOUTH, WEST
from geotex.tiles.frame import placed_band, placed_half

SET = "scales-planar"
PLATE, MERGED, INTERIOR = 0, 9, 10
PALETTE = {PLATE: "#bdb8ad", 1: "#d1495b", 2: "#f19ca6", 3: "#2e86ab", 4: "#9cc9e0",
           MERGED: "#edae49", INTERIOR: "#66a182"}
SIDES = (SOUTH, EAST, NORTH, WEST)

_panel = partial(labelled_panel, palette=PALETTE)


def _labelled(V, F, crossing: dict, band: dict, other: int):
    """Per-face labels of a tile mesh: the source of each element's vertices.

    An element all of whose vertices are vertices of one crossing half or
    band element (float32 keys) gets that part's label, any other ``other``.
    """
    n, comp = face_components(F, len(V))
    key = [tuple(p) for p in V.astype(np.float32).tolist()]
    out = np.full(len(F), other)
    for c in range(n):
        faces = np.flatnonzero(comp == c)
        hits = {crossing.get(key[v], band.get(key[v])) for v in np.unique(F[faces])}
        if len(hits) == 1 and None not in hits:
            out[faces] = hits.pop()
    return out


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = recipes()[SET]
    ex = exemplar(r["exemplar"]["name"], **r["exemplar"]["params"])
    planned = plan_tileset(ex, colors=r["colors"], planar=True, seed=r["seed"],
                           interior="quilt", corner_merge=True,
                           quilt_attempts=r.get("quilt_attempts", 3),
                           quilt_best_of=r.get("quilt_best_of", 1))
    stats = planned.corner_merges
    tile = int(np.argmax([s["absorbed"] + s["stitched"] + s["union"] for s in stats]))
    (a, b), cols = planned.groups[tile].tolist(), planned.cols[tile].tolist()
    strips = {SOUTH: planned.strips[a][cols[0]], EAST: planned.strips[b][cols[1]],
              NORTH: planned.strips[a][cols[2]], WEST: planned.strips[b][cols[3]]}
    shade = {SOUTH: 1, NORTH: 1, EAST: 3, WEST: 3}
    depth = planned.depth
    plate = (*box((0.0, 0.0, -depth - 0.01), (1.0, 1.0, -depth)), PLATE)

    crossing, band, parts1 = {}, {}, [plate]
    for side, st in strips.items():
        (V, F), _ = placed_half(st, side)
        Vb, Fb = placed_band(st, side)
        parts1 += [(V, F, shade[side]), (Vb, Fb, shade[side] + 1)]
        crossing.update({tuple(p): shade[side] for p in V.astype(np.float32).tolist()})
        band.update({tuple(p): shade[side] + 1 for p in Vb.astype(np.float32).tolist()})
    p1 = labelled_parts(parts1)

    (Vf, Ff), _ = planned.plan.frames[tile]
    p2 = labelled_parts([plate, (Vf, Ff, _labelled(Vf, Ff, crossing, band, MERGED))])

    (Vt, Ft), tstats = built_tile(planned.plan, tile)
    frame_keys = {tuple(p): MERGED for p in Vf.astype(np.float32).tolist()}
    lab = _labelled(Vt, Ft, crossing, band, INTERIOR)
    # merged frame elements keep their colour in the built tile
    n, comp = face_components(Ft, len(Vt))
    key = [tuple(p) for p in Vt.astype(np.float32).tolist()]
    for c in range(n):
        faces = np.flatnonzero(comp == c)
        if lab[faces[0]] == INTERIOR and all(key[v] in frame_keys for v in np.unique(Ft[faces])):
            lab[faces] = MERGED
    p3 = labelled_parts([plate, (Vt, Ft, lab)])

    s = stats[tile]
    print(f"{SET} with corner_merge: tile {tile} sides {cols}: {s['added']} band elements "
          f"added, {s['absorbed']} absorbed, {s['stitched']} stitched, {s['union']} united, "
          f"{s['dropped']} dropped, {s['undone']} undone; built tile coverage "
          f"{tstats['coverage']:.2f}")
    panels = [
        _panel(*p1, f"1. tile {tile}: strip halves on the sides, their bands (light), "
               "before the merge"),
        _panel(*p2, f"2. frame: {s['absorbed'] + s['stitched'] + s['union']} corresponding "
               f"corner pairs merged, {s['dropped']} band elements dropped"),
        _panel(*p3, "3. interior quilted around the frame (green)"),
    ]
    path = render_panels(panels, out / "tiles_corner_merge_scales.png", size=(800, 700))
    print(f"wrote {path}")


# %%
# Run: the picture goes to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
