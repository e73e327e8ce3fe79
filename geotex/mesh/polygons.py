"""Triangulating polygon faces (quads and n-gons, convex or not)."""

from __future__ import annotations

import manifold3d
import numpy as np

__all__ = ["polygon_triangle_corners"]


def _starts(counts: np.ndarray) -> np.ndarray:
    starts = np.zeros(counts.shape[0], dtype=np.int64)
    if counts.size > 1:
        np.cumsum(counts[:-1], out=starts[1:])
    return starts


def _newell_normals(P: np.ndarray) -> np.ndarray:
    """Newell normals of polygons given as ``(p, k, 3)`` corner positions."""
    Q = np.roll(P, -1, axis=1)
    return np.stack([((P[..., 1] - Q[..., 1]) * (P[..., 2] + Q[..., 2])).sum(1),
                     ((P[..., 2] - Q[..., 2]) * (P[..., 0] + Q[..., 0])).sum(1),
                     ((P[..., 0] - Q[..., 0]) * (P[..., 1] + Q[..., 1])).sum(1)], axis=1)


def _quad_corners(P: np.ndarray) -> np.ndarray:
    """Local corner triples (q, 2, 3) splitting each quad along its better diagonal."""
    N = _newell_normals(P)
    a = np.array([[0, 1, 2], [0, 2, 3]])
    b = np.array([[1, 2, 3], [1, 3, 0]])

    def valid(split):
        ok = np.ones(P.shape[0], dtype=bool)
        for tri in split:
            n = np.cross(P[:, tri[1]] - P[:, tri[0]], P[:, tri[2]] - P[:, tri[0]])
            ok &= np.einsum("ij,ij->i", n, N) > 0
        return ok

    va, vb = valid(a), valid(b)
    shorter_a = (np.linalg.norm(P[:, 0] - P[:, 2], axis=1)
                 <= np.linalg.norm(P[:, 1] - P[:, 3], axis=1))
    use_b = vb & (~va | ~shorter_a)
    return np.where(use_b[:, None, None], b[None], a[None])


def _ngon_corners(P: np.ndarray) -> np.ndarray:
    """Local corner triples (k - 2, 3) of one polygon with k >= 5 corners."""
    k = P.shape[0]
    fan = np.stack([np.zeros(k - 2, np.int64), np.arange(1, k - 1), np.arange(2, k)], axis=1)
    N = _newell_normals(P[None])[0]
    length = np.linalg.norm(N)
    if not np.isfinite(length) or length == 0:
        return fan
    N /= length
    u = P[1] - P[0] - N * ((P[1] - P[0]) @ N)
    if np.linalg.norm(u) == 0:
        u = np.cross(N, [1.0, 0.0, 0.0]) if abs(N[0]) < 0.9 else np.cross(N, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(N, u)
    Q = P - P.mean(axis=0)
    pts = np.ascontiguousarray(np.stack([Q @ u, Q @ v], axis=1))
    try:
        tri = np.asarray(manifold3d.triangulate([pts]), dtype=np.int64)
    except Exception:  # the triangulator rejects some self-overlapping outlines
        return fan
    if tri.shape != (k - 2, 3) or tri.min() < 0 or tri.max() >= k:
        return fan
    return _without_flat_triangles(pts, tri)


def _without_flat_triangles(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Flip interior edges until no triangle is flat (three collinear corners).

    Polygons with straight-angle corners (a vertex in the middle of a straight
    side, common in CAD exports) can be ear-clipped into zero-area triangles.
    A flat triangle (a, b, c) with b between a and c shares its long edge with
    a neighbour (c, a, d); flipping that edge gives (a, b, d) and (b, c, d).
    """
    tri = tri.copy()
    scale = float(np.ptp(pts, axis=0).max()) or 1.0

    def area2(t):
        a, b, c = pts[t[0]], pts[t[1]], pts[t[2]]
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    for _ in range(4 * len(tri)):
        flat = [i for i, t in enumerate(tri) if abs(area2(t)) <= 1e-12 * scale * scale]
        if not flat:
            break
        i = flat[0]
        t = tri[i]
        lengths = [np.linalg.norm(pts[t[(j + 2) % 3]] - pts[t[(j + 1) % 3]]) for j in range(3)]
        j = int(np.argmax(lengths))            # corner opposite the longest edge is straight
        b, c, a = t[j], t[(j + 1) % 3], t[(j + 2) % 3]
        nb = [n for n, u in enumerate(tri) if n != i and a in u and c in u]
        if not nb:
            break
        u = list(tri[nb[0]])
        d = [x for x in u if x not in (a, c)][0]
        tri[i] = (a, b, d)
        tri[nb[0]] = (b, c, d)
    return tri


def polygon_triangle_corners(counts, positions) -> tuple[np.ndarray, int]:
    """Triangulate polygons, returning the corners that make each triangle.

    Triangles pass through; quads are split along the diagonal that keeps
    both halves facing the polygon's normal (the shorter one when both do);
    polygons with five or more corners are ear-clipped in their best-fit
    plane (manifold3d's triangulator), so non-convex outlines do not produce
    overlapping triangles.  A polygon the triangulator rejects is fanned.

    Parameters
    ----------
    counts : array_like, (p,) int
        Corner count of each polygon, in order.
    positions : array_like, (sum(counts), 3) float64
        Position of every corner, polygon after polygon.

    Returns
    -------
    corners : numpy.ndarray, (t, 3) int64
        Indices into the flat corner list; triangle order follows polygon order.
    dropped : int
        Polygons with fewer than three corners (skipped).
    """
    counts = np.asarray(counts, dtype=np.int64)
    P = np.asarray(positions, dtype=np.float64)
    starts = _starts(counts)
    ntri = np.maximum(counts - 2, 0)
    first_tri = _starts(ntri)
    out = np.empty((int(ntri.sum()), 3), dtype=np.int64)
    tri_ids = counts == 3
    out[first_tri[tri_ids]] = starts[tri_ids, None] + np.arange(3)
    quads = np.flatnonzero(counts == 4)
    if quads.size:
        local = _quad_corners(P[starts[quads, None] + np.arange(4)])
        rows = first_tri[quads, None] + np.arange(2)
        out[rows] = starts[quads, None, None] + local
    for p in np.flatnonzero(counts >= 5):
        s, k = starts[p], counts[p]
        out[first_tri[p]:first_tri[p] + k - 2] = s + _ngon_corners(P[s:s + k])
    return out, int(np.count_nonzero(counts < 3))
