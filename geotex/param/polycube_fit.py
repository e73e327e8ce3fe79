"""Fit the polycube surface onto the base mesh: the map from tiles to the base.

The triangle sub-grid of the polycube (:mod:`~geotex.param.polycube_surface`)
starts at the voxel surface, which lies within about a cell of the base
surface. It is moved onto the base by alternating

1. projection of every vertex onto the base, restricted to base faces that
   face the same way as the vertex's *reference normal* (the voxel surface's
   vertex normals, smoothed, blended with the current normals), so the two
   sides of a thin part never collapse onto one side; and
2. tangential relaxation: every vertex moves toward the mean of its
   neighbours within the base's tangent plane, which spreads the polycube's
   unavoidable stretch evenly instead of leaving it at the voxel steps
   (vertices whose polycube position already lies on the base, and that are
   a few rings away from any that does not, stay where they are).

Faces whose normal ends up opposite to the base normal below them are
*folded*; a few local rounds of plain smoothing and projection around them
untangle most folds. What remains is reported, never hidden.

Last, :func:`reached_surface` moves the fitted surface outward where the
base sticks out of it (a horn thinner than a voxel: the projection puts the
sub-grid on the horn's root, the closest base to it, and the horn itself stays
outside), so that the texture laid on the surface reaches the base there.
"""

from __future__ import annotations

from dataclasses import dataclass

import igl
import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from geotex.mesh.geometry import clamped_barycentric, face_cross, face_normals
from geotex.mesh.topology import neighbour_mean

__all__ = ["closest_points_on_triangles", "SurfaceProjector", "SurfaceFit", "fitted_surface",
           "reached_surface"]


def closest_points_on_triangles(X: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray
                                ) -> np.ndarray:
    """Closest point of triangle ``(A_i, B_i, C_i)`` to ``X_i``, all ``(k, 3)``.

    Vectorized region test (vertex, edge or interior region of the triangle).
    """
    ab, ac = B - A, C - A
    ap, bp, cp = X - A, X - B, X - C
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        den = va + vb + vc
        out = A + (vb / den)[:, None] * ab + (vc / den)[:, None] * ac          # interior
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        t_ac = d2 / (d2 - d6)
        t_ab = d1 / (d1 - d3)
        cases = [  # Voronoi regions; applied in reverse priority, so the first listed wins
            ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), B + t_bc[:, None] * (C - B)),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), A + t_ac[:, None] * ac),
            ((d6 >= 0) & (d5 <= d6), C),
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), A + t_ab[:, None] * ab),
            ((d3 >= 0) & (d4 <= d3), B),
            ((d1 <= 0) & (d2 <= 0), A),
        ]
        for mask, value in cases:
            out[mask] = value[mask]
    bad = ~np.isfinite(out).all(axis=1)          # degenerate triangles: nearest corner
    if bad.any():
        corners = np.stack([A[bad], B[bad], C[bad]], axis=1)
        j = np.argmin(((corners - X[bad, None, :]) ** 2).sum(axis=2), axis=1)
        out[bad] = corners[np.arange(j.size), j]
    return out


#: Two fixed ray directions, along no axis or grid diagonal, for the winding numbers
#: of :meth:`SurfaceProjector.winding_numbers` (unit vectors).
_RAYS = np.array([[1.0, 2.0 ** 0.5, 3.0 ** 0.5], [-(5.0 ** 0.5), 1.0, 7.0 ** 0.5]])
_RAYS /= np.linalg.norm(_RAYS, axis=1, keepdims=True)

#: A ray crossing is trusted when its barycentric coordinates (single precision in
#: libigl's hits) and the cosine between the ray and the face's normal are above this.
_CLEAN = 1e-5


class SurfaceProjector:
    """Closest points on a fixed triangle mesh.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    """

    def __init__(self, V: np.ndarray, F: np.ndarray):
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        self._normals = None
        self._tree = igl.AABB()
        self._tree.init(self.V, self.F)
        self._kd = None

    @property
    def normals(self) -> np.ndarray:
        """Unit face normals ``(m, 3)`` (computed on first use)."""
        if self._normals is None:
            self._normals = face_normals(self.V, self.F)
        return self._normals

    @property
    def _centroids(self) -> cKDTree:
        if self._kd is None:                     # only the restricted projection needs it
            self._kd = cKDTree(self.V[self.F].mean(axis=1))
        return self._kd

    def closest(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closest points ``(k, 3)`` and their faces ``(k,)``."""
        _, face, C = self._tree.squared_distance(self.V, self.F, np.ascontiguousarray(X))
        return np.asarray(C, dtype=np.float64), np.asarray(face, dtype=np.int64)

    def winding_numbers(self, X: np.ndarray) -> np.ndarray:
        """Winding numbers of the closed mesh at points ``X`` ``(k, 3)`` off it, ``(k,)``.

        Counted as the signed crossings of a ray from every point through the
        AABB tree of the closest-point queries (+1 where the ray leaves
        through a face, -1 where it enters): on a closed mesh, self-crossing
        or not, that is the winding number. A point is counted along two
        fixed directions; where the two counts differ, or a crossing lies
        within ``1e-5`` of a face's edge (barycentric) or grazes the face,
        libigl's fast winding number is used instead. A point on the mesh
        has no defined winding number (either answer may come back).

        Parameters
        ----------
        X : numpy.ndarray, (k, 3) float64

        Returns
        -------
        numpy.ndarray, (k,) float64
            Integers where the rays decide; libigl's (approximate) fast winding
            number elsewhere.

        Examples
        --------
        >>> from geotex.mesh.primitives import icosphere
        >>> V, F = icosphere(2)
        >>> SurfaceProjector(V, F).winding_numbers(np.array([[0.0, 0.1, 0.0], [2.0, 0.0, 0.0]]))
        array([1., 0.])
        """
        X = np.ascontiguousarray(X, dtype=np.float64)
        k = X.shape[0]
        counts, trusted = [], np.ones(k, dtype=bool)
        for d in _RAYS:
            hits = self._tree.intersect_ray(self.V, self.F, X,
                                            np.ascontiguousarray(np.broadcast_to(d, X.shape)))
            rows = np.repeat(np.arange(k), [len(h) for h in hits])
            flat = np.array([hit for h in hits for hit in h], dtype=np.float64).reshape(-1, 4)
            cos = self.normals[flat[:, 0].astype(np.int64)] @ d
            u, v, t = flat[:, 2], flat[:, 3], flat[:, 1]
            clean = ((u > _CLEAN) & (v > _CLEAN) & (1.0 - u - v > _CLEAN)
                     & (np.abs(cos) > _CLEAN) & (t > 0))
            trusted[rows[~clean]] = False
            counts.append(np.bincount(rows, weights=np.sign(cos), minlength=k))
        out = counts[0]
        redo = np.flatnonzero(~trusted | (counts[0] != counts[1]))
        if redo.size:
            out[redo] = igl.fast_winding_number(self.V, self.F, np.ascontiguousarray(X[redo]))
        return out

    def project(self, X: np.ndarray, N: np.ndarray, *, min_cos: float = 0.0,
                candidates: int = 32) -> tuple[np.ndarray, np.ndarray]:
        """Closest points on faces whose normal makes ``cos > min_cos`` with ``N``.

        Points whose unrestricted closest face faces the wrong way look among
        the ``candidates`` faces with the nearest centroids for the closest
        compatible one; if there is none, the unrestricted point is kept.

        Returns
        -------
        points : numpy.ndarray, (k, 3) float64
        faces : numpy.ndarray, (k,) int64
        """
        C, face = self.closest(X)
        wrong = np.flatnonzero(np.einsum("ij,ij->i", self.normals[face], N) <= min_cos)
        if wrong.size == 0:
            return C, face
        k = min(candidates, self.F.shape[0])
        _, cand = self._centroids.query(X[wrong], k=k)
        cand = np.asarray(cand, dtype=np.int64).reshape(wrong.size, k)
        ok = np.einsum("ijk,ik->ij", self.normals[cand], N[wrong]) > min_cos
        flat = cand.ravel()
        Xr = np.repeat(X[wrong], k, axis=0)
        T = self.V[self.F[flat]]
        Cc = closest_points_on_triangles(Xr, T[:, 0], T[:, 1], T[:, 2]).reshape(wrong.size, k, 3)
        d2 = ((Cc - X[wrong, None, :]) ** 2).sum(axis=2)
        d2[~ok] = np.inf
        j = np.argmin(d2, axis=1)
        rows = np.arange(wrong.size)
        found = np.isfinite(d2[rows, j])
        C[wrong[found]] = Cc[rows[found], j[found]]
        face[wrong[found]] = cand[rows[found], j[found]]
        return C, face


@dataclass(frozen=True)
class SurfaceFit:
    """The polycube sub-grid moved onto the base.

    Attributes
    ----------
    Y : numpy.ndarray, (n, 3) float64
        Fitted vertex positions (on the base surface).
    base_face : numpy.ndarray, (n,) int64
        Base face under every vertex.
    folded : numpy.ndarray, (m,) bool
        Faces whose orientation disagrees with the base below them.
    repaired : int
        Folded faces before the local repair rounds.
    reached : int
        Vertices moved outward by :func:`reached_surface` (0 when it did not run).
    """

    Y: np.ndarray
    base_face: np.ndarray
    folded: np.ndarray
    repaired: int
    reached: int = 0


def _unit(X: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(X, axis=1, keepdims=True)
    return np.divide(X, n, out=np.zeros_like(X), where=n > 0)


def folded_faces(Y: np.ndarray, F: np.ndarray, projector: SurfaceProjector,
                 vertex_base_face: np.ndarray) -> np.ndarray:
    """Faces of ``(Y, F)`` turned over against the base below them.

    A face is folded when its normal points away both from the base face
    closest to its centroid and from the summed normals of the base faces its
    three corners were projected onto (``vertex_base_face``, chosen on the
    corners' own side). The second test keeps a face that spans a crest
    thinner than itself (its corners on both flanks, its centroid closest to
    the underside) from being called folded.
    """
    normals = face_normals(Y, F)
    _, below = projector.closest(Y[F].mean(axis=1))
    corner_side = projector.normals[vertex_base_face[F]].sum(axis=1)
    return ((np.einsum("ij,ij->i", normals, projector.normals[below]) <= 0)
            & (np.einsum("ij,ij->i", normals, corner_side) <= 0))


def _refolded(bad, Y, F, moved, projector, vertex_base_face) -> np.ndarray:
    """``bad`` with the faces touching the ``moved`` vertices tested again."""
    touch = np.flatnonzero(moved[F].any(axis=1))
    out = bad.copy()
    out[touch] = folded_faces(Y, F[touch], projector, vertex_base_face)
    return out


def fitted_surface(P: np.ndarray, F: np.ndarray, projector: SurfaceProjector, *,
                   iterations: int = 40, step: float = 0.8, reference_smoothing: int = 16,
                   repair_rounds: int = 8, tolerance: float = 0.1) -> SurfaceFit:
    """Move the closed surface ``(P, F)`` onto the base of ``projector``.

    Parameters
    ----------
    P : numpy.ndarray, (n, 3) float64
        Start positions in world units (the voxel surface).
    F : numpy.ndarray, (m, 3) int64
    projector : SurfaceProjector
        The base mesh.
    iterations : int
        Most projection + relaxation rounds.
    tolerance : float
        Converged (no more rounds) once 99 % of the vertices move less than
        ``tolerance`` times the sub-grid spacing in a round (tested every
        fourth round from the 16th on, so round-off rarely changes the count).
    step : float
        Fraction of the tangential move toward the neighbour mean per round.
    reference_smoothing : int
        Smoothing steps of the start normals that give every vertex its side.
    repair_rounds : int
        Local untangling rounds around folded faces.

    Returns
    -------
    SurfaceFit
    """
    n = P.shape[0]
    M = neighbour_mean(F, n)
    m = F.shape[0]
    incidence = sp.csr_matrix((np.ones(3 * m), (F.ravel(), np.repeat(np.arange(m), 3))),
                              shape=(n, m))

    def normals(Y):  # area-weighted vertex normals (unit)
        return _unit(incidence @ face_cross(Y, F))

    ref = normals(P)
    for _ in range(reference_smoothing):
        ref = _unit(M @ ref)

    def side(Y):
        return _unit(ref + normals(Y))

    Y, face = projector.project(P, ref)
    # relax only where the polycube does not already lie on the base (a grid-aligned
    # box stays exact), and a few rings around such places
    spacing = np.median(np.linalg.norm(P[F[:, 0]] - P[F[:, 1]], axis=1))
    weight = np.clip(np.linalg.norm(Y - P, axis=1) / (0.1 * spacing), 0.0, 1.0)
    for _ in range(4):
        weight = np.maximum(weight, M @ weight)
    for it in range(iterations):
        C, face = projector.project(Y, side(Y))
        Nb = projector.normals[face]
        d = M @ Y - Y
        d -= np.einsum("ij,ij->i", d, Nb)[:, None] * Nb
        Y, Y0 = C + (step * weight)[:, None] * d, Y
        if it >= 15 and it % 4 == 3 and np.percentile(
                np.linalg.norm(Y - Y0, axis=1), 99) < tolerance * spacing:
            break
    Y, face = projector.project(Y, side(Y))
    bad = folded_faces(Y, F, projector, face)
    before = int(bad.sum())
    ring = (M != 0).astype(np.float64)
    for rnd in range(repair_rounds):
        if not bad.any():
            break
        sel = np.zeros(n, dtype=bool)
        sel[F[bad].ravel()] = True
        for _ in range(2 + rnd // 2):        # a wider neighbourhood for stubborn folds
            sel = (ring @ sel.astype(np.float64)) > 0
        idx = np.flatnonzero(sel)
        # only the selected rows: the same sums as side(Y)[idx] and (M @ Y)[idx]
        near = np.flatnonzero(sel[F].any(axis=1))
        M_idx, inc_idx, F_near = M[idx], incidence[idx][:, near], F[near]
        for _ in range(10):
            side_idx = _unit(ref[idx] + _unit(inc_idx @ face_cross(Y, F_near)))
            Y[idx], face[idx] = projector.project(M_idx @ Y, side_idx)
        bad = _refolded(bad, Y, F, sel, projector, face)
    return SurfaceFit(Y=Y, base_face=face, folded=bad, repaired=before)


def _outside_far(S, surface, depth, closest=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points of ``S`` farther than ``depth`` outside the closed ``surface``
    (a :class:`SurfaceProjector`; ``closest``: its :meth:`~SurfaceProjector.closest`
    of ``S`` when known): their indices, closest points on it and the faces of those."""
    C, face = surface.closest(S) if closest is None else closest
    far = np.flatnonzero(np.linalg.norm(S - C, axis=1) > depth)
    if far.size:
        far = far[surface.winding_numbers(S[far]) < 0.5]
    return far, C[far], face[far]


def reached_surface(fit: SurfaceFit, P: np.ndarray, F: np.ndarray, projector: SurfaceProjector,
                    samples: np.ndarray, weights: np.ndarray, *, depth: float = 0.1,
                    rounds: int = 24, step: float = 0.5, spread: int = 8,
                    stall: float = 0.97, reference_smoothing: int = 16,
                    surface: SurfaceProjector | None = None,
                    closest: tuple[np.ndarray, np.ndarray] | None = None) -> SurfaceFit:
    """The fitted surface moved outward where the base sticks out of it by more than ``depth``.

    A protrusion of the base thinner than a voxel (Spot's horns at tile 0.12)
    is not in the voxel solid, so the fit lays the sub-grid on its root and
    the protrusion stays outside the fitted surface, out of reach of the
    texture laid on it. Each round, every base sample farther than ``depth``
    outside the fitted surface (winding number below one half) pulls the
    corners of the fitted face closest to it toward itself (barycentric
    weights times the sample's weight, averaged per vertex); the pull is
    spread harmonically ``spread`` rings around the pulled vertices (so the
    sub-grid stretches over the protrusion instead of forming a spike),
    ``step`` of it is taken, and the moved vertices are projected back onto
    the base on their own side. Moved vertices of faces that would fold
    (:func:`folded_faces`) go back to where they were in that round. A base
    with no sample that far outside is returned unchanged (the same object).

    Parameters
    ----------
    fit : SurfaceFit
        The fit of :func:`fitted_surface`.
    P : numpy.ndarray, (n, 3) float64
        The start positions given to :func:`fitted_surface` (their normals give
        every vertex its side).
    F : numpy.ndarray, (m, 3) int64
    projector : SurfaceProjector
        The base mesh.
    samples : numpy.ndarray, (k, 3) float64
        Points on the base.
    weights : numpy.ndarray, (k,) float64
        Their area weights.
    depth : float
        Distance outside the fitted surface (in the units of the base) above
        which a sample pulls.
    rounds : int
        Most rounds; fewer once no sample is that far out, or once a round
        leaves more than ``stall`` of the far samples' weighted distance to go
        (the fold guard holds them back).
    step : float
        Fraction of the pull taken per round.
    spread : int
        Smoothing steps that spread the pull to the neighbouring vertices.
    reference_smoothing : int
        As in :func:`fitted_surface`.
    surface : SurfaceProjector, optional
        The fitted surface ``(fit.Y, F)``, when the caller has built it (its
        tree is used for the first test, not built again).
    closest : tuple of numpy.ndarray, optional
        ``surface.closest(samples)`` when the caller has it.

    Returns
    -------
    SurfaceFit
        With ``reached`` the number of vertices that moved.
    """
    S = np.asarray(samples, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    Y, face = fit.Y, fit.base_face
    far, C, fface = _outside_far(S, SurfaceProjector(Y, F) if surface is None else surface,
                                 depth, closest)
    if far.size == 0:
        return fit
    n = Y.shape[0]
    M = neighbour_mean(F, n)
    m = F.shape[0]
    incidence = sp.csr_matrix((np.ones(3 * m), (F.ravel(), np.repeat(np.arange(m), 3))),
                              shape=(n, m))
    ref = _unit(incidence @ face_cross(P, F))
    for _ in range(reference_smoothing):
        ref = _unit(M @ ref)
    Y, face = Y.copy(), face.copy()
    bad = fit.folded
    # samples that can pull: the ones far out at the start (later rounds only
    # bring the surface nearer to the base, so no other sample gets far)
    near = S[far]
    wn = w[far]
    gap = wn @ np.linalg.norm(near - C, axis=1)      # weighted distance still to go
    for _ in range(rounds):
        corners = F[fface]
        T = Y[corners]
        b = clamped_barycentric(C, T[:, 0], T[:, 1], T[:, 2]) * wn[:, None]
        W = np.zeros(n)
        pull = np.zeros((n, 3))
        np.add.at(W, corners.ravel(), b.ravel())
        np.add.at(pull, corners.ravel(), (b[:, :, None] * (near - C)[:, None, :]).reshape(-1, 3))
        pulled = W > 0
        pull[pulled] /= W[pulled, None]
        for _ in range(spread):
            pull = np.where(pulled[:, None], pull, M @ pull)
        moved = np.flatnonzero(np.linalg.norm(pull, axis=1) > 0)
        Y0, face0 = Y.copy(), face.copy()
        Nn = _unit(ref[moved] + _unit((incidence @ face_cross(Y, F))[moved]))
        Y[moved], face[moved] = projector.project(Y[moved] + step * pull[moved], Nn)
        mask = np.zeros(n, dtype=bool)
        mask[moved] = True
        now = _refolded(bad, Y, F, mask, projector, face)
        for _ in range(8):             # put back the moved corners of faces that fold
            new = now & ~bad
            if not new.any():
                break
            back = np.zeros(n, dtype=bool)
            back[F[new].ravel()] = True
            back &= mask & (Y != Y0).any(axis=1)
            if not back.any():
                break
            Y[back], face[back] = Y0[back], face0[back]
            now = _refolded(now, Y, F, back, projector, face)
        bad = now
        sub, C, fface = _outside_far(near, SurfaceProjector(Y, F), depth)
        gap, gap0 = wn[sub] @ np.linalg.norm(near[sub] - C, axis=1), gap
        if sub.size == 0 or gap > stall * gap0:
            break
        near, wn = near[sub], wn[sub]
    reached = int(np.count_nonzero((Y != fit.Y).any(axis=1)))
    return SurfaceFit(Y=Y, base_face=face, folded=bad, repaired=fit.repaired, reached=reached)
