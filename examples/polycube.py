"""PolyCube shells of the catalog: Spot and the torus (genus 1).

For each base mesh of the shell catalog: the base coloured by polycube chart
label (+-X, +-Y, +-Z), the polycube itself, and the base with the polycube's
quad grid mapped back onto it (every quad edge located in the polycube and
carried to the base by barycentric coordinates). Each quad receives one Wang
tile when a tile set is mapped onto the shell.

Run:  python examples/polycube.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

from geotex.render import render_panels
from geotex.shells import load_named
from geotex.shells.picture import shell_panels


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    panels = []
    for name in ("spot", "torus"):
        shell = load_named(name)
        panels += shell_panels(shell)
        d = shell.distortion
        print(f"{name}: {shell.n_quads} quads of {shell.tile_size:g}, "
              f"{shell.polycube.chart_label.size} charts, max height {shell.max_height:.3g}, "
              f"distortion area {d['area_mean']:.3f} angle {d['angle_mean']:.3f}")
    # two rows would need a grid renderer; render one picture per row and stack them
    from PIL import Image

    rows = []
    for i, name in enumerate(("spot", "torus")):
        p = out / f".polycube_{name}.png"
        render_panels(panels[3 * i:3 * i + 3], p, size=(600, 560), up="y" if name == "spot"
                      else "z")
        rows.append(Image.open(p).convert("RGB"))
        p.unlink()
    w = max(r.width for r in rows)
    sheet = Image.new("RGB", (w, sum(r.height for r in rows)), "white")
    y = 0
    for r in rows:
        sheet.paste(r, (0, y))
        y += r.height
    from geotex.io.atomic import atomic_output

    with atomic_output(out / "polycube.png", "wb") as fh:
        sheet.save(fh, format="PNG")
    print(f"wrote {out / 'polycube.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
