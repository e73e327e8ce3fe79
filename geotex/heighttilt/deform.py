"""Reapplying a height-and-tilt texture to a deformed base (paper section 4.2).

The base shape is deformed (bent, twisted, resized) with its connectivity
kept, and the texture is put back on it, so that texture elements keep their
size and shape instead of being distorted by the space deformation.

Why the tilt coefficients are rescaled
--------------------------------------
Heights are lengths: they are applied as they are.  A tilt coefficient is a
line integral of the (dimensionless) tilt field along its edge,
``c_e = int_e <t, dp> = |e| <t_e, e/|e|>`` with ``t_e`` the mean tilt along
``e``.  For a texture element to keep its lean angle (``|t| = sin(alpha)``)
and its lean direction relative to the surrounding edges, the deformed edge
``e'`` must see the same tangential component along its own direction,
``<t', e'/|e'|> = <t, e/|e|>``, hence

    ``c_e' = c_e |e'| / |e|``.

Under a uniform scaling by ``s`` (with any rigid motion) every ratio is ``s``
and the Whitney gradients scale by ``1/s``, so the decoded vertex tilt is the
original one rotated with the mesh: the angles are kept exactly.  Under a
non-uniform deformation (a bend stretches the outer side and compresses the
inner side) the rescaled 1-form decodes to a tilt that differs from the
original by an amount of the order of the local strain.  :func:`reapplied`
therefore also recomputes the per-vertex residual of the texture
(:func:`geotex.heighttilt.base.encode_tilt`) so that the decoded tilt is the
original vertex tilt carried into the deformed vertex frame: its components
along the intrinsic frames ``(T1, T2)`` of
:func:`geotex.heighttilt.base.tilt_frames` (built from the 1-form itself:
``T1`` along its decoded direction) are kept.  The lean angle of every
vertex is then kept to round-off and its lean direction is kept relative to
the direction the carried 1-form decodes to.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt.base import decode_tilt, tilt_frames
from geotex.heighttilt.reconstruct import apply_texture, check_texture
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.mesh.arrays import as_mesh_arrays, as_vertices
from geotex.mesh.topology import edge_topology
from geotex.options import finite_number

__all__ = ["deformed_texture", "reapplied", "bend", "twist", "scale_base",
           "naive_space_deformation"]


def _span(u: np.ndarray, origin, length) -> tuple[float, float]:
    """Start and length of a deformation along ``u`` (default: the range of ``u``)."""
    u0 = float(u.min()) if origin is None else finite_number(origin, name="origin")
    L = float(u.max() - u.min()) if length is None else finite_number(length, name="length")
    if not L > 0:
        raise InputError(f"length must be positive, got {L!r}")
    return u0, L


def _axis(name, value) -> int:
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer))
            or not 0 <= value <= 2):
        raise InputError(f"{name} must be 0, 1 or 2 (x, y or z), got {value!r}")
    return int(value)


def deformed_texture(Vs, Vs_deformed, F, tex: HeightTiltTexture) -> HeightTiltTexture:
    """The texture to put on a deformed base so that lean angles are kept.

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
        The base the texture was extracted on.
    Vs_deformed : array_like, (n, 3) float64
        The deformed base, same connectivity.
    F : array_like, (m, 3) int64
        Must equal ``tex.faces``.
    tex : HeightTiltTexture

    Returns
    -------
    HeightTiltTexture
        Same heights; tilt coefficients ``c_e |e'| / |e|``; residual such that
        the decoded tilt on ``Vs_deformed`` has, at every vertex, the
        components along the deformed :func:`~geotex.heighttilt.base.tilt_frames`
        that the original decoded tilt had along the original frames (see the
        module docstring).

    Raises
    ------
    InputError
        Connectivity mismatch, empty, zero-area or non-manifold bases, or an
        edge of zero length in ``Vs``.
    """
    Vb, F = check_texture(Vs, F, tex)
    Vd, _ = check_texture(Vs_deformed, F, tex)
    topo = edge_topology(F, Vb.shape[0])
    E = topo.edges
    l0 = np.linalg.norm(Vb[E[:, 1]] - Vb[E[:, 0]], axis=1)
    l1 = np.linalg.norm(Vd[E[:, 1]] - Vd[E[:, 0]], axis=1)
    if np.any(l0 <= 0):
        raise InputError("Vs has zero-length edges: the tilt rescaling |e'|/|e| is undefined")
    c = tex.tilt * (l1 / l0)
    t0 = decode_tilt(Vb, F, tex.tilt, tex.residual, topology=topo)
    _, T1, T2 = tilt_frames(Vb, F, tex.tilt)
    a = np.einsum("nd,nd->n", t0, T1)
    b = np.einsum("nd,nd->n", t0, T2)
    _, S1, S2 = tilt_frames(Vd, F, c)
    target = a[:, None] * S1 + b[:, None] * S2
    miss = target - decode_tilt(Vd, F, c, topology=topo)
    r = np.column_stack([np.einsum("nd,nd->n", miss, S1), np.einsum("nd,nd->n", miss, S2)])
    meta = dict(tex.metadata)
    meta["deformed"] = True
    return tex.replace(tilt=c, residual=r, metadata=meta)


def reapplied(Vs_deformed, F, tex: HeightTiltTexture, *, base=None,
              keep_angles: bool = True) -> np.ndarray:
    """Apply a texture to a deformed base so that its elements keep size and shape.

    Parameters
    ----------
    Vs_deformed : array_like, (n, 3) float64
        Deformed base with the texture's connectivity.
    F : array_like, (m, 3) int64
        Must equal ``tex.faces``.
    tex : HeightTiltTexture
        Texture extracted on ``base``.
    base : array_like, (n, 3) float64, optional
        The undeformed base the texture was extracted on; required with
        ``keep_angles=True`` (the tilt rescaling needs the original edge
        lengths, which the texture does not store).
    keep_angles : bool, optional
        ``True`` (default): use :func:`deformed_texture` (tilt coefficients
        rescaled by ``|e'|/|e|``, residual recomputed) so every element keeps
        its height and its lean angle.  ``False``: apply the stored
        coefficients as they are (heights kept, but on a base scaled by ``s``
        the tilts, hence ``sin`` of the lean angles, become ``1/s`` as large).

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Textured deformed mesh; ``|V - Vs_deformed| = |h|`` per vertex.

    Raises
    ------
    InputError
        Connectivity mismatch, bad bases, or ``keep_angles=True`` without
        ``base``.

    Examples
    --------
    >>> from geotex.heighttilt import tentacle_stick, extract_texture
    >>> V0, F, Vs = tentacle_stick(n_along=24, suckers=4, seed=0)
    >>> tex, _ = extract_texture(V0, F, base=Vs)
    >>> V = reapplied(bend(Vs, angle=1.0), F, tex, base=Vs)
    >>> V.shape == V0.shape
    True
    """
    if not keep_angles:
        return apply_texture(Vs_deformed, F, tex)
    if base is None:
        raise InputError("base (the undeformed base of tex) is required with keep_angles=True")
    t2 = deformed_texture(base, Vs_deformed, F, tex)
    return apply_texture(Vs_deformed, F, t2)


def bend(V, *, angle, axis: int = 2, toward: int | None = None, origin: float | None = None,
         length: float | None = None) -> np.ndarray:
    """Bend points around a circular arc (a space deformation).

    The coordinate ``u = V[:, axis]`` runs along the bent object and
    ``w = V[:, toward]`` is the bending direction.  Points at ``w = 0`` go
    onto a circle of radius ``R = length / angle`` centred at
    ``(u, w) = (origin, R)``; a point at ``(u, w)`` goes to
    ``u' = origin + (R - w) sin(phi)``, ``w' = R - (R - w) cos(phi)`` with
    ``phi = (u - origin) / R``.  The line ``w = 0`` keeps its length, the side
    ``w < 0`` (outer) is stretched by ``(R - w) / R`` along ``u`` and the
    side ``w > 0`` compressed; the third coordinate is unchanged.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    angle : float
        Total bending angle in radians over ``length`` (0 returns a copy;
        negative bends the other way).
    axis : int, optional
        Axis along the object (0, 1, 2 for x, y, z; default z).
    toward : int, optional
        Bending direction axis (default ``(axis + 1) % 3``); must differ from
        ``axis``.
    origin, length : float, optional
        Where the bend starts along ``axis`` and over what length it turns by
        ``angle``; default the range of ``V[:, axis]``.

    Returns
    -------
    numpy.ndarray, (n, 3) float64

    Raises
    ------
    InputError
        Malformed ``V``, bad axes, non-finite values or a non-positive length.
    """
    V = as_vertices(V)
    axis = _axis("axis", axis)
    toward = (axis + 1) % 3 if toward is None else _axis("toward", toward)
    if toward == axis:
        raise InputError(f"toward must differ from axis, both are {axis}")
    ang = finite_number(angle, name="angle")
    out = V.copy()
    if V.shape[0] == 0 or ang == 0.0:
        return out
    u = V[:, axis]
    u0, L = _span(u, origin, length)
    R = L / ang
    w = V[:, toward]
    phi = (u - u0) / R
    out[:, axis] = u0 + (R - w) * np.sin(phi)
    out[:, toward] = R - (R - w) * np.cos(phi)
    return out


def twist(V, *, turns, axis: int = 2, origin: float | None = None,
          length: float | None = None) -> np.ndarray:
    """Twist points about a coordinate axis (a space deformation).

    A point at ``u = V[:, axis]`` is rotated about the axis (through the
    coordinate origin) by ``2 pi turns (u - origin) / length``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    turns : float
        Full turns over ``length`` (0 returns a copy).
    axis : int, optional
        0, 1 or 2 (default z).
    origin, length : float, optional
        Default: the minimum and the range of ``V[:, axis]``.

    Returns
    -------
    numpy.ndarray, (n, 3) float64

    Raises
    ------
    InputError
        Malformed ``V``, a bad axis, non-finite values or a non-positive length.
    """
    V = as_vertices(V)
    axis = _axis("axis", axis)
    tr = finite_number(turns, name="turns")
    out = V.copy()
    if V.shape[0] == 0 or tr == 0.0:
        return out
    u = V[:, axis]
    u0, L = _span(u, origin, length)
    a, b = (axis + 1) % 3, (axis + 2) % 3
    th = 2.0 * np.pi * tr * (u - u0) / L
    c, s = np.cos(th), np.sin(th)
    out[:, a] = c * V[:, a] - s * V[:, b]
    out[:, b] = s * V[:, a] + c * V[:, b]
    return out


def scale_base(V, s, *, center=None) -> np.ndarray:
    """Scale points uniformly by ``s`` about ``center`` (default: their centroid).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    s : float
        Positive factor.
    center : array_like, (3,) float64, optional

    Returns
    -------
    numpy.ndarray, (n, 3) float64

    Raises
    ------
    InputError
        Malformed ``V`` or ``center``, or a non-positive ``s``.
    """
    V = as_vertices(V)
    f = finite_number(s, name="s")
    if not f > 0:
        raise InputError(f"s must be a positive number, got {s!r}")
    if center is None:
        c = V.mean(axis=0) if V.shape[0] else np.zeros(3)
    else:
        try:
            c = np.asarray(center, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError("center must be a (3,) point") from None
        if c.shape != (3,) or not np.isfinite(c).all():
            raise InputError(f"center must be a finite (3,) point, got shape {c.shape}")
    return c + f * (V - c)


def naive_space_deformation(V0_detailed, Vs, Vs_deformed, F) -> np.ndarray:
    """Baseline: move every detailed vertex by its base vertex's displacement.

    ``V = V0 + (Vs_deformed - Vs)``: the displacement vectors ``V0 - Vs`` are
    carried over unchanged (not rotated with the surface, not rescaled), which
    is what a per-vertex space deformation does to details at the scale of the
    base.  For the other baseline, applying the space map itself to the
    detailed mesh, call the map on ``V0`` (e.g. ``bend(V0, ...)`` with the
    parameters used for the base).

    Parameters
    ----------
    V0_detailed, Vs, Vs_deformed : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        Shared connectivity (validated only).

    Returns
    -------
    numpy.ndarray, (n, 3) float64

    Raises
    ------
    InputError
        Malformed arrays or different vertex counts.
    """
    V0, F = as_mesh_arrays(V0_detailed, F)
    A = as_vertices(Vs, name="Vs")
    B = as_vertices(Vs_deformed, name="Vs_deformed")
    if A.shape != V0.shape or B.shape != V0.shape:
        raise InputError(f"Vs and Vs_deformed must have the shape of V0_detailed {V0.shape}, "
                         f"got {A.shape} and {B.shape}")
    return V0 + (B - A)
