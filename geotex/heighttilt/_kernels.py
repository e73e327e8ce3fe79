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
"""

from __future__ import annotations

import numpy as np

from geotex.mesh.topology import EdgeTopology, edge_topology

__all__ = ["cross", "dot", "edge_encode", "lowest_neighbours",
           "BaseGeometry"]


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


def lowest_neighbours(E: np.ndarray, n: int) -> np.ndarray:
    """Lowest-index neighbour of every vertex (``-1`` for isolated vertices).

    ``E`` are the sorted unique edges ``(i, j)``, ``i < j``: neighbours below a
    vertex ``v`` appear as ``(i, v)`` and are all lower than those above it,
    which appear as ``(v, j)``; the first ``(v, j)`` in the sorted order has the
    smallest ``j``.
    """
    below = np.full(n, n, dtype=np.int64)
    np.minimum.at(below, E[:, 1], E[:, 0])
    out = np.full(n, -1, dtype=np.int64)
    if E.shape[0]:
        start = np.flatnonzero(np.r_[True, E[1:, 0] != E[:-1, 0]])
        out[E[start, 0]] = E[start, 1]
    has_below = below < n
    out[has_below] = below[has_below]
    return out


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
        self._frames = None

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

    def tangent(self, X: np.ndarray) -> np.ndarray:
        """``X`` minus its component along the base normals."""
        nrm = self.normals
        return X - dot(X, nrm)[:, None] * nrm


def _norm2(v) -> np.ndarray:
    return v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
