"""``weave``: interlaced over-under strands in two directions (plain weave).

Every strand is one element: an elliptic tube swept through vertical slices
(``x = const`` for strands along x, ``y = const`` for strands along y) that
runs across the patch and ends in rounded caps just inside the border.  Its
centre line rises to ``+amplitude`` where it passes over a crossing strand
and falls to ``-amplitude`` where it passes under; the profile is a flattened
cosine (``tanh(k cos)``) so strands stay apart over the whole crossing.  The
lower halves of the under-crossings sink below ``z = 0`` into the base.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, concatenate, stack_faces, stack_vertices
from geotex.exemplars.params import Param

DESCRIPTION = "interlaced over-under strands in two directions (plain weave)"
GAP = 0.02
MARGIN = 0.005
FLAT = 2.0                      # profile flattening: tanh(FLAT cos) / tanh(FLAT)

PARAMS = (
    Param("pitch", 0.5, "spacing of parallel strands", 0.1, 4.0),
    Param("width", 0.36, "strand width (must leave a gap within the pitch)", 0.02, 4.0),
    Param("thickness", 0.07, "strand thickness", 0.01, 1.0),
    Param("height", 0.16, "top of the over-crossings above z = 0", 0.03, 2.0),
    Param("depth", 0.05, "how far the under-crossings sink below z = 0", 0.005, 1.0),
    Param("jitter", 0.5, "random sideways offset of the strands, 0 = regular", 0.0, 1.0),
    Param("resolution", 12, "points around each strand", 6, 64, integer=True),
)


def _profile(phase):
    return np.tanh(FLAT * np.cos(phase)) / np.tanh(FLAT)


def _phase(s, crossings, spacing):
    """Piecewise-linear phase: pi * i at crossing i, extrapolated beyond the ends."""
    c = crossings
    if c.size == 1:
        return np.pi * (s - c[0]) / spacing
    i = np.clip(np.searchsorted(c, s) - 1, 0, c.size - 2)
    return np.pi * (i + (s - c[i]) / (c[i + 1] - c[i]))


def _strands(along, across, fixed, length, crossings, sign, p, centre_z, amp):
    """Vertices of the strands parallel to axis ``along`` (0 = x, 1 = y)."""
    n = p["resolution"]
    w, t = p["width"] / 2, p["thickness"] / 2
    cap_len = min(0.6 * w, 0.45 * length)
    lo, hi = MARGIN, length - MARGIN
    body_len = hi - lo - 2 * cap_len
    per_pitch = max(6, int(round(0.7 * n)))
    nb = int(np.ceil(body_len / p["pitch"] * per_pitch)) + 1
    ncap = 4
    phi = 0.5 * np.pi * np.arange(1, ncap + 1) / (ncap + 1)            # pole -> body
    back = cap_len * (1 - np.cos(phi))
    s_body = lo + cap_len + np.linspace(0.0, body_len, nb)
    s = np.concatenate([lo + back, s_body, (hi - back)[::-1]])
    scale = np.concatenate([np.sin(phi), np.ones(nb), np.sin(phi)[::-1]])
    a = 2 * np.pi * np.arange(n) / n
    E = fixed.size
    zc = centre_z + amp * sign[:, None] * _profile(_phase(s, crossings, p["pitch"]))[None]
    rings = np.empty((E, s.size, n, 3))
    rings[..., along] = s[None, :, None]
    rings[..., across] = fixed[:, None, None] + w * scale[None, :, None] * np.cos(a)
    rings[..., 2] = zc[..., None] + t * scale[None, :, None] * np.sin(a)
    ends = _phase(np.array([lo, hi]), crossings, p["pitch"])
    z_end = centre_z + amp * sign[:, None] * _profile(ends)
    pole0 = np.zeros((E, 3))
    pole1 = np.zeros((E, 3))
    pole0[:, along], pole1[:, along] = lo, hi
    pole0[:, across] = pole1[:, across] = fixed
    pole0[:, 2], pole1[:, 2] = z_end[:, 0], z_end[:, 1]
    return assemble(stack_vertices(rings, pole0, pole1), stack_faces(s.size, n))


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the strands; see :data:`PARAMS`."""
    pitch, w, t = p["pitch"], p["width"] / 2, p["thickness"] / 2
    free = pitch - 2 * w - GAP
    if free < 0:
        raise InputError(f"exemplar 'weave': width {p['width']:g} leaves no gap within pitch "
                         f"{pitch:g}; use width <= {pitch - GAP:.4g}")
    amp = 0.5 * (p["height"] + p["depth"]) - t
    centre_z = 0.5 * (p["height"] - p["depth"])
    # vertical clearance at a crossing corner (offset w along both strands), flattened profile
    corner = 2 * amp * _profile(np.pi * w / pitch)
    if amp <= 0 or 2 * amp - 2 * t < GAP or corner - 2 * t * np.sqrt(0.5) < GAP:
        need = 2 * max(t + GAP / 2, (GAP + np.sqrt(2) * t) / (2 * _profile(np.pi * w / pitch))
                       if _profile(np.pi * w / pitch) > 0 else np.inf) + 2 * t
        hint = (f"raise height to at least {np.ceil(1e4 * (need - p['depth'])) / 1e4:.4g}"
                if np.isfinite(need) else "use a narrower width")
        raise InputError(f"exemplar 'weave': height + depth ({p['height'] + p['depth']:g}) "
                         f"is too small for thickness {p['thickness']:g}: crossing strands "
                         f"would touch; {hint} or lower thickness")
    nx = max(1, int(round(size[1] / pitch)))         # strands along x (stacked in y)
    ny = max(1, int(round(size[0] / pitch)))         # strands along y
    cy, cx = size[1] / nx, size[0] / ny
    if min(cx, cy) < 2 * w + GAP or size[0] < 4 * w or size[1] < 4 * w:
        raise InputError(f"exemplar 'weave': a {size[0]:g} x {size[1]:g} patch is too small "
                         f"for pitch {pitch:g}")
    j = p["jitter"]
    off_x = j * 0.5 * (cx - 2 * w - GAP) * rng.uniform(-1, 1, ny)
    off_y = j * 0.5 * (cy - 2 * w - GAP) * rng.uniform(-1, 1, nx)
    ys = (np.arange(nx) + 0.5) * cy + off_y            # strands along x sit at these y
    xs = (np.arange(ny) + 0.5) * cx + off_x            # strands along y sit at these x
    # strand i along x passes over strand k along y when i + k is even
    sx = np.where(np.arange(nx) % 2 == 0, 1.0, -1.0)
    sy = np.where(np.arange(ny) % 2 == 0, -1.0, 1.0)
    A = _strands(0, 1, ys, size[0], xs, sx, p, centre_z, amp)
    B = _strands(1, 0, xs, size[1], ys, sy, p, centre_z, amp)
    return concatenate([A, B])
