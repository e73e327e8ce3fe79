"""
A tileable image laid over Spot through the periodic global parameterization
============================================================================

``geotex pgp`` gives every face corner tile coordinates ``(s, t)``;
``geotex tile-image`` uses them directly as texture coordinates, one image
period per tile (no atlas, nothing resampled).  Left: a tile with the square's
symmetry (rounded studs on a grid), which hides the quarter turns the cross
field's combing leaves between charts, so the pattern runs on without a seam
except on the singular faces (around the cones, marked).  Right: a running-bond
brick tile, which is periodic but not symmetric under a quarter turn, on a
field projected from the up axis: the courses stay horizontal on the head,
flanks and legs, and the quarter turns show where the field must turn (on the
back, where "up" is normal to the surface).  Singular faces show one correctly sized piece of the tile (the
field's local map), not a squeezed period.

Run:  python examples/pgp_tile_image.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

import igl
import numpy as np

from geotex.data import sample_path
from geotex.fields.directions import projected_direction_field, smooth_direction_field
from geotex.image.tiled import tiled_texture_mesh
from geotex.io import read_mesh, write_mesh
from geotex.param.pgp import periodic_parameterization
from geotex.render import Panel, render_panels
from geotex.viewpage import mesh_turned_y_up


def stud_tile(px: int = 128) -> np.ndarray:
    """Rounded studs centred on the tile (invariant under quarter turns and shifts)."""
    u = (np.arange(px) + 0.5) / px - 0.5
    r = np.hypot(u[:, None], u[None, :])
    shade = np.clip((0.36 - r) / 0.05, 0.0, 1.0)
    light = 0.5 + 0.5 * np.clip(-(u[:, None] + u[None, :]) / 0.5, -1, 1)
    stud = np.array([176, 64, 52]) * (0.75 + 0.35 * light[..., None])
    base = np.array([236, 226, 204])
    img = base * (1 - shade[..., None]) + stud * shade[..., None]
    return np.ascontiguousarray(np.clip(img, 0, 255).astype(np.uint8))


def brick_tile(px: int = 128) -> np.ndarray:
    """Two courses of running-bond bricks (periodic, not quarter-turn symmetric), courses vertical."""
    y = (np.arange(px) + 0.5) / px
    x = (np.arange(px) + 0.5) / px
    course = (y * 2).astype(int)                                   # 0 or 1, row index
    shift = np.where(course % 2 == 1, 0.5, 0.0)[:, None]
    bx = (x[None, :] + shift) % 1.0
    by = (y * 2) % 1.0
    mortar = (np.minimum(bx, 1 - bx) < 0.03) | (np.minimum(by, 1 - by)[:, None] < 0.06)
    rng = np.random.default_rng(3)
    tone = rng.uniform(0.85, 1.1, size=(2, 2))[course[:, None], (bx * 2).astype(int) % 2]
    brick = np.array([170, 78, 52])[None, None] * tone[..., None]
    img = np.where(mortar[..., None], np.array([214, 208, 196]), brick)
    # courses along the image's columns: s (the image's x axis) follows the field
    # (the up axis on the flanks), so the courses run across it, horizontally
    return np.ascontiguousarray(np.clip(img, 0, 255).astype(np.uint8).transpose(1, 0, 2))


def panel(V, F, field, image, *, tile: float, title: str, out: Path, stem: str):
    p = periodic_parameterization(V, F, field, scale=tile)
    textured = tiled_texture_mesh(V, F, p.coords, image)
    write_mesh(out / f"{stem}.glb", mesh_turned_y_up(textured, up="z"))
    Vc = V[F].reshape(-1, 3)                       # one vertex per corner: per-corner uv
    Fc = np.arange(Vc.shape[0], dtype=np.int64).reshape(-1, 3)
    cones = np.array([V[v] for v, _ in p.cones]).reshape(-1, 3)
    line = (f"{title}: {len(F)} faces, tile {tile:.3g}, {len(p.cones)} cones, "
            f"{int(p.singular.sum())} singular faces "
            f"({100 * p.singular.mean():.1f}%), seam residual {p.seam_residual:.1e}")
    return Panel(Vc, Fc, uv=p.coords.reshape(-1, 2), texture=image,
                 title=f"{title}\n{len(p.cones)} cones, {int(p.singular.sum())} singular faces",
                 markers={"cone": (cones, "#1f6fd6")}), line


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces      # y-up -> z-up
    V, F = igl.upsample(V, F, 2)
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    tile = float(np.linalg.norm(np.ptp(V, axis=0))) / 22
    a, la = panel(V, F, smooth_direction_field(V, F, symmetry=4, seed=0), stud_tile(),
                  tile=tile, title="studs tile, smoothest field", out=out, stem="pgp_tile_studs")
    up, _ = projected_direction_field(V, F, (0.0, 0.0, 1.0))
    b, lb = panel(V, F, up, brick_tile(), tile=tile, title="brick tile, field from the up axis",
                  out=out, stem="pgp_tile_bricks")
    render_panels([a, b], out / "pgp_tile_image.png", size=(900, 760))
    print(la)
    print(lb)
    print(f"wrote {out / 'pgp_tile_image.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
