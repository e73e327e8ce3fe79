"""The polycube surface of a voxel solid: tile quads and their triangle sub-grid.

Tile quads follow the frame of :mod:`geotex.param.polycube_quads`: a quad with
label ``2a`` (``+axis a``) or ``2a + 1`` (``-axis a``) has in-plane axes
``(a1, a2)`` given by :func:`~geotex.param.polycube_quads.chart_axes`, corners
``c0 = (i, j)``, ``c1 = (i+1, j)``, ``c2 = (i+1, j+1)``, ``c3 = (i, j+1)``
counter-clockwise about its outward normal, and the tile point ``(u, v)`` at
``c0 + u e1 + v e2``. Coordinates are in tile units (integers).

Every tile quad is cut into ``res x res`` sub-cells, each split into two
triangles along the diagonal ``(0, 0)-(1, 1)``; vertices are shared between
neighbouring quads, so the triangles form one closed surface. Faces are stored
quad by quad: face ``f`` belongs to quad ``f // (2 res^2)``.
"""

from __future__ import annotations

import numpy as np

from geotex.param.polycube_quads import chart_axes

__all__ = ["boundary_quads", "subdivided_quads", "quad_of_face"]

_DU = np.array([0, 1, 1, 0], dtype=np.int64)
_DV = np.array([0, 0, 1, 1], dtype=np.int64)


def boundary_quads(S: np.ndarray, *, tiles_per_cell: int = 1
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Tile quads on the boundary of a voxel solid.

    Parameters
    ----------
    S : numpy.ndarray, bool (nx, ny, nz)
        Voxel solid; cell ``(i, j, k)`` spans ``[i, i+1] x [j, j+1] x [k, k+1]``
        cells.
    tiles_per_cell : int
        Tiles along a cell side: every boundary cell face gives
        ``tiles_per_cell**2`` quads.

    Returns
    -------
    corners : numpy.ndarray, (q, 4, 3) int64
        Quad corners in tile units (cell coordinates times ``tiles_per_cell``).
    labels : numpy.ndarray, (q,) int64
        Outward normal of every quad: ``0 +X, 1 -X, 2 +Y, 3 -Y, 4 +Z, 5 -Z``.
    """
    k = int(tiles_per_cell)
    P = np.pad(S, 1)
    out_c, out_l = [], []
    ii, jj = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    for a in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[a], hi[a] = slice(0, -1), slice(1, None)
        A, B = P[tuple(lo)], P[tuple(hi)]
        for label, face in ((2 * a, A & ~B), (2 * a + 1, ~A & B)):
            cell = np.argwhere(face).astype(np.int64) - 1   # lower cell of the pair, unpadded
            cell[:, a] += 1                                  # the face plane
            _, a1, a2 = chart_axes(np.array([label]))
            a1, a2 = int(a1[0]), int(a2[0])
            c0 = np.repeat(cell * k, k * k, axis=0)
            c0[:, a1] += np.tile(ii, cell.shape[0])
            c0[:, a2] += np.tile(jj, cell.shape[0])
            C = np.repeat(c0[:, None, :], 4, axis=1)
            C[:, :, a1] += _DU
            C[:, :, a2] += _DV
            out_c.append(C)
            out_l.append(np.full(C.shape[0], label, dtype=np.int64))
    corners = np.concatenate(out_c)
    labels = np.concatenate(out_l)
    order = np.lexsort((corners[:, 0, 2], corners[:, 0, 1], corners[:, 0, 0], labels))
    return corners[order], labels[order]


def subdivided_quads(corners: np.ndarray, labels: np.ndarray, *, res: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangulate every tile quad as a ``res x res`` grid of shared vertices.

    Parameters
    ----------
    corners : numpy.ndarray, (q, 4, 3) int64
    labels : numpy.ndarray, (q,) int64
    res : int
        Sub-cells along a tile side.

    Returns
    -------
    P : numpy.ndarray, (n, 3) float64
        Vertex positions in tile units (multiples of ``1 / res``).
    F : numpy.ndarray, (2 q res^2, 3) int64
        Triangles, counter-clockwise about the outward normal, quad by quad.
    grid : numpy.ndarray, (q, res + 1, res + 1) int64
        ``grid[q, i, j]`` is the vertex at tile point ``(i / res, j / res)``.
    """
    r = int(res)
    _, a1, a2 = chart_axes(labels)
    eye = np.eye(3, dtype=np.int64)
    e1, e2 = eye[a1], eye[a2]
    s = np.arange(r + 1)
    I, J = np.meshgrid(s, s, indexing="ij")
    pts = (corners[:, 0, None, None, :] * r + I[None, :, :, None] * e1[:, None, None, :]
           + J[None, :, :, None] * e2[:, None, None, :])
    keys, inverse = np.unique(pts.reshape(-1, 3), axis=0, return_inverse=True)
    grid = inverse.reshape(corners.shape[0], r + 1, r + 1).astype(np.int64)
    v00, v10 = grid[:, :-1, :-1], grid[:, 1:, :-1]
    v11, v01 = grid[:, 1:, 1:], grid[:, :-1, 1:]
    lower = np.stack([v00, v10, v11], axis=-1).reshape(corners.shape[0], -1, 3)
    upper = np.stack([v00, v11, v01], axis=-1).reshape(corners.shape[0], -1, 3)
    F = np.concatenate([lower, upper], axis=1).reshape(-1, 3)
    return keys.astype(np.float64) / r, F, grid


def quad_of_face(n_faces: int, res: int) -> np.ndarray:
    """Quad of every face of :func:`subdivided_quads`, ``(m,)`` int64."""
    return np.arange(n_faces, dtype=np.int64) // (2 * int(res) ** 2)
