"""``weave``: interlaced over-under strands in two directions (plain weave).

Every strand is one element: an elliptic tube swept through vertical slices
(``x = const`` for strands along x, ``y = const`` for strands along y) that
runs across the patch and ends in rounded caps just inside the border.  Its
centre line rises to ``+amplitude`` where it passes over a crossing strand
and falls to ``-amplitude`` where it passes under; the profile is a flattened
cosine (``tanh(k cos)``) so strands stay apart over the whole crossing.  The
lower halves of the under-crossings sink below ``z = 0`` into the base.

:func:`strand_geometry` and :func:`tile_strands` serve the periodic tile sets
(:mod:`geotex.tiles.periodic`): the same strands, open tubes that run from one
side of the unit tile to the other, whose end cross-sections depend only on
the side's lateral offsets (so a strand continues bit for bit on the
neighbour tile), and :func:`crossing_clearance` bounds how close two crossing
strands come.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, stack_faces, stack_vertices
from geotex.exemplars.params import Param
from geotex.mesh.topology import concatenated

__all__ = ["DESCRIPTION", "PARAMS", "GAP", "build", "strand_geometry", "tile_strands",
           "crossing_clearance"]

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


def strand_geometry(p: dict, *, pitch: float | None = None) -> dict:
    """Half width, half thickness, centre height and amplitude of the strands.

    Parameters
    ----------
    p : dict
        Weave parameters (:data:`PARAMS`).
    pitch : float, optional
        Strand spacing to use instead of ``p["pitch"]``.

    Returns
    -------
    dict
        ``w`` (half width), ``t`` (half thickness), ``amp`` (amplitude of the
        centre line), ``centre`` (its mean height), ``free`` (room left
        between parallel strands once :data:`GAP` is kept).

    Raises
    ------
    InputError
        The width leaves no gap within the pitch, or crossing strands would touch.
    """
    pitch = float(p["pitch"] if pitch is None else pitch)
    w, t = p["width"] / 2, p["thickness"] / 2
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
    return {"w": float(w), "t": float(t), "amp": float(amp), "centre": float(centre_z),
            "free": float(free)}


def crossing_clearance(geom: dict, pitch: float, shift: float, *, samples: int = 121) -> float:
    """Smallest vertical gap between two crossing strands moved sideways by up to ``shift``.

    The upper strand runs along x over the crossing at the origin, the lower
    one along y; each is moved sideways by ``-shift``, ``0`` or ``+shift``, and
    the gap between the upper strand's underside and the lower strand's top
    is taken on a ``samples x samples`` grid over the square where both
    overlap (vertical slices, as :func:`tile_strands` meshes them).

    Parameters
    ----------
    geom : dict
        From :func:`strand_geometry`.
    pitch : float
        Strand spacing (half a period of the over-under profile).
    shift : float
        Largest sideways offset of a strand from its lattice line.
    samples : int
        Grid points per axis.

    Returns
    -------
    float
        The smallest gap (negative: the strands would cross).
    """
    w, t, amp = geom["w"], geom["t"], geom["amp"]
    g = np.linspace(-1.0, 1.0, samples)
    best = np.inf
    for dx in (-shift, 0.0, shift):          # the lower strand (along y) sits at x = dx
        for dy in (-shift, 0.0, shift):      # the upper strand (along x) at y = dy
            x = dx + w * g[:, None]
            y = dy + w * g[None, :]
            upper = amp * _profile(np.pi * x / pitch) - t * np.sqrt(
                np.clip(1 - ((y - dy) / w) ** 2, 0, None))
            lower = -amp * _profile(np.pi * y / pitch) + t * np.sqrt(
                np.clip(1 - ((x - dx) / w) ** 2, 0, None))
            best = min(best, float((upper - lower).min()))
    return best


def _band_faces(k: int, n: int) -> np.ndarray:
    """Faces of an open tube of ``k`` rings of ``n`` points (outward for rings that
    turn from +u towards +z, stations along +x)."""
    rings = np.arange(k * n, dtype=np.int64).reshape(k, n)
    nxt = np.roll(rings, -1, axis=1)
    a, b, c, d = rings[:-1], nxt[:-1], nxt[1:], rings[1:]
    return np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                           np.stack([a, c, d], -1).reshape(-1, 3)])


def tile_strands(start, end, bump, sign, *, geom: dict, resolution: int,
                 stations: int) -> tuple[np.ndarray, np.ndarray]:
    """Strands along x across the unit tile, open at ``x = 0`` and ``x = 1``.

    Strand ``m`` of ``n = len(start)`` (``n`` even) follows the lattice line
    ``y = (m + 1/2) / n`` moved sideways by
    ``start[m] (1 - h(x)) + end[m] h(x) + bump[m] sin^2(pi x)``, ``h`` the
    smoothstep ``3 x^2 - 2 x^3`` (so the strand leaves both sides square to
    them); its centre line rises and falls as ``centre + sign[m] amp
    profile(pi (n x - 1/2))``, at mid height on the tile sides and at its top
    or bottom at the crossings ``x = (i + 1/2) / n``. Cross-sections are
    ellipses in the vertical planes ``x = const``. The end rings at ``x = 0``
    and ``x = 1`` depend only on ``start`` and ``end`` (same arithmetic for
    both), so two tiles whose sides carry the same offsets meet bit for bit.

    Parameters
    ----------
    start, end, bump : numpy.ndarray, (n,) float64
        Sideways offsets at ``x = 0``, at ``x = 1`` and mid-tile.
    sign : numpy.ndarray, (n,) float64
        ``+1``: the strand passes over at the crossings with ``i`` even.
    geom : dict
        From :func:`strand_geometry`.
    resolution : int
        Points around each strand.
    stations : int
        Cross-sections per pitch (``1 / n``).

    Returns
    -------
    V : numpy.ndarray, (n (n stations + 1) resolution, 3) float64
    F : numpy.ndarray, (2 n n stations resolution, 3) int64
        Open tubes, outward oriented; strand ``m`` owns one contiguous block of vertices.
    """
    start, end = np.asarray(start, float), np.asarray(end, float)
    bump, sign = np.asarray(bump, float), np.asarray(sign, float)
    n = start.size
    k = n * int(stations) + 1
    s = np.arange(k) / (k - 1)                              # 0 and 1 exactly
    h = s * s * (3.0 - 2.0 * s)
    b = np.sin(np.pi * s) ** 2
    off = start[:, None] * (1.0 - h) + end[:, None] * h + bump[:, None] * b
    zc = geom["centre"] + geom["amp"] * sign[:, None] * _profile(np.pi * (n * s - 0.5))
    # the side cross-sections from the side's offsets alone, at mid height exactly
    off[:, 0], off[:, -1] = start, end
    zc[:, 0] = zc[:, -1] = geom["centre"]
    u = (np.arange(n) + 0.5) / n
    a = 2 * np.pi * np.arange(resolution) / resolution
    cos_a, sin_a = np.cos(a), np.sin(a)
    P = np.empty((n, k, resolution, 3))
    P[..., 0] = s[None, :, None]
    P[..., 1] = (u[:, None] + off)[..., None] + geom["w"] * cos_a
    P[..., 2] = zc[..., None] + geom["t"] * sin_a
    F = _band_faces(k, resolution)
    faces = (F[None] + (k * resolution * np.arange(n))[:, None, None]).reshape(-1, 3)
    return P.reshape(-1, 3), faces


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the strands; see :data:`PARAMS`."""
    pitch = p["pitch"]
    geom = strand_geometry(p)
    w, amp, centre_z = geom["w"], geom["amp"], geom["centre"]
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
    return concatenated([A, B])
