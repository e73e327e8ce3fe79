"""Transfer of a height-and-tilt texture between two bases (paper section 3.3).

A destination base ``(V_dst, F_dst)`` receives the texture of a source base
``(Vs_src, F_src)`` through a *correspondence*: every destination vertex is
mapped to a point on the source surface, given as a source face index and
barycentric coordinates.

* Heights are resampled barycentrically.
* The source tilt field is the per-vertex decoded tilt (1-form plus residual,
  :func:`geotex.heighttilt.base.decode_tilt`) interpolated barycentrically.
  It is evaluated at ``samples`` points along every destination edge mapped
  into the source, carried into the destination tangent plane, and
  integrated along the edge (:func:`geotex.fields.oneforms.line_integrals`)
  to give the destination 1-form.  A per-vertex residual is then stored so
  that the decoded destination tilt equals, at every destination vertex, the
  carried tilt of its corresponding source point.

Mapping edge samples
--------------------
The correspondence is only known at the destination vertices.  The sample at
parameter ``q`` of a destination edge ``(i, j)`` is mapped to the point of the
source surface closest to ``(1 - q) P_i + q P_j``, where ``P_i``, ``P_j`` are
the source points of ``i`` and ``j`` (``igl.point_mesh_squared_distance``).
On a shared mesh with the identity correspondence this is the edge itself.

Carrying vectors between tangent planes
---------------------------------------
The interpolated source tilt is tangent (up to the interpolation error) to the
barycentric interpolation of the source *vertex* normals
(:func:`geotex.heighttilt.base.base_normals`), not to the face normal, because
the decoded tilts live in the vertex tangent planes.  The vector is therefore
rotated by the minimal rotation taking that interpolated source normal onto the
destination normal at the sample (the interpolation of the destination vertex
normals along the edge, or the vertex normal at a vertex), then projected
onto the destination tangent plane.  With coinciding normals (same mesh,
identity correspondence) the rotation is the identity, so a texture is
reproduced exactly; using face normals instead would rotate vertex tilts by
the angle between the face and the vertex normal.

The minimal rotation is meant for bases that nearly coincide in space (as with
:func:`closest_point_correspondence`).  It is not equivariant under a rigid
motion of one base only: the minimal rotation from ``n`` to ``Q n`` differs
from ``Q`` by a spin about ``Q n``, so for a correspondence between shapes in
different poses the lean directions would be turned about the normal (the
magnitudes, i.e. the lean angles, are kept by the rotation up to the final
tangent projection).
"""

from __future__ import annotations

import igl
import numpy as np

from geotex.errors import InputError
from geotex.fields.oneforms import line_integrals, segment_samples
from geotex.heighttilt.base import base_normals, check_base_mesh, decode_tilt, tilt_frames
from geotex.heighttilt.reconstruct import check_texture
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.mesh.arrays import as_vertices
from geotex.mesh.topology import edge_topology

__all__ = ["transfer_texture", "closest_point_correspondence", "check_correspondence"]

_BARY_TOL = 1e-6


def check_correspondence(correspondence, n_dst: int, m_src: int
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Validate a correspondence ``(faces, bary)``; return it as arrays.

    Parameters
    ----------
    correspondence : tuple of array_like
        ``faces`` (n_dst,) int64 source face per destination vertex and
        ``bary`` (n_dst, 3) float64 barycentric coordinates in that face.
    n_dst : int
        Number of destination vertices.
    m_src : int
        Number of source faces.

    Returns
    -------
    faces : numpy.ndarray, (n_dst,) int64
    bary : numpy.ndarray, (n_dst, 3) float64

    Raises
    ------
    InputError
        Not a pair, wrong shapes or dtypes, face indices outside
        ``[0, m_src)``, non-finite coordinates, or rows not summing to 1
        (tolerance 1e-6).
    """
    if not isinstance(correspondence, (tuple, list)) or len(correspondence) != 2:
        raise InputError("correspondence must be a pair (faces, bary) of arrays "
                         f"of shapes ({n_dst},) and ({n_dst}, 3)")
    fa = np.asarray(correspondence[0])
    if fa.shape != (n_dst,):
        raise InputError(f"correspondence faces must have shape ({n_dst},), got {fa.shape}")
    if fa.size and fa.dtype.kind not in "iu":
        raise InputError(f"correspondence faces must be integers, got dtype {fa.dtype}")
    fa = fa.astype(np.int64)
    if fa.size and (fa.min() < 0 or fa.max() >= m_src):
        bad = int(np.flatnonzero((fa < 0) | (fa >= m_src))[0])
        raise InputError(f"correspondence faces must be in [0, {m_src}) "
                         f"(destination vertex {bad} has {int(fa[bad])})")
    try:
        B = np.array(correspondence[1], dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"correspondence bary must be a numeric ({n_dst}, 3) array") from None
    if B.shape != (n_dst, 3):
        raise InputError(f"correspondence bary must have shape ({n_dst}, 3), got {B.shape}")
    if not np.isfinite(B).all():
        raise InputError("correspondence bary has non-finite values")
    err = np.abs(B.sum(axis=1) - 1.0)
    if err.size and err.max() > _BARY_TOL:
        bad = int(np.argmax(err))
        raise InputError(f"correspondence bary rows must sum to 1 "
                         f"(row {bad} sums to {B[bad].sum():.6g})")
    return fa, B


def closest_point_correspondence(V_dst, Vs_src, F_src) -> tuple[np.ndarray, np.ndarray]:
    """Map every destination vertex to its closest point on the source surface.

    Parameters
    ----------
    V_dst : array_like, (n_dst, 3) float64
    Vs_src : array_like, (n_src, 3) float64
    F_src : array_like, (m_src, 3) int64

    Returns
    -------
    faces : numpy.ndarray, (n_dst,) int64
        Source face of the closest point (``igl.point_mesh_squared_distance``).
    bary : numpy.ndarray, (n_dst, 3) float64
        Its barycentric coordinates (``igl.barycentric_coordinates``), clipped
        to be non-negative and renormalised to sum to 1.

    Raises
    ------
    InputError
        Malformed arrays or an invalid source base (see
        :func:`geotex.heighttilt.base.check_base_mesh`).
    """
    P = as_vertices(V_dst, name="V_dst")
    Vs, F = check_base_mesh(Vs_src, F_src, name="Vs_src")
    return _project(P, Vs, F)


def _project(P, Vs, F):
    if P.shape[0] == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3))
    _, idx, C = igl.point_mesh_squared_distance(P, Vs, F)
    idx = np.asarray(idx, dtype=np.int64)
    T = F[idx]
    B = igl.barycentric_coordinates(np.ascontiguousarray(C), np.ascontiguousarray(Vs[T[:, 0]]),
                                    np.ascontiguousarray(Vs[T[:, 1]]),
                                    np.ascontiguousarray(Vs[T[:, 2]]))
    B = np.clip(np.asarray(B, dtype=np.float64), 0.0, None)
    B /= B.sum(axis=1, keepdims=True)
    return idx, B


def _rotate(v, a, b):
    """Minimal rotation of vectors ``v`` taking unit ``a`` onto unit ``b`` (rowwise)."""
    k = np.cross(a, b)
    c = np.einsum("kd,kd->k", a, b)
    kv = np.cross(k, v)
    denom = np.maximum(1.0 + c, 1e-12)[:, None]
    return v + kv + np.cross(k, kv) / denom


def _unit(X):
    ln = np.linalg.norm(X, axis=-1, keepdims=True)
    return np.divide(X, ln, out=np.zeros_like(X), where=ln > 1e-300)


def transfer_texture(Vs_src, F_src, tex: HeightTiltTexture, V_dst, F_dst, *, correspondence,
                     samples: int = 5) -> HeightTiltTexture:
    """Transfer a height-and-tilt texture onto another base through a correspondence.

    Parameters
    ----------
    Vs_src : array_like, (n_src, 3) float64
        Source base.
    F_src : array_like, (m_src, 3) int64
        Must equal ``tex.faces``.
    tex : HeightTiltTexture
        Texture over the source base.
    V_dst : array_like, (n_dst, 3) float64
        Destination base.
    F_dst : array_like, (m_dst, 3) int64
    correspondence : tuple (faces, bary)
        ``faces`` (n_dst,) int64 and ``bary`` (n_dst, 3) float64: the source
        point of every destination vertex (see
        :func:`closest_point_correspondence`).
    samples : int, optional
        Gauss-Legendre points per destination edge (default 5, as in the
        paper).

    Returns
    -------
    HeightTiltTexture
        Over ``F_dst``: heights interpolated barycentrically; tilt 1-form from
        the line integrals of the carried source tilt along every destination
        edge; residual such that
        ``decode_tilt(V_dst, F_dst, tilt, residual)`` is, at every destination
        vertex, the carried source tilt at its source point (see the module
        docstring for how edge samples are mapped and vectors carried).

    Raises
    ------
    InputError
        Texture not over ``(Vs_src, F_src)``, invalid bases, a malformed
        correspondence (see :func:`check_correspondence`) or a bad ``samples``.

    Examples
    --------
    >>> from geotex.heighttilt import spiky_sphere, extract_texture, apply_texture
    >>> from geotex.mesh.primitives import icosphere
    >>> V0, F, Vs = spiky_sphere(subdivisions=2, spikes=4, seed=0)
    >>> tex, _ = extract_texture(V0, F, base=Vs)
    >>> Vd, Fd = icosphere(3)
    >>> corr = closest_point_correspondence(Vd, Vs, F)
    >>> out = transfer_texture(Vs, F, tex, Vd, Fd, correspondence=corr)
    >>> out.height.shape
    (642,)
    """
    Vs, Fs = check_texture(Vs_src, F_src, tex)
    Vd, Fd = check_base_mesh(V_dst, F_dst, name="V_dst")
    faces, bary = check_correspondence(correspondence, Vd.shape[0], Fs.shape[0])
    if (isinstance(samples, (bool, np.bool_)) or not isinstance(samples, (int, np.integer))
            or samples < 1):
        raise InputError(f"samples must be an integer >= 1, got {samples!r}")
    samples = int(samples)
    # source fields per vertex
    t_src = decode_tilt(Vs, Fs, tex.tilt, tex.residual)
    n_src = base_normals(Vs, Fs)

    def source_at(fc, B):
        T = Fs[fc]
        t = np.einsum("pk,pkd->pd", B, t_src[T])
        n = _unit(np.einsum("pk,pkd->pd", B, n_src[T]))
        return t, n

    height = np.einsum("pk,pk->p", bary, tex.height[Fs[faces]])
    n_dst = base_normals(Vd, Fd)
    # vertex targets
    tv, nv = source_at(faces, bary)
    tv = _rotate(tv, nv, n_dst)
    tv -= np.einsum("nd,nd->n", tv, n_dst)[:, None] * n_dst
    # edge samples mapped into the source
    topo = edge_topology(Fd, Vd.shape[0])
    E = topo.edges
    P = np.einsum("pk,pkd->pd", bary, Vs[Fs[faces]])              # source points of vertices
    src_pts, _ = segment_samples(P[E[:, 0]], P[E[:, 1]], samples=samples)
    fq, bq = _project(src_pts.reshape(-1, 3), Vs, Fs)
    tq, nq = source_at(fq, bq)
    # destination normal along each edge: interpolation of its end normals at the
    # Gauss-Legendre parameters used by segment_samples / line_integrals
    qs = np.polynomial.legendre.leggauss(samples)[0] * 0.5 + 0.5
    nd = _unit((1.0 - qs)[None, :, None] * n_dst[E[:, 0]][:, None, :]
               + qs[None, :, None] * n_dst[E[:, 1]][:, None, :]).reshape(-1, 3)
    tq = _rotate(tq, nq, nd)
    tq -= np.einsum("kd,kd->k", tq, nd)[:, None] * nd
    c = line_integrals(tq.reshape(E.shape[0], samples, 3), Vd[E[:, 0]], Vd[E[:, 1]],
                       samples=samples)
    u = decode_tilt(Vd, Fd, c, topology=topo)
    _, D1, D2 = tilt_frames(Vd, Fd, c)
    miss = tv - u
    r = np.column_stack([np.einsum("nd,nd->n", miss, D1), np.einsum("nd,nd->n", miss, D2)])
    meta = {"source": "transfer_texture", "samples": samples}
    return HeightTiltTexture(height=height, tilt=c, faces=Fd, residual=r, metadata=meta)
