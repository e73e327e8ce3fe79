"""Transparent holes in example images are filled from the image itself."""

import numpy as np
import pytest

from geotex.errors import InputError
from geotex.image.holes import RIM, transparent_filled
from geotex.image.material.tileable import tileable_image


def _bricks(n=120, seed=0):
    """A periodic brick pattern (period 24 x 12 texels) with noise, RGB in [0, 1]."""
    y, x = np.mgrid[0:n, 0:n]
    row = y // 12
    mortar = (y % 12 < 2) | ((x + 12 * (row % 2)) % 24 < 2)
    rgb = np.where(mortar[..., None], [0.85, 0.85, 0.8], [0.6, 0.25, 0.15])
    return rgb + np.random.default_rng(seed).normal(0.0, 0.01, rgb.shape)


def _disc(n, r, c=None):
    y, x = np.mgrid[0:n, 0:n]
    c = n / 2 if c is None else c
    return (y - c) ** 2 + (x - c) ** 2 < r * r


def test_a_hole_in_a_regular_pattern_is_filled_with_the_pattern():
    truth = _bricks()
    hole = _disc(120, 18)
    alpha = np.where(hole, 0.0, 1.0)
    damaged = np.where(hole[..., None], [0.0, 0.0, 0.0], truth)    # black behind the hole
    out = transparent_filled(damaged, alpha)
    assert out.shape == truth.shape
    # opaque texels away from the rim are kept
    away = ~_disc(120, 18 + RIM + 1)
    assert np.array_equal(out[away], damaged[away])
    # the pattern continues through the hole: close to the true texels (the noise
    # differs), nothing black left; a mean colour fill would be off by ~0.25
    err = np.abs(out[hole] - truth[hole]).mean()
    assert err < 0.05, err
    assert out[hole].min() > 0.1


def test_the_rim_of_a_cut_out_is_replaced():
    truth = _bricks()
    hole = _disc(120, 15)
    rim = _disc(120, 15 + 2) & ~hole
    damaged = truth.copy()
    damaged[hole] = 0.0
    damaged[rim] = [0.2, 0.9, 0.2]                 # blended colour around the cut
    out = transparent_filled(damaged, np.where(hole, 0.0, 1.0))
    assert np.abs(out[rim] - [0.2, 0.9, 0.2]).sum(axis=1).min() > 0.1


def test_no_hole_is_a_copy_and_all_transparent_is_refused():
    img = _bricks(40)
    out = transparent_filled(img, np.ones((40, 40)))
    assert np.array_equal(out, img) and out is not img
    with pytest.raises(InputError, match="transparent everywhere"):
        transparent_filled(img, np.zeros((40, 40)))
    with pytest.raises(InputError, match="does not match"):
        transparent_filled(img, np.ones((10, 40)))


def test_a_mostly_transparent_image_falls_back_to_the_nearest_colour():
    img = _bricks(60)
    alpha = np.zeros((60, 60))
    alpha[:6, :6] = 1.0                            # no window fits over opaque texels
    out = transparent_filled(img, alpha, block=8)
    # every texel took the colour of one of the opaque texels
    kept = {tuple(c) for c in img[:6, :6].reshape(-1, 3)}
    assert all(tuple(c) in kept for c in out.reshape(-1, 3))


def test_tileable_image_of_an_rgba_image_has_no_hole():
    truth = _bricks()
    hole = _disc(120, 18)
    rgba = np.dstack([np.where(hole[..., None], 0.0, truth), np.where(hole, 0.0, 1.0)])
    rgba = np.clip(np.rint(rgba * 255), 0, 255).astype(np.uint8)
    tile = tileable_image(rgba, size=64)
    # the black behind the hole would cover ~7% of the tile (the ringing of the
    # resize leaves a few dark texels at brick edges, not black ones)
    black = (tile.colors.max(axis=2) < 0.1).mean()
    assert black < 0.002, black
