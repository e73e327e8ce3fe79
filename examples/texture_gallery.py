"""
Gallery of the main job: every catalog tile set on catalog shells
=================================================================

For every tile set of the catalog that can cover a closed shape (complete,
isotropic or directional sets; planar sets only tile the plane; a directional
set is turned to the shell's up axis) and each of the shells
Spot, Bob and the torus: lay the tiles over the shell, unite them with the
base, check the solid, and draw it. One picture per tile set
(``texture_gallery_<set>.png``, a row of three shells and a close-up of the
first one, about three tiles across, where the elements and the tile seams
can be judged) and one overview (``texture_gallery.png``, the first shell of
every set). The printable solids
are written as STL beside the pictures.

Set ``GEOTEX_EXAMPLES_QUICK=1`` (the test suite does) to draw one set on one
shell only.

Run:  python examples/texture_gallery.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.io import write_mesh
from geotex.io.atomic import atomic_output
from geotex.mapping import textured_solid
from geotex.mesh import Mesh
from geotex.printing import export_printable
from geotex.render import Panel, render_panels, view_direction
from geotex.shells import load_named as load_shell
from geotex.tiles.catalog import list_tilesets, load_named as load_tiles
from geotex.tiles.directional import oriented_tileset
from geotex.viewpage import mesh_turned_y_up

SHELLS = {"spot": "y", "bob": "z", "torus": "z"}   # name -> up axis (y-up is turned z-up)
CLOSEUP_TILES = 1.5        # radius of the close-up, in tile sizes of the shell
COLOURS = ("#c9b38f", "#a9bfd1", "#b9c99a", "#d1a9a9", "#c4b0d6", "#d6c7a0")


def _sets():
    return [r["name"] for r in list_tilesets() if r["kind"] != "planar"]


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    quick = os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1"
    sets = _sets()[:1] if quick else _sets()
    shells = dict(list(SHELLS.items())[:1]) if quick else SHELLS
    firsts = []
    for k, name in enumerate(sets):
        tiles = load_tiles(name)
        panels = []
        for shell_name, up in shells.items():
            shell = load_shell(shell_name)
            t = time.perf_counter()
            # a directional set (scales) follows the shell's up axis (hangs down)
            res = textured_solid(shell, oriented_tileset(tiles, up="xyz".index(up))
                                 if tiles.directional else tiles, seed=0)
            dt = time.perf_counter() - t
            s = res.stats
            print(f"{name} on {shell_name}: {s.quads} tiles, {s.elements} elements, "
                  f"{s.faces} faces, printable {res.report.printable}, {dt:.1f} s")
            if res.report.printable:
                export_printable(out / f"texture_gallery_{name}_{shell_name}.stl",
                                 res.vertices, res.faces, report=res.report)
                if k == 0 and not firsts and not panels:   # one model for the 3D viewer
                    write_mesh(out / f"texture_gallery_{name}_{shell_name}.glb",
                               mesh_turned_y_up(Mesh(res.vertices, res.faces), up=up))
            shown = res.vertices[:, [0, 2, 1]] * [-1.0, 1.0, 1.0] if up == "y" else res.vertices
            panels.append(Panel(shown, res.faces, color=COLOURS[k % len(COLOURS)],
                                title=f"{name} on {shell_name}, {s.elements} elements"
                                + ("" if res.report.printable else " (NOT printable)")))
            if len(panels) == 1:
                # the point of the first shell that stands out most towards the camera
                towards = (shown - shown.mean(axis=0)) @ view_direction("z")
                closeup = Panel(shown, res.faces, color=COLOURS[k % len(COLOURS)],
                                title=f"{name} on {shell_name}, close-up",
                                closeup=shown[np.argmax(towards)],
                                closeup_radius=CLOSEUP_TILES * shell.tile_size)
        panels.append(closeup)
        path = out / f"texture_gallery_{name}.png"
        render_panels(panels, path, size=(640, 600), up="z")
        with Image.open(path) as im:
            firsts.append(im.convert("RGB").crop((0, 0, im.width // len(panels), im.height)))
        print(f"wrote {path}")
    # a grid with no empty cell: one row up to five sets, else rows of 3, 4 or 2
    n = len(firsts)
    cols = n if n <= 5 else next((c for c in (3, 4, 2) if n % c == 0), n)
    rows = (len(firsts) + cols - 1) // cols
    w, h = firsts[0].size
    sheet = Image.new("RGB", (cols * w, rows * h), "white")
    for i, im in enumerate(firsts):
        sheet.paste(im, ((i % cols) * w, (i // cols) * h))
    with atomic_output(out / "texture_gallery.png", "wb") as fh:
        sheet.save(fh, format="PNG")
    print(f"wrote {out / 'texture_gallery.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
