"""Vectorized kernels shared by extraction and reconstruction (private).

Everything here works on already validated arrays and is written for large
meshes: one pass of per-face geometry and column-wise float64 arithmetic
instead of ``(m, 3, 3)`` temporaries; the edge topology is
:func:`geotex.mesh.topology.edge_topology` (one sort of int64 half-edge keys).

* :meth:`BaseGeometry.decode` is :func:`geotex.fields.oneforms.decode_one_form_at_vertices`
  with ``weighting="uniform"`` on meshes without degenerate faces (the only
  meshes a height-and-tilt base may be): the mean over the incident faces of
  the Whitney corner vectors ``T_k = s_k G_{k+1} - s_{k+2} G_{k+2}``, written
  as ``N x (s_k e_{k+1} - s_{k+2} e_{k+2}) / |N|^2`` (one cross product per
  corner).
* :func:`edge_encode` is the direct per-edge encoding
  ``c_ij = <(t_i + t_j) / 2, p_j - p_i>`` clipped to ``|c_ij| <= |p_j - p_i|``.
* :meth:`BaseGeometry.decoder_transpose` writes the projected decoder ``P D``
  edge by edge: the decoded vector at a vertex only involves the coefficients of the
  edges *incident* to it (corner ``k`` of a face uses the two face edges at
  ``k``), so ``(P D c)_v = sum_{e=(v,j)} a_e c_e + sum_{e=(i,v)} b_e c_e`` with
  one tangent vector ``a_e`` (at the first endpoint) and ``b_e`` (at the
  second) per edge.  In tangent frames that is four numbers per edge: the
  transpose is a CSR matrix with four entries per row, built without a sort,
  and :func:`lsq_encode` iterates on it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from geotex.mesh.topology import EdgeTopology, edge_topology

__all__ = ["cross", "dot", "axis_frames", "edge_encode", "lsq_encode", "BaseGeometry",
           "LSQ_DAMPING", "LSQ_ITERATIONS", "LSQ_RTOL", "LSQ_ROUNDS", "LSQ_ROUND_ITERATIONS"]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of ``(k, 3)`` arrays (column arithmetic)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of ``(k, 3)`` arrays."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


#: Fixed generic directions for :func:`axis_frames` (no ties on axis-aligned meshes).
_FRAME_AXIS = np.array([1.0, np.sqrt(2.0), np.sqrt(3.0)]) / np.sqrt(6.0)
_FRAME_AXIS_ALT = np.array([np.sqrt(3.0), -1.0, -np.sqrt(0.5)])
_FRAME_AXIS_ALT = _FRAME_AXIS_ALT - (_FRAME_AXIS_ALT @ _FRAME_AXIS) * _FRAME_AXIS
_FRAME_AXIS_ALT /= np.linalg.norm(_FRAME_AXIS_ALT)


def axis_frames(nrm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangent frames from a fixed direction, independent of the indexing.

    ``X1`` is the generic direction ``(1, sqrt 2, sqrt 3) / sqrt 6`` made
    tangent and normalised, or a second direction orthogonal to it where the
    normal is within about 37 degrees of it (``|n . a| > 0.8``); ``X2 = n x X1``.
    A generic direction, unlike a coordinate axis chosen by the smallest
    normal component, has no ties on axis-aligned meshes, where round-off would
    otherwise pick the axis.  Fixed in space (not rotation invariant).
    """
    ca = nrm @ _FRAME_AXIS
    alt = np.abs(ca) > 0.8
    X1 = np.broadcast_to(_FRAME_AXIS, nrm.shape).copy()
    X1[alt] = _FRAME_AXIS_ALT
    c = np.where(alt, nrm @ _FRAME_AXIS_ALT, ca)
    X1 -= c[:, None] * nrm
    X1 /= np.sqrt(dot(X1, X1))[:, None]
    return X1, cross(nrm, X1)


def edge_encode(V: np.ndarray, E: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``c_ij = <(t_i + t_j) / 2, p_j - p_i>`` clipped to ``[-|e|, |e|]``.

    Coordinates are gathered column by column (contiguous 1-D gathers).
    """
    a = np.ascontiguousarray(E[:, 0])
    b = np.ascontiguousarray(E[:, 1])
    c = np.zeros(E.shape[0])
    len2 = np.zeros(E.shape[0])
    for d in range(3):
        vd = np.ascontiguousarray(V[:, d])
        td = np.ascontiguousarray(t[:, d])
        ed = vd[b] - vd[a]
        c += (td[a] + td[b]) * ed
        len2 += ed * ed
    c *= 0.5
    lim = np.sqrt(len2)
    return np.clip(c, -lim, lim, out=c)


class BaseGeometry:
    """Per-face geometry of a validated base, computed once and shared.

    Built by :func:`geotex.heighttilt.base.base_geometry` (which validates);
    holds the faces as three contiguous index columns, the opposite-edge
    vectors ``e_k = p_{k+2} - p_{k+1}`` and face normals ``N = e_1 x e_2`` as
    contiguous coordinate columns, the edge topology, the valence (faces per
    vertex) and the unit base normals.  Frames are computed on first use.

    Attributes
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    topo : EdgeTopology
    valence : numpy.ndarray, (n,) float64
    normals : numpy.ndarray, (n, 3) float64
        Normalised mean of the incident unit face normals.
    """

    def __init__(self, V: np.ndarray, F: np.ndarray, topo: EdgeTopology | None = None):
        self.V, self.F = V, F
        n = V.shape[0]
        self.FT = np.ascontiguousarray(F.T)
        cols = [np.ascontiguousarray(V[:, d]) for d in range(3)]
        P = [tuple(c[f] for c in cols) for f in self.FT]
        self.e = [tuple(a - b for a, b in zip(P[(k + 2) % 3], P[(k + 1) % 3]))
                  for k in range(3)]
        (a0, a1, a2), (b0, b1, b2) = self.e[1], self.e[2]
        self.N = (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)
        self.N2 = self.N[0] ** 2 + self.N[1] ** 2 + self.N[2] ** 2
        lmax2 = np.maximum(np.maximum(_norm2(self.e[0]), _norm2(self.e[1])), _norm2(self.e[2]))
        with np.errstate(over="ignore", invalid="ignore"):
            self.flat = ~(np.sqrt(self.N2) > 1e-12 * lmax2)
        self.valence = np.bincount(F.ravel(), minlength=n).astype(np.float64)
        self._topo = topo
        self._normals = None
        self._transpose = None

    @property
    def topo(self) -> EdgeTopology:
        if self._topo is None:
            self._topo = edge_topology(self.F, self.V.shape[0])
        return self._topo

    def unit_sum_normals(self) -> np.ndarray:
        """Sum of the incident unit face normals per vertex, (n, 3)."""
        n = self.V.shape[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / np.sqrt(self.N2)
        acc = np.empty((n, 3))
        for d in range(3):
            w = self.N[d] * inv
            acc[:, d] = sum(np.bincount(f, weights=w, minlength=n) for f in self.FT)
        return acc

    @property
    def normals(self) -> np.ndarray:
        """Unit base normals (set by the validator)."""
        return self._normals

    def set_normals(self, normals: np.ndarray) -> None:
        self._normals = normals

    def decode(self, c: np.ndarray) -> np.ndarray:
        """Uniform vertex average of the Whitney corner vectors of ``c``, (n, 3).

        Equals ``decode_one_form_at_vertices(V, F, c, weighting="uniform")``
        (to round-off) on meshes without degenerate faces.
        """
        n = self.V.shape[0]
        m = self.F.shape[0]
        h2e = self.topo.half_to_edge.reshape(m, 3)
        FT = self.FT
        s = []
        for k in range(3):
            sk = c[h2e[:, k]]
            s.append(np.where(FT[k] < FT[(k + 1) % 3], sk, -sk))
        inv = 1.0 / self.N2
        G = []
        for k in range(3):
            (n0, n1, n2), (x0, x1, x2) = self.N, self.e[k]
            G.append(((n1 * x2 - n2 * x1) * inv, (n2 * x0 - n0 * x2) * inv,
                      (n0 * x1 - n1 * x0) * inv))
        out = np.empty((n, 3))
        for d in range(3):
            acc = np.bincount(FT[0], weights=s[0] * G[1][d] - s[2] * G[2][d], minlength=n)
            acc += np.bincount(FT[1], weights=s[1] * G[2][d] - s[0] * G[0][d], minlength=n)
            acc += np.bincount(FT[2], weights=s[2] * G[0][d] - s[1] * G[1][d], minlength=n)
            out[:, d] = acc / self.valence
        return out

    def decoder_transpose(self) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
        """``(P D)^T`` in per-vertex tangent frames, with the frames; cached.

        Returns ``AT`` (e, 2n) CSR with four entries per row, the components
        of ``a_e`` and ``b_e`` (module docstring) along the frames of the
        edge's two endpoints, and the frames ``X1, X2`` (n, 3) of
        :func:`axis_frames`.  Half-edge ``k`` of a face (``F_k -> F_{k+1}``)
        enters corner ``k`` with ``+G_{k+1}`` and corner ``k+1`` with ``-G_k``
        (signed by its orientation against the edge), so the two vectors of
        every edge are sums over its (one or two) half-edges, gathered
        through the topology's grouped half-edges, then projected on the
        frames of the endpoints; the rows are built directly (no sort).
        ``AT.T`` (CSC, no copy) applies ``P D`` to coefficients and gives the
        two frame components of every vertex vector.
        """
        if self._transpose is None:
            m = self.F.shape[0]
            n = self.V.shape[0]
            E = self.topo.edges
            e = E.shape[0]
            X1, X2 = axis_frames(self.normals)
            # G_k of face f = N x e_k / |N|^2, coordinate by coordinate
            inv = 1.0 / self.N2
            G = []
            for k in range(3):
                (n0, n1, n2), (x0, x1, x2) = self.N, self.e[k]
                G.append(((n1 * x2 - n2 * x1) * inv, (n2 * x0 - n0 * x2) * inv,
                          (n0 * x1 - n1 * x0) * inv))
            # half-edge h = 3 f + k runs F_k -> F_{k+1}; the edge's first vertex gets
            # +G_{k+1} if h runs along the edge (a -> b), else +G_k; the second -G_k,
            # else -G_{k+1}: summed over the edge's half-edges (in half-edge order)
            FT = self.FT
            fwd = [FT[k] < FT[(k + 1) % 3] for k in range(3)]
            h2e = self.topo.half_to_edge
            ea, eb = np.ascontiguousarray(E[:, 0]), np.ascontiguousarray(E[:, 1])
            iv = 1.0 / self.valence
            wa, wb = iv[ea], iv[eb]
            # data row e: a_e . X1(a), a_e . X2(a), b_e . X1(b), b_e . X2(b), scaled by
            # 1 / valence; accumulated coordinate by coordinate on contiguous columns
            data = np.zeros((4, e))
            w = np.empty((m, 3))
            for d in range(3):
                for k in range(3):
                    np.copyto(w[:, k], np.where(fwd[k], G[(k + 1) % 3][d], G[k][d]))
                a_d = np.bincount(h2e, weights=w.ravel(), minlength=e)
                for k in range(3):
                    np.copyto(w[:, k], np.where(fwd[k], G[k][d], G[(k + 1) % 3][d]))
                b_d = np.bincount(h2e, weights=w.ravel(), minlength=e)
                x1, x2 = np.ascontiguousarray(X1[:, d]), np.ascontiguousarray(X2[:, d])
                data[0] += a_d * x1[ea]
                data[1] += a_d * x2[ea]
                data[2] -= b_d * x1[eb]
                data[3] -= b_d * x2[eb]
            data[:2] *= wa
            data[2:] *= wb
            index = np.int32 if 2 * n < 2 ** 31 else np.int64
            cols = np.empty((e, 4), dtype=index)
            cols[:, 0] = 2 * ea
            cols[:, 1] = cols[:, 0] + 1
            cols[:, 2] = 2 * eb
            cols[:, 3] = cols[:, 2] + 1
            AT = sp.csr_matrix((data.T.ravel(), cols.ravel(),
                                4 * np.arange(e + 1, dtype=index)), shape=(e, 2 * n))
            self._transpose = (AT, X1, X2)
        return self._transpose

    def tangent(self, X: np.ndarray) -> np.ndarray:
        """``X`` minus its component along the base normals."""
        nrm = self.normals
        return X - dot(X, nrm)[:, None] * nrm


def _norm2(v) -> np.ndarray:
    return v[0] * v[0] + v[1] * v[1] + v[2] * v[2]


#: Relative Tikhonov weight of :func:`lsq_encode` (towards the edge encoding).
LSQ_DAMPING = 1e-3
#: Conjugate-gradient iterations of the unconstrained fit, at most.
LSQ_ITERATIONS = 16
#: Relative residual at which the unconstrained fit stops early.
LSQ_RTOL = 1e-3
#: Active-set rounds for the bound ``|c_e| <= |e|``, and iterations per round.
LSQ_ROUNDS = 2
LSQ_ROUND_ITERATIONS = 4


def lsq_encode(g: BaseGeometry, t: np.ndarray) -> np.ndarray:
    """The paper's bounded least-squares 1-form of a tangent vertex field, matrix-free.

    Minimises ``|P D c - t|^2 + damping sum_e K_ee (c_e - c0_e)^2`` subject to
    ``|c_e| <= |e|``, with ``c0`` = :func:`edge_encode` (the start and the
    damping target: there are more edges than tangential equations) and
    ``K_ee`` the diagonal of the normal matrix (scale-free damping).  Solved by
    Jacobi-preconditioned conjugate gradients on the normal equations through
    :meth:`BaseGeometry.decoder_transpose` (four entries per edge)
    (at most ``LSQ_ITERATIONS``, stopping at relative residual ``LSQ_RTOL``),
    then ``LSQ_ROUNDS`` active-set rounds: coefficients past their bound are
    fixed at it and the free ones re-fitted (``LSQ_ROUND_ITERATIONS`` each);
    the result is clipped so the bound holds exactly.  A truncated solve: the
    iteration counts are fixed, so the cost is a few dozen passes over the
    edges whatever the mesh size.

    Parameters
    ----------
    g : BaseGeometry
    t : numpy.ndarray, (n, 3) float64
        Tangent vertex vectors.

    Returns
    -------
    numpy.ndarray, (e,) float64
    """
    E = g.topo.edges
    c0 = edge_encode(g.V, E, t)
    if E.shape[0] == 0:
        return c0
    AT, X1, X2 = g.decoder_transpose()
    A = AT.T
    lim = np.sqrt(np.einsum("ed,ed->e", g.V[E[:, 1]] - g.V[E[:, 0]],
                            g.V[E[:, 1]] - g.V[E[:, 0]]))
    diag = np.asarray(AT.multiply(AT).sum(axis=1)).ravel()
    reg = LSQ_DAMPING * diag
    Kd = diag + reg
    Kd[Kd <= 0] = 1.0

    def K(x):
        return AT @ (A @ x) + reg * x

    t2 = np.empty((t.shape[0], 2))
    t2[:, 0] = dot(t, X1)
    t2[:, 1] = dot(t, X2)
    rhs = AT @ (t2.ravel() - A @ c0)
    lo, hi = -lim - c0, lim - c0
    d = _pcg(K, rhs, np.zeros_like(c0), Kd, None, LSQ_ITERATIONS, LSQ_RTOL)
    free = np.ones(c0.shape, dtype=bool)
    for _ in range(LSQ_ROUNDS):
        out = free & ((d > hi) | (d < lo))
        if not out.any():
            break
        np.clip(d, lo, hi, out=d)
        free &= ~out
        d = _pcg(K, rhs, d, Kd, free, LSQ_ROUND_ITERATIONS, 0.0)
    c = c0 + d
    return np.clip(c, -lim, lim, out=c)


def _pcg(K, rhs, x, Kd, free, iterations, rtol):
    """Jacobi-preconditioned CG on ``K x = rhs`` over the ``free`` unknowns."""
    mask = None if free is None else free.astype(np.float64)
    r = rhs - K(x)
    if mask is not None:
        r *= mask
    z = r / Kd
    p = z.copy()
    rz = _vdot(r, z)
    stop = rtol * rtol * _vdot(rhs, rhs)
    for _ in range(iterations):
        if rz <= 0.0 or _vdot(r, r) <= stop:
            break
        Kp = K(p)
        if mask is not None:
            Kp *= mask
        alpha = rz / _vdot(p, Kp)
        x += alpha * p
        r -= alpha * Kp
        z = r / Kd
        rz_new = _vdot(r, z)
        p *= rz_new / rz
        p += z
        rz = rz_new
    return x


def _vdot(x: np.ndarray, y: np.ndarray) -> float:
    # einsum's own loop: BLAS ddot may spawn threads, slow on a busy machine
    return float(np.einsum("i,i->", x, y))
