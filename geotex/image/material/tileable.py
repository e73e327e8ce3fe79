"""Tileable inputs: a periodic tile and its binary feature mask from any image.

Material-space textures §1 starts from two *tiles* ``T_0`` and ``T_M``
(periodic in ``s`` and ``t``), made from the input images with the graph-cut
method of Kwatra et al. 2003.  Here:

0. transparent texels (an alpha channel below half) are filled from opaque
   parts of the image (:mod:`geotex.image.holes`);
1. the image is cropped to its central square and resized (Lanczos) to
   ``size + overlap`` texels on a side;
2. **horizontal wrap**: the first ``overlap`` columns ``A`` and the last
   ``overlap`` columns ``B`` cover the same columns of the periodic tile once
   it is ``size`` wide.  A minimum cut through that strip chooses, per texel,
   ``A`` or ``B``: the strip's left column is tied to ``B`` (it continues the
   tile's right edge, where ``B`` came from), its right column to ``A``; the
   capacity between neighbouring texels ``p, q`` is Kwatra's
   ``|A(p) - B(p)| + |A(q) - B(q)|``.  The cut is
   :func:`scipy.sparse.csgraph.maximum_flow` (Dinic) on integer capacities,
   the side of each texel the residual graph's reachability from the source;
3. **vertical wrap**: the same on rows of the horizontally periodic result;
   the strip's neighbours wrap around left-right.

Each pass mixes two copies that are both periodic along the other axis, so
the result is periodic to the texel by construction (whatever the cut), and
the cut only decides where the seam hides.  Everything is deterministic.

The feature mask (texton mask of Zhang et al. 2003, painted or computed in
the paper) is either a user mask image put through the *same* crop, resize
and cut, or the luminance thresholded (Otsu's threshold by default, a user
threshold otherwise); the feature is the smaller of the two classes unless
asked otherwise, and one 3x3 periodic median filter removes speckle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image
import scipy.sparse as sp
from scipy.ndimage import median_filter
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from geotex.errors import InputError
from geotex.image.holes import transparent_filled
from geotex.io.limits import MAX_TEXTURE_PIXELS

__all__ = ["TileableImage", "tileable_image", "feature_mask", "otsu_threshold",
           "luminance_of"]

#: integer capacity of one unit of colour difference (colours in [0, 1])
_CAPACITY_SCALE = 1000.0
#: terminal links: larger than any cut through the strip
_INFINITE = 2 ** 30


@dataclass(frozen=True, eq=False)
class TileableImage:
    """A periodic tile made from an image, with its feature mask.

    Attributes
    ----------
    colors : numpy.ndarray, (size, size, 3) float32
        RGB in ``[0, 1]``; row 0 is the top.  ``colors`` wraps seamlessly in
        both directions.
    mask : numpy.ndarray, (size, size) bool
        The feature mask (True on features), periodic like ``colors``.
    seam_cost : tuple of float
        Mean colour difference along the horizontal and vertical cuts.
    threshold : float or None
        The luminance threshold used for the mask, ``None`` for a mask image.
    """

    colors: np.ndarray
    mask: np.ndarray
    seam_cost: tuple
    threshold: float | None


def luminance_of(colors: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of ``(..., 3)`` RGB in ``[0, 1]``."""
    return colors[..., 0] * 0.2126 + colors[..., 1] * 0.7152 + colors[..., 2] * 0.0722


def otsu_threshold(values: np.ndarray, *, bins: int = 256) -> float:
    """Otsu's threshold of values in ``[0, 1]`` (the split of largest between-class variance)."""
    hist, edges = np.histogram(np.clip(values, 0.0, 1.0), bins=bins, range=(0.0, 1.0))
    p = hist.astype(np.float64) / max(hist.sum(), 1)
    centers = 0.5 * (edges[1:] + edges[:-1])
    w0 = np.cumsum(p)
    mu = np.cumsum(p * centers)
    w1 = 1.0 - w0
    with np.errstate(divide="ignore", invalid="ignore"):
        between = (mu[-1] * w0 - mu) ** 2 / (w0 * w1)
    between[~np.isfinite(between)] = -1.0
    k = int(np.argmax(between))
    return float(edges[k + 1])


def feature_mask(colors, *, threshold: float | None = None, feature: str = "minority"
                 ) -> tuple[np.ndarray, float]:
    """Binary feature mask of a periodic tile by a luminance threshold.

    Parameters
    ----------
    colors : array_like, (h, w, 3) float
        RGB in ``[0, 1]``.
    threshold : float, optional
        Luminance threshold in ``[0, 1]``; default Otsu's threshold.
    feature : {"minority", "dark", "bright"}, optional
        Which side of the threshold is the feature: the class with fewer
        texels (default), the texels below it, or the texels above it.

    Returns
    -------
    mask : numpy.ndarray, (h, w) bool
        After a 3x3 periodic median filter.
    threshold : float

    Raises
    ------
    InputError
        On a threshold outside ``[0, 1]``, an unknown ``feature``, or a mask
        that comes out empty or full.
    """
    C = np.asarray(colors, dtype=np.float64)
    lum = luminance_of(C)
    if threshold is None:
        thr = otsu_threshold(lum)
    else:
        thr = float(threshold)
        if not 0.0 <= thr <= 1.0:
            raise InputError(f"threshold {threshold!r} must lie in [0, 1]")
    bright = lum > thr
    if feature == "minority":
        mask = bright if bright.sum() <= bright.size / 2 else ~bright
    elif feature == "bright":
        mask = bright
    elif feature == "dark":
        mask = ~bright
    else:
        raise InputError(f"feature must be 'minority', 'dark' or 'bright', got {feature!r}")
    mask = median_filter(mask.astype(np.uint8), size=3, mode="wrap").astype(bool)
    if not mask.any() or mask.all():
        raise InputError(f"the feature mask at luminance threshold {thr:.3g} is "
                         f"{'empty' if not mask.any() else 'full'}; give another threshold "
                         "or a mask image")
    return mask, thr


def _square_resized(img: np.ndarray, side: int, *, nearest: bool = False) -> np.ndarray:
    """Central square crop resized to ``side`` (float32, channels kept)."""
    h, w = img.shape[:2]
    k = min(h, w)
    y0, x0 = (h - k) // 2, (w - k) // 2
    crop = np.ascontiguousarray(img[y0:y0 + k, x0:x0 + k])
    out = []
    for c in range(crop.shape[2]):
        ch = Image.fromarray(crop[:, :, c].astype(np.float32), mode="F")
        ch = ch.resize((side, side), Image.NEAREST if nearest else Image.LANCZOS)
        out.append(np.asarray(ch, dtype=np.float32))
    return np.clip(np.stack(out, axis=2), 0.0, 1.0)


def _cut_labels(A: np.ndarray, B: np.ndarray, *, wrap_rows: bool) -> tuple[np.ndarray, float]:
    """Min cut through an overlap strip: True where the texel takes ``A``.

    ``A``, ``B``: (h, o, c) strips; column 0 is tied to ``B``, column o-1 to
    ``A``.  With ``wrap_rows`` the strip's rows wrap (row h-1 touches row 0).
    """
    h, o = A.shape[:2]
    d = np.abs(A - B).sum(axis=2)                                 # (h, o)
    idx = np.arange(h * o).reshape(h, o)
    rows, cols, caps = [], [], []

    def link(p, q, cost):
        c = np.rint(cost * _CAPACITY_SCALE).astype(np.int64) + 1
        rows.extend([p.ravel(), q.ravel()])
        cols.extend([q.ravel(), p.ravel()])
        caps.extend([c.ravel(), c.ravel()])

    link(idx[:, :-1], idx[:, 1:], d[:, :-1] + d[:, 1:])
    if wrap_rows:
        link(idx, np.roll(idx, -1, axis=0), d + np.roll(d, -1, axis=0))
    else:
        link(idx[:-1], idx[1:], d[:-1] + d[1:])
    src, snk = h * o, h * o + 1
    rows += [np.full(h, src), idx[:, -1], idx[:, 0], np.full(h, snk)]
    cols += [idx[:, -1], np.full(h, src), np.full(h, snk), idx[:, 0]]
    caps += [np.full(h, _INFINITE), np.zeros(h, np.int64), np.full(h, _INFINITE),
             np.zeros(h, np.int64)]
    r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(caps)
    G = sp.csr_matrix((w.astype(np.int32), (r, c)), shape=(h * o + 2, h * o + 2))
    G.sum_duplicates()
    flow = maximum_flow(G, src, snk).flow
    residual = (G - flow).tocsr()
    residual.data[residual.data <= 0] = 0
    residual.eliminate_zeros()
    reach = breadth_first_order(residual, src, directed=True, return_predecessors=False)
    take_a = np.zeros(h * o + 2, dtype=bool)
    take_a[reach] = True
    labels = take_a[:h * o].reshape(h, o)
    # seam cost: mean colour difference (per channel) where neighbours took different sides
    seam = labels[:, :-1] != labels[:, 1:]
    return labels, float((seam * d[:, :-1]).sum() / max(int(seam.sum()), 1) / A.shape[2])


def _wrap_columns(img: np.ndarray, size: int, extra: list[np.ndarray], *, wrap_rows: bool):
    """Make ``img`` (h, size + o, c) periodic along columns; apply the same cut to ``extra``."""
    o = img.shape[1] - size
    A, B = img[:, :o], img[:, size:]
    labels, cost = _cut_labels(A, B, wrap_rows=wrap_rows)
    out = []
    for arr in [img] + extra:
        res = arr[:, :size].copy()
        res[:, :o] = np.where(labels[:, :, None], arr[:, :o], arr[:, size:])
        out.append(res)
    return out, cost


def tileable_image(image, *, size: int = 128, overlap: int | None = None, mask=None,
                   threshold: float | None = None, feature: str = "minority"
                   ) -> TileableImage:
    """Make a periodic tile and its feature mask from an image (graph-cut wrap).

    See the module docstring for the method.

    Parameters
    ----------
    image : array_like, (h, w, 3 or 4) uint8 or float in [0, 1]
        Any image; its central square is used. Transparent texels (alpha
        below half) and their rim are filled first from opaque parts of the
        image (:func:`geotex.image.holes.transparent_filled`).
    size : int, optional
        Side of the tile in texels: at least 8, and ``size**2`` at most
        :data:`geotex.io.limits.MAX_TEXTURE_PIXELS`.
    overlap : int, optional
        Width of the strips the cuts run through; default ``size // 4``.
    mask : array_like, (h, w) or (h, w, c), optional
        A feature mask image of the same size as ``image`` (non-zero / above
        half of its range = feature); cropped, resized and cut like the image.
        Default: :func:`feature_mask` of the tile.
    threshold, feature : optional
        Passed to :func:`feature_mask` when no mask image is given.

    Returns
    -------
    TileableImage

    Raises
    ------
    InputError
        On images that are not (h, w, 3 or 4), smaller than 8 texels, a mask
        of another size, a ``size`` out of range, or bad options.
    """
    img = np.asarray(image)
    if img.ndim != 3 or img.shape[2] not in (3, 4) or min(img.shape[:2]) < 8:
        raise InputError(f"image must be an (h, w, 3 or 4) array of at least 8 x 8 texels, "
                         f"got shape {img.shape}")
    if isinstance(size, bool) or int(size) != size or int(size) < 8:
        raise InputError(f"size must be an integer >= 8, got {size!r}")
    size = int(size)
    if size * size > MAX_TEXTURE_PIXELS:        # no tile geotex would not read back
        raise InputError(f"size {size} is too large: the tile would have more than the "
                         f"{MAX_TEXTURE_PIXELS} texels a texture may have; give a smaller size")
    o = max(size // 4, 2) if overlap is None else int(overlap)
    if not 2 <= o <= size:
        raise InputError(f"overlap must lie in [2, size], got {overlap!r}")
    rgb = img[:, :, :3].astype(np.float32)
    if img.dtype == np.uint8:
        rgb = rgb / 255.0
    if not np.isfinite(rgb).all():
        raise InputError("image has non-finite values")
    if img.shape[2] == 4:
        alpha = img[:, :, 3].astype(np.float64) / (255.0 if img.dtype == np.uint8 else 1.0)
        rgb = transparent_filled(rgb, alpha).astype(np.float32)
    big = _square_resized(np.clip(rgb, 0.0, 1.0), size + o)
    extra = []
    if mask is not None:
        mk = np.asarray(mask)
        if mk.ndim == 3:
            mk = mk[:, :, :3].mean(axis=2) if mk.shape[2] >= 3 else mk[:, :, 0]
        if mk.shape != img.shape[:2]:
            raise InputError(f"the mask image is {mk.shape[1]} x {mk.shape[0]} texels but the "
                             f"image is {img.shape[1]} x {img.shape[0]}; give a mask of the "
                             "same size")
        mk = mk.astype(np.float32)
        hi = float(mk.max()) if mk.size else 0.0
        binary = (mk > 0.5 * hi).astype(np.float32) if hi > 0 else mk * 0
        extra.append(_square_resized(binary[:, :, None], size + o, nearest=True))
    (wide, *rest), cost_h = _wrap_columns(big, size, extra, wrap_rows=False)
    # vertical: transpose so rows become columns; the strip wraps along the other axis
    tr = [np.ascontiguousarray(a.transpose(1, 0, 2)) for a in [wide] + rest]
    (tile, *rest), cost_v = _wrap_columns(tr[0], size, tr[1:], wrap_rows=True)
    tile = np.ascontiguousarray(tile.transpose(1, 0, 2), dtype=np.float32)
    if rest:
        mask_out = np.ascontiguousarray(rest[0].transpose(1, 0, 2)[:, :, 0] > 0.5)
        if not mask_out.any() or mask_out.all():
            raise InputError("the mask image is empty or full over the tile; paint the "
                             "features white on black")
        thr = None
    else:
        mask_out, thr = feature_mask(tile, threshold=threshold, feature=feature)
    return TileableImage(colors=tile, mask=mask_out, seam_cost=(cost_h, cost_v), threshold=thr)
