"""Near-conformal maps of closed genus-0 meshes onto the unit sphere, and their alignment.

:func:`sphere_map` follows the punctured-sphere construction of Angenent,
Haker et al.: the mesh punctured at one face (the *pole face*) is mapped
conformally onto the plane by solving two cotangent-Laplacian systems whose
right-hand side is the discrete derivative of a delta at the pole face (so
the pole face goes to infinity; cotan weights below a small positive floor
are raised to it), and the plane is wrapped onto the sphere by inverse
stereographic projection.
The discretisation is least accurate around the pole, so a few pole faces
chosen from the geometry (not the indexing) are tried and the map with the
smallest area-weighted conformal error is kept.  The result is normalised by
*Mobius centring*: hyperbolic translations of the unit ball (conformal on
the sphere) are applied until the area-weighted centroid of the sphere
points is at the origin, which fixes the map up to a rotation.

:func:`aligned_sphere_map` fixes that rotation: by default the sphere points
are rotated (Kabsch, area weighted) onto the directions of the shape's
*whitened principal coordinates* (centroid removed, principal axes with the
sign of the third moment, each axis divided by its standard deviation), so
two shapes of different proportions (an ellipsoid 1:1:2 and a pear) land in
one common frame: long axis to long axis, heavy end to heavy end.
:func:`landmark_rotation` instead rotates a source sphere onto a target
sphere through pairs of corresponding points.

Maps of two shapes in the common frame give a correspondence between the
shapes (:func:`geotex.heighttilt.transfer.sphere_correspondence`).
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.linalg import factor
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_areas, signed_volume
from geotex.mesh.topology import edge_topology, vertex_components
from geotex.param.distortion import singular_values

__all__ = ["sphere_map", "aligned_sphere_map", "principal_frame", "landmark_rotation",
           "point_on_sphere", "conformal_error", "check_sphere_topology",
           "CENTERING_ITERATIONS"]

#: Mobius centring steps at most (stops when the centroid is within 1e-9 of the origin).
CENTERING_ITERATIONS = 200
_WEIGHT_FLOOR = 1e-3       # cotan weights below this fraction of their mean are raised to it


def check_sphere_topology(V, F, *, name: str = "V") -> tuple[np.ndarray, np.ndarray]:
    """Validate a closed, connected, manifold genus-0 triangle mesh; return arrays.

    Raises
    ------
    InputError
        Empty mesh, boundary or non-manifold edges, inconsistent orientation,
        unused vertices, several components, or an Euler characteristic other
        than 2.
    """
    V, F = as_mesh_arrays(V, F)
    n, m = V.shape[0], F.shape[0]
    if n < 4 or m < 4:
        raise InputError(f"{name} needs a closed mesh (at least 4 vertices and faces), "
                         f"got {n} vertices and {m} faces")
    topo = edge_topology(F, n)
    if topo.non_manifold.size:
        raise InputError(f"{name} has {topo.non_manifold.size} non-manifold edges; "
                         "a sphere map needs a closed manifold mesh")
    if topo.boundary.size:
        raise InputError(f"{name} has {topo.boundary.size} boundary edges; a sphere map needs "
                         "a closed mesh (fill the holes first)")
    if np.any(topo.forward_count != 1):
        raise InputError(f"{name} is not consistently oriented (an edge is used twice in the "
                         "same direction); orient the faces first (geotex.repair)")
    if np.bincount(F.ravel(), minlength=n).min() == 0:
        raise InputError(f"{name} has vertices used by no face; remove them first")
    k, _ = vertex_components(F, n)
    if k != 1:
        raise InputError(f"{name} has {k} components; a sphere map needs one")
    chi = n - topo.edges.shape[0] + m
    if chi != 2:
        raise InputError(f"{name} has genus {(2 - chi) // 2} (Euler characteristic {chi}); "
                         "a sphere map needs genus 0")
    if np.any(face_areas(V, F) <= 0):
        raise InputError(f"{name} has zero-area faces; remove them (geotex.repair) first")
    return V, F


def _vertex_areas(V, F) -> np.ndarray:
    a = face_areas(V, F) / 3.0
    return np.bincount(F.ravel(), weights=np.repeat(a, 3), minlength=V.shape[0])


def _pole_candidates(V, F) -> list[int]:
    """Pole faces to try, chosen from the geometry (not the indexing).

    The faces nearest to and farthest from the area-weighted centroid, and the
    two extreme faces along the middle principal axis.  Which pole gives the
    most conformal map depends on the shape (a tip is best for an ellipsoid, a
    point on the body for Spot, whose tips are horns and ears), so
    :func:`sphere_map` keeps the candidate with the smallest measured error.
    """
    C = V[F].mean(axis=1)
    c, axes, _ = principal_frame(V, F)
    d = np.linalg.norm(C - c, axis=1)
    along = (C - c) @ axes[1]
    out = []
    for f in (int(np.argmin(d)), int(np.argmax(d)), int(np.argmax(along)), int(np.argmin(along))):
        if f not in out:
            out.append(f)
    return out


def conformal_error(V, F, S) -> float:
    """Area-weighted mean conformal error ``(s1/s2 + s2/s1)/2 - 1`` of the map ``V -> S``.

    Per face, the linear map between the two triangles (each in its own plane).
    """
    def planar(P):
        e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
        l1 = np.linalg.norm(e1, axis=1)
        x = e1 / l1[:, None]
        nn = np.cross(e1, e2)
        y = np.cross(nn / np.linalg.norm(nn, axis=1)[:, None], x)
        M = np.empty((P.shape[0], 2, 2))
        M[:, 0, 0], M[:, 1, 0] = l1, 0.0
        M[:, 0, 1], M[:, 1, 1] = (e2 * x).sum(1), (e2 * y).sum(1)
        return M
    A, B = planar(V[F]), planar(S[F])
    with np.errstate(divide="ignore", invalid="ignore"):
        J = B @ np.linalg.inv(A)
        s1, s2, _ = singular_values(J)
        err = np.where(s2 > 0, 0.5 * (s1 / s2 + s2 / s1) - 1.0, np.inf)
    w = face_areas(V, F)
    return float(np.sum(w * err) / w.sum())


def _planar_map(V, F, pole: int) -> np.ndarray:
    """Conformal map of the sphere punctured at the pole face onto the plane.

    Solves ``L x = a``, ``L y = b`` with ``L`` the (floored) cotangent
    Laplacian and ``a - i b`` the discrete ``(d/du - i d/dv) delta`` at the
    pole face ``ABC`` (Angenent, Haker et al.): ``a_A = -1/|AB|``,
    ``a_B = 1/|AB|``; with ``E`` the foot of ``C`` on ``AB`` and
    ``theta = <C - A, B - A> / |B - A|^2``: ``b_A = (1 - theta)/|CE|``,
    ``b_B = theta/|CE|``, ``b_C = -1/|CE|``.  Both right-hand sides sum to
    zero, so pinning one vertex only fixes the translation.
    """
    n = V.shape[0]
    L = sp.csr_matrix(igl.cotmatrix(V, F))
    W = (L - sp.diags(L.diagonal())).tocoo()
    floor = _WEIGHT_FLOOR * float(np.abs(W.data).mean())
    W = sp.csr_matrix((np.maximum(W.data, floor), (W.row, W.col)), shape=(n, n))
    W = 0.5 * (W + W.T)
    L = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsc()
    iA, iB, iC = (int(i) for i in F[pole])
    A, B, C = V[iA], V[iB], V[iC]
    ab = B - A
    theta = float((C - A) @ ab) / float(ab @ ab)
    E = A + theta * ab
    ce = float(np.linalg.norm(C - E))
    rhs = np.zeros((n, 2))
    rhs[iA, 0], rhs[iB, 0] = -1.0 / np.linalg.norm(ab), 1.0 / np.linalg.norm(ab)
    rhs[iA, 1], rhs[iB, 1], rhs[iC, 1] = (1.0 - theta) / ce, theta / ce, -1.0 / ce
    keep = np.ones(n, dtype=bool)
    keep[iC] = False                      # pin: the translation is free
    idx = np.flatnonzero(keep)
    uv = np.zeros((n, 2))
    uv[idx] = factor(L[idx][:, idx], what="sphere map").solve(rhs[idx])
    return uv


def _inverse_stereographic(uv: np.ndarray) -> np.ndarray:
    r2 = (uv * uv).sum(axis=1)
    return np.column_stack([2 * uv[:, 0], 2 * uv[:, 1], r2 - 1.0]) / (r2 + 1.0)[:, None]


def _mobius_centered(S: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Apply ball translations until the ``w``-weighted centroid of ``S`` is the origin."""
    w = w / w.sum()
    for _ in range(CENTERING_ITERATIONS):
        c = (w[:, None] * S).sum(axis=0)
        if np.linalg.norm(c) < 1e-9:
            break
        a = 0.5 * c
        a2 = float(a @ a)
        D = S - a
        S = ((1.0 - a2) * D - (D * D).sum(axis=1)[:, None] * a) / (D * D).sum(axis=1)[:, None]
        S /= np.linalg.norm(S, axis=1, keepdims=True)
    return S


def sphere_map(V, F) -> np.ndarray:
    """Near-conformal map of a closed genus-0 mesh onto the unit sphere.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        Closed, connected, manifold, genus 0, outward oriented.

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Unit vectors; ``(S, F)`` is a sphere-inscribed mesh with the
        orientation of ``(V, F)``, centred (area-weighted centroid of the
        points at the origin to 1e-9).  Unique up to a rotation.

    Raises
    ------
    InputError
        See :func:`check_sphere_topology`.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> S = sphere_map(2.0 * V, F)
    >>> bool(np.allclose(np.linalg.norm(S, axis=1), 1.0))
    True
    """
    V, F = check_sphere_topology(V, F)
    w = _vertex_areas(V, F)
    best, best_err = None, np.inf
    for pole in _pole_candidates(V, F):
        uv = _planar_map(V, F, pole)
        scale = np.sqrt(np.average((uv * uv).sum(axis=1), weights=w))
        S = _inverse_stereographic(uv / max(scale, 1e-300))
        if signed_volume(S, F) < 0:
            S[:, 2] = -S[:, 2]
        S = _mobius_centered(S, w)
        err = conformal_error(V, F, S)
        if err < best_err:
            best, best_err = S, err
    return best


def principal_frame(V, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Area-weighted centroid, principal axes and standard deviations of a surface.

    Returns
    -------
    center : numpy.ndarray, (3,)
    axes : numpy.ndarray, (3, 3)
        Rows are the principal axes, by decreasing standard deviation; the
        first two point to the side of positive third moment (the heavier
        tail); the third is their cross product (a rotation).
    sigma : numpy.ndarray, (3,)
        Standard deviations along the axes.
    """
    V, F = as_mesh_arrays(V, F)
    w = _vertex_areas(V, F)
    w = w / w.sum()
    c = (w[:, None] * V).sum(axis=0)
    X = V - c
    C = (w[:, None] * X).T @ X
    vals, vecs = np.linalg.eigh(C)
    order = np.argsort(vals)[::-1]
    axes = vecs[:, order].T
    for k in range(2):
        m3 = float((w * (X @ axes[k]) ** 3).sum())
        if m3 < 0:
            axes[k] = -axes[k]
    axes[2] = np.cross(axes[0], axes[1])
    sigma = np.sqrt(np.maximum(vals[order], 0.0))
    return c, axes, sigma


def _kabsch(A: np.ndarray, B: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Rotation ``R`` minimising ``sum w |R a - b|^2`` (rows of A, B)."""
    H = (w[:, None] * A).T @ B
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    return Vt.T @ np.diag([1.0, 1.0, d]) @ U.T


def aligned_sphere_map(V, F) -> np.ndarray:
    """:func:`sphere_map` rotated into the shape's whitened principal frame.

    The sphere points are rotated (area weighted Kabsch) onto the unit
    directions of ``diag(1/sigma) axes (V - center)`` (see
    :func:`principal_frame`).  Two shapes mapped this way share one frame.
    Shapes with a symmetric mass distribution along an axis (zero third
    moment) leave that axis' sign to round-off: pass landmarks then
    (:func:`landmark_rotation`).

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Unit vectors.

    Raises
    ------
    InputError
        See :func:`check_sphere_topology`.
    """
    V, F = check_sphere_topology(V, F)
    S = sphere_map(V, F)
    c, axes, sigma = principal_frame(V, F)
    X = ((V - c) @ axes.T) / np.maximum(sigma, 1e-300)
    X /= np.maximum(np.linalg.norm(X, axis=1, keepdims=True), 1e-300)
    R = _kabsch(S, X, _vertex_areas(V, F))
    return S @ R.T


def point_on_sphere(V, F, S, points) -> np.ndarray:
    """Sphere points of the surface points closest to ``points``.

    Parameters
    ----------
    V, F : the mesh; S : (n, 3) its sphere map; points : (k, 3)

    Returns
    -------
    numpy.ndarray, (k, 3) float64
        Barycentric interpolation of ``S`` at the closest surface points,
        normalised.
    """
    P = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    _, idx, C = igl.point_mesh_squared_distance(P, V, F)
    T = F[np.asarray(idx, dtype=np.int64)]
    B = igl.barycentric_coordinates(np.ascontiguousarray(C), np.ascontiguousarray(V[T[:, 0]]),
                                    np.ascontiguousarray(V[T[:, 1]]),
                                    np.ascontiguousarray(V[T[:, 2]]))
    Q = np.einsum("pk,pkd->pd", np.asarray(B), S[T])
    return Q / np.linalg.norm(Q, axis=1, keepdims=True)


def landmark_rotation(src_points: np.ndarray, dst_points: np.ndarray) -> np.ndarray:
    """Rotation taking source sphere landmarks onto target sphere landmarks.

    Parameters
    ----------
    src_points, dst_points : array_like, (k, 3) float64
        Unit vectors, ``k >= 2`` corresponding pairs.

    Returns
    -------
    numpy.ndarray, (3, 3)
        ``R`` minimising ``sum |R a_k - b_k|^2``.

    Raises
    ------
    InputError
        Fewer than two pairs, or pairs that leave the rotation undetermined
        (all landmarks on one line through the centre).
    """
    A = np.asarray(src_points, dtype=np.float64).reshape(-1, 3)
    B = np.asarray(dst_points, dtype=np.float64).reshape(-1, 3)
    if A.shape[0] < 2 or A.shape != B.shape:
        raise InputError(f"landmarks: give at least two corresponding point pairs, got "
                         f"{A.shape[0]}")
    if np.linalg.matrix_rank(A, tol=1e-6) < 2 or np.linalg.matrix_rank(B, tol=1e-6) < 2:
        raise InputError("landmarks: the points lie on one line through the shape's "
                         "centre on the sphere; the rotation is undetermined")
    return _kabsch(A, B, np.ones(A.shape[0]))
