"""Cuts from reflex chart corners: split non-convex polycube faces into convex parts.

A harmonic (Tutte) map onto a non-convex polygon can fold near a reflex
(270 degree) corner.  From every reflex corner of a chart, the polycube edge
arriving at it is continued straight into the chart along a path of mesh
edges (a greedy walk on the input surface in the direction of the extension)
until the path meets the chart border.  The path's vertices get the line's
coordinate fixed, which turns them into a polycube-edge-like chain
(arc-length interpolated between its two ends); the border vertex where the
path ends gets the line's coordinate too (a T-junction).  The parts of the
chart on either side are then convex at the former reflex corner.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from geotex.param.polycube_quads import chart_axes

__all__ = ["reflex_corners", "reflex_cuts"]


def reflex_corners(P, F, labels, chart, vertex_chart, neighbors):
    """Reflex (corner, chart) pairs and the arriving polycube-edge direction.

    A corner is reflex for a chart when the chart's border, followed with the
    chart on its left, turns right there (decided from the exact polycube-edge
    directions of ``P``, so a fan that folded does not hide it).

    Returns
    -------
    corner : (k,) int64
    corner_chart : (k,) int64
    arriving : (k, 3) float64
        Direction of the polycube edge arriving at the corner.
    """
    fixed = vertex_chart >= 0
    is_corner = fixed.sum(axis=1) == 3
    f, k = np.nonzero(chart[neighbors] != chart[:, None])
    src, dst, hc = F[f, k], F[f, (k + 1) % 3], chart[f]
    inc, out = is_corner[dst], is_corner[src]
    nch = int(chart.max()) + 1
    kin = dst[inc] * nch + hc[inc]
    kout = src[out] * nch + hc[out]
    o_in, o_out = np.argsort(kin), np.argsort(kout)
    common = np.intersect1d(kin, kout)
    i_in = o_in[np.searchsorted(kin[o_in], common)]
    i_out = o_out[np.searchsorted(kout[o_out], common)]
    v, c = common // nch, common % nch
    label_of = np.zeros(nch, np.int64)
    label_of[chart] = labels
    _, a1, a2 = chart_axes(label_of[c])
    t_in = P[v] - P[src[inc][i_in]]
    t_out = P[dst[out][i_out]] - P[v]
    r = np.arange(v.size)
    turn = t_in[r, a1] * t_out[r, a2] - t_in[r, a2] * t_out[r, a1]
    sel = turn < 0
    return v[sel], c[sel], t_in[sel]


def reflex_cuts(P: np.ndarray, Vgeo: np.ndarray, F: np.ndarray, labels: np.ndarray,
                chart: np.ndarray, vertex_chart: np.ndarray, neighbors: np.ndarray,
                edges: np.ndarray, *, max_steps: int = 400) -> np.ndarray:
    """Extra fixed coordinates ``(n, 3)`` (NaN where free) cutting reflex corners.

    Parameters
    ----------
    P : (n, 3) float64
        A first embedding (tile units) whose polycube edges are exact.
    Vgeo : (n, 3) float64
        Surface positions used to steer the walks (the input mesh).

    Returns
    -------
    (n, 3) float64
    """
    n = P.shape[0]
    fixed = vertex_chart >= 0
    extra = np.full((n, 3), np.nan)
    corners, cch, arriving = reflex_corners(P, F, labels, chart, vertex_chart, neighbors)
    if corners.size == 0:
        return extra
    A = sp.coo_matrix((np.ones(2 * edges.shape[0]),
                       (np.concatenate([edges[:, 0], edges[:, 1]]),
                        np.concatenate([edges[:, 1], edges[:, 0]]))), shape=(n, n)).tocsr()
    nch = int(chart.max()) + 1
    label_of = np.zeros(nch, np.int64)
    label_of[chart] = labels
    for v, c, d in zip(corners, cch, arriving):
        v, c = int(v), int(c)
        a = label_of[c] // 2
        caxis = int(np.argmax(np.abs(d)))
        if caxis == a or d[caxis] == 0:
            continue
        direction = np.zeros(3)
        direction[caxis] = np.sign(d[caxis])
        baxis = 3 - a - caxis
        line = P[v, baxis]
        on_line = ((fixed[:, baxis] & (P[:, baxis] == line))
                   | (extra[:, baxis] == line))
        path = _walk(A, Vgeo, v, c, a, direction, vertex_chart, extra, on_line, max_steps)
        if path is None:
            continue
        inner, end = path
        state_end = fixed[end] | ~np.isnan(extra[end])
        if state_end[baxis]:
            val = P[end, baxis] if fixed[end, baxis] else extra[end, baxis]
            if val != line:
                continue
        else:
            if state_end.sum() != 2:
                continue
            extra[end, baxis] = line
        extra[inner, baxis] = line
    return extra


def _walk(A, X, v, c, a, direction, vertex_chart, extra, on_line, max_steps):
    """Greedy path from ``v`` along ``direction`` (on positions ``X``) inside chart ``c``.

    Gives up (None) when the path would touch another vertex already on the
    cut's line (its faces would be flat) or cannot advance.
    """
    path = [v]
    banned = {v}
    cur = v
    for _ in range(max_steps):
        nb = A.indices[A.indptr[cur]:A.indptr[cur + 1]]
        nb = nb[(vertex_chart[nb, a] == c) & np.array([y not in banned for y in nb], bool)]
        if nb.size == 0:
            return None
        d = X[nb] - X[cur]
        score = (d @ direction) / np.maximum(np.linalg.norm(d, axis=1), 1e-300)
        best = int(np.argmax(score))
        if score[best] < 0.2:
            return None
        y = int(nb[best])
        if (vertex_chart[y] >= 0).sum() != 1 or not np.isnan(extra[y]).all():
            return np.asarray(path[1:], np.int64), y
        ynb = A.indices[A.indptr[y]:A.indptr[y + 1]]
        if any(((u in banned) or on_line[u]) and u != cur for u in ynb):
            return None
        banned.add(y)
        path.append(y)
        cur = y
    return None
