"""Texture reconstruction: base shape + height-and-tilt texture -> textured mesh."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt._kernels import BaseGeometry, cross, dot
from geotex.heighttilt.base import base_geometry, decode_on
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.mesh.arrays import as_mesh_arrays

__all__ = ["apply_texture", "displacements", "check_texture"]


def check_texture(Vs, F, tex) -> tuple[np.ndarray, np.ndarray]:
    """Validate that ``tex`` belongs to the base mesh ``(Vs, F)``; return arrays."""
    g = texture_base(Vs, F, tex)
    return g.V, g.F


def texture_base(Vs, F, tex) -> BaseGeometry:
    """:func:`check_texture` returning the validated base geometry."""
    if not isinstance(tex, HeightTiltTexture):
        raise InputError(f"tex must be a HeightTiltTexture, got {type(tex).__name__}")
    V, F = as_mesh_arrays(Vs, F)
    if V.shape[0] != tex.n_vertices:
        raise InputError(f"Vs has {V.shape[0]} vertices but tex has {tex.n_vertices}: "
                         "connectivity mismatch")
    if F.shape != tex.faces.shape or not np.array_equal(F, tex.faces):
        raise InputError("F differs from tex.faces: connectivity mismatch")
    # a texture made by extraction or transfer remembers the edge topology of its faces
    return base_geometry(V, F, name="Vs", topology=tex.__dict__.get("_topology"))


def displacements(Vs, F, tex: HeightTiltTexture) -> np.ndarray:
    """Per-vertex displacement vectors of a texture over a base.

    The tilt ``t`` is decoded at the vertices (Whitney average of the 1-form,
    projected onto the base tangent plane, plus the stored residual), clamped
    to ``|t| <= 1``, and the displacement direction is the base normal ``n``
    tilted by ``alpha`` with ``sin(alpha) = |t|``,
    ``cos(alpha) = sign(h) sqrt(1 - |t|^2)``:
    ``u = sign(h) sqrt(1 - |t|^2) n + n x t``.  This is the rotation of ``n``
    about the axis ``t`` by ``-alpha`` (Rodrigues), the exact inverse of the
    definition ``t = d/|d| x n``: ``n x t`` is the tangential part of
    ``d/|d|``.  (The paper words the axis as ``n x t``; rotating about that
    axis would lean the displacement along ``t`` instead of along ``n x t``
    and would not invert the extraction, so geotex rotates about ``t``.)

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    tex : HeightTiltTexture

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        ``|h| u``.

    Raises
    ------
    InputError
        See :func:`apply_texture`.
    """
    return _displacements(texture_base(Vs, F, tex), tex)


def _displacements(g: BaseGeometry, tex: HeightTiltTexture) -> np.ndarray:
    n = g.normals
    t = decode_on(g, tex.tilt, tex.residual)
    mag2 = dot(t, t)
    big = mag2 > 1.0
    if big.any():
        t[big] /= np.sqrt(mag2[big])[:, None]
        mag2[big] = dot(t[big], t[big])
    s2 = np.clip(1.0 - mag2, 0.0, 1.0)
    sign = np.where(tex.height < 0, -1.0, 1.0)
    u = (sign * np.sqrt(s2))[:, None] * n + cross(n, t)
    return np.abs(tex.height)[:, None] * u


def apply_texture(Vs, F, tex: HeightTiltTexture) -> np.ndarray:
    """Put a height-and-tilt texture back onto a base shape.

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
        Base positions (the extraction base, or a deformed/resized copy with
        the same connectivity).
    F : array_like, (m, 3) int64
        Must equal ``tex.faces``.
    tex : HeightTiltTexture

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        ``Vs + displacements(Vs, F, tex)``; see :func:`displacements`.
        On the extraction base this reproduces the textured mesh to round-off.
        Heights are lengths and are applied as they are, so texture elements
        keep their size on a resized base; the tilt coefficients are line
        integrals of a dimensionless field, so on a base uniformly scaled by
        ``s`` the same coefficients decode to tilts ``1/s`` as large: pass
        ``tex.replace(tilt=s * tex.tilt)`` to keep the lean angles.

    Raises
    ------
    InputError
        Texture of another connectivity (vertex count or faces differ),
        empty mesh, zero-area or non-manifold base.

    Examples
    --------
    >>> from geotex.heighttilt.procedural import spiky_sphere
    >>> from geotex.heighttilt.extract import extract_texture
    >>> V0, F, Vs = spiky_sphere(subdivisions=2, spikes=6, seed=1)
    >>> tex, _ = extract_texture(V0, F, base=Vs)
    >>> bool(abs(apply_texture(Vs, F, tex) - V0).max() < 1e-9)
    True
    """
    g = texture_base(Vs, F, tex)
    return g.V + _displacements(g, tex)
