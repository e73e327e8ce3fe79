"""Seam contrast of a textured mesh: colour jumps across region borders vs inside regions."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import map_coordinates

from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import edge_topology

__all__ = ["SeamContrast", "seam_contrast", "edge_contrast", "texture_colors"]


@dataclass(frozen=True)
class SeamContrast:
    """Mean colour differences across edges, in RGB units of ``[0, 1]``.

    Attributes
    ----------
    border : float
        Mean over edges between two regions.
    within : float
        Mean over edges inside a region.
    ratio : float
        ``border / within`` (1: borders are invisible in the statistics).
    n_border, n_within : int
    """

    border: float
    within: float
    ratio: float
    n_border: int
    n_within: int


def texture_colors(texture: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear RGB in ``[0, 1]`` of a texture at uv (``v`` up; wraps like GL_REPEAT).

    Parameters
    ----------
    texture : numpy.ndarray, (h, w, 3 or 4) uint8
    uv : numpy.ndarray, (k, 2) float64

    Returns
    -------
    numpy.ndarray, (k, 3) float64
    """
    h, w = texture.shape[:2]
    x = np.mod(uv[:, 0], 1.0) * w - 0.5
    y = (1.0 - np.mod(uv[:, 1], 1.0)) * h - 0.5
    img = texture[:, :, :3].astype(np.float64) / 255.0
    return np.stack([map_coordinates(img[:, :, k], [y, x], order=1, mode="grid-wrap")
                     for k in range(3)], axis=1)


def seam_contrast(V, F, uv, uv_faces, texture, regions, *, offset: float = 0.1
                  ) -> SeamContrast:
    """Mean colour difference across region borders divided by the mean inside regions.

    Every interior edge is sampled once on each side, at the point of each
    adjacent face that lies ``offset`` of the way from the edge midpoint to
    the face's opposite vertex; the colour each face shows there (its own
    texture coordinates) is compared.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    uv : array_like, (k, 2) float64
    uv_faces : array_like, (m, 3) int64
    texture : numpy.ndarray, (h, w, 3 or 4) uint8
    regions : array_like, (m,) int
        Region (patch, cluster, paste) of every face.
    offset : float, optional
        In ``(0, 1)``.

    Returns
    -------
    SeamContrast

    Raises
    ------
    InputError
        On mismatched arrays.
    """
    V, F = as_mesh_arrays(V, F)
    uv = np.asarray(uv, dtype=np.float64)
    FT = np.asarray(uv_faces, dtype=np.int64)
    reg = np.asarray(regions)
    if FT.shape != F.shape or reg.shape != (F.shape[0],):
        raise InputError("uv_faces and regions must have one row per face")
    if not 0.0 < float(offset) < 1.0:
        raise InputError(f"offset must be in (0, 1), got {offset!r}")
    topo = edge_topology(F, V.shape[0])
    two = topo.face_count == 2
    ef = topo.edge_faces()[two]
    ed = topo.edges[two]
    cols = []
    for side in (0, 1):
        f = ef[:, side]
        tri = F[f]
        # barycentric weights: the two edge ends get (1 - offset) / 2, the third offset
        w = np.where((tri == ed[:, :1]) | (tri == ed[:, 1:]), (1.0 - offset) / 2.0, offset)
        p = np.einsum("ek,ekd->ed", w, uv[FT[f]])
        cols.append(texture_colors(texture, p))
    d = np.linalg.norm(cols[0] - cols[1], axis=1)
    cross = reg[ef[:, 0]] != reg[ef[:, 1]]
    b = float(d[cross].mean()) if cross.any() else float("nan")
    i = float(d[~cross].mean()) if (~cross).any() else float("nan")
    return SeamContrast(border=b, within=i, ratio=b / i if i > 0 else float("nan"),
                        n_border=int(cross.sum()), n_within=int((~cross).sum()))


def _side_colors(F, FT, uv, texture, ed, faces, offset):
    """Colour each face shows ``offset`` of the way from the edge midpoint to its third vertex."""
    tri = F[faces]
    w = np.where((tri == ed[:, :1]) | (tri == ed[:, 1:]), (1.0 - offset) / 2.0, offset)
    return texture_colors(texture, np.einsum("ek,ekd->ed", w, uv[FT[faces]]))


def edge_contrast(V, F, uv, uv_faces, texture, *, offset: float = 0.1) -> SeamContrast:
    """Mean colour jump across edges divided by the mean colour change inside faces.

    Across every interior edge the two faces' colours are compared at the
    points ``offset`` of the way from the edge midpoint to each face's
    opposite vertex (``border``); inside every face, the colour at that point
    is compared with the colour ``3 offset`` of the way, the same distance
    apart (``within``).  With no seam anywhere the ratio is about 1; a
    parameterization with seams (or a lapped texture's paste borders) raises it.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    uv : array_like, (k, 2) float64
    uv_faces : array_like, (m, 3) int64
    texture : numpy.ndarray, (h, w, 3 or 4) uint8
    offset : float, optional
        In ``(0, 1/3)``.

    Returns
    -------
    SeamContrast
        ``border``: across edges, ``within``: inside faces.

    Raises
    ------
    InputError
        On mismatched arrays or a bad offset.
    """
    V, F = as_mesh_arrays(V, F)
    uv = np.asarray(uv, dtype=np.float64)
    FT = np.asarray(uv_faces, dtype=np.int64)
    if FT.shape != F.shape:
        raise InputError("uv_faces must have one row per face")
    if not 0.0 < float(offset) < 1.0 / 3.0:
        raise InputError(f"offset must be in (0, 1/3), got {offset!r}")
    topo = edge_topology(F, V.shape[0])
    two = topo.face_count == 2
    ef = topo.edge_faces()[two]
    ed = topo.edges[two]
    near = [_side_colors(F, FT, uv, texture, ed, ef[:, s], offset) for s in (0, 1)]
    far = [_side_colors(F, FT, uv, texture, ed, ef[:, s], 3.0 * offset) for s in (0, 1)]
    across = np.linalg.norm(near[0] - near[1], axis=1)
    inside = np.concatenate([np.linalg.norm(near[s] - far[s], axis=1) for s in (0, 1)])
    b, i = float(across.mean()), float(inside.mean())
    return SeamContrast(border=b, within=i, ratio=b / i if i > 0 else float("nan"),
                        n_border=int(across.size), n_within=int(inside.size))
