"""Transparent holes in an example image, filled from the image itself.

A texture photo with an alpha channel (a cut-out, a masked defect) cannot be
wrapped into a periodic tile or pasted through a parameterization as it is:
the transparent texels would show as holes (or as whatever colour they
store). :func:`transparent_filled` fills the transparent texels block by
block with copies of opaque parts of the same image, chosen by how well they
match the texels already known around each block.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_dilation, distance_transform_edt

from geotex.errors import InputError

__all__ = ["transparent_filled", "RIM"]

#: Texels around a transparent region that are filled with it (their colours
#: are blended with what was cut away).
RIM = 3


def _correlation(image: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``sum_k kernel[k] * image[p + k]`` for every placement ``p`` inside the image."""
    # lazy: scipy.signal takes ~0.7 s to import, and only images with holes need it
    from scipy.signal import fftconvolve

    return fftconvolve(image, kernel[::-1, ::-1], mode="valid")


def transparent_filled(colors, alpha, *, block: int | None = None,
                       ring: int | None = None) -> np.ndarray:
    """Fill the transparent texels of an image from its best-matching opaque parts.

    The holes are filled block by block from their border inwards (image
    quilting's idea, Efros and Freeman 2001, without its minimum-error cut):
    each step takes the first hole texel on a hole's border (row by row), the
    ``block`` square around it and a ``ring`` of texels around that, and copies
    the hole texels of the square from the placement of that window over fully
    opaque texels of the original whose colours best match the window's known
    texels (sum of squared differences, every placement at once by FFT
    correlation).  A regular pattern (bricks, tiles) continues across the hole.
    When no opaque placement exists (the image is mostly transparent), the
    rest takes the nearest known texel's colour.

    Parameters
    ----------
    colors : array_like, (h, w, c) float
        Colours (any range).
    alpha : array_like, (h, w) float in [0, 1]
        Opacity; texels below 0.5 are holes, and so are the texels within
        :data:`RIM` texels of one.
    block : int, optional
        Side of the square filled per step; default ``max(4, min(h, w) // 12)``.
    ring : int, optional
        Width of the known band matched around it; default ``max(2, block // 3)``.

    Returns
    -------
    numpy.ndarray, (h, w, c) float64
        A copy of ``colors`` with every hole texel replaced.

    Raises
    ------
    InputError
        If the shapes disagree or every texel is transparent.
    """
    rgb = np.array(colors, dtype=np.float64)
    a = np.asarray(alpha, dtype=np.float64)
    if rgb.ndim != 3 or a.shape != rgb.shape[:2]:
        raise InputError(f"alpha of shape {a.shape} does not match an image of shape {rgb.shape}")
    hole = a < 0.5
    if not hole.any():
        return rgb
    # the rim of a cut-out holds colours blended with what was cut away (in
    # the shared bricks image: 3 texels, opaque but greyish): fill it too
    hole = binary_dilation(hole, iterations=RIM)
    if hole.all():
        raise InputError("the image is transparent everywhere: nothing to texture with")
    h, w = hole.shape
    b = max(4, min(h, w) // 12) if block is None else int(block)
    r = max(2, b // 3) if ring is None else int(ring)
    side = b + 2 * r
    if side < min(h, w):
        # every placement of a side x side window over opaque texels only
        clear = _correlation(hole.astype(np.float64), np.ones((side, side))) < 0.5
        sources = (clear.any(), clear)
    else:
        sources = (False, None)
    squares = [rgb[:, :, c] ** 2 for c in range(rgb.shape[2])]
    while sources[0] and hole.any():
        border = hole & binary_dilation(~hole)
        y, x = np.unravel_index(int(np.argmax(border)), border.shape)   # first in row order
        # the window: the block around (y, x) and its ring, shifted to lie inside
        y0 = min(max(y - b // 2 - r, 0), h - side)
        x0 = min(max(x - b // 2 - r, 0), w - side)
        win = (slice(y0, y0 + side), slice(x0, x0 + side))
        known = ~hole[win]
        T = rgb[win]
        ssd = np.zeros(sources[1].shape)
        for c in range(rgb.shape[2]):
            ssd += _correlation(squares[c], known.astype(np.float64)) \
                - 2.0 * _correlation(rgb[:, :, c], np.where(known, T[:, :, c], 0.0))
        score = np.where(sources[1], ssd, np.inf)
        sy, sx = np.unravel_index(int(np.argmin(score)), score.shape)
        fill = np.zeros((side, side), dtype=bool)
        fill[r:r + b, r:r + b] = True
        fill &= hole[win]
        if not fill.any():                  # the border texel lies in the ring only
            fill = hole[win].copy()
        source = rgb[sy:sy + side, sx:sx + side]
        rgb[win][fill] = source[fill]
        for c in range(rgb.shape[2]):
            squares[c][win][fill] = source[fill, c] ** 2
        hole[win][fill] = False
    if hole.any():                                    # no opaque placement at all
        _, (iy, ix) = distance_transform_edt(hole, return_indices=True)
        rgb[hole] = rgb[iy[hole], ix[hole]]
    return rgb
