"""Local parameterizations of surface patches.

* :func:`field_aligned_parameterization` – lapped textures §3.4: every face
  maps the field's tangent frame ``(S, T)`` to the texture axes; one sparse
  least-squares solve with a free boundary.
* :func:`harmonic_parameterization` – boundary fixed on a circle or a square,
  interior harmonic (libigl).
* :func:`lscm_parameterization` – least-squares conformal map (libigl).

Derivation of the field-aligned functional
------------------------------------------
The paper writes the field vector of a face as ``T = a A + b B + c C`` with
``a + b + c = 0`` and asks the piecewise-linear map ``phi`` to send ``S`` and
``T`` to the texture axes: it minimises ``sum_f |phi(S) - s|^2 + |phi(T) - t|^2``.
On a face, ``phi`` is linear with Jacobian ``J = [grad u; grad v]`` (rows in
the face plane), so ``phi(S) = (grad u . S, grad v . S)``.  With ``(S, T)``
orthonormal in the face plane::

    |J S - s|^2 + |J T - t|^2
        = (grad u.S - 1)^2 + (grad v.S)^2 + (grad u.T)^2 + (grad v.T - 1)^2
        = |grad u - S|^2 + |grad v - T|^2,

i.e. the paper's per-face term is the gradient mismatch.  We weight every face
by its area, which makes the energy a discretisation of
``int |grad u - S/h|^2 + |grad v - T/h|^2 dA`` (independent of how finely the
patch is triangulated; the paper sums unweighted).  ``h`` is the ``scale``:
surface length per texture unit, so one texture unit spans ``h`` on the
surface.  The normal equations are ``L u = D^T A S/h`` and ``L v = D^T A T/h``
with ``L = D^T A D`` the cotangent Laplacian (``D`` the per-face gradient
operator, ``A`` the face areas): one sparse factorisation, two right-hand
sides.  The minimum is unique up to a translation; we pin one vertex of the
centre face and then translate so the centre face's centroid lands on
``center_uv`` (the paper pins the patch centre the same way).  The boundary
is free.  When the field is the restriction of a constant field to a planar
(or developable, field along the rulings) patch, the map is an exact isometry
scaled by ``1/h``.
"""

from __future__ import annotations

import math

import igl
import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.linalg import factor
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import edge_topology, vertex_components
from geotex.patches.grow import check_triangles, boundary_loops, disc_problem

__all__ = ["field_aligned_parameterization", "harmonic_parameterization",
           "lscm_parameterization", "gradient_operator"]


def gradient_operator(V: np.ndarray, F: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """Per-face gradient of piecewise-linear vertex functions.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Faces with non-zero area.

    Returns
    -------
    G : scipy.sparse.csr_matrix, (3m, n)
        Row ``3 f + i`` gives coordinate ``i`` of the gradient on face ``f``:
        ``grad phi_a = N x (x_c - x_b) / (2 area)`` for corner ``a`` opposite
        edge ``(b, c)``.
    area : numpy.ndarray, (m,) float64
    """
    m = F.shape[0]
    P = V[F]
    cr = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    dbl = np.linalg.norm(cr, axis=1)
    N = cr / dbl[:, None]
    grads = np.empty((m, 3, 3))
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        grads[:, a] = np.cross(N, P[:, c] - P[:, b]) / dbl[:, None]
    rows = (3 * np.arange(m)[:, None, None] + np.arange(3)[None, None, :]).repeat(3, axis=1)
    cols = np.broadcast_to(F[:, :, None], (m, 3, 3))
    G = sp.csr_matrix((grads.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * m, V.shape[0]))
    return G, 0.5 * dbl


def _patch_arg(patch_faces, m: int) -> np.ndarray:
    arr = np.asarray(patch_faces)
    if arr.ndim != 1 or arr.size == 0:
        raise InputError(f"patch_faces must be a non-empty 1-D array of face ids, got shape "
                         f"{arr.shape}")
    if arr.dtype.kind not in "iu":
        raise InputError(f"patch_faces must hold integer face ids, got dtype {arr.dtype}")
    arr = arr.astype(np.int64)
    if arr.min() < 0 or arr.max() >= m:
        raise InputError(f"patch_faces has face ids outside [0, {m})")
    if np.unique(arr).size != arr.size:
        raise InputError("patch_faces lists a face more than once")
    return arr


def field_aligned_parameterization(V, F, patch_faces, field, *, scale=1.0, center_face=None,
                                   center_uv=(0.5, 0.5)) -> tuple[np.ndarray, np.ndarray]:
    """Flatten a patch so each face maps the field frame to the texture axes.

    Lapped textures §3.4 with area weights; see the module docstring for the
    derivation.  Per face, ``S`` is ``field`` projected into the face plane
    and normalised, ``T = N x S``; the map minimises
    ``sum_f area_f (|grad u - S/h|^2 + |grad v - T/h|^2)`` with ``h = scale``.
    ``u`` increases along the field, ``(u, v)`` is counter-clockwise seen from
    the normal side.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    patch_faces : array_like, (k,) int
        Faces of the patch (e.g. :attr:`geotex.patches.Patch.faces`); they must
        be connected through shared vertices.  Any topology works (the paper
        grows discs so that the field has no circular dependency).
    field : array_like, (m, 3) float64
        Tangent direction per face of the whole mesh; only patch faces are
        read; it need not be unit length or exactly tangent.
    scale : float or array_like (m,), optional
        Surface length of one texture unit (``> 0``), global or per face.
    center_face : int, optional
        Face whose centroid maps to ``center_uv``; defaults to
        ``patch_faces[0]`` (the seed of a grown patch).
    center_uv : (2,) float, optional
        Texture position of the centre face centroid.

    Returns
    -------
    uv : numpy.ndarray, (p, 2) float64
        Texture coordinates of the patch vertices.
    vertices : numpy.ndarray, (p,) int64
        Sorted global vertex ids; ``uv[i]`` belongs to ``vertices[i]`` and the
        local faces are ``numpy.searchsorted(vertices, F[patch_faces])``.

    Raises
    ------
    InputError
        On malformed arrays, repeated or out-of-range patch faces, a centre
        face outside the patch, degenerate patch faces, a field that vanishes
        (or is normal to the face) on a patch face, a non-positive scale, or a
        patch in several pieces.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(4, 4)
    >>> field = np.tile([1.0, 0.0, 0.0], (len(F), 1))
    >>> uv, verts = field_aligned_parameterization(V, F, np.arange(len(F)), field)
    >>> bool(np.allclose(uv - uv[0], V[verts, :2] - V[verts[0], :2]))
    True
    """
    V, F = as_mesh_arrays(V, F)
    m = F.shape[0]
    faces = _patch_arg(patch_faces, m)
    fld = np.asarray(field, dtype=np.float64)
    if fld.shape != (m, 3):
        raise InputError(f"field must have shape ({m}, 3) (one vector per face), got {fld.shape}")
    sc = np.asarray(scale, dtype=np.float64)
    if sc.ndim == 0:
        sc = np.full(faces.size, float(sc))
    elif sc.shape == (m,):
        sc = sc[faces]
    else:
        raise InputError(f"scale must be a number or have shape ({m},), got {sc.shape}")
    if not (np.all(np.isfinite(sc)) and np.all(sc > 0)):
        raise InputError("scale must be finite and > 0 on every patch face")
    if center_face is None:
        center = int(faces[0])
    else:
        try:
            center = int(center_face)
        except (TypeError, ValueError):
            raise InputError(f"center_face must be a face index, got {center_face!r}") from None
    where = np.flatnonzero(faces == center)
    if where.size == 0:
        raise InputError(f"center_face {center_face!r} is not one of patch_faces")
    cuv = np.asarray(center_uv, dtype=np.float64)
    if cuv.shape != (2,) or not np.all(np.isfinite(cuv)):
        raise InputError(f"center_uv must be two finite numbers, got {center_uv!r}")

    sub = F[faces]
    check_triangles(sub, "F[patch_faces]")
    verts = np.unique(sub)
    Fl = np.searchsorted(verts, sub).astype(np.int64)
    P = V[verts]
    cr = np.cross(P[Fl[:, 1]] - P[Fl[:, 0]], P[Fl[:, 2]] - P[Fl[:, 0]])
    dbl = np.linalg.norm(cr, axis=1)
    e2 = np.max([np.sum((P[Fl[:, (i + 1) % 3]] - P[Fl[:, i]]) ** 2, axis=1) for i in range(3)],
                axis=0)
    flat = ~(dbl > 1e-12 * e2)
    if flat.any():
        raise InputError(f"patch face {int(faces[np.flatnonzero(flat)[0]])} is degenerate "
                         "(zero area); remove degenerate faces first (geotex.repair)")
    count, _ = vertex_components(Fl, verts.size)
    if count != 1:
        raise InputError(f"patch_faces form {count} separate pieces; pass one connected patch")
    N = cr / dbl[:, None]
    S = fld[faces]
    if not np.all(np.isfinite(S)):
        raise InputError("field has non-finite vectors on patch faces")
    S = S - np.einsum("ij,ij->i", S, N)[:, None] * N
    sl = np.linalg.norm(S, axis=1)
    fl = np.linalg.norm(fld[faces], axis=1)
    weak = ~(sl > 1e-9 * np.maximum(fl, np.finfo(float).tiny))
    if weak.any():
        raise InputError(f"field is zero or normal to face {int(faces[np.flatnonzero(weak)[0]])}"
                         "; it needs a tangent direction on every patch face")
    S = S / sl[:, None]
    T = np.cross(N, S)
    G, area = gradient_operator(P, Fl)
    w = np.repeat(area, 3)
    GtW = (G.T.multiply(w)).tocsr()
    L = (GtW @ G).tocsc()
    rhs = np.stack([GtW @ (S / sc[:, None]).ravel(), GtW @ (T / sc[:, None]).ravel()], axis=1)
    p = verts.size
    pin = int(Fl[where[0], 0])
    free = np.ones(p, bool)
    free[pin] = False
    uv = np.zeros((p, 2))
    if p > 1:
        idx = np.flatnonzero(free)
        Lff = L[idx][:, idx].tocsc()
        uv[idx] = factor(Lff, what="field-aligned parameterization").solve(rhs[idx])
    centroid = uv[Fl[where[0]]].mean(axis=0)
    uv += cuv - centroid
    return uv, verts


# ---------------------------------------------------------------------------
# libigl wrappers
# ---------------------------------------------------------------------------

def _disc_mesh(V, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate a disc mesh; return ``(V, F, boundary loop)`` (loop counter-clockwise)."""
    V, F = as_mesh_arrays(V, F, allow_empty=False)
    check_triangles(F)
    used = np.zeros(V.shape[0], bool)
    used[F.ravel()] = True
    if not used.all():
        raise InputError(f"V has {int((~used).sum())} vertices no face uses; pass the patch's "
                         "own mesh (e.g. Patch.local_mesh(V))")
    why = disc_problem(F, V.shape[0])
    if why is not None:
        raise InputError(f"F must be a topological disc (one boundary loop, Euler "
                         f"characteristic 1), but {why}")
    if edge_topology(F, V.shape[0]).inconsistent.size:
        raise InputError("F is not consistently oriented; orient it first (geotex.repair)")
    loop = boundary_loops(F)[0]
    return V, F, loop


def _signed_area(uv: np.ndarray, F: np.ndarray) -> float:
    a, b, c = uv[F[:, 0]], uv[F[:, 1]], uv[F[:, 2]]
    return float(np.sum((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                        - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])))


def _square_boundary(V: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Map a loop onto the unit square by arc length, corners snapped to vertices."""
    nb = loop.size
    if nb < 4:
        raise InputError(f"the boundary has {nb} vertices; a square boundary needs at least 4")
    seg = np.linalg.norm(V[np.roll(loop, -1)] - V[loop], axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = s[-1]
    corners = [0]
    for j in (1, 2, 3):
        c = int(np.argmin(np.abs(s[:nb] - j * total / 4.0)))
        c = min(max(c, corners[-1] + 1), nb - (4 - j))
        corners.append(c)
    corners.append(nb)
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]])
    out = np.empty((nb, 2))
    for j in range(4):
        a, b = corners[j], corners[j + 1]
        t = (s[a:b] - s[a]) / (s[b] - s[a])
        out[a:b] = square[j] + t[:, None] * (square[j + 1] - square[j])
    return out


def harmonic_parameterization(V, F, *, boundary: str = "circle",
                              weights: str = "cotan") -> np.ndarray:
    """Harmonic map of a disc with its boundary fixed on a convex curve.

    The boundary loop is laid out by arc length on the unit circle (centred at
    the origin, ``igl.map_vertices_to_circle``) or on the unit square
    ``[0, 1]^2`` (corners at the vertices nearest to the quarter arc lengths);
    the interior solves the Laplace equation (``igl.harmonic`` with cotangent
    weights, or uniform "Tutte" weights, which guarantee a fold-free map on a
    convex boundary).  The result is oriented like ``F`` (positive total
    signed area).  On a square, a triangle with all three corners on one side
    collapses to zero area: prefer the circle for such meshes.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A consistently oriented topological disc using every vertex.
    boundary : {"circle", "square"}, optional
    weights : {"cotan", "uniform"}, optional

    Returns
    -------
    numpy.ndarray, (n, 2) float64

    Raises
    ------
    InputError
        If the mesh is not a disc (closed, several boundary loops, handles,
        several pieces, non-manifold), has unused vertices, or an option is
        unknown.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(4, 4)
    >>> uv = harmonic_parameterization(V, F)
    >>> uv.shape
    (25, 2)
    """
    if boundary not in ("circle", "square"):
        raise InputError(f"boundary must be 'circle' or 'square', got {boundary!r}")
    if weights not in ("cotan", "uniform"):
        raise InputError(f"weights must be 'cotan' or 'uniform', got {weights!r}")
    V, F, loop = _disc_mesh(V, F)
    if boundary == "circle":
        bc = np.asarray(igl.map_vertices_to_circle(np.asfortranarray(V), loop.astype(np.int32)),
                        dtype=np.float64)
    else:
        bc = _square_boundary(V, loop)
    n = V.shape[0]
    if weights == "cotan":
        uv = np.asarray(igl.harmonic(V, F, loop, np.ascontiguousarray(bc), 1), dtype=np.float64)
    else:
        e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
        e = np.unique(np.sort(e, axis=1), axis=0)
        A = sp.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                          shape=(n, n)).tocsr()
        L = (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()
        free = np.ones(n, bool)
        free[loop] = False
        idx = np.flatnonzero(free)
        uv = np.zeros((n, 2))
        uv[loop] = bc
        if idx.size:
            rhs = -(L[idx][:, loop] @ bc)
            uv[idx] = factor(L[idx][:, idx], what="harmonic parameterization").solve(rhs)
    if _signed_area(uv, F) < 0:
        uv[:, 1] = (1.0 if boundary == "square" else 0.0) - uv[:, 1]
    return np.ascontiguousarray(uv)


def lscm_parameterization(V, F) -> np.ndarray:
    """Least-squares conformal map of a disc (``igl.lscm``).

    Two boundary vertices are pinned: the first vertex of the boundary loop
    (its smallest vertex id) at ``(0, 0)`` and the boundary vertex farthest
    from it in space at ``(d, 0)``, ``d`` their 3D distance, so the map keeps
    roughly the surface scale.  The result is oriented like ``F``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A consistently oriented topological disc using every vertex.

    Returns
    -------
    numpy.ndarray, (n, 2) float64

    Raises
    ------
    InputError
        If the mesh is not a disc or has unused vertices.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(3, 3)
    >>> lscm_parameterization(V, F).shape
    (16, 2)
    """
    V, F, loop = _disc_mesh(V, F)
    a = int(loop[0])
    dist = np.linalg.norm(V[loop] - V[a], axis=1)
    b = int(loop[int(np.argmax(dist))])
    d = float(dist.max())
    if not d > 0 or not math.isfinite(d):
        raise InputError("the boundary of F has no extent; cannot pin an LSCM map")
    pins = np.array([a, b], dtype=np.int64)
    bc = np.array([[0.0, 0.0], [d, 0.0]])
    res = igl.lscm(V, F, pins, bc)
    uv = np.asarray(res[0] if isinstance(res, tuple) else res, dtype=np.float64)
    if uv.shape != (V.shape[0], 2) or not np.all(np.isfinite(uv)):
        raise InputError("igl.lscm failed on this mesh (degenerate triangles?)")
    if _signed_area(uv, F) < 0:
        uv[:, 1] = -uv[:, 1]
    return np.ascontiguousarray(uv)
