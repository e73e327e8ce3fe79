"""Texture patch fitting by FFT correlation (hierarchical pattern mapping §4.2).

For a mask ``I`` (colours of the already textured neighbours' bands, drawn in
the frame of the cluster to texture) with support ``J``, the squared error
of placing the mask at every translation ``x0`` of the sample ``T`` is

    E(x0) = sum I^2 - 2 (I * T)(x0) + (J * T^2)(x0),

with ``(f * g)(x0) = sum_x f(x) g(x + x0)``, computed for all translations at
once with real FFTs (``F^-1(conj(F(f)) F(g))``).  The spectra of ``T`` and
``T^2`` are precomputed for every orientation (rotated copies of the sample),
so a fit costs the forward transforms of ``I`` and ``J`` (one call, the row
transforms over the rows of the support only: a band is a fraction of the
sample) and one inverse transform per orientation.  Channels are summed in the
Fourier domain before the inverse transform.

The sample is **not** assumed toroidal: a translation is admissible only
when the whole footprint of the patch (the cluster and its mask) falls on
pixels of the rotated sample that come from inside the image.  The inside
of a rotated image is a rotated rectangle, so the admissible translations
are cut out by four half-planes, offset by the footprint's extent along the
rectangle's axes (no extra transform needed).

Colour space.  The paper matches in HSV.  Hue is an angle (red sits at both
ends of its range) and is undefined for grey pixels, so squared differences
of HSV triples jump for nearly equal colours.  We use an opponent space
instead: luminance ``Y = 0.299 R + 0.587 G + 0.114 B`` with weight 1 and
the two chroma differences ``(R - G) / 2`` and ``(R + G) / 2 - B`` with
weight 0.5.  Like HSV it separates brightness from colour and lets the
structure of the pattern (mostly carried by luminance, to which the eye is
most sensitive) dominate the error, but it is linear in RGB, so the error
is a plain weighted squared distance, continuous for every colour and exact
for grey images (the chroma channels vanish).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from scipy import ndimage as ndi
from scipy.ndimage import map_coordinates

from geotex.errors import InputError
from geotex.jit import compiled

__all__ = ["opponent_colors", "TextureSpectra", "texture_spectra", "match_energy",
           "brute_force_energy", "PatternScale", "pattern_scale",
           "quarter_turn_symmetry"]

#: An autocorrelation peak counts as a repeat of the pattern when it and the value at twice
#: its lag both reach this (see :func:`pattern_scale`).
PERIOD_PEAK = 0.15
#: A second repeat found beyond a quarter of the image must exceed the correlation on a ring
#: a quarter period around it by this much (a peak of the lattice, not a point of a ridge).
LONG_REPEAT_MARGIN = 0.05

_WEIGHTS = np.array([[0.299, 0.587, 0.114],
                     [0.25, -0.25, 0.0],
                     [0.25, 0.25, -0.5]])


def opponent_colors(rgb) -> np.ndarray:
    """Weighted opponent colour channels of an RGB image (see the module docstring).

    Parameters
    ----------
    rgb : array_like, (..., 3) float
        Values in ``[0, 1]``.

    Returns
    -------
    numpy.ndarray, (..., 3) float64
    """
    return np.asarray(rgb, dtype=np.float64) @ _WEIGHTS.T


@dataclass(frozen=True, eq=False)
class TextureSpectra:
    """Rotated copies of a sample and the spectra needed by :func:`match_energy`.

    Attributes
    ----------
    image : numpy.ndarray, (h, w, c) float64
        The sample (matching resolution, matching colour space).
    angles : numpy.ndarray, (k,) float64
        Orientation of every copy (radians): copy ``k`` at pixel ``p`` shows
        the sample at ``center + R(-angles[k]) (p - center)``.
    rotated : numpy.ndarray, (k, h, w, c) float64
    valid : numpy.ndarray, (k, h, w) bool
        Pixels of each copy that come from inside the sample.
    spec_t : numpy.ndarray, (k, c, h, w // 2 + 1) complex64
    spec_t2 : numpy.ndarray, (k, h, w // 2 + 1) complex64
        Spectrum of ``sum_c T_c^2``.
    variance : float
        Sum over channels of the sample's variance (``2 * variance`` is the
        mean squared difference of two random pixels).
    """

    image: np.ndarray
    angles: np.ndarray
    rotated: np.ndarray
    valid: np.ndarray
    spec_t: np.ndarray
    spec_t2: np.ndarray
    variance: float

    @property
    def center(self) -> np.ndarray:
        """Rotation centre ``(x, y)`` in pixels."""
        h, w = self.image.shape[:2]
        return np.array([w / 2.0, h / 2.0])


def rotate_image(image: np.ndarray, angle: float) -> tuple[np.ndarray, np.ndarray]:
    """Copy of ``image`` rotated by ``angle`` about its centre, and its valid pixels."""
    h, w = image.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    cx, cy = w / 2.0, h / 2.0
    c, s = np.cos(angle), np.sin(angle)
    # source = center + R(-angle) (p - center), pixel centres at +0.5
    px, py = xx + 0.5 - cx, yy + 0.5 - cy
    sx = c * px + s * py + cx - 0.5
    sy = -s * px + c * py + cy - 0.5
    valid = (sx >= -0.01) & (sx <= w - 0.99) & (sy >= -0.01) & (sy <= h - 0.99)
    out = np.stack([map_coordinates(image[:, :, k], [sy, sx], order=1, mode="nearest")
                    for k in range(image.shape[2])], axis=2)
    return out, valid


def texture_spectra(image, *, orientations: int = 24) -> TextureSpectra:
    """Precompute rotated copies of a sample and their spectra.

    Parameters
    ----------
    image : array_like, (h, w, c) float64
        Sample in the matching colour space.
    orientations : int, optional
        Number of orientations, evenly spaced over a full turn (the paper
        uses 19).

    Returns
    -------
    TextureSpectra
    """
    T = np.ascontiguousarray(image, dtype=np.float64)
    if T.ndim != 3 or T.shape[0] < 2 or T.shape[1] < 2:
        raise InputError(f"image must be (h, w, c) with h, w >= 2, got {T.shape}")
    k = int(orientations)
    if k < 1:
        raise InputError(f"orientations must be >= 1, got {orientations!r}")
    angles = 2.0 * np.pi * np.arange(k) / k
    rot, val = zip(*(rotate_image(T, a) for a in angles))
    rot = np.stack(rot)
    val = np.stack(val)
    rot = np.where(val[..., None], rot, 0.0)
    h, w = T.shape[:2]
    # single precision halves memory traffic; the energies keep ~6 significant digits,
    # plenty to rank translations (the test compares with a float64 brute force)
    spec_t = sfft.rfft2(np.moveaxis(rot, 3, 1).astype(np.float32), axes=(-2, -1))
    spec_t2 = sfft.rfft2(np.sum(rot * rot, axis=3).astype(np.float32), axes=(-2, -1))
    var = float(np.sum(T.reshape(-1, T.shape[2]).var(axis=0)))
    return TextureSpectra(image=T, angles=angles, rotated=rot, valid=val, spec_t=spec_t,
                          spec_t2=spec_t2, variance=var)


def match_energy(spectra: TextureSpectra, mask, support, footprint, *, which=None,
                 fast: bool = False, footprint_pixels=None):
    """Matching energy of a mask at every translation and orientation.

    Parameters
    ----------
    spectra : TextureSpectra
    mask : numpy.ndarray, (h, w, c) float64
        ``I``: colours of the mask, zero outside its support (same size as
        the sample, mask drawn from the top-left corner).
    support : numpy.ndarray, (h, w) float64
        ``J`` (0 or 1).
    footprint : numpy.ndarray, (h, w) float64
        Pixels the placed patch covers (cluster and mask): a translation is
        admissible when none of them falls outside the rotated sample.
    which : array_like of int, optional
        Orientations to evaluate (default all).
    fast : bool, optional
        Assemble the admissible block in the compiled loop
        :func:`_admissible_slabs` (the same values; loading numba costs
        about a second once, worth it for thousands of calls).
    footprint_pixels : array_like of int, optional
        Flat indices (row-major) of the pixels where ``footprint > 0``, in any
        order, repeats allowed, when the caller has them (hpm: the rasterized
        pixels); spares the scan of ``footprint``.  The same result.

    Returns
    -------
    energy : numpy.ndarray, (k', h, w) float64
        ``E`` for translation ``(dy, dx)`` of the mask; ``inf`` where not
        admissible (footprint leaving the sample, or wrapping around).
    """
    h, w = spectra.image.shape[:2]
    I = np.asarray(mask, dtype=np.float64)
    J = np.asarray(support, dtype=np.float64)
    K = np.asarray(footprint, dtype=np.float64)
    idx = np.arange(spectra.angles.size) if which is None else np.asarray(which, np.int64)
    rows = np.flatnonzero(J.any(axis=1))       # I is zero outside the support's rows
    fI, fJ = _mask_spectra(I, J, rows)
    if which is None:
        St, St2 = spectra.spec_t, spectra.spec_t2
    elif idx.size == 1:                  # one orientation (hpm with a field): views, no copy
        St, St2 = spectra.spec_t[idx[0]:idx[0] + 1], spectra.spec_t2[idx[0]:idx[0] + 1]
    else:
        St, St2 = spectra.spec_t[idx], spectra.spec_t2[idx]
    spec = fJ * St2
    tmp = np.empty_like(spec)
    for ch in range(fI.shape[0]):
        fI[ch] *= 2.0
        spec -= np.multiply(fI[ch], St[:, ch], out=tmp)
    E = sfft.irfft2(spec, s=(h, w), axes=(-2, -1))
    Ir = I[rows[0]:rows[-1] + 1] if rows.size else I[:0]
    sum_i2 = float(np.sum(Ir * Ir))
    if footprint_pixels is None:
        ys, xs = np.nonzero(K > 0)
    else:
        ys, xs = np.divmod(np.asarray(footprint_pixels, np.int64), w)
    if ys.size == 0:
        return np.maximum(E.astype(np.float64) + sum_i2, 0.0)
    # admissible block: the footprint must not wrap around
    hy, wx = h - int(ys.max()), w - int(xs.max())
    # inside of the rotated image: |r1 . (p - c)| <= w/2 - 1, |r2 . (p - c)| <= h/2 - 1
    # for every footprint pixel p; for each orientation and row dy the admissible
    # shifts dx form one interval (intersection of two slabs)
    c = spectra.center
    q = np.stack([xs + 0.5 - c[0], ys + 0.5 - c[1]], axis=1)
    a = spectra.angles[idx]
    co, si = np.cos(a), np.sin(a)
    if fast:
        # the footprint's extent along both slabs' directions as below, the intervals and
        # the block in one compiled pass (the same operations on the same values)
        ext = np.empty((2, 2, idx.size))
        for j, (r0, r1) in enumerate(((co, si), (-si, co))):
            proj = q @ np.stack([r0, r1])
            ext[j, 0], ext[j, 1] = proj.min(axis=0), proj.max(axis=0)
        return _admissible_slabs(E, sum_i2, ext, co, si, w / 2.0 - 1.0, h / 2.0 - 1.0,
                                 hy, wx)
    dy = np.arange(hy, dtype=np.float64)[None, :]
    lo = np.full((idx.size, hy), -np.inf)
    hi = np.full((idx.size, hy), np.inf)
    for r0, r1, half in ((co, si, w / 2.0 - 1.0), (-si, co, h / 2.0 - 1.0)):
        proj = q @ np.stack([r0, r1])                              # (p, k')
        # admissible: tmin <= r0 dx + r1 dy <= tmax
        tmin = (-half - proj.min(axis=0))[:, None] - r1[:, None] * dy
        tmax = (half - proj.max(axis=0))[:, None] - r1[:, None] * dy
        r0c = r0[:, None]
        tiny = np.abs(r0c) < 1e-12
        safe = np.where(tiny, 1.0, r0c)
        x1, x2 = tmin / safe, tmax / safe
        lo_k = np.where(tiny, np.where((tmin <= 0) & (tmax >= 0), -np.inf, np.inf),
                        np.minimum(x1, x2))
        hi_k = np.where(tiny, np.where((tmin <= 0) & (tmax >= 0), np.inf, -np.inf),
                        np.maximum(x1, x2))
        lo = np.maximum(lo, lo_k)
        hi = np.minimum(hi, hi_k)
    out = np.full(E.shape, np.inf)
    blk = np.maximum(E[:, :hy, :wx].astype(np.float64) + sum_i2, 0.0)
    dx = np.arange(wx, dtype=np.float64)[None, None, :]
    ok = (dx >= lo[:, :, None]) & (dx <= hi[:, :, None])
    out[:, :hy, :wx] = np.where(ok, blk, np.inf)
    return out


@compiled
def _admissible_slabs(E, sum_i2, ext, co, si, half_w, half_h, hy, wx):
    """:func:`match_energy`'s admissible intervals and block in one pass: per
    orientation ``a`` and row ``dy < hy`` the interval ``[lo, hi]`` of shifts ``dx``
    cut by the two slabs (directions ``(co, si)`` and ``(-si, co)``, half widths
    ``half_w`` and ``half_h``, the footprint's extent along them ``ext[slab, 0 / 1,
    a]``), computed with the numpy lines' operations in their order, then
    ``max(E + sum_i2, 0)`` (in float64) inside the intervals and the block
    ``dy < hy``, ``dx < wx``, ``inf`` elsewhere: the same bytes."""
    k, h, w = E.shape
    out = np.empty((k, h, w))
    for a in range(k):
        for y in range(h):
            lo = -np.inf
            hi = np.inf
            if y < hy:
                for j in range(2):
                    r0 = co[a] if j == 0 else -si[a]
                    r1 = si[a] if j == 0 else co[a]
                    half = half_w if j == 0 else half_h
                    tmin = (-half - ext[j, 0, a]) - r1 * np.float64(y)
                    tmax = (half - ext[j, 1, a]) - r1 * np.float64(y)
                    if abs(r0) < 1e-12:
                        inside = tmin <= 0 and tmax >= 0
                        lo_k = -np.inf if inside else np.inf
                        hi_k = np.inf if inside else -np.inf
                    else:
                        x1 = tmin / r0
                        x2 = tmax / r0
                        lo_k = min(x1, x2)
                        hi_k = max(x1, x2)
                    lo = max(lo, lo_k)
                    hi = min(hi, hi_k)
            for x in range(w):
                v = np.inf
                if y < hy and x < wx and x >= lo and x <= hi:
                    v = np.float64(E[a, y, x]) + sum_i2
                    if v < 0.0:
                        v = 0.0
                out[a, y, x] = v
    return out


def _mask_spectra(I, J, rows=None):
    """Conjugate spectra of the mask's channels ``(c, h, w // 2 + 1)`` and of its support.

    The same values as ``rfft2`` of each plane (float32): the row transforms
    are computed only over the rows from the support's first to its last
    (the others are zero), all planes in one call, then the column
    transforms, as ``rfft2`` itself proceeds; only the sign of some zeros
    may differ.  A mask is a band along one cluster: a fraction of the rows.
    """
    h, w = J.shape
    nc = I.shape[2]
    out = np.zeros((nc + 1, h, w // 2 + 1), np.complex64)
    if rows is None:                     # the rows holding the support
        rows = np.flatnonzero(J.any(axis=1))
    if rows.size:
        r0, r1 = int(rows[0]), int(rows[-1]) + 1
        X = np.empty((nc + 1, r1 - r0, w), np.float32)
        X[:nc] = np.moveaxis(I[r0:r1], 2, 0)
        X[nc] = J[r0:r1]
        out[:, r0:r1] = sfft.rfft(X, axis=-1)
        out = sfft.fft(out, axis=-2, overwrite_x=True)
    out = np.conj(out, out=out)
    return out[:nc], out[nc]


def brute_force_energy(image, mask, support, dy: int, dx: int) -> float:
    """``sum_x J(x) (I(x) - T(x + x0))^2`` for one translation, without wrapping.

    Parameters
    ----------
    image : numpy.ndarray, (h, w, c)
    mask : numpy.ndarray, (h, w, c)
    support : numpy.ndarray, (h, w)
    dy, dx : int

    Returns
    -------
    float
    """
    ys, xs = np.nonzero(support)
    d = mask[ys, xs] - image[ys + dy, xs + dx]
    return float(np.sum(support[ys, xs][:, None] * d * d))


@dataclass(frozen=True)
class PatternScale:
    """Size and anisotropy of the pattern of a sample (:func:`pattern_scale`).

    Attributes
    ----------
    periodic : bool
        Whether the autocorrelation has a peak that repeats (a structured,
        periodic pattern: bricks, weaves, nets, tiles).
    period : float
        Pattern size in pixels: the longer of the two shortest independent
        repeat vectors (the one found for stripes); 0 when not ``periodic``.
    periods : numpy.ndarray, (k, 2) float64
        The repeat vectors ``(x, y)`` found, in pixels (k = 0, 1 or 2).
    correlation_length : float
        Lag in pixels at which the ring mean of the autocorrelation falls
        below ``1/e`` (the size of the features of a stochastic sample).
    peak : float
        Strength of the weakest accepted repeat (the smaller of the
        autocorrelation at the lag and at twice the lag; 0 if none).
    coherence : float
        Global anisotropy of the structure tensor, ``(l1 - l2) / (l1 + l2)``
        of the summed gradient tensor: 0 for an isotropic sample, 1 for
        straight parallel stripes.
    orientation : float
        Dominant direction of the features (radians, along the stripes, x
        right, y down), meaningful when ``coherence`` is large.
    """

    periodic: bool
    period: float
    periods: np.ndarray
    correlation_length: float
    peak: float
    coherence: float
    orientation: float

    @property
    def size(self) -> float:
        """Pattern size in pixels: ``period`` if periodic, else ``correlation_length``."""
        return self.period if self.periodic else self.correlation_length


def _centred_luminance(image):
    """``(a, Y)``: the image as float64 and its luminance minus its mean, (h, w).

    Raises
    ------
    InputError
        If the image is not (h, w) or (h, w, 3+) with h, w >= 8.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] >= 3:
        Y = a[:, :, :3] @ _WEIGHTS[0]
    elif a.ndim == 2:
        Y = a.copy()
    else:
        raise InputError(f"image must be (h, w) or (h, w, 3), got shape {a.shape}")
    h, w = Y.shape
    if min(h, w) < 8:
        raise InputError(f"image must be at least 8 x 8 pixels, got {w} x {h}")
    return a, Y - Y.mean()


def pattern_scale(image) -> PatternScale:
    """Estimate the size and anisotropy of a sample's pattern.

    The normalised autocorrelation ``rho`` of the luminance (mean removed,
    divided by the number of overlapping pixels at every lag, so that long
    lags are not damped; ``rho(0) = 1``) is computed by FFT over lags up to
    half the image.  Its local maxima (5 x 5 neighbourhood) outside the
    central lobe (the part connected to lag 0 where ``rho > 0.2``) and
    within a quarter of the image are repeat candidates, nearest first.  A
    candidate ``p`` is a repeat of the pattern when both ``rho(p)`` and
    ``rho(2 p)`` (max over 3 x 3) reach ``PERIOD_PEAK = 0.15``: a pattern
    repeats at twice its period, a blob-like stochastic sample does not.
    On the quilting samples the repeats found are rope net 37 / 42 px
    (peaks 0.50-0.53), slate tiles 15 / 21, bricks 20 / 22 (0.15-0.22),
    basket weave 34 (0.16-0.17, and 61 px by the longer search below); the
    stochastic ones give none: gravel (no
    peak), peppers (0.19 at 14 px but 0.07 at twice it), water (0.14).  The
    threshold 0.15 sits between water's 0.14 and the weave's 0.16; it is
    the least robust constant here.  The first repeat is the nearest; the
    second is the nearest one at more than 30 degrees from it such that
    ``v - k u`` (``|k| <= 3``) is not in the central lobe (for stripes the
    lobe is a ridge along them, and every point of the next ridge is a
    maximum); the pair is reduced to the shortest basis of its lattice
    (Lagrange-Gauss) and ``period`` is the longer of the two (the pattern
    cell must hold both).  The search stops at a quarter of the
    image so that ``2 p`` stays within the half-image of reliable lags:
    a pattern larger than a quarter of the sample is not seen repeating.
    When only one repeat ``u`` is found there, a second one ``v`` is looked
    for further (up to half the image) among the same candidates: at more
    than 30 degrees from ``u``, not on a ridge of stripes, with ``rho``
    reaching ``PERIOD_PEAK`` at ``v + u`` or ``v - u`` as well (the lattice
    holds) and ``rho(v)`` standing ``LONG_REPEAT_MARGIN`` above a ring of
    radius ``|u| / 4`` around it (a peak, not a point of a ridge).  The
    basket weave's cell is found so, (33, 7) and (-2, 61) (before: (33, 7)
    only, and its perpendicular taken as the second lattice vector); the
    slate tiles keep their single repeat (stripes), the stochastic samples
    none.

    Anisotropy: the structure tensor (products of Sobel gradients of the
    luminance) summed over the image; ``coherence`` is the normalised
    difference of its eigenvalues.

    Parameters
    ----------
    image : array_like, (h, w, 3) or (h, w) uint8 or float
        The sample (RGB: luminance 0.299 R + 0.587 G + 0.114 B).

    Returns
    -------
    PatternScale

    Raises
    ------
    InputError
        If the image is not (h, w) or (h, w, 3+) with h, w >= 8.
    """

    a, Y = _centred_luminance(image)
    h, w = Y.shape
    var = float(np.mean(Y * Y))
    # structure tensor
    gx = ndi.sobel(Y, axis=1)
    gy = ndi.sobel(Y, axis=0)
    jxx, jyy, jxy = float(np.sum(gx * gx)), float(np.sum(gy * gy)), float(np.sum(gx * gy))
    tr = jxx + jyy
    coherence = float(np.hypot(jxx - jyy, 2 * jxy) / tr) if tr > 0 else 0.0
    # gradient direction = 0.5 atan2(2 jxy, jxx - jyy); the features run across it
    orientation = float((0.5 * np.arctan2(2 * jxy, jxx - jyy) + 0.5 * np.pi) % np.pi)
    empty = np.zeros((0, 2))
    if var <= 1e-12 * (1.0 + float(np.mean(a * a))):
        return PatternScale(False, 0.0, empty, 0.0, 0.0, coherence, orientation)
    shape = (2 * h, 2 * w)
    spec = sfft.rfft2(Y, s=shape)
    acf = sfft.irfft2(spec * np.conj(spec), s=shape)
    one = sfft.rfft2(np.ones((h, w)), s=shape)
    cnt = sfft.irfft2(one * np.conj(one), s=shape)
    rho = np.fft.fftshift(acf / np.maximum(np.rint(cnt), 1.0) / var)
    hy, hx = h // 2, w // 2
    rho = rho[h - hy:h + hy + 1, w - hx:w + hx + 1]           # lags up to half the image
    cy, cx = hy, hx
    yy, xx = np.mgrid[-cy:cy + 1, -cx:cx + 1]
    R = np.hypot(xx, yy)
    ring = np.rint(R).astype(np.int64)
    ring_mean = np.bincount(ring.ravel(), weights=rho.ravel()) / np.bincount(ring.ravel())
    below = np.flatnonzero(ring_mean < np.exp(-1.0))
    corr = float(below[0]) if below.size else float(ring_mean.size)
    lab, _ = ndi.label(rho > 0.2)
    lobe = lab == lab[cy, cx]
    cand = ((rho == ndi.maximum_filter(rho, size=5)) & ~lobe & (rho >= PERIOD_PEAK)
            & (R <= min(h, w) / 4.0))
    near = ndi.maximum_filter(rho, size=3)
    py, px = np.nonzero(cand)
    order = np.lexsort((px, py, R[py, px]))
    found, strength = [], []
    for i in order:
        v = np.array([xx[py[i], px[i]], yy[py[i], px[i]]], dtype=np.float64)
        if v[1] < 0 or (v[1] == 0 and v[0] < 0):
            continue                        # rho is symmetric: keep one of +-p
        qy, qx = int(2 * v[1]) + cy, int(2 * v[0]) + cx
        if not (0 <= qy < rho.shape[0] and 0 <= qx < rho.shape[1]):
            continue
        r2 = float(near[qy, qx])
        if r2 < PERIOD_PEAK:
            continue
        if found:
            u = found[0]
            cosang = abs(float(u @ v)) / (np.linalg.norm(u) * np.linalg.norm(v))
            if cosang > np.cos(np.radians(30.0)):
                continue
            # v - k u inside the central lobe (|k| <= 3): v lies on the k-th ridge of
            # stripes (rho stays high along them), it is not a second lattice vector
            dup = False
            for d in (v - k * u for k in (-3, -2, -1, 1, 2, 3)):
                dy, dx = int(d[1]) + cy, int(d[0]) + cx
                if 0 <= dy < rho.shape[0] and 0 <= dx < rho.shape[1] and lobe[dy, dx]:
                    dup = True
            if dup:
                continue
        found.append(v)
        strength.append(min(float(rho[py[i], px[i]]), r2))
        if len(found) == 2:
            break
    if len(found) == 1:
        # a second repeat longer than a quarter of the image (the basket weave's cell is
        # 33 x 61 px in a 192 px sample): its double is out of the reliable lags, so it is
        # checked against the lattice instead - rho reaches PERIOD_PEAK at v + u or v - u
        # too, and v is a peak standing LONG_REPEAT_MARGIN above its surroundings
        u = found[0]

        def at(p):
            qy, qx = int(round(p[1])) + cy, int(round(p[0])) + cx
            inside = 0 <= qy < rho.shape[0] and 0 <= qx < rho.shape[1]
            return float(near[qy, qx]) if inside else -np.inf

        far = ((rho == ndi.maximum_filter(rho, size=5)) & ~lobe & (rho >= PERIOD_PEAK)
               & (R > min(h, w) / 4.0) & (yy >= 0))
        fy, fx = np.nonzero(far)
        for i in np.lexsort((fx, fy, R[fy, fx])):
            v = np.array([xx[fy[i], fx[i]], yy[fy[i], fx[i]]], dtype=np.float64)
            if v[1] == 0 and v[0] < 0:
                continue
            cosang = abs(float(u @ v)) / (np.linalg.norm(u) * np.linalg.norm(v))
            if cosang > np.cos(np.radians(30.0)):
                continue
            if any(lobe[int(d[1]) + cy, int(d[0]) + cx] for d in (v - k * u for k in
                                                                   (-3, -2, -1, 1, 2, 3))
                   if 0 <= int(d[1]) + cy < rho.shape[0] and 0 <= int(d[0]) + cx < rho.shape[1]):
                continue
            r1 = float(rho[fy[i], fx[i]])
            r2 = max(at(v + u), at(v - u))
            if r2 < PERIOD_PEAK:
                continue
            # a peak of the lattice stands above a ring a quarter period around it; on a
            # ridge of stripes (or its slow decay) the ring meets values as high as rho(v)
            ring = max(rho[int(round(v[1] + rr * np.sin(a))) + cy,
                           int(round(v[0] + rr * np.cos(a))) + cx]
                       if 0 <= int(round(v[1] + rr * np.sin(a))) + cy < rho.shape[0]
                       and 0 <= int(round(v[0] + rr * np.cos(a))) + cx < rho.shape[1]
                       else -np.inf
                       for rr in [max(3.0, 0.25 * float(np.linalg.norm(u)))]
                       for a in np.linspace(0.0, 2 * np.pi, 16, endpoint=False))
            if ring > r1 - LONG_REPEAT_MARGIN:
                continue
            found.append(v)
            strength.append(min(r1, r2))
            break
    if not found:
        return PatternScale(False, 0.0, empty, corr, 0.0, coherence, orientation)
    if len(found) == 2:                  # Lagrange-Gauss reduction: the shortest basis
        u, v = found
        while True:
            if v @ v < u @ u:
                u, v = v, u
            k = np.rint((u @ v) / (u @ u))
            if k == 0:
                break
            v = v - k * u
        found = [u, v]
    per = np.array(found)
    return PatternScale(True, float(np.linalg.norm(per, axis=1).max()), per, corr,
                        float(min(strength)), coherence, orientation)


def quarter_turn_symmetry(image) -> float:
    """How much a sample looks the same after a quarter turn (in [-1, 1]).

    The normalised luminance autocorrelation ``rho`` (as in
    :func:`pattern_scale`, lags within a quarter of the smaller side) is
    compared with itself turned by 90 degrees: the Pearson correlation of
    the two over the disc of lags, lag 0 left out.  A square grid (rope net,
    basket weave) gives values near 1, stripes, bricks and other patterns with
    one dominant direction low or negative values.

    Parameters
    ----------
    image : array_like, (h, w, 3) or (h, w) uint8 or float

    Returns
    -------
    float
        0 for a constant image.

    Raises
    ------
    InputError
        If the image is not (h, w) or (h, w, 3+) with h, w >= 8.
    """
    a, Y = _centred_luminance(image)
    h, w = Y.shape
    var = float(np.mean(Y * Y))
    if var <= 1e-12 * (1.0 + float(np.mean(a * a))):
        return 0.0
    shape = (2 * h, 2 * w)
    spec = sfft.rfft2(Y, s=shape)
    acf = sfft.irfft2(spec * np.conj(spec), s=shape)
    one = sfft.rfft2(np.ones((h, w)), s=shape)
    cnt = sfft.irfft2(one * np.conj(one), s=shape)
    rho = np.fft.fftshift(acf / np.maximum(np.rint(cnt), 1.0) / var)
    r = max(min(h, w) // 4, 2)
    rho = rho[h - r:h + r + 1, w - r:w + r + 1]
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    disc = (np.hypot(xx, yy) <= r) & ((xx != 0) | (yy != 0))
    x, y = rho[disc], np.rot90(rho)[disc]
    x, y = x - x.mean(), y - y.mean()
    den = float(np.sqrt(np.sum(x * x) * np.sum(y * y)))
    return float(np.sum(x * y) / den) if den > 0 else 0.0
