"""Triangulating polygon faces (quads and n-gons, convex or not)."""

from __future__ import annotations

import manifold3d
import numpy as np

from geotex.errors import InputError

__all__ = ["polygon_triangle_corners", "without_flat_triangles", "MAX_EAR_CLIP_CORNERS",
           "EAR_CLIP_BUDGET"]

#: Polygons with more corners than this are not ear-clipped (the triangulator
#: is quadratic on tangled outlines): convex ones are fanned, others refused.
MAX_EAR_CLIP_CORNERS = 10_000
#: Sum over ear-clipped polygons of corners squared (a few seconds at most).
EAR_CLIP_BUDGET = 250_000_000


class _TooLarge(Exception):
    def __init__(self, k):
        self.k = k


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


def _is_convex(pts: np.ndarray) -> bool:
    """Whether a 2-D outline turns one way only, once around (a convex polygon)."""
    d = np.roll(pts, -1, axis=0) - pts
    keep = np.abs(d).sum(axis=1) > 0
    d = d[keep]
    if d.shape[0] < 3:
        return False
    e = np.roll(d, -1, axis=0)
    cross = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
    dot = (d * e).sum(axis=1)
    turn = np.arctan2(cross, dot)
    return bool((turn >= -1e-12).all() and abs(turn.sum() - 2 * np.pi) < 1e-6)


def _ngon_corners(P: np.ndarray, *, ear_clip: bool = True) -> np.ndarray:
    """Local corner triples (k - 2, 3) of one polygon with k >= 5 corners.

    With ``ear_clip=False`` (a polygon beyond the triangulation budget) a
    convex polygon is fanned and any other raises :class:`InputError`.
    """
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
    if not ear_clip:
        if _is_convex(pts):
            return fan
        raise _TooLarge(k)
    try:
        tri = np.asarray(manifold3d.triangulate([pts]), dtype=np.int64)
    except Exception:  # the triangulator rejects some self-overlapping outlines
        return fan
    if tri.shape != (k - 2, 3) or tri.min() < 0 or tri.max() >= k:
        return fan
    return without_flat_triangles(pts, tri)


def without_flat_triangles(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Flip interior edges until no triangle is flat (three collinear corners).

    Polygons with straight-angle corners (a vertex in the middle of a straight
    side, common in CAD exports) can be ear-clipped into zero-area triangles.
    A flat triangle (a, b, c) with b between a and c shares its long edge with
    a neighbour (c, a, d); flipping that edge gives (a, b, d) and (b, c, d).
    """
    import heapq

    tri = tri.copy()
    scale = float(np.ptp(pts, axis=0).max()) or 1.0
    tol = 1e-12 * scale * scale

    xy = pts.tolist()                    # Python floats: cheap scalar arithmetic below

    def area2(t):
        a, b, c = xy[t[0]], xy[t[1]], xy[t[2]]
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    def length2(p, q):
        return (xy[p][0] - xy[q][0]) ** 2 + (xy[p][1] - xy[q][1]) ** 2

    A, B, C = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    areas = (B[:, 0] - A[:, 0]) * (C[:, 1] - A[:, 1]) - (B[:, 1] - A[:, 1]) * (C[:, 0] - A[:, 0])
    heap = np.flatnonzero(np.abs(areas) <= tol).tolist()
    if not heap:
        return tri
    # Undirected edge -> triangles holding it, updated as edges flip: every
    # flip costs O(1), so the pass is linear in the number of flips.
    edges: dict[tuple[int, int], set[int]] = {}

    def link(n, add):
        t = tri[n]
        for j in range(3):
            u, v = t[j], t[(j + 1) % 3]
            key = (u, v) if u < v else (v, u)
            if add:
                edges.setdefault(key, set()).add(n)
            else:
                edges[key].discard(n)

    tri = tri.tolist()
    for n in range(len(tri)):
        link(n, True)
    heapq.heapify(heap)
    for _ in range(4 * len(tri)):
        i = None
        while heap:                      # smallest triangle still flat
            cand = heapq.heappop(heap)
            if abs(area2(tri[cand])) <= tol:
                i = cand
                break
        if i is None:
            break
        t = tri[i]
        lengths = [length2(t[(j + 2) % 3], t[(j + 1) % 3]) for j in range(3)]
        j = lengths.index(max(lengths))        # corner opposite the longest edge is straight
        b, c, a = t[j], t[(j + 1) % 3], t[(j + 2) % 3]
        nb = sorted(edges.get((a, c) if a < c else (c, a), set()) - {i})
        if not nb:
            break
        k = nb[0]
        d = [x for x in tri[k] if x not in (a, c)][0]
        link(i, False)
        link(k, False)
        tri[i] = [a, b, d]
        tri[k] = [b, c, d]
        link(i, True)
        link(k, True)
        for n in (i, k):
            if abs(area2(tri[n])) <= tol:
                heapq.heappush(heap, n)
    return np.array(tri, dtype=np.int64).reshape(-1, 3)


def polygon_triangle_corners(counts, positions) -> tuple[np.ndarray, int]:
    """Triangulate polygons, returning the corners that make each triangle.

    Triangles pass through; quads are split along the diagonal that keeps
    both halves facing the polygon's normal (the shorter one when both do);
    polygons with five or more corners are ear-clipped in their best-fit
    plane (manifold3d's triangulator), so non-convex outlines do not produce
    overlapping triangles.  A polygon the triangulator rejects is fanned.
    The triangulator is quadratic on tangled outlines: beyond
    :data:`MAX_EAR_CLIP_CORNERS` corners, or once the corners squared of the
    polygons ear-clipped so far exceed :data:`EAR_CLIP_BUDGET`, a convex
    polygon is fanned and a non-convex one refused.

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

    Raises
    ------
    InputError
        If a non-convex polygon is beyond the triangulation limits.
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
    budget = EAR_CLIP_BUDGET
    for p in np.flatnonzero(counts >= 5):
        s, k = int(starts[p]), int(counts[p])
        ear_clip = k <= MAX_EAR_CLIP_CORNERS and k * k <= budget
        if ear_clip:
            budget -= k * k
        try:
            local = _ngon_corners(P[s:s + k], ear_clip=ear_clip)
        except _TooLarge:
            why = (f"more than {MAX_EAR_CLIP_CORNERS} corners" if k > MAX_EAR_CLIP_CORNERS
                   else "too many corners in all")
            raise InputError(f"polygon {int(p)} (0-based) has {k} corners and is not "
                             f"convex: {why} to triangulate in reasonable time; "
                             "triangulate it in the modeller first") from None
        out[first_tri[p]:first_tri[p] + k - 2] = s + local
    return out, int(np.count_nonzero(counts < 3))
