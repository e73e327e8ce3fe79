"""The material-space tile ``T(s, t, m)``: building, sampling, files, pictures.

A tile is ``K`` colour layers of ``n x n`` texels, periodic in ``s`` (columns)
and ``t`` (rows), with the material axis ``m`` in ``[0, 1]`` running through
the layers (layer ``k`` at ``m = k / (K - 1)``).  Sampling is trilinear:
bilinear with wrap-around in ``(s, t)``, linear between the two nearest
layers in ``m``.

Building (material-space textures §1, Fig. 2): both inputs are made tileable
with their feature masks (:mod:`.tileable`), the masks are morphed
(:mod:`.morph`), every layer is synthesized twice under its morphed mask -
from ``T_0`` (layers in increasing ``m``) and from ``T_M`` (decreasing ``m``)
(:mod:`.synthesis`) - and the two are blended with weight ``m``.  The end
layers are the two tileable inputs themselves.

A *periodicity-hiding* tile (paper Fig. 14) is built from one input: every
layer keeps the input's own feature mask, layer 0 is the input, and every
other layer is synthesized starting from the input shifted by a random
offset (drawn from ``seed``), with the input texels near each output texel's own position refused
(``EXCLUDE_FRACTION``), so the layers share their layout and differ in their
details.

File format (``.npz``, :data:`TILE_FORMAT` in ``format``): ``layers``
``(K, n, n, 3)`` uint8, ``masks`` ``(K, n, n)`` bool, ``format``, and
``metadata`` (JSON: kind, inputs, seed, timings, histogram distances).
"""

from __future__ import annotations

import dataclasses
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geotex.errors import InputError
from geotex.image.material.morph import morph_masks
from geotex.image.material.synthesis import (SynthesisOptions, indirection_colors,
                                             synthesize_layers)
from geotex.image.material.tileable import tileable_image
from geotex.io.records import read_record, write_record

__all__ = ["TILE_FORMAT", "MaterialTile", "build_material_tile", "build_periodicity_tile",
           "sample_tile", "blend_weights", "save_tile", "load_tile", "tile_slices_image",
           "histogram_distance",
           "cross_fade_layers"]

#: format tag of tile files
TILE_FORMAT = "geotex-material-tile/1"
#: periodicity-hiding layers copy nothing from within this fraction of the
#: tile around their own position (so they cannot fall back to the input)
EXCLUDE_FRACTION = 0.1
#: width of the soft border of the "select" blend, in units of m
SELECT_SOFTNESS = 0.15
#: metadata keys that :func:`save_tile` leaves out (they change from run to run)
VOLATILE_METADATA = ("timings",)
#: bins per channel of :func:`histogram_distance`
HISTOGRAM_BINS = 64


@dataclass(frozen=True, eq=False)
class MaterialTile:
    """A periodic 3D ``(s, t, m)`` texture tile.

    Attributes
    ----------
    layers : numpy.ndarray, (K, n, n, 3) uint8
        Colour per layer; row 0 is ``t = 0``, column 0 is ``s = 0``.
    masks : numpy.ndarray, (K, n, n) bool
        Feature mask per layer.
    metadata : dict
    """

    layers: np.ndarray
    masks: np.ndarray
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        L = np.asarray(self.layers)
        Mk = np.asarray(self.masks)
        if L.ndim != 4 or L.shape[3] != 3 or L.dtype != np.uint8 or L.shape[1] != L.shape[2] \
                or L.shape[0] < 1:
            raise InputError(f"tile layers must be a (K, n, n, 3) uint8 array, got "
                             f"{L.dtype} {L.shape}")
        if Mk.shape != L.shape[:3]:
            raise InputError(f"tile masks must have shape {L.shape[:3]}, got {Mk.shape}")
        object.__setattr__(self, "layers", np.ascontiguousarray(L))
        object.__setattr__(self, "masks", np.ascontiguousarray(Mk, dtype=bool))

    @property
    def n_layers(self) -> int:
        return int(self.layers.shape[0])

    @property
    def size(self) -> int:
        return int(self.layers.shape[1])


def _checked_image(img, name: str) -> np.ndarray:
    arr = np.asarray(img)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4):
        raise InputError(f"{name} must be an (h, w, 3 or 4) image, got shape {arr.shape}")
    return arr


def histogram_distance(image, reference_hist) -> float:
    """Mean over RGB of the 1D Wasserstein distance between normalised histograms.

    Parameters
    ----------
    image : array_like, (h, w, 3) uint8
    reference_hist : array_like, (3, HISTOGRAM_BINS) float
        Per-channel probabilities.

    Returns
    -------
    float
        In units of the colour range (0 = identical histograms, 1 = all mass
        moved across the whole range).
    """
    h = _histograms(image)
    cdf = np.cumsum(h, axis=1) - np.cumsum(np.asarray(reference_hist), axis=1)
    return float(np.abs(cdf).sum(axis=1).mean() / HISTOGRAM_BINS)


def _histograms(image) -> np.ndarray:
    img = np.asarray(image).reshape(-1, 3)
    out = np.empty((3, HISTOGRAM_BINS))
    for c in range(3):
        hc = np.bincount(img[:, c].astype(np.int64) * HISTOGRAM_BINS // 256,
                         minlength=HISTOGRAM_BINS)
        out[c] = hc / max(hc.sum(), 1)
    return out


def cross_fade_layers(first, last, n_layers: int) -> np.ndarray:
    """The baseline: ``(1 - m) T_0 + m T_M`` per layer, ``(K, n, n, 3)`` uint8."""
    a = np.asarray(first, dtype=np.float64)
    b = np.asarray(last, dtype=np.float64)
    w = np.linspace(0.0, 1.0, n_layers)[:, None, None, None]
    return np.clip(np.rint((1.0 - w) * a + w * b), 0, 255).astype(np.uint8)


def _histogram_report(layers: np.ndarray) -> dict:
    """Distance of every layer (and of a cross-fade) to the blend of the end histograms."""
    K = layers.shape[0]
    h0, h1 = _histograms(layers[0]), _histograms(layers[-1])
    fade = cross_fade_layers(layers[0], layers[-1], K)
    ours, base = [], []
    for k in range(K):
        w = k / max(K - 1, 1)
        ref = (1 - w) * h0 + w * h1
        ours.append(histogram_distance(layers[k], ref))
        base.append(histogram_distance(fade[k], ref))
    return {"histogram_distance": ours, "cross_fade_histogram_distance": base}


def _to_uint8(x: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(x * 255.0), 0, 255).astype(np.uint8)


def build_material_tile(image_a, image_b, *, size: int = 128, layers: int = 8, seed=None,
                        mask_a=None, mask_b=None, threshold_a: float | None = None,
                        threshold_b: float | None = None, options: SynthesisOptions | None = None,
                        blend: str = "select", progress=None) -> MaterialTile:
    """Build a material-space tile that morphs one texture into another.

    Parameters
    ----------
    image_a, image_b : array_like, (h, w, 3 or 4) uint8
        The two textures (``m = 0`` and ``m = 1``); any size, their central
        squares are used.
    size : int, optional
        Tile side in texels (divisible by 4, at least 32).
    layers : int, optional
        ``K``: layers along ``m`` (at least 2).
    seed : int, optional
        Order of the synthesis sub-passes (same seed, same bytes).
    mask_a, mask_b : array_like, optional
        Feature mask images of the same size as their textures; default a
        luminance threshold.
    threshold_a, threshold_b : float, optional
        Luminance thresholds in ``[0, 1]`` (default Otsu).
    options : SynthesisOptions, optional
    blend : {"linear", "select"}, optional
        How the two syntheses of a layer combine (:func:`blend_weights`):
        a histogram-keeping selection (default: measured closer to the
        inputs' histograms than a plain cross-fade on every pair of
        ``benchmarks/results/material.md``, where the paper's linear blend
        lost on two of three), or the paper's linear blend with weight ``m``.
    progress : callable, optional
        Called with a stage name as each stage starts.

    Returns
    -------
    MaterialTile
        ``metadata`` holds the timings, the mask areas and the histogram
        distances of every layer and of a plain cross-fade.

    Raises
    ------
    InputError
        On bad images, masks of the wrong size, empty masks or bad options.
    """
    opt = SynthesisOptions() if options is None else options
    A = _checked_image(image_a, "image A")
    B = _checked_image(image_b, "image B")
    size = _tile_size(size, opt)
    if isinstance(layers, bool) or int(layers) != layers or int(layers) < 2:
        raise InputError(f"layers must be an integer >= 2, got {layers!r}")
    K = int(layers)
    if blend not in ("linear", "select"):
        raise InputError(f"blend must be 'linear' or 'select', got {blend!r}")
    t0 = time.perf_counter()
    _report(progress, "tileable inputs")
    ta = tileable_image(A, size=size, mask=mask_a, threshold=threshold_a)
    tb = tileable_image(B, size=size, mask=mask_b, threshold=threshold_b)
    t1 = time.perf_counter()
    _report(progress, "mask morph")
    morph = morph_masks(ta.mask, tb.mask, layers=K)
    t2 = time.perf_counter()
    rng = np.random.default_rng(seed)
    seeds = rng.integers(0, 2 ** 63 - 1, size=2)
    _report(progress, "synthesis from A")
    maps_a = synthesize_layers(ta.colors, ta.mask, morph.masks, options=opt,
                               seed=int(seeds[0]), progress=progress)
    _report(progress, "synthesis from B")
    maps_b = synthesize_layers(tb.colors, tb.mask, morph.masks[::-1], options=opt,
                               seed=int(seeds[1]), progress=progress)[::-1]
    t3 = time.perf_counter()
    col_a = indirection_colors(ta.colors, maps_a)
    col_b = indirection_colors(tb.colors, maps_b)
    w = blend_weights(size, K, blend=blend, seed=int(seeds[0]))[..., None]
    layers_f = (1.0 - w) * col_a + w * col_b
    layers_f[0], layers_f[-1] = ta.colors, tb.colors
    out = _to_uint8(layers_f)
    meta = {"kind": "morph", "size": size, "layers": K, "seed": seed, "blend": blend,
            "thresholds": [ta.threshold, tb.threshold],
            "seam_cost": [list(ta.seam_cost), list(tb.seam_cost)],
            "mask_areas": morph.areas.tolist(), "morph_steps": morph.steps.tolist(),
            "area_adjusted": morph.adjusted.tolist(),
            "timings": {"tileable_s": round(t1 - t0, 3), "morph_s": round(t2 - t1, 3),
                        "synthesis_s": round(t3 - t2, 3)},
            "synthesis": {"levels": opt.levels, "iterations": list(opt.iterations),
                          "candidates": opt.candidates,
                          "histogram_weight": opt.histogram_weight}}
    meta.update(_histogram_report(out))
    return MaterialTile(layers=out, masks=morph.masks, metadata=meta)


def blend_weights(size: int, layers: int, *, blend: str = "linear", seed=None,
                  softness: float = SELECT_SOFTNESS) -> np.ndarray:
    """Weight of the second synthesis per layer and texel, ``(K, n, n)`` float64.

    ``"linear"`` (the paper, Fig. 5): ``m = k / (K - 1)`` everywhere.  Each
    texel then mixes the two syntheses' colours, which pulls the layer's
    histogram toward the mean (what a cross-fade does too, only with the
    features aligned).

    ``"select"`` (geotex's variant, not in the paper): a smooth periodic
    noise ``u(s, t)`` with uniform distribution (a Gaussian-blurred random
    field, ranked) decides where the second synthesis shows:
    ``w = clip((m - u) / softness + 1/2, 0, 1)``.  A fraction ``m`` of the
    texels shows the second synthesis, the rest the first, with narrow soft
    borders, so the layer's colour histogram is close to the blend
    ``(1 - m) H_0 + m H_M`` of the two syntheses' histograms (which the usage
    penalty keeps close to the inputs').  Every texel moves from 0 to 1 once
    along ``m``, so the tile stays smooth along ``m``.
    """
    K = int(layers)
    m = np.linspace(0.0, 1.0, K)[:, None, None]
    if blend == "linear":
        return np.broadcast_to(m, (K, size, size)).copy()
    # lazy: scipy.ndimage takes ~0.1 s to import (only the smooth blend needs it)
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(seed)
    noise = gaussian_filter(rng.normal(size=(size, size)), sigma=max(size / 24.0, 1.0),
                            mode="wrap")
    rank = np.empty(size * size)
    rank[np.argsort(noise.ravel(), kind="stable")] = (np.arange(size * size) + 0.5) / (size ** 2)
    u = rank.reshape(size, size)[None]
    # squeeze u into [softness / 2, 1 - softness / 2]: w = 0 at m = 0, 1 at m = 1
    u = softness / 2.0 + u * (1.0 - softness)
    return np.clip((m - u) / softness + 0.5, 0.0, 1.0)


def build_periodicity_tile(image, *, size: int = 128, layers: int = 4, seed=None, mask=None,
                           threshold: float | None = None,
                           options: SynthesisOptions | None = None,
                           progress=None) -> MaterialTile:
    """Build a tile whose layers share one feature mask (periodicity hiding, Fig. 14).

    Parameters
    ----------
    image : array_like, (h, w, 3 or 4) uint8
    size, layers, seed, mask, threshold, options, progress
        As :func:`build_material_tile`; ``seed`` also draws the random
        coarse starts of layers 1..K-1.

    Returns
    -------
    MaterialTile
        Layer 0 is the tileable input; every layer has the input's mask.

    Raises
    ------
    InputError
        As :func:`build_material_tile`.
    """
    opt = SynthesisOptions() if options is None else options
    A = _checked_image(image, "image")
    size = _tile_size(size, opt)
    if isinstance(layers, bool) or int(layers) != layers or int(layers) < 2:
        raise InputError(f"layers must be an integer >= 2, got {layers!r}")
    K = int(layers)
    t0 = time.perf_counter()
    _report(progress, "tileable input")
    ta = tileable_image(A, size=size, mask=mask, threshold=threshold)
    rng = np.random.default_rng(seed)
    n0 = size // 2 ** (opt.levels - 1)
    # every layer starts as the input shifted by a random offset beyond the exclusion
    yy, xx = np.divmod(np.arange(n0 * n0).reshape(n0, n0), n0)
    lo = int(np.ceil(EXCLUDE_FRACTION * n0)) + 1
    off = rng.integers(lo, n0 - lo + 1, size=(K - 1, 2))
    starts = ((yy[None] + off[:, 0, None, None]) % n0) * n0 + (xx[None] + off[:, 1, None,
                                                                             None]) % n0
    _report(progress, "synthesis")
    hide = dataclasses.replace(opt, exclude_fraction=max(opt.exclude_fraction,
                                                         EXCLUDE_FRACTION))
    maps = synthesize_layers(ta.colors, ta.mask, np.repeat(ta.mask[None], K - 1, axis=0),
                             options=hide, seed=int(rng.integers(2 ** 62)), starts=starts,
                             progress=progress)
    out = np.concatenate([ta.colors[None], indirection_colors(ta.colors, maps)])
    layers_u8 = _to_uint8(out)
    meta = {"kind": "periodicity", "size": size, "layers": K, "seed": seed,
            "thresholds": [ta.threshold], "seam_cost": [list(ta.seam_cost)],
            "timings": {"total_s": round(time.perf_counter() - t0, 3)}}
    return MaterialTile(layers=layers_u8, masks=np.repeat(ta.mask[None], K, axis=0),
                        metadata=meta)


def _tile_size(size, opt: SynthesisOptions) -> int:
    q = 2 ** (opt.levels - 1)
    if isinstance(size, bool) or int(size) != size or int(size) < 8 * q or int(size) % q:
        raise InputError(f"size must be an integer >= {8 * q} divisible by {q}, got {size!r}")
    return int(size)


def _report(progress, stage: str) -> None:
    if progress is not None:
        progress(stage)


def sample_tile(tile: MaterialTile, s, t, m) -> np.ndarray:
    """Trilinear colour of the tile at ``(s, t, m)``.

    Parameters
    ----------
    tile : MaterialTile
    s, t : array_like, (k,) float
        Tile coordinates (one period per unit; any real value, wrapped).
    m : array_like, (k,) float
        Material coordinate, clipped to ``[0, 1]``.

    Returns
    -------
    numpy.ndarray, (k, 3) float64
        RGB in ``[0, 255]``.
    """
    L = tile.layers
    K, n = L.shape[0], L.shape[1]
    s = np.asarray(s, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    mm = np.clip(np.asarray(m, dtype=np.float64), 0.0, 1.0) * (K - 1)
    x = np.mod(s, 1.0) * n - 0.5
    y = np.mod(t, 1.0) * n - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = x - x0, y - y0
    x0 = x0.astype(np.int64) % n
    y0 = y0.astype(np.int64) % n
    x1, y1 = (x0 + 1) % n, (y0 + 1) % n
    k0 = np.minimum(np.floor(mm).astype(np.int64), K - 1)
    k1 = np.minimum(k0 + 1, K - 1)
    fm = mm - k0
    flat = L.reshape(K * n * n, 3).astype(np.float32)
    out = np.zeros(s.shape + (3,))
    for k, wk in ((k0, 1.0 - fm), (k1, fm)):
        base = k * n * n
        for yy, wy in ((y0, 1.0 - fy), (y1, fy)):
            for xx, wx in ((x0, 1.0 - fx), (x1, fx)):
                out += (wk * wy * wx)[..., None] * flat[base + yy * n + xx]
    return out


def save_tile(path, tile: MaterialTile) -> Path:
    """Write a tile file (``.npz``, atomically); returns the path.

    The metadata keys in :data:`VOLATILE_METADATA` (timings) are not
    written, so the same inputs and seed give a byte-identical file.

    Raises
    ------
    InputError
        If the path does not end in ``.npz``.
    """
    meta = {k: v for k, v in tile.metadata.items() if k not in VOLATILE_METADATA}
    meta["format"] = TILE_FORMAT
    return write_record(path, {"layers": tile.layers, "masks": tile.masks,
                               "metadata": np.array(json.dumps(meta))},
                        compressed=True, kind="material tile")


def load_tile(path) -> MaterialTile:
    """Read a tile file written by :func:`save_tile`.

    Raises
    ------
    MissingFileError
        When the file is missing.
    MeshFileError
        When it is not a tile file, is damaged, or of another version.
    """
    d, meta = read_record(path, kind="material tile", format=TILE_FORMAT,
                          arrays=("layers", "masks"),
                          hint="build one with 'geotex material tile'")
    meta.pop("format", None)
    return MaterialTile(layers=d["layers"], masks=d["masks"], metadata=meta)


def tile_slices_image(tile: MaterialTile, *, masks: bool = True, repeat: int = 1,
                      gap: int = 4) -> np.ndarray:
    """A picture of the m-slices side by side (masks below when asked).

    Parameters
    ----------
    tile : MaterialTile
    masks : bool, optional
        Add a row with the feature masks.
    repeat : int, optional
        Show every slice repeated ``repeat x repeat`` times (to see the wrap).
    gap : int, optional
        White texels between slices.

    Returns
    -------
    numpy.ndarray, (h, w, 3) uint8
    """
    rows = [[np.tile(layer, (repeat, repeat, 1)) for layer in tile.layers]]
    if masks:
        rows.append([np.repeat(np.tile(mk, (repeat, repeat))[:, :, None] * 255, 3,
                               axis=2).astype(np.uint8) for mk in tile.masks])
    side = tile.size * repeat
    K = tile.n_layers
    img = np.full((len(rows) * (side + gap) - gap, K * (side + gap) - gap, 3), 255, np.uint8)
    for r, row in enumerate(rows):
        for k, im in enumerate(row):
            y0, x0 = r * (side + gap), k * (side + gap)
            img[y0:y0 + side, x0:x0 + side] = im
    return img
