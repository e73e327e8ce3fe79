"""
Tangent direction fields and their singularities, drawn on real meshes
======================================================================

Panels: a smooth 1-direction field through two constraints on Spot; the
globally smoothest 4-direction (cross) field on Spot; the smoothest field on
a torus (no singularities: the torus has Euler characteristic 0); the
"up"-projected field on Bob (genus 1). Arrows show one representative per
face (a sample of faces); red balls are singular vertices of positive index,
blue of negative index. The title of each panel gives the index sum, which
equals the Euler characteristic.

Meshes: the bundled Spot and Bob (``geotex/data``), and a generated torus.

Run:  python examples/direction_fields.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from geotex.data import sample_path
from geotex.fields.directions import projected_direction_field, smooth_direction_field
from geotex.fields.singularities import singularities
from geotex.io import read_mesh
from geotex.mesh.primitives import torus
from geotex.render import Panel, render_panels

def field_panel(V, F, vectors, sing, *, title, every=1, length=0.6):
    C = V[F].mean(axis=1)
    edge = np.linalg.norm(V[F[:, 1]] - V[F[:, 0]], axis=1).mean()
    pick = np.arange(0, F.shape[0], every)
    pos = np.array([V[v] for v, k in sing if k > 0]).reshape(-1, 3)
    neg = np.array([V[v] for v, k in sing if k < 0]).reshape(-1, 3)
    total = sum(k for _, k in sing)
    return Panel(V, F, title=f"{title}\n{len(sing)} singularities, index sum {total:g}",
                 arrows=(C[pick], vectors[pick] * edge * length * every ** 0.5),
                 markers={"index > 0": (pos, "#e4202a"), "index < 0": (neg, "#1f6fd6")})


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    spot = read_mesh(sample_path("spot"))
    V, F = spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces      # y-up -> z-up
    cons = [{"point": V[np.argmax(V[:, 2])], "direction": [1, 0, 0]},
            {"point": V[np.argmin(V[:, 1])], "direction": [0, 0, 1]}]
    smooth = smooth_direction_field(V, F, symmetry=1, constraints=cons)
    cross = smooth_direction_field(V, F, symmetry=4, seed=0)
    panels = [field_panel(V, F, smooth.vectors, smooth.singularities,
                          title="Spot, smooth 1-field, 2 constraints", every=2),
              field_panel(V, F, cross.vectors, cross.singularities,
                          title="Spot, smoothest 4-field", every=2)]
    Vt, Ft = torus(1.0, 0.4, n_major=60, n_minor=24)
    ring = smooth_direction_field(Vt, Ft, symmetry=1, seed=0)
    panels.append(field_panel(Vt, Ft, ring.vectors, ring.singularities,
                              title="torus, smoothest 1-field", every=3))
    bob = read_mesh(sample_path("bob"))
    Vb, Fb = bob.vertices[:, [0, 2, 1]] * [-1, 1, 1], bob.faces
    up, _ = projected_direction_field(Vb, Fb, [0, 0, 1])
    panels.append(field_panel(Vb, Fb, up, singularities(Vb, Fb, up),
                              title="Bob, 'up' projected", every=6))
    render_panels(panels, out / "direction_fields.png", size=(700, 650))
    print(f"wrote {out / 'direction_fields.png'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
