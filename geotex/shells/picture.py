"""Pictures of shells: the polycube, its map onto the base, and the quad grid."""

from __future__ import annotations

import numpy as np

from geotex.render import Panel
from geotex.shells.locate import quad_points_to_base

__all__ = ["quad_grid_lines", "shell_panels"]


def quad_grid_lines(shell, *, samples: int = 8, lift: float = 0.0):
    """Polylines of every quad edge mapped onto the base.

    Parameters
    ----------
    samples : int, optional
        Points per edge.
    lift : float, optional
        Offset along the shell direction (so lines show above the surface).

    Returns
    -------
    points : (E * samples, 3) float64
    segments : (E * (samples - 1), 2) int64
        Index pairs into ``points``.
    """
    pc = shell.polycube
    E = pc.layout.edge_axis.size
    q = pc.layout.edge_quads[:, 0]
    side = pc.layout.edge_sides[:, 0]
    t = np.linspace(0.0, 1.0, samples)
    u = np.select([side[:, None] == 0, side[:, None] == 1, side[:, None] == 2],
                  [t[None, :], np.ones((1, samples)), 1.0 - t[None, :]], 0.0)
    v = np.select([side[:, None] == 0, side[:, None] == 1, side[:, None] == 2],
                  [np.zeros((1, samples)), t[None, :], np.ones((1, samples))], 1.0 - t[None, :])
    qq = np.repeat(q, samples)
    x, d = quad_points_to_base(shell, qq, np.stack([u.ravel(), v.ravel()], axis=1))
    pts = x + lift * d
    base = np.arange(E)[:, None] * samples
    a = (base + np.arange(samples - 1)[None, :]).ravel()
    return pts, np.stack([a, a + 1], axis=1)


def shell_panels(shell, *, title: str | None = None) -> list:
    """Three panels: the polycube, the base coloured by quad direction, the quad grid."""
    pc = shell.polycube
    name = title or shell.name
    labels = pc.layout.quad_label[pc.layout.face_quad]
    diag = float(np.linalg.norm(np.ptp(pc.Y, axis=0)))
    pts, seg = quad_grid_lines(shell, lift=2e-3 * diag)
    n = shell.base_vertices.shape[0]
    Vg = np.vstack([shell.base_vertices, pts])
    folded = int(pc.quad_folded.sum())
    return [
        Panel(pc.positions, pc.F, scalars=labels, cmap="Set2",
              title=f"{name}: polycube, {pc.layout.n_quads} quads"),
        Panel(pc.Y, pc.F, scalars=labels, cmap="Set2",
              title="mapped onto the base" + (f", {folded} bare" if folded else "")),
        Panel(Vg, shell.base_faces, color="#d9c7a3", highlight={"quad edge segments": seg + n},
              title=f"tile grid, max height {shell.max_height:.3g}"),
    ]
