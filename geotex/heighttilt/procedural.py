"""Procedural textured meshes (detailed mesh + base with the same connectivity)."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt.base import base_normals
from geotex.mesh.primitives import grid_plane, icosphere
from geotex.options import count, positive_number

__all__ = ["spiky_sphere", "bumpy_plane", "tentacle_stick"]


def _lean(name, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number of degrees in [0, 90), got {value!r}") from None
    if not (0.0 <= v < 90.0):
        raise InputError(f"{name} must be a number of degrees in [0, 90), got {value!r}")
    return np.radians(v)


def _lean_displacement(profile, height, n, direction, lean):
    """``height * profile * (cos(a) n + sin(a) u)``, ``u`` = direction made tangent."""
    u = direction - np.einsum("kd,kd->k", direction, n)[:, None] * n
    un = np.linalg.norm(u, axis=1, keepdims=True)
    u = np.divide(u, un, out=np.zeros_like(u), where=un > 1e-12)
    a = lean * profile
    return (height * profile)[:, None] * (np.cos(a)[:, None] * n + np.sin(a)[:, None] * u)


def spiky_sphere(*, spikes: int = 24, lean_degrees: float = 60.0, subdivisions: int = 4,
                 height: float = 0.4, width: float = 0.18, seed=None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A unit icosphere with leaning spikes that overhang the base.

    Every spike is a smooth bump of angular radius ``width`` (radians) around
    a random centre; its vertices are displaced by ``height * p`` with ``p``
    the bump profile (1 at the centre) along the normal tilted by
    ``lean * p`` towards the spike's random lean direction.  With the
    defaults the tip moves ``height * sin(lean) ~ 0.35`` sideways, farther
    than the spike's base radius, so the spike overhangs: no height field over
    the base can represent it.

    Parameters
    ----------
    spikes : int, optional
    lean_degrees : float, optional
        In ``[0, 90)``.
    subdivisions : int, optional
        Icosphere level (``20 * 4**k`` faces).
    height, width : float, optional
    seed : int or numpy.random.Generator, optional

    Returns
    -------
    V0 : numpy.ndarray, (n, 3) float64
        Spiky mesh.
    F : numpy.ndarray, (m, 3) int64
    Vs : numpy.ndarray, (n, 3) float64
        The sphere (base).

    Raises
    ------
    InputError
        On non-positive counts or sizes, or a lean outside ``[0, 90)``.
    """
    spikes = count(spikes, name="spikes")
    lean = _lean("lean_degrees", lean_degrees)
    height = positive_number(height, name="height")
    width = positive_number(width, name="width")
    Vs, F = icosphere(count(subdivisions, name="subdivisions", minimum=0))
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(spikes, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    dirs = rng.normal(size=(spikes, 3))
    n = base_normals(Vs, F)
    ang = np.arccos(np.clip(Vs @ centres.T, -1.0, 1.0))             # (n, spikes)
    prof = np.clip(1.0 - (ang / width) ** 2, 0.0, None) ** 2
    owner = np.argmax(prof, axis=1)
    p = prof[np.arange(Vs.shape[0]), owner]
    d = _lean_displacement(p, height, n, dirs[owner], lean)
    return Vs + d, F, Vs


def bumpy_plane(nx: int = 32, ny: int = 32, *, bumps: int = 12, height: float = 0.08,
                radius: float = 0.09, lean_degrees: float = 30.0, seed=None,
                periodic: bool = False, direction=None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A unit grid plane with random (leaning) bumps.

    Parameters
    ----------
    nx, ny : int
        Grid cells along x and y.
    bumps : int, optional
    height, radius : float, optional
        Bump height and radius (plane units).
    lean_degrees : float, optional
        Tilt of the bump tops towards a random direction, in ``[0, 90)``.
    seed : int or numpy.random.Generator, optional
    periodic : bool, optional
        ``False`` (default): bump centres in ``[0.1, 0.9]^2``, distances in the
        plane.  ``True``: centres anywhere in ``[0, 1)^2`` and distances on the
        unit torus (the shortest way around in x and y), so the texture tiles
        the plane seamlessly with period 1: the opposite borders carry the
        same heights and leans (as used by
        :func:`geotex.heighttilt.planar.transfer_planar`).  Needs
        ``radius < 0.5``.
    direction : array_like (2,), optional
        Lean every bump towards this ``(x, y)`` direction instead of a random
        one (the random draws are the same, so only the leans change).

    Returns
    -------
    V0, F, Vs
        Bumpy mesh, faces (open mesh, normals +z), flat base.

    Raises
    ------
    InputError
        On non-positive counts or sizes.
    """
    Vs, F = grid_plane(count(nx, name="nx"), count(ny, name="ny"))
    bumps = count(bumps, name="bumps")
    height = positive_number(height, name="height")
    radius = positive_number(radius, name="radius")
    lean = _lean("lean_degrees", lean_degrees)
    if periodic and radius >= 0.5:
        raise InputError(f"radius must be below 0.5 for a periodic plane, got {radius!r}")
    if direction is not None:
        try:
            lean_dir = np.asarray(direction, dtype=np.float64).reshape(2)
        except (TypeError, ValueError):
            raise InputError(f"direction must be two numbers (x, y), got {direction!r}") from None
        if not (np.isfinite(lean_dir).all() and np.linalg.norm(lean_dir) > 0):
            raise InputError(f"direction must be a finite non-zero (x, y), got {direction!r}")
    rng = np.random.default_rng(seed)
    centres = (rng.uniform(0.0, 1.0, size=(bumps, 2)) if periodic
               else rng.uniform(0.1, 0.9, size=(bumps, 2)))
    dirs = np.column_stack([rng.normal(size=(bumps, 2)), np.zeros(bumps)])
    if direction is not None:
        dirs[:, :2] = lean_dir
    delta = Vs[:, None, :2] - centres[None]
    if periodic:
        delta -= np.round(delta)
    r = np.linalg.norm(delta, axis=2)
    prof = np.clip(1.0 - (r / radius) ** 2, 0.0, None) ** 2
    owner = np.argmax(prof, axis=1)
    p = prof[np.arange(Vs.shape[0]), owner]
    n = np.tile([0.0, 0.0, 1.0], (Vs.shape[0], 1))
    return Vs + _lean_displacement(p, height, n, dirs[owner], lean), F, Vs


def tentacle_stick(*, length: float = 3.0, radius: float = 0.25, n_around: int = 24,
                   n_along: int = 72, suckers: int = 30, height: float = 0.12,
                   size: float = 0.14, lean_degrees: float = 45.0, seed=None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An open cylindrical stick along z carrying tentacles that lean towards +z.

    Parameters
    ----------
    length, radius : float, optional
        Cylinder size; its axis runs from ``z = 0`` to ``z = length``.
    n_around, n_along : int, optional
        Quads around and along (each split into two triangles).
    suckers : int, optional
        Number of tentacles (bumps), placed at random away from the ends.
    height, size : float, optional
        Tentacle length and base radius.
    lean_degrees : float, optional
        Lean towards +z (along the stick), in ``[0, 90)``.
    seed : int or numpy.random.Generator, optional

    Returns
    -------
    V0, F, Vs
        Textured stick, faces (outward, open at both ends), base cylinder.

    Raises
    ------
    InputError
        On non-positive counts or sizes.
    """
    length = positive_number(length, name="length")
    radius = positive_number(radius, name="radius")
    na = count(n_around, name="n_around", minimum=3)
    nl = count(n_along, name="n_along")
    suckers = count(suckers, name="suckers")
    height = positive_number(height, name="height")
    size = positive_number(size, name="size")
    lean = _lean("lean_degrees", lean_degrees)
    th = 2 * np.pi * np.arange(na) / na
    z = np.linspace(0.0, length, nl + 1)
    tt, zz = np.meshgrid(th, z, indexing="ij")                           # (na, nl+1)
    Vs = np.stack([radius * np.cos(tt), radius * np.sin(tt), zz], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(na), np.arange(nl), indexing="ij")
    a = i * (nl + 1) + j
    b = ((i + 1) % na) * (nl + 1) + j
    F = np.concatenate([np.stack([a, b, b + 1], -1).reshape(-1, 3),
                        np.stack([a, b + 1, a + 1], -1).reshape(-1, 3)]).astype(np.int64)
    rng = np.random.default_rng(seed)
    ct = rng.uniform(0, 2 * np.pi, suckers)
    cz = rng.uniform(0.1 * length, 0.9 * length, suckers)
    C = np.column_stack([radius * np.cos(ct), radius * np.sin(ct), cz])
    dist = np.linalg.norm(Vs[:, None, :] - C[None], axis=2)
    prof = np.clip(1.0 - (dist / size) ** 2, 0.0, None) ** 2
    owner = np.argmax(prof, axis=1)
    p = prof[np.arange(Vs.shape[0]), owner]
    n = base_normals(Vs, F)
    up = np.tile([0.0, 0.0, 1.0], (Vs.shape[0], 1))
    return Vs + _lean_displacement(p, height, n, up, lean), F, Vs
