"""
Material-space tiles (paper Fig. 1): the 3D (s, t, m) tile and Spot with material varying
=========================================================================================

Writes into OUT_DIR (default docs/gallery):

* ``material_tiles.png`` - left: the tile as a stack of its m-slices (s, t
  across, m upwards); right: Spot textured through the PGP with ``m`` running
  from the tail (first texture) to the head (second texture), the (s, t, m)
  lookup baked into a texture atlas;
* ``material_tiles_slices.png`` - the m-slices side by side (each repeated
  2 x 2 to show that it wraps) with their morphed feature masks below.

Images: almonds (m = 0) and peppers (m = 1) from ``../shared/data/images``
(quilting classics); without the shared data (a clean clone), the bundled
brick wall (m = 0) and water (m = 1) photos (``geotex/data/NOTICE.md``).
``GEOTEX_EXAMPLES_QUICK=1`` draws a smaller tile.

Run:  python examples/material_tiles.py [OUT_DIR]
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import igl
import numpy as np

from geotex.data import sample_path, shared_data_dir
from geotex.fields.directions import smooth_direction_field
from geotex.image.material.mapping import bake_material_texture, default_material
from geotex.image.material.tile import build_material_tile, tile_slices_image
from geotex.io import read_mesh
from geotex.io.images import load_texture_image, texture_to_png_bytes
from geotex.param.pgp import periodic_parameterization
from geotex.render import Panel, render_panels

SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: bundled images
QUICK = bool(os.environ.get("GEOTEX_EXAMPLES_QUICK"))


def inputs() -> tuple[np.ndarray, np.ndarray, str]:
    """The two images (m = 0, m = 1) and their caption: quilting classics from the
    shared data, else two bundled sample photos."""
    if SHARED is not None:
        folder = SHARED / "images" / "quilting_classic"
        a, b = (folder / n for n in ("t5_almonds.png", "t6_peppers.png"))
        return load_texture_image(a), load_texture_image(b), "almonds -> peppers"
    return (load_texture_image(sample_path("bricks")), load_texture_image(sample_path("water")),
            "brick photo -> water photo")


def stacked_slices(tile, *, gap: float = 0.28):
    """One quad per m-slice, stacked along z, textured from a side-by-side atlas."""
    K = tile.n_layers
    atlas = np.concatenate(list(tile.layers), axis=1)                 # (n, K n, 3)
    V, F, uv = [], [], []
    for k in range(K):
        z = k * gap
        V += [[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]]
        u0, u1 = k / K, (k + 1) / K
        uv += [[u0, 0], [u1, 0], [u1, 1], [u0, 1]]
        F += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
    return (np.array(V, float), np.array(F, np.int64), np.array(uv, float),
            np.ascontiguousarray(atlas))


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    A, B, label = inputs()
    size, layers = (32, 4) if QUICK else (96, 6)
    t0 = time.perf_counter()
    tile = build_material_tile(A, B, size=size, layers=layers, seed=0)
    t_tile = time.perf_counter() - t0
    (out / "material_tiles_slices.png").write_bytes(
        texture_to_png_bytes(np.kron(tile_slices_image(tile, repeat=2),
                                     np.ones((2, 2, 1), np.uint8))))
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces          # y-up -> z-up
    V, F = igl.upsample(V, F, 1)
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    field = smooth_direction_field(V, F, symmetry=4, seed=0)
    params = periodic_parameterization(V, F, field, scale=0.35)
    # m from the tail (0) to the head (1): Spot's head points along -y after the swap
    material = default_material(V, F, up=[0.0, -1.0, 0.0])
    textured = bake_material_texture(V, F, params, material, tile, field=field,
                                     resolution=1024 if QUICK else 2048)
    Vc = V[F].reshape(-1, 3)
    Fc = np.arange(Vc.shape[0], dtype=np.int64).reshape(-1, 3)
    uv = textured.uv[textured.uv_faces].reshape(-1, 2)
    Vs, Fs, uvs, atlas = stacked_slices(tile)
    h = tile.metadata["histogram_distance"][1:-1]
    c = tile.metadata["cross_fade_histogram_distance"][1:-1]
    # close-up: a point in the middle of the body, where m is near 1/2 (the whole mesh,
    # seen by the renderer's close-up camera)
    mid = np.abs(material - 0.5) + 0.01 * (V[:, 2] < np.percentile(V[:, 2], 40))
    spot_mid = V[int(np.argmin(mid))]
    panels = [Panel(Vs, Fs, uv=uvs, texture=atlas,
                    title=f"(s, t, m) tile: {label}\n{layers} slices of {size}^2, "
                          f"built in {t_tile:.0f} s"),
              Panel(Vc, Fc, uv=uv, texture=textured.texture,
                    title=f"Spot, m from tail (0) to head (1)\n"
                          f"{int(params.singular.sum())} singular faces blended"),
              Panel(Vc, Fc, uv=uv, texture=textured.texture, closeup=spot_mid,
                    closeup_radius=0.15 * float(np.linalg.norm(np.ptp(V, axis=0))),
                    title="close-up where m is about 1/2")]
    render_panels(panels, out / "material_tiles.png", size=(700, 650))
    print(f"tile {label}: {t_tile:.1f} s; histogram distance inner layers "
          f"{np.mean(h):.4f} (cross-fade {np.mean(c):.4f}); mask areas "
          f"{tile.metadata['mask_areas']}")
    print(f"wrote {out / 'material_tiles.png'} and {out / 'material_tiles_slices.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else
         Path(__file__).resolve().parents[1] / "docs" / "gallery")
