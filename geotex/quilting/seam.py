"""Boundary loops of open surface pieces and the strip that zips two loops together.

Used by :mod:`geotex.quilting.merge` after a graph cut opened two elements:
each kept piece has boundary loops (traced along boundary half-edges, so a
loop runs in the direction its faces use it), loops of the two pieces are
paired by proximity, and every pair is closed by a triangle strip built with
the shortest-diagonal rule (made globally optimal by dynamic programming).
The strip uses every boundary half-edge in the
opposite direction, so an outward-oriented piece stays outward-oriented.
"""

from __future__ import annotations

import numpy as np

from geotex.mesh.geometry import face_normals
from geotex.mesh.topology import edge_topology, half_edges

__all__ = ["boundary_loops", "closest_on_polyline", "pair_loops", "strip_between",
           "seam_quality"]


def boundary_loops(F: np.ndarray, n_vertices: int) -> list[np.ndarray] | None:
    """Trace the boundary loops of a triangle mesh.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n_vertices : int

    Returns
    -------
    list of numpy.ndarray (k_i,) int64, or None
        Vertex loops in boundary half-edge order (``loop[i] -> loop[i + 1]``
        is an edge of a face).  ``None`` when the boundary is not a set of
        simple loops (a vertex with several outgoing boundary half-edges, or
        a non-manifold edge).
    """
    if F.shape[0] == 0:
        return []
    topo = edge_topology(F, n_vertices)
    if topo.non_manifold.size:
        return None
    he = half_edges(F)
    bnd = he[topo.face_count[topo.half_to_edge] == 1]
    if bnd.shape[0] == 0:
        return []
    nxt = np.full(n_vertices, -1, dtype=np.int64)
    if np.unique(bnd[:, 0]).size != bnd.shape[0]:
        return None
    nxt[bnd[:, 0]] = bnd[:, 1]
    seen = np.zeros(n_vertices, dtype=bool)
    loops = []
    for start in bnd[:, 0]:
        if seen[start]:
            continue
        loop = [start]
        seen[start] = True
        v = nxt[start]
        while v != start:
            if v < 0 or seen[v]:
                return None
            seen[v] = True
            loop.append(v)
            v = nxt[v]
        loops.append(np.asarray(loop, dtype=np.int64))
    return loops


def closest_on_polyline(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Closest points of the closed polyline ``Q`` (k, 3) to the points ``P`` (p, 3)."""
    A = Q
    B = np.roll(Q, -1, axis=0)
    AB = B - A
    den = np.einsum("ij,ij->i", AB, AB)
    den = np.where(den > 0, den, 1.0)
    s = np.einsum("pij,ij->pi", P[:, None, :] - A[None], AB) / den
    s = np.clip(s, 0.0, 1.0)
    C = A[None] + s[..., None] * AB[None]
    d = np.einsum("pij,pij->pi", C - P[:, None, :], C - P[:, None, :])
    best = np.argmin(d, axis=1)
    return C[np.arange(P.shape[0]), best]


def pair_loops(loops_a: list, VA: np.ndarray, loops_b: list, VB: np.ndarray
               ) -> list[tuple[int, int]] | None:
    """Pair loops of two pieces one to one by the distance of their centroids.

    Returns
    -------
    list of (i, j) or None
        ``None`` when the loop counts differ or the pairing is not mutual.
    """
    if len(loops_a) != len(loops_b):
        return None
    if not loops_a:
        return []
    ca = np.array([VA[l].mean(axis=0) for l in loops_a])
    cb = np.array([VB[l].mean(axis=0) for l in loops_b])
    D = np.linalg.norm(ca[:, None] - cb[None], axis=2)
    pairs = []
    used_b = set()
    for i in np.argsort(D.min(axis=1), kind="stable"):
        j = int(np.argmin(D[i]))
        if j in used_b:
            return None
        used_b.add(j)
        pairs.append((int(i), j))
    return pairs


def strip_between(a: np.ndarray, Pa: np.ndarray, b: np.ndarray, Pb: np.ndarray
                  ) -> np.ndarray:
    """Triangulate the band between two loops with the shortest total diagonals.

    Dynamic programming over the two loops (the shortest-diagonal rule made
    globally optimal): after choosing the start of ``b`` that lines the two
    loops up best (centroids matched, vertices walked in step), every
    triangle spans one edge of one loop and a vertex of the other, and the
    sum of the diagonals' lengths is minimal.

    Parameters
    ----------
    a : numpy.ndarray, (na,) int64
        Loop of piece A in its boundary half-edge order (global vertex ids).
    Pa : numpy.ndarray, (na, 3) float64
        Positions of ``a``.
    b : numpy.ndarray, (nb,) int64
        Loop of piece B in *its* boundary half-edge order (global ids).
    Pb : numpy.ndarray, (nb, 3) float64

    Returns
    -------
    numpy.ndarray, (na + nb, 3) int64
        Strip triangles; each boundary half-edge of both loops appears once,
        reversed, so the result is closed and consistently oriented.
    """
    # B runs the other way along the seam: walk it backwards, starting where
    # the two loops line up best once their centroids are matched (the loops
    # may be offset by more than the element is thick, e.g. two cross-sections
    # of a strand on a slope: then the vertex of B nearest to a[0] can lie on
    # the wrong side and the strip would twist)
    b = b[::-1]
    Pb = Pb[::-1]
    na, nb = a.size, b.size
    Ra, Rb = Pa - Pa.mean(axis=0), Pb - Pb.mean(axis=0)
    walk = np.floor(np.arange(na) * nb / na + 0.5).astype(np.int64)
    idx = (np.arange(nb)[:, None] + walk[None, :]) % nb                 # (starts, na)
    spread = np.linalg.norm(Rb[idx] - Ra[None], axis=2).sum(axis=1)
    start = int(np.argmin(spread))
    b = np.roll(b, -start)
    Pb = np.roll(Pb, -start, axis=0)
    ia = np.arange(na + 1) % na
    ib = np.arange(nb + 1) % nb
    D = np.linalg.norm(Pa[ia][:, None, :] - Pb[ib][None, :, :], axis=2)  # (na+1, nb+1)
    cost = np.full((na + 1, nb + 1), np.inf)
    cost[0, 0] = 0.0
    came = np.zeros((na + 1, nb + 1), dtype=np.int8)  # 1: advanced a, 2: advanced b
    # The path starts by advancing a and ends by advancing b, and never
    # visits (na, 0): otherwise a diagonal would be used twice around the
    # cycle (a non-manifold edge)
    blocked = np.zeros((na + 1, nb + 1), dtype=bool)
    blocked[0, 1:] = True
    blocked[:na, nb] = True
    blocked[na, 0] = True
    for i in range(na + 1):
        for j in range(nb + 1):
            if (i == 0 and j == 0) or blocked[i, j]:
                continue
            ca = cost[i - 1, j] + D[i, j] if i > 0 else np.inf
            cb = cost[i, j - 1] + D[i, j] if j > 0 else np.inf
            if ca <= cb:
                cost[i, j], came[i, j] = ca, 1
            else:
                cost[i, j], came[i, j] = cb, 2
    steps = []
    i, j = na, nb
    while i or j:
        steps.append(came[i, j])
        if came[i, j] == 1:
            i -= 1
        else:
            j -= 1
    tris = np.empty((na + nb, 3), dtype=np.int64)
    i = j = 0
    for k, step in enumerate(reversed(steps)):
        if step == 1:
            tris[k] = (a[i % na], b[j % nb], a[(i + 1) % na])
            i += 1
        else:
            tris[k] = (b[j % nb], b[(j + 1) % nb], a[i % na])
            j += 1
    return tris


def seam_quality(V, F, ma, mb, loops_a, loops_b, off, pairs):
    """Largest loop-to-loop gap and largest normal jump (degrees) across the seam.

    ``F`` holds piece A's ``ma`` faces, then piece B's ``mb`` faces, then the
    strips.  The gap is the largest distance of a vertex of an A loop to its
    partner B loop.  The normal jump is the largest angle between the normals
    of the two faces on a loop edge, one of the piece and one of the strip:
    the bend the seam puts into the surface.  Loop edges run across the
    element (along a cut through it), so where the strip continues the two
    pieces smoothly the angle is as small as the element's own bends along
    its length, whatever creases its cross-section has.
    """
    gaps = [np.linalg.norm(V[loops_a[i]] - closest_on_polyline(V[loops_a[i]],
                                                               V[loops_b[j] + off]), axis=1).max()
            for i, j in pairs]
    topo = edge_topology(F, V.shape[0])
    ef = topo.edge_faces()[topo.face_count == 2]
    strip = ma + mb
    across = (ef[:, 0] >= strip) != (ef[:, 1] >= strip)
    if not across.any():
        return float(max(gaps)), float("nan")
    N = face_normals(V, F)
    cosang = np.einsum("ij,ij->i", N[ef[across, 0]], N[ef[across, 1]])
    return float(max(gaps)), float(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))).max())
