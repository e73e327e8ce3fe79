"""
Geometric Wang tiles: every catalog set laid out tile by tile, and a random tiling of it
========================================================================================

For each set of the tile catalog (``geotex tiles list``), two pictures:

* ``tiles_NAME_layout.png``: every tile on its own plate, with a bar along each
  side in the colour of that side (one hue family per axis class; an isotropic
  set has one family for all sides).
* ``tiles_NAME_tiling.png``: a random legal 6 x 6 arrangement (planar group),
  welded by exact position and united with a slab into one printable solid;
  the ticks along two slab edges mark the tile borders. Elements cut by the
  tiling's outer border are dropped, except the weave's strands, which run
  across the whole tiling and are capped there (the set's ``tiling_border``).

The script also prints, per set, the seam check and whether the tiling is
printable. ``GEOTEX_EXAMPLES_QUICK=1`` (the test suite) draws the two smallest
sets only.

Run:  python examples/tiles.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from geotex.check import check_mesh
from geotex.tiles import list_tilesets, load_named
from geotex.tiles.preview import render_tiles, render_tiling
from geotex.tiles.tiling import on_slab, planar_tiling, random_arrangement
from geotex.tiles.verify import check_seams


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    entries = list_tilesets()
    if not entries:
        raise SystemExit("the tile catalog is empty")
    if os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1":
        entries = sorted(entries, key=lambda e: e["bytes"])[:2]
    for entry in entries:
        tiles = load_named(entry["name"])
        seams = check_seams(tiles)
        # the planar group (0, 1) of any set tiles the plane
        V, F = on_slab(*planar_tiling(tiles, random_arrangement(tiles, 6, 6, seed=0)), (6, 6))
        printable = check_mesh(V, F).printable
        render_tiles(tiles, out / f"tiles_{entry['name']}_layout.png")
        render_tiling(tiles, out / f"tiles_{entry['name']}_tiling.png", grid=6, seed=0)
        print(f"{entry['name']:16s} {tiles.kind:10s} {len(tiles):3d} tiles, "
              f"{entry['bytes'] / 1e6:.2f} MB, seams {'ok' if seams.ok else 'BROKEN'} "
              f"({seams.pairs_checked} side pairs), 6 x 6 tiling printable: {printable}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
