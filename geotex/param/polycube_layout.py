"""Polycube layout: charts, their neighbours and integer chart planes.

Every chart of a valid labelling (see :mod:`geotex.param.polycube_labels`)
becomes one planar polycube face lying in the plane ``x[axis] = plane *
tile_size``.  The integer plane values are chosen by a small mixed-integer
program (scipy's HiGHS ``milp``): stay as close as possible (area-weighted L1)
to the chart's mean coordinate, subject to *separation constraints*: every
polycube edge (a chain of border edges between two charts, from corner to
corner) runs along the third axis from the plane of the chart at its first
corner to the plane of the chart at its last corner; the two planes keep the
order the corners have in the input mesh and at least one tile between them.
So every polycube edge is at least one tile long, every polycube face at least
one tile wide, and thin parts are inflated to one tile rather than collapsed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse.csgraph import connected_components

from geotex.errors import GeotexError
from geotex.param.polycube_labels import LABEL_NAMES, FaceGraph, charts_of

__all__ = ["ChartLayout", "LayoutError", "chart_layout", "solve_planes", "flat_border_faces"]


class LayoutError(GeotexError):
    """An invalid chart configuration; ``faces`` are the faces to relabel."""

    def __init__(self, message: str, faces: np.ndarray, *, merge: bool = False):
        self.faces = faces
        self.merge = merge  # merge the faces (one chart) into a neighbouring chart
        super().__init__(message)


@dataclass(frozen=True)
class ChartLayout:
    """Charts of a labelling and how they touch.

    Attributes
    ----------
    n_charts : int
    chart : (m,) int64
        Chart of every face.
    chart_label : (n_charts,) int64
        Label (0..5) of every chart.
    chart_area : (n_charts,) float64
    target : (n_charts,) float64
        Area-weighted mean coordinate of the chart along its axis.
    separations : (s, 2) int64
        Rows ``(lo, hi)`` meaning ``plane[hi] - plane[lo] >= 1``: the two
        charts at the ends of a polycube edge, in the order of the edge's
        corners along its axis in the input mesh.
    vertex_chart : (n, 3) int64
        For every vertex and axis, the chart of that axis touching the vertex,
        or ``-1``.
    """

    n_charts: int
    chart: np.ndarray
    chart_label: np.ndarray
    chart_area: np.ndarray
    target: np.ndarray
    separations: np.ndarray
    vertex_chart: np.ndarray


def chart_layout(V: np.ndarray, F: np.ndarray, g: FaceGraph, labels: np.ndarray
                 ) -> ChartLayout:
    """Compute the :class:`ChartLayout` of a (valid) labelling.

    Raises
    ------
    GeotexError
        If a vertex touches two charts of the same axis (invalid labelling).
    """
    n = V.shape[0]
    nch, chart = charts_of(g, labels)
    chart_label = np.zeros(nch, np.int64)
    chart_label[chart] = labels
    area = np.bincount(chart, weights=g.areas, minlength=nch)
    cen = V[F].mean(axis=1)
    ax = chart_label // 2
    coord = cen[np.arange(F.shape[0]), ax[chart]]
    target = np.bincount(chart, weights=g.areas * coord, minlength=nch) / area
    # vertex -> chart per axis
    vc = np.full((n, 3), -1, np.int64)
    vf_v = F.ravel()
    vf_c = np.repeat(chart, 3)
    vf_a = ax[vf_c]
    vc[vf_v, vf_a] = vf_c
    check = vc[vf_v, vf_a] != vf_c
    if check.any():
        bad_v = np.unique(vf_v[check])
        faces = np.unique(np.flatnonzero(np.isin(F, bad_v).any(axis=1)))
        raise LayoutError(f"vertex {int(bad_v[0])} touches two polycube charts of the same "
                          "axis", faces)
    # polycube edges (chains): border edges linked through non-corner vertices
    ef = g.edge_faces
    cut = chart[ef[:, 0]] != chart[ef[:, 1]]
    e = g.edges[cut]
    ce = np.flatnonzero(cut)
    corner = (vc >= 0).sum(axis=1) == 3
    k = e.shape[0]
    ends = e.ravel()
    eid = np.repeat(np.arange(k), 2)
    keep = ~corner[ends]
    order = np.lexsort((eid[keep], ends[keep]))
    vv, ee = ends[keep][order], eid[keep][order]
    same = np.flatnonzero(vv[1:] == vv[:-1])
    G = sp.coo_matrix((np.ones(same.size), (ee[same], ee[same + 1])), shape=(k, k))
    n_chain, chain_of = connected_components(G, directed=False)
    # endpoints: corner ends of each chain
    is_c = corner[ends]
    c_chain = chain_of[eid[is_c]]
    c_vert = ends[is_c]
    cnt = np.bincount(c_chain, minlength=n_chain)
    bad_chain = np.flatnonzero(cnt != 2)
    fa = ef[ce, 0]
    fb = ef[ce, 1]
    if bad_chain.size:
        faces = np.unique(np.concatenate([fa[np.isin(chain_of, bad_chain)],
                                          fb[np.isin(chain_of, bad_chain)]]))
        raise LayoutError("two charts meet along a closed loop without polycube corners",
                          faces)
    # orient every border edge from chart A = min(chart) side: its half-edge in A's face
    ca, cb = chart[fa], chart[fb]
    fA = np.where(ca < cb, fa, fb)
    fB = np.where(ca < cb, fb, fa)
    h = 3 * fA[:, None] + np.arange(3)[None, :]
    kloc = np.argmax(g.half_to_edge[h] == ce[:, None], axis=1)
    src = F[fA, kloc]
    dst = F[fA, (kloc + 1) % 3]
    A = np.zeros(n_chain, np.int64)
    B = np.zeros(n_chain, np.int64)
    A[chain_of] = chart[fA]
    B[chain_of] = chart[fB]
    a_ax, b_ax = ax[A], ax[B]
    run = 3 - a_ax - b_ax
    # side of A w.r.t. B's plane (local: A's faces next to the chain), per chain
    mid = 0.5 * (V[src] + V[dst])
    length = np.linalg.norm(V[dst] - V[src], axis=1)
    off = (cen[fA] - mid)[np.arange(k), ax[chart[fB]]] * length
    sigma = np.where(np.bincount(chain_of, weights=off, minlength=n_chain) >= 0, 1, -1)
    # A's boundary runs along +s e_run with  s = -sigma * eps * sign(A)
    eps = np.where((a_ax + 1) % 3 == b_ax, 1, -1)
    sign_a = np.where(chart_label[A] % 2 == 0, 1, -1)
    s_dir = -sigma * eps * sign_a
    # start corner: tail of a half-edge of the chain; end corner: head
    start = np.full(n_chain, -1, np.int64)
    end = np.full(n_chain, -1, np.int64)
    tail_c = corner[src]
    head_c = corner[dst]
    start[chain_of[tail_c]] = src[tail_c]
    end[chain_of[head_c]] = dst[head_c]
    C = vc[np.maximum(start, 0), run]
    D = vc[np.maximum(end, 0), run]
    C[start < 0] = -1
    D[end < 0] = -1
    lo = np.where(s_dir > 0, C, D)
    hi = np.where(s_dir > 0, D, C)
    degenerate = (lo == hi) | (lo < 0) | (hi < 0)
    if degenerate.any():
        bad_chain = np.flatnonzero(degenerate)
        faces = np.unique(np.concatenate([fa[np.isin(chain_of, bad_chain)],
                                          fb[np.isin(chain_of, bad_chain)]]))
        raise LayoutError("a polycube edge starts and ends on the same chart", faces)
    sep = np.unique(np.stack([lo, hi], axis=1), axis=0)
    return ChartLayout(n_charts=nch, chart=chart, chart_label=chart_label, chart_area=area,
                       target=target, separations=sep, vertex_chart=vc)


def solve_planes(layout: ChartLayout, tile_size: float, *, max_shift: float = 1.0
                 ) -> np.ndarray:
    """Integer plane value (in tiles) of every chart.

    Parameters
    ----------
    layout : ChartLayout
    tile_size : float
    max_shift : float, optional
        Largest allowed distance, in tiles, between a chart's plane and its
        mean coordinate; beyond it the tile size is too large for the part.

    Returns
    -------
    (n_charts,) int64

    Raises
    ------
    LayoutError
        When the separations cannot be met (inconsistent layout: ``faces``
        are those of the smallest chart) or a plane must move more than
        ``max_shift`` tiles (tile size too large for that chart's part).
    """
    nc = layout.n_charts
    t = layout.target / tile_size
    sep = layout.separations
    w = layout.chart_area / layout.chart_area.sum()
    # variables: p (nc, integer), d (nc, >= |p - t|)
    c = np.concatenate([np.zeros(nc), w + 1e-9])
    rows, cols, vals, lb, ub = [], [], [], [], []
    r = 0
    for i in range(nc):  # d_i - p_i >= -t_i ; d_i + p_i >= t_i
        rows += [r, r, r + 1, r + 1]
        cols += [nc + i, i, nc + i, i]
        vals += [1.0, -1.0, 1.0, 1.0]
        lb += [-t[i], t[i]]
        ub += [np.inf, np.inf]
        r += 2
    for lo, hi in sep:
        rows += [r, r]
        cols += [hi, lo]
        vals += [1.0, -1.0]
        lb.append(1.0)
        ub.append(np.inf)
        r += 1
    Amat = sp.csr_matrix((vals, (rows, cols)), shape=(r, 2 * nc))
    span = float(np.abs(t).max()) + nc + 2
    bounds_lo = np.concatenate([np.full(nc, -np.ceil(span)), np.zeros(nc)])
    bounds_hi = np.concatenate([np.full(nc, np.ceil(span)), np.full(nc, np.inf)])
    res = milp(c, integrality=np.concatenate([np.ones(nc), np.zeros(nc)]),
               bounds=Bounds(bounds_lo, bounds_hi),
               constraints=LinearConstraint(Amat, lb, ub), options={"time_limit": 20.0})
    if res.x is None:
        k = int(np.argmin(layout.chart_area))
        raise LayoutError("the polycube charts cannot be separated consistently (the "
                          "labelling has no polycube)", np.flatnonzero(layout.chart == k),
                          merge=True)
    p = np.round(res.x[:nc]).astype(np.int64)
    shift = np.abs(p - t)
    if shift.max() > max_shift + 1e-9:
        k = int(np.argmax(shift))
        raise LayoutError(
            f"tile size too large for the part around chart {k} ({LABEL_NAMES[layout.chart_label[k]]}"
            f", {layout.chart_area[k]:.3g} area): its polycube face would move "
            f"{shift[k]:.2f} tiles; use a smaller tile size (or the part is too intricate for "
            "the labelling)", np.flatnonzero(layout.chart == k),
            merge=True)
    return p


def flat_border_faces(F: np.ndarray, labels: np.ndarray, layout: ChartLayout
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Faces whose three corners touch one other chart (they would be collinear).

    Returns
    -------
    faces : (k,) int64
    new_labels : (k,) int64
        The label of that other chart, which the face should take.
    """
    vc = layout.vertex_chart[F]  # (m, 3 corners, 3 axes)
    a = labels // 2
    same = (vc[:, 0] >= 0) & (vc[:, 0] == vc[:, 1]) & (vc[:, 0] == vc[:, 2])  # (m, 3 axes)
    same[np.arange(F.shape[0]), a] = False
    faces = np.flatnonzero(same.any(axis=1))
    axis = np.argmax(same[faces], axis=1)
    return faces, layout.chart_label[vc[faces, 0, axis]]
