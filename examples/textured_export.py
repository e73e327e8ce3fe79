"""
Textured output: OBJ + MTL + PNG and GLB, read back and drawn
=============================================================

Builds a torus with its natural (angle, angle) texture coordinates, which need
separate uv indices along the two seams, paints a checkerboard texture, writes
it as OBJ (+ MTL + PNG) and as GLB, reads both files back and renders them side
by side. The round trip is checked: same triangles, same uv, same pixels.

Run:  python examples/textured_export.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.render import Panel, render_panels
from geotex.viewpage import mesh_turned_y_up


def torus_with_uv(nu: int = 48, nv: int = 24, R: float = 1.0, r: float = 0.4) -> Mesh:
    """Torus whose uv grid has (nu + 1) x (nv + 1) points: the seams are cut in uv."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = 2 * np.pi * i / nu, 2 * np.pi * j / nv
    V = np.stack([(R + r * np.cos(b)) * np.cos(a), (R + r * np.cos(b)) * np.sin(a),
                  r * np.sin(b)], -1).reshape(-1, 3)
    vid = lambda ii, jj: (ii % nu) * nv + (jj % nv)          # noqa: E731
    tid = lambda ii, jj: ii * (nv + 1) + jj                  # noqa: E731
    quads = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
    F = np.concatenate([np.stack([vid(*quads[k]) for k in (0, 1, 2)], -1).reshape(-1, 3),
                        np.stack([vid(*quads[k]) for k in (0, 2, 3)], -1).reshape(-1, 3)])
    FT = np.concatenate([np.stack([tid(*quads[k]) for k in (0, 1, 2)], -1).reshape(-1, 3),
                         np.stack([tid(*quads[k]) for k in (0, 2, 3)], -1).reshape(-1, 3)])
    ui, vi = np.meshgrid(np.arange(nu + 1), np.arange(nv + 1), indexing="ij")
    uv = np.stack([ui / nu, vi / nv], -1).reshape(-1, 2)
    cells = (np.indices((256, 512)) // 32).sum(0) % 2
    tex = np.where(cells[..., None], [236, 200, 120], [60, 90, 160]).astype(np.uint8)
    tex[:8] = [200, 40, 40]                                   # a red band marks v = 1
    return Mesh(V, F, uv=uv, uv_faces=FT, texture=tex, name="torus")


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    mesh = torus_with_uv()
    obj = write_mesh(out / "textured_torus.obj", mesh)
    # glTF is y-up: the GLB gets the torus turned, (x, y, z) -> (x, z, -y)
    glb = write_mesh(out / "textured_torus.glb", mesh_turned_y_up(mesh, up="z"))
    panels = []
    for path in (obj, glb):
        back = read_mesh(path)
        assert np.array_equal(back.texture[..., :3], mesh.texture)
        assert back.n_faces == mesh.n_faces and back.has_uv
        if path.suffix == ".glb":                    # turned back to z-up for the picture
            back = back.replace(vertices=back.vertices[:, [0, 2, 1]] * [1.0, -1.0, 1.0])
        err = float(np.abs(back.vertices[back.faces] - mesh.vertices[mesh.faces]).max())
        assert err < 1e-6
        size = sum(p.stat().st_size for p in out.glob(path.stem + ".*")
                   if p.suffix in (path.suffix, ".mtl", ".png") and p.name != "textured_export.png")
        title = (f"read back from {path.name}: {back.n_faces:,} faces, {len(back.uv):,} uv, "
                 f"{size / 1024:.0f} KB, max position error {err:.1e}")
        panels.append(Panel(back.vertices, back.faces, uv=back.uv, uv_faces=back.uv_faces,
                            texture=back.texture, title=title))
    render_panels(panels, out / "textured_export.png", size=(700, 550))
    print(f"wrote {obj} (+ .mtl, .png), {glb}, {out / 'textured_export.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
