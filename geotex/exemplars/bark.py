"""``bark``: elongated irregular ridges along y, broken into plates, with noise.

Ridges stand in columns along y.  Each column is broken into segments of
random length (bark plates) with short gaps; every segment is swept through
vertical slices ``y = const``: a flat bottom at ``z = -depth`` and a rounded,
slightly ribbed top whose centre line, width and height wander with smooth
random noise shared along the column, and all columns sway together with a
slower wave.  The noise amplitudes are bounded so that neighbouring columns
always keep a gap.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.exemplars.builders import (assemble, noise_at, smooth_noise,
                                       stack_faces, stack_vertices)
from geotex.exemplars.params import Param
from geotex.mesh.topology import concatenated

DESCRIPTION = "elongated irregular bark ridges along y, broken into plates"
GAP = 0.02
MARGIN = 0.005
WANDER = 0.12             # centre-line wander, fraction of the ridge half-width
SWAY = 0.3                # sway of all columns together, fraction of the pitch
SWELL = 0.2               # width variation, fraction of the half-width

PARAMS = (
    Param("pitch", 0.25, "spacing of the ridge columns", 0.06, 4.0),
    Param("width", 0.165, "mean ridge width", 0.02, 4.0),
    Param("length", 0.9, "mean plate (segment) length along y", 0.1, 100.0),
    Param("height", 0.2, "tallest ridge height above z = 0", 0.02, 2.0),
    Param("depth", 0.05, "how far ridges sink below z = 0", 0.005, 1.0),
    Param("jitter", 0.6, "irregularity of widths, heights, plate lengths and columns",
          0.0, 1.0),
    Param("resolution", 10, "points around each ridge cross-section", 6, 64, integer=True),
)


def _segments(ly, mean, rng, jitter):
    """Random plate intervals ``[(y0, y1), ...]`` covering ``[MARGIN, ly - MARGIN]``."""
    out, y = [], MARGIN + jitter * rng.uniform(0, 0.5) * mean
    end = ly - MARGIN
    while y < end - 0.25 * mean:
        L = mean * (1 + 0.6 * jitter * rng.uniform(-1, 1))
        gap = GAP + 0.08 * mean * jitter * rng.uniform(0, 1) + 0.02
        y1 = min(y + L, end)
        if end - y1 < 0.4 * mean:           # no short stub at the end
            y1 = end
        out.append((y, y1))
        y = y1 + gap
    return out


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the ridges; see :data:`PARAMS`."""
    pitch, w, j = p["pitch"], p["width"] / 2, p["jitter"]
    sway_amp = SWAY * pitch * j                          # shared by all columns
    ncol = max(1, int(round((size[0] - 2 * sway_amp) / pitch)))
    cx = (size[0] - 2 * sway_amp) / ncol
    reach = w * (1 + SWELL * j) + w * WANDER * j          # farthest a ridge side can go
    if 2 * reach + GAP > cx:
        raise InputError(f"exemplar 'bark': width {p['width']:g} is too large for pitch "
                         f"{pitch:g} (ridges would touch); use width <= "
                         f"{(cx - GAP) / (1 + SWELL * j + WANDER * j):.4g}")
    if size[1] < 0.25 * p["length"] + 2 * MARGIN:
        raise InputError(f"exemplar 'bark': a {size[0]:g} x {size[1]:g} patch is too short for "
                         f"plates of length {p['length']:g}")
    n = p["resolution"]
    # cross-section: the top arc from the right side over to the left side (most of
    # the n points), then the flat bottom back; angles in (0, 2 pi)
    nb_pts = max(2, n // 4)
    a = np.concatenate([np.pi * (np.arange(n - nb_pts) + 0.5) / (n - nb_pts),
                        np.pi * (1 + (np.arange(nb_pts) + 0.5) / nb_pts)])
    upper = np.arange(n) < n - nb_pts
    noise = smooth_noise(rng, 3 * ncol, waves=4, wavelength=1.5 * p["length"])
    rough = smooth_noise(rng, ncol, waves=5, wavelength=0.25)
    sway = smooth_noise(rng, 1, waves=3, wavelength=2.0 * p["length"])
    xs = sway_amp + (np.arange(ncol) + 0.5) * cx
    hmax = p["height"] + p["depth"]
    step = min(0.06, 0.5 * w)
    parts = []
    for c in range(ncol):
        rib_phase = rng.uniform(0, 2 * np.pi)
        for y0, y1 in _segments(size[1], p["length"], rng, j):
            L = y1 - y0
            cap = min(1.2 * w, 0.3 * L)
            ncap = 4
            nb = max(2, int(np.ceil((L - 2 * cap) / step)) + 1)
            phi = 0.5 * np.pi * np.arange(1, ncap + 1) / (ncap + 1)    # pole -> body
            back = cap * (1 - np.cos(phi))
            ys = np.concatenate([y0 + back, np.linspace(y0 + cap, y1 - cap, nb),
                                 (y1 - back)[::-1]])
            taper = np.concatenate([np.sin(phi), np.ones(nb), np.sin(phi)[::-1]])
            rows = np.array([3 * c, 3 * c + 1, 3 * c + 2])
            wander = (w * WANDER * j * noise_at(noise, rows[0], ys)
                      + sway_amp * noise_at(sway, 0, ys))
            half = w * (1 + SWELL * j * noise_at(noise, rows[1], ys)) * taper
            top = hmax * (1 - 0.35 * j * (0.5 + 0.5 * noise_at(noise, rows[2], ys))) * taper
            top *= (1 + 0.1 * j * noise_at(rough, c, ys)) / (1 + 0.1 * j)
            rib = 1 + 0.06 * np.sin(3 * a + rib_phase)          # lengthwise ribs on the top
            bulge = 0.45 + 0.25 * j * rng.uniform(-1, 1)       # rounder or flatter plates
            prof = np.where(upper, np.abs(np.sin(a)) ** bulge * rib / 1.06, 0.0)
            k = ys.size
            ring = np.empty((1, k, n, 3))
            ring[0, :, :, 0] = xs[c] + wander[:, None] + half[:, None] * np.cos(a)[None]
            ring[0, :, :, 1] = ys[:, None]
            ring[0, :, :, 2] = -p["depth"] + top[:, None] * prof[None]
            pole0 = np.array([[xs[c] + wander[0], y0, -p["depth"]]])
            pole1 = np.array([[xs[c] + wander[-1], y1, -p["depth"]]])
            parts.append(assemble(stack_vertices(ring, pole0, pole1), stack_faces(k, n)))
    V, F = concatenated(parts)
    return V, F
