"""Distortion of a piecewise-linear map from a triangle mesh to the plane.

On every face the map is linear; its Jacobian ``J`` (2x2, from an
orthonormal frame of the face plane to texture space) has singular values
``s1 >= s2 >= 0``, computed in closed form for all faces at once: with
``J = [[a, b], [c, d]]``, ``q = |((a + d)/2, (c - b)/2)|`` and
``r = |((a - d)/2, (c + b)/2)|`` give ``s1 = q + r``, ``s2 = |q - r|`` and
``det J = q^2 - r^2``.

Measures (all zero for an isometry, i.e. ``s1 = s2 = 1``):

* **area** – ``area_ratio = s1 s2`` (texture area per surface area).  The
  error is ``|log(s1 s2)|``; ``|log(s1 s2 / R)|`` with ``R`` the ratio of the
  total texture area to the total surface area ignores a global scale (the
  right measure for maps whose scale is arbitrary, e.g. LSCM, or a
  field-aligned map with ``scale != 1``).
* **angle** – the conformal ratio ``s1 / s2 >= 1`` and the conformal error
  ``(s1/s2 + s2/s1) / 2 - 1 = (s1 - s2)^2 / (2 s1 s2)`` (the MIPS energy minus
  its minimum; zero exactly for similarities, independent of scale).
* **flips** – faces with ``det J < 0`` (orientation reversed); faces with
  ``s2 = 0`` are *collapsed*.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_faces, as_mesh_arrays

__all__ = ["face_jacobians", "singular_values", "FaceDistortion", "face_distortion",
           "DistortionStat", "DistortionSummary", "distortion_summary"]


def _uv_args(V, F, uv, uv_faces):
    V, F = as_mesh_arrays(V, F)
    UV = np.ascontiguousarray(uv, dtype=np.float64)
    if UV.ndim != 2 or UV.shape[1] != 2:
        raise InputError(f"uv must have shape (k, 2), got {UV.shape}")
    if not np.all(np.isfinite(UV)):
        raise InputError("uv has non-finite texture coordinates")
    if uv_faces is None:
        if UV.shape[0] != V.shape[0]:
            raise InputError(f"uv has {UV.shape[0]} rows but V has {V.shape[0]}; pass uv_faces "
                             "when texture coordinates are indexed separately")
        FT = F
    else:
        FT = as_faces(uv_faces, UV.shape[0], name="uv_faces")
        if FT.shape[0] != F.shape[0]:
            raise InputError(f"uv_faces has {FT.shape[0]} rows but F has {F.shape[0]}")
    return V, F, UV, FT


def face_jacobians(V, F, uv, *, uv_faces=None) -> tuple[np.ndarray, np.ndarray]:
    """Jacobian of the map on every face, in an orthonormal frame of the face.

    The frame is ``e1 = (x1 - x0)/|x1 - x0|``, ``e2 = n x e1``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    uv : array_like, (n, 2) float64, or (k, 2) with ``uv_faces``
    uv_faces : array_like, (m, 3) int64, optional
        Corners of every face in ``uv`` (defaults to ``F``).

    Returns
    -------
    J : numpy.ndarray, (m, 2, 2) float64
        NaN on faces of zero surface area.
    area : numpy.ndarray, (m,) float64
        Surface area of every face.
    """
    V, F, UV, FT = _uv_args(V, F, uv, uv_faces)
    P = V[F]
    a = P[:, 1] - P[:, 0]
    b = P[:, 2] - P[:, 0]
    la = np.linalg.norm(a, axis=1)
    cr = np.cross(a, b)
    dbl = np.linalg.norm(cr, axis=1)
    ok = (la > 0) & (dbl > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        b1 = np.einsum("ij,ij->i", b, a) / la
        b2 = dbl / la
        Q = UV[FT]
        q1 = Q[:, 1] - Q[:, 0]
        q2 = Q[:, 2] - Q[:, 0]
        J = np.empty((F.shape[0], 2, 2))
        J[:, :, 0] = q1 / la[:, None]
        J[:, :, 1] = (q2 - q1 * (b1 / la)[:, None]) / b2[:, None]
    J[~ok] = np.nan
    return J, 0.5 * dbl


def singular_values(J) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-form singular values and determinant of 2x2 matrices.

    Parameters
    ----------
    J : array_like, (m, 2, 2) float64

    Returns
    -------
    s1, s2 : numpy.ndarray, (m,) float64
        ``s1 >= s2 >= 0``.
    det : numpy.ndarray, (m,) float64
    """
    J = np.asarray(J, dtype=np.float64)
    if J.ndim != 3 or J.shape[1:] != (2, 2):
        raise InputError(f"J must have shape (m, 2, 2), got {J.shape}")
    a, b, c, d = J[:, 0, 0], J[:, 0, 1], J[:, 1, 0], J[:, 1, 1]
    q = np.hypot(0.5 * (a + d), 0.5 * (c - b))
    r = np.hypot(0.5 * (a - d), 0.5 * (c + b))
    return q + r, np.abs(q - r), a * d - b * c


@dataclass(frozen=True, eq=False)
class FaceDistortion:
    """Per-face distortion of a map (all arrays ``(m,)`` float64 unless noted).

    Attributes
    ----------
    s1, s2 : singular values, ``s1 >= s2 >= 0``
    det : signed Jacobian determinant (negative on flipped faces)
    area : surface area of every face (the weights of the summary)
    area_ratio : ``s1 * s2``
    log_area : ``log(s1 * s2)``
    log_area_normalized : ``log(s1 * s2 / R)``, ``R`` the global area ratio
    stretch_ratio : ``s1 / s2`` (``inf`` on collapsed faces)
    conformal_error : ``(s1/s2 + s2/s1)/2 - 1``
    flipped, collapsed : (m,) bool
    global_area_ratio : float, ``R`` = total texture area / total surface area
    """

    s1: np.ndarray
    s2: np.ndarray
    det: np.ndarray
    area: np.ndarray
    area_ratio: np.ndarray
    log_area: np.ndarray
    log_area_normalized: np.ndarray
    stretch_ratio: np.ndarray
    conformal_error: np.ndarray
    flipped: np.ndarray
    collapsed: np.ndarray
    global_area_ratio: float


def face_distortion(V, F, uv, *, uv_faces=None) -> FaceDistortion:
    """Per-face singular values and area / angle distortion of a map.

    See the module docstring for the definitions.  Faces of zero surface
    area get NaN values (and are neither flipped nor collapsed).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    uv : array_like, (n, 2) float64, or (k, 2) with ``uv_faces``
    uv_faces : array_like, (m, 3) int64, optional

    Returns
    -------
    FaceDistortion

    Raises
    ------
    InputError
        On malformed or mismatched arrays.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(2, 2)
    >>> d = face_distortion(V, F, V[:, :2] * [2.0, 1.0])
    >>> bool(np.allclose(d.area_ratio, 2) and np.allclose(d.stretch_ratio, 2))
    True
    """
    J, area = face_jacobians(V, F, uv, uv_faces=uv_faces)
    s1, s2, det = singular_values(J)
    valid = np.isfinite(s1)
    with np.errstate(divide="ignore", invalid="ignore"):
        collapsed = valid & ~(s2 > 1e-14 * s1)
        ratio = s1 * s2
        total = float(area[valid].sum())
        R = float((ratio[valid] * area[valid]).sum() / total) if total > 0 else float("nan")
        log_area = np.log(ratio)
        log_norm = np.log(ratio / R) if R > 0 else np.full_like(ratio, np.nan)
        stretch = np.where(collapsed, np.inf, s1 / s2)
        conformal = np.where(collapsed, np.inf, (s1 - s2) ** 2 / (2.0 * s1 * s2))
    flipped = valid & (det < 0)
    return FaceDistortion(s1=s1, s2=s2, det=det, area=area, area_ratio=ratio, log_area=log_area,
                          log_area_normalized=log_norm, stretch_ratio=stretch,
                          conformal_error=conformal, flipped=flipped, collapsed=collapsed,
                          global_area_ratio=R)


@dataclass(frozen=True)
class DistortionStat:
    """Area-weighted mean, area-weighted 95th percentile and maximum of a measure."""

    mean: float
    p95: float
    max: float


@dataclass(frozen=True)
class DistortionSummary:
    """Summary of a map's distortion.

    Statistics are over faces with positive surface area that are not
    collapsed (those are counted instead), weighted by surface area.

    Attributes
    ----------
    n_faces, n_flipped, n_collapsed : int
    area_ratio : float
        Total texture area / total surface area.
    area : DistortionStat
        Of ``|log(s1 s2)|``.
    area_normalized : DistortionStat
        Of ``|log(s1 s2 / area_ratio)|`` (scale-free).
    angle : DistortionStat
        Of the conformal error ``(s1/s2 + s2/s1)/2 - 1``.
    stretch : DistortionStat
        Of ``s1 / s2``.
    """

    n_faces: int
    n_flipped: int
    n_collapsed: int
    area_ratio: float
    area: DistortionStat
    area_normalized: DistortionStat
    angle: DistortionStat
    stretch: DistortionStat


def _stat(x: np.ndarray, w: np.ndarray) -> DistortionStat:
    if x.size == 0 or not w.sum() > 0:
        return DistortionStat(float("nan"), float("nan"), float("nan"))
    order = np.argsort(x, kind="stable")
    cw = np.cumsum(w[order])
    k = int(np.searchsorted(cw, 0.95 * cw[-1]))
    return DistortionStat(mean=float(np.sum(x * w) / np.sum(w)),
                          p95=float(x[order][min(k, x.size - 1)]), max=float(x.max()))


def distortion_summary(V, F, uv, *, uv_faces=None) -> DistortionSummary:
    """Summarise the distortion of a map (see :func:`face_distortion`).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    uv : array_like, (n, 2) float64, or (k, 2) with ``uv_faces``
    uv_faces : array_like, (m, 3) int64, optional

    Returns
    -------
    DistortionSummary

    Raises
    ------
    InputError
        On malformed or mismatched arrays.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(2, 2)
    >>> s = distortion_summary(V, F, V[:, :2] * [2.0, 1.0])
    >>> round(s.stretch.max, 12), s.n_flipped
    (2.0, 0)
    """
    d = face_distortion(V, F, uv, uv_faces=uv_faces)
    ok = np.isfinite(d.s1) & (d.area > 0) & ~d.collapsed
    w = d.area[ok]
    return DistortionSummary(
        n_faces=int(d.s1.size), n_flipped=int(d.flipped.sum()),
        n_collapsed=int(d.collapsed.sum()), area_ratio=d.global_area_ratio,
        area=_stat(np.abs(d.log_area[ok]), w),
        area_normalized=_stat(np.abs(d.log_area_normalized[ok]), w),
        angle=_stat(d.conformal_error[ok], w),
        stretch=_stat(d.stretch_ratio[ok], w))
