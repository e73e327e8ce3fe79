"""
A planar height-and-tilt texture tiled over Spot and Bob along the "up" field
=============================================================================

Left: the planar texture, leaning bumps on a periodic square (one tile).
Middle and right: the same texture on Spot and on Bob (the bundled meshes). Each base is remeshed to the texture's resolution, covered
with disc patches that are flattened along the projected "up" direction
(field-aligned parameterization), and the texture is read through the
patches: heights resampled, the tilt 1-form integrated along every edge
through the map. Every bump leans up the surface, following the field; the
patch seams are matched in texture space and blended.

``GEOTEX_EXAMPLES_QUICK=1`` (the test suite) textures Spot only.

Run:  python examples/heighttilt_transfer.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

from geotex.data import sample_path
from geotex.heighttilt import apply_texture, bumpy_plane, extract_texture, transfer_planar
from geotex.io import read_mesh
from geotex.render import Panel, render_panels

COLOR = "#b97a56"


def textured(name, V, F, plane, scale):
    V0, Fp, Vs, tex = plane
    t = time.perf_counter()
    res = transfer_planar(Vs, Fp, tex, V, F, scale=scale, field="up", up=(0, 0, 1), seed=0)
    Vt = apply_texture(res.vertices, res.faces, res.texture)
    print(f"{name}: {len(V)} -> {len(res.vertices)} vertices, {res.n_patches} patches, "
          f"{time.perf_counter() - t:.1f} s")
    return res, Vt


def tiles(V0, F, k=2):
    """``k x k`` copies of the periodic tile, stood up: x (the lean) -> z, normal -> +x."""
    Vs, Fs = [], []
    for i in range(k):
        for j in range(k):
            Vs.append(V0 + [i, j, 0.0])
            Fs.append(F + len(V0) * (i * k + j))
    V = np.concatenate(Vs)
    return np.column_stack([V[:, 2], -V[:, 1], V[:, 0]]), np.concatenate(Fs)


def flank_point(V):
    """The middle of the +x flank (facing the camera): where the close-up looks."""
    c = 0.5 * (V.min(axis=0) + V.max(axis=0))
    mid = (np.abs(V[:, 1] - c[1]) < 0.15) & (np.abs(V[:, 2] - c[2]) < 0.15)
    return V[mid][np.argmax(V[mid, 0])]


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    V0, F, Vs = bumpy_plane(24, 24, bumps=7, height=0.24, radius=0.13, lean_degrees=50,
                            periodic=True, direction=(1, 0), seed=5)
    tex, Vs = extract_texture(V0, F, base=Vs)
    plane = (V0, F, Vs, tex)
    panels = [Panel(*tiles(V0, F), color=COLOR, title="planar texture, 2 x 2 tiles (x up)")]
    spot = read_mesh(sample_path("spot"))
    Vspot = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1]                 # y-up -> z-up
    res, Vt = textured("Spot", Vspot, spot.faces, plane, scale=0.3)
    panels.append(Panel(Vt, res.faces, color=COLOR,
                        title=f"Spot: {len(Vt) // 1000}k vertices, {res.n_patches} patches"))
    panels.append(Panel(Vt, res.faces, color=COLOR, closeup=flank_point(Vt),
                        closeup_radius=0.3, title="Spot, close up: bumps lean up"))
    if os.environ.get("GEOTEX_EXAMPLES_QUICK") != "1":
        bob = read_mesh(sample_path("bob"))
        Vbob = bob.vertices[:, [0, 2, 1]] * [-1, 1, 1]
        res, Vt = textured("Bob", Vbob, bob.faces, plane, scale=0.3)
        panels.append(Panel(Vt, res.faces, color=COLOR,
                            title=f"Bob: {len(Vt) // 1000}k vertices, {res.n_patches} patches"))
    render_panels(panels, out / "heighttilt_transfer.png", size=(520, 620), up="z")
    print(f"wrote {out / 'heighttilt_transfer.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
