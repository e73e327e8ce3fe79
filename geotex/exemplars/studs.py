"""``studs``: rounded rivets on a jittered grid (surfaces of revolution)."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, stack_faces, stack_vertices
from geotex.exemplars.params import Param

DESCRIPTION = "rounded rivets/studs on a jittered grid"
GAP = 0.02

PARAMS = (
    Param("pitch", 0.5, "grid spacing between stud centres", 0.1, 4.0),
    Param("radius", 0.17, "stud radius (must leave a gap within the pitch)", 0.02, 2.0),
    Param("height", 0.2, "stud height above z = 0", 0.02, 2.0),
    Param("depth", 0.05, "how far studs sink below z = 0", 0.005, 1.0),
    Param("jitter", 0.5, "random offset and size variation, 0 = regular", 0.0, 1.0),
    Param("resolution", 12, "points around each stud", 6, 96, integer=True),
)


def grid_cells(size, pitch):
    """Cell counts and sizes of a grid of about ``pitch`` fitting ``size`` exactly."""
    nx = max(1, int(round(size[0] / pitch)))
    ny = max(1, int(round(size[1] / pitch)))
    return nx, ny, size[0] / nx, size[1] / ny


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the studs; see :data:`PARAMS`."""
    nx, ny, cx, cy = grid_cells(size, p["pitch"])
    r_max = p["radius"] * (1 + 0.1 * p["jitter"])
    if 2 * r_max + GAP > min(cx, cy):
        raise InputError(
            f"exemplar 'studs': radius {p['radius']:g} is too large for pitch {p['pitch']:g} "
            f"on a {size[0]:g} x {size[1]:g} patch (studs would touch); use radius <= "
            f"{(min(cx, cy) - GAP) / 2 / (1 + 0.1 * p['jitter']):.4g} or a larger pitch")
    E = nx * ny
    ii, jj = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    centre = np.stack([(ii.ravel() + 0.5) * cx, (jj.ravel() + 0.5) * cy], -1)
    j = p["jitter"]
    r = p["radius"] * (1 + 0.1 * j * rng.uniform(-1, 1, E))
    h = p["height"] * (1 + 0.1 * j * rng.uniform(-1, 1, E))
    h *= p["height"] / h.max()                      # the tallest stud is exactly `height`
    free = np.stack([cx / 2 - r - GAP / 2, cy / 2 - r - GAP / 2], -1)
    centre = centre + j * free * rng.uniform(-1, 1, (E, 2))
    n = p["resolution"]
    nd = max(2, n // 4)                             # dome rings (quarter circle)
    dome = np.minimum(0.75 * r, 0.7 * h)
    wall = h - dome
    phi = 0.5 * np.pi * np.arange(nd) / nd          # 0 = top of the wall
    ring_r = np.concatenate([r[:, None], r[:, None] * np.cos(phi)[None]], axis=1)
    ring_z = np.concatenate([np.full((E, 1), -p["depth"]),
                             wall[:, None] + dome[:, None] * np.sin(phi)[None]], axis=1)
    t = 2 * np.pi * np.arange(n) / n
    rings = np.empty((E, ring_r.shape[1], n, 3))
    rings[..., 0] = centre[:, None, None, 0] + ring_r[..., None] * np.cos(t)
    rings[..., 1] = centre[:, None, None, 1] + ring_r[..., None] * np.sin(t)
    rings[..., 2] = ring_z[..., None]
    pole0 = np.column_stack([centre, np.full(E, -p["depth"])])
    pole1 = np.column_stack([centre, h])
    P = stack_vertices(rings, pole0, pole1)
    return assemble(P, stack_faces(rings.shape[1], n))
