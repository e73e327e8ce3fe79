"""A library of seamless height maps, generated procedurally (no licences involved).

Every map is a function of the unit square that repeats with period one in
both directions *by construction*: waves and lattices use whole numbers of
periods, cells use periodic distances (a KD-tree on the unit torus), noise
is white noise shaped in the Fourier domain (periodic by definition).
Hexagonal and triangular lattices cannot repeat exactly on a square; they use
the nearest whole-number lattice (7 x 8 rows, about 1 % stretched).
Random ones are seeded, so the same name always gives the same pixels.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from geotex.errors import InputError

__all__ = ["library_names", "library_height_map", "library_descriptions", "LIBRARY_SIZE"]

#: Side of the generated maps, pixels.
LIBRARY_SIZE = 512


def _grid(N):
    t = (np.arange(N) + 0.5) / N
    x, y = np.meshgrid(t, 1.0 - t)            # y up, like the tile coordinates
    return x, y


def _frac(t):
    return t - np.floor(t)


def _tri(t):
    """Triangle wave in [0, 1], 1 at whole numbers."""
    return 1.0 - 2.0 * np.abs(_frac(t) - 0.5)


def _smooth(e0, e1, t):
    s = np.clip((t - e0) / (e1 - e0), 0.0, 1.0)
    return s * s * (3 - 2 * s)


def _norm(h):
    lo, hi = float(h.min()), float(h.max())
    return (h - lo) / (hi - lo) if hi > lo else np.zeros_like(h)


def _noise(N, beta=2.0, seed=0, low=2):
    """Periodic fractal noise: white noise with a 1/f**beta spectrum."""
    rng = np.random.default_rng(seed)
    w = rng.standard_normal((N, N))
    k = np.fft.fftfreq(N) * N
    kx, ky = np.meshgrid(k, k)
    f = np.hypot(kx, ky)
    amp = np.where(f >= 1, (np.maximum(f, 1) / low) ** (-beta / 1.0), 0.0)
    amp[f < 1] = 0.0
    h = np.real(np.fft.ifft2(np.fft.fft2(w) * amp))
    return _norm(h)


def _cells(N, points, k=2):
    """Periodic distances to the nearest ``k`` points and the nearest's index."""
    from scipy.spatial import cKDTree

    x, y = _grid(N)
    P = np.mod(points, 1.0)
    tree = cKDTree(P, boxsize=1.0)
    d, i = tree.query(np.column_stack([x.ravel(), y.ravel()]), k=k)
    return d.reshape(N, N, k), i.reshape(N, N, k)


def _hex_lattice(n=7, m=8):
    j, i = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
    return np.column_stack([((i + 0.5 * (j % 2)) / n).ravel(), (j / m).ravel()])


def _periodic_delta(a, b):
    return _frac(a - b + 0.5) - 0.5


# --------------------------------------------------------------------- maps


def knurling(N):
    x, y = _grid(N)
    n = 12
    return np.minimum(_tri(n * (x + y)), _tri(n * (x - y)))


def knurl_straight(N):
    x, _ = _grid(N)
    return _tri(16 * x)


def hexagons(N):
    d, _ = _cells(N, _hex_lattice())
    return _smooth(0.0, 0.025, d[..., 1] - d[..., 0])


def honeycomb(N):
    return 1.0 - hexagons(N)


def _jittered(n, seed, jitter=0.8):
    """``n * n`` cell sites: a grid with random offsets (no near-duplicate sites)."""
    rng = np.random.default_rng(seed)
    j, i = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    g = np.column_stack([i.ravel(), j.ravel()]) + 0.5
    return (g + jitter * (rng.random(g.shape) - 0.5)) / n


def voronoi(N):
    d, _ = _cells(N, _jittered(7, 7))
    return _smooth(0.0, 0.03, d[..., 1] - d[..., 0])


def bricks(N):
    x, y = _grid(N)
    rows, per_row, mortar = 8, 4, 0.06
    ry = y * rows
    row = np.floor(ry)
    bx = x * per_row + 0.5 * (row % 2)
    fx, fy = _frac(bx), _frac(ry)
    ex = np.minimum(fx, 1 - fx) / per_row        # distance to a vertical joint, tile units
    ey = np.minimum(fy, 1 - fy) / rows
    e = np.minimum(ex, ey)
    g = mortar / rows
    return _smooth(0.5 * g, 1.5 * g, e)


def weave(N):
    x, y = _grid(N)
    n = 8
    cx, cy = np.floor(x * n), np.floor(y * n)
    fx, fy = _frac(x * n), _frac(y * n)
    over = (cx + cy) % 2 == 0                   # horizontal strand on top in this cell
    hs = np.sqrt(np.clip(1 - (2 * fy - 1) ** 2, 0, 1)) * np.where(over, 1.0, 0.55)
    vs = np.sqrt(np.clip(1 - (2 * fx - 1) ** 2, 0, 1)) * np.where(over, 0.55, 1.0)
    return np.maximum(hs, vs)


def carbon_fiber(N):
    x, y = _grid(N)
    n = 8
    cx, cy = np.floor(x * n), np.floor(y * n)
    horiz = ((cx + cy) % 4) < 2                 # 2 x 2 twill
    fx, fy = _frac(x * n), _frac(y * n)
    tow = np.where(horiz, np.sqrt(np.clip(1 - (2 * fy - 1) ** 2, 0, 1)),
                   np.sqrt(np.clip(1 - (2 * fx - 1) ** 2, 0, 1)))
    fib = np.where(horiz, _tri(6 * y * n), _tri(6 * x * n))
    return 0.85 * tow + 0.15 * fib * tow


def wood(N):
    x, y = _grid(N)
    w = _noise(N, beta=2.5, seed=3)
    return 0.5 + 0.5 * np.sin(2 * np.pi * (10 * y + 1.5 * w + 0.3 * np.sin(2 * np.pi * x)))


def leather(N):
    pts = _jittered(15, 11)
    d, _ = _cells(N, pts)
    ridge = _smooth(0.0, 0.012, d[..., 1] - d[..., 0])
    return 0.8 * ridge * (0.7 + 0.3 * _noise(N, beta=1.2, seed=5)) + 0.2 * _noise(N, seed=6)


def dots(N):
    x, y = _grid(N)
    n = 8
    r = np.hypot(_frac(x * n) - 0.5, _frac(y * n) - 0.5) / 0.35
    return np.sqrt(np.clip(1 - r * r, 0, 1))


def studs(N):
    x, y = _grid(N)
    n = 6
    r = np.hypot(_frac(x * n) - 0.5, _frac(y * n) - 0.5)
    return _smooth(0.32, 0.28, r)


def grid(N):
    x, y = _grid(N)
    n, w = 8, 0.08
    e = np.minimum(np.minimum(_frac(x * n), 1 - _frac(x * n)),
                   np.minimum(_frac(y * n), 1 - _frac(y * n)))
    return _smooth(w, 0.5 * w, e)


def noise(N):
    return _noise(N, beta=2.0, seed=1)


def isogrid(N):
    x, y = _grid(N)
    n, m = 7, 8
    w = 0.07
    rib = np.zeros_like(x)
    for g in (m * y, n * x - 0.5 * m * y, n * x + 0.5 * m * y):
        rib = np.maximum(rib, _smooth(w, 0.5 * w, np.minimum(_frac(g), 1 - _frac(g))))
    return rib


def grip(N):
    x, y = _grid(N)
    chev = _frac(10 * x + 2 * _tri(4 * y))
    return _smooth(0.2, 0.35, np.minimum(chev, 1 - chev) * 2)


def bubbles(N):
    rng = np.random.default_rng(21)
    x, y = _grid(N)
    h = np.zeros_like(x)
    for _ in range(70):
        cx, cy = rng.random(2)
        r = rng.uniform(0.03, 0.09)
        d2 = (_periodic_delta(x, cx) ** 2 + _periodic_delta(y, cy) ** 2) / (r * r)
        h = np.maximum(h, (r / 0.09) * np.sqrt(np.clip(1 - d2, 0, 1)))
    return h


def crystal(N):
    rng = np.random.default_rng(31)
    pts = rng.random((40, 2))
    d, i = _cells(N, pts, k=1)
    i = i[..., 0]
    x, y = _grid(N)
    g = rng.normal(size=(40, 2)) * 3.0
    c = rng.uniform(0.3, 0.7, 40)
    dx = _periodic_delta(x, pts[i, 0])
    dy = _periodic_delta(y, pts[i, 1])
    facet = np.clip(c[i] + g[i, 0] * dx + g[i, 1] * dy, 0, 1)
    return 0.7 * facet + 0.3 * (1 - _norm(d[..., 0]))


def waves(N):
    x, y = _grid(N)
    return 0.5 + 0.5 * np.sin(2 * np.pi * (8 * y + 0.6 * np.sin(2 * np.pi * 2 * x)))


def scales(N):
    x, y = _grid(N)
    n = 8                                        # scales per row and rows per tile
    h = np.zeros_like(x)
    # each scale: a disc of radius 0.7 hanging from the top of its row; rows lower down
    # the tile lie on top (painted later), so every scale shows its rounded lower rim
    for k in (1, 0):
        j = np.floor(y * n) + k                  # the row whose scale may reach here
        off = 0.5 * (j % 2)
        cx = (np.floor(x * n - off) + 0.5 + off) / n
        d = np.hypot(_periodic_delta(x, cx) * n, (y - j / n) * n) / 0.72
        inside = (d < 1) & (y <= j / n)
        h = np.where(inside, 0.35 + 0.65 * d, h)
    return h


def checker(N):
    x, y = _grid(N)
    n = 8
    s = np.sin(2 * np.pi * n / 2 * x) * np.sin(2 * np.pi * n / 2 * y)
    return 0.5 + 0.5 * np.tanh(6 * s)


def diamond_plate(N):
    x, y = _grid(N)
    n = 6
    cx, cy = np.floor(x * n), np.floor(y * n)
    fx, fy = _frac(x * n) - 0.5, _frac(y * n) - 0.5
    flip = (cx + cy) % 2 == 1
    a = np.where(flip, fx + fy, fx - fy) / math.sqrt(2)
    b = np.where(flip, fx - fy, fx + fy) / math.sqrt(2)
    r = (a / 0.42) ** 2 + (b / 0.1) ** 2
    return np.sqrt(np.clip(1 - r, 0, 1))


def ribs(N):
    x, y = _grid(N)
    return _smooth(0.25, 0.45, _tri(12 * (x + y)))


def hammered(N):
    pts = _jittered(9, 41)
    d, _ = _cells(N, pts, k=1)
    return 1.0 - _norm(d[..., 0] ** 2)


_MAPS = {
    "knurling": (knurling, "diamond knurl, 12 pyramids across each diagonal"),
    "knurl-straight": (knurl_straight, "straight knurl: 16 ridges"),
    "hexagons": (hexagons, "raised hexagons with grooves (7 x 8 lattice)"),
    "honeycomb": (honeycomb, "hexagon walls raised, cells sunk"),
    "voronoi": (voronoi, "raised Voronoi cells with grooves (49 jittered cells)"),
    "bricks": (bricks, "running bond, 8 courses of 4 bricks"),
    "weave": (weave, "plain weave, 8 x 8 crossings"),
    "carbon-fiber": (carbon_fiber, "2 x 2 twill of rounded tows"),
    "wood": (wood, "wood grain rings, noise-distorted"),
    "leather": (leather, "leather grain: small cells with soft creases"),
    "dots": (dots, "domes on an 8 x 8 grid"),
    "studs": (studs, "flat round bosses, 6 x 6"),
    "grid": (grid, "raised grid lines, 8 x 8"),
    "noise": (noise, "fractal noise (1/f^2 spectrum)"),
    "isogrid": (isogrid, "triangular ribs (isogrid)"),
    "grip": (grip, "chevron grip ridges"),
    "bubbles": (bubbles, "overlapping domes of three sizes"),
    "crystal": (crystal, "faceted crystal cells"),
    "waves": (waves, "wavy parallel ridges"),
    "scales": (scales, "overlapping fish scales"),
    "checker": (checker, "soft checkerboard"),
    "diamond-plate": (diamond_plate, "tread plate lozenges"),
    "ribs": (ribs, "diagonal ribs"),
    "hammered": (hammered, "hammered metal dimples"),
}


def library_names() -> tuple[str, ...]:
    """Names of the library's height maps, sorted."""
    return tuple(sorted(_MAPS))


def library_descriptions() -> dict:
    """One-line description per library name."""
    return {k: _MAPS[k][1] for k in library_names()}


@functools.lru_cache(maxsize=8)
def _cached(name: str, size: int) -> np.ndarray:
    h = np.asarray(_MAPS[name][0](size), dtype=np.float64)
    h = np.clip(h, 0.0, 1.0).astype(np.float32)
    h.setflags(write=False)
    return h


def library_height_map(name: str, *, size: int = LIBRARY_SIZE) -> np.ndarray:
    """A library height map.

    Parameters
    ----------
    name : str
        One of :func:`library_names`.
    size : int, optional
        Side in pixels.

    Returns
    -------
    numpy.ndarray, (size, size) float32
        In ``[0, 1]``, periodic.

    Raises
    ------
    InputError
        On an unknown name or a size below 16.
    """
    if name not in _MAPS:
        raise InputError(f"{name!r} is not a library texture; use one of "
                         f"{', '.join(library_names())}")
    if int(size) != size or size < 16 or size > 4096:
        raise InputError(f"size must be an integer in [16, 4096], got {size!r}")
    return _cached(name, int(size)).copy()
