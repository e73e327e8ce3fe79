"""
A brick relief on Spot through the periodic global parameterization
===================================================================

The height-map version of ``geotex tile-image``: the same per-corner tile
coordinates of ``geotex pgp`` read a periodic height map (the ``bricks`` map of
``geotex displace --list``), the part is refined by exact edge splits and
every vertex moves along its crease-aware normal (the shared relief path of
``geotex displace``).  Spot is scaled to 80 mm, 0.8 mm deep bricks, one tile
(two courses) about 11 mm, the cross field follows the up axis so the
courses stay horizontal on the flanks; the file is written only when it is
printable as an STL stores it.  Panels: the whole part, and a close-up of the
rump, where the up field turns round a cone: the courses bend and a few
singular faces show a rough patch.

Run:  python examples/pgp_relief.py [OUT_DIR]     (default docs/gallery)
"""

# %%
# Build the parameterization, read the relief through it, write and look.

from __future__ import annotations

import os
import sys
from pathlib import Path

import igl
import numpy as np

from geotex.data import sample_path
from geotex.displace import displaced_mesh
from geotex.displace.library import library_height_map
from geotex.fields.directions import projected_direction_field
from geotex.io import read_mesh, write_mesh
from geotex.mesh.record import Mesh
from geotex.param.pgp import periodic_parameterization
from geotex.printing import export_printable
from geotex.render import Panel, render_panels
from geotex.viewpage import mesh_turned_y_up

QUICK = os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces      # y-up -> z-up
    V = (V - V.min(axis=0)) * (80.0 / float(np.ptp(V, axis=0).max()))  # 80 mm, on the bed
    V, F = igl.upsample(V, F, 1 if QUICK else 2)
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    up, _ = projected_direction_field(V, F, (0.0, 0.0, 1.0))
    tile_mm = 11.0
    p = periodic_parameterization(V, F, up, scale=tile_mm)
    # courses across the field's s axis: the map's rows run along t
    H = library_height_map("bricks").T.copy()
    res = displaced_mesh(V, F, H, depth=0.8, mapping="uv", uv=p.coords,
                         target_faces=150_000 if QUICK else 600_000)
    rep = export_printable(out / "pgp_relief.stl", res.vertices, res.faces, report=res.report)
    write_mesh(out / "pgp_relief.glb", mesh_turned_y_up(Mesh(res.vertices, res.faces), up="z"))
    rump = V[np.argmax(V[:, 1])]                        # the back end, below the tail
    title = (f"bricks through the PGP: {len(res.faces)} faces\ntile {tile_mm:g} mm, 0.8 mm "
             f"deep, printable as STL: {'yes' if rep.printable else 'no'}")
    render_panels([Panel(res.vertices, res.faces, color="#c8a27a", title=title),
                   Panel(res.vertices, res.faces, color="#c8a27a", closeup=rump,
                         closeup_radius=14.0,
                         title="close-up: the rump, where the field\nturns round a cone")],
                  out / "pgp_relief.png", size=(900, 760))
    print(f"{title.replace(chr(10), ' ')}; {len(p.cones)} cones, {int(p.singular.sum())} singular faces")
    print(f"wrote {out / 'pgp_relief.png'}")


# %%
# Run: the pictures (and a GLB shown in the 3D viewer) go to the folder given
# as the first argument, by default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
