"""A tileable image laid over a mesh through a periodic global parameterization.

The per-corner tile coordinates ``(s, t)`` of
:func:`geotex.param.pgp.periodic_parameterization` become texture
coordinates directly (one image period per tile, the image repeated), so no
atlas is resampled: across every non-singular edge the two sides' coordinates
differ by a grid symmetry (an integer translation, a rotation by a multiple of
90 degrees), which a tileable image with the square's symmetry maps to the
same colours.  An image that is periodic but not symmetric under a quarter
turn (bricks) shows its rotation where the cross field's combing turns.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.record import Mesh

__all__ = ["tiled_texture_mesh"]


def tiled_texture_mesh(V, F, coords, image, *, name: str = "geotex") -> Mesh:
    """A textured mesh whose texture coordinates are the PGP tile coordinates.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    coords : array_like, (m, 3, 2) float64
        ``(s, t)`` per face corner in tile units
        (:attr:`~geotex.param.pgp.PeriodicParameterization.coords`).
    image : numpy.ndarray, (h, w, 3 or 4) uint8
        The tileable image: one period per tile, ``t`` upwards.
    name : str, optional

    Returns
    -------
    Mesh
        With ``uv`` (3m, 2), ``uv_faces`` (m, 3) and ``texture``; written by
        :func:`geotex.io.write_mesh` as GLB (repeat sampler) or OBJ + MTL + PNG.

    Raises
    ------
    InputError
        If ``coords`` does not have one row per face, or is not finite.
    """
    V, F = as_mesh_arrays(V, F)
    coords = np.asarray(coords, dtype=np.float64)
    m = F.shape[0]
    if coords.shape != (m, 3, 2):
        raise InputError(f"coords must have shape ({m}, 3, 2) (one (s, t) per face corner), "
                         f"got {coords.shape}")
    if not np.isfinite(coords).all():
        raise InputError("coords has non-finite tile coordinates")
    uv = coords.reshape(-1, 2)
    uv_faces = np.arange(3 * m, dtype=np.int64).reshape(m, 3)
    return Mesh(V, F, uv=uv, uv_faces=uv_faces, texture=np.asarray(image), name=name)
