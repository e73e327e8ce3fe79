"""Closed, outward-oriented primitive meshes built with numpy."""

from __future__ import annotations

import igl
import numpy as np

from geotex.errors import InputError

__all__ = ["icosphere", "closed_cylinder", "torus", "box", "grid_plane", "plate_with_holes", "sphere_with_rod"]


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


def closed_cylinder(radius: float = 1.0, height: float = 2.0, *, n_theta: int = 64,
                    n_height: int = 16, n_cap_rings: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Return a closed cylinder along z (base at z = 0), outward oriented.

    The side is a grid of ``n_theta`` x ``n_height`` quads (two triangles
    each); each cap is ``n_cap_rings`` concentric rings of ``n_theta``
    vertices around a centre vertex.  The cap's rim is a sharp 90 degree
    crease.

    Returns
    -------
    V : numpy.ndarray, (n_theta * (n_height + 1 + 2 * (n_cap_rings - 1)) + 2, 3) float64
    F : numpy.ndarray, (2 * n_theta * (n_height + 2 * n_cap_rings - 1), 3) int64

    Raises
    ------
    InputError
        On non-positive sizes or counts below 3 / 1 / 1.
    """
    if n_theta < 3 or n_height < 1 or n_cap_rings < 1 or not (radius > 0 and height > 0):
        raise InputError("closed_cylinder needs radius, height > 0, n_theta >= 3, "
                         "n_height >= 1 and n_cap_rings >= 1")
    t = np.arange(n_theta) * 2 * np.pi / n_theta
    ring = np.stack([np.cos(t), np.sin(t)], axis=1)
    z = np.linspace(0.0, height, n_height + 1)
    side = np.concatenate([np.column_stack([radius * ring, np.full(n_theta, zz)]) for zz in z])
    rows = [np.arange(n_theta) + k * n_theta for k in range(n_height + 1)]
    Vs = [side]
    nv = side.shape[0]
    Fs = []

    def band(lo, hi):             # quads between two rings, outward for lo below hi
        a, b = lo, np.roll(lo, -1)
        c, d = np.roll(hi, -1), hi
        return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])

    for k in range(n_height):
        Fs.append(band(rows[k], rows[k + 1]))
    for top in (False, True):
        zz = height if top else 0.0
        prev = rows[-1] if top else rows[0]
        for r in range(n_cap_rings - 1, 0, -1):
            rr = radius * r / n_cap_rings
            Vs.append(np.column_stack([rr * ring, np.full(n_theta, zz)]))
            cur = np.arange(n_theta) + nv
            nv += n_theta
            Fs.append(band(cur, prev) if not top else band(prev, cur))
            prev = cur
        Vs.append(np.array([[0.0, 0.0, zz]]))
        c = nv
        nv += 1
        a, b = prev, np.roll(prev, -1)
        fan = np.stack([a, b, np.full(n_theta, c)], 1)
        Fs.append(fan if top else fan[:, ::-1])
    V = np.ascontiguousarray(np.concatenate(Vs))
    return V, np.ascontiguousarray(np.concatenate(Fs), dtype=np.int64)


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


def _implicit_mesh(f, lo, hi, *, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Marching cubes of ``f < 0`` (vectorized ``f((k, 3)) -> (k,)``) over a box.

    The grid is nudged by an irrational fraction of a cell so no grid value is
    exactly zero (no degenerate triangles); faces are returned outward.
    """
    lo = np.asarray(lo, np.float64) - 2 * cell + cell * 0.1234567
    n = np.ceil((np.asarray(hi, np.float64) + 2 * cell - lo) / cell).astype(int) + 1
    axes = [lo[a] + cell * np.arange(n[a]) for a in range(3)]
    gz, gy, gx = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")   # x fastest
    GV = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1)
    S = np.asarray(f(GV), dtype=np.float64)
    V, F, _ = igl.marching_cubes(S, GV, int(n[0]), int(n[1]), int(n[2]), 0.0)
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    # orient outward: the signed volume must be positive
    vol = np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum()
    if vol < 0:
        F = F[:, ::-1].copy()
    return V, F


def _hole_layout(genus: int) -> np.ndarray:
    cols = int(np.ceil(np.sqrt(genus)))
    rows = int(np.ceil(genus / cols))
    ij = np.array([(i, j) for j in range(rows) for i in range(cols)][:genus], dtype=np.float64)
    return ij, cols, rows


def plate_with_holes(genus: int, *, hole: float = 1.0, bar: float = 0.6,
                     thickness: float = 0.6, cell: float = 0.1
                     ) -> tuple[np.ndarray, np.ndarray]:
    """A rounded plate pierced by ``genus`` round holes on a grid: a closed surface of genus ``genus``.

    Parameters
    ----------
    genus : int
        Number of holes, 0 to 64 (0 gives a rounded slab).
    hole : float, optional
        Hole diameter.
    bar : float, optional
        Width of the material between two holes and around the border.
    thickness : float, optional
        Plate thickness.
    cell : float, optional
        Marching-cubes grid step (the mesh resolution).

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Closed, manifold, outward oriented, one component.

    Raises
    ------
    InputError
        Genus out of range or a non-positive size.
    """
    g = int(genus)
    if g < 0 or g > 64:
        raise InputError(f"genus must be in [0, 64], got {genus}")
    if min(hole, bar, thickness, cell) <= 0 or cell > min(bar, thickness) / 3:
        raise InputError("hole, bar, thickness must be positive and cell at most a third "
                         "of bar and thickness")
    ij, cols, rows = _hole_layout(max(g, 1))
    pitch = hole + bar
    half = np.array([cols * pitch + bar, rows * pitch + bar, thickness]) / 2
    centres = (ij + 0.5) * pitch + bar / 2 - half[:2]
    if g == 0:
        centres = centres[:0]
    rounding = 0.45 * min(bar, thickness)

    def f(X):
        q = np.abs(X) - (half - rounding)
        d = (np.linalg.norm(np.maximum(q, 0.0), axis=1)
             + np.minimum(q.max(axis=1), 0.0) - rounding)        # rounded box
        for c in centres:
            r = np.linalg.norm(X[:, :2] - c, axis=1) - hole / 2
            d = np.maximum(d, -r)
        return d

    return _implicit_mesh(f, -half, half, cell=cell)


def sphere_with_rod(*, radius: float = 1.0, rod_radius: float = 0.08, rod_length: float = 1.0,
                    cell: float = 0.04) -> tuple[np.ndarray, np.ndarray]:
    """A sphere with a thin rod (capped cylinder) sticking out along +X: a thin part.

    Parameters
    ----------
    radius : float, optional
    rod_radius : float, optional
    rod_length : float, optional
        Length of the rod outside the sphere.
    cell : float, optional
        Marching-cubes grid step; at most ``rod_radius / 1.5``.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Closed, manifold, outward oriented, genus 0.
    """
    if min(radius, rod_radius, rod_length, cell) <= 0 or cell > rod_radius / 1.5:
        raise InputError("sizes must be positive and cell at most rod_radius / 1.5")
    tip = radius + rod_length - rod_radius

    def f(X):
        s = np.linalg.norm(X, axis=1) - radius
        x = np.clip(X[:, 0], 0.0, tip)
        rod = np.sqrt((X[:, 0] - x) ** 2 + X[:, 1] ** 2 + X[:, 2] ** 2) - rod_radius
        return np.minimum(s, rod)

    hi = np.array([radius + rod_length, radius, radius])
    return _implicit_mesh(f, -np.full(3, radius), hi, cell=cell)
