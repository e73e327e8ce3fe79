"""Base validation and geometry, base normals, tilt frames and the tilt codec.

The base shape is a smoothed copy of the textured mesh with the same
connectivity (vertex ``i`` of the base corresponds to vertex ``i`` of the
detailed mesh; :func:`smoothed_base`, from :mod:`geotex.heighttilt.smoothing`,
and :func:`check_base_mesh` / :func:`base_geometry`, from
:mod:`geotex.heighttilt.validation`, are re-exported here).  Base normals,
frames and the tilt encoding used by extraction, reconstruction and the edits
live here so that every module agrees on them.  :func:`base_geometry` validates a base once and keeps its
face geometry, edge topology, valences, normals and frames for reuse
(:class:`geotex.heighttilt._kernels.BaseGeometry`).

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

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from geotex.errors import InputError
from geotex.linalg import single_threaded_blas
from geotex.fields.oneforms import projected_decoder
from geotex.heighttilt._kernels import (BaseGeometry, axis_frames, cross, dot, edge_encode,
                                        lsq_encode)
from geotex.heighttilt.smoothing import smoothed_base
from geotex.heighttilt.validation import base_geometry, check_base_mesh
from geotex.mesh.topology import EdgeTopology

__all__ = ["smoothed_base", "base_normals", "tilt_frames", "encode_tilt", "decode_tilt",
           "check_base_mesh", "base_geometry", "ENCODINGS"]


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
    return base_geometry(Vs, F, name="Vs").normals.copy()


#: Below this length a decoded tilt (dimensionless, at most 1) gives no frame direction
#: (the direction of a shorter vector would carry its round-off, magnified, into the frame).
FRAME_TOLERANCE = 1e-7


def tilt_frames(Vs, F, c=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-vertex frames ``(n, T1, T2)`` in which the tilt residual is stored.

    ``n`` is :func:`base_normals` and ``T2 = n x T1``.  ``T1`` follows the
    texture's own 1-form ``c``, so it depends on neither the vertex nor the
    face order (the paper's objection to edge-ordering bases):

    1. the direction of the decoded tilt ``u = P D(c)`` at the vertex, where
       ``|u| > FRAME_TOLERANCE``;
    2. otherwise the tangent part of the sum of ``u`` over the vertex's
       neighbours, where that is longer than ``FRAME_TOLERANCE``;
    3. otherwise (the 1-form vanishes on the whole one-ring, e.g. ``c`` is
       None or zero) a fixed generic direction projected onto the tangent
       plane (:func:`geotex.heighttilt._kernels.axis_frames`).

    Steps 1 and 2 move with the mesh under rigid motions and do not change
    under uniform scaling; step 3 is fixed in space (still independent of the
    indexing).

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64, optional
        The texture's tilt 1-form (geotex's unique edge order of ``F``).

    Returns
    -------
    n, T1, T2 : numpy.ndarray, (n, 3) float64 each

    Raises
    ------
    InputError
        See :func:`check_base_mesh`; ``c`` of the wrong shape.
    """
    g = base_geometry(Vs, F, name="Vs")
    if c is None:
        u = np.zeros_like(g.V)
    else:
        u = g.tangent(g.decode(_coefficients(g, c)))
    return frames_of(g, u)


def frames_of(g: BaseGeometry, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`tilt_frames` of a validated base from the decoded 1-form ``u = P D(c)``."""
    nrm = g.normals
    n = nrm.shape[0]
    T1 = u.copy()
    ln = np.sqrt(dot(T1, T1))
    weak = ln <= FRAME_TOLERANCE
    if weak.any():
        E = g.topo.edges
        ring = np.empty((n, 3))
        for d in range(3):
            ring[:, d] = (np.bincount(E[:, 0], weights=u[E[:, 1], d], minlength=n)
                          + np.bincount(E[:, 1], weights=u[E[:, 0], d], minlength=n))
        ring = g.tangent(ring)
        T1[weak] = ring[weak]
        ln[weak] = np.sqrt(dot(ring[weak], ring[weak]))
        still = ln <= FRAME_TOLERANCE
        if still.any():
            T1[still] = axis_frames(nrm[still])[0]
            ln[still] = 1.0
    T1 /= ln[:, None]
    return nrm, T1, cross(nrm, T1)


def _coefficients(g: BaseGeometry, c) -> np.ndarray:
    e = g.topo.edges.shape[0]
    try:
        c = np.ascontiguousarray(c, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"c must be a numeric ({e},) array: {exc}") from None
    if c.shape != (e,) or not np.isfinite(c).all():
        raise InputError(f"c must be a finite ({e},) array, one coefficient per unique edge, "
                         f"got shape {c.shape}")
    return c


#: Conjugate-gradient iterations of the minimum-norm correction in :func:`encode_tilt`.
CORRECTION_ITERATIONS = 400
#: Tilt encodings accepted by :func:`encode_tilt` and the extraction.
ENCODINGS = ("lsq", "edge")


def check_encoding(encode) -> str:
    """Return ``encode`` if it names a tilt encoding, else raise InputError."""
    if not isinstance(encode, str) or encode not in ENCODINGS:
        raise InputError(f"encode must be one of {', '.join(map(repr, ENCODINGS))}, "
                         f"got {encode!r}")
    return encode


def encode_tilt(Vs, F, tilt, *, encode: str = "lsq", exact: bool = False,
                topology: EdgeTopology | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Encode per-vertex tilt vectors as a 1-form plus a per-vertex residual.

    1. The 1-form ``c`` from the tangential tilt ``P t`` (``P`` the projector
       onto the tangent plane of :func:`base_normals`):

       * ``encode="lsq"`` (default): the paper's bounded least squares
         (sections 2 and 5): ``c`` fits the decoded vertex vectors,
         ``min |P D(c) - P t|^2`` subject to ``|c_e| <= |e|``, lightly damped
         towards the edge encoding below (there are more edges than tangential
         equations).  Matrix-free truncated conjugate gradients with a few
         active-set rounds for the bound
         (:func:`geotex.heighttilt._kernels.lsq_encode`): a fixed number of
         passes over the edges.
       * ``encode="edge"`` (fast): ``c_ij = <(t_i + t_j) / 2, p_j - p_i>``,
         the exact line integral of the linearly interpolated tilt along the
         edge, clipped to ``|c_ij| <= |p_j - p_i|``.  One gather per edge; the
         decoded 1-form is a one-ring average of the tilt, so sharp elements
         lose much of their lean in it (the residual holds the rest).

    2. With ``exact=True``, the minimum-norm correction towards exact vertex
       interpolation: ``c <- c + B^T y``, ``(B B^T + eps I) y = t2 - B c``,
       with ``B`` (2n, e) the map from coefficients to the two tangent-frame
       components of ``decode_one_form_at_vertices(..., weighting="uniform")``
       (:func:`geotex.fields.oneforms.projected_decoder` in the frames) and
       ``eps = 1e-12 * mean(diag(B B^T))``, solved by Jacobi-preconditioned
       conjugate gradients (at most ``CORRECTION_ITERATIONS``; ``B`` has full
       row rank on the closed meshes tried, e.g. icospheres, but loses rank on
       discs).  The correction may push a few coefficients past ``|e|``.
       After it, the 1-form alone decodes to the tilt (to round-off on
       closed meshes).
    3. The residual ``r = t - P D(c)`` that the 1-form does not reproduce,
       stored as its two components in the frames :func:`tilt_frames` builds
       from ``c`` itself (``T1`` along the decoded 1-form: independent of
       the indexing, rigid-motion and scale invariant).  ``P D(c) + r`` equals the target
       to round-off whatever the encoding: this is what makes extraction
       followed by reconstruction exact.

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
        Base vertices.
    F : array_like, (m, 3) int64
    tilt : array_like, (n, 3) float64
        Target tilt per vertex; only its part tangent to :func:`base_normals`
        is encoded.
    encode : {"lsq", "edge"}, optional
        How the 1-form is computed (step 1).
    exact : bool, optional
        Apply step 2 (default False: the residual holds what the 1-form misses).
    topology : EdgeTopology, optional
        ``edge_topology(F, len(Vs))``, to reuse.

    Returns
    -------
    c : numpy.ndarray, (e,) float64
        Coefficients in geotex's unique edge order.
    residual : numpy.ndarray, (n, 2) float64
        Components of ``t - P D(c)`` along ``(T1, T2)`` of ``tilt_frames(Vs, F, c)``.

    Raises
    ------
    InputError
        See :func:`check_base_mesh`; malformed ``tilt``; unknown ``encode``.
    """
    encode = check_encoding(encode)
    g = base_geometry(Vs, F, name="Vs", topology=topology)
    n = g.V.shape[0]
    try:
        t = np.ascontiguousarray(tilt, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"tilt must be a numeric ({n}, 3) array: {exc}") from None
    if t.shape != (n, 3) or not np.isfinite(t).all():
        raise InputError(f"tilt must be a finite ({n}, 3) array, got shape {t.shape}")
    return encode_on(g, t, encode=encode, exact=bool(exact))


def encode_on(g: BaseGeometry, t: np.ndarray, *, encode: str = "lsq", exact: bool = False
              ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`encode_tilt` on a validated base geometry and a checked ``(n, 3)`` tilt."""
    n = g.V.shape[0]
    t = g.tangent(t)
    if encode == "edge":
        c = edge_encode(g.V, g.topo.edges, t)
    else:
        c = lsq_encode(g, t)
    if exact:
        B3, _ = projected_decoder(g.V, g.F, topology=g.topo)
        # the correction is expressed in frames that do not depend on c
        _, T1, T2 = frames_of(g, np.zeros_like(t))
        rows = np.repeat(np.arange(2 * n), 3)
        cols = np.repeat((3 * np.arange(n)[:, None] + np.arange(3)), 2, axis=0)
        vals = np.stack([T1, T2], axis=1)
        S = sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(2 * n, 3 * n))
        B = (S @ B3).tocsr()
        t2 = np.stack([dot(t, T1), dot(t, T2)], axis=1).ravel()
        K = (B @ B.T).tocsr()
        eps = 1e-12 * float(K.diagonal().mean())
        K = K + eps * sp.identity(2 * n, format="csr")
        diag = K.diagonal()
        pre = spla.LinearOperator(K.shape, matvec=lambda x: x / diag, dtype=np.float64)
        with single_threaded_blas():
            y, _ = spla.cg(K, t2 - B @ c, rtol=1e-13, atol=0.0, maxiter=CORRECTION_ITERATIONS,
                           M=pre)
        c = c + B.T @ y
    Pc = g.tangent(g.decode(c))
    _, T1, T2 = frames_of(g, Pc)
    r = np.stack([dot(t - Pc, T1), dot(t - Pc, T2)], axis=1)
    # one step of iterative refinement against exactly what decode_on computes,
    # so the decoded tilt is t to the last bit or so (|t| near 1 is ill-conditioned
    # for the reconstruction's sqrt(1 - |t|^2))
    miss = t - (Pc + (r[:, :1] * T1 + r[:, 1:] * T2))
    r += np.stack([dot(miss, T1), dot(miss, T2)], axis=1)
    return c, r


def decode_tilt(Vs, F, c, residual=None, *, topology: EdgeTopology | None = None
                ) -> np.ndarray:
    """Tangential tilt per vertex: ``P D(c) + residual`` (see :func:`encode_tilt`).

    Parameters
    ----------
    Vs : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    c : array_like, (e,) float64
    residual : array_like, (n, 2) float64, optional
        Components along ``tilt_frames(Vs, F, c)``; zero if omitted.
    topology : EdgeTopology, optional

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        Tangent to :func:`base_normals` (not clamped).

    Raises
    ------
    InputError
        See :func:`check_base_mesh`; ``c`` or ``residual`` of the wrong shape
        or with non-finite values.
    """
    g = base_geometry(Vs, F, name="Vs", topology=topology)
    c = _coefficients(g, c)
    return decode_on(g, c, residual)


def decode_on(g: BaseGeometry, c: np.ndarray, residual=None) -> np.ndarray:
    """:func:`decode_tilt` on a validated base geometry."""
    t = g.tangent(g.decode(c))
    if residual is not None:
        r = np.asarray(residual, dtype=np.float64)
        if r.shape != (g.V.shape[0], 2):
            raise InputError(f"residual must have shape ({g.V.shape[0]}, 2), got {r.shape}")
        _, T1, T2 = frames_of(g, t)
        t = t + (r[:, :1] * T1 + r[:, 1:] * T2)
    return t
