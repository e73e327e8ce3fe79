"""
A small batch on Dask: four parts, per-part tile sets, one failing part, a contact sheet
========================================================================================

Writes a folder of parts (the bundled Spot and Bob, a generated torus, and the
bundled open teapot, which cannot be textured), a manifest giving each part
its own tile set, size and seed, and runs the ``texture`` job over it on a
local Dask cluster of 2 worker processes (:func:`geotex.batch.run`). The
outputs are read back and drawn side by side with their summary row; the
failed part is drawn in red with its reason.

Run:  python examples/batch_folder.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import textwrap
from pathlib import Path

from geotex.batch import run
from geotex.data import sample_path
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import torus
from geotex.render import Panel, render_panels

MANIFEST = """\
input,name,tiles,size_mm,tile_size,seed
spot.obj,spot,studs,50,{t},0
bob.ply,bob,knurl,50,{t},1
ring.off,ring,chainmail,50,{r},2
teapot.stl,teapot,studs,50,{t},0
"""
QUICK = bool(os.environ.get("GEOTEX_EXAMPLES_QUICK"))     # the test suite: larger tiles


def main(out_dir: Path) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="geotex-batch-example-") as tmp:
        parts = Path(tmp) / "parts"
        parts.mkdir()
        shutil.copy(sample_path("spot"), parts / "spot.obj")
        shutil.copy(sample_path("bob"), parts / "bob.ply")
        shutil.copy(sample_path("teapot-open"), parts / "teapot.stl")
        write_mesh(parts / "ring.off", Mesh(*torus(1.0, 0.4, n_major=48, n_minor=24)))
        (parts / "parts.csv").write_text(MANIFEST.format(t=8 if QUICK else 5,
                                                         r=8 if QUICK else 6))
        outdir = Path(tmp) / "out"
        rows = run(parts / "parts.csv", job="texture", outdir=outdir, workers=2,
                   progress=lambda r, done, total: print(f"[{done}/{total}] {r['part']}: "
                                                         f"{r['status']} {r['reason']}"))
        panels = []
        for r in rows:
            opts = r["options"]
            if r["status"] == "ok":
                mesh = read_mesh(outdir / r["output"])
                title = (f"{r['part']}: {opts['tiles']}, {r['faces']} faces,\n"
                         f"tiles {r['tile_size']:g} mm, {r['seconds']:.1f} s, "
                         f"{'printable' if r['printable'] else 'NOT printable'}")
                panels.append(Panel(mesh.vertices, mesh.faces, title=title, color="#c9b38f"))
            else:
                mesh = read_mesh(r["input"])
                # "FILE: mesh cannot get a polycube: open (64 boundary edges), ..."
                first = r["reason"].split(": ")[-1].split(", ")[0]
                panels.append(Panel(mesh.vertices, mesh.faces, color="#d05050",
                                    title=f"{r['part']}: FAILED, batch went on\n"
                                    f"{textwrap.shorten(first, 30)}"))
        print(f"summary: {outdir / 'summary.csv'}")
        print((outdir / "summary.csv").read_text())
    return render_panels(panels, out_dir / "batch_folder.png", size=(520, 520), up="y")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    gallery = Path(sys.argv[0]).resolve().parents[1] / "docs" / "gallery"
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else gallery
    print(f"wrote {main(target)}")
