"""
Hiding the periodicity of a tile by modulating m (paper Fig. 14), on Spot
=========================================================================

Writes ``material_periodicity.png`` into OUT_DIR (default docs/gallery):

A. a brick tile in repeat mode (``m = 0`` everywhere): the repetition shows
   (close-up of Spot's flank);
B. the same flank through a 4-layer periodicity-hiding tile (every layer has the
   bricks' feature mask, the layers differ in their details), with ``m``
   modulated over the surface by smooth noise (wavelength 3 tiles);
C. the modulated ``m`` (colour).

Also ``material_periodicity_tile.png``: the four layers (2 x 2 repeats each).

Image: ``t1_bricks`` from ``../shared/data/images``; without the shared
data (a clean clone), a 128-pixel crop of the bundled brick wall photo
(``geotex/data/NOTICE.md``).
``GEOTEX_EXAMPLES_QUICK=1`` draws a smaller tile.

Run:  python examples/material_periodicity.py [OUT_DIR]
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import igl
import numpy as np

from geotex.data import sample_path, shared_data_dir
from geotex.fields.directions import projected_direction_field
from geotex.image.material.mapping import bake_material_texture, modulated_material
from geotex.image.material.tile import build_periodicity_tile, tile_slices_image
from geotex.io import read_mesh
from geotex.io.images import load_texture_image, texture_to_png_bytes
from geotex.param.pgp import periodic_parameterization
from geotex.render import Panel, render_panels

SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: a bundled image
QUICK = bool(os.environ.get("GEOTEX_EXAMPLES_QUICK"))


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    if SHARED is not None:
        label = "bricks (quilting classic)"
        img = load_texture_image(SHARED / "images" / "quilting_classic" / "t1_bricks.png")
    else:
        # a 128-texel crop (left, below the middle) of the 256-texel photo: the tile
        # resamples its input, and the whole photo would leave bricks 3 texels high
        label = "brick photo, crop"
        img = load_texture_image(sample_path("bricks"))[100:228, :128]
    size = 32 if QUICK else 96
    tile = build_periodicity_tile(img, size=size, layers=4, seed=0)
    strip = tile_slices_image(tile, repeat=2, masks=False)
    zoom = max(2, -(-200 // strip.shape[0]))                  # at least 200 pixels high
    (out / "material_periodicity_tile.png").write_bytes(
        texture_to_png_bytes(np.kron(strip, np.ones((zoom, zoom, 1), np.uint8))))
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces
    V, F = igl.loop(V, F, 1)                                  # smooth: no facets in the close-up
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    field, _ = projected_direction_field(V, F, [0.0, 0.0, 1.0])
    scale = 0.3
    params = periodic_parameterization(V, F, field, scale=scale)
    res = 1024 if QUICK else 2048
    flat = np.zeros(V.shape[0])
    repeat = bake_material_texture(V, F, params, flat, tile, field=field, resolution=res)
    m = modulated_material(V, np.full(V.shape[0], 0.5), amplitude=0.5, wavelength=3 * scale,
                           seed=0)
    hidden = bake_material_texture(V, F, params, m, tile, field=field, resolution=res)
    # close-up: the flank (the whole mesh, seen by the renderer's close-up camera)
    lo, hi = V.min(axis=0), V.max(axis=0)
    target = lo + (hi - lo) * np.array([1.0, 0.6, 0.5])
    flank = V[int(np.argmin(np.linalg.norm(V - target, axis=1)))]
    Vc = V[F].reshape(-1, 3)
    Fc = np.arange(Vc.shape[0], dtype=np.int64).reshape(-1, 3)
    radius = 0.12 * float(np.linalg.norm(hi - lo))

    def textured(mesh, title):
        return Panel(Vc, Fc, uv=mesh.uv[mesh.uv_faces].reshape(-1, 2), texture=mesh.texture,
                     closeup=flank, closeup_radius=radius, title=title)

    panels = [textured(repeat, f"A: {label}, repeat mode (m = 0)\nflank close-up"),
              textured(hidden, "B: m modulated over 4 layers\n(same mask, other details)"),
              Panel(V, F, scalars=m, cmap="viridis", title="C: m (wavelength 3 tiles)")]
    render_panels(panels, out / "material_periodicity.png", size=(700, 600))
    print(f"wrote {out / 'material_periodicity.png'} and "
          f"{out / 'material_periodicity_tile.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else
         Path(__file__).resolve().parents[1] / "docs" / "gallery")
