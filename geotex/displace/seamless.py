"""Seamless mappings: periodic global parameterization and lapped pastes.

``pgp``: :func:`geotex.param.pgp.periodic_parameterization` over a cross field
gives per-corner tile coordinates that agree across every edge up to a
rotation by a multiple of 90 degrees plus a whole number of tiles.  The
height map repeats with period one tile, so translations never show; a
90-degree turn shows only for images that are not four-fold symmetric (it
happens only along the few seams that lead to the field's singular points).
One tile is ``scale_u`` millimetres (the parameterization is isotropic:
``scale_v`` is ignored).  The field is ``"smooth"`` (the globally smoothest
cross field: its orientation on a surface without features is arbitrary, on a
cylinder courses can come out helical), ``"curvature"``, or a direction that
the image's "up" follows (e.g. ``(0, 0, 1)`` for horizontal courses on
upright walls; it degenerates where the surface faces that direction).

``lapped``: the existing lapped-texture machinery
(:func:`geotex.image.lapped.lapped_texture`) pastes the height map, 2 x 2
tiles per patch, field-aligned (a global "up" direction projected on the
surface; default +z), so rows of bricks stay rows; one tile is ``scale_u``
millimetres.  Heights are the composited luminance.
"""

from __future__ import annotations

import numpy as np

from geotex.displace.heightmap import sample_periodic
from geotex.errors import InputError
from geotex.fields.directions import (principal_direction_field, projected_direction_field,
                                      smooth_direction_field)
from geotex.image.composite import composite_at, luminance
from geotex.image.lapped import lapped_texture
from geotex.image.patches import texture_patches
from geotex.param.pgp import periodic_parameterization

__all__ = ["pgp_corner_coordinates", "pgp_heights", "lapped_height_texture", "lapped_heights",
           "direction_vectors"]


def direction_vectors(V, F, field="smooth"):
    """A per-face direction (field) by name.

    Parameters
    ----------
    field : str or sequence of 3 floats
        ``"smooth"`` (the globally smoothest cross field), ``"curvature"``
        (maximal principal curvature directions) or a direction vector to
        project on every face.

    Returns
    -------
    DirectionField or numpy.ndarray, (m, 3)
    """
    if isinstance(field, str):
        if field == "smooth":
            return smooth_direction_field(V, F, symmetry=4, constraints=[], seed=0)
        if field == "curvature":
            return principal_direction_field(V, F).directions
        raise InputError(f"field must be 'smooth', 'curvature' or a direction X,Y,Z, got {field!r}")
    d = np.asarray(field, dtype=np.float64).ravel()
    if d.shape != (3,) or not np.isfinite(d).all() or not np.linalg.norm(d) > 0:
        raise InputError(f"field direction must be 3 finite numbers, not all 0, got {field!r}")
    vectors, _ = projected_direction_field(V, F, d)
    return vectors


def pgp_corner_coordinates(V, F, *, tile: float, field="smooth", seed: int = 0) -> np.ndarray:
    """Per-corner tile coordinates of the periodic global parameterization.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    tile : float
        Tile size (mm).
    field : str or sequence, optional
        See :func:`direction_vectors`.
    seed : int, optional

    Returns
    -------
    numpy.ndarray, (m, 3, 2) float64
    """
    # a direction or the curvature lines keep the image's "up" everywhere (half-turn
    # jumps only: a brick map is symmetric under those, not under quarter turns);
    # the smoothest cross field can only be combed by quarter turns
    p = periodic_parameterization(V, F, direction_vectors(V, F, field), scale=float(tile),
                                  seed=seed, symmetry=4 if field == "smooth" else 2)
    return np.asarray(p.coords, dtype=np.float64)


def pgp_heights(points, H, coords, *, offset=(0.0, 0.0), rotation: float = 0.0) -> np.ndarray:
    """Heights of refined vertices read through per-corner tile coordinates.

    Parameters
    ----------
    points : geotex.relief.ReliefPoints
    H : numpy.ndarray, (h, w) float32
    coords : numpy.ndarray, (m, 3, 2) float64
        Per base corner, tile units.
    offset : tuple of 2 floats, optional
        Tile units.
    rotation : float, optional
        Degrees.

    Returns
    -------
    numpy.ndarray, (p,) float64
    """
    T = np.einsum("pj,pjx->px", points.bary, coords[points.face])
    r = np.radians(rotation)
    c, s = np.cos(r), np.sin(r)
    u = c * T[:, 0] + s * T[:, 1] + offset[0]
    v = -s * T[:, 0] + c * T[:, 1] + offset[1]
    return sample_periodic(H, u, v)


def lapped_height_texture(V, F, H, *, tile: float, up=(0.0, 0.0, 1.0), seed: int = 0):
    """Paste a height map over a base with lapped textures, field-aligned.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    H : numpy.ndarray, (h, w) float
    tile : float
        Millimetres per image tile.
    up : sequence of 3 floats, optional
        Direction the image's "up" follows (projected per face).
    seed : int, optional

    Returns
    -------
    LappedTexture
    """

    img = np.tile(np.asarray(H, dtype=np.float64), (2, 2))
    rgb = np.repeat((np.clip(img, 0, 1) * 255).round().astype(np.uint8)[..., None], 3, axis=2)
    patches = texture_patches(rgb, mask="splotch", seed=seed)
    return lapped_texture(V, F, patches, field=direction_vectors(V, F, up), symmetry=1,
                          scale=2.0 * float(tile), seed=seed)


def lapped_heights(points, lapped) -> np.ndarray:
    """Composited luminance of a lapped texture at the refined vertices.

    Returns
    -------
    numpy.ndarray, (p,) float64
    """
    return luminance(composite_at(lapped, points.face, points.bary)[:, :3]).astype(np.float64)
