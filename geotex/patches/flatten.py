"""Recursive barycentric flattening of face clusters (hierarchical pattern mapping §3.2).

A cluster is flattened through its *control polygon*: its control vertices
laid out in the plane with the 3D distances between consecutive control
vertices as edge lengths and the directions of their projection onto the
cluster's mean plane (the plane of its vector area, which is the
least-squares plane of its border for a disc) as edge directions; the
closure error of the polygon is spread along it in proportion to arc length,
so a flat cluster keeps its shape exactly.

Mapping then follows eq. (1) of the paper, ``T(l, j) = C_bary(l, j) T(l - 1,
parent)``: the control points of every sub-cluster get texture positions as
barycentric combinations of the parent's control points, down to the faces,
whose control points are the mesh vertices.  ``C_bary`` is precomputed once
for the whole hierarchy (:func:`barycentric_hierarchy`):

* a control vertex that is also a control vertex of the parent copies it
  (the paper's case 1);
* any other control vertex (on the parent's border or inside) is projected
  onto the parent's mean plane together with the parent's control points,
  and gets, by default, mean value coordinates (Floater 2003) with respect
  to the whole projected parent polygon.  The paper instead takes triangle
  barycentric coordinates with respect to the three parent control points
  that give the smallest coordinates (its *stable base choice*, available
  as ``coordinates="stable_base"``).  The texture-space control polygon is
  laid out with 3D edge lengths, so it is not an affine image of the
  projected polygon, and two neighbouring vertices that pick different
  triangles get positions from two different affine maps: the flattening
  jumps along the lines where the choice changes, and on fine meshes the
  jumps are longer than the edges and fold faces (Spot at 30k faces with
  water: most refusals on the coarser levels were such folds).  Mean value
  coordinates are smooth and exact for affine maps (a flat cluster still
  maps exactly), so the map has no jumps; a vertex whose coordinates are
  not finite or too large (a projected polygon folded over itself) falls
  back to the stable base.  The paper also projects vertices on a parent
  edge along the mean normal of that edge; here every non-control vertex
  uses the parent's plane, which keeps the coordinates of a vertex shared
  by two sibling clusters identical (both come from the same parent).

A mesh vertex reached through several faces (with different ancestors) gets
the average of its values (the paper's treatment of *in-cluster cracks*),
and positions imposed on some vertices (``fixed``) replace the computed ones
at every level of the traversal, so their effect spreads into the cluster
through the barycentric coordinates (the paper's treatment of *border
cracks*).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from geotex.errors import InputError
from geotex.patches.clusters import ClusterHierarchy

__all__ = ["BarycentricHierarchy", "barycentric_hierarchy", "control_polygon",
           "flatten_cluster", "polygon_coordinates", "cluster_frames", "edge_band"]

_CHUNK = 4096
#: Largest absolute mean value coordinate accepted before falling back to the stable base.
MVC_LIMIT = 4.0


@dataclass(frozen=True, eq=False)
class BarycentricHierarchy:
    """Precomputed barycentric coordinates of every control slot.

    Attributes
    ----------
    hierarchy : ClusterHierarchy
    faces : numpy.ndarray, (m, 3) int64
        The mesh faces.
    normals : list of numpy.ndarray, (c, 3) float64
        Unit mean-plane normal of every cluster of every level.
    base : list of numpy.ndarray, (s, w) int64
        For every control slot of level ``l >= 1`` (CSR order of
        ``levels[l].control_vertices``), ``w`` control slots of level
        ``l - 1`` (global slot indices; ``w = 3`` for the stable base, the
        largest parent polygon for mean value coordinates, unused columns
        with weight 0); level 0 holds an empty array.
    weights : list of numpy.ndarray, (s, w) float64
        The barycentric coordinates (sum 1) with respect to ``base``.
    topo_base, topo_weights : list of numpy.ndarray, (s, 3)
        The *topological* barycentric coordinates (§4.1) of every control
        slot w.r.t. its parent's control points: a parent control point
        copies it; a vertex on the parent's border between corners ``a`` and
        ``b`` gets ``(1 - t, t)`` on them with ``t`` its arc-length fraction
        along that stretch of border (the paper uses 1/2, 1/2 for the
        midpoints of subdivision surfaces); an inner vertex gets weights
        proportional to the inverse distances to the three nearest parent
        corners (the paper: proportional to the distances to all corners,
        which needs a variable number of columns).
    """

    hierarchy: ClusterHierarchy
    faces: np.ndarray
    normals: list
    base: list
    weights: list
    topo_base: list
    topo_weights: list


def cluster_frames(V, F, labels, n_clusters, direction=None):
    """Unit normal and tangent frame of the mean plane of every cluster.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
    n_clusters : int
    direction : numpy.ndarray, (c, 3) float64, optional
        Preferred first tangent axis of each cluster (projected onto the
        plane); default: the axis of the world frame least aligned with the
        normal.

    Returns
    -------
    normal, e1, e2 : numpy.ndarray, (c, 3) float64
    """
    cr = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N = np.stack([np.bincount(labels, weights=cr[:, i], minlength=n_clusters)
                  for i in range(3)], 1)
    ln = np.linalg.norm(N, axis=1)
    N = N / np.where(ln > 0, ln, 1.0)[:, None]
    N[ln == 0] = (0.0, 0.0, 1.0)
    if direction is None:
        axis = np.eye(3)[np.argmin(np.abs(N), axis=1)]
    else:
        axis = np.asarray(direction, dtype=np.float64).reshape(n_clusters, 3)
    e1 = axis - N * np.sum(axis * N, axis=1, keepdims=True)
    l1 = np.linalg.norm(e1, axis=1)
    weak = l1 < 1e-9
    if weak.any():
        alt = np.eye(3)[np.argmin(np.abs(N[weak]), axis=1)]
        e1[weak] = alt - N[weak] * np.sum(alt * N[weak], axis=1, keepdims=True)
        l1 = np.linalg.norm(e1, axis=1)
    e1 /= l1[:, None]
    e2 = np.cross(N, e1)
    return N, e1, e2


def _stable_barycentric(poly: np.ndarray, valid: np.ndarray, x: np.ndarray):
    """Barycentric coordinates of points in the best triangle of their polygon.

    ``poly`` (N, k, 2) with ``valid`` (N, k) marking real corners, ``x`` (N, 2).
    Returns corner indices (N, 3) and weights (N, 3).
    """
    N, k = poly.shape[:2]
    tri = np.array(list(combinations(range(k), 3)), dtype=np.int64)
    out_i = np.zeros((N, 3), np.int64)
    out_w = np.zeros((N, 3))
    for s in range(0, N, _CHUNK):
        P = poly[s:s + _CHUNK]
        X = x[s:s + _CHUNK]
        ok = valid[s:s + _CHUNK][:, tri].all(axis=2)                 # (n, t)
        A, B, C = P[:, tri[:, 0]], P[:, tri[:, 1]], P[:, tri[:, 2]]   # (n, t, 2)
        den = (B[..., 0] - A[..., 0]) * (C[..., 1] - A[..., 1]) \
            - (B[..., 1] - A[..., 1]) * (C[..., 0] - A[..., 0])
        ext = np.ptp(np.where(valid[s:s + _CHUNK, :, None], P, P[:, :1]), axis=1).max(axis=1)
        ok &= np.abs(den) > 1e-6 * (ext[:, None] ** 2 + 1e-300)
        d = np.where(ok, den, 1.0)
        Xe = X[:, None, :]
        wb = ((Xe[..., 0] - A[..., 0]) * (C[..., 1] - A[..., 1])
              - (Xe[..., 1] - A[..., 1]) * (C[..., 0] - A[..., 0])) / d
        wc = ((B[..., 0] - A[..., 0]) * (Xe[..., 1] - A[..., 1])
              - (B[..., 1] - A[..., 1]) * (Xe[..., 0] - A[..., 0])) / d
        wa = 1.0 - wb - wc
        W = np.stack([wa, wb, wc], axis=2)
        score = np.where(ok, np.abs(W).max(axis=2), np.inf)
        best = np.argmin(score, axis=1)
        r = np.arange(P.shape[0])
        out_i[s:s + _CHUNK] = tri[best]
        out_w[s:s + _CHUNK] = W[r, best]
        none = ~np.isfinite(score[r, best])
        if none.any():                      # all corners aligned: equal weights on 3 corners
            out_w[s:s + _CHUNK][none] = 1.0 / 3.0
    return out_i, out_w


def _mean_value(poly: np.ndarray, x: np.ndarray):
    """Mean value coordinates (Floater 2003) of points w.r.t. their polygons.

    ``poly`` (N, k, 2) closed polygons (all k corners real), ``x`` (N, 2).
    Returns weights (N, k), summing to 1, smooth in ``x`` and exact for
    affine maps; a point on a polygon edge gets the linear coordinates on
    it.  Rows where the coordinates are not finite get nan.
    """
    s = poly - x[:, None, :]                                   # (N, k, 2)
    r = np.linalg.norm(s, axis=2)
    sn = np.roll(s, -1, axis=1)
    rn = np.roll(r, -1, axis=1)
    cr = s[..., 0] * sn[..., 1] - s[..., 1] * sn[..., 0]
    dt = np.sum(s * sn, axis=2)
    scale = np.maximum(r * rn, 1e-300)
    on_edge = (np.abs(cr) <= 1e-12 * scale) & (dt < 0)        # x inside segment i, i + 1
    flat = np.abs(cr) <= 1e-12 * scale
    tan = np.where(flat, 0.0, (r * rn - dt) / np.where(flat, 1.0, cr))
    w = (tan + np.roll(tan, 1, axis=1)) / np.maximum(r, 1e-300)
    tot = w.sum(axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        lam = w / tot
    # exact cases: x on a corner, x on an edge
    k = poly.shape[1]
    at = r <= 1e-12 * np.maximum(r.max(axis=1, keepdims=True), 1e-300)
    rows = np.flatnonzero(at.any(axis=1))
    lam[rows] = at[rows] / at[rows].sum(axis=1, keepdims=True)
    rows_e, ei = np.nonzero(on_edge & ~at.any(axis=1, keepdims=True))
    if rows_e.size:
        t = r[rows_e, ei] / np.maximum(r[rows_e, ei] + rn[rows_e, ei], 1e-300)
        lam[rows_e] = 0.0
        lam[rows_e, ei] = 1.0 - t
        lam[rows_e, (ei + 1) % k] = t
    bad = ~np.isfinite(lam).all(axis=1) | (np.abs(tot[:, 0]) <= 1e-300)
    bad[rows] = False
    bad[rows_e] = False
    lam[bad] = np.nan
    return lam


def polygon_coordinates(V, corners, normal, e1, e2, points):
    """Stable-base barycentric coordinates of points w.r.t. one 3D control polygon.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    corners : numpy.ndarray, (k,) int64
        Control vertices (k >= 3).
    normal, e1, e2 : numpy.ndarray, (3,) float64
        Frame of the projection plane.
    points : numpy.ndarray, (p, 3) float64

    Returns
    -------
    index : numpy.ndarray, (p, 3) int64
        Positions in ``corners``.
    weights : numpy.ndarray, (p, 3) float64
    """
    k = corners.size
    if k < 3:
        raise InputError("a control polygon needs at least 3 corners")
    Q = V[corners]
    q = np.stack([Q @ e1, Q @ e2], axis=1)
    x = np.stack([points @ e1, points @ e2], axis=1)
    p = x.shape[0]
    return _stable_barycentric(np.broadcast_to(q, (p, k, 2)), np.ones((p, k), bool), x)


def barycentric_hierarchy(V, F, hierarchy: ClusterHierarchy, *,
                          coordinates: str = "mean_value") -> BarycentricHierarchy:
    """Precompute ``C_bary`` (eq. 1) for every control slot of every level.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    hierarchy : ClusterHierarchy
    coordinates : {"mean_value", "stable_base"}, optional
        How a control vertex that is not a parent corner is expressed in
        the parent's projected control polygon.  ``"stable_base"`` is the
        paper's choice: triangle coordinates w.r.t. the three parent corners
        that give the smallest coordinates.  Neighbouring vertices then pick
        different triangles, and since the texture-space control polygon is
        laid out with 3D lengths (not an affine image of the projected one)
        the map jumps where the choice changes; on fine meshes these jumps
        are longer than the edges and fold faces.  ``"mean_value"`` (default)
        uses mean value coordinates w.r.t. the whole parent polygon: smooth,
        exact for affine maps (a flat cluster still maps exactly), no jumps.
        A vertex where they are not finite or exceed ``MVC_LIMIT`` in
        absolute value (projected polygon folded over itself) falls back to
        the stable base.

    Returns
    -------
    BarycentricHierarchy

    Raises
    ------
    InputError
        If ``coordinates`` is not one of the two names.
    """
    if coordinates not in ("mean_value", "stable_base"):
        raise InputError(f"coordinates must be 'mean_value' or 'stable_base', got "
                         f"{coordinates!r}")
    V = np.asarray(V, dtype=np.float64)
    normals, bases, weights = [], [], []
    frames = []
    for lv in hierarchy.levels:
        N, e1, e2 = cluster_frames(V, F, lv.labels, lv.n_clusters)
        normals.append(N)
        frames.append((N, e1, e2))
    bases.append(np.zeros((0, 3), np.int64))
    weights.append(np.zeros((0, 3)))
    for li in range(1, len(hierarchy.levels)):
        lv, pv = hierarchy.levels[li], hierarchy.levels[li - 1]
        S = lv.control_vertices.size
        slot_cluster = np.repeat(np.arange(lv.n_clusters), np.diff(lv.control_ptr))
        par = lv.parent[slot_cluster]
        pk = np.diff(pv.control_ptr)
        usable = pk[par] >= 3
        width = 3 if coordinates == "stable_base" else max(3, int(pk[par].max(initial=3)))
        base = np.zeros((S, width), np.int64)
        w = np.zeros((S, width))
        # case 1: the vertex is a control vertex of the parent
        key_p = np.repeat(np.arange(pv.n_clusters), pk) * np.int64(V.shape[0]) + pv.control_vertices
        key = par * np.int64(V.shape[0]) + lv.control_vertices
        order = np.argsort(key_p, kind="stable")
        pos = np.searchsorted(key_p[order], key)
        posc = np.minimum(pos, max(key_p.size - 1, 0))
        same = (key_p.size > 0) & (key_p[order][posc] == key) if key_p.size else np.zeros(S, bool)
        if key_p.size:
            hit = order[posc]
            base[same] = hit[same][:, None]
            w[same, 0] = 1.0
        todo = np.flatnonzero(~same & usable)
        if todo.size:
            Np, E1, E2 = frames[li - 1]
            kk = pk[par[todo]]
            kmax = int(kk.max())
            start = pv.control_ptr[par[todo]]
            idx = start[:, None] + np.arange(kmax)[None, :]
            valid = np.arange(kmax)[None, :] < kk[:, None]
            idx = np.where(valid, idx, start[:, None])
            Q = V[pv.control_vertices[idx]]                       # (t, kmax, 3)
            e1, e2 = E1[par[todo]], E2[par[todo]]
            q = np.stack([np.einsum("tkd,td->tk", Q, e1), np.einsum("tkd,td->tk", Q, e2)], 2)
            P = V[lv.control_vertices[todo]]
            x = np.stack([np.sum(P * e1, 1), np.sum(P * e2, 1)], 1)
            base[todo] = start[:, None]
            # group by polygon size to keep the triangle enumeration small
            for k in np.unique(kk):
                sel = np.flatnonzero(kk == k)
                if coordinates == "mean_value":
                    lam = _mean_value(q[sel, :k], x[sel])
                    good = np.isfinite(lam).all(axis=1)
                    good[good] = np.abs(lam[good]).max(axis=1) <= MVC_LIMIT
                    g = sel[good]
                    base[todo[g], :k] = start[g][:, None] + np.arange(k)[None, :]
                    w[todo[g], :k] = lam[good]
                    sel = sel[~good]
                    if sel.size == 0:
                        continue
                ii, ww = _stable_barycentric(q[sel, :k], valid[sel, :k], x[sel])
                base[todo[sel], :3] = start[sel][:, None] + ii
                w[todo[sel], :3] = ww
        bases.append(base)
        weights.append(w)
    tb, tw = _topological(V, hierarchy)
    return BarycentricHierarchy(hierarchy=hierarchy, faces=np.asarray(F, dtype=np.int64),
                                normals=normals, base=bases,
                                weights=weights, topo_base=tb, topo_weights=tw)


def _topological(V, hierarchy):
    """Topological barycentric coordinates of every control slot (see the class doc)."""
    n = V.shape[0]
    bases = [np.zeros((0, 3), np.int64)]
    weights = [np.zeros((0, 3))]
    for li in range(1, len(hierarchy.levels)):
        lv, pv = hierarchy.levels[li], hierarchy.levels[li - 1]
        S = lv.control_vertices.size
        slot_cluster = np.repeat(np.arange(lv.n_clusters), np.diff(lv.control_ptr))
        par = lv.parent[slot_cluster]
        base = np.zeros((S, 3), np.int64)
        w = np.zeros((S, 3))
        pk = np.diff(pv.control_ptr)
        # arc-length position of every parent loop vertex between its corners
        lp = pv.loop_ptr
        loop_c = np.repeat(np.arange(pv.n_clusters), np.diff(lp))
        lv_v = pv.loop_vertices
        nxt = np.arange(lv_v.size) + 1
        nxt[lp[1:][np.diff(lp) > 0] - 1] = lp[:-1][np.diff(lp) > 0]
        seg = np.linalg.norm(V[lv_v[nxt]] - V[lv_v], axis=1) if lv_v.size else np.zeros(0)
        corner_key = pv.control_vertices + np.repeat(np.arange(pv.n_clusters), pk) * np.int64(n)
        loop_key = lv_v + loop_c * np.int64(n)
        is_corner = np.isin(loop_key, corner_key)
        # corner index (slot) at or before each loop position, and after it
        slot_of_key = dict(zip(corner_key.tolist(), range(corner_key.size)))
        prev_slot = np.full(lv_v.size, -1, np.int64)
        next_slot = np.full(lv_v.size, -1, np.int64)
        t_arc = np.zeros(lv_v.size)
        for c in np.flatnonzero((np.diff(lp) > 0) & (pk >= 1)):
            a, b = lp[c], lp[c + 1]
            keys = loop_key[a:b]
            corn = np.flatnonzero(is_corner[a:b])
            L = b - a
            order = (np.arange(L) - corn[0]) % L              # start at the first corner
            ro = np.argsort(order)
            cum = np.concatenate([[0.0], np.cumsum(seg[a:b][ro])])
            cslots = np.array([slot_of_key[int(k)] for k in keys[corn]])
            cpos = np.sort(order[corn])
            cs_sorted = cslots[np.argsort(order[corn])]
            k_idx = np.searchsorted(cpos, order, side="right") - 1
            lo_pos = cpos[k_idx]
            hi_pos = np.where(k_idx + 1 < cpos.size, cpos[np.minimum(k_idx + 1, cpos.size - 1)],
                              L)
            lo_arc = cum[lo_pos]
            hi_arc = cum[hi_pos]
            t = (cum[order] - lo_arc) / np.maximum(hi_arc - lo_arc, 1e-300)
            prev_slot[a:b] = cs_sorted[k_idx]
            next_slot[a:b] = cs_sorted[(k_idx + 1) % cs_sorted.size]
            t_arc[a:b] = t
        on = np.zeros(S, bool)
        hit = np.zeros(S, np.int64)
        if loop_key.size:
            lk_order = np.argsort(loop_key, kind="stable")
            key = lv.control_vertices + par * np.int64(n)
            posc = np.minimum(np.searchsorted(loop_key[lk_order], key), loop_key.size - 1)
            hit = lk_order[posc]
            on = (loop_key[hit] == key) & (prev_slot[hit] >= 0)
        base[on, 0] = prev_slot[hit[on]]
        base[on, 1] = next_slot[hit[on]]
        base[on, 2] = prev_slot[hit[on]]
        w[on, 0] = 1.0 - t_arc[hit[on]]
        w[on, 1] = t_arc[hit[on]]
        inner = np.flatnonzero(~on & (pk[par] >= 1))
        if inner.size:
            kmax = int(pk[par[inner]].max())
            start = pv.control_ptr[par[inner]]
            idx = start[:, None] + np.arange(kmax)[None, :]
            valid = np.arange(kmax)[None, :] < pk[par[inner]][:, None]
            idx = np.where(valid, idx, start[:, None])
            d = np.linalg.norm(V[pv.control_vertices[idx]]
                               - V[lv.control_vertices[inner]][:, None, :], axis=2)
            d = np.where(valid, d, np.inf)
            near = np.argsort(d, axis=1)[:, :3]
            dn = np.take_along_axis(d, near, axis=1)
            inv = np.where(np.isfinite(dn), 1.0 / np.maximum(dn, 1e-300), 0.0)
            inv /= inv.sum(axis=1, keepdims=True)
            base[inner] = np.take_along_axis(idx, near, axis=1)
            w[inner] = inv
        bases.append(base)
        weights.append(w)
    return bases, weights


def control_polygon(V, corners, e1, e2) -> np.ndarray:
    """Texture-space control polygon of a cluster (see the module docstring).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    corners : numpy.ndarray, (k,) int64
        Control vertices in loop order.
    e1, e2 : numpy.ndarray, (3,) float64
        Tangent frame of the cluster's mean plane.

    Returns
    -------
    numpy.ndarray, (k, 2) float64
        In the units of ``V``, centred on the projected centroid.
    """
    Q = V[corners]
    q = np.stack([Q @ e1, Q @ e2], axis=1)
    d2 = np.roll(q, -1, axis=0) - q
    l3 = np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1)
    l2 = np.linalg.norm(d2, axis=1)
    d = np.where(l2[:, None] > 0, d2 / np.where(l2 > 0, l2, 1.0)[:, None], 0.0)
    steps = d * l3[:, None]
    closure = steps.sum(axis=0)
    total = l3.sum()
    if total > 0:
        steps = steps - np.outer(l3 / total, closure)
    P = np.vstack([np.zeros(2), np.cumsum(steps, axis=0)[:-1]])
    return P - P.mean(axis=0) + q.mean(axis=0)


def flatten_cluster(bh: BarycentricHierarchy, level: int, cluster: int, polygon,
                    *, fixed=None, fixed_mask=None, topological: bool = False):
    """Texture positions of the vertices of one cluster by recursive barycentric mapping.

    Parameters
    ----------
    bh : BarycentricHierarchy
    level, cluster : int
    polygon : numpy.ndarray, (k, 2) float64
        Texture positions of the cluster's control vertices (loop order).
    fixed : numpy.ndarray, (n, 2) float64, optional
    fixed_mask : numpy.ndarray, (n,) bool, optional
        Vertices whose position is imposed (replaces the computed value at
        every level, so the change spreads through the descendants).

    topological : bool, optional
        Propagate with the topological coordinates instead (pass the
        identity as ``polygon`` to get every vertex's topological
        coordinates ``M`` in the cluster's base, §4.1).

    Returns
    -------
    vertices : numpy.ndarray, (p,) int64
        The vertices of the cluster's faces, ascending.
    uv : numpy.ndarray, (p, d) float64
        Their positions (mean over the faces that reach them).
    faces : numpy.ndarray, (f,) int64
        The cluster's faces.
    """
    H = bh.hierarchy
    lv = H.levels[level]
    lo, hi = int(cluster), int(cluster) + 1
    s0, s1 = lv.control_ptr[lo], lv.control_ptr[hi]
    pos = np.asarray(polygon, dtype=np.float64).reshape(s1 - s0, -1).copy()
    base_l = bh.topo_base if topological else bh.base
    weight_l = bh.topo_weights if topological else bh.weights
    if fixed_mask is not None:
        cv = lv.control_vertices[s0:s1]
        pos[fixed_mask[cv]] = fixed[cv[fixed_mask[cv]]]
    for li in range(level + 1, len(H.levels)):
        plv, clv = H.levels[li - 1], H.levels[li]
        cp = plv.child_ptr
        clo, chi = int(cp[lo]), int(cp[hi])
        t0, t1 = clv.control_ptr[clo], clv.control_ptr[chi]
        ps0 = plv.control_ptr[lo]
        b = base_l[li][t0:t1] - ps0
        new = np.einsum("sk,skd->sd", weight_l[li][t0:t1], pos[b])
        if fixed_mask is not None:
            cv = clv.control_vertices[t0:t1]
            m = fixed_mask[cv]
            new[m] = fixed[cv[m]]
        pos, lo, hi = new, clo, chi
    last = H.levels[-1]
    cv = last.control_vertices[last.control_ptr[lo]:last.control_ptr[hi]]
    verts, inv = np.unique(cv, return_inverse=True)
    cnt = np.bincount(inv, minlength=verts.size)
    uv = np.stack([np.bincount(inv, weights=pos[:, i], minlength=verts.size)
                   for i in range(pos.shape[1])], 1) / cnt[:, None]
    faces = np.flatnonzero((last.labels >= lo) & (last.labels < hi))
    return verts, uv, faces


def edge_band(bh: BarycentricHierarchy, level: int, cluster: int, edges, *,
              width: float = 0.2) -> np.ndarray:
    """Faces of a cluster in a band along some of its control-polygon edges (§4.1).

    The *position value* of a vertex w.r.t. the edge ``(i, i + 1)`` of the
    cluster's control polygon is the sum of its topological barycentric
    coordinates in the cluster's base except those of corners ``i`` and
    ``i + 1``; the band keeps the faces whose three vertices have a position
    value below ``width`` for one of ``edges``.

    Parameters
    ----------
    bh : BarycentricHierarchy
    level, cluster : int
    edges : array_like of int
        Indices ``i`` of the polygon edges ``(i, i + 1 mod k)``.
    width : float, optional
        The paper's threshold (0.2).

    Returns
    -------
    numpy.ndarray, (b,) int64
        Faces, ascending.
    """
    lv = bh.hierarchy.levels[level]
    k = int(lv.control_ptr[cluster + 1] - lv.control_ptr[cluster])
    verts, M, faces = flatten_cluster(bh, level, cluster, np.eye(k), topological=True)
    e = np.asarray(edges, dtype=np.int64).reshape(-1)
    if e.size == 0 or k == 0:
        return np.zeros(0, np.int64)
    val = 1.0 - M[:, e % k] - M[:, (e + 1) % k]              # (p, edges)
    near = (val < width).any(axis=1)
    keep = np.zeros(int(verts.max()) + 1, bool)
    keep[verts[near]] = True
    return np.sort(faces[np.all(keep[bh.faces[faces]], axis=1)])
