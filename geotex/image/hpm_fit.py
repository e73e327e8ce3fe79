"""Placement fits and crack handling of hierarchical pattern mapping.

:func:`_rigid_fit` (closed-form 2D rotation and translation between point
sets), :func:`_refine_placement` (sub-pixel and sub-grid refinement of an FFT
placement), :func:`_snap` (border vertices moved onto the neighbour's texture
position unless that folds a face) and :func:`_relax` (the paper's local edge
relaxation of the vertices where the map jumps, Fig. 6).
"""

from __future__ import annotations

import numpy as np

from geotex.image.hpm_kernels import _relax_error_compiled, _relax_search_compiled, _sample

#: Largest relaxation move, as a fraction of the shortest edge at the vertex (texture space).
RELAX_EDGE_FRACTION = 0.2


def _rigid_fit(X, Y):
    """Least-squares rotation and translation ``Y ~ R X + t`` of 2D points (k, 2).

    The rotation maximising ``sum y . (R x)`` over the centred points has the
    angle of ``(a + e, b - d)`` for ``[[a, b], [d, e]] = sum x y^T`` (the
    2 x 2 Kabsch solution in closed form: the rotation of the SVD's ``V U^T``).
    Returns ``(R, t)``, or None when the best orthogonal map is a reflection
    (``det < 0``, the SVD's ``V U^T`` has determinant -1) or the points give no
    direction.
    """
    xm, ym = X.mean(axis=0), Y.mean(axis=0)
    (a, b), (d, e) = ((X - xm).T @ (Y - ym)).tolist()
    r = np.hypot(a + e, b - d)
    if not (a * e - b * d > 0 and r > 0):
        return None
    co, si = (a + e) / r, (b - d) / r
    R = np.array([[co, -si], [si, co]])
    return R, ym - R @ xm


def _refine_placement(img, R, t, q, target, angle_step, fast=False):
    """Sub-pixel and sub-grid refinement of a mask placement ``x -> R q + t``.

    The FFT search gives the best placement on the pixel grid and on the
    orientation grid.  Around it, the continuous mask error
    ``E = sum (target - img(R q + t))^2`` (bilinear samples of ``img`` at the
    placed mask points ``q`` (k, 2), colours ``target`` (k, c)) is fitted by a
    parabola in x, in y (steps of half a pixel) and in the angle (steps of
    half the orientation grid, rotating about the mask's centroid), two
    rounds with halved steps; the lowest evaluated placement is kept, so the
    result is never worse than the start.  ``fast``: sample the image with the
    compiled loop (same values).

    Returns
    -------
    R, t : numpy.ndarray, (2, 2) and (2,) float64
    error : float
        ``E`` at the returned placement.
    """
    qc = q.mean(axis=0)

    def place(p):
        c, s = np.cos(p[2]), np.sin(p[2])
        R1 = np.array([[c, s], [-s, c]]) @ R
        return R1, R @ qc + t - R1 @ qc + p[:2]

    def energy(p):
        R1, t1 = place(p)
        d = target - _sample(img, q @ R1.T + t1, fast)
        return float(np.sum(d * d))

    p = np.zeros(3)
    e0 = energy(p)
    steps = np.array([0.5, 0.5, 0.5 * angle_step])
    for _ in range(2):
        for j in range(3):
            h = steps[j]
            em = energy(p - h * np.eye(3)[j])
            ep = energy(p + h * np.eye(3)[j])
            cand = [(e0, 0.0), (em, -h), (ep, h)]
            curv = em - 2.0 * e0 + ep
            if curv > 0:
                x = float(np.clip(0.5 * h * (em - ep) / curv, -h, h))
                if 0.0 < abs(x) < h:
                    cand.append((energy(p + x * np.eye(3)[j]), x))
            e_best, x_best = min(cand, key=lambda z: z[0])
            p[j] += x_best
            e0 = e_best
        steps *= 0.5
    R1, t1 = place(p)
    return R1, t1, e0


def _signed_areas(P: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Twice the signed areas of triangles ``tri`` (t, 3) over positions ``P`` (p, 2)."""
    t = P[tri]
    return (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
        - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])


def _snap(P, target, close, tri):
    """Move the ``close`` rows of ``P`` (in place) onto ``target`` unless that folds a face.

    ``tri`` (t, 3) are the cluster's faces as row indices of ``P``.  On fine
    meshes the snapping distance is a sizeable part of an edge in pixels, and
    snapping both ends of a short edge can reverse or crush a face: the
    vertices of such faces keep their own position (a small crack instead of
    a flipped face).  Returns the rows actually snapped.
    """
    close = close.copy()
    a0 = _signed_areas(P, tri)
    while close.any():                  # every round unsnaps at least one vertex
        trial = P.copy()
        trial[close] = target[close]
        bad = _signed_areas(trial, tri) * np.sign(a0) < 0.3 * np.abs(a0)
        if not bad.any():
            break
        close[np.unique(tri[bad])] = False
    P[close] = target[close]
    return close


def _relax(P, verts, faces, movable, F, st, full, rng, f, fast=False):
    """Local edge relaxation (Fig. 6): greedy random moves of shared border vertices.

    ``P`` (p, 2) full-res positions of ``verts``; ``movable`` marks the shared
    border vertices where the mapping jumps.  For each, the error is the
    squared colour difference between this cluster's and the neighbour's
    texture at samples along the shared edges around it, weighted by the
    vertex's hat function; candidate moves are drawn in a disc of radius
    ``f`` pixels halved at each of three rounds, and the best is kept.
    ``fast``: sample the image with the compiled loop (same values).
    """
    mv = np.flatnonzero(movable)
    if mv.size == 0:
        return P
    n = int(F.max()) + 1
    pos = np.full((n, 2), np.nan)
    pos[verts] = P
    # neighbour positions per vertex (mean over textured corners)
    nb = st.agreed()
    cnt = np.where(np.isnan(nb[:, 0]), 0.0, 1.0)
    # shared edges of the cluster (both ends with a neighbour position)
    e = np.concatenate([F[faces][:, [0, 1]], F[faces][:, [1, 2]], F[faces][:, [2, 0]]])
    e = np.sort(e, axis=1)
    key = np.unique(e[:, 0] * n + e[:, 1])          # = np.unique(e, axis=0), without a
    e = np.stack([key // n, key % n], axis=1)       # structured sort
    both = (cnt[e[:, 0]] > 0) & (cnt[e[:, 1]] > 0)
    e = e[both]
    if e.shape[0] == 0:
        return P
    ts = np.array([0.0, 0.25, 0.5, 0.75])
    vid = verts[mv]
    # per movable vertex: its shared edges, oriented from it
    ea = np.concatenate([e[:, 0], e[:, 1]])
    eb = np.concatenate([e[:, 1], e[:, 0]])
    slot = np.full(n, -1, np.int64)
    slot[vid] = np.arange(vid.size)
    sel = slot[ea] >= 0
    ea, eb, owner = ea[sel], eb[sel], slot[ea[sel]]
    if ea.size == 0:
        return P

    na, nbb = nb[ea], nb[eb]
    y = na[:, None, :] * (1 - ts)[None, :, None] + nbb[:, None, :] * ts[None, :, None]
    target = _sample(full, y.reshape(-1, 2), fast)   # the neighbour's texture along the edges
    b = pos[eb]

    # compiled: three colour channels (the order of np.sum checked for them), no NaN
    jit_err = fast and full.shape[2] == 3 and np.isfinite(b).all() and np.isfinite(target).all()

    def err(cand):                       # cand (k, 2) positions of the movable vertices
        if jit_err and np.isfinite(cand).all():
            return _relax_error_compiled(full, cand, owner, b, target, ts, vid.size)
        a = cand[owner]
        x = a[:, None, :] * (1 - ts)[None, :, None] + b[:, None, :] * ts[None, :, None]
        d = _sample(full, x.reshape(-1, 2), fast) - target
        w = np.broadcast_to((1 - ts)[None, :], x.shape[:2]).ravel()
        per = np.sum(d * d, axis=1) * w
        return np.bincount(np.repeat(owner, ts.size), weights=per, minlength=vid.size)

    cur = pos[vid].copy()
    e0 = err(cur)
    # search radius: the paper's disc, capped by a fifth of the shortest edge at the vertex
    elen = np.linalg.norm(pos[ea] - pos[eb], axis=1)
    short = np.full(vid.size, np.inf)
    np.minimum.at(short, owner, elen)
    ff = F[faces]
    loc = np.searchsorted(verts, ff)
    for a_, b_ in ((0, 1), (1, 2), (2, 0)):
        own = slot[ff[:, a_]]
        ok_ = own >= 0
        np.minimum.at(short, own[ok_], np.linalg.norm(P[loc[ok_, a_]] - P[loc[ok_, b_]], axis=1))
    radius = np.minimum(float(f), RELAX_EDGE_FRACTION * np.where(np.isfinite(short), short, 0.0))

    def areas(posv):
        t = posv[loc]
        return (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
            - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])

    a_before = areas(P)
    if jit_err and np.isfinite(cur).all() and np.isfinite(radius).all():
        # the same draws (one (18, 2, k) block is the 36 calls' stream, in order), the
        # same offsets (numpy's own sqrt, cos, sin of them) and the candidates' errors
        # and greedy updates in one compiled loop
        u = rng.random((3 * 6, 2, vid.size))
        r = (radius * np.array([1.0, 0.5, 0.25]).repeat(6)[:, None]) * np.sqrt(u[:, 0])
        t = u[:, 1] * 2 * np.pi
        off = np.stack([r * np.cos(t), r * np.sin(t)], 2)
        cur = _relax_search_compiled(full, cur, off, owner, b, target, ts, e0)
    else:
        for _ in range(3):
            for _k in range(6):
                r = radius * np.sqrt(rng.random(vid.size))
                t = rng.random(vid.size) * 2 * np.pi
                cand = cur + np.stack([r * np.cos(t), r * np.sin(t)], 1)
                e1 = err(cand)
                better = e1 < e0
                cur[better] = cand[better]
                e0 = np.where(better, e1, e0)
            radius = radius * 0.5
    # undo moves that fold or crush a face of the cluster
    for _ in range(3):
        trial = P.copy()
        trial[mv] = cur
        a_after = areas(trial)
        crushed = (a_after * np.sign(a_before) < 0.3 * np.abs(a_before))
        if not crushed.any():
            break
        back = np.unique(ff[crushed])
        back = back[slot[back] >= 0]
        cur[slot[back]] = P[mv][slot[back]]
    out = P.copy()
    out[mv] = cur
    return out
