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

import copy
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.io.atomic import atomic_output
from geotex.render import render_panels
from geotex.shells import load_named
from geotex.shells.picture import shell_panels

SHELLS = {"spot": "y", "bob": "z", "blub": "y", "torus": "z"}   # name -> up axis


def turned_z_up(panels):
    """y-up panels turned z-up with the model's face towards the camera (as geotex demo turns it)."""
    def turn(P):
        return np.asarray(P)[:, [0, 2, 1]] * np.array([-1.0, 1.0, 1.0])

    out = []
    for p in panels:
        q = copy.copy(p)
        q.V = turn(p.V)
        q.markers = {k: (turn(P), c) for k, (P, c) in p.markers.items()}
        if p.arrows is not None:
            q.arrows = (turn(p.arrows[0]), turn(p.arrows[1]))
        out.append(q)
    return out


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
        panels = shell_panels(shell)
        if up == "y":
            panels, up = turned_z_up(panels), "z"
        render_panels(panels, p, size=(560, 520), up=up)
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
