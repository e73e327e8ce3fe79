"""Base shape, base normals and exact tilt encoding for height-and-tilt textures.

The base shape is a smoothed copy of the textured mesh with the same
connectivity (vertex ``i`` of the base corresponds to vertex ``i`` of the
detailed mesh).  Base normals and the tilt encoding used by extraction and by
the edits live here so that every module agrees on them.

Base normals
------------
The normal at a base vertex is the normalised *mean of the unit normals of
its incident non-degenerate faces* (uniform weighting).  This is the tangent
plane that :func:`geotex.fields.oneforms.decode_one_form_at_vertices` with
``weighting="uniform"`` (the paper's plain average) and
:func:`geotex.fields.oneforms.encode_one_form` use, so the decoded tilt and
the normal refer to the same plane.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from geotex.errors import InputError
from geotex.fields._sparse import single_threaded_blas
from geotex.fields.oneforms import (_projected_decoder, decode_one_form_at_vertices,
                                    encode_one_form)
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import degenerate_faces
from geotex.mesh.topology import EdgeTopology, edge_topology

__all__ = ["smoothed_base", "base_normals", "tilt_frames", "encode_tilt", "decode_tilt",
           "check_base_mesh"]


def check_base_mesh(V, F, *, name: str = "V") -> tuple[np.ndarray, np.ndarray]:
    """Validate a mesh used as (or to build) a height-and-tilt base.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    name : str, optional
        Name of the vertex argument, used in messages.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64

    Raises
    ------
    InputError
        Empty vertices or faces; zero-area faces (no normal, no cotangent
        weights); edges shared by more than two faces (no tangent plane);
        vertices referenced by no face (no normal).  Open (boundary) meshes
        are accepted.
    """
    V, F = as_mesh_arrays(V, F)
    if V.shape[0] == 0:
        raise InputError(f"{name} is empty: a height-and-tilt base needs vertices")
    if F.shape[0] == 0:
        raise InputError("F is empty: a height-and-tilt base needs faces")
    bad = degenerate_faces(V, F)
    if bad.size:
        raise InputError(f"F has {bad.size} zero-area faces in {name} (first: face {int(bad[0])}); "
                         "remove them (geotex.repair) before extracting a texture")
    topo = edge_topology(F, V.shape[0])
    if topo.non_manifold.size:
        raise InputError(f"F has {topo.non_manifold.size} non-manifold edges (shared by more "
                         "than two faces); repair the mesh first")
    used = np.zeros(V.shape[0], dtype=bool)
    used[F.ravel()] = True
    if not used.all():
        raise InputError(f"{name} has {int((~used).sum())} vertices used by no face "
                         f"(first: {int(np.flatnonzero(~used)[0])}); remove them first")
    return V, F


def base_normals(Vs, F) -> np.ndarray:
    """Unit base normals: normalised mean of the incident unit face normals.

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
    F : array_like, (m, 3) int64

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Unit normals; the tangent plane of
        ``decode_one_form_at_vertices(..., weighting="uniform")``.

    Raises
    ------
    InputError
        See :func:`check_base_mesh`.
    """
    Vs, F = check_base_mesh(Vs, F, name="Vs")
    return _normals(Vs, F)


def _normals(Vs: np.ndarray, F: np.ndarray) -> np.ndarray:
    """:func:`base_normals` on already validated arrays."""
    N = np.cross(Vs[F[:, 1]] - Vs[F[:, 0]], Vs[F[:, 2]] - Vs[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    acc = np.zeros_like(Vs)
    for d in range(3):
        acc[:, d] = np.bincount(F.ravel(), weights=np.repeat(N[:, d], 3), minlength=Vs.shape[0])
    ln = np.linalg.norm(acc, axis=1, keepdims=True)
    if np.any(ln[:, 0] <= 1e-12):
        v = int(np.flatnonzero(ln[:, 0] <= 1e-12)[0])
        raise InputError(f"Vs has a vertex whose incident face normals cancel (vertex {v}); "
                         "the base normal is undefined there")
    return acc / ln


def smoothed_base(V, F, *, steps: int = 3, time_step: float | None = None) -> np.ndarray:
    """Smooth a textured mesh by implicit mean-curvature flow, keeping correspondence.

    Each step solves ``(M_k - dt L) V_{k+1} = M_k V_k`` (Desbrun et al. 1999)
    with the cotangent Laplacian ``L`` of the *input* mesh (``igl.cotmatrix``,
    negative semi-definite, scale free) and the Voronoi mass matrix ``M_k``
    (``igl.massmatrix``) *recomputed at every step* on the current positions,
    so that shrinking regions keep a consistent area weighting.  The vertices
    move, the faces stay: vertex ``i`` of the result corresponds to vertex
    ``i`` of ``V``.  Boundary vertices of open meshes move too (their
    Laplacian rows are the one-sided cotangent sums).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    steps : int, optional
        Number of implicit steps (>= 0; 0 returns a copy).
    time_step : float, optional
        Dimensionless step.  The actual ``dt = time_step * l**2`` with ``l``
        the mean edge length of the input, which makes the flow invariant
        under uniform scaling (``M`` scales as length squared, ``L`` not at
        all) and under rigid motions.  Default 1.0: about one ring of
        neighbours is smoothed per step.

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        The base shape ``Vs``.

    Raises
    ------
    InputError
        Empty mesh, zero-area faces, non-manifold edges, unreferenced
        vertices (see :func:`check_base_mesh`), a negative ``steps`` or a
        non-positive ``time_step``.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> smoothed_base(V, F).shape
    (162, 3)
    """
    V, F = check_base_mesh(V, F)
    if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, got {steps!r}")
    if time_step is None:
        time_step = 1.0
    try:
        ts = float(time_step)
    except (TypeError, ValueError):
        raise InputError(f"time_step must be a positive number, got {time_step!r}") from None
    if not (np.isfinite(ts) and ts > 0):
        raise InputError(f"time_step must be a positive number, got {time_step!r}")
    topo = edge_topology(F, V.shape[0])
    E = topo.edges
    mean_len = float(np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1).mean())
    dt = ts * mean_len * mean_len
    L = sp.csc_matrix(igl.cotmatrix(V, F))
    Vk = V.copy()
    for _ in range(int(steps)):
        M = sp.csc_matrix(igl.massmatrix(Vk, F, igl.MASSMATRIX_TYPE_VORONOI))
        solve = spla.factorized(sp.csc_matrix(M - dt * L))
        rhs = M @ Vk
        Vk = np.column_stack([solve(np.ascontiguousarray(rhs[:, d])) for d in range(3)])
        if not np.isfinite(Vk).all():
            raise InputError("smoothed_base diverged (non-finite positions); "
                             "use a smaller time_step or fewer steps")
    return np.ascontiguousarray(Vk)


def tilt_frames(Vs, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-vertex frames ``(n, T1, T2)`` intrinsic to the base mesh.

    ``n`` is :func:`base_normals`; ``T1`` is the direction to the vertex's
    lowest-index neighbour projected onto the tangent plane and normalised
    (or, if that edge is parallel to ``n``, the next neighbour); ``T2 = n x T1``.
    The frames move with the mesh under rigid motions and do not change under
    uniform scaling.  They are only used to store the tilt residual.

    Returns
    -------
    n, T1, T2 : numpy.ndarray, (n, 3) float64 each
    """
    Vs, F = check_base_mesh(Vs, F, name="Vs")
    return _frames(Vs, F, _normals(Vs, F), edge_topology(F, Vs.shape[0]))


def _frames(Vs: np.ndarray, F: np.ndarray, nrm: np.ndarray, topo: EdgeTopology
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`tilt_frames` on validated arrays with normals and topology given."""
    E = topo.edges
    both = np.concatenate([E, E[:, ::-1]])
    order = np.lexsort((both[:, 1], both[:, 0]))
    both = both[order]
    vec = Vs[both[:, 1]] - Vs[both[:, 0]]
    vec -= np.einsum("kd,kd->k", vec, nrm[both[:, 0]])[:, None] * nrm[both[:, 0]]
    ln = np.linalg.norm(vec, axis=1)
    ok = ln > 1e-9 * np.maximum(np.linalg.norm(Vs[both[:, 1]] - Vs[both[:, 0]], axis=1), 1e-300)
    cand = np.flatnonzero(ok)
    src = both[cand, 0]
    first = cand[np.unique(src, return_index=True)[1]]
    T1 = np.zeros_like(Vs)
    T1[both[first, 0]] = vec[first] / ln[first, None]
    T2 = np.cross(nrm, T1)
    return nrm, T1, T2


#: Conjugate-gradient iterations of the minimum-norm correction in :func:`encode_tilt`.
CORRECTION_ITERATIONS = 400


def encode_tilt(Vs, F, tilt, *, exact: bool = True,
                topology: EdgeTopology | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Encode per-vertex tilt vectors as a 1-form plus a per-vertex residual.

    1. The paper's bounded least-squares encoding
       ``c0 = encode_one_form(Vs, F, P t, at="vertices", bound=True)``
       (``|c_e| <= |e|``, paper section 5), ``P`` the tangent projector.
    2. With ``exact=True``, the minimum-norm correction towards exact vertex
       interpolation: ``c = c0 + B^T y``, ``(B B^T + eps I) y = t2 - B c0``,
       with ``B`` (2n, e) the map from coefficients to the two tangent-frame
       components of ``decode_one_form_at_vertices(..., weighting="uniform")``
       and ``eps = 1e-12 * mean(diag(B B^T))``, solved by Jacobi-preconditioned
       conjugate gradients (at most ``CORRECTION_ITERATIONS``; ``B`` has full
       row rank on the closed meshes tried, e.g. icospheres, but loses rank on
       discs: a grid plane has rank ``2n - 1``).  The correction may push a
       few coefficients past ``|e|``.  Whatever it leaves is kept in the
       residual, so exactness never depends on its convergence.
    3. The residual ``r = t - P D(c)`` that the 1-form cannot represent, stored
       as its two components in :func:`tilt_frames` (intrinsic: rigid-motion
       and scale invariant).  On closed meshes it is at round-off level after
       step 2; on open meshes it is the one or few unreachable directions.
       ``P D(c) + r`` equals the target exactly (to round-off): this is what
       makes extraction followed by reconstruction exact.

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
        Base vertices.
    F : array_like, (m, 3) int64
    tilt : array_like, (n, 3) float64
        Target tilt per vertex; only its part tangent to :func:`base_normals`
        is encoded.
    exact : bool, optional
        Apply step 2 (default).  ``False`` keeps the paper's bounded
        least-squares coefficients (the residual then holds the whole loss).
    topology : EdgeTopology, optional
        ``edge_topology(F, len(Vs))``, to reuse.

    Returns
    -------
    c : numpy.ndarray, (e,) float64
        Coefficients in geotex's unique edge order.
    residual : numpy.ndarray, (n, 2) float64
        Components of ``t - P D(c)`` along ``(T1, T2)`` of :func:`tilt_frames`.

    Raises
    ------
    InputError
        See :func:`check_base_mesh`; malformed ``tilt``.
    """
    Vs, F = check_base_mesh(Vs, F, name="Vs")
    n = Vs.shape[0]
    try:
        t = np.ascontiguousarray(tilt, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"tilt must be a numeric ({n}, 3) array: {exc}") from None
    if t.shape != (n, 3) or not np.isfinite(t).all():
        raise InputError(f"tilt must be a finite ({n}, 3) array, got shape {t.shape}")
    topo = edge_topology(F, n) if topology is None else topology
    nrm, T1, T2 = tilt_frames(Vs, F)
    t = t - np.einsum("nd,nd->n", t, nrm)[:, None] * nrm
    c = encode_one_form(Vs, F, t, at="vertices", bound=True, weighting="uniform",
                        topology=topo)
    B3, _ = _projected_decoder(Vs, F, topo, "uniform")
    rows = np.repeat(np.arange(2 * n), 3)
    cols = np.repeat((3 * np.arange(n)[:, None] + np.arange(3)), 2, axis=0)
    vals = np.stack([T1, T2], axis=1)
    S = sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(2 * n, 3 * n))
    B = (S @ B3).tocsr()
    t2 = np.stack([np.einsum("nd,nd->n", t, T1), np.einsum("nd,nd->n", t, T2)], axis=1).ravel()
    if exact:
        K = (B @ B.T).tocsr()
        eps = 1e-12 * float(K.diagonal().mean())
        K = K + eps * sp.identity(2 * n, format="csr")
        diag = K.diagonal()
        pre = spla.LinearOperator(K.shape, matvec=lambda x: x / diag, dtype=np.float64)
        with single_threaded_blas():
            y, _ = spla.cg(K, t2 - B @ c, rtol=1e-13, atol=0.0, maxiter=CORRECTION_ITERATIONS,
                           M=pre)
        c = c + B.T @ y
    residual = (t2 - B @ c).reshape(n, 2)
    return c, residual


def decode_tilt(Vs, F, c, residual=None, *, topology: EdgeTopology | None = None
                ) -> np.ndarray:
    """Tangential tilt per vertex: ``P D(c) + residual`` (see :func:`encode_tilt`).

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
    residual : array_like, (n, 2) float64, optional
        Components along :func:`tilt_frames`; zero if omitted.
    topology : EdgeTopology, optional

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Tangent to :func:`base_normals` (not clamped).
    """
    Vs, F = check_base_mesh(Vs, F, name="Vs")
    topo = edge_topology(F, Vs.shape[0]) if topology is None else topology
    nrm = _normals(Vs, F)
    return _decode(Vs, F, c, residual, nrm, _frames(Vs, F, nrm, topo), topo)


def _decode(Vs, F, c, residual, nrm, frames, topo) -> np.ndarray:
    """:func:`decode_tilt` on validated arrays with normals, frames and topology given."""
    _, T1, T2 = frames
    t = decode_one_form_at_vertices(Vs, F, c, weighting="uniform", topology=topo)
    t = t - np.einsum("nd,nd->n", t, nrm)[:, None] * nrm
    if residual is not None:
        r = np.asarray(residual, dtype=np.float64)
        if r.shape != (Vs.shape[0], 2):
            raise InputError(f"residual must have shape ({Vs.shape[0]}, 2), got {r.shape}")
        t = t + r[:, :1] * T1 + r[:, 1:] * T2
    return t
