"""Tangent direction fields per face: projected, principal-curvature and smooth N-direction.

Representation
--------------
A field lives on faces.  At face ``f`` an N-direction (N = 1 vector, N = 2 line,
N = 4 cross) is one angle ``theta_f`` in the face frame ``(T1, T2)`` of
:func:`geotex.fields.frames.face_frames`, defined up to multiples of
``2 pi / N``; it is stored as the complex number ``z_f = exp(i N theta_f)``,
which does not depend on the representative.

Smooth fields (Knöppel et al. 2013, face-based)
-----------------------------------------------
:func:`smooth_direction_field` minimises the discrete Dirichlet energy of the
N-th power field with the discrete Levi-Civita connection
(:func:`geotex.fields.frames.face_connection`)::

    E(z) = sum over interior edges (f, g) of  w_fg | z_g - exp(i N rho_fg) z_f |^2

with ``rho_fg`` the transport angle from ``f`` to ``g`` (unfolding about the
shared edge) and ``w_fg = |e| / (dual path length)`` (edge length over the path
centroid - edge midpoint - centroid).  ``E = z^H A z`` with ``A`` Hermitian
positive semi-definite; the mass matrix is ``M = diag(face area / mean area)``.
All weights are dimensionless, so scaling the mesh leaves the field unchanged.

* With constraints, ``z`` is fixed at the constrained faces (hard; the
  unknowns are eliminated and ``A_uu z_u = -A_uc z_c`` is one sparse complex
  solve) or pulled towards them by strong penalties (``mode="soft"``).
* Without constraints, ``z`` is the eigenvector of the smallest eigenvalue of
  ``A z = lambda M z`` (ARPACK shift-invert with one factorization of
  ``A + eps M``): the globally smoothest unit-norm field.
* Each connected component of the face graph is handled on its own:
  components without a constraint get the smoothest field.

Singularities emerge where the field needs them; their indices sum to the
Euler characteristic (:mod:`geotex.fields.singularities`).
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral

import igl
import numpy as np
import scipy.linalg
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

from geotex.errors import InputError
from geotex.fields.scalar import scale_field
from geotex.linalg import factor, single_threaded_blas
from geotex.fields.frames import (FaceConnection, _checked_arrays, _connection, _frames,
                                  tangent_angles, vectors_from_angles)
from geotex.fields.singularities import _index_numerators, _singularity_list
from geotex.options import positive_number

__all__ = [
    "Constraint",
    "DirectionField",
    "PrincipalDirections",
    "projected_direction_field",
    "principal_direction_field",
    "smooth_direction_field",
    "constraint_scale_field",
]

#: a direction is parallel to the normal when its tangential part is below this
#: fraction of its length
PARALLEL_TOLERANCE = 1e-6
#: default snapping distance of a point constraint, as a fraction of the
#: bounding-box diagonal
SNAP_FRACTION = 1e-2


@dataclass(frozen=True, kw_only=True)
class Constraint:
    """A user constraint on a direction field.

    Give exactly one of ``face`` and ``point``.  Plain dictionaries with the same
    keys are accepted wherever a ``Constraint`` is (``{"face": 12, "direction":
    [1, 0, 0]}`` or ``{"point": [x, y, z], "direction": [...]}``).

    Parameters
    ----------
    direction : array_like, (3,)
        The direction in space; its projection onto the face plane is used.
        Must be finite, non-zero and not (nearly) parallel to the face normal
        (tangential part at least ``1e-6`` of its length).
    face : int, optional
        Face index.
    point : array_like, (3,), optional
        A point on (or near) the surface; it is snapped to the closest face.
        It must lie within ``max_snap_distance`` of the surface (by default
        1 % of the bounding-box diagonal).
    weight : float, optional
        Positive.  Penalty multiplier in ``mode="soft"`` smooth fields, fitting
        weight in RBF fields with ``smoothing > 0``; hard constraints ignore it.
    radius : float, optional
        Positive extent of this constraint's basis function in RBF fields
        (surface distance); ignored by smooth fields.
    scale : float, optional
        Positive texture scale at this constraint, interpolated over the
        surface by :func:`constraint_scale_field`; direction solvers ignore it.
    """

    direction: tuple
    face: int | None = None
    point: tuple | None = None
    weight: float = 1.0
    radius: float | None = None
    scale: float | None = None


_KEYS = ("face", "point", "direction", "weight", "radius", "scale")


@dataclass(frozen=True)
class _Resolved:
    faces: np.ndarray        # (k,) int64
    tangents: np.ndarray     # (k, 3) unit, in the face plane
    weights: np.ndarray      # (k,)
    radii: np.ndarray        # (k,) NaN where not given
    scales: np.ndarray       # (k,) NaN where not given


def _vector3(value, what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be three numbers, got {value!r}") from None
    if arr.shape != (3,):
        raise InputError(f"{what} must be three numbers, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(f"{what} must be finite, got {arr.tolist()}")
    return arr


def _resolve_constraints(V: np.ndarray, F: np.ndarray, conn: FaceConnection, constraints,
                         *, max_snap_distance=None, name: str = "constraints") -> _Resolved:
    """Validate constraints, snap points to faces and project directions."""
    if constraints is None:
        constraints = []
    if isinstance(constraints, (Constraint, dict)) or not hasattr(constraints, "__iter__"):
        raise InputError(f"{name} must be a list of Constraint objects or dicts")
    items = list(constraints)
    m = F.shape[0]
    faces = np.empty(len(items), dtype=np.int64)
    dirs = np.empty((len(items), 3))
    weights = np.empty(len(items))
    radii = np.full(len(items), np.nan)
    scales = np.full(len(items), np.nan)
    points, point_rows = [], []
    for i, c in enumerate(items):
        where = f"{name}[{i}]"
        if isinstance(c, Constraint):
            c = {k: getattr(c, k) for k in _KEYS}
        elif isinstance(c, dict):
            unknown = sorted(set(c) - set(_KEYS))
            if unknown:
                raise InputError(f"{where} has unknown key {unknown[0]!r}; "
                                 f"use {', '.join(_KEYS)}")
        else:
            raise InputError(f"{where} must be a Constraint or a dict, got {type(c).__name__}")
        face, point = c.get("face"), c.get("point")
        if (face is None) == (point is None):
            raise InputError(f"{where} needs exactly one of 'face' and 'point'")
        if c.get("direction") is None:
            raise InputError(f"{where} needs a 'direction'")
        dirs[i] = _vector3(c["direction"], f"{where} direction")
        if not np.linalg.norm(dirs[i]) > 0:
            raise InputError(f"{where} direction is zero; give a non-zero tangent direction")
        weights[i] = positive_number(c.get("weight", 1.0), name=f"{where} weight")
        if c.get("radius") is not None:
            radii[i] = positive_number(c["radius"], name=f"{where} radius")
        if c.get("scale") is not None:
            scales[i] = positive_number(c["scale"], name=f"{where} scale")
        if face is not None:
            if isinstance(face, bool) or not isinstance(face, Integral):
                raise InputError(f"{where} face must be an integer index, got {face!r}")
            if not 0 <= int(face) < m:
                raise InputError(f"{where} face {int(face)} is out of range [0, {m})")
            faces[i] = int(face)
        else:
            points.append(_vector3(point, f"{where} point"))
            point_rows.append(i)
    if points:
        P = np.array(points)
        sq, idx, _ = igl.point_mesh_squared_distance(P, V, F)
        dist = np.sqrt(np.asarray(sq, dtype=np.float64).ravel())
        if max_snap_distance is None:
            limit = SNAP_FRACTION * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
            how = "1% of the bounding-box diagonal"
        else:
            limit = positive_number(max_snap_distance, name="max_snap_distance")
            how = "max_snap_distance"
        far = np.flatnonzero(dist > limit)
        if far.size:
            j = int(far[0])
            raise InputError(
                f"{name}[{point_rows[j]}] point {P[j].tolist()} is {dist[j]:.6g} from the "
                f"surface, farther than {limit:.6g} ({how}); move it onto the surface "
                "or pass a larger max_snap_distance")
        faces[point_rows] = np.asarray(idx, dtype=np.int64).ravel()
    n = conn.N[faces]
    tang = dirs - np.einsum("ij,ij->i", dirs, n)[:, None] * n
    tlen = np.linalg.norm(tang, axis=1)
    dlen = np.linalg.norm(dirs, axis=1)
    bad = np.flatnonzero(~(tlen >= PARALLEL_TOLERANCE * dlen))
    if bad.size:
        i = int(bad[0])
        raise InputError(
            f"{name}[{i}] direction {dirs[i].tolist()} is parallel to the normal of face "
            f"{int(faces[i])}; give a direction along the surface")
    return _Resolved(faces=faces, tangents=tang / tlen[:, None], weights=weights, radii=radii,
                     scales=scales)


@dataclass(frozen=True, eq=False)
class DirectionField:
    """A per-face N-direction field.

    Attributes
    ----------
    vectors : numpy.ndarray, (m, 3) float64
        One unit tangent representative per face; the others are its rotations
        by ``2 pi k / N`` about the face normal (:meth:`representatives`).  At
        hard-constrained faces it is the user's (projected) direction.
    symmetry : int
        ``N``: 1 (vectors), 2 (lines), 4 (crosses), or any positive integer.
    values : numpy.ndarray, (m,) complex128
        ``z_f``, whose argument is ``N theta_f`` in the face frame.  Its modulus
        is the solver's magnitude (it dips near singularities); fields built
        from explicit vectors have modulus 1.
    singularities : tuple of (int, float)
        ``(vertex, index)`` for interior vertices with non-zero index ``k / N``.
    normals : numpy.ndarray, (m, 3) float64
        Unit face normals.
    constrained : numpy.ndarray, (k,) int64
        Faces that carried a constraint, ascending.
    """

    vectors: np.ndarray
    symmetry: int
    values: np.ndarray
    singularities: tuple
    normals: np.ndarray
    constrained: np.ndarray

    @property
    def index_sum(self) -> float:
        """Sum of the singularity indices (the Euler characteristic on closed meshes)."""
        return sum(round(i * self.symmetry) for _, i in self.singularities) / self.symmetry

    def representatives(self) -> np.ndarray:
        """Return all ``N`` unit vectors per face, ``(m, N, 3)``, counter-clockwise."""
        a = 2.0 * np.pi * np.arange(self.symmetry) / self.symmetry
        v = self.vectors[:, None, :]
        w = np.cross(self.normals, self.vectors)[:, None, :]
        return np.cos(a)[None, :, None] * v + np.sin(a)[None, :, None] * w


def _check_symmetry(symmetry) -> int:
    if isinstance(symmetry, bool) or not isinstance(symmetry, Integral) or symmetry < 1:
        raise InputError(f"symmetry must be a positive integer (1, 2 or 4 usually), "
                         f"got {symmetry!r}")
    return int(symmetry)


def _energy_matrix(conn: FaceConnection, N: int) -> sp.csc_matrix:
    """Hermitian ``A`` with ``z^H A z = sum w |z_g - exp(i N rho) z_f|^2``."""
    m = conn.n_faces
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    w = conn.weight
    r = np.exp(1j * N * conn.angle)
    rows = np.concatenate([f, g, g, f])
    cols = np.concatenate([f, g, f, g])
    vals = np.concatenate([w, w, -w * r, -w * np.conj(r)]).astype(np.complex128)
    return sp.csc_matrix((vals, (rows, cols)), shape=(m, m))


def _face_components(conn: FaceConnection) -> tuple[int, np.ndarray]:
    m = conn.n_faces
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    adj = sp.coo_matrix((np.ones(f.size, dtype=np.int8), (f, g)), shape=(m, m)).tocsr()
    return connected_components(adj, directed=False)


def _smoothest(A: sp.csc_matrix, mass: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Smallest generalized eigenvector of ``A z = lambda M z`` (M = diag(mass)).

    Small problems use a dense solver; large ones ARPACK in shift-invert mode
    around ``-eps`` (``A + eps M`` is positive definite even when ``A`` is
    singular, as on flat tori), with one SuperLU factorization and a start
    vector drawn from ``rng``.  The phase is fixed so that the first face with
    at least half the largest modulus is real positive, and the field has unit
    area-weighted RMS modulus.
    """
    k = A.shape[0]
    diag_mean = float(np.real(A.diagonal()).mean()) if k else 0.0
    if k == 1 or diag_mean <= 0.0:
        return np.ones(k, dtype=np.complex128)
    if k <= 64:
        _, vecs = scipy.linalg.eigh(A.toarray(), np.diag(mass).astype(np.complex128),
                                    subset_by_index=[0, 0])
        x = vecs[:, 0]
    else:
        eps = 1e-10 * diag_mean / float(mass.mean())
        lu = factor(A + sp.diags((eps * mass).astype(np.complex128)), hpd=True, what="direction field")
        op = LinearOperator((k, k), dtype=np.complex128,
                            matvec=lambda b: lu.solve(np.asarray(b, np.complex128).ravel()))
        v0 = rng.standard_normal(k) + 1j * rng.standard_normal(k)
        M = sp.diags(mass.astype(np.complex128)).tocsc()
        try:
            _, vecs = eigsh(A, k=1, M=M, sigma=-eps, OPinv=op, v0=v0, which="LM",
                            ncv=min(6, k - 1), tol=1e-8)
            x = vecs[:, 0]
        except ArpackNoConvergence:
            # fall back to plain inverse iteration: converges, just more slowly
            x = v0
            for _ in range(200):
                x = lu.solve(mass * x)
                x /= np.sqrt(np.real(np.vdot(x, mass * x)))
    mod = np.abs(x)
    ref = int(np.flatnonzero(mod >= 0.5 * mod.max())[0])
    x = x * (np.conj(x[ref]) / mod[ref])
    return x / np.sqrt(float(np.sum(mass * mod ** 2)) / float(mass.sum()))


def _solve_values(conn: FaceConnection, N: int, rng: np.random.Generator, *,
                  hard_faces=None, hard_values=None,
                  soft_faces=None, soft_values=None, soft_weights=None) -> np.ndarray:
    """Minimise the connection Dirichlet energy; see the module docstring."""
    empty_i = np.zeros(0, dtype=np.int64)
    empty_z = np.zeros(0, dtype=np.complex128)
    hard_faces = empty_i if hard_faces is None else hard_faces
    hard_values = empty_z if hard_values is None else hard_values
    soft_faces = empty_i if soft_faces is None else soft_faces
    soft_values = empty_z if soft_values is None else soft_values
    soft_weights = np.zeros(0) if soft_weights is None else soft_weights
    with single_threaded_blas():
        return _solve_components(conn, N, rng, hard_faces, hard_values, soft_faces,
                                 soft_values, soft_weights)


def _solve_components(conn, N, rng, hard_faces, hard_values, soft_faces, soft_values,
                      soft_weights) -> np.ndarray:
    m = conn.n_faces
    A = _energy_matrix(conn, N)
    mass = conn.areas / conn.areas.mean()
    ncomp, label = _face_components(conn)
    anchored = np.zeros(ncomp, dtype=bool)
    anchored[label[hard_faces]] = True
    anchored[label[soft_faces]] = True
    z = np.zeros(m, dtype=np.complex128)
    z[hard_faces] = hard_values
    is_hard = np.zeros(m, dtype=bool)
    is_hard[hard_faces] = True
    S = np.flatnonzero(anchored[label] & ~is_hard)
    if S.size:
        pen_w = np.bincount(soft_faces, weights=soft_weights, minlength=m)
        pen_re = np.bincount(soft_faces, weights=soft_weights * soft_values.real, minlength=m)
        pen_im = np.bincount(soft_faces, weights=soft_weights * soft_values.imag, minlength=m)
        rhs = (pen_re + 1j * pen_im)[S]
        if hard_faces.size:
            rhs = rhs - A[S][:, hard_faces] @ hard_values
        K = A[S][:, S] + sp.diags(pen_w[S].astype(np.complex128))
        z[S] = factor(K, hpd=True, what="direction field").solve(rhs)
    free = np.flatnonzero(~anchored)
    if free.size:
        order = np.argsort(label, kind="stable")
        starts = np.searchsorted(label[order], np.arange(ncomp + 1))
        for c in free:
            idx = order[starts[c]:starts[c + 1]]
            z[idx] = _smoothest(A[idx][:, idx], mass[idx], rng)
    return z


def _make_field(V: np.ndarray, F: np.ndarray, conn: FaceConnection, N: int,
                values: np.ndarray, constrained: np.ndarray,
                fixed_faces: np.ndarray | None = None,
                fixed_vectors: np.ndarray | None = None) -> DirectionField:
    vectors = vectors_from_angles(conn.T1, conn.T2, np.angle(values) / N)
    if fixed_faces is not None and fixed_faces.size:
        vectors[fixed_faces] = fixed_vectors
    k = _index_numerators(V, F, conn, np.angle(values), N)
    return DirectionField(vectors=vectors, symmetry=N, values=values,
                          singularities=tuple(_singularity_list(k, N)), normals=conn.N,
                          constrained=np.unique(constrained).astype(np.int64))


def smooth_direction_field(V, F, *, symmetry: int = 1, constraints=None, mode: str = "hard",
                           soft_strength: float = 100.0, max_snap_distance=None,
                           seed=None) -> DirectionField:
    """Return the smoothest N-direction field that follows the constraints.

    One sparse complex solve (hard constraints eliminated) or, without
    constraints, the smallest eigenvector of the connection Laplacian; see the
    module docstring for the energy.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A consistently oriented triangle mesh (boundaries allowed; non-manifold
        edges are treated as boundary).
    symmetry : int, optional
        ``N``: 1 for vectors, 2 for lines (d ~ -d), 4 for crosses.
    constraints : sequence of Constraint or dict, optional
        See :class:`Constraint`.  Several constraints on one face are allowed
        when they agree (as N-directions) in hard mode.
    mode : {"hard", "soft"}, optional
        ``"hard"``: the field equals the constraints exactly at their faces.
        ``"soft"``: add ``soft_strength * weight * mean(diag A) * |z_f - q|^2``
        per constraint, so conflicting constraints are averaged.
    soft_strength : float, optional
        Penalty scale of soft constraints, relative to the mean diagonal of the
        energy matrix (about the weight of one face's smoothness terms).
    max_snap_distance : float, optional
        Largest distance of a point constraint from the surface (default: 1 %
        of the bounding-box diagonal).
    seed : int or numpy.random.Generator, optional
        Start vector of the eigen solve (used only for components without
        constraints); ``None`` means seed 0, so results are reproducible.

    Returns
    -------
    DirectionField

    Raises
    ------
    InputError
        On malformed or degenerate meshes, inconsistent orientation, a bad
        ``symmetry`` or ``mode``, invalid constraints (face out of range, zero,
        non-finite or normal-parallel direction, point too far from the
        surface), or conflicting hard constraints on one face.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(4, 4)
    >>> field = smooth_direction_field(V, F, constraints=[{"face": 0, "direction": [1, 1, 0]}])
    >>> bool(np.allclose(field.vectors, np.sqrt(0.5) * np.array([1.0, 1.0, 0.0])))
    True
    """
    V, F = _checked_arrays(V, F)
    N = _check_symmetry(symmetry)
    if mode not in ("hard", "soft"):
        raise InputError(f"mode must be 'hard' or 'soft', got {mode!r}")
    strength = positive_number(soft_strength, name="soft_strength")
    conn = _connection(V, F)
    res = _resolve_constraints(V, F, conn, constraints, max_snap_distance=max_snap_distance)
    rng = np.random.default_rng(0 if seed is None else seed)
    theta = tangent_angles(conn.T1[res.faces], conn.T2[res.faces], res.tangents)
    q = np.exp(1j * N * theta)
    if mode == "hard":
        faces, first = np.unique(res.faces, return_index=True)
        # constraints on one face must agree as N-directions
        rep = first[np.searchsorted(faces, res.faces)]
        clash = np.flatnonzero(np.abs(q - q[rep]) > 1e-9)
        if clash.size:
            i = int(clash[0])
            raise InputError(
                f"constraints[{i}] and constraints[{int(rep[i])}] give different directions "
                f"for face {int(res.faces[i])}; give one direction per face or use mode='soft'")
        z = _solve_values(conn, N, rng, hard_faces=faces, hard_values=q[first])
        return _make_field(V, F, conn, N, z, faces, faces, res.tangents[first])
    A_scale = 2.0 * float(conn.weight.sum()) / conn.n_faces      # mean diagonal of A
    z = _solve_values(conn, N, rng, soft_faces=res.faces, soft_values=q,
                      soft_weights=strength * max(A_scale, 1e-300) * res.weights)
    return _make_field(V, F, conn, N, z, res.faces)


def _fill(V: np.ndarray, F: np.ndarray, conn: FaceConnection, vectors: np.ndarray,
          undefined: np.ndarray) -> np.ndarray:
    """Replace vectors at ``undefined`` faces by the smoothest 1-field through the rest."""
    out = vectors.copy()
    if not undefined.any():
        return out
    keep = np.flatnonzero(~undefined)
    q = np.exp(1j * tangent_angles(conn.T1[keep], conn.T2[keep], vectors[keep]))
    z = _solve_values(conn, 1, np.random.default_rng(0), hard_faces=keep, hard_values=q)
    bad = np.flatnonzero(undefined)
    out[bad] = vectors_from_angles(conn.T1[bad], conn.T2[bad], np.angle(z[bad]))
    return out


def projected_direction_field(V, F, direction, *, tolerance: float = 1e-3
                              ) -> tuple[np.ndarray, np.ndarray]:
    """Project a global direction onto every face (lapped textures' "up" field).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    direction : array_like, (3,) or (m, 3)
        One direction for all faces, or one per face.
    tolerance : float, optional
        A face is *undefined* where the tangential part of the direction is
        below ``tolerance`` times its length (the direction is nearly normal
        to the face) or, for per-face input, where the direction is zero.

    Returns
    -------
    vectors : numpy.ndarray, (m, 3) float64
        Unit tangent vectors.  On defined faces, the normalized projection.
        Undefined faces are filled from their neighbours: the smoothest
        1-direction field (:func:`smooth_direction_field`'s energy) with every
        defined face as a hard constraint.  When no face is defined, the
        globally smoothest field is returned.
    undefined : numpy.ndarray, (m,) bool
        The faces that were filled.

    Raises
    ------
    InputError
        On malformed or degenerate meshes, or a direction that is not finite,
        of the wrong shape, or zero (single direction).

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> vec, undefined = projected_direction_field(*grid_plane(2, 2), [0.0, 1.0, 5.0])
    >>> vec[0].tolist(), bool(undefined.any())
    ([0.0, 1.0, 0.0], False)
    """
    V, F = _checked_arrays(V, F)
    tol = positive_number(tolerance, name="tolerance")
    m = F.shape[0]
    d = np.asarray(direction, dtype=np.float64) if not isinstance(direction, str) else None
    if d is None or d.shape not in ((3,), (m, 3)):
        raise InputError(f"direction must have shape (3,) or ({m}, 3)")
    if not np.isfinite(d).all():
        raise InputError("direction must be finite")
    if d.shape == (3,):
        if not np.linalg.norm(d) > 0:
            raise InputError("direction is zero; give a non-zero direction such as [0, 0, 1]")
        d = np.broadcast_to(d, (m, 3))
    conn = _connection(V, F)
    t = d - np.einsum("ij,ij->i", d, conn.N)[:, None] * conn.N
    tlen = np.linalg.norm(t, axis=1)
    undefined = ~(tlen > tol * np.linalg.norm(d, axis=1))
    vec = np.zeros((m, 3))
    ok = ~undefined
    vec[ok] = t[ok] / tlen[ok, None]
    return _fill(V, F, conn, vec, undefined), undefined


@dataclass(frozen=True, eq=False)
class PrincipalDirections:
    """Per-face principal curvature directions and curvatures.

    Attributes
    ----------
    directions : numpy.ndarray, (m, 3) float64
        Unit tangent direction of the requested curvature (a 2-direction:
        ``d`` and ``-d`` are the same line).
    k_max, k_min : numpy.ndarray, (m,) float64
        Maximal and minimal (signed) principal curvature, averaged from the
        face's vertices; positive on convex parts of outward-oriented meshes.
    coherence : numpy.ndarray, (m,) float64
        ``|sum w exp(2 i theta)| / sum w`` over the face's vertices, in
        ``[0, 1]``: near 1 where the vertex directions agree, near 0 at
        umbilics (spheres, planes), where the direction is arbitrary.
    """

    directions: np.ndarray
    k_max: np.ndarray
    k_min: np.ndarray
    coherence: np.ndarray


def principal_direction_field(V, F, *, which: str = "max", radius: int = 5
                              ) -> PrincipalDirections:
    """Return principal curvature directions per face.

    libigl's per-vertex quadric fit (``igl.principal_curvature``) gives the
    direction of maximal curvature at every vertex.  Each face averages its
    three vertices' directions as 2-directions: the angles ``theta`` in the
    face frame are doubled, ``sum w exp(2 i theta)`` is formed with weights
    ``w = |tangential part|^2 * |k_max - k_min|`` (so umbilic vertices count
    little), and the face direction is half the argument.  ``d`` and ``-d``
    therefore agree.  The minimal direction is the maximal one turned by 90
    degrees in the face plane, so the two are exactly orthogonal.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    which : {"max", "min"}, optional
        Direction of maximal or minimal signed curvature.
    radius : int, optional
        Neighbourhood of the fit in vertex rings (libigl's ``radius``); at
        least 2.

    Returns
    -------
    PrincipalDirections

    Raises
    ------
    InputError
        On malformed or degenerate meshes, a bad ``which`` or ``radius``.

    Examples
    --------
    >>> from geotex.mesh.primitives import torus
    >>> pd = principal_direction_field(*torus(n_major=32, n_minor=16))
    >>> bool(np.all(pd.k_max >= pd.k_min))
    True
    """
    V, F = _checked_arrays(V, F)
    if which not in ("max", "min"):
        raise InputError(f"which must be 'max' or 'min', got {which!r}")
    if isinstance(radius, bool) or not isinstance(radius, Integral) or radius < 2:
        raise InputError(f"radius must be an integer >= 2 (vertex rings), got {radius!r}")
    T1, T2, _ = _frames(V, F)
    PD1, _, PV1, PV2, _ = igl.principal_curvature(V, F, int(radius), True)
    PD1 = np.asarray(PD1, dtype=np.float64)
    PV1 = np.asarray(PV1, dtype=np.float64).ravel()
    PV2 = np.asarray(PV2, dtype=np.float64).ravel()
    P = PD1[F]                                            # (m, 3, 3)
    x = np.einsum("ijk,ik->ij", P, T1)
    y = np.einsum("ijk,ik->ij", P, T2)
    tan2 = x * x + y * y
    aniso = np.abs(PV1 - PV2)[F]
    w = tan2 * aniso
    dbl = (x * x - y * y + 2j * x * y) / np.where(tan2 > 0, tan2, 1.0)   # exp(2 i theta)
    s = (w * dbl).sum(axis=1)
    wsum = w.sum(axis=1)
    flat = ~(np.abs(s) > 0)
    s[flat] = (tan2[flat] * dbl[flat]).sum(axis=1)
    coherence = np.divide(np.abs(s), wsum, out=np.zeros(F.shape[0]), where=wsum > 0)
    coherence[flat] = 0.0
    angle = np.angle(s) / 2.0 + (0.5 * np.pi if which == "min" else 0.0)
    return PrincipalDirections(directions=vectors_from_angles(T1, T2, angle),
                               k_max=PV1[F].mean(axis=1), k_min=PV2[F].mean(axis=1),
                               coherence=np.clip(coherence, 0.0, 1.0))


def constraint_scale_field(V, F, constraints, *, epsilon: float | None = None,
                           max_snap_distance=None) -> np.ndarray | None:
    """Interpolate the ``scale`` of constraints into a per-vertex scale field.

    The vertices of every constrained face that carries a ``scale`` are locked
    to it (the mean where faces share a vertex) and the rest is filled by
    cotan-Laplacian interpolation, clamped above ``epsilon``
    (:func:`geotex.fields.scalar.scale_field`).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    constraints : sequence of Constraint or dict
        As for :func:`smooth_direction_field`.
    epsilon : float, optional
        Smallest scale (default ``1e-3`` times the largest given scale).
    max_snap_distance : float, optional
        See :class:`Constraint`.

    Returns
    -------
    numpy.ndarray, (n,) float64, or None
        ``None`` when no constraint gives a scale.

    Raises
    ------
    InputError
        On invalid constraints, or a connected component without any scale.
    """
    V, F = _checked_arrays(V, F)
    res = _resolve_constraints(V, F, _connection(V, F), constraints,
                               max_snap_distance=max_snap_distance)
    given = np.flatnonzero(np.isfinite(res.scales))
    if given.size == 0:
        return None
    verts = F[res.faces[given]].ravel()
    vals = np.repeat(res.scales[given], 3)
    uniq, inv = np.unique(verts, return_inverse=True)
    mean = np.bincount(inv, weights=vals) / np.bincount(inv)
    return scale_field(V, F, uniq, mean, epsilon=epsilon)
