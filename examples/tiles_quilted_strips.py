"""
Wang tiles from a small exemplar: strips cut from a quilted source
==================================================================

The catalog's studs exemplar cropped to 1.3 x 1.3 tile units holds four
studs. Cut straight from it (``quilted_source=False``), every edge strip of
a 2-colour isotropic set holds one stud and the strips repeat the same few
neighbourhoods. With ``quilted_source`` (here ``"auto"``, the default, which
quilts because the crop offers fewer than 8 distinct candidate segments per
strip) the crop is first quilted into a 4 x 4 texture
(:func:`geotex.quilting.quilt_texture`, :mod:`geotex.tiles.source`: the
paper's "when ``M_in`` is too small, synthesize a larger ``M_out`` and
pick the strips from it"), and the strips, the frames and the interiors are
cut from that.

Panels, left to right:

1. the cropped exemplar, the elements of the strips cut from it coloured
   (a stud in both strips shows both colours);
2. the quilted 4 x 4 source, the elements of its strips coloured;
3. its strips in their own coordinates, the two halves of each pulled apart
   (one tile receives one half, its neighbour the other);
4. a random 6 x 6 tiling of the set built from the quilted source (seed 0,
   the one ``geotex tiles tile --grid 6 6`` writes): elements that cross a
   tile side orange, the rest green, tile sides drawn on the plate;
5. the same tiling of the set built from the crop itself.

The script prints, for both sets, the strips' element counts, the elements
crossing tile sides in the tiling and the corner density ratio
(:func:`geotex.tiles.verify.corner_density`).

Run:  python examples/tiles_quilted_strips.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from functools import partial
from pathlib import Path

import numpy as np

from geotex.exemplars import exemplar
from geotex.mesh.geometry import group_boxes
from geotex.mesh.primitives import box
from geotex.mesh.topology import face_components
from geotex.render import labelled_panel, labelled_parts, render_panels
from geotex.tiles.build import build_tileset, plan_tileset
from geotex.tiles.catalog import recipes
from geotex.tiles.strips import from_strip
from geotex.tiles.tiling import planar_tiling, random_arrangement
from geotex.tiles.verify import check_seams, corner_density

SET = "studs"
CROP = 1.3
GRID = 6
GREY, LINE, CROSSING, INSIDE = 0, 1, 2, 3        # labels; strip k is 4 + k
PALETTE = {GREY: "#bdb8ad", LINE: "#4a4a4a", CROSSING: "#e07a2f", INSIDE: "#66a182",
           4: "#d1495b", 5: "#2e86ab", 6: "#edae49", 7: "#8e6c8a"}

_panel = partial(labelled_panel, palette=PALETTE)


def _plate(w, h, z, lines=False):
    """A plate under ``[0, w] x [0, h]`` (and the tile sides on it as dark bars)."""
    parts = [box((0.0, 0.0, z - 0.02), (w, h, z)) + (GREY,)]
    if lines:
        for k in range(int(w) + 1):
            parts.append(box((k - 0.02, 0.0, z), (k + 0.02, h, z + 0.01)) + (LINE,))
        for k in range(int(h) + 1):
            parts.append(box((0.0, k - 0.02, z), (w, k + 0.02, z + 0.01)) + (LINE,))
    return parts


def _with_strips(V, F, strips, size, depth):
    """The source grey with its strips' elements coloured over it."""
    parts = _plate(size[0], size[1], -depth) + [(V, F, GREY)]
    for k, st in enumerate(strips):
        for half in (st.below, st.above):
            parts.append((from_strip(half[0], st.origin, st.along) + [0, 0, 0.002],
                          half[1], 4 + k))
    return labelled_parts(parts)


def _tiling(tiles, depth):
    """A random 6 x 6 tiling, elements crossing a tile side coloured; and their count."""
    V, F = planar_tiling(tiles, random_arrangement(tiles, GRID, GRID, seed=0), border="open")
    n, comp = face_components(F, len(V))
    vlab = np.full(len(V), -1, dtype=np.int64)
    vlab[F.ravel()] = np.repeat(comp, 3)
    lo, hi = group_boxes(V, vlab, n)
    crossing = (np.floor(lo[:, :2] + 1e-9) != np.floor(hi[:, :2] - 1e-9)).any(axis=1)
    d = corner_density(V, F, (GRID, GRID))
    label = np.where(crossing[comp], CROSSING, INSIDE)
    return labelled_parts(_plate(GRID, GRID, -depth, lines=True) + [(V, F, label)]), \
        int(crossing.sum()), int(n), d.ratio


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = recipes()[SET]
    small = exemplar(r["exemplar"]["name"], **r["exemplar"]["params"]).cropped((CROP, CROP))
    options = dict(colors=2, isotropic=True, seed=r["seed"], interior="quilt")
    plain = plan_tileset(small, quilted_source=False, **options)
    quilted = plan_tileset(small, **options)                       # "auto": quilts
    src = quilted.plan.src
    depth = quilted.depth
    sets = {"quilted": build_tileset(small, **options),
            "crop": build_tileset(small, quilted_source=False, **options)}

    p1 = _with_strips(small.vertices, small.faces, plain.strips[0], small.size, depth)
    p2 = _with_strips(src.V, src.F, quilted.strips[0], src.size, depth)
    parts = []
    for k, st in enumerate(quilted.strips[0]):
        y = -0.9 * k
        for half, ds in ((st.below, -0.06), (st.above, 0.06)):
            parts.append((half[0] + [0.0, y + ds, 0.0], half[1], 4 + k))
        parts.append(box((0.0, y - 0.01, -depth - 0.01), (1.0, y + 0.01, -depth)) + (GREY,))
    p3 = labelled_parts(parts)
    tilings = {}
    for name, ts in sets.items():
        tilings[name] = _tiling(ts, depth)
        counts = [len(st.boxes) for st in (quilted if name == "quilted" else plain).strips[0]]
        _, cross, n, ratio = tilings[name]
        print(f"{name}: {len(ts)} tiles, seamless {check_seams(ts).ok}, strips of "
              f"{counts} elements, coverage {ts.metadata['coverage_mean']:.3f}; 6 x 6 "
              f"tiling: {cross} of {n} elements cross a tile side, corner density ratio "
              f"{ratio:.2f}")
    q = sets["quilted"].metadata["quilted_source"]
    panels = [
        _panel(*p1, f"1. {SET} cropped to {CROP} x {CROP}: its 2 strips hold "
               f"{' and '.join(str(len(st.boxes)) for st in plain.strips[0])} of its "
               f"{small.n_elements} studs"),
        _panel(*p2, f"2. quilted {q['side']:g} x {q['side']:g} source ({q['elements']} "
               "studs) and its 2 strips"),
        _panel(*p3, "3. the quilted source's strips, halves pulled apart"),
        _panel(*tilings["quilted"][0], f"4. 6 x 6 tiling from the quilted source: "
               f"{tilings['quilted'][1]} elements cross a side (orange)"),
        _panel(*tilings["crop"][0], f"5. the same from the crop's own strips: "
               f"{tilings['crop'][1]} cross a side"),
    ]
    path = render_panels(panels, out / "tiles_quilted_strips.png", size=(760, 720))
    print(f"wrote {path}")


# %%
# Run: the picture goes to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
