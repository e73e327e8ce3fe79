"""``knurl``: diamond or hexagonal knurl pyramids on a staggered lattice."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, polygon_outline, stack_faces, stack_vertices
from geotex.exemplars.params import Param

DESCRIPTION = "diamond or hexagonal knurl pyramids"
GAP = 0.015
MARGIN = 0.005

PARAMS = (
    Param("pattern", "diamond", "pyramid base shape", choices=("diamond", "hex")),
    Param("pitch", 0.4, "distance between neighbouring pyramid centres (diamond: "
          "diagonal)", 0.08, 4.0),
    Param("height", 0.15, "apex height above z = 0", 0.02, 2.0),
    Param("depth", 0.05, "how far pyramids sink below z = 0", 0.005, 1.0),
    Param("jitter", 0.3, "random apex offset and height variation, 0 = regular", 0.0, 1.0),
    Param("resolution", 3, "subdivisions of every pyramid face", 1, 16, integer=True),
)


def _lattice(size, p, pattern):
    """Centres, outline (unit), circumradius, apothem and plan half-extents."""
    if pattern == "diamond":
        d = p / 2 - GAP / np.sqrt(2)                # half-diagonal after the gap
        ext = np.array([d, d])
        step, row = np.array([p, p / 2]), "rows"
        sides, rotation, circ, apo = 4, 0.0, d, d / np.sqrt(2)
    else:
        apo = p / 2 - GAP / 2
        circ = apo * 2 / np.sqrt(3)
        ext = np.array([circ, apo])
        step, row = np.array([1.5 * p / np.sqrt(3), p]), "columns"
        sides, rotation = 6, 0.0
    lo = ext + MARGIN
    hi = np.asarray(size) - ext - MARGIN
    if np.any(hi < lo):
        raise InputError(f"exemplar 'knurl': pitch {p:g} is too large for a "
                         f"{size[0]:g} x {size[1]:g} patch; use a smaller pitch")
    n = np.floor((hi - lo) / step).astype(int) + 1
    ii, jj = np.meshgrid(np.arange(n[0]), np.arange(n[1]), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    C = lo + np.stack([ii, jj], -1) * step
    if row == "rows":
        C[:, 0] += (jj % 2) * p / 2
    else:
        C[:, 1] += (ii % 2) * p / 2
    keep = np.all((C >= lo - 1e-12) & (C <= hi + 1e-12), axis=1)
    C = C[keep]
    C += 0.5 * ((hi - C.max(axis=0)) - (C.min(axis=0) - lo))      # centre the pattern
    return C, sides, rotation, circ, apo


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the pyramids; see :data:`PARAMS`."""
    C, sides, rotation, circ, apo = _lattice(size, p["pitch"], p["pattern"])
    E = C.shape[0]
    m = p["resolution"]
    outline = circ * polygon_outline(sides, m, rotation=rotation)       # (n, 2)
    n = outline.shape[0]
    j = p["jitter"]
    h = p["height"] * (1 - 0.15 * j * rng.uniform(0, 1, E))
    h *= p["height"] / h.max()
    ang = rng.uniform(0, 2 * np.pi, E)
    off = 0.15 * j * apo * rng.uniform(0, 1, E)
    apex = C + off[:, None] * np.stack([np.cos(ang), np.sin(ang)], -1)
    z_rim = -0.4 * p["depth"]
    rho = np.arange(m, 0, -1) / m                                      # 1 .. 1/m
    rim = C[:, None, :] + outline[None]                                 # (E, n, 2)
    plan = apex[:, None, None] + rho[None, :, None, None] * (rim[:, None] - apex[:, None, None])
    ztop = z_rim + (h[:, None] - z_rim) * (1 - rho)[None]               # (E, m)
    rings = np.empty((E, m + 1, n, 3))
    rings[:, 0, :, :2] = rim
    rings[:, 0, :, 2] = -p["depth"]
    rings[:, 1:, :, :2] = plan
    rings[:, 1:, :, 2] = ztop[..., None]
    pole0 = np.column_stack([C, np.full(E, -p["depth"])])
    pole1 = np.column_stack([apex, h])
    return assemble(stack_vertices(rings, pole0, pole1), stack_faces(m + 1, n))
