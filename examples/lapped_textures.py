"""
Lapped textures: image patches pasted over Spot and Bob, isotropic and along fields
===================================================================================

Pictures (written to OUT_DIR):

* ``lapped_textures.png`` - per row (Spot, Bob): the direction field the
  anisotropic pastes follow (arrows, singular vertices as dots), the texture
  pasted along it, and the same texture pasted isotropically (each paste
  with a random orientation propagated over its patch).
* ``lapped_textures_gallery.png`` - every image in ``../shared/data/images``
  (see its MANIFEST), or in a clean clone the four bundled sample images, on
  Spot or Bob, and when needed geotex's procedural height maps (grey images)
  to fill the grid; structured textures (bricks, weave,
  tiles, net, hexagons) follow the field, stochastic ones are pasted
  isotropically. Each panel shows its input image in the lower right corner.
* ``lapped_textures_relief.png`` - the composited texture used as a height
  field: a refined copy of Spot displaced into a solid that passes the
  printability check.

Every textured surface is the mesh with a packed xatlas atlas and the pastes
composited into it (what ``geotex lapped`` writes as GLB / OBJ).  Without
the shared data (a clean clone, an installed package), the bundled
low-resolution Spot and Bob and the bundled images (a brick wall and a water
photo, knitted wool and brick depth maps; ``geotex/data/NOTICE.md``) are used;
the relief then reads the brick depth map inverted (bricks high).

Set ``GEOTEX_EXAMPLES_QUICK=1`` (the test suite does) for the bundled
low-resolution Spot and two images only.

Run:  python examples/lapped_textures.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.check import check_mesh
from geotex.data import SAMPLE_IMAGES, sample_path, shared_data_dir
from geotex.displace.library import library_height_map
from geotex.fields.directions import principal_direction_field, projected_direction_field
from geotex.fields.singularities import singularities
from geotex.image import (alignment_errors, displace, lapped_texture, texture_patches,
                          textured_mesh)
from geotex.io import read_mesh
from geotex.io.images import load_texture_image
from geotex.render import Panel, render_panels

SHARED = shared_data_dir(sys.argv[0])        # None in a clean clone: bundled samples
#: Textures with a direction (pasted along the field in the gallery).
STRUCTURED = ("bricks", "weave", "slate", "rope", "hexagons")
SIZE = (480, 520)
#: Columns of the gallery grid; procedural maps fill its last row.
GALLERY_COLUMNS = 5
FILLERS = ("hexagons", "voronoi")


#: caption names of the bundled sample images
LABELS = {"bricks": "brick photo", "water": "water photo", "wool-height": "wool depth map",
          "bricks-height": "brick depth map"}


def label(name: str) -> str:
    """An input image's name in a caption."""
    return LABELS.get(name, name.replace("bricks_with_alpha_hole", "bricks+hole"))


def z_up(mesh):
    return np.ascontiguousarray(mesh.vertices[:, [0, 2, 1]] * [-1, 1, 1]), mesh.faces


def load_bases():
    """Spot and Bob: with their own uv layouts from the shared data, else the bundled ones."""
    if SHARED is None:
        return z_up(read_mesh(sample_path("spot"))), z_up(read_mesh(sample_path("bob")))
    return (z_up(read_mesh(SHARED / "base" / "spot_uv" / "spot.obj")),
            z_up(read_mesh(SHARED / "base" / "bob_uv" / "bob_tri.obj")))


def images() -> list[tuple[str, object]]:
    """(name, path) of every input image: the shared data's, else the bundled samples."""
    if SHARED is None:
        return [(name, sample_path(name)) for name in SAMPLE_IMAGES]
    images = SHARED / "images"
    found = sorted(images.rglob("*.png")) + sorted(images.rglob("*.jpg"))
    return [(f"{p.parent.name}_{p.stem}" if p.parent.name == "embark" else p.stem, p)
            for p in found]


def split_by_uv(m):
    """Per-vertex uv for the renderer: one vertex per distinct (vertex, uv) corner."""
    key = m.faces.ravel() * np.int64(len(m.uv)) + m.uv_faces.ravel()
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    V = m.vertices[m.faces.ravel()[first]]
    uv = m.uv[m.uv_faces.ravel()[first]]
    return V, inv.reshape(-1, 3), uv


def paste(V, F, image, *, field=None, symmetry=None, scale, seed=0, mask="splotch",
          resolution=1024):
    t = time.perf_counter()
    patches = texture_patches(image, mask=mask, seed=seed)
    lt = lapped_texture(V, F, patches, field=field, symmetry=symmetry, scale=scale, seed=seed)
    m = textured_mesh(V, F, lt, resolution=resolution)
    err = np.degrees(alignment_errors(V, F, lt))
    dt = time.perf_counter() - t
    print(f"  {lt.n_pastes} pastes, complete {lt.complete}, angle error median "
          f"{np.median(err):.1f} deg, {dt:.1f} s")
    return m, lt, err


def textured_panel(m, title):
    Vs, Fs, uv = split_by_uv(m)
    return Panel(Vs, Fs, uv=uv, texture=m.texture, title=title)


def field_panel(V, F, vectors, symmetry, title, count=900):
    C = V[F].mean(axis=1)
    pick = np.random.default_rng(0).choice(len(F), size=min(count, len(F)), replace=False)
    L = 0.025 * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    P, D = C[pick], vectors[pick] * L
    if symmetry == 2:                                   # lines: draw both ways
        P, D = np.concatenate([P, P]), np.concatenate([D, -D])
    sing = singularities(V, F, vectors, symmetry=symmetry)
    plus = np.array([V[v] for v, k in sing if k > 0]).reshape(-1, 3)
    minus = np.array([V[v] for v, k in sing if k < 0]).reshape(-1, 3)
    return Panel(V, F, color="#e8e2d4", arrows=(P, D), title=title,
                 markers={"index > 0": (plus, "#d62728"), "index < 0": (minus, "#1f77b4")})


def stitch(rows: list[list[Panel]], path: Path, *, swatches=None) -> None:
    """Render rows of panels into one picture; ``swatches[r][k]`` (an image or
    None) is pasted into the lower right corner of panel ``k`` of row ``r``."""
    with tempfile.TemporaryDirectory() as tmp:
        pics = []
        for i, row in enumerate(rows):
            p = render_panels(row, Path(tmp) / f"row{i}.png", size=SIZE, up="z")
            with Image.open(p) as im:
                pic = im.convert("RGB").copy()
            for k, sw in enumerate(swatches[i] if swatches else []):
                if sw is not None:
                    _paste_swatch(pic, sw, k)
            pics.append(pic)
    w = max(p.width for p in pics)
    canvas = Image.new("RGB", (w, sum(p.height for p in pics)), "white")
    y = 0
    for p in pics:
        canvas.paste(p, (0, y))
        y += p.height
    canvas.save(path)
    print(f"wrote {path}")


def _paste_swatch(pic, image, k, side=110, margin=10):
    """The input image, ``side`` pixels square with a thin frame, in a panel's corner."""
    if isinstance(image, (str, Path)):
        with Image.open(image) as im:
            sw = im.convert("RGB")
    else:
        a = np.asarray(image)
        a = (np.clip(a, 0.0, 1.0) * 255).astype(np.uint8) if a.dtype != np.uint8 else a
        sw = Image.fromarray(a).convert("RGB")
    sw = sw.resize((side, side), Image.LANCZOS)
    x = (k + 1) * SIZE[0] - side - margin
    y = SIZE[1] - side - margin
    pic.paste(Image.new("RGB", (side + 4, side + 4), "#404040"), (x - 2, y - 2))
    pic.paste(sw, (x, y))


def diag(V):
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (spot, bob) = load_bases()
    imgs = dict(images())
    if os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1":   # the test suite: small and few
        spot, bob = z_up(read_mesh(sample_path("spot"))), None
        imgs = dict(list(imgs.items())[:2])
    bricks_name = next((k for k in imgs if "bricks" in k and "embark" not in k
                        and "height" not in k), next(iter(imgs)))
    weave_name = next((k for k in imgs if "weave" in k), bricks_name)
    bricks, weave = imgs[bricks_name], imgs[weave_name]

    # ---------------------------------------------------------------- fields
    rows = []
    V, F = spot
    up, _ = projected_direction_field(V, F, [0.0, 0.0, 1.0])
    print("Spot, up field:")
    m_a, lt_a, err = paste(V, F, bricks, field=up, scale=0.3 * diag(V))
    print("Spot, isotropic:")
    m_i, lt_i, _ = paste(V, F, bricks, scale=0.3 * diag(V))
    rows.append([field_panel(V, F, up, 1, "Spot: up field"),
                 textured_panel(m_a, f"{label(bricks_name)}, up field\n{lt_a.n_pastes} "
                                     f"pastes, error {np.median(err):.1f} deg"),
                 textured_panel(m_i, f"{label(bricks_name)}, isotropic\n"
                                     f"{lt_i.n_pastes} pastes")])
    if bob is not None:
        V, F = bob
        lines = principal_direction_field(V, F).directions
        print("Bob, curvature lines:")
        m_a, lt_a, err = paste(V, F, weave, field=lines, symmetry=2, scale=0.25 * diag(V))
        print("Bob, isotropic:")
        m_i, lt_i, _ = paste(V, F, weave, scale=0.25 * diag(V))
        rows.append([field_panel(V, F, lines, 2, "Bob: curvature lines"),
                     textured_panel(m_a, f"{label(weave_name)}, along the lines\n"
                                         f"{lt_a.n_pastes} pastes, error "
                                         f"{np.median(err):.1f} deg"),
                     textured_panel(m_i, f"{label(weave_name)}, isotropic\n"
                                         f"{lt_i.n_pastes} pastes")])
    stitch(rows, out / "lapped_textures.png")

    # ---------------------------------------------------------------- gallery
    panels, inputs = [], []
    small_bob = None
    if bob is not None:                    # half the faces: 13 textures stay quick
        import fast_simplification
        Vb, Fb = fast_simplification.simplify(bob[0], bob[1], target_reduction=0.5)
        small_bob = (np.ascontiguousarray(Vb, dtype=np.float64),
                     np.ascontiguousarray(Fb, dtype=np.int64))
    for i, (name, img) in enumerate(imgs.items()):
        V, F = small_bob if (bob is not None and i % 2) else spot
        who = "Bob" if (bob is not None and i % 2) else "Spot"
        structured = any(s in name for s in STRUCTURED)
        print(f"{name} on {who} ({'field' if structured else 'isotropic'}):")
        fld = projected_direction_field(V, F, [0.0, 0.0, 1.0])[0] if structured else None
        m, lt, _ = paste(V, F, img, field=fld, scale=0.25 * diag(V), seed=i, resolution=512)
        panels.append(textured_panel(m, f"{label(name)} "
                                        f"({'field' if structured else 'isotropic'})"))
        inputs.append(img)
    # the grid has no empty cells: procedural grey maps fill the last row
    fill = -len(panels) % GALLERY_COLUMNS if len(panels) > GALLERY_COLUMNS else 0
    for j, name in enumerate(FILLERS[:fill]):
        V, F = spot
        img = library_height_map(name, size=256)
        structured = any(s in name for s in STRUCTURED)
        print(f"library map {name} on Spot ({'field' if structured else 'isotropic'}):")
        fld = projected_direction_field(V, F, [0.0, 0.0, 1.0])[0] if structured else None
        m, lt, _ = paste(V, F, img, field=fld, scale=0.25 * diag(V), seed=100 + j,
                         resolution=512)
        panels.append(textured_panel(m, f"map '{name}' ({'field' if structured else 'isotropic'})"))
        inputs.append(img)
    cols = GALLERY_COLUMNS if len(panels) > GALLERY_COLUMNS else len(panels)
    stitch([panels[k:k + cols] for k in range(0, len(panels), cols)],
           out / "lapped_textures_gallery.png",
           swatches=[inputs[k:k + cols] for k in range(0, len(inputs), cols)])

    # ---------------------------------------------------------------- relief
    V, F = spot
    if SHARED is None:     # a depth map (light is deep), inverted: the bricks stand
        relief_name = "brick depth map, inverted"
        relief_img = 255 - load_texture_image(sample_path("bricks-height"))
    else:
        relief_name, relief_img = next(((k, v) for k, v in imgs.items() if "cracker" in k),
                                       (label(bricks_name), bricks))
    print(f"Spot relief ({relief_name}):")
    _, lt, _ = paste(V, F, relief_img, scale=0.2 * diag(V))
    t = time.perf_counter()
    depth = 0.008 * diag(V)
    Vd, Fd = displace(V, F, lt, depth=depth, edge_length=0.2 * diag(V) / 50)
    rep = check_mesh(Vd, Fd)
    print(f"  relief: {len(Fd)} faces, printable {rep.printable}, {time.perf_counter() - t:.1f} s")
    # close up: the point at mid height that faces the camera (head and neck), in the whole
    # lit mesh (not a cut-out piece)
    view = np.array([0.75, -1.0, 0.55]) / np.linalg.norm([0.75, -1.0, 0.55])
    c = 0.5 * (Vd.min(axis=0) + Vd.max(axis=0))
    flank = np.abs(Vd[:, 2] - c[2]) < 0.15
    p = Vd[flank][np.argmax((Vd[flank] - c) @ view)]
    stitch([[Panel(Vd, Fd, color="#c9b28f",
                   title=f"{relief_name}: relief {depth:.3f}\n{len(Fd) // 1000}k faces, "
                         f"{'printable' if rep.printable else 'NOT printable'}"),
             Panel(Vd, Fd, color="#c9b28f", title="close up: head and neck", closeup=p,
                   closeup_radius=0.12 * diag(Vd))]],
           out / "lapped_textures_relief.png")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
