"""
Geometric Wang tiles step by step: strips, frame, interior (the paper's Fig. 3)
===============================================================================

The stages of building one tile of the catalog set ``studs`` (an isotropic
2-colour set), from the same random draws as ``geotex tiles build`` /
``python -m geotex.tiles.catalog studs`` (:func:`geotex.tiles.build.plan_tileset`
then :func:`geotex.tiles.build.built_tile`):

1. **Exemplar and strips**: one edge strip per colour, the elements crossing
   a unit segment of the exemplar (coloured by strip; the rest of the
   exemplar grey).
2. **Strips cut at the tile side**: each strip is cut once along its
   segment; one tile receives the half on one side, its neighbour the other
   half, and the two halves share their cut vertices bit for bit (drawn
   pulled apart here).
3. **Frame**: the four strip halves of a tile's side colours placed on its
   sides (coloured by side). Elements crossing a side are kept up to the
   tile corners; strips are chosen so that the halves meeting in a corner
   do not collide there (the paper merges corresponding elements in these
   overlaps instead; here there is nothing to merge).
4. **Interior**: the rest of the tile synthesized around the frame by
   constrained mesh quilting (copies of the exemplar matched to the frame;
   a copy's element that is the same element as a frame half is absorbed,
   one that collides with a different element is dropped), gaps and
   corner squares then filled with whole exemplar elements. Frame elements
   keep their colour, interior elements are green.

The script prints, per stage, the element counts.

Run:  python examples/tiles_pipeline.py [OUT_DIR]     (default docs/gallery)
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
from geotex.tiles.frame import placed_half
from geotex.tiles.strips import from_strip

SET = "studs"
TILE = 5                         # which tile of the set is shown
GREY, INTERIOR = 0, 9            # labels of the exemplar/plate and of interior elements
PALETTE = {GREY: "#bdb8ad", 1: "#d1495b", 2: "#2e86ab", 3: "#edae49", 4: "#8e6c8a",
           INTERIOR: "#66a182"}     # label 1 + k: strip colour k

_panel = partial(labelled_panel, palette=PALETTE)


def _plate(x0, y0, x1, y1, z):
    """A thin plate under a tile (the tile square), scalar GREY."""
    V, F = box((x0, y0, z - 0.01), (x1, y1, z))
    return V, F, GREY


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = recipes()[SET]
    ex = exemplar(r["exemplar"]["name"], **r["exemplar"]["params"])
    planned = plan_tileset(ex, colors=r["colors"], planar=r.get("planar", False),
                           isotropic=r.get("isotropic", False),
                           lattice=r.get("lattice", False), seed=r["seed"],
                           interior=r.get("interior", "quilt"))
    strips = planned.strips[0]
    depth = planned.depth

    # 1. exemplar with the strips' elements coloured
    parts = [(ex.vertices, ex.faces, GREY)]
    for k, st in enumerate(strips):
        for half in (st.below, st.above):
            parts.append((from_strip(half[0], st.origin, st.along) + [0, 0, 0.002],
                          half[1], 1.0 + k))
    p1 = labelled_parts(parts)

    # 2. the strips in their own coordinates, the two halves pulled apart
    parts = []
    for k, st in enumerate(strips):
        y = -0.9 * k
        for half, ds in ((st.below, -0.06), (st.above, 0.06)):
            parts.append((half[0] + [0.0, y + ds, 0.0], half[1], 1.0 + k))
        parts.append(_plate(0.0, y - 0.01, 1.0, y + 0.01, -depth))
    p2 = labelled_parts(parts)

    # 3. the frame of one tile, coloured by the strip (side colour) of each side
    cols = planned.cols[TILE].tolist()
    parts = [_plate(0.0, 0.0, 1.0, 1.0, -depth)]
    for side, colour in zip((SOUTH, EAST, NORTH, WEST), cols):
        (V, F), _ = placed_half(strips[colour], side)
        parts.append((V, F, 1 + colour))
    p3 = labelled_parts(parts)

    # 4. the built tile: frame elements as in 3, interior green
    (Vt, Ft), stats = built_tile(planned.plan, TILE)
    frame_V = np.concatenate([placed_half(strips[c], s)[0][0]
                              for s, c in zip((SOUTH, EAST, NORTH, WEST), cols)])
    side_of = {}
    for s, c in zip((SOUTH, EAST, NORTH, WEST), cols):
        for p in placed_half(strips[c], s)[0][0].astype(np.float32).tolist():
            side_of[tuple(p)] = 1 + c
    n_comp, comp = face_components(Ft, len(Vt))
    key = [tuple(p) for p in Vt.astype(np.float32).tolist()]
    scal = np.full(len(Ft), INTERIOR)
    for c in range(n_comp):
        faces = np.flatnonzero(comp == c)
        verts = np.unique(Ft[faces])
        hits = [side_of.get(key[v]) for v in verts]
        if all(h is not None for h in hits):
            scal[faces] = hits[0]
    plate = _plate(0.0, 0.0, 1.0, 1.0, -depth)
    V4, F4, S4 = labelled_parts([plate, (Vt, Ft, 0.0)])
    S4[len(plate[1]):] = scal
    n_frame = len({tuple(p) for p in frame_V.astype(np.float32).tolist()})
    interior = int(sum(1 for c in range(n_comp) if (scal[comp == c] == INTERIOR).all()))
    print(f"{SET}: {len(strips)} strips ({', '.join(str(len(st.boxes)) for st in strips)} "
          f"elements), tile {TILE} sides {cols}: frame {n_comp - interior} element pieces, "
          f"interior {interior} elements ({stats.get('filled', 0)} gap fills, "
          f"{stats.get('corner_filled', 0)} corner fills), coverage {stats['coverage']:.2f}; "
          f"{n_frame} frame vertices")

    panels = [
        _panel(*p1, "1. exemplar: one strip per colour (the elements crossing a unit "
               "segment)"),
        _panel(*p2, "2. strips cut at the tile side (halves pulled apart; they share "
               "the cut)"),
        _panel(*p3, f"3. frame of tile {TILE}: the halves of its side colours "
               f"(S, E, N, W) = {tuple(cols)}"),
        _panel(V4, F4, S4, "4. interior: constrained quilting around the frame, then "
               "gap and corner fills (green)"),
    ]
    path = render_panels(panels, out / "tiles_pipeline_studs.png", size=(800, 700))
    print(f"wrote {path}")


# %%
# Run: the picture goes to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
