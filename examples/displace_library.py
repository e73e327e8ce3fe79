"""
Displace: the procedural height-map library
===========================================

Pictures (written to OUT_DIR):

* ``displace_library.png`` - every library map (``geotex displace --list``)
  tiled 2 x 2, so the seams of the repetition would show if there were any,
  with its name.

Run:  python examples/displace_library.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from geotex.displace.library import library_height_map, library_names

HERE = Path(sys.argv[0]).resolve().parent      # the script's folder (no __file__ in the gallery build)


def main(out_dir=None):
    out = Path(out_dir or HERE.parent / "docs" / "gallery")
    out.mkdir(parents=True, exist_ok=True)
    names = library_names()
    cell, pad, label = 200, 8, 22
    cols = 6
    rows = -(-len(names) // cols)
    sheet = Image.new("RGB", (cols * (cell + pad) + pad, rows * (cell + pad + label) + pad),
                      "white")
    draw = ImageDraw.Draw(sheet)
    for k, name in enumerate(names):
        H = library_height_map(name, size=256)
        tiled = np.tile(H, (2, 2))                       # 2 x 2 tiles: seams would show
        im = Image.fromarray((tiled * 255).round().astype(np.uint8)).resize((cell, cell),
                                                                           Image.LANCZOS)
        r, c = divmod(k, cols)
        x, y = pad + c * (cell + pad), pad + r * (cell + pad + label)
        sheet.paste(im.convert("RGB"), (x, y + label))
        draw.text((x + 2, y + 4), name, fill="black")
    path = out / "displace_library.png"
    sheet.save(path)
    print(f"wrote {path} ({len(names)} maps)")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
