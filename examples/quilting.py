"""
Mesh quilting: every procedural exemplar beside a larger patch synthesized from it
==================================================================================

For each exemplar kind of ``geotex.exemplars`` (a 2 x 2 patch), a 4 x 4 texture
(four times the area) is quilted: copies of the exemplar are placed where they
match what is already there (matching energy + ICP, on the exemplar's
lattice), corresponding elements are merged (graph cut + welded seam, or pull +
stitch, exact union as the fallback: the weave's strands of successive copies
join into strands that run across the patch) and elements crossing the border
are clipped to it.  Each caption gives the element count, the joins, and the
fraction of the plane covered (the report compares it with the exemplar's;
the script prints every report's one-line summary and its seam measures).

``GEOTEX_EXAMPLES_QUICK=1`` (the test suite) quilts two kinds only.

Run:  python examples/quilting.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import io
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from geotex.exemplars import EXEMPLAR_KINDS, exemplar
from geotex.quilting import quilt_texture
from geotex.render import Panel, render_panels

COLORS = {"studs": "#c9a86a", "scales": "#6f9a7a", "knurl": "#9aa7b8", "weave": "#b98a5e",
          "chainmail": "#a3a9b3", "bark": "#8a6a4f"}


def main(out: Path) -> None:
    from PIL import Image

    from geotex.io.atomic import atomic_output

    out.mkdir(parents=True, exist_ok=True)
    rows = []
    lines = []
    kinds = list(EXEMPLAR_KINDS)
    if os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1":
        kinds = ["studs", "weave"]          # an isolated element and one that joins across copies
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(0, len(kinds), 2):
            panels = []
            for kind in kinds[r:r + 2]:
                ex = exemplar(kind, size=(2.0, 2.0), seed=0)
                res = quilt_texture(ex, out_size=(4.0, 4.0), seed=0, boundary="clip")
                rep = res.report
                assert rep.valid, f"{kind}: {rep.summary()}"
                c = COLORS.get(kind, "#b0a090")
                panels.append(Panel(ex.vertices, ex.faces, color=c,
                                    title=f"{kind} exemplar, {ex.n_elements} el."))
                joined = rep.merges.get("stitched", 0) + rep.merges.get("union", 0)
                panels.append(Panel(res.vertices, res.faces, color=c,
                                    title=f"quilted x4: {rep.elements} el."
                                          + (f", {joined} joins" if joined else "")
                                          + f", cover {rep.coverage:.0%}"))
                lines.append(f"{kind:10s} {rep.summary()}")
                if np.isfinite(rep.seam_gap_max):
                    lines.append(f"{'':10s} seams: gap {rep.seam_gap_mean:.3f} mean, "
                                 f"{rep.seam_gap_max:.3f} max (of the cell); normal jump "
                                 f"{rep.seam_normal_jump_mean:.1f} mean, "
                                 f"{rep.seam_normal_jump_max:.1f} max (degrees)")
            path = Path(tmp) / f"row{r}.png"
            render_panels(panels, path, size=(520, 420), up="z")
            rows.append(np.asarray(Image.open(path).convert("RGB")))
    width = max(im.shape[1] for im in rows)
    canvas = np.full((sum(im.shape[0] for im in rows), width, 3), 255, dtype=np.uint8)
    y = 0
    for im in rows:
        canvas[y:y + im.shape[0], :im.shape[1]] = im
        y += im.shape[0]
    buf = io.BytesIO()
    Image.fromarray(canvas).save(buf, format="PNG")
    with atomic_output(out / "quilting.png", "wb") as fh:
        fh.write(buf.getvalue())
    print("\n".join(lines))
    print(f"wrote {out / 'quilting.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
