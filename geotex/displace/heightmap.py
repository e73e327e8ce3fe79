"""Height maps: load, filter and sample a grey image as a periodic height field.

A height map is a float32 array ``(h, w)`` in ``[0, 1]`` (white high).  It is
sampled with bilinear interpolation in *tile coordinates* ``(u, v)``: one
unit is one image tile, ``u`` to the right, ``v`` up, and the image repeats
(wraps) in both directions, so an integer jump of ``(u, v)`` never shows.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.displace.library import library_height_map, library_names
from geotex.errors import InputError

__all__ = ["load_height_map", "filtered_height_map", "sample_periodic", "MAX_IMAGE_PIXELS"]

#: Larger images are refused (decompression bombs).
MAX_IMAGE_PIXELS = 64_000_000


def load_height_map(source) -> np.ndarray:
    """Read a height map: a library name, an image file or an array.

    Parameters
    ----------
    source : str, os.PathLike or array_like, (h, w[, c])
        A name of :func:`geotex.displace.library.library_names`, an image file
        (PNG, JPEG, TIFF, ...; 8 or 16 bit; colour is turned into luminance),
        or an array (uint8, uint16 or float in ``[0, 1]``).

    Returns
    -------
    numpy.ndarray, (h, w) float32
        In ``[0, 1]``.

    Raises
    ------
    InputError
        On a missing or unreadable file, an unknown name, or an image smaller
        than 2 x 2 or larger than ``MAX_IMAGE_PIXELS``.
    """
    if isinstance(source, (str, Path)):
        p = Path(source)
        if not p.suffix and str(source) in library_names():
            return library_height_map(str(source))
        if not p.is_file():
            hint = "" if p.suffix else f"; library names: {', '.join(library_names())}"
            raise InputError(f"{source}: no such image file or library texture{hint}")
        Image.MAX_IMAGE_PIXELS = MAX_IMAGE_PIXELS
        try:
            with Image.open(p) as im:
                im.load()
                if im.mode in ("I;16", "I;16B", "I;16L", "I"):
                    a = np.asarray(im, dtype=np.float64)
                    a = a / (65535.0 if a.max() > 255 else 255.0)
                elif im.mode == "F":
                    a = np.asarray(im, dtype=np.float64)
                else:
                    a = np.asarray(im.convert("L"), dtype=np.float64) / 255.0
        except (OSError, ValueError, Image.DecompressionBombError) as exc:
            raise InputError(f"{source}: cannot read the image ({exc})") from None
    else:
        a = np.asarray(source)
        if a.ndim == 3:
            a = a[..., :3].astype(np.float64)
            if np.asarray(source).dtype == np.uint8:
                a = a / 255.0
            a = a @ np.array([0.2126, 0.7152, 0.0722])[: a.shape[-1]] if a.shape[-1] == 3 \
                else a.mean(axis=-1)
        elif a.dtype == np.uint8:
            a = a / 255.0
        elif a.dtype == np.uint16:
            a = a / 65535.0
        a = np.asarray(a, dtype=np.float64)
    if a.ndim != 2 or min(a.shape) < 2:
        raise InputError(f"height map must be an image of at least 2 x 2 pixels, got shape {a.shape}")
    if a.size > MAX_IMAGE_PIXELS:
        raise InputError(f"height map has {a.size} pixels, more than {MAX_IMAGE_PIXELS}")
    if not np.isfinite(a).all():
        raise InputError("height map has non-finite values")
    return np.ascontiguousarray(np.clip(a, 0.0, 1.0), dtype=np.float32)


def filtered_height_map(H, *, sigma_pixels: float = 0.0, invert: bool = False) -> np.ndarray:
    """Blur (periodic Gaussian) and optionally invert a height map.

    The blur is :func:`scipy.ndimage.gaussian_filter` with ``mode="wrap"``
    and its default truncation (4 standard deviations), computed here in
    numpy with the same weights, sums and roundings (equal bit for bit,
    tested): importing ``scipy.ndimage`` costs ~0.15-0.2 s, more than the
    blur of a 1000 x 1000 map.

    Parameters
    ----------
    H : array_like, (h, w) float
    sigma_pixels : float, optional
        Gaussian standard deviation in pixels (wraps around the tile).
    invert : bool, optional
        ``1 - H`` (dark high).

    Returns
    -------
    numpy.ndarray, (h, w) float32

    Raises
    ------
    InputError
        On a negative or non-finite ``sigma_pixels``.
    """
    H = np.asarray(H, dtype=np.float32)
    s = float(sigma_pixels)
    if not (math.isfinite(s) and s >= 0):
        raise InputError(f"blur must be a number >= 0, got {sigma_pixels!r}")
    if s > 0.3:
        H = _periodic_gaussian(H, min(s, 0.5 * max(H.shape)))
    return (1.0 - H) if invert else H.copy()


def _periodic_gaussian(H: np.ndarray, sigma: float) -> np.ndarray:
    """``scipy.ndimage.gaussian_filter(H, sigma, mode="wrap")`` of a float32 image.

    As scipy does it: a kernel of radius ``int(4 sigma + 0.5)``, axis 0 then
    axis 1, each pass summing in float64 ``H[i] w[0] + sum over j from the
    radius down to 1 of (H[i - j] + H[i + j]) w[j]`` (its symmetric-kernel
    loop) and rounding to float32.
    """
    r = int(4.0 * sigma + 0.5)
    x = np.arange(-r, r + 1)
    w = np.exp(-0.5 / (sigma * sigma) * x ** 2)
    w = (w / w.sum())[::-1]
    out = H
    for axis in (0, 1):
        a = np.moveaxis(out, axis, 0)
        n = a.shape[0]
        p = np.pad(a.astype(np.float64), [(r, r), (0, 0)], mode="wrap")
        acc = p[r:r + n] * w[r]
        tmp = np.empty_like(acc)
        for j in range(r, 0, -1):
            np.add(p[r - j:r - j + n], p[r + j:r + j + n], out=tmp)
            tmp *= w[r - j]
            acc += tmp
        out = np.ascontiguousarray(np.moveaxis(acc.astype(np.float32), 0, axis))
    return out


def sample_periodic(H, u, v) -> np.ndarray:
    """Bilinear samples of a height map repeated over the plane.

    Parameters
    ----------
    H : numpy.ndarray, (h, w) float32
    u, v : array_like, (q,) float
        Tile coordinates (one unit is one image; ``v`` points up the image).

    Returns
    -------
    numpy.ndarray, (q,) float64
    """
    h, w = H.shape
    x = np.asarray(u, dtype=np.float64) * w - 0.5
    y = (1.0 - np.asarray(v, dtype=np.float64)) * h - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0).astype(np.float32)
    fy = (y - y0).astype(np.float32)
    x0 = x0.astype(np.int64) % w
    y0 = y0.astype(np.int64) % h
    x1 = (x0 + 1) % w
    y1 = (y0 + 1) % h
    flat = H.ravel()
    a = flat[y0 * w + x0]
    b = flat[y0 * w + x1]
    c = flat[y1 * w + x0]
    d = flat[y1 * w + x1]
    top = a + (b - a) * fx
    bot = c + (d - c) * fx
    return (top + (bot - top) * fy).astype(np.float64)
