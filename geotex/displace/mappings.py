"""Where on the height map each refined vertex reads its height: the projections.

Every mapping turns a :class:`geotex.relief.ReliefPoints` into tile
coordinates ``(u, v)`` (:func:`geotex.displace.heightmap.sample_periodic`) or,
for the blended projections, a weighted mean of several samples.  Sizes are
in millimetres (the part's units), angles in degrees:

* ``scale_u``, ``scale_v``: millimetres per image tile;
* ``offset_u``, ``offset_v``: shift of the image in millimetres;
* ``rotation``: the image turned by this many degrees in its plane.

``triplanar`` blends the three axis projections with weights ``|n_i| **
sharpness``; ``cubic`` uses the dominant axis only and blends across the
cube seams within ``blend`` (difference of the normal's two largest
components); both read each side from outside (not mirrored).
``cylindrical`` wraps around an axis with a whole number of tiles around
(``scale_u`` is rounded to the nearest such size, so the wrap has no seam;
a ``rotation`` other than 0 turns the tiles off the wrap direction and a
seam can show there)
and projects the caps (normals within ``cap_angle`` of the axis) flat,
blending over 10 degrees; ``spherical`` wraps longitude the same way and
reads latitude as arc length (the poles pinch, as in every spherical map).
``planar-xy|xz|yz`` project along one axis.  ``uv`` reads the mesh's own
texture coordinates (``scale_*``/``offset_*`` are then in UV units, default
one tile per UV unit).  ``pgp`` and ``lapped`` read coordinates made by
:mod:`geotex.displace.seamless`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from geotex.displace.choices import MAPPINGS
from geotex.displace.heightmap import sample_periodic
from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled, helper
from geotex.options import finite_number, positive_number

__all__ = ["MAPPINGS", "MappingOptions", "mapping_options", "projected_heights"]

#: Default millimetres per tile for the projections.
DEFAULT_SCALE_MM = 20.0
#: Cap blending band of the cylindrical mapping, degrees.
CAP_BAND = 10.0
AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class MappingOptions:
    """How the height map is laid on the surface (see the module docstring).

    Attributes
    ----------
    name : str
        One of ``MAPPINGS``.
    scale_u, scale_v : float
        Millimetres (UV units for ``uv``) per image tile.
    offset_u, offset_v : float
    rotation : float
        Degrees.
    sharpness : float
        Triplanar blend exponent (higher: narrower blends).
    blend : float
        Cubic seam blend width (0 to 1).
    axis : str
        ``"x"``, ``"y"`` or ``"z"``: axis of the cylindrical and spherical maps.
    cap_angle : float
        Cylindrical caps: normals within this many degrees of the axis.
    """

    name: str = "triplanar"
    scale_u: float = DEFAULT_SCALE_MM
    scale_v: float = DEFAULT_SCALE_MM
    offset_u: float = 0.0
    offset_v: float = 0.0
    rotation: float = 0.0
    sharpness: float = 4.0
    blend: float = 0.15
    axis: str = "z"
    cap_angle: float = 20.0


def mapping_options(name: str = "triplanar", *, scale_u=None, scale_v=None, offset_u=0.0,
                    offset_v=0.0, rotation=0.0, sharpness=4.0, blend=0.15, axis="z",
                    cap_angle=20.0) -> MappingOptions:
    """Validated :class:`MappingOptions` (``scale_v`` defaults to ``scale_u``).

    Raises
    ------
    InputError
        Unknown mapping or axis, non-positive scale, sharpness or angle out of range.
    """
    if name not in MAPPINGS:
        raise InputError(f"mapping must be one of {', '.join(MAPPINGS)}, got {name!r}")
    if axis not in AXES:
        raise InputError(f"axis must be x, y or z, got {axis!r}")
    default = 1.0 if name == "uv" else DEFAULT_SCALE_MM
    su = default if scale_u is None else positive_number(scale_u, name="scale_u")
    sv = su if scale_v is None else positive_number(scale_v, name="scale_v")
    sharp = positive_number(sharpness, name="sharpness")
    b = finite_number(blend, name="blend")
    if not (0.0 <= b <= 1.0):
        raise InputError(f"blend must be in [0, 1], got {blend!r}")
    cap = finite_number(cap_angle, name="cap_angle")
    if not (0.0 <= cap <= 80.0):
        raise InputError(f"cap_angle must be in [0, 80] degrees, got {cap_angle!r}")
    return MappingOptions(name, su, sv, finite_number(offset_u, name="offset_u"),
                          finite_number(offset_v, name="offset_v"),
                          finite_number(rotation, name="rotation"), sharp, b, axis, cap)


def _tiles(a, b, opt: MappingOptions, su=None):
    """Plane coordinates (mm) -> tile coordinates: rotate, offset, scale."""
    r = math.radians(opt.rotation)
    c, s = math.cos(r), math.sin(r)
    x = c * a + s * b + opt.offset_u
    y = -s * a + c * b + opt.offset_v
    return x / (opt.scale_u if su is None else su), y / opt.scale_v


def _axis_frame(k: int):
    """Two in-plane axes (i, j) read from outside the +k side, right-handed."""
    return {0: (1, 2), 1: (2, 0), 2: (0, 1)}[k]


def _side_sample(H, P, N, k, opt):
    """Sample the projection along axis k, mirrored on the negative side."""
    i, j = _axis_frame(k)
    sgn = np.where(N[:, k] >= 0, 1.0, -1.0)
    return sample_periodic(H, *_tiles(sgn * P[:, i], P[:, j], opt))


def _triplanar(H, P, N, opt, lo):
    W = np.abs(N) ** opt.sharpness
    W /= np.maximum(W.sum(axis=1, keepdims=True), 1e-300)
    if P.shape[0] >= JIT_MIN_SIZE:
        return _blended(H, P, lo, N, W, opt, 1e-4, True)
    P = P - lo
    h = np.zeros(P.shape[0])
    for k in range(3):
        sel = W[:, k] > 1e-4
        if sel.any():
            h[sel] += W[sel, k] * _side_sample(H, P[sel], N[sel], k, opt)
    ws = np.zeros(P.shape[0])
    for k in range(3):
        ws += np.where(W[:, k] > 1e-4, W[:, k], 0.0)
    return h / np.maximum(ws, 1e-300)


def _cubic(H, P, N, opt, lo):
    A = np.abs(N)
    top = A.max(axis=1, keepdims=True)
    b = max(opt.blend, 1e-6)
    W = np.clip((A - (top - b)) / b, 0.0, 1.0)
    W = W * W * (3 - 2 * W)
    W /= np.maximum(W.sum(axis=1, keepdims=True), 1e-300)
    if P.shape[0] >= JIT_MIN_SIZE:
        return _blended(H, P, lo, N, W, opt, 0.0, False)
    P = P - lo
    h = np.zeros(P.shape[0])
    for k in range(3):
        sel = W[:, k] > 0
        if sel.any():
            h[sel] += W[sel, k] * _side_sample(H, P[sel], N[sel], k, opt)
    return h


def _blended(H, P, lo, N, W, opt, floor, divide):
    """The numpy paths of :func:`_triplanar` and :func:`_cubic` as one compiled
    loop (the same operations in the same order: bit for bit), without the
    masked copies and the per-side temporaries."""
    r = math.radians(opt.rotation)
    out = np.empty(P.shape[0])
    _blended_loop(np.ascontiguousarray(H, dtype=np.float32), P, np.asarray(lo, np.float64), N,
                  W, math.cos(r), math.sin(r), float(opt.offset_u), float(opt.offset_v),
                  float(opt.scale_u), float(opt.scale_v), float(floor), bool(divide), out)
    return out


@helper
def _periodic_sample(H, u, v):
    """:func:`geotex.displace.heightmap.sample_periodic` at one point (the same
    operations, float32 interpolation included)."""
    hh = H.shape[0]
    ww = H.shape[1]
    x = u * ww - 0.5
    y = (1.0 - v) * hh - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = np.float32(x - x0)
    fy = np.float32(y - y0)
    ix = np.int64(x0)
    iy = np.int64(y0)
    if ix < 0 or ix >= ww:            # the same integers as %, without a division
        ix %= ww
    if iy < 0 or iy >= hh:
        iy %= hh
    ix1 = ix + 1 if ix + 1 < ww else 0
    iy1 = iy + 1 if iy + 1 < hh else 0
    a = H[iy, ix]
    b = H[iy, ix1]
    c = H[iy1, ix]
    d = H[iy1, ix1]
    top = a + (b - a) * fx
    bot = c + (d - c) * fx
    return np.float64(top + (bot - top) * fy)


@compiled
def _blended_loop(H, P, lo, N, W, c, s, off_u, off_v, su, sv, floor, divide, out):
    for q in range(P.shape[0]):
        h = 0.0
        ws = 0.0
        for k in range(3):
            w = W[q, k]
            if w > floor:
                # _axis_frame(k), the side read from outside (_side_sample), _tiles
                i = (k + 1) % 3
                j = (k + 2) % 3
                sg = 1.0 if N[q, k] >= 0 else -1.0
                a = sg * (P[q, i] - lo[i])
                b = P[q, j] - lo[j]
                x = c * a + s * b + off_u
                y = -s * a + c * b + off_v
                h += w * _periodic_sample(H, x / su, y / sv)
                ws += w
        if divide:                    # np.maximum(ws, 1e-300), NaN kept
            out[q] = h / (ws if (ws >= 1e-300 or ws != ws) else 1e-300)
        else:
            out[q] = h


def _whole_tiles(length: float, scale: float) -> float:
    """Tile size closest to ``scale`` that repeats a whole number of times in ``length``."""
    k = max(1, round(length / scale))
    return length / k


def _cylindrical(H, P, N, opt, center, radius):
    k = AXES[opt.axis]
    i, j = _axis_frame(k)
    X = P - center
    theta = np.arctan2(X[:, j], X[:, i])
    su = _whole_tiles(2 * math.pi * radius, opt.scale_u)
    h_side = sample_periodic(H, *_tiles(theta * radius, X[:, k], opt, su=su))
    t = np.abs(N[:, k])
    c0 = math.cos(math.radians(opt.cap_angle))
    c1 = math.cos(math.radians(min(opt.cap_angle + CAP_BAND, 90.0)))
    wc = np.clip((t - c1) / max(c0 - c1, 1e-9), 0.0, 1.0)
    wc = wc * wc * (3 - 2 * wc)
    h = h_side
    sel = wc > 0
    if sel.any():
        sgn = np.where(N[sel, k] >= 0, 1.0, -1.0)
        h_cap = sample_periodic(H, *_tiles(sgn * X[sel, i], X[sel, j], opt))
        h = h.copy()
        h[sel] = (1 - wc[sel]) * h_side[sel] + wc[sel] * h_cap
    return h


def _spherical(H, P, opt, center, radius):
    k = AXES[opt.axis]
    i, j = _axis_frame(k)
    X = P - center
    r = np.maximum(np.linalg.norm(X, axis=1), 1e-300)
    lon = np.arctan2(X[:, j], X[:, i])
    lat = np.arcsin(np.clip(X[:, k] / r, -1.0, 1.0))
    su = _whole_tiles(2 * math.pi * radius, opt.scale_u)
    return sample_periodic(H, *_tiles(lon * radius, lat * radius, opt, su=su))


def projected_heights(points, H, opt: MappingOptions, *, uv=None) -> np.ndarray:
    """Height in ``[0, 1]`` of every refined vertex under a projection mapping.

    Parameters
    ----------
    points : geotex.relief.ReliefPoints
    H : numpy.ndarray, (h, w) float32
        The (filtered) height map.
    opt : MappingOptions
        Any mapping but ``pgp`` and ``lapped``.
    uv : numpy.ndarray, (q, 3, 2) float64, optional
        Per base corner texture coordinates (``uv`` mapping only).

    Returns
    -------
    numpy.ndarray, (p,) float64

    Raises
    ------
    InputError
        ``uv`` without coordinates, or a mapping this function does not do.
    """
    P, N = points.positions, points.normals
    Vb = points.base_vertices
    lo, hi = Vb.min(axis=0), Vb.max(axis=0)
    center = 0.5 * (lo + hi)
    name = opt.name
    if name == "triplanar":
        return _triplanar(H, P, N, opt, lo)
    if name == "cubic":
        return _cubic(H, P, N, opt, lo)
    if name.startswith("planar-"):
        a, b = AXES[name[-2]], AXES[name[-1]]
        return sample_periodic(H, *_tiles(P[:, a] - lo[a], P[:, b] - lo[b], opt))
    if name in ("cylindrical", "spherical"):
        k = AXES[opt.axis]
        X = Vb - center
        if name == "cylindrical":
            rad = float(np.linalg.norm(np.delete(X, k, axis=1), axis=1).max())
            return _cylindrical(H, P, N, opt, center, max(rad, 1e-12))
        rad = float(np.linalg.norm(X, axis=1).max())
        return _spherical(H, P, opt, center, max(rad, 1e-12))
    if name == "uv":
        if uv is None:
            raise InputError("the uv mapping needs a mesh with texture coordinates "
                             "(an OBJ with vt, or a GLB with TEXCOORD_0)")
        T = np.einsum("pj,pjx->px", points.bary, uv[points.face])
        return sample_periodic(H, *_tiles(T[:, 0], T[:, 1], opt))
    raise InputError(f"projected_heights does not do the {name!r} mapping")
