"""Embedding of a labelled mesh onto its polycube: the deformed positions ``P``.

A vertex touched by charts of ``k`` different axes has ``k`` coordinates fixed
to those charts' planes: corners (three axes) are fully fixed, vertices on a
polycube edge (two axes) keep one free coordinate, chart-interior vertices
two.  The free coordinate of polycube-edge vertices is interpolated by arc
length between the corners (a 1D harmonic solve along the border edges with
weights ``1 / length``); chart interiors are then a harmonic map in the chart
plane with the border fixed (positive cotangent weights, or uniform Tutte
weights as the fallback).  Each axis is one sparse solve.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from geotex.errors import GeotexError
from geotex.param.polycube_labels import LABEL_DIRECTIONS

__all__ = ["embed_polycube", "folded_faces", "interior_weights"]


def interior_weights(V: np.ndarray, F: np.ndarray, *, uniform: bool) -> sp.csr_matrix:
    """Symmetric positive edge weights ``(n, n)``: clamped cotangents or ones."""
    n = V.shape[0]
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])
    if uniform:
        w = np.ones(i.size)
    else:
        w = np.zeros(i.size)
        m = F.shape[0]
        for k in range(3):  # angle at corner k is opposite edge (k+1, k+2)
            a, b, c = V[F[:, k]], V[F[:, (k + 1) % 3]], V[F[:, (k + 2) % 3]]
            u, v = b - a, c - a
            cot = np.einsum("ij,ij->i", u, v) / np.maximum(
                np.linalg.norm(np.cross(u, v), axis=1), 1e-300)
            w[((k + 1) % 3) * m:((k + 1) % 3 + 1) * m] = 0.5 * cot
        w = np.clip(w, 0.0, None)
    W = sp.coo_matrix((w, (i, j)), shape=(n, n)).tocsr()
    W = W + W.T
    if not uniform:
        # keep every edge with a small positive weight (Tutte-style positivity)
        ones = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n)).tocsr()
        ones = ((ones + ones.T) > 0).astype(np.float64)
        floor = 1e-3 * float(W.data.mean()) if W.nnz else 1.0
        W = W + floor * ones
    return W.tocsr()


def _dirichlet(W: sp.csr_matrix, unknown: np.ndarray, known_values: np.ndarray,
               known_mask: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
    """Solve ``L (x - reference) = 0`` on ``unknown`` rows, ``x = known_values`` elsewhere."""
    Wu = W[unknown]
    deg = np.asarray(Wu.sum(axis=1)).ravel()
    Wuu = Wu[:, unknown]
    Wuk = Wu[:, np.flatnonzero(known_mask)]
    rhs = Wuk @ known_values[known_mask]
    if reference is not None:
        rhs = rhs + deg * reference[unknown] - Wu @ reference
    L = (sp.diags(deg) - Wuu).tocsc()
    return splu(L).solve(rhs)


def embed_polycube(V: np.ndarray, F: np.ndarray, edges: np.ndarray, vertex_chart: np.ndarray,
                   planes: np.ndarray, *, uniform: bool, reference: np.ndarray | None = None,
                   extra: np.ndarray | None = None) -> np.ndarray:
    """Polycube positions in tile units, ``(n, 3)`` float64.

    Parameters
    ----------
    edges : (e, 2) int64
        Unique edges of ``F``.  An edge whose two ends have the same two
        coordinates fixed lies on a polycube edge and takes part in the
        arc-length interpolation.
    vertex_chart : (n, 3) int64
        Chart of each axis touching each vertex, ``-1`` if none (see
        :class:`~geotex.param.polycube_layout.ChartLayout`).
    planes : (n_charts,) int64
        Plane of every chart, in tiles.
    uniform : bool
        Uniform (Tutte) weights for chart interiors instead of clamped cotangents.
    reference : (n, 3) float64, optional
        When given (tile units), chart interiors keep its shape: the
        *displacement* from ``reference`` is harmonic instead of the positions.
    extra : (n, 3) float64, optional
        Additional fixed coordinates (tile units, NaN where free), e.g. the
        reflex-corner cuts of :mod:`~geotex.param.polycube_cuts`.

    Raises
    ------
    GeotexError
        When a closed polycube edge has no corner (it cannot be a straight
        segment) or a solve fails.
    """
    n = V.shape[0]
    fixed = vertex_chart >= 0
    P = np.zeros((n, 3))
    P[fixed] = planes[vertex_chart[fixed]].astype(np.float64)
    if extra is not None:
        more = ~np.isnan(extra) & ~fixed
        P[more] = extra[more]
        fixed = fixed | more
    n_axes = fixed.sum(axis=1)
    corner = n_axes == 3
    e = edges
    length = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    length = np.maximum(length, 1e-300)
    # a polycube-edge (line) edge: both ends have the other two coordinates fixed, equal
    both = fixed[e[:, 0]] & fixed[e[:, 1]] & (P[e[:, 0]] == P[e[:, 1]])
    for k in range(3):
        on = (n_axes == 2) & ~fixed[:, k]
        if not on.any():
            continue
        sel = both[:, (k + 1) % 3] & both[:, (k + 2) % 3]
        ek = e[sel]
        W = sp.coo_matrix((1.0 / length[sel], (ek[:, 0], ek[:, 1])), shape=(n, n)).tocsr()
        W = (W + W.T).tocsr()
        unknown = np.flatnonzero(on)
        known = corner.copy()
        deg = np.asarray(W[unknown].sum(axis=1)).ravel()
        if (deg == 0).any():
            raise GeotexError("a polycube edge vertex has no polycube-edge neighbours "
                              "(invalid chart border)")
        _check_reach(W, unknown, known)
        P[unknown, k] = _dirichlet(W, unknown, P[:, k], known)
    Wi = interior_weights(V, F, uniform=uniform)
    for k in range(3):
        unknown = np.flatnonzero((n_axes == 1) & ~fixed[:, k])
        if unknown.size == 0:
            continue
        known = np.ones(n, bool)
        known[unknown] = False
        ref = None if reference is None else reference[:, k]
        P[unknown, k] = _dirichlet(Wi, unknown, P[:, k], known, ref)
    return P


def _check_reach(W: sp.csr_matrix, unknown: np.ndarray, known: np.ndarray) -> None:
    from scipy.sparse.csgraph import connected_components

    sub = np.flatnonzero(known)
    idx = np.concatenate([unknown, sub])
    G = W[idx][:, idx]
    _, comp = connected_components(G, directed=False)
    reach = np.zeros(comp.max() + 1, bool)
    reach[comp[unknown.size:]] = True
    if not reach[comp[:unknown.size]].all():
        raise GeotexError("a closed polycube edge has no corner: two charts meet along a "
                          "loop, which cannot be a straight polycube edge")


def folded_faces(P: np.ndarray, F: np.ndarray, face_label: np.ndarray, *,
                 rel_tol: float = 1e-9) -> np.ndarray:
    """Faces of ``P`` not strictly positive in their chart plane, ``(k,)`` int64.

    Each face's doubled area, measured along its label's outward direction,
    must exceed ``rel_tol`` (``P`` is in tile units) and the face must be flat
    in its plane (checked by the caller through the fixed coordinates).
    """
    a = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    s = np.einsum("ij,ij->i", a, LABEL_DIRECTIONS[face_label])
    return np.flatnonzero(~(s > rel_tol))


def _kernel_polygon(gx, gy, c0, A, B):
    """Kernel ``{v : c0 + g.v >= 0}`` of a ring, as polygon vertices ``(k, 2)`` or None.

    Clips the ring's bounding box (enlarged) by each half-plane in turn
    (Sutherland-Hodgman); returns None when the kernel is empty.
    """
    pts = np.vstack([A, B])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = float((hi - lo).max()) + 1e-9
    poly = np.array([[lo[0] - pad, lo[1] - pad], [hi[0] + pad, lo[1] - pad],
                     [hi[0] + pad, hi[1] + pad], [lo[0] - pad, hi[1] + pad]])
    for a, b, c in zip(gx, gy, c0):
        val = c + a * poly[:, 0] + b * poly[:, 1]
        inside = val >= 0
        if inside.all():
            continue
        if not inside.any():
            return None
        nxt = np.roll(np.arange(len(poly)), -1)
        out = []
        for i in range(len(poly)):
            j = nxt[i]
            if inside[i]:
                out.append(poly[i])
            if inside[i] != inside[j]:
                t = val[i] / (val[i] - val[j])
                out.append(poly[i] + t * (poly[j] - poly[i]))
        poly = np.asarray(out)
        if len(poly) < 3:
            return None
    return poly


def untangle(P: np.ndarray, F: np.ndarray, face_label: np.ndarray, movable: np.ndarray, *,
             sweeps: int = 30, rel_tol: float = 1e-9, grow: int = 0) -> np.ndarray:
    """Move chart-interior vertices of folded faces into the kernel of their ring.

    Each sweep visits the movable vertices of the folded faces and places each
    at the vertex average of the kernel of its one-ring polygon in the chart
    plane (half-plane clipping, with a small margin), which makes all its
    triangles positive whenever the kernel is not empty.  Folds left after
    ``sweeps`` sweeps are reported by the caller.

    Returns
    -------
    (n, 3) float64
        A new array; only movable vertices change.
    """
    from geotex.param.polycube_quads import chart_axes

    P = P.copy()
    m = F.shape[0]
    vf = sp.csr_matrix((np.ones(3 * m), (F.ravel(), np.repeat(np.arange(m), 3))),
                       shape=(P.shape[0], m))
    _, a1, a2 = chart_axes(face_label)
    best, stall = None, 0
    for _ in range(sweeps):
        bad = folded_faces(P, F, face_label, rel_tol=rel_tol)
        if bad.size == 0:
            break
        if best is not None and bad.size >= best:
            stall += 1
            if stall >= 3:
                break
        else:
            best, stall = bad.size, 0
        verts = np.unique(F[bad].ravel())
        for _ in range(grow):  # also relax the rings around the folds
            verts = np.unique(F[np.unique(vf[verts].indices)].ravel())
        verts = verts[movable[verts]]
        if verts.size == 0:
            break
        for v in verts:
            faces = vf.indices[vf.indptr[v]:vf.indptr[v + 1]]
            ax1, ax2 = a1[faces[0]], a2[faces[0]]
            if not ((a1[faces] == ax1).all() and (a2[faces] == ax2).all()):
                continue
            k = np.argmax(F[faces] == v, axis=1)
            A = P[F[faces, (k + 1) % 3]][:, [ax1, ax2]]
            B = P[F[faces, (k + 2) % 3]][:, [ax1, ax2]]
            c0 = A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0]
            gx, gy = A[:, 1] - B[:, 1], B[:, 0] - A[:, 0]
            gn = np.hypot(gx, gy)
            # kernel of the ring: half-planes c0 + g.v >= margin |g|, clipped polygon
            margin = 1e-3 * float(np.min(gn[gn > 0])) if (gn > 0).any() else 0.0
            poly = _kernel_polygon(gx, gy, c0 - margin * gn, A, B)
            if poly is not None:
                P[v, ax1], P[v, ax2] = poly.mean(axis=0)
    return P
