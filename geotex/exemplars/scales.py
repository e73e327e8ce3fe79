"""``scales``: overlapping fish/dragon scales, thin curved shells lifted at the tail.

Each scale is a star-shaped solid over an elliptic outline whose root end
(toward -y) sinks into the base while the rest is a shell of constant
thickness rising linearly toward the tail (+y) and sagging toward its sides.
Rows are offset by half a pitch; the row spacing is shorter than a scale, so
every tail lies over the roots of the next row.  All scales share one slope,
so a tail floats ``slope * row_spacing - thickness - sag`` above the scale
below it: they overlap in plan view but never touch in 3D.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, stack_faces, stack_vertices
from geotex.exemplars.params import Param

DESCRIPTION = "overlapping fish/dragon scales in offset rows, lifted at the tail"
GAP = 0.03
MARGIN = 0.005
JITTER_X = 0.25 * GAP     # largest sideways offset of a scale (at jitter 1)

PARAMS = (
    Param("pitch", 0.5, "spacing of scales along a row (scale width + gap)", 0.1, 4.0),
    Param("length", 0.5, "scale length along y", 0.1, 4.0),
    Param("row_spacing", 0.28, "spacing of the rows (between length/2 and length)", 0.05, 4.0),
    Param("height", 0.25, "height of the lifted tails above z = 0", 0.05, 2.0),
    Param("thickness", 0.035, "shell thickness", 0.005, 0.5),
    Param("depth", 0.05, "how far the roots sink below z = 0", 0.005, 1.0),
    Param("jitter", 0.5, "random offset and tail height variation, 0 = regular", 0.0, 1.0),
    Param("resolution", 20, "points around each scale", 8, 96, integer=True),
)


def _layout(size, p):
    L, py, px = p["length"], p["row_spacing"], p["pitch"]
    if not (0.5 * L < py < L):
        raise InputError(f"exemplar 'scales': row_spacing {py:g} must lie between length/2 "
                         f"and length ({0.5 * L:g} .. {L:g}) so that rows overlap once")
    rx = (px - GAP) / 2
    edge = MARGIN + rx + JITTER_X * p["jitter"]
    lo_x, hi_x = edge, size[0] - edge
    rows = int(np.floor((size[1] - 2 * MARGIN - L) / py)) + 1 if size[1] - 2 * MARGIN >= L else 0
    if rows < 1 or hi_x < lo_x:
        raise InputError(f"exemplar 'scales': a {size[0]:g} x {size[1]:g} patch is too small "
                         f"for scales of pitch {px:g} and length {L:g}")
    n_even = int(np.floor((hi_x - lo_x) / px)) + 1
    x0 = lo_x + 0.5 * ((hi_x - lo_x) - (n_even - 1) * px)
    y_free = (size[1] - 2 * MARGIN - L) - (rows - 1) * py
    roots = []
    for r in range(rows):
        xs = x0 + px * np.arange(n_even) + (r % 2) * px / 2
        xs = xs[xs <= hi_x + 1e-12]
        roots.append(np.column_stack([xs, np.full(xs.size, MARGIN + 0.5 * y_free + r * py)]))
    return np.vstack(roots), rx


def period(size, p: dict) -> tuple[float, float]:
    """Lattice of the layout: half a pitch along the rows, one row spacing across.

    Odd rows are offset by half a pitch, so a shift by ``(pitch / 2,
    row_spacing)`` maps the pattern onto itself (quilting picks the right
    parity of the cell multiples by the matching energy).
    """
    return (0.5 * p["pitch"], p["row_spacing"])


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the scales; see :data:`PARAMS`."""
    root, rx = _layout(size, p)
    E = root.shape[0]
    L, py, t, depth = p["length"], p["row_spacing"], p["thickness"], p["depth"]
    ry = L / 2
    z0 = 0.1 * (p["height"] - t)                       # top of the root end
    j = p["jitter"]
    h = p["height"] * (1 - 0.06 * j * rng.uniform(0, 1, E))
    h *= p["height"] / h.max()
    slope = (h - z0) / L
    # smallest possible slope (any seed): heights vary by at most 6 % x jitter
    least = (p["height"] * (1 - 0.06 * j) - z0) / L
    clearance = least * (py - 0.06 * j * L) - t
    sag = 0.5 * clearance
    if clearance - sag < GAP / 3:
        raise InputError(f"exemplar 'scales': tails would touch the next row; raise height "
                         f"(now {p['height']:g}) or row_spacing, or lower thickness "
                         f"(now {t:g})")
    root = root + np.column_stack([JITTER_X * j * rng.uniform(-1, 1, E), np.zeros(E)])
    n = p["resolution"]
    a = 2 * np.pi * np.arange(n) / n
    ring = np.stack([rx * np.cos(a), ry * np.sin(a)], -1)      # (n, 2) around the centre
    rho_bot = np.array([1 / 3, 2 / 3, 1.0])
    rho_top = np.array([1.0, 0.75, 0.5, 0.25])
    centre = root + np.array([0.0, ry])

    def plan(rho):                                             # (E, k, n, 2) local dx, dy
        d = rho[:, None, None] * ring[None]
        return np.broadcast_to(d + np.array([0.0, ry]), (E,) + d.shape)

    def top(d):
        return (z0 + slope[:, None, None] * d[..., 1]
                - sag * (d[..., 0] / rx) ** 2)

    def bottom(d):
        s = np.clip((d[..., 1] - 0.2 * L) / (0.15 * L), 0.0, 1.0)
        s = s * s * (3 - 2 * s)
        return -depth + s * (top(d) - t + depth)

    db, dt = plan(rho_bot), plan(rho_top)
    rings = np.concatenate([
        np.concatenate([db + root[:, None, None], bottom(db)[..., None]], -1),
        np.concatenate([dt + root[:, None, None], top(dt)[..., None]], -1)], axis=1)
    c0 = np.zeros((1, 1, 1, 2)) + np.array([0.0, ry])
    pole0 = np.column_stack([centre, bottom(np.broadcast_to(c0, (E, 1, 1, 2)))[:, 0, 0]])
    pole1 = np.column_stack([centre, top(np.broadcast_to(c0, (E, 1, 1, 2)))[:, 0, 0]])
    k = rho_bot.size + rho_top.size
    return assemble(stack_vertices(rings, pole0, pole1), stack_faces(k, n))
