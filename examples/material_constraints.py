"""
Material and orientation constraints on Bob (paper Figs. 8-10), with a local update
===================================================================================

Writes ``material_constraints.png`` into OUT_DIR (default docs/gallery), four panels:

1. the constraints: orientation strokes (arrows) and material points (red:
   m = 1, blue: m = 0) over the interpolated material field (colour = m);
2. the result: the (s, t, m) tile baked over Bob through the PGP steered by
   the smooth cross field through the strokes;
3. a local update: one more material point (m = 1, on the flank); only
   its effect area (25 % of the surface, outlined) is re-solved, the rest
   stays locked;
4. the textured result after the update.

The tile morphs gravel (m = 0) into peppers (m = 1) from
``../shared/data/images``; without the shared data (a clean clone), the
bundled water photo (m = 0) into the bundled brick wall photo (m = 1)
(``geotex/data/NOTICE.md``).
``GEOTEX_EXAMPLES_QUICK=1`` draws a smaller tile.

Run:  python examples/material_constraints.py [OUT_DIR]
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

from geotex.data import sample_path, shared_data_dir
from geotex.fields.directions import smooth_direction_field
from geotex.fields.scalar import material_field
from geotex.image.material.mapping import bake_material_texture, material_locks, update_material
from geotex.image.material.tile import build_material_tile
from geotex.io import read_mesh
from geotex.io.images import load_texture_image
from geotex.mesh.topology import edge_topology
from geotex.param.pgp import periodic_parameterization
from geotex.patches.grow import face_adjacency
from geotex.render import Panel, render_panels

SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: bundled images
QUICK = bool(os.environ.get("GEOTEX_EXAMPLES_QUICK"))


def inputs() -> tuple[np.ndarray, np.ndarray, str]:
    """The two images (m = 0, m = 1) and their caption: quilting classics from the
    shared data, else two bundled sample photos."""
    if SHARED is not None:
        folder = SHARED / "images" / "quilting_classic"
        a, b = (folder / n for n in ("t4_gravel.png", "t6_peppers.png"))
        return load_texture_image(a), load_texture_image(b), "gravel -> peppers"
    return (load_texture_image(sample_path("water")), load_texture_image(sample_path("bricks")),
            "water photo -> brick photo")


def corner_panel(V, F, textured, title):
    Vc = V[F].reshape(-1, 3)
    Fc = np.arange(Vc.shape[0], dtype=np.int64).reshape(-1, 3)
    return Panel(Vc, Fc, uv=textured.uv[textured.uv_faces].reshape(-1, 2),
                 texture=textured.texture, title=title)


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    A, B, label = inputs()
    size, layers = (32, 4) if QUICK else (64, 6)
    tile = build_material_tile(A, B, size=size, layers=layers, seed=0)
    bob = read_mesh(sample_path("bob"))
    V, F = bob.vertices[:, [0, 2, 1]] * [-1, 1, 1], bob.faces               # y-up -> z-up
    lo, hi = V.min(axis=0), V.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    # orientation strokes: along the body on the back, around the tail
    cen = V[F].mean(axis=1)
    def nearest_face(p):
        return int(np.argmin(np.linalg.norm(cen - np.asarray(p), axis=1)))
    strokes = []
    for t in np.linspace(0.25, 0.75, 5):
        p = lo + (hi - lo) * [t, 0.5, 0.95]
        strokes.append({"face": nearest_face(p), "direction": [1.0, 0.0, 0.0]})
    for t in np.linspace(0.3, 0.7, 3):
        p = lo + (hi - lo) * [0.5, t, 0.05]
        strokes.append({"face": nearest_face(p), "direction": [0.0, 1.0, 0.0]})
    head = V[np.argmax(V[:, 0])]
    tail = V[np.argmin(V[:, 0])]
    mats = [{"point": head.tolist(), "material": 1.0, "radius": 0.08 * diag},
            {"point": tail.tolist(), "material": 0.0, "radius": 0.08 * diag}]
    field = smooth_direction_field(V, F, symmetry=4, constraints=strokes, seed=0)
    params = periodic_parameterization(V, F, field, scale=0.09 * diag)
    lv, lval = material_locks(V, F, mats)
    m0 = material_field(V, F, lv, lval)
    res = 1024 if QUICK else 2048
    before = bake_material_texture(V, F, params, m0, tile, field=field, resolution=res)
    # local update: one more m = 1 point on the flank facing the camera (-y)
    adj = face_adjacency(V, F)
    mid = 0.5 * (lo + hi)
    belly = int(np.argmin(V[:, 1] + 0.5 * np.abs(V[:, 0] - mid[0] + 0.15 * (hi - lo)[0])
                          + 0.5 * np.abs(V[:, 2] - mid[2])))
    t0 = time.perf_counter()
    nv, nval = material_locks(V, F, [{"point": V[belly].tolist(), "material": 1.0,
                                      "radius": 0.06 * diag}])
    upd = update_material(V, F, m0, nv, nval, budget_area=0.25 * adj.areas.sum(),
                          keep_vertices=lv, adjacency=adj)
    t_up = time.perf_counter() - t0
    after = bake_material_texture(V, F, params, upd.material, tile, field=field,
                                  resolution=res)
    inside = np.zeros(F.shape[0], bool)
    inside[upd.faces] = True
    topo = edge_topology(F, V.shape[0])
    n_in = np.bincount(topo.half_to_edge, weights=np.repeat(inside, 3).astype(float),
                       minlength=topo.edges.shape[0])
    border = topo.edges[(topo.face_count == 2) & (n_in == 1)]
    arrows = (cen[[s["face"] for s in strokes]],
              np.array([s["direction"] for s in strokes]) * 0.08 * diag)
    marks = {"m = 1": (np.array([head]), "#e4202a"), "m = 0": (np.array([tail]), "#1f6fd6")}
    panels = [Panel(V, F, scalars=m0, cmap="coolwarm", arrows=arrows, markers=marks,
                    title="constraints: strokes + material points\ncolour = interpolated m"),
              corner_panel(V, F, before, f"result ({label})\n"
                           f"{int(params.singular.sum())} singular faces blended"),
              Panel(V, F, scalars=upd.material, cmap="coolwarm",
                    highlight={"effect area border": border},
                    markers={"new m = 1": (V[[belly]], "#e4202a")},
                    title=f"local update: {upd.faces.size} of {F.shape[0]} faces\n"
                          f"re-solved in {t_up * 1000:.0f} ms"),
              corner_panel(V, F, after, "after the update")]
    render_panels(panels, out / "material_constraints.png", size=(650, 520))
    print(f"Bob {F.shape[0]} faces; local update {t_up * 1000:.1f} ms on {upd.faces.size} faces "
          f"({upd.free_vertices.size} free vertices)")
    print(f"wrote {out / 'material_constraints.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else
         Path(__file__).resolve().parents[1] / "docs" / "gallery")
