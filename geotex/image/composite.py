"""Composite all pastes of a lapped texture at surface points.

At a point of face ``f`` with barycentric coordinates ``b``, every paste
that holds ``f`` maps the point to ``b . corner_uv`` in its texture patch;
the samples are blended back to front in paste order with the "over"
operator (``C = a Cs + (1 - a) C``), starting from a background colour (the
alpha-weighted mean colour of the patches).  The layers are processed one
depth at a time, vectorized over all points whose face has that many pastes.
This is the same compositing the paper performs into its texture atlas
(§4); it serves the atlas texels and the height field alike.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.image.patches import sample_patch
from geotex.image.records import LappedTexture

__all__ = ["composite_at", "background_color", "luminance"]

_LUMA = np.array([0.299, 0.587, 0.114], dtype=np.float32)


def background_color(lapped: LappedTexture) -> np.ndarray:
    """Alpha-weighted mean colour of the texture patches, ``(3,)`` float32."""
    num = np.zeros(3)
    den = 0.0
    for p in lapped.patches:
        a = p.rgba[:, :, 3].astype(np.float64)
        num += (p.rgba[:, :, :3] * a[:, :, None]).sum(axis=(0, 1))
        den += a.sum()
    return (num / max(den, 1e-12)).astype(np.float32)


def luminance(rgb) -> np.ndarray:
    """Rec. 601 luma of ``(..., 3)`` colours in ``[0, 1]``."""
    return np.asarray(rgb, dtype=np.float32)[..., :3] @ _LUMA


def composite_at(lapped: LappedTexture, faces, bary, *, background=None) -> np.ndarray:
    """Colour of the lapped texture at surface points.

    Parameters
    ----------
    lapped : LappedTexture
    faces : array_like, (q,) int64
        Face of every point.
    bary : array_like, (q, 3) float64
        Barycentric coordinates of the points in their faces.
    background : array_like, (3,), optional
        Colour under all pastes (default :func:`background_color`).

    Returns
    -------
    numpy.ndarray, (q, 4) float32
        Composited colour and accumulated alpha (1 where an opaque part of
        some paste covers the point).

    Raises
    ------
    InputError
        On face ids outside the mesh or mismatched shapes.
    """
    faces = np.asarray(faces, dtype=np.int64).ravel()
    bary = np.asarray(bary, dtype=np.float64).reshape(-1, 3)
    if bary.shape[0] != faces.shape[0]:
        raise InputError(f"bary has {bary.shape[0]} rows for {faces.shape[0]} faces")
    m = lapped.n_faces
    if faces.size and (faces.min() < 0 or faces.max() >= m):
        raise InputError(f"faces must be face ids in [0, {m})")
    bg = background_color(lapped) if background is None else np.asarray(background, np.float32)
    out = np.zeros((faces.shape[0], 4), np.float32)
    out[:, :3] = bg[:3]
    face, _, patch, uv = lapped.layers()
    if face.size == 0 or faces.size == 0:
        return out
    order = np.argsort(face, kind="stable")          # by face, paste order inside
    face_s, patch_s, uv_s = face[order], patch[order], uv[order]
    start = np.searchsorted(face_s, np.arange(m + 1))
    count = start[1:] - start[:-1]
    qc = count[faces]
    for depth in range(int(qc.max()) if qc.size else 0):
        q = np.flatnonzero(qc > depth)
        e = start[faces[q]] + depth
        puv = np.einsum("qj,qjc->qc", bary[q], uv_s[e])
        pid = patch_s[e]
        for k in np.unique(pid).tolist():
            sel = pid == k
            rows = q[sel]
            s = sample_patch(lapped.patches[k], puv[sel])
            a = s[:, 3:4]
            out[rows, :3] = a * s[:, :3] + (1.0 - a) * out[rows, :3]
            out[rows, 3:4] = a + (1.0 - a) * out[rows, 3:4]
    return out
