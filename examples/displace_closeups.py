"""
Displace close-ups: bricks on a cylinder and on Spot, triplanar vs pgp
======================================================================

Pictures (written to OUT_DIR):

* ``displace_closeups.png`` - left: a closed cylinder (r 20 x h 40 mm)
  with the library's bricks (20 mm per tile, 1 mm relief) under triplanar,
  cylindrical and pgp; right: their close-ups at the cap edge (8 mm around
  it; the inset circles where).
* ``displace_closeups_spot.png`` - Spot at 89 mm: triplanar and pgp, whole
  and the flank close up.  Triplanar's blend zones (where the normal is
  about 45 degrees from two axes) mix two projections of the bricks; pgp
  follows a smooth cross field, so courses bend with the surface and only
  meet at the field's few singular points.

``GEOTEX_EXAMPLES_QUICK=1`` uses coarser meshes.

Run:  python examples/displace_closeups.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

from geotex.displace import displaced_mesh
from geotex.mesh.primitives import closed_cylinder
from geotex.render import Panel, render_panels

HERE = Path(sys.argv[0]).resolve().parent      # the script's folder (no __file__ in the gallery build)
sys.path.insert(0, str(HERE))
QUICK = bool(os.environ.get("GEOTEX_EXAMPLES_QUICK"))


def run(V, F, mapping, faces):
    t = time.perf_counter()
    r = displaced_mesh(V, F, "bricks", depth=1.0, mapping=mapping, scale_u=20.0,
                       target_faces=faces)
    verdict = "printable" if r.report.printable else "NOT printable"
    print(f"{mapping}: {r.faces.shape[0]} faces, {verdict}, {time.perf_counter() - t:.1f} s")
    return r, verdict


def main(out_dir=None):
    from displace_mappings import spot_89mm

    out = Path(out_dir or HERE.parent / "docs" / "gallery")
    out.mkdir(parents=True, exist_ok=True)
    faces = 80_000 if QUICK else 500_000
    V, F = closed_cylinder(20.0, 40.0, n_theta=200 if not QUICK else 64,
                           n_height=130 if not QUICK else 20,
                           n_cap_rings=20 if not QUICK else 5)
    top, bottom = [], []
    edge = np.array([20 / np.sqrt(2), -20 / np.sqrt(2), 40.0])
    for m in (["triplanar", "pgp"] if QUICK else ["triplanar", "cylindrical", "pgp"]):
        r, verdict = run(V, F, m, faces)
        top.append(Panel(r.vertices, r.faces, color="#c9b38f",
                         title=f"cylinder, {m}: {r.faces.shape[0] // 1000}k faces, {verdict}"))
        bottom.append(Panel(r.vertices, r.faces, color="#c9b38f", closeup=edge,
                            closeup_radius=8.0, title=f"{m}: cap edge"))
    path = out / "displace_closeups.png"
    render_panels(top + bottom, path, size=(620, 620), up="z")
    print(f"wrote {path}")

    V, F, _ = spot_89mm()
    panels = []
    for m in ("triplanar", "pgp"):
        r, verdict = run(V, F, m, faces)
        hi = V.max(axis=0)
        c = V[np.argmin(np.linalg.norm(V - np.array([hi[0], 0.5 * hi[1], 0.45 * hi[2]]),
                                       axis=1))]
        panels.append(Panel(r.vertices, r.faces, color="#c9b38f",
                            title=f"Spot, {m}: {r.faces.shape[0] // 1000}k faces, {verdict}"))
        panels.append(Panel(r.vertices, r.faces, color="#c9b38f", closeup=c,
                            closeup_radius=12.0, title=f"{m}: flank"))
    path = out / "displace_closeups_spot.png"
    render_panels(panels, path, size=(620, 620), up="z")
    print(f"wrote {path}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
