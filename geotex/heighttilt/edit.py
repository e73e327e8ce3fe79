"""Edits of height-and-tilt textures (paper section 4.1): each returns a new texture.

Every edit takes an optional ``mask``: a per-vertex ``(n,)`` bool array or
weights in ``[0, 1]``.  With weights ``w`` the edited per-vertex quantity is
``(1 - w) old + w new`` (height values for :func:`scale_height`, tilt vectors
for the tilt edits), so ``w = 0`` leaves a vertex exactly as it was.

Tilt edits work on tilt vectors at the vertices: the current tilt is decoded
(:func:`geotex.heighttilt.base.decode_tilt`), the new one is computed and
blended, and the result is encoded again with
:func:`geotex.heighttilt.base.encode_tilt` (1-form plus residual, so the
vertex tilt after the edit is exactly the one requested).  A lean by angle
``a`` towards a unit tangent direction ``u`` is the tilt ``sin(a) (u x n)``:
the reconstructed displacement is then ``|h| (cos(a) n + sin(a) u)`` for
``h > 0``.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt.base import base_normals, decode_tilt, encode_tilt
from geotex.heighttilt.reconstruct import check_texture
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.options import finite_number

__all__ = ["scale_height", "set_tilt", "wrap", "wiggle"]


def _mask(mask, n: int) -> np.ndarray:
    if mask is None:
        return np.ones(n)
    m = np.asarray(mask)
    if m.shape != (n,):
        raise InputError(f"mask must have shape ({n},), one entry per vertex, got {m.shape}")
    if m.dtype == bool:
        return m.astype(np.float64)
    try:
        w = m.astype(np.float64)
    except (TypeError, ValueError):
        raise InputError("mask must be a bool array or numeric weights in [0, 1]") from None
    if not np.isfinite(w).all() or w.min() < 0 or w.max() > 1:
        raise InputError("mask weights must be finite and in [0, 1]")
    return w


def _lean_dirs(Vs, F, nrm, direction, current) -> np.ndarray:
    """Unit tangent lean directions per vertex (zero where undefined)."""
    n, m = Vs.shape[0], F.shape[0]
    if direction is None:
        u = np.cross(nrm, current)                         # lean direction of current tilt
    else:
        try:
            d = np.asarray(direction, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError("direction must be None, a (3,) vector or an (n, 3) or (m, 3) "
                             "field") from None
        if d.shape == (3,):
            if np.isfinite(d).all() and not np.any(d):
                raise InputError("direction must be a non-zero vector, got (0, 0, 0)")
            u = np.broadcast_to(d, (n, 3)).copy()
        elif d.shape == (n, 3):
            u = d.copy()
        elif d.shape == (m, 3):                            # per face: average to vertices
            u = np.zeros((n, 3))
            for k in range(3):
                u[:, k] = np.bincount(F.ravel(), weights=np.repeat(d[:, k], 3), minlength=n)
        else:
            raise InputError(f"direction must be None, a (3,) vector or an ({n}, 3) or "
                             f"({m}, 3) field, got shape {d.shape}")
        if not np.isfinite(u).all():
            raise InputError("direction has non-finite values")
    u = u - np.einsum("nd,nd->n", u, nrm)[:, None] * nrm
    ln = np.linalg.norm(u, axis=1, keepdims=True)
    return np.divide(u, ln, out=np.zeros_like(u), where=ln > 1e-12)


def _retilt(Vs, F, tex, new_tilt, w, meta) -> HeightTiltTexture:
    cur = decode_tilt(Vs, F, tex.tilt, tex.residual)
    t = (1.0 - w)[:, None] * cur + w[:, None] * new_tilt
    c, r = encode_tilt(Vs, F, t)
    return tex.replace(tilt=c, residual=r, metadata={**tex.metadata, "edit": meta})


def scale_height(tex: HeightTiltTexture, s, *, mask=None) -> HeightTiltTexture:
    """Scale the pseudo-heights: ``h' = h ((1 - w) + w s)``.

    Parameters
    ----------
    tex : HeightTiltTexture
    s : float
        Scale factor (negative flips the texture through the base).
    mask : array_like, (n,) bool or float, optional
        Per-vertex weights ``w`` (default all 1).

    Returns
    -------
    HeightTiltTexture
        Same tilt and residual, new heights.

    Raises
    ------
    InputError
        Non-texture, non-finite ``s``, malformed mask.
    """
    if not isinstance(tex, HeightTiltTexture):
        raise InputError(f"tex must be a HeightTiltTexture, got {type(tex).__name__}")
    s = finite_number(s, name="s")
    w = _mask(mask, tex.n_vertices)
    return tex.replace(height=tex.height * ((1.0 - w) + w * s),
                       metadata={**tex.metadata, "edit": f"scale_height({s!r})"})


def set_tilt(Vs, F, tex: HeightTiltTexture, *, angle_degrees, direction=None,
             mask=None) -> HeightTiltTexture:
    """Make every displacement lean by a fixed angle from the base normal.

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
        Base the texture belongs to.
    F : array_like, (m, 3) int64
    tex : HeightTiltTexture
    angle_degrees : float
        Lean angle in ``[0, 90]``.
    direction : None, array_like (3,), (n, 3) or (m, 3), optional
        Lean direction: one non-zero vector for all, per vertex, or per face
        (summed at the vertices); projected onto each tangent plane (where
        it is normal to the surface, or a field vector is zero, the vertex
        gets no tilt).  ``None`` keeps each vertex's current lean direction
        (vertices without tilt stay untilted).  If ``n == m`` an array of
        that length is taken per vertex.
    mask : array_like, (n,), optional
        Per-vertex weights.

    Returns
    -------
    HeightTiltTexture
        Tilt ``sin(a) (u x n)`` at every vertex with a defined direction
        ``u`` (zero tilt where ``u`` is undefined), blended by the mask.

    Raises
    ------
    InputError
        Connectivity mismatch, angle outside ``[0, 90]``, bad direction (wrong
        shape, non-finite, the zero vector) or mask.
    """
    Vs, F = check_texture(Vs, F, tex)
    a = finite_number(angle_degrees, name="angle_degrees")
    if not 0.0 <= a <= 90.0:
        raise InputError(f"angle_degrees must be in [0, 90], got {angle_degrees!r}")
    w = _mask(mask, Vs.shape[0])
    nrm = base_normals(Vs, F)
    cur = decode_tilt(Vs, F, tex.tilt, tex.residual)
    u = _lean_dirs(Vs, F, nrm, direction, cur)
    new = np.sin(np.radians(a)) * np.cross(u, nrm)
    return _retilt(Vs, F, tex, new, w, f"set_tilt({a!r})")


def wrap(Vs, F, tex: HeightTiltTexture, *, k, direction=None, mask=None) -> HeightTiltTexture:
    """Bend the texture: the lean angle grows with the height, ``a = clip(k |h|, 0, pi/2)``.

    Parameters
    ----------
    Vs, F, tex
        As in :func:`set_tilt`.
    k : float
        Radians of lean per unit of height (``k >= 0``); tips (large ``|h|``)
        bend most, so spikes curl.  Scale with ``1 / size`` of the texture
        to keep the look under uniform scaling.
    direction, mask
        As in :func:`set_tilt`.

    Returns
    -------
    HeightTiltTexture

    Raises
    ------
    InputError
        Connectivity mismatch, negative ``k``, bad direction or mask.
    """
    Vs, F = check_texture(Vs, F, tex)
    k = finite_number(k, name="k")
    if k < 0:
        raise InputError(f"k must be >= 0, got {k!r}")
    w = _mask(mask, Vs.shape[0])
    nrm = base_normals(Vs, F)
    cur = decode_tilt(Vs, F, tex.tilt, tex.residual)
    u = _lean_dirs(Vs, F, nrm, direction, cur)
    a = np.clip(k * np.abs(tex.height), 0.0, np.pi / 2)
    new = np.sin(a)[:, None] * np.cross(u, nrm)
    return _retilt(Vs, F, tex, new, w, f"wrap({k!r})")


def wiggle(Vs, F, tex: HeightTiltTexture, *, amplitude, phase, direction,
           wavelength=None, mask=None) -> HeightTiltTexture:
    """Travelling wave of lean along a direction, for animation.

    At vertex ``v`` the lean angle is
    ``a_v = amplitude * sin(2 pi s_v / wavelength - phase)`` towards the
    tangent projection of the unit ``w``, where ``s_v = <Vs_v, w> - min_u <Vs_u, w>``
    is the distance along ``w`` from the base's first point in that direction
    (so the wave does not depend on where the base sits); stepping ``phase``
    over time moves the wave along ``w``.

    Parameters
    ----------
    Vs, F, tex
        As in :func:`set_tilt`.
    amplitude : float
        Maximum lean in degrees, ``[0, 90]``.
    phase : float
        Radians (the time parameter).
    direction : array_like, (3,)
        Wave (and lean) direction ``w``.
    wavelength : float, optional
        Default: a quarter of the extent of ``Vs`` along ``w`` (four waves
        across the base, whatever its position, orientation and size).
    mask : array_like, (n,), optional

    Returns
    -------
    HeightTiltTexture

    Raises
    ------
    InputError
        Connectivity mismatch, bad amplitude, direction, wavelength or mask.
    """
    Vs, F = check_texture(Vs, F, tex)
    amp = finite_number(amplitude, name="amplitude")
    if not 0.0 <= amp <= 90.0:
        raise InputError(f"amplitude must be in [0, 90] degrees, got {amplitude!r}")
    ph = finite_number(phase, name="phase")
    try:
        wdir = np.asarray(direction, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("direction must be a (3,) vector") from None
    if wdir.shape != (3,) or not np.isfinite(wdir).all() or np.linalg.norm(wdir) == 0:
        raise InputError(f"direction must be a finite non-zero (3,) vector, got {direction!r}")
    wdir = wdir / np.linalg.norm(wdir)
    along = Vs @ wdir
    if wavelength is None:
        lam = 0.25 * float(np.ptp(along))
        if not lam > 0:
            raise InputError("the base has no extent along direction; give a wavelength")
    else:
        lam = finite_number(wavelength, name="wavelength")
        if lam <= 0:
            raise InputError(f"wavelength must be > 0, got {wavelength!r}")
    w = _mask(mask, Vs.shape[0])
    nrm = base_normals(Vs, F)
    u = _lean_dirs(Vs, F, nrm, wdir, None)
    a = np.radians(amp) * np.sin(2 * np.pi * (along - along.min()) / lam - ph)
    new = np.sin(a)[:, None] * np.cross(u, nrm)
    return _retilt(Vs, F, tex, new, w, f"wiggle({amp!r}, {ph!r})")
