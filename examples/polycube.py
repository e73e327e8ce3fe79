"""
PolyCube shells of the catalog: Spot, Bob (genus 1), Blub and a torus
=====================================================================

For each shell of the catalog, one row: the voxel polycube coloured by quad
direction (+-X, +-Y, +-Z), the same quads fitted onto the base (the map that
carries tiles to the surface), and the base with the tile grid drawn on it.
Each grid quad receives one Wang tile when a tile set is mapped onto the shell.

Run:  python examples/polycube.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

from PIL import Image

from geotex.io.atomic import atomic_output
from geotex.render import render_panels
from geotex.shells import load_named
from geotex.shells.picture import shell_panels

SHELLS = {"spot": "y", "bob": "z", "blub": "y", "torus": "z"}   # name -> up axis


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for name, up in SHELLS.items():
        shell = load_named(name)
        d, c = shell.distortion, shell.polycube.diagnostics.coverage
        print(f"{name}: {shell.n_quads} quads of {shell.tile_size:g}, "
              f"{int(shell.polycube.quad_folded.sum())} folded, max height "
              f"{shell.max_height:.3g}, distortion area {d['area_mean']:.3f} "
              f"angle {d['angle_mean']:.3f}, base within 1/4 tile {c['within_quarter_tile']:.3f}")
        p = out / f".polycube_{name}.png"
        render_panels(shell_panels(shell), p, size=(560, 520), up=up)
        with Image.open(p) as im:
            rows.append(im.convert("RGB"))
        p.unlink()
    sheet = Image.new("RGB", (max(r.width for r in rows), sum(r.height for r in rows)), "white")
    y = 0
    for r in rows:
        sheet.paste(r, (0, y))
        y += r.height
    with atomic_output(out / "polycube.png", "wb") as fh:
        sheet.save(fh, format="PNG")
    print(f"wrote {out / 'polycube.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
