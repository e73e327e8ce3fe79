"""
The six procedural exemplar geometric textures, each fused onto a slab
======================================================================

Every kind of :mod:`geotex.exemplars` (studs, scales, knurl, weave, chain
mail, bark) is built on a 2 x 2 patch (one Wang tile is 1 x 1), united with a
slab ``[0, 2] x [0, 2] x [-0.2, 0]`` by manifold3d, checked printable, and
drawn from an oblique angle (two rows of three panels).

Run:  python examples/exemplars.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import manifold3d
from PIL import Image

from geotex.check import check_mesh
from geotex.exemplars import EXEMPLAR_KINDS, exemplar
from geotex.io.atomic import atomic_output
from geotex.mesh.primitives import box
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.render import Panel, render_panels

COLORS = {"studs": "#c9a227", "scales": "#3f8f6b", "knurl": "#9aa7b8",
          "weave": "#b97a56", "chainmail": "#8c96a3", "bark": "#7a5a3c"}


def on_slab(ex):
    """Union of the exemplar's elements with a 0.2 thick slab under its footprint."""
    lx, ly = ex.size
    slab = manifold_of(*box((0.0, 0.0, -0.2), (lx, ly, 0.0)))
    solid = manifold3d.Manifold.batch_boolean([slab, manifold_of(ex.vertices, ex.faces)],
                                              manifold3d.OpType.Add)
    return arrays_of_manifold(solid)


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    panels = []
    for name in EXEMPLAR_KINDS:
        ex = exemplar(name, size=(2.0, 2.0), seed=1)
        V, F = on_slab(ex)
        ok = check_mesh(V, F).printable
        print(f"{name:10s} {ex.n_elements:4d} elements {ex.faces.shape[0]:6d} faces, "
              f"height {ex.height:.3f}, union with slab {F.shape[0]} faces, "
              f"printable {ok}")
        panels.append(Panel(V, F, color=COLORS[name], title=f"{name} ({ex.n_elements})"))
    # two rows of three panels, stacked into one picture
    path = out / "exemplars.png"
    with tempfile.TemporaryDirectory(dir=out) as tmp:
        rows = [render_panels(panels[i:i + 3], Path(tmp) / f"row{i}.png", size=(640, 520),
                              up="z") for i in (0, 3)]
        images = [Image.open(r).convert("RGB") for r in rows]
        sheet = Image.new("RGB", (max(im.width for im in images),
                                  sum(im.height for im in images)), "white")
        for k, im in enumerate(images):
            sheet.paste(im, (0, k * images[0].height))
        with atomic_output(path, "wb") as fh:
            sheet.save(fh, format="PNG")
    print(f"wrote {path}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
