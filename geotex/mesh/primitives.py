"""Closed, outward-oriented primitive meshes built with numpy."""

from __future__ import annotations

import igl
import numpy as np

from geotex.errors import InputError

__all__ = ["icosphere", "torus", "box", "grid_plane"]


def icosphere(subdivisions: int = 2, *, radius: float = 1.0, center=(0.0, 0.0, 0.0)
              ) -> tuple[np.ndarray, np.ndarray]:
    """Return a unit-sphere triangulation by Loop-subdividing an icosahedron.

    Parameters
    ----------
    subdivisions : int, optional
        Each level multiplies the face count by 4 (20 * 4**k faces).
    radius : float, optional
    center : array_like, (3,), optional

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Outward oriented.
    """
    if subdivisions < 0 or subdivisions > 9:
        raise InputError(f"subdivisions must be in [0, 9], got {subdivisions}")
    V, F = igl.icosahedron()
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if subdivisions:
        V, F = igl.upsample(V, F, subdivisions)
    V = V / np.linalg.norm(V, axis=1, keepdims=True)
    return np.ascontiguousarray(V * radius + np.asarray(center, float)), np.asarray(F, np.int64)


def torus(major: float = 1.0, minor: float = 0.35, *, n_major: int = 48, n_minor: int = 24
          ) -> tuple[np.ndarray, np.ndarray]:
    """Return a torus around the z axis, outward oriented.

    Returns
    -------
    V : numpy.ndarray, (n_major * n_minor, 3) float64
    F : numpy.ndarray, (2 * n_major * n_minor, 3) int64
    """
    if n_major < 3 or n_minor < 3 or not (0 < minor < major):
        raise InputError("torus needs n_major, n_minor >= 3 and 0 < minor < major")
    u = np.arange(n_major) * 2 * np.pi / n_major
    v = np.arange(n_minor) * 2 * np.pi / n_minor
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = major + minor * np.cos(vv)
    V = np.stack([r * np.cos(uu), r * np.sin(uu), minor * np.sin(vv)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    a = i * n_minor + j
    b = ((i + 1) % n_major) * n_minor + j
    c = ((i + 1) % n_major) * n_minor + (j + 1) % n_minor
    d = i * n_minor + (j + 1) % n_minor
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                        np.stack([a, c, d], -1).reshape(-1, 3)])
    return V, F.astype(np.int64)


def grid_plane(nx: int, ny: int, *, size=(1.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Return a triangulated rectangle in the z = 0 plane, normals +z.

    Returns
    -------
    V : numpy.ndarray, ((nx + 1) * (ny + 1), 3) float64
    F : numpy.ndarray, (2 * nx * ny, 3) int64
    """
    if nx < 1 or ny < 1:
        raise InputError("grid_plane needs nx, ny >= 1")
    x = np.linspace(0.0, size[0], nx + 1)
    y = np.linspace(0.0, size[1], ny + 1)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    V = np.stack([xx, yy, np.zeros_like(xx)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    a = i * (ny + 1) + j
    b = (i + 1) * (ny + 1) + j
    F = np.concatenate([np.stack([a, b, b + 1], -1).reshape(-1, 3),
                        np.stack([a, b + 1, a + 1], -1).reshape(-1, 3)])
    return V, F.astype(np.int64)


def box(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0), *, divisions: int = 1
        ) -> tuple[np.ndarray, np.ndarray]:
    """Return an axis-aligned box, each side split into ``divisions`` squares.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (12 * divisions**2, 3) int64
        Closed and outward oriented.
    """
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    if divisions < 1 or not np.all(hi > lo):
        raise InputError("box needs divisions >= 1 and hi > lo on every axis")
    gV, gF = grid_plane(divisions, divisions)
    Vs, Fs = [], []
    offset = 0
    # unit-cube sides as (origin, u axis, v axis); u x v points outward
    sides = [((0, 0, 0), (0, 1, 0), (1, 0, 0)), ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
             ((0, 0, 0), (1, 0, 0), (0, 0, 1)), ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
             ((0, 0, 0), (0, 0, 1), (0, 1, 0)), ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    for o, u, v in sides:
        P = np.asarray(o, float) + gV[:, :1] * np.asarray(u, float) + gV[:, 1:2] * np.asarray(v, float)
        Vs.append(P)
        Fs.append(gF + offset)
        offset += P.shape[0]
    V = np.vstack(Vs)
    F = np.vstack(Fs)
    # weld the shared edges of the six sides (exact: grid coordinates coincide)
    key = np.round(V * divisions).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    Vw = V[first[order]]
    Fw = rank[inv][F]
    return lo + Vw * (hi - lo), Fw.astype(np.int64)
