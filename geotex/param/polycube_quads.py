"""Grid quads of a polycube and point location of quad points in the deformed mesh.

Quad frame convention
---------------------
A chart with label axis ``a`` and sign ``s`` has the in-plane axes
``(a1, a2) = ((a+1)%3, (a+2)%3)`` when ``s = +1`` and ``((a+2)%3, (a+1)%3)``
when ``s = -1``; ``e1 = +unit(a1)``, ``e2 = +unit(a2)`` and ``e1 x e2`` is the
chart's outward normal (a right-handed frame).  A quad is the grid cell
``[i, i+1] x [j, j+1]`` of the chart plane in ``(a1, a2)`` tile coordinates;
its corners, counter-clockwise around the outward normal, are
``c0 = (i, j)``, ``c1 = (i+1, j)``, ``c2 = (i+1, j+1)``, ``c3 = (i, j+1)``
and the tile point ``(u, v)`` lies at ``(i + u, j + v)``.  Quad edge ``k``
runs from ``c_k`` to ``c_(k+1)%4``: ``0`` south (``v = 0``, along ``+e1``),
``1`` east (``u = 1``, along ``+e2``), ``2`` north (``v = 1``, along ``-e1``),
``3`` west (``u = 0``, along ``-e2``).  Two quads sharing an edge traverse it
in opposite directions (the surface is closed and oriented).

Because ``e1`` and ``e2`` always point along *increasing* coordinates, the
tile coordinate along any side (``u`` on south/north, ``v`` on east/west)
grows with the global coordinate of the edge's axis: two quads sharing a
global edge see the same point at the same ``t``, whichever sides (and charts,
across a polycube edge) they use.  Colour matching therefore never needs to
reverse a side.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import GeotexError

__all__ = ["chart_axes", "face_coords_2d", "enumerate_quads", "quad_edges", "QuadLocator"]


def chart_axes(label: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normal axis, first and second in-plane axes of labels, each ``(k,)`` int64."""
    label = np.asarray(label, np.int64)
    a = label // 2
    pos = label % 2 == 0
    a1 = np.where(pos, (a + 1) % 3, (a + 2) % 3)
    a2 = np.where(pos, (a + 2) % 3, (a + 1) % 3)
    return a, a1, a2


def face_coords_2d(P: np.ndarray, F: np.ndarray, face_label: np.ndarray) -> np.ndarray:
    """Corner coordinates of every face in its chart's ``(a1, a2)`` axes, ``(m, 3, 2)``."""
    _, a1, a2 = chart_axes(face_label)
    X = P[F]  # (m, 3, 3)
    rows = np.arange(F.shape[0])[:, None]
    return np.stack([X[rows, np.arange(3)[None, :], a1[:, None]],
                     X[rows, np.arange(3)[None, :], a2[:, None]]], axis=-1)


def _bary_setup(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Origins ``(m, 2)`` and inverse edge matrices ``(m, 2, 2)`` of 2D triangles."""
    o = T[:, 0]
    M = np.stack([T[:, 1] - o, T[:, 2] - o], axis=2)  # columns = edges
    det = M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]
    det = np.where(det == 0, np.inf, det)
    inv = np.empty_like(M)
    inv[:, 0, 0] = M[:, 1, 1] / det
    inv[:, 1, 1] = M[:, 0, 0] / det
    inv[:, 0, 1] = -M[:, 0, 1] / det
    inv[:, 1, 0] = -M[:, 1, 0] / det
    return o, inv


def _bary(o, inv, f, p):
    d = p - o[f]
    b1 = inv[f, 0, 0] * d[..., 0] + inv[f, 0, 1] * d[..., 1]
    b2 = inv[f, 1, 0] * d[..., 0] + inv[f, 1, 1] * d[..., 1]
    return np.stack([1.0 - b1 - b2, b1, b2], axis=-1)


def _cell_pairs(T: np.ndarray, res: int, charts: np.ndarray):
    """Every (face, cell) pair whose cell (size ``1/res``) meets the face's box."""
    lo = np.floor(T.min(axis=1) * res).astype(np.int64)
    hi = np.ceil(T.max(axis=1) * res).astype(np.int64) - 1
    hi = np.maximum(hi, lo)
    nx = hi[:, 0] - lo[:, 0] + 1
    ny = hi[:, 1] - lo[:, 1] + 1
    cnt = nx * ny
    f = np.repeat(np.arange(T.shape[0]), cnt)
    start = np.cumsum(cnt) - cnt
    r = np.arange(cnt.sum()) - np.repeat(start, cnt)
    cx = lo[f, 0] + r % nx[f]
    cy = lo[f, 1] + r // nx[f]
    return f, charts[f], cx, cy


def enumerate_quads(P: np.ndarray, F: np.ndarray, face_label: np.ndarray,
                    face_chart: np.ndarray, chart_label: np.ndarray, planes: np.ndarray):
    """Grid cells covered by every chart.

    Returns
    -------
    quad_chart : (q,) int64
    quad_ij : (q, 2) int64
        Lower cell corner in the chart's ``(a1, a2)`` tile coordinates.
    quad_corners : (q, 4, 3) int64
        Corners ``c0..c3`` in tile units (polycube point = corner * tile_size).
    """
    T = face_coords_2d(P, F, face_label)
    o, inv = _bary_setup(T)
    f, c, cx, cy = _cell_pairs(T, 1, face_chart)
    p = np.stack([cx + 0.5, cy + 0.5], axis=1)
    b = _bary(o, inv, f, p)
    inside = (b >= -1e-12).all(axis=1)
    key = np.unique(np.stack([c[inside], cx[inside], cy[inside]], 1), axis=0)
    quad_chart = key[:, 0]
    ij = key[:, 1:]
    a, a1, a2 = chart_axes(chart_label[quad_chart])
    q = quad_chart.size
    corners = np.zeros((q, 4, 3), np.int64)
    du = np.array([0, 1, 1, 0])
    dv = np.array([0, 0, 1, 1])
    rows = np.arange(q)[:, None]
    corners[rows, np.arange(4)[None], a[:, None]] = planes[quad_chart][:, None]
    corners[rows, np.arange(4)[None], a1[:, None]] = ij[:, :1] + du[None]
    corners[rows, np.arange(4)[None], a2[:, None]] = ij[:, 1:] + dv[None]
    return quad_chart, ij, corners


def quad_edges(corners: np.ndarray):
    """Global edges of the quads.

    Returns
    -------
    quad_edge : (q, 4) int64
        Global id of quad edge ``k`` (from corner ``k`` to ``(k+1)%4``).
    quad_edge_forward : (q, 4) bool
        True when the quad traverses the edge toward increasing coordinate.
    edge_axis : (E,) int64
        Axis class (0 X, 1 Y, 2 Z) of every global edge.
    edge_quads : (E, 2) int64
        The two quads of every edge (lower quad index first).
    edge_sides : (E, 2) int64
        Local edge index (0..3) of the edge in each of those quads.

    Raises
    ------
    GeotexError
        If a grid edge is not shared by exactly two quads.
    """
    q = corners.shape[0]
    a = corners
    b = np.roll(corners, -1, axis=1)
    lo = np.minimum(a, b).reshape(-1, 3)
    hi = np.maximum(a, b).reshape(-1, 3)
    key = np.concatenate([lo, hi], axis=1)
    uniq, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if (counts != 2).any():
        raise GeotexError(f"{int((counts != 2).sum())} polycube grid edges are not shared by "
                          "exactly two quads (the polycube surface is not a closed manifold)")
    d = (b - a).reshape(-1, 3)
    axis_of_half = np.argmax(np.abs(d), axis=1)
    forward = d[np.arange(d.shape[0]), axis_of_half] > 0
    E = uniq.shape[0]
    edge_axis = np.zeros(E, np.int64)
    edge_axis[inv] = axis_of_half
    order = np.argsort(inv, kind="stable")
    edge_quads = (order // 4).reshape(E, 2)
    edge_sides = (order % 4).reshape(E, 2)
    return (inv.reshape(q, 4).astype(np.int64), forward.reshape(q, 4), edge_axis,
            edge_quads.astype(np.int64), edge_sides.astype(np.int64))


@dataclass
class QuadLocator:
    """Point location of quad points ``(u, v)`` in the polycube triangles.

    Every quad is split into ``res x res`` sub-cells; ``table[s]`` lists (padded
    with ``-1``) the faces whose bounding box meets sub-cell ``s`` of quad
    ``s // res**2``.  Built by :meth:`build`; queries are vectorized.
    """

    res: int
    table: np.ndarray        # (q * res * res, K) int64
    quad_ij: np.ndarray      # (q, 2) int64
    origin: np.ndarray       # (m, 2)
    inverse: np.ndarray      # (m, 2, 2)

    @classmethod
    def build(cls, P, F, face_label, face_chart, quad_chart, quad_ij) -> "QuadLocator":
        """Index the faces of every chart by the quad sub-cells they overlap."""
        T = face_coords_2d(P, F, face_label)
        o, inv = _bary_setup(T)
        q = quad_chart.size
        f, c, cx, cy = _cell_pairs(T, 1, face_chart)
        per_quad = max(1.0, f.size / max(q, 1))
        res = 1
        while res * res < 2 * per_quad and res < 64:
            res *= 2
        f, c, cx, cy = _cell_pairs(T, res, face_chart)
        # quad of each sub-cell
        span = int(max(np.abs(quad_ij).max(), np.abs(cx // res).max(), np.abs(cy // res).max())) + 2
        W = 2 * span + 1
        key_q = (quad_chart * W + (quad_ij[:, 0] + span)) * W + (quad_ij[:, 1] + span)
        order = np.argsort(key_q)
        key_sorted = key_q[order]
        key_c = (c * W + (cx // res + span)) * W + (cy // res + span)
        pos = np.searchsorted(key_sorted, key_c)
        pos = np.minimum(pos, key_sorted.size - 1)
        hit = key_sorted[pos] == key_c
        quad = order[pos[hit]]
        sub = quad * res * res + (cy[hit] % res) * res + (cx[hit] % res)
        fh = f[hit]
        srt = np.lexsort((fh, sub))
        sub, fh = sub[srt], fh[srt]
        n_sub = q * res * res
        cnt = np.bincount(sub, minlength=n_sub)
        if (cnt == 0).any():
            raise GeotexError("a polycube quad is not covered by the deformed mesh")
        K = int(cnt.max())
        start = np.cumsum(cnt) - cnt
        slot = np.arange(sub.size) - start[sub]
        table = np.full((n_sub, K), -1, np.int64)
        table[sub, slot] = fh
        return cls(res=res, table=table, quad_ij=np.asarray(quad_ij, np.int64), origin=o,
                   inverse=inv)

    def locate(self, quad_ids: np.ndarray, uv: np.ndarray, *, chunk: int = 200_000
               ) -> tuple[np.ndarray, np.ndarray]:
        """Face and barycentric coordinates of quad points (see module docstring)."""
        k = quad_ids.size
        face = np.empty(k, np.int64)
        bary = np.empty((k, 3))
        res = self.res
        for s in range(0, k, chunk):
            qi = quad_ids[s:s + chunk]
            u = uv[s:s + chunk]
            p = self.quad_ij[qi].astype(np.float64) + u
            si = np.clip(np.floor(u * res).astype(np.int64), 0, res - 1)
            cell = qi * res * res + si[:, 1] * res + si[:, 0]
            best_f = self.table[cell, 0].copy()
            best_s = np.full(qi.size, -np.inf)
            best_b = np.zeros((qi.size, 3))
            todo = np.arange(qi.size)
            for j in range(self.table.shape[1]):
                f = self.table[cell[todo], j]
                keep = f >= 0
                todo, f = todo[keep], f[keep]
                if todo.size == 0:
                    break
                b = _bary(self.origin, self.inverse, f, p[todo])
                sc = b.min(axis=1)
                better = sc > best_s[todo]
                upd = todo[better]
                best_f[upd], best_s[upd], best_b[upd] = f[better], sc[better], b[better]
                todo = todo[sc < -1e-12]
            bb = np.clip(best_b, 0.0, None)
            bb /= bb.sum(axis=1, keepdims=True)
            face[s:s + chunk] = best_f
            bary[s:s + chunk] = bb
        return face, bary
