"""
A checkerboard through the periodic global parameterization (PGP) on four shapes
================================================================================

Panels: Spot (the bundled low-resolution cow, one Loop subdivision) with the
smoothest cross field; the bundled Bob (genus 1) with the smoothest cross
field; a torus with its principal-curvature cross field (no
cones: the Euler characteristic is 0); a genus-2 plate with two holes and the
smoothest cross field.  The texture is one periodic tile of 2 x 2 checks whose
cells are centred on the tile corners, so that it is unchanged by the
90-degree rotations and integer shifts that PGP leaves across edges: away
from the singular faces the checks run on without a seam.  Red / blue balls:
cones of the cross field (index > 0 / < 0); orange balls: faces where a
periodic function winds (grid dislocations).  Singular faces carry the
field's local map (one correctly sized piece of the tile, a small jump at
their edges).

Run:  python examples/pgp_checkerboard.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

import igl
import numpy as np

from geotex.data import sample_path
from geotex.fields.directions import principal_direction_field, smooth_direction_field
from geotex.io import read_mesh
from geotex.mesh.primitives import plate_with_holes, torus
from geotex.param.pgp import periodic_parameterization
from geotex.render import Panel, render_panels


def checker_tile(px: int = 64) -> np.ndarray:
    """One period: colour = parity of round(2u) + round(2v) (cells centred on tile corners)."""
    u = (np.arange(px) + 0.5) / px
    par = (np.rint(2 * u)[:, None] + np.rint(2 * u)[None, :]).astype(int) % 2
    img = np.where(par[..., None] == 1, [40, 40, 48], [238, 232, 214]).astype(np.uint8)
    return np.ascontiguousarray(img)


def pgp_panel(V, F, field, *, tiles_across: float, title: str) -> tuple[Panel, str]:
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    p = periodic_parameterization(V, F, field, scale=diag / tiles_across)
    Vc = V[F].reshape(-1, 3)                       # one vertex per corner: per-corner uv
    Fc = np.arange(Vc.shape[0], dtype=np.int64).reshape(-1, 3)
    pos = np.array([V[v] for v, k in p.cones if k > 0]).reshape(-1, 3)
    neg = np.array([V[v] for v, k in p.cones if k < 0]).reshape(-1, 3)
    dis = V[F[[f for f, _, _ in p.dislocations]]].mean(axis=1).reshape(-1, 3)
    line = (f"{title}: {len(F)} faces, {len(p.cones)} cones (index sum {p.index_sum:g}), "
            f"{len(p.dislocations)} dislocations, {int(p.singular.sum())} singular faces, "
            f"seam residual {p.seam_residual:.1e}, gradient error {p.gradient_error:.3f}")
    panel = Panel(Vc, Fc, uv=p.coords.reshape(-1, 2), texture=checker_tile(),
                  title=f"{title}\n{len(p.cones)} cones, sum {p.index_sum:g}; "
                        f"residual {p.seam_residual:.0e}",
                  markers={"cone index > 0": (pos, "#e4202a"),
                           "cone index < 0": (neg, "#1f6fd6"),
                           "dislocation": (dis, "#ff8c00")})
    return panel, line


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces      # y-up -> z-up
    V, F = igl.upsample(V, F, 1)
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    panels, lines = [], []
    panel, line = pgp_panel(V, F, smooth_direction_field(V, F, symmetry=4, seed=0),
                            tiles_across=14, title="Spot, smoothest field")
    panels.append(panel)
    lines.append(line)
    bob = read_mesh(sample_path("bob"))
    Vb, Fb = bob.vertices[:, [0, 2, 1]] * [-1, 1, 1], bob.faces
    panel, line = pgp_panel(Vb, Fb, smooth_direction_field(Vb, Fb, symmetry=4, seed=0),
                            tiles_across=14, title="Bob, smoothest field")
    panels.append(panel)
    lines.append(line)
    Vt, Ft = torus(1.0, 0.4, n_major=120, n_minor=48)
    panel, line = pgp_panel(Vt, Ft, principal_direction_field(Vt, Ft).directions,
                            tiles_across=14, title="torus, curvature field")
    panels.append(panel)
    lines.append(line)
    Vg, Fg = plate_with_holes(2, cell=0.07)
    panel, line = pgp_panel(Vg, Fg, smooth_direction_field(Vg, Fg, symmetry=4, seed=0),
                            tiles_across=14, title="genus 2, smoothest field")
    panels.append(panel)
    lines.append(line)
    render_panels(panels, out / "pgp_checkerboard.png", size=(640, 640))
    print("\n".join(lines))
    print(f"wrote {out / 'pgp_checkerboard.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
