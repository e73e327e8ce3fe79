"""
Displace mappings: the library's bricks on Spot (89 mm) under every mapping
===========================================================================

Pictures (written to OUT_DIR):

* ``displace_mappings.png`` - one panel per mapping (triplanar, cubic,
  cylindrical, spherical, planar-xy, uv when the part has texture
  coordinates, pgp, lapped), 20 mm per tile, 1 mm relief, with the verdict
  on the solid as an STL would store it.

Spot with its own UVs comes from ``../shared/data/base/spot_uv`` when present
(public domain, Keenan Crane); otherwise the bundled low-resolution Spot
(no UVs, so no uv panel).  ``GEOTEX_EXAMPLES_QUICK=1`` draws fewer, coarser
panels.

Run:  python examples/displace_mappings.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

from geotex.data import sample_path, shared_data_dir
from geotex.displace import displaced_mesh
from geotex.io import read_mesh
from geotex.render import Panel, render_panels

HERE = Path(sys.argv[0]).resolve().parent      # the script's folder (no __file__ in the gallery build)
SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: the bundled Spot
QUICK = bool(os.environ.get("GEOTEX_EXAMPLES_QUICK"))


def spot_89mm():
    """Spot, z up, largest extent 89 mm, with per-corner UVs when the file has them."""
    mesh = read_mesh(sample_path("spot") if SHARED is None or QUICK
                     else SHARED / "base" / "spot_uv" / "spot.obj")
    # y up -> z up, face towards the picture's camera (as geotex demo turns it)
    V = mesh.vertices[:, [0, 2, 1]] * np.array([-1.0, 1.0, 1.0])
    V = V - V.min(axis=0)
    V *= 89.0 / float(np.ptp(V, axis=0).max())
    uv = None if mesh.uv is None else np.asarray(mesh.uv)[np.asarray(mesh.uv_faces)]
    return V, mesh.faces, uv


def main(out_dir=None):
    out = Path(out_dir or HERE.parent / "docs" / "gallery")
    out.mkdir(parents=True, exist_ok=True)
    V, F, uv = spot_89mm()
    mappings = ["triplanar", "cubic", "cylindrical", "spherical", "planar-xy", "uv", "pgp",
                "lapped"]
    if uv is None:
        mappings.remove("uv")
    if QUICK:
        mappings = ["triplanar", "cylindrical", "pgp"]
    faces = 60_000 if QUICK else 250_000
    panels = []
    for m in mappings:
        t = time.perf_counter()
        kw = {"uv": uv, "scale_u": 0.25} if m == "uv" else {"scale_u": 20.0}
        r = displaced_mesh(V, F, "bricks", depth=1.0, mapping=m, target_faces=faces,
                           masks=None, **kw)
        dt = time.perf_counter() - t
        verdict = "printable" if r.report.printable else "NOT printable"
        print(f"{m}: {r.faces.shape[0]} faces, {verdict}, {dt:.1f} s")
        panels.append(Panel(r.vertices, r.faces, color="#c9b38f",
                            title=f"{m}: {r.faces.shape[0] // 1000}k faces, {verdict}"))
    cols = 4 if len(panels) > 4 else len(panels)
    for i in range(0, len(panels), cols):
        suffix = "" if i == 0 else f"_{i // cols + 1}"
        path = out / f"displace_mappings{suffix}.png"
        render_panels(panels[i:i + cols], path, size=(700, 700), up="z")
        print(f"wrote {path}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
