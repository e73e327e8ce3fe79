"""Texture extraction: displacement from a base shape -> pseudo-height and tilt."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt._kernels import cross
from geotex.heighttilt.base import (base_geometry, check_base_mesh, check_encoding, encode_on,
                                    smoothed_base)
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.mesh.arrays import as_vertices

__all__ = ["extract_texture", "displacement_to_height_tilt"]


def displacement_to_height_tilt(d: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pseudo-height and tilt vectors of displacements ``d`` over unit normals ``n``.

    Parameters
    ----------
    d, n : numpy.ndarray, (k, 3) float64

    Returns
    -------
    h : numpy.ndarray, (k,) float64
        ``sign(d . n) |d|`` with the paper's non-zero sign (sign(0) = +1).
    t : numpy.ndarray, (k, 3) float64
        ``(d / |d|) x n``, zero where ``|d| = 0``.  ``|t| = sin`` of the angle
        between ``d`` and ``n``.
    """
    length = np.linalg.norm(d, axis=1)
    sign = np.where(np.einsum("kd,kd->k", d, n) < 0, -1.0, 1.0)
    unit = np.divide(d, length[:, None], out=np.zeros_like(d), where=length[:, None] > 0)
    return sign * length, cross(unit, n)


def extract_texture(V0, F, *, base=None, steps: int = 3, time_step: float | None = None,
                    encode: str = "lsq", exact: bool = False
                    ) -> tuple[HeightTiltTexture, np.ndarray]:
    """Split a textured mesh into a base shape and a height-and-tilt texture.

    Parameters
    ----------
    V0 : array_like, (n, 3) float64
        Textured (detailed) mesh.
    F : array_like, (m, 3) int64
        Its faces, shared by the base.
    base : array_like, (n, 3) float64, optional
        Base vertex positions with the same connectivity.  Default:
        ``smoothed_base(V0, F, steps=steps, time_step=time_step)``.
    steps, time_step
        Passed to :func:`~geotex.heighttilt.base.smoothed_base` when ``base``
        is not given.
    encode : {"lsq", "edge"}, optional
        Tilt 1-form encoding, passed to
        :func:`~geotex.heighttilt.base.encode_tilt`: ``"lsq"`` (default) the
        paper's bounded least squares, ``"edge"`` the direct per-edge integral
        of the interpolated tilt (faster, but its 1-form alone loses much of
        the lean of sharp elements).  The round trip is exact either way: the
        residual holds what the 1-form misses.
    exact : bool, optional
        Passed to :func:`~geotex.heighttilt.base.encode_tilt` (minimum-norm
        correction so that the 1-form alone decodes to the tilt; slow).

    Returns
    -------
    tex : HeightTiltTexture
        ``d = V0 - Vs``, ``n`` the base normals (normalised mean of unit face
        normals of the base, :func:`~geotex.heighttilt.base.base_normals`),
        ``height = sign(d . n) |d|`` (sign(0) = +), tilt vectors
        ``t = d/|d| x n`` (zero where ``d = 0``) encoded as a 1-form plus a
        per-vertex residual (see :func:`~geotex.heighttilt.base.encode_tilt`),
        so that :func:`~geotex.heighttilt.reconstruct.apply_texture` gives
        back ``V0``.
    Vs : numpy.ndarray, (n, 3) float64
        The base used.

    Raises
    ------
    InputError
        Malformed arrays, empty mesh, zero-area faces or non-manifold edges
        (in ``V0`` when smoothing, in the base always), ``base`` of a different
        shape than ``V0``, an unknown ``encode``.

    Examples
    --------
    >>> from geotex.heighttilt.procedural import bumpy_plane
    >>> V0, F, Vs = bumpy_plane(8, 8, seed=0)
    >>> tex, _ = extract_texture(V0, F, base=Vs)
    >>> tex.height.shape
    (81,)
    """
    encode = check_encoding(encode)
    V0 = as_vertices(V0, name="V0")
    if V0.shape[0] == 0:
        raise InputError("V0 is empty: a textured mesh needs vertices")
    if base is None:
        V0, F = check_base_mesh(V0, F, name="V0")
        Vs = smoothed_base(V0, F, steps=steps, time_step=time_step)
    else:
        Vs = as_vertices(base, name="base")
        if Vs.shape != V0.shape:
            raise InputError(f"base must have the shape of V0 {V0.shape} (same connectivity), "
                             f"got {Vs.shape}")
    g = base_geometry(Vs, F, name="base")
    h, t = displacement_to_height_tilt(V0 - g.V, g.normals)
    c, r = encode_on(g, t, encode=encode, exact=bool(exact))
    tex = HeightTiltTexture._trusted(h, c, g.F, r, {"source": "extract_texture",
                                                      "encode": encode}, topology=g.topo)
    return tex, g.V.copy()
