"""
Hierarchical pattern mapping: texture coordinates into one image, coarse to fine
================================================================================

Pictures (written to OUT_DIR), after the paper's figures:

* ``hpm_textures_clusters.png`` (Fig. 1) - levels 1 to 3 of the top-down
  face-cluster hierarchy of Spot, one colour per cluster, control vertices
  as dots.
* ``hpm_textures_scale.png`` (Fig. 8) - the same image mapped at three
  scales (surface length per image width), and the patches used for the
  largest, coloured by the hierarchy level they were placed at.
* ``hpm_textures.png`` (Figs. 9-11) - Spot, Bob and genus-2 / genus-4
  shapes (double torus, Fertility) with six images from
  ``../shared/data/images``.  The structured patterns (basket weave on
  Bob, rope net on Fertility) are mapped at a smaller scale (0.2 and 0.15
  x the diagonal) than the others: the paper (§5.2) notes that patches
  smaller than the pattern lose its structure, and these shapes' clusters
  flat enough to take one patch are about one net cell wide at 0.3 x the
  diagonal (the report's ``patch_periods``: rope net 0.93 at 0.3, 1.27 at
  0.15).  The structured images (bricks, weave, rope net, slate tiles) take
  their orientation from the smoothest direction field of each surface
  (``orientation_field="auto"``), so their rows run one way over the body
  and turn only around the field's singularities; the stochastic ones
  (gravel, peppers, water) follow their neighbours as before.

The textured surfaces are the base meshes with the output texture
coordinates and the input image itself (what ``geotex hpm`` writes as GLB /
OBJ).  Without the shared data (a clean clone, an installed package) the
bundled samples are used instead (:func:`geotex.data.sample_path`): the
low-resolution Spot, Bob and Blub with the brick wall and water photos and
the knitted wool depth map (``geotex/data/NOTICE.md``), the slate tiles of
the scale figure replaced by the bricks; ``GEOTEX_EXAMPLES_QUICK=1`` (the
test suite sets it) uses them too.

Run:  python examples/hpm_textures.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.data import sample_path, shared_data_dir
from geotex.image.hpm import hpm_texture, read_hpm_image
from geotex.io import read_mesh
from geotex.patches import cluster_hierarchy
from geotex.render import Panel, render_panels

HERE = Path(sys.argv[0]).resolve().parent
SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: bundled samples
QUICK = os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1" or SHARED is None
SIZE = (520, 520)


def mesh(name: str):
    """A base mesh by name: from the shared data, or the bundled sample (QUICK)."""
    if QUICK:
        m = read_mesh(sample_path(name))
    else:
        m = read_mesh(SHARED / "base" / {"spot": "spot_odedstein.obj",
                                         "bob": "bob_uv/bob_tri.obj",
                                         "double torus": "double_torus_gpjs.obj",
                                         "fertility": "fertility_libigl.off"}[name])
    if name == "spot":
        # y up -> z up, the face towards the picture's camera (as geotex demo turns it)
        return m.vertices[:, [0, 2, 1]] * np.array([-1.0, 1.0, 1.0]), m.faces
    return m.vertices, m.faces


#: caption names of the images
LABELS = {"embark/1.jpg": "water", "water": "water photo", "bricks": "brick photo",
          "wool-height": "wool depth map"}


def image(name: str) -> tuple[str, np.ndarray]:
    """An image by its path under the shared ``images`` folder, or a bundled sample's name."""
    if name in LABELS and "/" not in name:
        return LABELS[name], read_hpm_image(sample_path(name))
    return (LABELS.get(name, Path(name).stem.split("_", 1)[-1]),
            read_hpm_image(SHARED / "images" / name))


def split(V, F, uv, uv_faces):
    """One render vertex per distinct (vertex, uv) corner."""
    key = F.ravel() * np.int64(len(uv)) + uv_faces.ravel()
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    return V[F.ravel()[first]], inv.reshape(-1, 3), uv[uv_faces.ravel()[first]]


def textured(V, F, img, scale, *, seed=0, title=""):
    t = time.perf_counter()
    r = hpm_texture(V, F, img, scale=scale, seed=seed)
    rep = r.report()
    placed = sum(lv["placed"] for lv in rep["levels"])
    last = rep["levels"][-1]
    span = rep["pattern"].get("patch_periods")
    print(f"  {title}: {placed} patches, face level: {last['matched_faces']} faces matched, "
          f"{last['filled_faces']} unfolded, {time.perf_counter() - t:.1f} s"
          + ("" if span is None else f", patches span {span:.2f} pattern periods"))
    Vs, Fs, uv = split(V, F, r.uv, r.uv_faces)
    return Panel(Vs, Fs, uv=uv, texture=img, title=f"{title}\n{placed} patches"), r


def diag(V) -> float:
    return float(np.linalg.norm(np.ptp(V, axis=0)))


def clusters_figure(out: Path) -> None:
    V, F = mesh("spot")
    H = cluster_hierarchy(V, F, seed=0)
    rng = np.random.default_rng(0)
    panels = []
    for li in (1, 2, 3):
        lv = H[li]
        colors = rng.permutation(lv.n_clusters)
        markers = {"control vertices": (V[np.unique(lv.control_vertices)], "#222222")}
        panels.append(Panel(V, F, scalars=colors[lv.labels], cmap="tab20",
                            markers=markers if li < 3 else None,
                            title=f"level {li}: {lv.n_clusters} clusters"))
    render_panels(panels, out, size=SIZE, up="z")
    print(f"wrote {out}")


def scale_figure(out: Path) -> None:
    V, F = mesh("spot")
    label, img = image("bricks" if QUICK else "quilting_classic/t7_slate_tiles.png")
    d = diag(V)
    panels, last = [], None
    for k in (0.15, 0.3, 0.6):
        p, r = textured(V, F, img, k * d, title=f"scale {k:g} x diagonal")
        panels.append(p)
        last = r
    panels.append(Panel(V, F, scalars=last.face_level, cmap="viridis",
                        title="levels used (dark = coarse)"))
    render_panels(panels, out, size=SIZE, up="z")
    print(f"wrote {out}")


def results_figure(out: Path) -> None:
    jobs = [("spot", "quilting_classic/t4_gravel.png", 0.3, "z"),
            ("spot", "quilting_classic/t1_bricks.png", 0.35, "z"),
            ("bob", "quilting_classic/t6_peppers.png", 0.35, "y"),
            ("bob", "quilting_classic/t2_basket_weave.png", 0.2, "y"),
            ("double torus", "embark/1.jpg", 0.35, "y"),
            ("fertility", "quilting_classic/t8_rope_net.png", 0.15, "y")]
    if QUICK:       # the bundled meshes and images
        jobs = [("spot", "bricks", 0.35, "z"), ("bob", "water", 0.35, "y"),
                ("blub", "wool-height", 0.3, "y")]
    with tempfile.TemporaryDirectory() as tmp:
        rows = []
        for i in range(0, len(jobs), 3):
            panels, up = [], "y"
            for name, img_name, k, up in jobs[i:i + 3]:
                V, F = mesh(name)
                label, img = image(img_name)
                p, _ = textured(V, F, img, k * diag(V), title=f"{name}, {label}")
                panels.append(p)
            part = Path(tmp) / f"row{i}.png"
            # each row shares one up axis: render panels one by one, then paste
            pics = []
            for j, (p, job) in enumerate(zip(panels, jobs[i:i + 3])):
                f = Path(tmp) / f"p{i}_{j}.png"
                render_panels([p], f, size=SIZE, up=job[3])
                pics.append(Image.open(f).convert("RGB"))
            row = Image.new("RGB", (sum(q.width for q in pics), pics[0].height), "white")
            x = 0
            for q in pics:
                row.paste(q, (x, 0))
                x += q.width
            row.save(part)
            rows.append(Image.open(part).convert("RGB"))
        W = max(r.width for r in rows)
        sheet = Image.new("RGB", (W, sum(r.height for r in rows)), "white")
        y = 0
        for r in rows:
            sheet.paste(r, (0, y))
            y += r.height
        sheet.save(out)
    print(f"wrote {out}")


def main() -> None:
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs" / "gallery"
    out_dir.mkdir(parents=True, exist_ok=True)
    clusters_figure(out_dir / "hpm_textures_clusters.png")
    scale_figure(out_dir / "hpm_textures_scale.png")
    results_figure(out_dir / "hpm_textures.png")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main()
