"""Discrete 1-forms: tangent vector fields stored as one scalar per edge.

A tangent field ``X`` on a triangle mesh is encoded by its line integrals along
the edges (height-and-tilt paper, section 2).  The representation is intrinsic:
it needs no per-face frame, and it is what the tilt of a height-and-tilt
texture is stored as.

Conventions
-----------
* Coefficients follow the geotex unique edge order
  (:func:`geotex.mesh.topology.edge_topology`): ``c[e]`` belongs to the edge
  ``edges[e] = (i, j)`` with ``i < j`` and is the integral of ``X`` from
  ``v_i`` to ``v_j``,  ``c_ij = int_{v_i}^{v_j} <X, dp>``.  Traversed the other
  way the integral changes sign, ``c_ji = -c_ij``.
* Within a face ``f = (v_0, v_1, v_2)`` the corner ``k`` has the barycentric
  (hat) function ``phi_k`` with gradient
  ``grad phi_k = N x (p_{k+2} - p_{k+1}) / |N|^2``, ``N = (p_1 - p_0) x (p_2 - p_0)``
  (indices modulo 3).  The gradients, and therefore every decoded vector, do
  not depend on the face orientation.
* Whitney reconstruction: the edge ``a -> b`` has the basis field
  ``W_ab = phi_a grad phi_b - phi_b grad phi_a`` whose integral along
  ``a -> b`` is 1 and along the two other edges 0, and
  ``X = sum_edges c_ab W_ab`` in every face.  This field is linear in the
  barycentric coordinates, so it is the barycentric interpolation of its three
  corner values, which are the paper's equation (1):
  ``X_f(v_i) = c_ij grad phi_j - c_ki grad phi_k
  = (c_ij e_ki^perp - c_ki e_ij^perp) / (2 A_f)``.
  Whitney reconstruction is exact for constant tangent fields: encoding
  ``c_ij = <X, e_ij>`` of a constant ``X`` tangent to a face decodes to ``X``
  everywhere in that face.
* Faces whose area is (numerically) zero, ``|N| <= 1e-12 l_max^2``, have no
  well-defined tangent plane: they decode to the zero vector and take no part
  in vertex averages.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.mesh.arrays import as_faces, as_mesh_arrays
from geotex.mesh.topology import EdgeTopology, edge_topology

__all__ = [
    "encode_one_form",
    "decode_one_form",
    "decode_one_form_at_vertices",
    "evaluate_one_form",
    "whitney_corner_vectors",
    "exterior_derivative",
    "circulation",
    "segment_samples",
    "line_integrals",
    "integrate_edges",
    "projected_decoder",
]

_DEGENERATE_REL = 1e-12
_CG_RTOL = 1e-9
_CG_RTOL_LOOSE = 1e-4
_CG_MAXITER = 20000
_ACTIVE_SET_ROUNDS = 100


# --------------------------------------------------------------------------
# validation helpers

def _topology(F: np.ndarray, n: int, topology) -> EdgeTopology:
    if topology is None:
        return edge_topology(F, n)
    if (not isinstance(topology, EdgeTopology)
            or topology.half_to_edge.shape != (3 * F.shape[0],)
            or (topology.edges.size and int(topology.edges.max()) >= max(n, 1))):
        raise InputError("topology does not belong to F: pass edge_topology(F, len(V)) "
                         "computed for this mesh, or leave it out")
    return topology


def _coefficients(c, n_edges: int, name: str = "c") -> np.ndarray:
    try:
        arr = np.ascontiguousarray(c, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric (e,) array: {exc}") from None
    if arr.shape != (n_edges,):
        raise InputError(f"{name} must have shape ({n_edges},), one coefficient per unique "
                         f"edge in edge_topology order, got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(f"{name} has non-finite values (first at edge "
                         f"{int(np.flatnonzero(~np.isfinite(arr))[0])})")
    return arr


def _vectors(X, rows: int, name: str, what: str) -> np.ndarray:
    try:
        arr = np.ascontiguousarray(X, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric ({what}, 3) array: {exc}") from None
    if arr.shape != (rows, 3):
        raise InputError(f"{name} must have shape ({rows}, 3), one vector per {what}, "
                         f"got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(f"{name} has non-finite values (first at row "
                         f"{int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])})")
    return arr


def _bound_factor(bound) -> float | None:
    if bound is None or bound is False:
        return None
    if bound is True:
        return 1.0
    try:
        b = float(bound)
    except (TypeError, ValueError):
        raise InputError(f"bound must be True, False or a positive number, got {bound!r}") from None
    if not (np.isfinite(b) and b > 0):
        raise InputError(f"bound must be True, False or a positive number, got {bound!r}")
    return b


def _weighting(weighting: str) -> str:
    if weighting not in ("uniform", "area"):
        raise InputError(f"weighting must be 'uniform' or 'area', got {weighting!r}")
    return weighting


# --------------------------------------------------------------------------
# per-face building blocks

def _face_frames(P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Barycentric gradients of triangles ``P`` (k, 3, 3).

    Returns
    -------
    G : (k, 3, 3) float64
        ``G[f, c]`` is the gradient of the hat function of corner ``c``
        (zero on degenerate faces).
    N : (k, 3) float64
        ``(p1 - p0) x (p2 - p0)``.
    ok : (k,) bool
        Face is not degenerate.
    """
    e_opp = np.roll(P, -2, axis=1) - np.roll(P, -1, axis=1)      # p_{k+2} - p_{k+1}
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n2 = np.einsum("ij,ij->i", N, N)
    lmax2 = np.einsum("ijk,ijk->ij", e_opp, e_opp).max(axis=1) if P.shape[0] else np.zeros(0)
    with np.errstate(over="ignore", invalid="ignore"):
        ok = np.sqrt(n2) > _DEGENERATE_REL * lmax2
    inv = np.zeros_like(n2)
    np.divide(1.0, n2, out=inv, where=ok)
    G = np.cross(N[:, None, :], e_opp) * inv[:, None, None]
    return G, N, ok


def _half_edge_signs(F: np.ndarray) -> np.ndarray:
    """+1 where half-edge ``3f + k`` runs like its unique edge (low -> high), else -1."""
    return np.where(F < np.roll(F, -1, axis=1), 1.0, -1.0)


def _corner_vectors(G: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Equation (1): ``T_k = s_k G_{k+1} - s_{k+2} G_{k+2}``, (k, 3, 3)."""
    return (s[:, :, None] * np.roll(G, -1, axis=1)
            - np.roll(s, -2, axis=1)[:, :, None] * np.roll(G, -2, axis=1))


def _corner_weights(N: np.ndarray, ok: np.ndarray, weighting: str) -> np.ndarray:
    w = np.linalg.norm(N, axis=1) if weighting == "area" else np.ones(N.shape[0])
    return np.where(ok, w, 0.0)


def _vertex_normals(F, n, N, ok, weighting) -> np.ndarray:
    """Unit vertex normals consistent with the vertex averaging (zero if undefined)."""
    if weighting == "area":
        per_face = np.where(ok[:, None], N, 0.0)
    else:
        nn = np.linalg.norm(N, axis=1, keepdims=True)
        per_face = np.divide(N, nn, out=np.zeros_like(N), where=ok[:, None])
    acc = np.zeros((n, 3))
    for d in range(3):
        acc[:, d] = np.bincount(F.ravel(), weights=np.repeat(per_face[:, d], 3), minlength=n)
    ln = np.linalg.norm(acc, axis=1, keepdims=True)
    return np.divide(acc, ln, out=np.zeros_like(acc), where=ln > 0)


def _signed_face_coefficients(F, c, topo) -> np.ndarray:
    return c[topo.half_to_edge.reshape(-1, 3)] * _half_edge_signs(F)


# --------------------------------------------------------------------------
# decoding

def whitney_corner_vectors(V, F, c, *, topology: EdgeTopology | None = None) -> np.ndarray:
    """Return every face's Whitney vector at each of its corners (equation 1).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
        1-form coefficients in unique edge order.
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse across calls.

    Returns
    -------
    numpy.ndarray, (m, 3, 3) float64
        ``out[f, k]`` is the value at corner ``F[f, k]`` of the Whitney field of
        face ``f``: ``c_ij grad phi_j - c_ki grad phi_k`` for corner ``i`` and
        the face's next corners ``j``, ``k``.  It lies in the plane of ``f``.

    Raises
    ------
    InputError
        On malformed arrays or a coefficient vector of the wrong length.
    """
    V, F = as_mesh_arrays(V, F)
    topo = _topology(F, V.shape[0], topology)
    c = _coefficients(c, topo.edges.shape[0])
    G, _, _ = _face_frames(V[F])
    return _corner_vectors(G, _signed_face_coefficients(F, c, topo))


def decode_one_form(V, F, c, *, topology: EdgeTopology | None = None) -> np.ndarray:
    """Reconstruct one tangent vector per face from a 1-form (Whitney, at the centroid).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
        Coefficients in unique edge order; ``c[e]`` integrates from
        ``edges[e, 0]`` to ``edges[e, 1]``.
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse across calls.

    Returns
    -------
    numpy.ndarray, (m, 3) float64
        ``X_f = 1/3 sum_{a->b in f} c_ab (grad phi_b - grad phi_a)``, the Whitney
        field at the centroid (the mean of the three corner vectors).  It lies
        in the plane of the face, and ``<X_f, e> = c_e`` for every edge of ``f``
        when the three coefficients of ``f`` sum to zero around it (a closed
        1-form).  Degenerate faces give zero.

    Raises
    ------
    InputError
        On malformed arrays or a coefficient vector of the wrong length.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(4, 4)
    >>> c = encode_one_form(V, F, np.tile([0.3, -0.2, 0.0], (len(F), 1)))
    >>> np.allclose(decode_one_form(V, F, c), [0.3, -0.2, 0.0])
    True
    """
    V, F = as_mesh_arrays(V, F)
    topo = _topology(F, V.shape[0], topology)
    c = _coefficients(c, topo.edges.shape[0])
    G, _, _ = _face_frames(V[F])
    s = _signed_face_coefficients(F, c, topo)
    # sum_k s_k (G_{k+1} - G_k) / 3
    return np.einsum("fk,fkd->fd", s, np.roll(G, -1, axis=1) - G) / 3.0


def decode_one_form_at_vertices(V, F, c, *, weighting: str = "uniform",
                                topology: EdgeTopology | None = None) -> np.ndarray:
    """Reconstruct one tangent vector per vertex from a 1-form (paper, equation 1).

    Every incident face contributes its Whitney vector at the vertex
    (:func:`whitney_corner_vectors`); the contributions are averaged.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
        Coefficients in unique edge order.
    weighting : {"uniform", "area"}, optional
        ``"uniform"`` (default) is the paper's plain average over the incident
        faces; ``"area"`` weights each face by its area.  Degenerate faces get
        weight zero.
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse across calls.

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Zero at vertices without a non-degenerate incident face.  On a curved
        mesh the average of vectors from different face planes is not exactly
        tangent to any one plane.

    Raises
    ------
    InputError
        On malformed arrays, a coefficient vector of the wrong length, or an
        unknown weighting.
    """
    V, F = as_mesh_arrays(V, F)
    weighting = _weighting(weighting)
    topo = _topology(F, V.shape[0], topology)
    c = _coefficients(c, topo.edges.shape[0])
    n = V.shape[0]
    G, N, ok = _face_frames(V[F])
    T = _corner_vectors(G, _signed_face_coefficients(F, c, topo))
    w = np.repeat(_corner_weights(N, ok, weighting), 3)
    idx = F.ravel()
    total = np.bincount(idx, weights=w, minlength=n)
    out = np.empty((n, 3))
    Tw = T.reshape(-1, 3) * w[:, None]
    for d in range(3):
        out[:, d] = np.bincount(idx, weights=Tw[:, d], minlength=n)
    np.divide(out, total[:, None], out=out, where=total[:, None] > 0)
    out[total <= 0] = 0.0
    return out


def evaluate_one_form(V, F, c, faces, bary, *, topology: EdgeTopology | None = None
                      ) -> np.ndarray:
    """Evaluate the Whitney field of a 1-form at points given in barycentric form.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
        Coefficients in unique edge order.
    faces : array_like, (k,) int64
        Face of every point.
    bary : array_like, (k, 3) float64
        Barycentric coordinates of every point with respect to
        ``F[faces[p], 0..2]``; each row must sum to 1.
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse across calls.

    Returns
    -------
    numpy.ndarray, (k, 3) float64
        ``X(p) = sum_k bary_k T_k`` with ``T_k`` the face's corner vectors
        (equation 1), which equals ``sum_edges c_ab (phi_a grad phi_b -
        phi_b grad phi_a)`` (the paper's point evaluation formula).

    Raises
    ------
    InputError
        On malformed arrays, out-of-range faces, or rows of ``bary`` that do not
        sum to 1 (tolerance 1e-6).
    """
    V, F = as_mesh_arrays(V, F)
    topo = _topology(F, V.shape[0], topology)
    c = _coefficients(c, topo.edges.shape[0])
    faces_arr = np.asarray(faces)
    if faces_arr.ndim != 1 or (faces_arr.size and faces_arr.dtype.kind not in "iu"):
        raise InputError(f"faces must be a 1-D integer array, got shape {faces_arr.shape} "
                         f"and dtype {faces_arr.dtype}")
    faces_arr = faces_arr.astype(np.int64)
    k = faces_arr.shape[0]
    if k and (faces_arr.min() < 0 or faces_arr.max() >= F.shape[0]):
        raise InputError(f"faces has indices outside [0, {F.shape[0]})")
    B = _vectors(bary, k, "bary", "point")
    if k and np.abs(B.sum(axis=1) - 1.0).max() > 1e-6:
        bad = int(np.flatnonzero(np.abs(B.sum(axis=1) - 1.0) > 1e-6)[0])
        raise InputError(f"bary rows must sum to 1 (row {bad} sums to {B[bad].sum():.6g})")
    Fk = F[faces_arr]
    G, _, _ = _face_frames(V[Fk])
    s = c[topo.half_to_edge.reshape(-1, 3)[faces_arr]] * _half_edge_signs(Fk)
    T = _corner_vectors(G, s)
    return np.einsum("pk,pkd->pd", B, T)


# --------------------------------------------------------------------------
# encoding

def encode_one_form(V, F, vectors, *, at: str = "faces", bound=True,
                    weighting: str = "uniform", damping: float = 1e-2,
                    topology: EdgeTopology | None = None, decoder=None) -> np.ndarray:
    """Encode a tangent vector field as a 1-form, one coefficient per unique edge.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    vectors : array_like, (m, 3) or (n, 3) float64
        The field, per face (``at="faces"``) or per vertex (``at="vertices"``).
        Only its tangential part is encoded: face vectors are (implicitly)
        projected onto their face plane, vertex vectors onto the plane
        orthogonal to the vertex normal (mean of unit face normals for
        ``weighting="uniform"``, area-weighted for ``"area"``).
    at : {"faces", "vertices"}, optional
        ``"faces"``: piecewise constant field;
        ``c_ij = mean over the faces f of edge ij of <X_f, p_j - p_i>``
        (exact for a constant tangent field and for the gradient of a
        piecewise-linear function).
        ``"vertices"``: the paper's least-squares encoding.  ``c`` minimises
        ``sum_v |P_v (X_v - D(c)_v)|^2 + damping * sum_e K_ee (c_e - c0_e)^2``
        where ``D`` is :func:`decode_one_form_at_vertices` (same
        ``weighting``), ``P_v`` the tangent projector at ``v``,
        ``c0_ij = <(X_i + X_j) / 2, p_j - p_i>`` the exact integral of the
        linearly interpolated field along the edge, and ``K_ee`` the diagonal
        of the data term's normal matrix (makes ``damping`` scale free).
        Only tangential residuals are fitted: the normal part of an average
        over differently tilted faces cannot be represented, and fitting it
        makes the system nearly singular (coefficients blow up).  The damping
        fixes the null space (there are more edges than tangential equations)
        and keeps coefficients near the local encoding ``c0``.  Solved by
        Jacobi-preconditioned conjugate gradients on the normal equations.
    bound : bool or float, optional
        ``True`` (default) enforces the paper's bound ``|c_e| <= |e|`` (right
        for fields of magnitude at most 1, such as tilt); a positive number
        ``b`` enforces ``|c_e| <= b |e|``; ``False`` or ``None`` none.  For
        ``at="faces"`` the bound is a clip (the constrained optimum of the
        per-edge average); for ``at="vertices"`` the bounded least-squares
        problem is solved exactly by block principal pivoting (an active-set
        method: fix the edges at their bounds, re-solve the free ones by
        conjugate gradients, exchange the infeasible ones; Judice-Pires
        safeguard against cycling; at most 100 rounds), and the result is
        clipped so that the bound holds exactly.
    weighting : {"uniform", "area"}, optional
        Vertex averaging of the decoder that the ``"vertices"`` fit targets
        (see :func:`decode_one_form_at_vertices`).  Ignored for faces.
    damping : float, optional
        Relative Tikhonov weight for ``at="vertices"`` (> 0).  Smaller fits
        the vertex values more closely and takes more iterations (about
        ``20 / sqrt(damping)`` conjugate-gradient iterations for rough data).
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse across calls.
    decoder : tuple, optional
        ``projected_decoder(V, F, weighting=weighting, topology=topology)``,
        to reuse when the caller needs the matrix too (``at="vertices"``
        only; it is assembled here otherwise).

    Returns
    -------
    numpy.ndarray, (e,) float64
        ``c[e]`` is the integral of the field from ``edges[e, 0]`` to
        ``edges[e, 1]`` (``edges[e, 0] < edges[e, 1]``, unique edge order).

    Raises
    ------
    InputError
        On malformed arrays, a field of the wrong shape or with non-finite
        values, an unknown ``at`` or ``weighting``, a non-positive bound or
        damping.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh import edge_topology
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> a = np.array([0.2, -0.1, 0.4])
    >>> c = encode_one_form(V, F, np.tile(a, (len(F), 1)))     # gradient of <a, p>
    >>> E = edge_topology(F, len(V)).edges
    >>> np.allclose(c, V[E[:, 1]] @ a - V[E[:, 0]] @ a)
    True
    """
    V, F = as_mesh_arrays(V, F)
    if at not in ("faces", "vertices"):
        raise InputError(f"at must be 'faces' or 'vertices', got {at!r}")
    weighting = _weighting(weighting)
    beta = _bound_factor(bound)
    try:
        damping = float(damping)
    except (TypeError, ValueError):
        raise InputError(f"damping must be a positive number, got {damping!r}") from None
    if not (np.isfinite(damping) and damping > 0):
        raise InputError(f"damping must be a positive number, got {damping!r}")
    n, m = V.shape[0], F.shape[0]
    topo = _topology(F, n, topology)
    E = topo.edges
    X = _vectors(vectors, m if at == "faces" else n, "vectors",
                 "face" if at == "faces" else "vertex")
    if E.shape[0] == 0:
        return np.zeros(0)
    evec = V[E[:, 1]] - V[E[:, 0]]
    limit = None if beta is None else beta * np.linalg.norm(evec, axis=1)

    if at == "faces":
        he_vec = np.roll(V[F], -1, axis=1) - V[F]                     # p_{k+1} - p_k
        dots = np.einsum("fkd,fd->fk", he_vec, X) * _half_edge_signs(F)
        c = np.bincount(topo.half_to_edge, weights=dots.ravel(),
                        minlength=E.shape[0]) / topo.face_count
        return c if limit is None else np.clip(c, -limit, limit)

    if decoder is not None:
        ok = (isinstance(decoder, tuple) and len(decoder) == 2
              and getattr(decoder[0], "shape", None) == (3 * n, E.shape[0])
              and np.shape(decoder[1]) == (n, 3))
        if not ok:
            raise InputError("decoder must be the pair returned by projected_decoder(V, F, "
                             "weighting=..., topology=...) for this mesh")
    return _encode_vertices(V, F, X, topo, evec, limit, weighting, damping, decoder)


def projected_decoder(V, F, *, weighting: str = "uniform",
                      topology: EdgeTopology | None = None) -> tuple[sp.csr_matrix, np.ndarray]:
    """Sparse matrix of the vertex decoder followed by the tangent projection.

    ``B @ c`` is ``P_v decode_one_form_at_vertices(V, F, c, weighting=...)``
    flattened vertex-major (``x0, y0, z0, x1, ...``), with ``P_v = I - n_v n_v^T``
    the projector onto the plane orthogonal to the unit vertex normal ``n_v``
    (mean of unit face normals for ``"uniform"``, area weighted for
    ``"area"``).  It is the data term of the ``at="vertices"`` least-squares
    encoding; assemble it once and pass it to :func:`encode_one_form`
    (``decoder=``) when it is needed elsewhere too (as the exact tilt
    correction of :func:`geotex.heighttilt.base.encode_tilt` does).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    weighting : {"uniform", "area"}, optional
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse across calls.

    Returns
    -------
    B : scipy.sparse.csr_matrix, (3n, e)
        At most 6 non-zeros per face corner and coordinate; degenerate faces
        contribute nothing.
    normals : numpy.ndarray, (n, 3) float64
        The unit vertex normals used (zero where undefined).

    Raises
    ------
    InputError
        On malformed arrays, a topology of another mesh or an unknown weighting.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(1)
    >>> B, nrm = projected_decoder(V, F)
    >>> c = np.random.default_rng(0).normal(size=B.shape[1])
    >>> X = decode_one_form_at_vertices(V, F, c)
    >>> PX = X - np.einsum("nd,nd->n", X, nrm)[:, None] * nrm
    >>> bool(np.allclose(B @ c, PX.ravel()))
    True
    """
    V, F = as_mesh_arrays(V, F)
    weighting = _weighting(weighting)
    return _projected_decoder(V, F, _topology(F, V.shape[0], topology), weighting)


def _projected_decoder(V, F, topo, weighting):
    """:func:`projected_decoder` on validated arrays."""
    n, m = V.shape[0], F.shape[0]
    G, N, ok = _face_frames(V[F])
    normals = _vertex_normals(F, n, N, ok, weighting)
    w = _corner_weights(N, ok, weighting)
    total = np.bincount(F.ravel(), weights=np.repeat(w, 3), minlength=n)
    wn = np.divide(np.repeat(w[:, None], 3, axis=1), total[F],
                   out=np.zeros((m, 3)), where=total[F] > 0)
    sign = _half_edge_signs(F)
    eid = topo.half_to_edge.reshape(m, 3)
    # corner k: + s_k G_{k+1} (column of half-edge k), - s_{k+2} G_{k+2} (column k+2)
    va = (wn * sign)[:, :, None] * np.roll(G, -1, axis=1)
    vb = -(wn * np.roll(sign, -2, axis=1))[:, :, None] * np.roll(G, -2, axis=1)
    nc = normals[F]                                                     # (m, 3, 3)
    va -= np.einsum("fkd,fkd->fk", va, nc)[:, :, None] * nc
    vb -= np.einsum("fkd,fkd->fk", vb, nc)[:, :, None] * nc
    rows = 3 * F[:, :, None] + np.arange(3)
    ca = np.broadcast_to(eid[:, :, None], (m, 3, 3))
    cb = np.broadcast_to(np.roll(eid, -2, axis=1)[:, :, None], (m, 3, 3))
    R = np.concatenate([rows.ravel(), rows.ravel()])
    C = np.concatenate([ca.ravel(), cb.ravel()])
    D = np.concatenate([va.ravel(), vb.ravel()])
    B = sp.csr_matrix((D, (R, C)), shape=(3 * n, topo.edges.shape[0]))
    return B, normals


def _dot(x: np.ndarray, y: np.ndarray) -> float:
    # einsum's own loop: BLAS ddot spawns threads, which is slow on busy machines
    return float(np.einsum("i,i->", x, y))


def _cg(K, b, x0, diag, rtol=_CG_RTOL, free=None):
    """Jacobi-preconditioned conjugate gradients for SPD ``K``; returns ``x``.

    With ``free`` (a boolean mask) only the free unknowns are solved for:
    ``K_ff x_f = b_f - K_fa x_a`` with ``x_a = x0[~free]`` kept, done on full
    length vectors (masking instead of slicing ``K``).  Stops when
    ``|r| <= rtol |b_f - K_fa x_a|`` or after ``_CG_MAXITER`` iterations.
    """
    x = np.zeros_like(b) if x0 is None else x0.astype(np.float64, copy=True)
    mask = None if free is None else free.astype(np.float64)
    if mask is None:
        rhs = b
        r = b - K @ x if x0 is not None else b.copy()
    else:
        xa = x * (1.0 - mask)
        rhs = (b - K @ xa) * mask
        r = rhs - (K @ (x * mask)) * mask
    bn2 = _dot(rhs, rhs)
    if bn2 == 0.0:
        if mask is not None:
            x *= 1.0 - mask
            return x
        return np.zeros_like(b)
    stop = rtol * rtol * bn2
    inv = 1.0 / diag if mask is None else mask / diag
    z = inv * r
    p = z.copy()
    rz = _dot(r, z)
    for _ in range(_CG_MAXITER):
        if _dot(r, r) <= stop:
            break
        Kp = K @ p
        if mask is not None:
            Kp *= mask
        alpha = rz / _dot(p, Kp)
        x += alpha * p
        r -= alpha * Kp
        z = inv * r
        rz_new = _dot(r, z)
        p *= rz_new / rz
        p += z
        rz = rz_new
    return x


def _encode_vertices(V, F, X, topo, evec, limit, weighting, damping, decoder=None):
    E = topo.edges
    B, normals = (_projected_decoder(V, F, topo, weighting) if decoder is None
                  else decoder)
    Xt = X - np.einsum("nd,nd->n", X, normals)[:, None] * normals
    c0 = 0.5 * np.einsum("ed,ed->e", Xt[E[:, 0]] + Xt[E[:, 1]], evec)
    A = (B.T @ B).tocsr()
    diag = A.diagonal()
    pos = diag > 0
    fill = diag[pos].mean() if pos.any() else 1.0
    reg = damping * np.where(pos, diag, fill)
    K = (A + sp.diags(reg)).tocsr()
    Kd = K.diagonal()
    b = B.T @ (Xt.ravel() - B @ c0)
    # unconstrained correction c - c0 (loose when the active-set solve refines it)
    d = _cg(K, b, None, Kd, _CG_RTOL if limit is None else _CG_RTOL_LOOSE)
    if limit is None:
        return c0 + d
    return np.clip(c0 + _box_qp(K, Kd, b, d, -limit - c0, limit - c0), -limit, limit)


def _box_qp(K, Kd, b, d, lo, hi):
    """Minimise ``1/2 d'Kd - b'd`` subject to ``lo <= d <= hi`` (K SPD).

    Block principal pivoting (equivalently a primal-dual active-set method):
    each round fixes the current active edges at their bounds and solves the
    free ones by warm-started conjugate gradients, then exchanges every
    infeasible edge (free but outside its bounds, or active with a multiplier
    of the wrong sign).  While the number of exchanges keeps falling the free
    solves are loose; afterwards they are tight and Judice-Pires' safeguard
    applies: when the number of infeasible edges has not improved for three
    rounds, only one edge (the highest-index one, Murty's rule) is exchanged,
    which guarantees termination for SPD matrices.  ``d`` on entry is an
    (approximate) unconstrained minimiser.
    """
    d = d.copy()
    tol = 1e-9 * np.maximum(hi - lo, np.finfo(float).tiny)
    lam = np.zeros_like(d)
    up = np.zeros(d.shape, dtype=bool)
    down = np.zeros(d.shape, dtype=bool)
    loose = True
    last = best = None
    patience = 3
    for _ in range(_ACTIVE_SET_ROUNDS):
        free = ~(up | down)
        lam_tol = tol * Kd
        to_up = free & (d > hi + tol)
        to_down = free & (d < lo - tol)
        release = (up & (lam < -lam_tol)) | (down & (lam > lam_tol))
        bad = np.flatnonzero(to_up | to_down | release)
        if bad.size == 0:
            if loose:
                loose = False
            else:
                break
        elif loose:
            if last is not None and bad.size >= last:
                loose = False
            last = bad.size
        if not loose and bad.size:
            if best is None or bad.size < best:
                best, patience = bad.size, 3
            elif patience > 0:
                patience -= 1
            else:
                only = np.zeros(d.shape, dtype=bool)
                only[bad[-1]] = True
                to_up, to_down, release = to_up & only, to_down & only, release & only
        up = (up & ~release) | to_up
        down = (down & ~release) | to_down
        act = up | down
        d[up] = hi[up]
        d[down] = lo[down]
        d = _cg(K, b, d, Kd, _CG_RTOL_LOOSE if loose else _CG_RTOL, free=~act)
        lam = b - K @ d
        lam[~act] = 0.0
    return d


# --------------------------------------------------------------------------
# exterior derivative and circulation

def exterior_derivative(F, values, *, topology: EdgeTopology | None = None) -> np.ndarray:
    """Return the 1-form ``d f`` of a per-vertex function: ``f[j] - f[i]`` per edge.

    Parameters
    ----------
    F : array_like, (m, 3) int64
    values : array_like, (n,) float64
        One value per vertex; ``n`` must exceed every index in ``F``.
    topology : EdgeTopology, optional
        ``edge_topology(F, n)``, to reuse across calls.

    Returns
    -------
    numpy.ndarray, (e,) float64
        In unique edge order (``i < j``).

    Raises
    ------
    InputError
        On malformed arrays or non-finite values.
    """
    try:
        f = np.ascontiguousarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"values must be a numeric (n,) array: {exc}") from None
    if f.ndim != 1:
        raise InputError(f"values must have shape (n,), got {f.shape}")
    if not np.isfinite(f).all():
        raise InputError("values has non-finite entries")
    F = as_faces(F, f.shape[0])
    topo = _topology(F, f.shape[0], topology)
    return f[topo.edges[:, 1]] - f[topo.edges[:, 0]]


def circulation(F, c, *, topology: EdgeTopology | None = None) -> np.ndarray:
    """Return the sum of a 1-form around every face, ``c_01 + c_12 + c_20``.

    The discrete curl (``d`` of the 1-form): zero on every face for the
    1-form of a gradient.

    Parameters
    ----------
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
        Coefficients in unique edge order.
    topology : EdgeTopology, optional
        ``edge_topology(F)``, to reuse across calls.

    Returns
    -------
    numpy.ndarray, (m,) float64
        Oriented by the corner order of ``F``.

    Raises
    ------
    InputError
        On malformed arrays or a coefficient vector of the wrong length.
    """
    F = as_faces(F)
    n = int(F.max()) + 1 if F.size else 0
    topo = _topology(F, n, topology)
    c = _coefficients(c, topo.edges.shape[0])
    return _signed_face_coefficients(F, c, topo).sum(axis=1)


# --------------------------------------------------------------------------
# line integrals

def _points(P, name) -> np.ndarray:
    try:
        arr = np.ascontiguousarray(P, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric (s, 3) array: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{name} must have shape (s, 3), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(f"{name} has non-finite coordinates")
    return arr


def _rule(samples, rule) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(samples, (bool, np.bool_)) or not isinstance(samples, (int, np.integer)):
        raise InputError(f"samples must be an integer, got {samples!r}")
    samples = int(samples)
    if rule == "gauss":
        if samples < 1:
            raise InputError(f"samples must be >= 1 for rule='gauss', got {samples}")
        x, w = np.polynomial.legendre.leggauss(samples)
        return 0.5 * (x + 1.0), 0.5 * w
    if rule == "trapezoid":
        if samples < 2:
            raise InputError(f"samples must be >= 2 for rule='trapezoid', got {samples}")
        t = np.linspace(0.0, 1.0, samples)
        w = np.full(samples, 1.0 / (samples - 1))
        w[[0, -1]] *= 0.5
        return t, w
    raise InputError(f"rule must be 'gauss' or 'trapezoid', got {rule!r}")


def segment_samples(P0, P1, *, samples: int = 5, rule: str = "gauss"
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Return the quadrature points and weights used by :func:`line_integrals`.

    Parameters
    ----------
    P0, P1 : array_like, (s, 3) float64
        Segment start and end points.
    samples : int, optional
        Points per segment.
    rule : {"gauss", "trapezoid"}, optional
        ``"gauss"``: Gauss-Legendre nodes (interior points), exact for fields
        that are polynomials of degree ``<= 2 * samples - 1`` along the
        segment.  ``"trapezoid"``: equally spaced points including both ends,
        the integral of the piecewise-linear interpolation of the samples (the
        height-and-tilt paper's transfer rule), exact for degree ``<= 1``.

    Returns
    -------
    points : numpy.ndarray, (s, samples, 3) float64
        ``points[i, q] = P0[i] + t_q (P1[i] - P0[i])``.
    weights : numpy.ndarray, (samples,) float64
        Weights on ``[0, 1]`` (they sum to 1).

    Raises
    ------
    InputError
        On malformed or mismatched points, a bad ``samples`` or ``rule``.
    """
    P0 = _points(P0, "P0")
    P1 = _points(P1, "P1")
    if P0.shape != P1.shape:
        raise InputError(f"P0 and P1 must have the same shape, got {P0.shape} and {P1.shape}")
    t, w = _rule(samples, rule)
    pts = P0[:, None, :] + t[None, :, None] * (P1 - P0)[:, None, :]
    return pts, w


def line_integrals(field, P0, P1, *, samples: int = 5, rule: str = "gauss") -> np.ndarray:
    """Integrate a vector field along straight segments: ``int_{P0}^{P1} <X, dp>``.

    All segments are handled in one vectorized pass: the field is requested
    once, for every quadrature point of every segment.

    Parameters
    ----------
    field : callable or array_like
        Either ``field(points) -> (k, 3)`` for ``points`` of shape ``(k, 3)``
        with ``k = s * samples`` (segment-major: the samples of segment 0, then
        of segment 1, ...), or the values at :func:`segment_samples` points as
        an array of shape ``(s, samples, 3)``.
    P0, P1 : array_like, (s, 3) float64
        Segment start and end points.
    samples : int, optional
        Quadrature points per segment (default 5, as in the paper's transfer).
    rule : {"gauss", "trapezoid"}, optional
        See :func:`segment_samples`.  With the default Gauss-Legendre rule and
        5 samples the result is exact (to round-off) for fields that vary
        along each segment as polynomials of degree <= 9, in particular for
        linear fields.

    Returns
    -------
    numpy.ndarray, (s,) float64
        ``sum_q w_q <X(p_q), P1 - P0>``.

    Raises
    ------
    InputError
        On malformed points, a bad rule, or field values of the wrong shape
        or with non-finite entries.

    Examples
    --------
    >>> import numpy as np
    >>> P0 = np.zeros((1, 3)); P1 = np.array([[1.0, 2.0, 0.0]])
    >>> float(line_integrals(lambda p: p, P0, P1)[0])    # grad of |p|^2 / 2
    2.5
    """
    pts, w = segment_samples(P0, P1, samples=samples, rule=rule)
    s, q = pts.shape[0], pts.shape[1]
    if callable(field):
        vals = field(pts.reshape(-1, 3))
        try:
            vals = np.asarray(vals, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InputError(f"field must return a numeric (k, 3) array: {exc}") from None
        if vals.shape != (s * q, 3):
            raise InputError(f"field returned shape {vals.shape}, expected ({s * q}, 3) "
                             "for the points it was given")
        vals = vals.reshape(s, q, 3)
    else:
        try:
            vals = np.asarray(field, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InputError(f"field must be callable or a numeric array: {exc}") from None
        if vals.shape != (s, q, 3):
            raise InputError(f"field values must have shape ({s}, {q}, 3), got {vals.shape}")
    if not np.isfinite(vals).all():
        raise InputError("field has non-finite values at some quadrature points")
    d = np.asarray(P1, dtype=np.float64) - np.asarray(P0, dtype=np.float64)
    return np.einsum("q,sqd,sd->s", w, vals, d)


def integrate_edges(V, F, field, *, samples: int = 5, rule: str = "gauss", bound=False,
                    topology: EdgeTopology | None = None) -> np.ndarray:
    """Encode a field given at arbitrary points as a 1-form by edge line integrals.

    This is the height-and-tilt transfer rule: sample each edge of the target
    mesh, evaluate the (mapped) source field there, and integrate.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    field : callable
        ``field(points) -> (k, 3)``; see :func:`line_integrals` (points are
        edge-major in unique edge order, segments run from ``edges[e, 0]`` to
        ``edges[e, 1]``).
    samples : int, optional
    rule : {"gauss", "trapezoid"}, optional
    bound : bool or float, optional
        As in :func:`encode_one_form` (clip to ``|c_e| <= b |e|``); default none.
    topology : EdgeTopology, optional

    Returns
    -------
    numpy.ndarray, (e,) float64

    Raises
    ------
    InputError
        As :func:`line_integrals`, plus malformed meshes or a bad bound.
    """
    V, F = as_mesh_arrays(V, F)
    beta = _bound_factor(bound)
    topo = _topology(F, V.shape[0], topology)
    E = topo.edges
    c = line_integrals(field, V[E[:, 0]], V[E[:, 1]], samples=samples, rule=rule)
    if beta is not None:
        lim = beta * np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)
        c = np.clip(c, -lim, lim)
    return c
