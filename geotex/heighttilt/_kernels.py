"""Vectorized kernels shared by extraction and reconstruction (private).

Everything here works on already validated arrays and is written for large
meshes: one pass of per-face geometry and column-wise float64 arithmetic
instead of ``(m, 3, 3)`` temporaries; the edge topology is
:func:`geotex.mesh.topology.edge_topology` (one sort of int64 half-edge keys).
Large temporaries are few: buffers are reused through ``out=`` and the
conjugate-gradient updates are in-place BLAS calls (fresh memory costs page
faults, which on a busy machine weigh as much as the arithmetic).

* :meth:`BaseGeometry.decode` is :func:`geotex.fields.oneforms.decode_one_form_at_vertices`
  with ``weighting="uniform"`` on meshes without degenerate faces (the only
  meshes a height-and-tilt base may be): the mean over the incident faces of
  the Whitney corner vectors ``T_k = s_k G_{k+1} - s_{k+2} G_{k+2}`` with the
  face gradients ``G_k = N x e_k / |N|^2`` computed once per base
  (:meth:`BaseGeometry.gradients`, shared with the decoder transpose).
* :func:`edge_encode` is the direct per-edge encoding
  ``c_ij = <(t_i + t_j) / 2, p_j - p_i>`` clipped to ``|c_ij| <= |p_j - p_i|``.
* On large meshes (from :data:`geotex.jit.JIT_MIN_SIZE` half-edges or
  edges) the decoder, its transpose and the conjugate gradients of
  :func:`lsq_encode` run as compiled loops (:mod:`geotex.jit`): the same sums
  without the sparse matrices and temporaries (equal to round-off; tested).
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
import scipy.linalg.blas as blas
import scipy.sparse as sp

from geotex.jit import JIT_MIN_SIZE, compiled
from geotex.linalg import single_threaded_blas
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
    cols = [np.ascontiguousarray(nrm[:, d]) for d in range(3)]
    ca = cols[0] * _FRAME_AXIS[0] + cols[1] * _FRAME_AXIS[1] + cols[2] * _FRAME_AXIS[2]
    alt = np.flatnonzero(np.abs(ca) > 0.8)
    c = ca
    c[alt] = (cols[0][alt] * _FRAME_AXIS_ALT[0] + cols[1][alt] * _FRAME_AXIS_ALT[1]
              + cols[2][alt] * _FRAME_AXIS_ALT[2])
    X1 = np.empty(nrm.shape)
    len2 = np.zeros(nrm.shape[0])
    for d in range(3):
        x = X1[:, d]
        np.multiply(c, cols[d], out=x)
        np.subtract(_FRAME_AXIS[d], x, out=x)
        x[alt] = _FRAME_AXIS_ALT[d] - c[alt] * cols[d][alt]
        len2 += x * x
    X1 /= np.sqrt(len2)[:, None]
    return X1, cross(nrm, X1)


def edge_encode(V: np.ndarray, E: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``c_ij = <(t_i + t_j) / 2, p_j - p_i>`` clipped to ``[-|e|, |e|]``.

    Coordinates are gathered column by column (contiguous 1-D gathers).
    """
    return edge_encode_and_lengths(V, E, t)[0]


def edge_encode_and_lengths(V: np.ndarray, E: np.ndarray, t: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`edge_encode` and the edge lengths ``|p_j - p_i|`` (its bounds), ``(e,)`` each."""
    if E.shape[0] >= JIT_MIN_SIZE:
        c, lim = np.empty(E.shape[0]), np.empty(E.shape[0])
        _edge_integrals(np.ascontiguousarray(E), np.ascontiguousarray(V, dtype=np.float64),
                        np.ascontiguousarray(t, dtype=np.float64), c, lim)
        return c, lim
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
    return np.clip(c, -lim, lim, out=c), lim


@compiled
def _edge_integrals(E, V, t, c, lim):
    """:func:`edge_encode_and_lengths` edge by edge (the same sums, bit for bit)."""
    for i in range(E.shape[0]):
        a = E[i, 0]
        b = E[i, 1]
        ci = 0.0
        len2 = 0.0
        for d in range(3):
            ed = V[b, d] - V[a, d]
            ci += (t[a, d] + t[b, d]) * ed
            len2 += ed * ed
        ci *= 0.5
        li = np.sqrt(len2)
        lim[i] = li
        c[i] = min(max(ci, -li), li)


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
        self.FT = np.ascontiguousarray(F.T)
        if F.size >= JIT_MIN_SIZE:
            rows = np.empty((13, F.shape[0]))
            self.flat = np.empty(F.shape[0], dtype=bool)
            _face_geometry(self.FT, np.ascontiguousarray(V, dtype=np.float64), rows, self.flat)
            self.e = [tuple(rows[3 * k:3 * k + 3]) for k in range(3)]
            self.N, self.N2 = tuple(rows[9:12]), rows[12]
            self._finish(topo, rows)
            return
        cols = [np.ascontiguousarray(V[:, d]) for d in range(3)]
        P0, P1, P2 = ([np.take(c, f) for c in cols] for f in self.FT)
        # e_k = p_{k+2} - p_{k+1}, written over the gathered corners once they are used
        e0 = [b - a for a, b in zip(P1, P2)]
        e1 = [np.subtract(a, b, out=b) for a, b in zip(P0, P2)]
        e2 = [np.subtract(b, a, out=b) for a, b in zip(P0, P1)]
        del P0
        self.e = [tuple(e0), tuple(e1), tuple(e2)]
        (a0, a1, a2), (b0, b1, b2) = self.e[1], self.e[2]
        tmp = np.empty(F.shape[0])
        N = []
        for (p, q), (r, u) in (((a1, b2), (a2, b1)), ((a2, b0), (a0, b2)), ((a0, b1), (a1, b0))):
            x = p * q
            x -= np.multiply(r, u, out=tmp)
            N.append(x)
        self.N = tuple(N)
        self.N2 = _norm2(self.N, tmp)
        lmax2 = _norm2(self.e[0], tmp)
        for k in (1, 2):
            np.maximum(lmax2, _norm2(self.e[k], tmp), out=lmax2)
        with np.errstate(over="ignore", invalid="ignore"):
            np.sqrt(self.N2, out=tmp)
            lmax2 *= 1e-12
            self.flat = ~(tmp > lmax2)
        del tmp, lmax2
        self._finish(topo)

    def _finish(self, topo: EdgeTopology | None, rows: np.ndarray | None = None) -> None:
        self._rows = rows                       # (13, m) face arrays of the compiled pass
        self._gradient_stack = None
        self.valence = np.bincount(self.F.ravel(), minlength=self.V.shape[0]).astype(np.float64)
        self._topo = topo
        self._normals = None
        self._transpose = None
        self._gradients = None
        self._forward = None

    @property
    def topo(self) -> EdgeTopology:
        if self._topo is None:
            self._topo = edge_topology(self.F, self.V.shape[0])
        return self._topo

    def unit_sum_normals(self) -> np.ndarray:
        """Sum of the incident unit face normals per vertex, (n, 3)."""
        n = self.V.shape[0]
        if 3 * self.F.shape[0] >= JIT_MIN_SIZE:
            acc = np.zeros((n, 3))
            _unit_normal_sums(self.FT, *self.N, self.N2, acc)
            return acc
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

    def gradients(self) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """``G_k = N x e_k / |N|^2`` of every face (the gradient of the hat function
        of corner ``k``), three coordinate columns ``(m,)`` per corner; cached."""
        if self._gradients is None and 3 * self.F.shape[0] >= JIT_MIN_SIZE:
            self.gradient_stack()
        if self._gradients is None:
            inv = 1.0 / self.N2
            G = []
            for k in range(3):
                (n0, n1, n2), (x0, x1, x2) = self.N, self.e[k]
                G.append(((n1 * x2 - n2 * x1) * inv, (n2 * x0 - n0 * x2) * inv,
                          (n0 * x1 - n1 * x0) * inv))
            self._gradients = G
        return self._gradients

    def gradient_stack(self) -> np.ndarray:
        """:meth:`gradients` as one ``(3, 3, m)`` array ``[corner, axis, face]``; cached.

        Computed in one compiled pass from the face arrays (the same products,
        bit for bit); a copy of the numpy path's columns where those came first.
        """
        if self._gradient_stack is None:
            if self._gradients is not None:
                self._gradient_stack = np.array(self._gradients)
            else:
                E = self._rows[:9].reshape(3, 3, -1) if self._rows is not None \
                    else np.array(self.e)
                G = np.empty((3, 3, self.F.shape[0]))
                _face_gradients(np.array(self.N) if self._rows is None else self._rows[9:12],
                                self.N2, E, G)
                self._gradient_stack = G
                self._gradients = [tuple(G[k]) for k in range(3)]
        return self._gradient_stack

    def forward(self) -> np.ndarray:
        """``(3, m)`` bool: half-edge ``k`` of face ``f`` runs from the lower to the
        higher vertex index (along its unique edge); cached."""
        if self._forward is None:
            FT = self.FT
            self._forward = np.stack([FT[k] < FT[(k + 1) % 3] for k in range(3)])
        return self._forward

    def decode(self, c: np.ndarray) -> np.ndarray:
        """Uniform vertex average of the Whitney corner vectors of ``c``, (n, 3).

        Equals ``decode_one_form_at_vertices(V, F, c, weighting="uniform")``
        (to round-off) on meshes without degenerate faces.
        """
        n = self.V.shape[0]
        m = self.F.shape[0]
        if 3 * m >= JIT_MIN_SIZE:
            out = np.zeros((n, 3))
            _decode_loops(self.FT, self.topo.half_to_edge, c, self.gradient_stack(),
                          self.valence, out)
            return out
        h2e = self.topo.half_to_edge.reshape(m, 3)
        FT = self.FT
        fwd = self.forward()
        s = []
        for k in range(3):
            sk = c[h2e[:, k]]
            np.negative(sk, out=sk, where=~fwd[k])
            s.append(sk)
        G = self.gradients()
        out = np.empty((n, 3))
        w = np.empty(m)
        tmp = np.empty(m)
        for d in range(3):
            acc = None
            for k in range(3):
                # corner k: s_k G_{k+1} - s_{k+2} G_{k+2}
                np.multiply(s[k], G[(k + 1) % 3][d], out=w)
                np.multiply(s[(k + 2) % 3], G[(k + 2) % 3][d], out=tmp)
                w -= tmp
                b = np.bincount(FT[k], weights=w, minlength=n)
                if acc is None:
                    acc = b
                else:
                    acc += b
            np.divide(acc, self.valence, out=out[:, d])
        return out

    def decoder_transpose(self) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
        """``(P D)^T`` as a CSR matrix (see :meth:`decoder_rows`), with the frames; cached."""
        if self._transpose is None:
            data, X1, X2 = self.decoder_rows()
            self._transpose = (_four_per_row(data, self.topo.edges, self.V.shape[0]), X1, X2)
        return self._transpose

    def decoder_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(P D)^T`` in per-vertex tangent frames, four numbers per edge, with the frames.

        Returns ``data`` (e, 4), row ``i`` of ``AT`` (e, 2n), the components
        of ``a_e`` and ``b_e`` (module docstring) along the frames of the
        edge's two endpoints, and the frames ``X1, X2`` (n, 3) of
        :func:`axis_frames`.  Half-edge ``k`` of a face (``F_k -> F_{k+1}``)
        enters corner ``k`` with ``+G_{k+1}`` and corner ``k+1`` with ``-G_k``
        (signed by its orientation against the edge).  Both vectors are
        projected on the frames (divided by the valence) of their corner's
        vertex, face by face; the four numbers of an edge are then the sums
        over its (one or two: the base is manifold) half-edges, read through
        the topology's grouped half-edges in half-edge order.  The rows are
        built directly (no sort).  ``AT.T`` (CSC, no copy) applies ``P D`` to
        coefficients and gives the two frame components of every vertex vector.
        Not cached (:meth:`decoder_transpose` is).
        """
        m = self.F.shape[0]
        topo = self.topo
        E = topo.edges
        e = E.shape[0]
        X1, X2 = axis_frames(self.normals)
        iv = 1.0 / self.valence
        Y = [np.ascontiguousarray(X[:, d]) * iv for X in (X1, X2) for d in range(3)]
        G = self.gradients()
        if 3 * m >= JIT_MIN_SIZE:
            data = np.zeros((e, 4))
            _decoder_rows(self.FT, topo.half_to_edge, self.gradient_stack(), np.array(Y), data)
            return data, X1, X2
        FT = self.FT
        fwd = self.forward()
        rev = ~fwd
        # W[i, k, f]: part i of half-edge k of face f -- parts 0, 1 at the
        # edge's first vertex a, 2, 3 at its second vertex b.  Corner k (vertex
        # F_k) is the tail of half-edge k, which puts +G_{k+1} there, and the
        # head of half-edge k+2, which puts -G_{k+2} there; a forward half-edge
        # (F_k < F_{k+1}) has a at its tail, a reversed one at its head and
        # enters with the opposite sign.  Entry 3m stays zero.
        W = np.zeros((4, 3 * m + 1))
        Wk = W[:, :3 * m].reshape(4, 3, m)
        y = [np.empty(m) for _ in range(6)]
        acc = np.empty(m)
        tmp = np.empty(m)
        for k in range(3):
            k1, k2 = (k + 1) % 3, (k + 2) % 3
            for i in range(6):
                np.take(Y[i], FT[k], out=y[i])
            for j in range(2):
                _dot_into(G[k1], y[3 * j:3 * j + 3], acc, tmp)     # tail of k
                np.copyto(Wk[j, k], acc, where=fwd[k])
                np.negative(acc, out=Wk[2 + j, k], where=rev[k])
                _dot_into(G[k2], y[3 * j:3 * j + 3], acc, tmp)     # -head of k+2
                np.negative(acc, out=Wk[2 + j, k2], where=fwd[k2])
                np.copyto(Wk[j, k2], acc, where=rev[k2])
        del y, acc, tmp
        # an edge's four numbers: the sum over its one or two half-edges (the
        # base is manifold), in half-edge order; half-edge 3 f + k is W[:, k, f]
        order = topo.grouped_half_edges()
        start = topo.edge_starts()
        h0 = order[start]
        h1 = h0.copy()
        two = topo.face_count == 2
        h1[two] = order[start[two] + 1]
        rem = np.empty(e, dtype=np.int64)
        for h in (h0, h1):                  # 3 f + k -> k m + f, in place
            np.remainder(h, 3, out=rem)
            h //= 3
            rem *= m
            h += rem
        h1[~two] = 3 * m
        del rem
        data = np.empty((e, 4))
        b0, b1 = np.empty(e), np.empty(e)
        for i in range(4):
            np.take(W[i], h0, out=b0)
            np.take(W[i], h1, out=b1)
            np.add(b0, b1, out=data[:, i])
        del b0, b1
        del W
        return data, X1, X2

    def tangent(self, X: np.ndarray) -> np.ndarray:
        """``X`` minus its component along the base normals."""
        nrm = self.normals
        return X - dot(X, nrm)[:, None] * nrm


def _four_per_row(data: np.ndarray, E: np.ndarray, n: int) -> sp.csr_matrix:
    """The ``(e, 2n)`` CSR matrix with row ``i`` holding ``data[i]`` at the frame
    columns ``2a, 2a+1, 2b, 2b+1`` of edge ``(a, b) = E[i]``."""
    e = E.shape[0]
    index = np.int32 if 2 * n < 2 ** 31 else np.int64
    cols = np.empty((e, 4), dtype=index)
    cols[:, 0] = E[:, 0]
    cols[:, 0] *= 2
    cols[:, 1] = cols[:, 0] + 1
    cols[:, 2] = E[:, 1]
    cols[:, 2] *= 2
    cols[:, 3] = cols[:, 2] + 1
    return sp.csr_matrix((data.reshape(-1), cols.reshape(-1),
                          np.arange(0, 4 * e + 1, 4, dtype=index)), shape=(e, 2 * n))


@compiled
def _face_geometry(FT, V, rows, flat):
    """:class:`BaseGeometry`'s face arrays in one pass (the same products, bit for
    bit): ``rows`` (13, m) gets ``e_0``, ``e_1``, ``e_2`` (``e_k = p_{k+2} -
    p_{k+1}``, three rows each), ``N = e_1 x e_2`` (three rows) and ``|N|^2``;
    ``flat`` whether ``|N| <= 1e-12`` times the longest edge squared (or NaN)."""
    for f in range(FT.shape[1]):
        i, j, k = FT[0, f], FT[1, f], FT[2, f]
        lmax2 = 0.0
        for d in range(3):
            rows[d, f] = V[k, d] - V[j, d]
            rows[3 + d, f] = V[i, d] - V[k, d]
            rows[6 + d, f] = V[j, d] - V[i, d]
        a0, a1, a2 = rows[3, f], rows[4, f], rows[5, f]
        b0, b1, b2 = rows[6, f], rows[7, f], rows[8, f]
        n0 = a1 * b2 - a2 * b1
        n1 = a2 * b0 - a0 * b2
        n2 = a0 * b1 - a1 * b0
        rows[9, f], rows[10, f], rows[11, f] = n0, n1, n2
        nn = n0 * n0 + n1 * n1 + n2 * n2
        rows[12, f] = nn
        for q in range(3):
            x, y, z = rows[3 * q, f], rows[3 * q + 1, f], rows[3 * q + 2, f]
            l2 = x * x + y * y + z * z
            if q == 0 or not (lmax2 >= l2):              # np.maximum: NaN wins
                lmax2 = l2
        flat[f] = not (np.sqrt(nn) > lmax2 * 1e-12)


@compiled
def _unit_normal_sums(FT, n0, n1, n2, N2, acc):
    """:meth:`BaseGeometry.unit_sum_normals` face by face (``acc`` (n, 3) zeroed;
    a zero-area face adds NaN, as the numpy path's ``0 / 0``)."""
    for f in range(FT.shape[1]):
        inv = 1.0 / np.sqrt(N2[f])
        u0, u1, u2 = n0[f] * inv, n1[f] * inv, n2[f] * inv
        for k in range(3):
            v = FT[k, f]
            acc[v, 0] += u0
            acc[v, 1] += u1
            acc[v, 2] += u2


@compiled
def _face_gradients(N, N2, E, G):
    """:meth:`BaseGeometry.gradients` in one pass (the same products, bit for bit):
    ``G[k, :, f] = N x e_k / |N|^2`` from ``N`` (3, m) and ``E`` (3, 3, m) =
    ``[k, axis, face]``."""
    for f in range(N2.shape[0]):
        inv = 1.0 / N2[f]
        m0, m1, m2 = N[0, f], N[1, f], N[2, f]
        for k in range(3):
            x0, x1, x2 = E[k, 0, f], E[k, 1, f], E[k, 2, f]
            G[k, 0, f] = (m1 * x2 - m2 * x1) * inv
            G[k, 1, f] = (m2 * x0 - m0 * x2) * inv
            G[k, 2, f] = (m0 * x1 - m1 * x0) * inv


@compiled
def _decode_loops(FT, half_to_edge, c, G, valence, out):
    """:meth:`BaseGeometry.decode` face by face (``out`` (n, 3) zeroed; ``G`` the
    (3, 3, m) gradients): corner ``k`` adds ``s_k G_{k+1} - s_{k+2} G_{k+2}``
    to its vertex, ``s_k`` the coefficient of half-edge ``k`` signed by its
    direction; then the mean."""
    m = FT.shape[1]
    s = np.empty(3)
    for f in range(m):
        for k in range(3):
            sk = c[half_to_edge[3 * f + k]]
            # a half-edge against its edge's direction
            s[k] = sk if FT[k, f] < FT[(k + 1) % 3, f] else -sk
        for k in range(3):
            k1, k2 = (k + 1) % 3, (k + 2) % 3
            v = FT[k, f]
            for d in range(3):
                out[v, d] += s[k] * G[k1, d, f] - s[k2] * G[k2, d, f]
    for v in range(out.shape[0]):
        for d in range(3):
            out[v, d] /= valence[v]


@compiled
def _decoder_rows(FT, half_to_edge, G, Y, data):
    """:meth:`BaseGeometry.decoder_transpose`'s four numbers per edge, face by face.

    The same products and sums as the numpy path (bit for bit): half-edge
    ``k`` of face ``f`` adds ``G_{k+1} . Y(F_k)`` at its tail and
    ``-G_k . Y(F_{k+1})`` at its head (``G`` (3, 3, m), ``Y`` (6, n): the two
    frames over the valence), to the parts of the edge's first or second
    vertex by its direction; ``data`` (e, 4) starts at zero and the half-edges
    of an edge arrive in ascending order, as the numpy path sums them.
    """
    m = FT.shape[1]
    for f in range(m):
        for k in range(3):
            k1 = (k + 1) % 3
            tail = FT[k, f]
            head = FT[k1, f]
            row = half_to_edge[3 * f + k]
            # + G_{k+1} . Y(tail) and -(G_k . Y(head)), both frames j = 0, 1
            t0 = G[k1, 0, f] * Y[0, tail]
            t0 += G[k1, 1, f] * Y[1, tail]
            t0 += G[k1, 2, f] * Y[2, tail]
            t1 = G[k1, 0, f] * Y[3, tail]
            t1 += G[k1, 1, f] * Y[4, tail]
            t1 += G[k1, 2, f] * Y[5, tail]
            h0 = G[k, 0, f] * Y[0, head]
            h0 += G[k, 1, f] * Y[1, head]
            h0 += G[k, 2, f] * Y[2, head]
            h1 = G[k, 0, f] * Y[3, head]
            h1 += G[k, 1, f] * Y[4, head]
            h1 += G[k, 2, f] * Y[5, head]
            if tail < head:              # tail is the edge's first vertex
                data[row, 0] += t0
                data[row, 1] += t1
                data[row, 2] += -h0
                data[row, 3] += -h1
            else:
                data[row, 0] += h0
                data[row, 1] += h1
                data[row, 2] += -t0
                data[row, 3] += -t1


def _dot_into(g, y, out: np.ndarray, tmp: np.ndarray) -> None:
    """``out = g . y`` for two vectors given as three coordinate columns."""
    np.multiply(g[0], y[0], out=out)
    np.multiply(g[1], y[1], out=tmp)
    out += tmp
    np.multiply(g[2], y[2], out=tmp)
    out += tmp


def _norm2(v, tmp: np.ndarray | None = None) -> np.ndarray:
    """``|v|^2`` of a vector given as three coordinate columns (``tmp``: scratch)."""
    out = v[0] * v[0]
    if tmp is None:
        tmp = np.empty_like(out)
    out += np.multiply(v[1], v[1], out=tmp)
    out += np.multiply(v[2], v[2], out=tmp)
    return out


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
    :meth:`BaseGeometry.decoder_transpose` (four entries per edge), written as
    plain CG on the diagonally rescaled system (the same iterates, one pass
    over the edges less per iteration)
    (at most ``LSQ_ITERATIONS``, stopping at relative residual ``LSQ_RTOL``),
    then ``LSQ_ROUNDS`` active-set rounds: coefficients past their bound are
    fixed at it and the free ones re-fitted (``LSQ_ROUND_ITERATIONS`` each);
    the result is clipped so the bound holds exactly.  A truncated solve: the
    iteration counts are fixed, so the cost is a few dozen passes over the
    edges whatever the mesh size.  From :data:`geotex.jit.JIT_MIN_SIZE` edges
    up the iterations run as compiled loops (:func:`_lsq_fit_compiled`).

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
    c0, lim = edge_encode_and_lengths(g.V, E, t)
    if E.shape[0] == 0:
        return c0
    compiled_fit = E.shape[0] >= JIT_MIN_SIZE
    if compiled_fit:
        data, X1, X2 = g.decoder_rows()          # a fresh array: rescaled in place below
    else:
        AT, X1, X2 = g.decoder_transpose()
        data = AT.data.reshape(-1, 4)
    diag = np.einsum("ij,ij->i", data, data)
    reg = LSQ_DAMPING * diag
    Kd = diag + reg
    Kd[Kd <= 0] = 1.0
    # Jacobi preconditioning as a change of variables: with S = Kd^(-1/2) and
    # c = c0 + S x, plain CG on S K S x = S rhs makes the same iterates as
    # Jacobi-preconditioned CG on K d = rhs, with one pass less per iteration
    # (no division by Kd) and the damping a scalar where every diag > 0
    sq = np.sqrt(Kd)
    scale = 1.0 / sq
    t2 = np.empty((t.shape[0], 2))
    t2[:, 0] = dot(t, X1)
    t2[:, 1] = dot(t, X2)
    if compiled_fit:
        x = _lsq_fit_compiled(data, E, t.shape[0], c0, lim, t2.ravel(), sq, scale, reg, Kd,
                              bool((diag > 0).all()))
        c = c0 + scale * x
        return np.clip(c, -lim, lim, out=c)
    ATs = sp.csr_matrix((np.multiply(data, scale[:, None]).reshape(-1), AT.indices, AT.indptr),
                        shape=AT.shape)
    As = ATs.T
    if (diag > 0).all():
        mu = LSQ_DAMPING / (1.0 + LSQ_DAMPING)

        def K(x):
            y = ATs @ (As @ x)
            blas.daxpy(x, y, a=mu)
            return y
    else:
        mu_v = reg / Kd

        def K(x):
            y = ATs @ (As @ x)
            y += mu_v * x
            return y

    rhs = ATs @ (t2.ravel() - As @ (sq * c0))
    lo, hi = (-lim - c0) * sq, (lim - c0) * sq
    with single_threaded_blas():
        x = _cg(K, rhs, None, None, LSQ_ITERATIONS, LSQ_RTOL, Kd)
        free = np.ones(c0.shape, dtype=bool)
        for _ in range(LSQ_ROUNDS):
            out = free & ((x > hi) | (x < lo))
            if not out.any():
                break
            np.clip(x, lo, hi, out=x)
            free &= ~out
            x = _cg(K, rhs, x, free, LSQ_ROUND_ITERATIONS, 0.0, Kd)
    c = c0 + scale * x
    return np.clip(c, -lim, lim, out=c)


def _cg(K, rhs, x, free, iterations, rtol, weight):
    """CG on ``K x = rhs`` over the ``free`` unknowns (all when None).

    ``x`` is the start (updated in place), None for zero.  Stops early when
    ``sum(weight r^2) <= rtol^2 sum(weight rhs^2)`` (the residual of the
    unscaled system when ``K`` is Jacobi-scaled by ``weight^(-1/2)``).  In-place
    BLAS updates (call with BLAS limited to one thread: deterministic sums).
    """
    mask = None if free is None else free.astype(np.float64)
    if x is None:
        x = np.zeros_like(rhs)
        r = rhs.copy()
    else:
        r = rhs - K(x)
    if mask is not None:
        r *= mask
    p = r.copy()
    rr = blas.ddot(r, r)
    stop = rtol * rtol * float(np.einsum("i,i,i->", rhs, rhs, weight))
    for _ in range(iterations):
        if rr <= 0.0 or (rtol > 0.0 and float(np.einsum("i,i,i->", r, r, weight)) <= stop):
            break
        Kp = K(p)
        if mask is not None:
            Kp *= mask
        alpha = rr / blas.ddot(p, Kp)
        blas.daxpy(p, x, a=alpha)
        blas.daxpy(Kp, r, a=-alpha)
        rr_new = blas.ddot(r, r)
        blas.dscal(rr_new / rr, p)
        blas.daxpy(r, p)
        rr = rr_new
    return x


def _lsq_fit_compiled(data, E, n, c0, lim, t2, sq, scale, reg, Kd, all_positive):
    """The fit of :func:`lsq_encode` with compiled loops (large meshes; ``data``,
    the decoder rows, is rescaled in place): the same
    damped, Jacobi-scaled normal equations, unconstrained CG and active-set
    rounds, with the operator applied from the four numbers per edge (no
    sparse matrix; the step's vector updates and dot products folded into the
    passes over the edges).  Equal to the numpy path to round-off (sums in a
    different order); returns the scaled unknowns ``x`` (e,).  (Reading the
    operator in single precision would save a sixth of the time but makes the
    truncated iterates depend on the rounding of a rotated copy of the mesh at
    1e-6: the stored 1-form would no longer be rigid-motion invariant to 1e-9.)"""
    e = E.shape[0]
    index = np.int32 if 2 * n < 2 ** 31 else np.int64
    E2 = np.ascontiguousarray(E, dtype=index)
    D = data
    D *= scale[:, None]                          # the caller's fresh rows, rescaled in place
    mu = LSQ_DAMPING / (1.0 + LSQ_DAMPING)
    mu_v = np.empty(0) if all_positive else reg / Kd
    z = np.empty(2 * n)
    rhs = np.empty(e)
    _scaled_rhs(D, E2, sq * c0, t2, z, rhs)
    lo, hi = (-lim - c0) * sq, (lim - c0) * sq
    x = np.zeros(e)
    r, p, Kp = np.empty(e), np.empty(e), np.empty(e)
    none = np.empty(0)
    _cg_loops(D, E2, mu, mu_v, rhs, x, none, False, LSQ_ITERATIONS, LSQ_RTOL, Kd, r, p, Kp, z)
    free = np.ones(e, dtype=bool)
    for _ in range(LSQ_ROUNDS):
        out = free & ((x > hi) | (x < lo))
        if not out.any():
            break
        np.clip(x, lo, hi, out=x)
        free &= ~out
        _cg_loops(D, E2, mu, mu_v, rhs, x, free.astype(np.float64), True,
                  LSQ_ROUND_ITERATIONS, 0.0, Kd, r, p, Kp, z)
    return x


@compiled
def _scaled_rhs(D, E, w, t2, z, rhs):
    """``rhs = A^T (t2 - A w)`` for the four-per-row ``A^T`` of ``D`` on ``E``."""
    z[:] = t2
    for i in range(D.shape[0]):
        a = 2 * E[i, 0]
        b = 2 * E[i, 1]
        wi = w[i]
        z[a] -= D[i, 0] * wi
        z[a + 1] -= D[i, 1] * wi
        z[b] -= D[i, 2] * wi
        z[b + 1] -= D[i, 3] * wi
    for i in range(D.shape[0]):
        a = 2 * E[i, 0]
        b = 2 * E[i, 1]
        rhs[i] = D[i, 0] * z[a] + D[i, 1] * z[a + 1] + D[i, 2] * z[b] + D[i, 3] * z[b + 1]


@compiled
def _cg_loops(D, E, mu, mu_v, rhs, x, mask, start, iterations, rtol, weight, r, p, Kp, z):
    """CG on ``(A^T A + mu) x = rhs`` over the unknowns where ``mask`` is 1 (all
    when ``mask`` is empty), from ``x`` (used when ``start``, else taken as
    zero; updated in place).  ``mu_v`` (e,) replaces the scalar ``mu`` when not
    empty.  Stops early when ``sum(weight r^2) <= rtol^2 sum(weight rhs^2)``
    (``rtol > 0``).  ``r``, ``p``, ``Kp`` (e,) and ``z`` (2n,): scratch."""
    e = D.shape[0]
    masked = mask.shape[0] > 0
    per_edge = mu_v.shape[0] > 0

    def product(v, out, z, beta):
        # v = r + beta v first where beta >= 0; then out = (A^T A + mu) v,
        # masked; returns v . out
        z[:] = 0.0
        for i in range(e):
            a = 2 * E[i, 0]
            b = 2 * E[i, 1]
            if beta >= 0.0:
                v[i] = r[i] + beta * v[i]
            vi = v[i]
            z[a] += D[i, 0] * vi
            z[a + 1] += D[i, 1] * vi
            z[b] += D[i, 2] * vi
            z[b + 1] += D[i, 3] * vi
        vkv = 0.0
        for i in range(e):
            a = 2 * E[i, 0]
            b = 2 * E[i, 1]
            y = D[i, 0] * z[a] + D[i, 1] * z[a + 1] + D[i, 2] * z[b] + D[i, 3] * z[b + 1]
            y += (mu_v[i] if per_edge else mu) * v[i]
            if masked:
                y *= mask[i]
            out[i] = y
            vkv += v[i] * y
        return vkv

    if start:
        product(x, Kp, z, -1.0)
        for i in range(e):
            r[i] = rhs[i] - Kp[i]
    else:
        x[:] = 0.0
        r[:] = rhs
    if masked:
        for i in range(e):
            r[i] *= mask[i]
    rr = 0.0
    wrr = 0.0
    stop = 0.0
    for i in range(e):
        p[i] = r[i]
        rr += r[i] * r[i]
    if rtol > 0.0:
        for i in range(e):
            wrr += weight[i] * r[i] * r[i]
            stop += weight[i] * rhs[i] * rhs[i]
        stop *= rtol * rtol
    beta = -1.0                  # p = r + beta p is folded into the next product
    for _ in range(iterations):
        if rr <= 0.0 or (rtol > 0.0 and wrr <= stop):
            break
        alpha = rr / product(p, Kp, z, beta)
        rr_new = 0.0
        wrr = 0.0
        for i in range(e):
            x[i] += alpha * p[i]
            ri = r[i] - alpha * Kp[i]
            r[i] = ri
            rr_new += ri * ri
            if rtol > 0.0:
                wrr += weight[i] * ri * ri
        beta = rr_new / rr
        rr = rr_new
