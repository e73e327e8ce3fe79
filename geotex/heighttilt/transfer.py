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
:func:`closest_point_correspondence`); between different shapes use
:func:`transfer_between_shapes`, which carries vectors by the map itself.
The minimal rotation is not equivariant under a rigid motion of one base
only: the minimal rotation from ``n`` to ``Q n`` differs from ``Q`` by a
spin about ``Q n``, so for a correspondence between shapes in different
poses the lean directions would be turned about the normal (the
magnitudes, i.e. the lean angles, are kept by the rotation up to the final
tangent projection).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import igl
import numpy as np
from scipy.sparse.csgraph import connected_components
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.fields.oneforms import line_integrals, segment_samples
from geotex.heighttilt._kernels import axis_frames
from geotex.heighttilt.base import base_normals, check_base_mesh, decode_tilt, tilt_frames
from geotex.heighttilt.reconstruct import check_texture
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.mesh.arrays import as_vertices
from geotex.mesh.topology import edge_topology
from geotex.param.distortion import DistortionSummary, distortion_summary
from geotex.param.sphere import (aligned_sphere_map, check_sphere_topology, landmark_rotation,
                                 point_on_sphere)

__all__ = ["transfer_texture", "closest_point_correspondence", "check_correspondence",
           "sphere_correspondence", "transfer_between_shapes", "ShapeTransferReport",
           "HeightStats", "height_stats", "surface_map_distortion", "check_landmarks"]

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


# --------------------------------------------------------------------------
# transfer between different shapes through the sphere

def check_landmarks(landmarks) -> tuple[np.ndarray, np.ndarray] | None:
    """Validate landmarks: pairs ``[[src_x, src_y, src_z], [dst_x, dst_y, dst_z]]``.

    Returns
    -------
    (src, dst) : numpy.ndarray, (k, 3) float64 each, or None for None.

    Raises
    ------
    InputError
        Not a list of pairs of 3-vectors, non-finite, or fewer than 2 pairs.
    """
    if landmarks is None:
        return None
    try:
        L = np.array(landmarks, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("landmarks must be a list of [[x, y, z], [x, y, z]] pairs "
                         "(source point, target point)") from None
    if L.ndim != 3 or L.shape[1:] != (2, 3):
        raise InputError("landmarks must be a list of [[x, y, z], [x, y, z]] pairs "
                         f"(source point, target point), got shape {L.shape}")
    if not np.isfinite(L).all():
        raise InputError("landmarks has non-finite coordinates")
    if L.shape[0] < 2:
        raise InputError(f"landmarks: give at least two pairs, got {L.shape[0]}")
    return L[:, 0].copy(), L[:, 1].copy()


def sphere_correspondence(Vs_src, F_src, V_dst, F_dst, *, landmarks=None
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Correspondence between two closed genus-0 shapes through the unit sphere.

    Both shapes are mapped near-conformally onto the sphere in their whitened
    principal frames (:func:`geotex.param.sphere.aligned_sphere_map`); with
    ``landmarks`` the target sphere is then rotated so that the landmarks'
    sphere points match best (:func:`geotex.param.sphere.landmark_rotation`).
    Every destination vertex's sphere point is located on the source sphere
    mesh (closest point of the inscribed polyhedron); the face and barycentric
    coordinates found there are the correspondence on the source base.

    Parameters
    ----------
    Vs_src, F_src : source base, (n_src, 3) float64 and (m_src, 3) int64
    V_dst, F_dst : destination base
    landmarks : sequence of pairs, optional
        ``[[src_xyz, dst_xyz], ...]`` (at least two), points on or near the
        source and the destination base that should correspond.

    Returns
    -------
    faces : numpy.ndarray, (n_dst,) int64
    bary : numpy.ndarray, (n_dst, 3) float64

    Raises
    ------
    InputError
        A base that is not closed, connected, manifold and genus 0 (see
        :func:`geotex.param.sphere.check_sphere_topology`), malformed or
        degenerate landmarks.
    """
    Vs, Fs = check_sphere_topology(Vs_src, F_src, name="Vs_src")
    Vd, Fd = check_sphere_topology(V_dst, F_dst, name="V_dst")
    marks = check_landmarks(landmarks)
    Ss = aligned_sphere_map(Vs, Fs)
    Sd = aligned_sphere_map(Vd, Fd)
    if marks is not None:
        a = point_on_sphere(Vs, Fs, Ss, marks[0])
        b = point_on_sphere(Vd, Fd, Sd, marks[1])
        R = landmark_rotation(b, a)
        Sd = Sd @ R.T
    return _project(Sd, Ss, Fs)


@dataclass(frozen=True)
class HeightStats:
    """Height statistics of a texture.

    Attributes
    ----------
    mean_abs : float
        Mean ``|h|`` over vertices.
    max : float
        Largest height.
    elements : int
        Connected groups of vertices with ``h > threshold * max``.
    mean_element_height : float
        Mean over those elements of their largest height.
    threshold : float
    """

    mean_abs: float
    max: float
    elements: int
    mean_element_height: float
    threshold: float


def height_stats(F, height, *, threshold: float = 0.25) -> HeightStats:
    """:class:`HeightStats` of per-vertex heights over faces ``F``."""
    h = np.asarray(height, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = h.shape[0]
    top = float(h.max()) if n else 0.0
    if not top > 0:
        return HeightStats(float(np.abs(h).mean()) if n else 0.0, top, 0, 0.0, threshold)
    up = h > threshold * top
    E = edge_topology(F, n).edges
    E = E[up[E[:, 0]] & up[E[:, 1]]]
    G = sp.coo_matrix((np.ones(E.shape[0]), (E[:, 0], E[:, 1])), shape=(n, n))
    _, lab = connected_components(G, directed=False)
    lab = lab[up]
    uniq, inv = np.unique(lab, return_inverse=True)
    peak = np.full(uniq.size, -np.inf)
    np.maximum.at(peak, inv, h[up])
    return HeightStats(float(np.abs(h).mean()), top, int(uniq.size), float(peak.mean()),
                       threshold)


def surface_map_distortion(V, F, W) -> DistortionSummary:
    """Distortion of the piecewise-linear map sending every vertex ``V_i`` to ``W_i``.

    Each image triangle is laid out in its own plane and
    :func:`geotex.param.distortion.distortion_summary` measures the map from
    ``(V, F)`` onto it (area and angle distortion, flips are not detected:
    every image triangle is laid out with positive orientation).
    """
    W = np.asarray(W, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    P = W[F]
    e1 = P[:, 1] - P[:, 0]
    e2 = P[:, 2] - P[:, 0]
    l1 = np.linalg.norm(e1, axis=1)
    x = np.divide(e1, l1[:, None], out=np.zeros_like(e1), where=l1[:, None] > 0)
    nn = np.cross(e1, e2)
    ln = np.linalg.norm(nn, axis=1)
    y = np.cross(np.divide(nn, ln[:, None], out=np.zeros_like(nn), where=ln[:, None] > 0), x)
    uv = np.zeros((F.shape[0], 3, 2))
    uv[:, 1, 0] = l1
    uv[:, 2, 0] = np.einsum("fd,fd->f", e2, x)
    uv[:, 2, 1] = np.einsum("fd,fd->f", e2, y)
    return distortion_summary(V, F, uv.reshape(-1, 2),
                              uv_faces=np.arange(3 * F.shape[0]).reshape(-1, 3))


@dataclass(frozen=True)
class ShapeTransferReport:
    """What :func:`transfer_between_shapes` did and measured.

    Attributes
    ----------
    aligned_by : str
        ``"principal axes"`` or ``"landmarks"``.
    distortion : DistortionSummary
        Of the map destination base -> source base.
    source, target : HeightStats
        Heights of the source texture and of the transferred one.
    tilt_direction_error_deg : tuple of float
        Median and 90th percentile angle between the tilt the destination
        1-form alone decodes to and the source tilt carried by the map's
        differential (its local linear fit), over vertices whose carried tilt
        exceeds 0.1.
    """

    aligned_by: str
    distortion: DistortionSummary
    source: HeightStats
    target: HeightStats
    tilt_direction_error_deg: tuple[float, float]

    def as_dict(self) -> dict:
        """JSON-ready dictionary."""
        return asdict(self)

    def lines(self) -> list[str]:
        """Human-readable summary lines."""
        d = self.distortion
        return [
            f"map: sphere, aligned by {self.aligned_by}; area distortion |log| mean "
            f"{d.area_normalized.mean:.3f} (p95 {d.area_normalized.p95:.3f}), angle error "
            f"mean {d.angle.mean:.4f} (p95 {d.angle.p95:.4f}), stretch p95 {d.stretch.p95:.3f}",
            f"heights: source mean |h| {self.source.mean_abs:.4g}, max {self.source.max:.4g}, "
            f"{self.source.elements} elements of mean height "
            f"{self.source.mean_element_height:.4g}; target mean |h| {self.target.mean_abs:.4g}, "
            f"max {self.target.max:.4g}, {self.target.elements} elements of mean height "
            f"{self.target.mean_element_height:.4g}",
            f"tilt direction error of the 1-form: median {self.tilt_direction_error_deg[0]:.2f} "
            f"deg, p90 {self.tilt_direction_error_deg[1]:.2f} deg",
        ]


def _carried_tilt(Vd, E, P, t_src, n_dst):
    """Source tilts pushed to the destination by the map's per-vertex linear fit.

    At every destination vertex ``v`` a linear map ``M_v`` (3x2, from the
    tangent frame at ``v``) is fitted to the incident edges, ``M_v e_d ~ e_s``
    (``e_s`` the chord between the edge ends' source points); the carried tilt
    is the least-squares preimage of the source tilt under ``M_v``, scaled
    back to the source tilt's length (the lean angle is kept; for a conformal
    map this is the source direction turned by the map's rotation).
    """
    n = Vd.shape[0]
    D1, D2 = axis_frames(n_dst)
    ed = Vd[E[:, 1]] - Vd[E[:, 0]]
    es = P[E[:, 1]] - P[E[:, 0]]
    A = np.zeros((n, 2, 2))
    B = np.zeros((n, 3, 2))
    for col in (E[:, 0], E[:, 1]):
        a = np.stack([np.einsum("ed,ed->e", ed, D1[col]), np.einsum("ed,ed->e", ed, D2[col])], 1)
        for i in range(2):
            for j in range(2):
                A[:, i, j] += np.bincount(col, weights=a[:, i] * a[:, j], minlength=n)
            for d in range(3):
                B[:, d, i] += np.bincount(col, weights=es[:, d] * a[:, i], minlength=n)
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    ok = np.abs(det) > 1e-30
    Ainv = np.zeros_like(A)
    Ainv[ok, 0, 0], Ainv[ok, 1, 1] = A[ok, 1, 1] / det[ok], A[ok, 0, 0] / det[ok]
    Ainv[ok, 0, 1], Ainv[ok, 1, 0] = -A[ok, 0, 1] / det[ok], -A[ok, 1, 0] / det[ok]
    M = np.einsum("vdi,vij->vdj", B, Ainv)                          # (n, 3, 2)
    MtM = np.einsum("vdi,vdj->vij", M, M)
    Mtt = np.einsum("vdi,vd->vi", M, t_src)
    det2 = MtM[:, 0, 0] * MtM[:, 1, 1] - MtM[:, 0, 1] ** 2
    ok &= np.abs(det2) > 1e-30
    x = np.zeros((n, 2))
    x[ok, 0] = (MtM[ok, 1, 1] * Mtt[ok, 0] - MtM[ok, 0, 1] * Mtt[ok, 1]) / det2[ok]
    x[ok, 1] = (MtM[ok, 0, 0] * Mtt[ok, 1] - MtM[ok, 0, 1] * Mtt[ok, 0]) / det2[ok]
    lx = np.linalg.norm(x, axis=1)
    x *= np.divide(np.linalg.norm(t_src, axis=1), lx, out=np.zeros_like(lx), where=lx > 0)[:, None]
    return x[:, :1] * D1 + x[:, 1:] * D2


def transfer_between_shapes(Vs_src, F_src, tex: HeightTiltTexture, V_dst, F_dst, *,
                            landmarks=None, samples: int = 5
                            ) -> tuple[HeightTiltTexture, ShapeTransferReport]:
    """Transfer a texture between two different closed genus-0 shapes (paper section 3.3).

    The map destination -> source is :func:`sphere_correspondence` (both
    bases mapped near-conformally to the unit sphere, aligned by principal
    axes or by landmarks).  Heights are resampled barycentrically.  The tilt
    1-form of a destination edge ``(i, j)`` is the source tilt integrated
    along the chord between the source points of ``i`` and ``j`` (``samples``
    Gauss-Legendre points, each projected onto the source surface) and
    multiplied by ``|e_d| / |e_s|``, the edge's length ratio: for a map that
    is locally a similarity (conformal) this is the line integral of the
    source tilt carried by the map's rotation, with the lean angle kept (the
    same rescaling as :func:`geotex.heighttilt.deform.deformed_texture`).  The
    result is clipped to the paper's bound ``|c| <= |e|``.  A per-vertex
    residual makes the decoded tilt equal, at every destination vertex, the
    source tilt carried by the map's local linear fit (``_carried_tilt``).

    Parameters
    ----------
    Vs_src : array_like, (n_src, 3) float64
        Source base (closed, genus 0).
    F_src : array_like, (m_src, 3) int64
        Must equal ``tex.faces``.
    tex : HeightTiltTexture
    V_dst : array_like, (n_dst, 3) float64
        Destination base (closed, genus 0).
    F_dst : array_like, (m_dst, 3) int64
    landmarks : sequence of pairs, optional
        ``[[src_xyz, dst_xyz], ...]`` corresponding points (at least two).
    samples : int, optional
        Gauss-Legendre points per edge (default 5, as in the paper).

    Returns
    -------
    texture : HeightTiltTexture
        Over ``F_dst``.
    report : ShapeTransferReport
        Map distortion, height statistics before/after and the tilt
        direction error of the transferred 1-form.

    Raises
    ------
    InputError
        Texture not over the source base, a base that is not a closed
        genus-0 manifold, bad landmarks or ``samples``.
    """
    Vs, Fs = check_texture(Vs_src, F_src, tex)
    Vd, Fd = check_base_mesh(V_dst, F_dst, name="V_dst")
    if (isinstance(samples, (bool, np.bool_)) or not isinstance(samples, (int, np.integer))
            or samples < 1):
        raise InputError(f"samples must be an integer >= 1, got {samples!r}")
    samples = int(samples)
    faces, bary = sphere_correspondence(Vs, Fs, Vd, Fd, landmarks=landmarks)
    t_src = decode_tilt(Vs, Fs, tex.tilt, tex.residual)
    n_src = base_normals(Vs, Fs)

    def source_tilt(fc, B):
        T = Fs[fc]
        t = np.einsum("pk,pkd->pd", B, t_src[T])
        n = _unit(np.einsum("pk,pkd->pd", B, n_src[T]))
        return t - np.einsum("pd,pd->p", t, n)[:, None] * n

    height = np.einsum("pk,pk->p", bary, tex.height[Fs[faces]])
    P = np.einsum("pk,pkd->pd", bary, Vs[Fs[faces]])
    topo = edge_topology(Fd, Vd.shape[0])
    E = topo.edges
    pts, _ = segment_samples(P[E[:, 0]], P[E[:, 1]], samples=samples)
    fq, bq = _project(pts.reshape(-1, 3), Vs, Fs)
    tq = source_tilt(fq, bq).reshape(E.shape[0], samples, 3)
    cs = line_integrals(tq, P[E[:, 0]], P[E[:, 1]], samples=samples)
    ld = np.linalg.norm(Vd[E[:, 1]] - Vd[E[:, 0]], axis=1)
    ls = np.linalg.norm(P[E[:, 1]] - P[E[:, 0]], axis=1)
    c = np.divide(cs * ld, ls, out=np.zeros_like(cs), where=ls > 1e-12 * ld)
    np.clip(c, -ld, ld, out=c)
    n_dst = base_normals(Vd, Fd)
    tv = _carried_tilt(Vd, E, P, source_tilt(faces, bary), n_dst)
    u = decode_tilt(Vd, Fd, c, topology=topo)
    _, D1, D2 = tilt_frames(Vd, Fd, c)
    miss = tv - u
    r = np.column_stack([np.einsum("nd,nd->n", miss, D1), np.einsum("nd,nd->n", miss, D2)])
    strong = np.linalg.norm(tv, axis=1) > 0.1
    if strong.any():
        cosang = np.einsum("nd,nd->n", _unit(u[strong]), _unit(tv[strong]))
        ang = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
        err = (float(np.median(ang)), float(np.percentile(ang, 90)))
    else:
        err = (float("nan"), float("nan"))
    report = ShapeTransferReport(
        aligned_by="landmarks" if landmarks is not None else "principal axes",
        distortion=surface_map_distortion(Vd, Fd, P),
        source=height_stats(Fs, tex.height), target=height_stats(Fd, height),
        tilt_direction_error_deg=err)
    meta = {"source": "transfer_between_shapes", "samples": samples, "map": "sphere",
            "aligned_by": report.aligned_by}
    out = HeightTiltTexture(height=height, tilt=c, faces=Fd, residual=r, metadata=meta)
    return out, report
