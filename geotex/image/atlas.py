"""A texture atlas for a lapped texture: packed charts, pastes composited in.

Lapped textures §4 ("rendering with a texture atlas"): the mesh gets one
global parameterization whose charts do not overlap, and every paste is
composited into the atlas image in a preprocess.  The paper flattens normal
-cone regions and lets the user arrange them; geotex uses **xatlas** (chart
segmentation, parameterization and packing, a well-kept library used by
game engines and Blender add-ons) and then:

1. rasterizes every face's atlas triangle (texel centres inside it, found
   per face bounding box, vectorized over chunks of faces), which gives each
   covered texel a face and barycentric coordinates;
2. composites the pastes at those surface points
   (:func:`geotex.image.composite.composite_at`);
3. fills the texels outside every chart from the nearest chart texel
   (a distance transform), so bilinear filtering and mip-mapping do not
   bleed background colour across chart borders.

The result is a :class:`geotex.mesh.Mesh` with per-corner ``uv`` and a
texture, written by :func:`geotex.io.write_mesh` as OBJ + MTL + PNG or GLB.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import distance_transform_edt
import xatlas

from geotex.errors import InputError
from geotex.image.composite import composite_at
from geotex.image.records import LappedTexture
from geotex.jit import compiled
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.record import Mesh

__all__ = ["Atlas", "build_atlas", "rasterize_triangles", "composite_atlas", "textured_mesh"]

#: Faces rasterized per vectorized chunk.
_CHUNK = 4096


@dataclass(frozen=True, eq=False)
class Atlas:
    """A packed chart parameterization of a mesh.

    Attributes
    ----------
    uv : numpy.ndarray, (k, 2) float64
        Texture coordinates in ``[0, 1]^2`` (``v = 0`` at the bottom of the
        image).
    uv_faces : numpy.ndarray, (m, 3) int64
        Corners of every face in ``uv``.
    width, height : int
        Image size in texels the charts were packed for.
    n_charts : int
    """

    uv: np.ndarray
    uv_faces: np.ndarray
    width: int
    height: int
    n_charts: int


def build_atlas(V, F, *, resolution: int = 1024, padding: int = 2) -> Atlas:
    """Segment, flatten and pack a mesh into charts with xatlas.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    resolution : int, optional
        Texels on the longer side of the atlas image (about).
    padding : int, optional
        Texels between charts.

    Returns
    -------
    Atlas

    Raises
    ------
    InputError
        On malformed or empty meshes or bad options.
    """
    V, F = as_mesh_arrays(V, F)
    if F.shape[0] == 0:
        raise InputError("F is empty: nothing to put in an atlas")
    for name, value, lo in (("resolution", resolution, 16), ("padding", padding, 0)):
        if int(value) != value or int(value) < lo:
            raise InputError(f"{name} must be an integer >= {lo}, got {value!r}")
    atlas = xatlas.Atlas()
    atlas.add_mesh(np.ascontiguousarray(V, dtype=np.float32),
                   np.ascontiguousarray(F, dtype=np.uint32))
    pack = xatlas.PackOptions()
    pack.resolution = int(resolution)
    pack.padding = int(padding)
    pack.bilinear = True
    atlas.generate(xatlas.ChartOptions(), pack)
    vmapping, indices, uvs = atlas[0]
    indices = np.asarray(indices, dtype=np.int64)
    if indices.shape != F.shape or not np.array_equal(np.asarray(vmapping)[indices], F):
        raise InputError("xatlas changed the face order; cannot build the atlas")
    return Atlas(uv=np.ascontiguousarray(uvs, dtype=np.float64), uv_faces=indices,
                 width=int(atlas.width), height=int(atlas.height),
                 n_charts=int(atlas.chart_count))


def rasterize_triangles(tri, width: int, height: int, *, strict: bool = False,
                        fast: bool = False):
    """Texel centres inside 2D triangles.

    Parameters
    ----------
    tri : array_like, (m, 3, 2) float64
        Triangles in texel units (``x`` right, ``y`` down from the top-left
        corner; texel ``(r, c)`` has its centre at ``(c + 0.5, r + 0.5)``).
    width, height : int
    strict : bool, optional
        Only texels strictly inside (barycentric coordinates > 1e-9); by
        default texels on an edge count for every triangle that has it.
    fast : bool, optional
        Use the compiled loop :func:`_rasterize_compiled` (the same output bit
        for bit, without the numpy temporaries: for the thousands of small
        calls of :func:`geotex.image.hpm.hpm_texture`; loading numba costs
        about a second once).  Triangles with a non-finite coordinate keep
        the numpy path.

    Returns
    -------
    texel : numpy.ndarray, (t,) int64
        ``r * width + c``.
    face : numpy.ndarray, (t,) int64
    bary : numpy.ndarray, (t, 3) float64
    """
    T = np.asarray(tri, dtype=np.float64)
    eps = 1e-9 if strict else -1e-9
    if fast and np.isfinite(T).all():
        return _rasterize_compiled(np.ascontiguousarray(T.reshape(-1, 3, 2)), int(width),
                                   int(height), eps)
    out_t, out_f, out_b = [], [], []
    for s in range(0, T.shape[0], _CHUNK):
        P = T[s:s + _CHUNK]
        lo = np.ceil(P.min(axis=1) - 0.5).astype(np.int64)
        hi = np.floor(P.max(axis=1) - 0.5).astype(np.int64)
        lo = np.maximum(lo, 0)
        hi[:, 0] = np.minimum(hi[:, 0], width - 1)
        hi[:, 1] = np.minimum(hi[:, 1], height - 1)
        nx = np.maximum(hi[:, 0] - lo[:, 0] + 1, 0)
        ny = np.maximum(hi[:, 1] - lo[:, 1] + 1, 0)
        cnt = nx * ny
        total = int(cnt.sum())
        if total == 0:
            continue
        fid = np.repeat(np.arange(P.shape[0]), cnt)
        first = np.repeat(np.cumsum(cnt) - cnt, cnt)
        k = np.arange(total) - first
        cx = lo[fid, 0] + k % nx[fid]
        cy = lo[fid, 1] + k // nx[fid]
        px, py = cx + 0.5, cy + 0.5
        A, B, C = P[fid, 0], P[fid, 1], P[fid, 2]
        den = (B[:, 1] - C[:, 1]) * (A[:, 0] - C[:, 0]) + (C[:, 0] - B[:, 0]) * (A[:, 1] - C[:, 1])
        ok = np.abs(den) > 0
        den = np.where(ok, den, 1.0)
        l0 = ((B[:, 1] - C[:, 1]) * (px - C[:, 0]) + (C[:, 0] - B[:, 0]) * (py - C[:, 1])) / den
        l1 = ((C[:, 1] - A[:, 1]) * (px - C[:, 0]) + (A[:, 0] - C[:, 0]) * (py - C[:, 1])) / den
        l2 = 1.0 - l0 - l1
        inside = ok & (l0 > eps) & (l1 > eps) & (l2 > eps)
        out_t.append((cy * width + cx)[inside])
        out_f.append((fid + s)[inside])
        out_b.append(np.stack([l0, l1, l2], axis=1)[inside])
    if not out_t:
        z = np.zeros(0, np.int64)
        return z, z, np.zeros((0, 3))
    return np.concatenate(out_t), np.concatenate(out_f), np.concatenate(out_b)


@compiled
def _rasterize_compiled(T, width, height, eps):
    """:func:`rasterize_triangles` for finite triangles: the same texels in the same
    order (triangle by triangle, row by row) and the same operations per texel, so
    the same barycentric coordinates."""
    m = T.shape[0]
    lo = np.empty((m, 2), np.int64)
    n = np.empty((m, 2), np.int64)
    total = 0
    for i in range(m):
        for d in range(2):
            a = min(min(T[i, 0, d], T[i, 1, d]), T[i, 2, d])
            b = max(max(T[i, 0, d], T[i, 1, d]), T[i, 2, d])
            l_ = max(int(np.ceil(a - 0.5)), 0)
            h_ = min(int(np.floor(b - 0.5)), (width if d == 0 else height) - 1)
            lo[i, d] = l_
            n[i, d] = max(h_ - l_ + 1, 0)
        total += n[i, 0] * n[i, 1]
    texel = np.empty(total, np.int64)
    face = np.empty(total, np.int64)
    bary = np.empty((total, 3))
    k = 0
    for i in range(m):
        A0, A1 = T[i, 0, 0], T[i, 0, 1]
        B0, B1 = T[i, 1, 0], T[i, 1, 1]
        C0, C1 = T[i, 2, 0], T[i, 2, 1]
        den = (B1 - C1) * (A0 - C0) + (C0 - B0) * (A1 - C1)
        if not abs(den) > 0:
            continue
        for r in range(n[i, 1]):
            cy = lo[i, 1] + r
            py = cy + 0.5
            for c in range(n[i, 0]):
                cx = lo[i, 0] + c
                px = cx + 0.5
                l0 = ((B1 - C1) * (px - C0) + (C0 - B0) * (py - C1)) / den
                l1 = ((C1 - A1) * (px - C0) + (A0 - C0) * (py - C1)) / den
                l2 = 1.0 - l0 - l1
                if l0 > eps and l1 > eps and l2 > eps:
                    texel[k] = cy * width + cx
                    face[k] = i
                    bary[k, 0] = l0
                    bary[k, 1] = l1
                    bary[k, 2] = l2
                    k += 1
    return texel[:k].copy(), face[:k].copy(), bary[:k].copy()


def _texel_triangles(atlas: Atlas) -> np.ndarray:
    Q = atlas.uv[atlas.uv_faces]
    return np.stack([Q[..., 0] * atlas.width, (1.0 - Q[..., 1]) * atlas.height], axis=-1)


def composite_atlas(lapped: LappedTexture, atlas: Atlas) -> np.ndarray:
    """Composite every paste into the atlas image.

    Parameters
    ----------
    lapped : LappedTexture
    atlas : Atlas
        Of the same mesh.

    Returns
    -------
    numpy.ndarray, (height, width, 3) uint8
        Row 0 is the top of the image (``v = 1``).
    """
    if atlas.uv_faces.shape[0] != lapped.n_faces:
        raise InputError(f"the atlas has {atlas.uv_faces.shape[0]} faces, the lapped texture "
                         f"{lapped.n_faces}: they belong to different meshes")
    W, H = atlas.width, atlas.height
    texel, face, bary = rasterize_triangles(_texel_triangles(atlas), W, H)
    rgba = composite_at(lapped, face, bary)
    img = np.zeros((H * W, 3), np.float32)
    filled = np.zeros(H * W, dtype=bool)
    img[texel] = rgba[:, :3]
    filled[texel] = True
    img = img.reshape(H, W, 3)
    if filled.any() and not filled.all():
        _, (iy, ix) = distance_transform_edt(~filled.reshape(H, W), return_indices=True)
        img = img[iy, ix]
    return np.clip(np.rint(img * 255.0), 0, 255).astype(np.uint8)


def textured_mesh(V, F, lapped: LappedTexture, *, resolution: int = 1024, padding: int = 2,
                  atlas: Atlas | None = None, name: str = "") -> Mesh:
    """The mesh with an atlas and the lapped texture composited into it.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    lapped : LappedTexture
        Pastes over ``(V, F)``.
    resolution, padding : int, optional
        Passed to :func:`build_atlas`.
    atlas : Atlas, optional
        Reuse an atlas already built for ``(V, F)``.
    name : str, optional

    Returns
    -------
    geotex.mesh.Mesh
        With ``uv``, ``uv_faces`` and an RGB ``texture``; write it with
        :func:`geotex.io.write_mesh` (``.obj`` gives OBJ + MTL + PNG, ``.glb``
        one file with the PNG embedded).
    """
    V, F = as_mesh_arrays(V, F)
    if F.shape[0] != lapped.n_faces or V.shape[0] != lapped.n_vertices:
        raise InputError(f"the lapped texture was made for {lapped.n_vertices} vertices and "
                         f"{lapped.n_faces} faces, not {V.shape[0]} and {F.shape[0]}")
    at = build_atlas(V, F, resolution=resolution, padding=padding) if atlas is None else atlas
    tex = composite_atlas(lapped, at)
    return Mesh(V, F, uv=at.uv, uv_faces=at.uv_faces, texture=tex, name=name,
                metadata={"atlas_charts": at.n_charts, "pastes": lapped.n_pastes})
