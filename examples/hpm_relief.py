"""
The relief version of hierarchical pattern mapping
==================================================

``geotex hpm ... --displace MM``: the image that hierarchical pattern mapping
lays over the surface (per-corner coordinates into the image itself) is read
as a height map (light high) through the shared relief path of ``geotex
displace`` and becomes a printable solid.  Spot (the bundled low-resolution
cow, one Loop subdivision) at 80 mm, a gravel photo from the shared data (or,
in a clean clone and in quick mode, the bundled brick wall depth map of the
Godot demos, inverted so that the bricks stand and the mortar is low), 1 mm
deep; the file is
written only when printable as an STL stores it.  Panels: the textured map
(what ``geotex hpm`` writes as GLB) and the relief, whole and a close-up
of the head and neck.

Run:  python examples/hpm_relief.py [OUT_DIR]     (default docs/gallery)
"""

# %%
# Map the image, read it as heights through the same coordinates, write and look.

from __future__ import annotations

import os
import sys
from pathlib import Path

import igl
import numpy as np

from geotex.data import sample_path, shared_data_dir
from geotex.displace import displaced_mesh
from geotex.image.hpm import hpm_texture, read_hpm_image
from geotex.io import read_mesh, write_mesh
from geotex.mesh.record import Mesh
from geotex.printing import export_printable
from geotex.render import Panel, render_panels
from geotex.viewpage import mesh_turned_y_up

SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: a bundled image
QUICK = os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces      # y-up -> z-up
    V = (V - V.min(axis=0)) * (80.0 / float(np.ptp(V, axis=0).max()))
    V, F = igl.upsample(V, F, 1)
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    if QUICK or SHARED is None:
        # a depth map (light is deep): inverted, the bricks stand and the mortar is low
        label, img = "brick depth map, inverted", 255 - read_hpm_image(sample_path("bricks-height"))
    else:
        label, img = "gravel photo", read_hpm_image(SHARED / "images" / "quilting_classic"
                                                    / "t4_gravel.png")
    r = hpm_texture(V, F, img, scale=30.0, seed=0)                 # 30 mm per image width
    uv = r.uv[r.uv_faces]                                          # (m, 3, 2)
    res = displaced_mesh(V, F, img, depth=1.0, mapping="uv", uv=uv,
                         target_faces=120_000 if QUICK else 500_000)
    rep = export_printable(out / "hpm_relief.stl", res.vertices, res.faces, report=res.report)
    write_mesh(out / "hpm_relief.glb", mesh_turned_y_up(Mesh(res.vertices, res.faces), up="z"))
    Vc = V[F].reshape(-1, 3)
    Fc = np.arange(Vc.shape[0], dtype=np.int64).reshape(-1, 3)
    near = V[int(np.argmin(np.linalg.norm(V - (V.min(0) + np.ptp(V, 0) * [0.8, 0.12, 0.65]),
                                           axis=1)))]
    render_panels([
        Panel(Vc, Fc, uv=uv.reshape(-1, 2), texture=img,
              title=f"hpm: {label}, 30 mm per image\n{len(F)} faces"),
        Panel(res.vertices, res.faces, color="#c8b08c",
              title=f"relief 1 mm: {len(res.faces)} faces\nprintable as STL: "
                    f"{'yes' if rep.printable else 'no'}"),
        Panel(res.vertices, res.faces, color="#c8b08c", closeup=near, closeup_radius=15.0,
              title="close-up: head and neck"),
    ], out / "hpm_relief.png", size=(640, 640))
    print(f"{label}: {len(res.faces)} faces, printable {rep.printable}")
    print(f"wrote {out / 'hpm_relief.png'}")


# %%
# Run: the pictures (and a GLB shown in the 3D viewer) go to the folder given as the
# first argument, by default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
