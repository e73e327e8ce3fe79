"""Texture patches cut from an image, with alpha masks that fall off at the border.

Lapped textures §3.1: a *texture patch* is a region of the example image
with an alpha mask that falls off near its boundary (over about 3 pixels).
Homogeneous textures use predefined shapes (a circle, an irregular
"splotch"); structured ones use a user mask image.

Texture coordinates
-------------------
A patch of ``h x w`` pixels spans ``u in [0, w / L]``, ``v in [0, h / L]``
with ``L = max(h, w)``: one texture unit is the patch's longer side, ``u``
runs to the right and ``v`` up (pixel row 0 is the top, at ``v = h / L``).
The paste *centre* is the opaque pixel farthest from any non-opaque one, so
the point a paste is centred on is always covered by it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image
from scipy.ndimage import distance_transform_edt

from geotex.errors import InputError, MissingFileError
from geotex.image.hull import star_hull
from geotex.io.images import load_texture_image

__all__ = ["TexturePatch", "MASKS", "load_image", "circle_mask", "splotch_mask",
           "mask_from_image", "texture_patches", "sample_patch", "sample_alpha"]

#: Predefined mask shapes.
MASKS = ("splotch", "circle")
#: Alpha at or above which a texel counts as opaque (covering).
OPAQUE = 0.99


@dataclass(frozen=True, eq=False)
class TexturePatch:
    """An image region with an alpha mask, ready to paste.

    Attributes
    ----------
    rgba : numpy.ndarray, (h, w, 4) float32
        Colour in ``[0, 1]`` and alpha (mask fall-off times the image's own
        alpha).
    size : numpy.ndarray, (2,) float64
        Extent ``(w / L, h / L)`` in texture units.
    center : numpy.ndarray, (2,) float64
        Texture coordinates of the paste centre (an opaque point).
    hull : numpy.ndarray, (k, 2) float64
        Conservative polygon around every pixel with alpha > 0,
        counter-clockwise, star-shaped about ``center``
        (:func:`geotex.image.hull.star_hull`).
    opaque : float
        Alpha at or above which a sample counts as covered.
    """

    rgba: np.ndarray
    size: np.ndarray
    center: np.ndarray
    hull: np.ndarray
    opaque: float = OPAQUE

    @property
    def shape(self) -> tuple[int, int]:
        """``(h, w)`` in pixels."""
        return int(self.rgba.shape[0]), int(self.rgba.shape[1])

    @property
    def pixels_per_unit(self) -> float:
        """Pixels per texture unit (the longer side ``L``)."""
        return float(max(self.shape))


def load_image(path) -> np.ndarray:
    """Read an image file as an ``(h, w, 3 or 4)`` uint8 array.

    Raises
    ------
    MissingFileError
        If the file does not exist.
    InputError
        If it is not an image pillow can read.
    """
    p = Path(path)
    if not p.is_file():
        raise MissingFileError(f"{p}: no such image file")
    try:
        return load_texture_image(p)
    except Exception as exc:  # pillow raises many types for unreadable images
        raise InputError(f"{p}: cannot read the image ({type(exc).__name__}); "
                         "give a PNG or JPEG file") from None


def _as_image(image, name: str) -> np.ndarray:
    """``(h, w, 4)`` float32 RGBA in ``[0, 1]`` from a path or an array."""
    if isinstance(image, (str, Path)):
        image = load_image(image)
    arr = np.asarray(image)
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4) or arr.shape[0] < 4 or arr.shape[1] < 4:
        raise InputError(f"{name} must be an (h, w), (h, w, 3) or (h, w, 4) image of at least "
                         f"4 x 4 pixels, got shape {arr.shape}")
    if arr.dtype == np.uint8:
        out = arr.astype(np.float32) / 255.0
    elif arr.dtype.kind == "f":
        out = arr.astype(np.float32)
        if not (np.isfinite(out).all() and out.min() >= 0.0 and out.max() <= 1.0):
            raise InputError(f"{name}: float images must hold finite values in [0, 1]")
    else:
        raise InputError(f"{name} must be uint8 or float in [0, 1], got dtype {arr.dtype}")
    if out.shape[2] == 3:
        out = np.concatenate([out, np.ones(out.shape[:2] + (1,), np.float32)], axis=2)
    return np.ascontiguousarray(out)


def _falloff(value, name: str = "falloff") -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number of pixels, got {value!r}") from None
    if not (math.isfinite(x) and x >= 0):
        raise InputError(f"{name} must be >= 0 pixels, got {value!r}")
    return x


def _shape(h, w) -> tuple[int, int]:
    try:
        hh, ww = int(h), int(w)
    except (TypeError, ValueError):
        raise InputError(f"mask size must be two integers, got {(h, w)!r}") from None
    if hh < 4 or ww < 4:
        raise InputError(f"masks need at least 4 x 4 pixels, got {hh} x {ww}")
    return hh, ww


def _edt_alpha(inside: np.ndarray, falloff: float) -> np.ndarray:
    """Alpha rising from 0 at the region border to 1 ``falloff`` pixels inside."""
    if falloff == 0:
        return inside.astype(np.float32)
    d = distance_transform_edt(inside)
    return np.clip((d - 0.5) / falloff, 0.0, 1.0).astype(np.float32) * inside


def circle_mask(h: int, w: int, *, falloff: float = 3.0, margin: float = 1.0) -> np.ndarray:
    """Alpha of the largest centred disc, falling off linearly at its rim.

    Parameters
    ----------
    h, w : int
        Mask size in pixels.
    falloff : float, optional
        Width of the fall-off band in pixels (alpha 0 at the rim, 1 inside).
    margin : float, optional
        Transparent pixels kept between the disc and the image border.

    Returns
    -------
    numpy.ndarray, (h, w) float32

    Examples
    --------
    >>> a = circle_mask(32, 32)
    >>> float(a[16, 16]), float(a[0, 0])
    (1.0, 0.0)
    """
    h, w = _shape(h, w)
    fo = _falloff(falloff)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    r = np.hypot(x + 0.5 - w / 2.0, y + 0.5 - h / 2.0)
    R = min(h, w) / 2.0 - float(margin)
    if R <= fo:
        raise InputError(f"a {h} x {w} mask is too small for a falloff of {fo:g} pixels")
    if fo == 0:
        return (r <= R).astype(np.float32)
    return np.clip((R - r) / fo, 0.0, 1.0).astype(np.float32)


def splotch_mask(h: int, w: int, *, falloff: float = 3.0, margin: float = 1.0,
                 shape_seed: int = 7) -> np.ndarray:
    """Alpha of an irregular blob ("splotch"), falling off at its border.

    The border is ``r(theta) = R (0.8 + sum_k a_k cos(k theta + phi_k))``
    (harmonics 2..5, amplitudes up to ``0.11 / k^0.5``) scaled to touch the inscribed
    circle of radius ``R``; the fixed ``shape_seed`` makes it a predefined
    shape.  The fall-off follows the Euclidean distance to the border.

    Parameters
    ----------
    h, w : int
    falloff : float, optional
        Fall-off width in pixels.
    margin : float, optional
        Transparent pixels kept at the image border.
    shape_seed : int, optional
        Another seed gives another splotch.

    Returns
    -------
    numpy.ndarray, (h, w) float32
    """
    h, w = _shape(h, w)
    fo = _falloff(falloff)
    rng = np.random.default_rng(int(shape_seed))
    k = np.arange(2, 6, dtype=np.float64)
    amp = 0.11 / np.sqrt(k) * rng.uniform(0.6, 1.0, k.size)
    phase = rng.uniform(0.0, 2.0 * np.pi, k.size)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    dx, dy = x + 0.5 - w / 2.0, y + 0.5 - h / 2.0
    theta = np.arctan2(dy, dx)
    R = min(h, w) / 2.0 - float(margin)
    if R <= 2 * fo + 2:
        raise InputError(f"a {h} x {w} mask is too small for a falloff of {fo:g} pixels")

    def profile(angle):
        return 0.8 + np.tensordot(amp, np.cos(k[:, None] * np.ravel(angle)[None, :]
                                              + phase[:, None]), axes=1).reshape(np.shape(angle))

    top = float(profile(np.linspace(0.0, 2.0 * np.pi, 1441)).max())
    rad = R * profile(theta) / top
    inside = np.hypot(dx, dy) <= rad
    return _edt_alpha(inside, fo)


def mask_from_image(mask, *, shape=None, falloff: float = 3.0) -> np.ndarray:
    """Alpha from a user mask image: pixels at or above 0.5 are inside.

    The mask's alpha channel is used when it has one that is not fully
    opaque, its luminance otherwise.  The fall-off band is ``falloff`` pixels
    wide inside the region border.

    Parameters
    ----------
    mask : str, os.PathLike or array_like
        Mask image (file or array, uint8 or float in ``[0, 1]``).
    shape : (int, int), optional
        Resize the mask to ``(h, w)`` first (bilinear).
    falloff : float, optional

    Returns
    -------
    numpy.ndarray, (h, w) float32

    Raises
    ------
    InputError
        If the mask cannot be read or is empty (no pixel at or above 0.5).
    """
    name = str(mask) if isinstance(mask, (str, Path)) else "mask"
    img = _as_image(mask, name)
    fo = _falloff(falloff)
    a = img[:, :, 3]
    grey = a if a.min() < 1.0 else img[:, :, :3] @ np.array([0.299, 0.587, 0.114], np.float32)
    if shape is not None:
        hh, ww = _shape(*shape)
        if grey.shape != (hh, ww):
            grey = np.asarray(Image.fromarray(grey.astype(np.float32), mode="F").resize(
                (ww, hh), Image.BILINEAR), dtype=np.float32)
    inside = grey >= 0.5
    if not inside.any():
        raise InputError(f"{name}: the mask is empty (no pixel at or above 0.5); "
                         "paint the patch region white (or opaque)")
    return _edt_alpha(inside, fo)


def _mask_alpha(mask, h, w, falloff, crop, image_shape):
    if isinstance(mask, str) and mask in MASKS:
        return (circle_mask if mask == "circle" else splotch_mask)(h, w, falloff=falloff)
    if isinstance(mask, str) and not Path(mask).suffix and not Path(mask).is_file():
        raise InputError(f"mask must be one of {', '.join(MASKS)} or a mask image, got {mask!r}")
    name = str(mask) if isinstance(mask, (str, Path)) else "mask"
    img = _as_image(mask, name)
    if img.shape[:2] == tuple(image_shape):
        y0, x0 = crop
        img = img[y0:y0 + h, x0:x0 + w]
    return mask_from_image(img, shape=(h, w), falloff=falloff)


def _patch(rgba: np.ndarray, alpha: np.ndarray, name: str) -> TexturePatch:
    h, w = alpha.shape
    out = rgba.copy()
    out[:, :, 3] *= alpha
    L = float(max(h, w))
    opaque = out[:, :, 3] >= OPAQUE
    if not opaque.any():
        raise InputError(f"{name}: no pixel of the patch is opaque (alpha >= {OPAQUE}) after "
                         "the mask fall-off; use a larger mask or a smaller falloff")
    depth = distance_transform_edt(opaque)
    iy, ix = np.unravel_index(int(np.argmax(depth)), depth.shape)
    center = np.array([(ix + 0.5) / L, (h - iy - 0.5) / L])
    support = out[:, :, 3] > 0
    hull = star_hull(support, center, pixels_per_unit=L)
    for arr in (out, center, hull):
        arr.setflags(write=False)
    size = np.array([w / L, h / L])
    size.setflags(write=False)
    return TexturePatch(rgba=out, size=size, center=center, hull=hull)


def texture_patches(image, *, mask="splotch", count: int = 1, size: int | None = None,
                    falloff: float = 3.0, seed=0) -> tuple[TexturePatch, ...]:
    """Cut texture patches from an image (lapped textures §3.1).

    Parameters
    ----------
    image : str, os.PathLike or array_like, (h, w[, 3 or 4])
        Example texture (uint8, or float in ``[0, 1]``); an alpha channel is
        kept and multiplies the mask.
    mask : {"splotch", "circle"} or str, os.PathLike, array_like
        A predefined shape or a mask image (white / opaque = inside).  A mask
        of the image's size is cropped with the patch; any other size is
        resized to the patch.
    count : int, optional
        Number of patches, cut at random positions when ``size`` is smaller
        than the image (the first one centred).
    size : int, optional
        Side of the square patches in pixels (default: the image's shorter
        side; the whole image when the mask is an image).
    falloff : float, optional
        Alpha fall-off width in pixels (the paper uses 3).
    seed : int or numpy.random.Generator, optional
        Positions of the patches.

    Returns
    -------
    tuple of TexturePatch

    Raises
    ------
    InputError
        On an unreadable image, an unknown mask, an empty mask, ``count < 1``
        or a size larger than the image.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.random.default_rng(0).integers(0, 255, (64, 64, 3), dtype=np.uint8)
    >>> (patch,) = texture_patches(img, mask="circle")
    >>> patch.rgba.shape, patch.hull.shape[1]
    ((64, 64, 4), 2)
    """
    name = str(image) if isinstance(image, (str, Path)) else "image"
    rgba = _as_image(image, name)
    H, W = rgba.shape[:2]
    try:
        n = int(count)
    except (TypeError, ValueError):
        raise InputError(f"count must be an integer >= 1, got {count!r}") from None
    if n < 1 or n != count:
        raise InputError(f"count must be an integer >= 1, got {count!r}")
    user_mask = not (isinstance(mask, str) and mask in MASKS)
    if size is None:
        ph, pw = (H, W) if user_mask else (min(H, W),) * 2
    else:
        try:
            s = int(size)
        except (TypeError, ValueError):
            raise InputError(f"size must be a number of pixels, got {size!r}") from None
        if s < 8 or s > min(H, W):
            raise InputError(f"size must be between 8 and the image's shorter side "
                             f"({min(H, W)} pixels), got {size!r}")
        ph = pw = s
    fo = _falloff(falloff)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    out = []
    for i in range(n):
        if i == 0:
            y0, x0 = (H - ph) // 2, (W - pw) // 2
        else:
            y0 = int(rng.integers(0, H - ph + 1))
            x0 = int(rng.integers(0, W - pw + 1))
        alpha = _mask_alpha(mask, ph, pw, fo, (y0, x0), (H, W))
        out.append(_patch(rgba[y0:y0 + ph, x0:x0 + pw], alpha, name))
    return tuple(out)


def _taps(patch: TexturePatch, uv: np.ndarray):
    h, w = patch.shape
    L = patch.pixels_per_unit
    x = uv[..., 0] * L - 0.5
    y = (h - uv[..., 1] * L) - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0).astype(np.float32)
    fy = (y - y0).astype(np.float32)
    x0 = x0.astype(np.int64)
    y0 = y0.astype(np.int64)
    taps = []
    for dy, dx, wt in ((0, 0, (1 - fy) * (1 - fx)), (0, 1, (1 - fy) * fx),
                       (1, 0, fy * (1 - fx)), (1, 1, fy * fx)):
        yy, xx = y0 + dy, x0 + dx
        ok = (xx >= 0) & (xx < w) & (yy >= 0) & (yy < h)
        taps.append((np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1), ok, wt))
    return taps


def sample_alpha(patch: TexturePatch, uv) -> np.ndarray:
    """Bilinear alpha of a patch at texture coordinates, 0 outside the image.

    Parameters
    ----------
    patch : TexturePatch
    uv : array_like, (..., 2) float64

    Returns
    -------
    numpy.ndarray, (...) float32
    """
    uv = np.asarray(uv, dtype=np.float64)
    a = patch.rgba[:, :, 3]
    out = np.zeros(uv.shape[:-1], np.float32)
    for yy, xx, ok, wt in _taps(patch, uv):
        out += wt * np.where(ok, a[yy, xx], 0.0)
    return out


def sample_patch(patch: TexturePatch, uv) -> np.ndarray:
    """Bilinear colour and alpha of a patch at texture coordinates.

    Outside the image the alpha is 0 and the colour is clamped to the border
    (texture-coordinate clamping, lapped textures §4).

    Parameters
    ----------
    patch : TexturePatch
    uv : array_like, (..., 2) float64

    Returns
    -------
    numpy.ndarray, (..., 4) float32
        Straight (not premultiplied) colour and alpha.
    """
    uv = np.asarray(uv, dtype=np.float64)
    out = np.zeros(uv.shape[:-1] + (4,), np.float32)
    for yy, xx, ok, wt in _taps(patch, uv):
        v = patch.rgba[yy, xx]
        out[..., :3] += wt[..., None] * v[..., :3]
        out[..., 3] += wt * np.where(ok, v[..., 3], 0.0)
    return out
