"""Boundary loops of open surface pieces and the strip that zips two loops together.

Used by :mod:`geotex.quilting.merge` after a graph cut opened two elements:
each kept piece has boundary loops (traced along boundary half-edges, so a
loop runs in the direction its faces use it), loops of the two pieces are
paired by proximity, and every pair is closed by a triangle strip built with
the shortest-diagonal rule (made globally optimal by dynamic programming), or
welded into one seam (:func:`zip_loops`) after both loops were moved to the
midpoints of corresponding points (:func:`matched_on_loops`).
The strip uses every boundary half-edge in the
opposite direction, so an outward-oriented piece stays outward-oriented.
"""

from __future__ import annotations

import numpy as np

from geotex.mesh.geometry import face_normals
from geotex.mesh.topology import edge_topology, half_edges

__all__ = ["boundary_loops", "closest_on_polyline", "matched_on_loops", "pair_loops",
           "strip_between", "zip_loops", "seam_normal_jumps"]


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


def _at_parameter(P: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Points of the closed polyline ``P`` (k, 3) at arc-length parameters ``t`` (in turns)."""
    seg = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    cum = np.r_[0.0, np.cumsum(seg)]
    s = np.mod(t, 1.0) * cum[-1]
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, P.shape[0] - 1)
    f = np.where(seg[i] > 0, (s - cum[i]) / np.where(seg[i] > 0, seg[i], 1.0), 0.0)
    return P[i] + f[:, None] * (np.roll(P, -1, axis=0)[i] - P[i])


def matched_on_loops(Pa: np.ndarray, Pb: np.ndarray, *, samples: int = 8
                     ) -> tuple[np.ndarray, np.ndarray] | None:
    """Corresponding points of two loops that run opposite ways along one seam.

    Each loop is parametrised by its arc length (in turns), ``b`` backwards
    (the two pieces' boundary loops run in opposite directions); the offset
    between the two parameters is the one that lines the loops up best once
    their centroids are matched (least squares over ``samples`` points per
    vertex of the longer loop, refined by a parabola through the best three
    offsets).  A vertex of one loop then corresponds to the point of the
    other loop at the same parameter.  Unlike the closest point, this keeps
    the order: two copies of one cross-section offset sideways or along the
    seam (e.g. a flat strand whose loops are half a ring apart) map onto
    each other vertex after vertex, so points moved toward their partners
    stay in the order of both loops.

    Parameters
    ----------
    Pa : numpy.ndarray, (na, 3) float64
        Loop of piece A, in its boundary half-edge order.
    Pb : numpy.ndarray, (nb, 3) float64
        Loop of piece B, in *its* boundary half-edge order.
    samples : int, optional
        Samples per vertex of the longer loop in the offset search.

    Returns
    -------
    (Qa, Qb) : numpy.ndarray (na, 3) and (nb, 3) float64, or None
        ``Qa[i]``: the point of loop ``b`` corresponding to ``Pa[i]``;
        ``Qb[j]``: the point of loop ``a`` corresponding to ``Pb[j]``.
        ``None`` when a loop has fewer than 3 vertices or no length.
    """
    na, nb = Pa.shape[0], Pb.shape[0]
    if na < 3 or nb < 3:
        return None
    Rb = Pb[::-1]
    la = np.linalg.norm(np.roll(Pa, -1, axis=0) - Pa, axis=1)
    lb = np.linalg.norm(np.roll(Rb, -1, axis=0) - Rb, axis=1)
    if not (la.sum() > 0 and lb.sum() > 0):
        return None
    ta = np.r_[0.0, np.cumsum(la)[:-1]] / la.sum()
    tb = np.r_[0.0, np.cumsum(lb)[:-1]] / lb.sum()
    k = samples * max(na, nb)
    u = np.arange(k) / k
    Sa = _at_parameter(Pa, u)
    Sb = _at_parameter(Rb, u)
    Sa -= Sa.mean(axis=0)
    Sb -= Sb.mean(axis=0)
    # cost of each cyclic offset of b's samples against a's (circular cross-correlation)
    cost = -np.array([np.einsum("ij,ij->", Sa, np.roll(Sb, -m, axis=0)) for m in range(k)])
    m = int(np.argmin(cost))
    c0, c1, c2 = cost[m - 1], cost[m], cost[(m + 1) % k]
    den = c0 - 2.0 * c1 + c2
    frac = 0.5 * (c0 - c2) / den if den > 0 else 0.0
    shift = (m + float(np.clip(frac, -0.5, 0.5))) / k
    Qa = _at_parameter(Rb, ta + shift)
    Qb = _at_parameter(Pa, tb - shift)[::-1]
    return Qa, Qb


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
    na, nb = a.size, b.size
    start, steps = _strip_steps(Pa, Pb)
    b = np.roll(b[::-1], -start)
    tris = np.empty((na + nb, 3), dtype=np.int64)
    i = j = 0
    for k, step in enumerate(steps):
        if step == 1:
            tris[k] = (a[i % na], b[j % nb], a[(i + 1) % na])
            i += 1
        else:
            tris[k] = (b[j % nb], b[(j + 1) % nb], a[i % na])
            j += 1
    return tris


def zip_loops(F: np.ndarray, a: np.ndarray, Pa: np.ndarray, b: np.ndarray, Pb: np.ndarray,
              *, weld: float = 0.0) -> tuple[np.ndarray, np.ndarray, dict] | None:
    """Weld two boundary loops into one seam without a strip (a zipper).

    The two loops are interleaved in the order of the shortest-diagonal walk
    (:func:`strip_between`): every vertex of ``b`` that the walk visits
    between ``a[i]`` and ``a[i + 1]`` is inserted into the boundary edge
    ``a[i] -> a[i + 1]`` (its face becomes a fan of triangles over the same
    third vertex), and likewise every vertex of ``a`` into the edges of
    ``b``.  Both loops then run through the same ``na + nb`` vertices, in
    opposite directions, so the two pieces share the seam: closed, no gap,
    no new vertices.  A vertex of ``b`` that the walk visits next to a
    vertex of ``a`` closer than ``weld`` times the shorter loop edge at
    either becomes that vertex (corresponding loops: copies of one
    cross-section), so the fans do not get triangles of nearly zero width.
    The caller places the seam vertices (they should lie on one curve, in
    the walk's order, or the fans fold) and drops the vertices of ``b``
    that were welded.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
        Faces of both pieces (global vertex ids).
    a, b : numpy.ndarray, (na,) and (nb,) int64
        The loops in their pieces' boundary half-edge order (global ids).
    Pa, Pb : numpy.ndarray, (na, 3) and (nb, 3) float64
        Their positions (for the walk and the weld test).
    weld : float, optional
        Weld distance relative to the loop edge lengths (0: never).

    Returns
    -------
    faces : numpy.ndarray, (m + k, 3) int64
        The faces with the boundary faces of both loops split into fans (a
        split face keeps its row, the other triangles of its fan come last).
    parent : numpy.ndarray, (m + k,) int64
        Row of ``F`` every face comes from.
    welded : dict of int -> int
        Vertex of ``b`` -> the vertex of ``a`` that replaced it.

    Or ``None`` when a boundary half-edge of a loop is not used by exactly
    one face.
    """
    na, nb = a.size, b.size
    start, steps = _strip_steps(Pa, Pb)
    rb = np.roll(b[::-1], -start)
    order = []                                   # the seam: vertices in walk order
    i = j = 0
    for step in steps:
        if step == 1:
            i += 1
            order.append(int(a[i % na]))
        else:
            j += 1
            order.append(int(rb[j % nb]))
    side = {int(v): 0 for v in a}
    side.update({int(v): 1 for v in b})
    pos = {int(v): p for v, p in zip(a.tolist(), Pa)}
    pos.update({int(v): p for v, p in zip(b.tolist(), Pb)})
    ea = np.linalg.norm(Pa - np.roll(Pa, -1, axis=0), axis=1)
    eb = np.linalg.norm(Pb - np.roll(Pb, -1, axis=0), axis=1)
    reach = {int(v): min(x, y) for v, x, y in zip(a.tolist(), ea, np.roll(ea, 1))}
    reach.update({int(v): min(x, y) for v, x, y in zip(b.tolist(), eb, np.roll(eb, 1))})
    rep = {}
    taken = set()
    for k in range(len(order)):
        u, v = order[k], order[(k + 1) % len(order)]
        if side[u] == side[v] or u in taken or v in taken:
            continue
        if np.linalg.norm(pos[u] - pos[v]) < weld * min(reach[u], reach[v]):
            ua, vb = (u, v) if side[u] == 0 else (v, u)
            rep[vb] = ua
            taken.update((u, v))
    order = [v for v in order if v not in rep]
    where = {v: k for k, v in enumerate(order)}
    where.update({vb: where[va] for vb, va in rep.items()})
    n = len(order)
    faces = [list(f) for f in F.tolist()]
    parent = list(range(len(faces)))
    owner = {}
    for f, (x, y, z) in enumerate(faces):
        for u, v in ((x, y), (y, z), (z, x)):
            owner[(u, v)] = f
    jobs = []
    # edges of A run along the walk; those of B against it
    for k in range(na):
        u, v = int(a[k]), int(a[(k + 1) % na])
        ku, kv = where[u], where[v]
        jobs.append((u, v, [order[(ku + t) % n] for t in range(1, (kv - ku) % n)]))
    for k in range(nb):
        u, v = int(b[k]), int(b[(k + 1) % nb])
        ku, kv = where[u], where[v]
        between = [order[(kv + t) % n] for t in range(1, (ku - kv) % n)]
        jobs.append((u, v, between[::-1]))
    if any((u, v) not in owner or (v, u) in owner for u, v, _ in jobs):
        return None
    for u, v, ins in jobs:
        f = owner[(u, v)]
        if not ins:
            continue
        x, y, z = faces[f]
        c = ({x, y, z} - {u, v}).pop()
        chain = [u, *ins, v]
        fan = [[chain[t], chain[t + 1], c] for t in range(len(chain) - 1)]
        faces[f] = fan[0]
        owner[(c, u)] = f
        for t, tri in enumerate(fan[1:], 1):
            faces.append(tri)
            parent.append(parent[f])
            owner[(tri[0], tri[1])] = len(faces) - 1
        owner[(v, c)] = len(faces) - 1 if len(fan) > 1 else f
        del owner[(u, v)]
    out = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if rep:
        alias = np.arange(max(int(out.max()) + 1, 1))
        alias[list(rep)] = list(rep.values())
        out = alias[out]
    return out, np.asarray(parent, dtype=np.int64), rep


def _strip_steps(Pa: np.ndarray, Pb: np.ndarray) -> tuple[int, list[int]]:
    """Start of the reversed ``b`` loop and the steps of the shortest-diagonal walk.

    ``b`` runs the other way along the seam: it is walked backwards
    (``b[::-1]`` rolled by ``start``).  Each step advances ``a`` (1) or ``b``
    (2); the walk starts by advancing ``a`` and ends by advancing ``b``.
    """
    # B runs the other way along the seam: walk it backwards, starting where
    # the two loops line up best once their centroids are matched (the loops
    # may be offset by more than the element is thick, e.g. two cross-sections
    # of a strand on a slope: then the vertex of B nearest to a[0] can lie on
    # the wrong side and the strip would twist)
    Pb = Pb[::-1]
    na, nb = Pa.shape[0], Pb.shape[0]
    Ra, Rb = Pa - Pa.mean(axis=0), Pb - Pb.mean(axis=0)
    walk = np.floor(np.arange(na) * nb / na + 0.5).astype(np.int64)
    idx = (np.arange(nb)[:, None] + walk[None, :]) % nb                 # (starts, na)
    spread = np.linalg.norm(Rb[idx] - Ra[None], axis=2).sum(axis=1)
    start = int(np.argmin(spread))
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
    return start, steps[::-1]


def seam_normal_jumps(V: np.ndarray, F: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Normal jumps (degrees) across the seams between differently labelled faces.

    ``labels`` (m,) tells the pieces apart (e.g. 0 for piece A, 1 for piece
    B, 2 for a stitch strip).  At every edge whose two faces carry different
    labels, the angle between the two face normals: the bend the seam puts
    into the surface.  Seams run across the element (along a cut through
    it), so where the join continues the two pieces smoothly the angle is as
    small as the element's own bends along its length, whatever creases its
    cross-section has.

    Returns
    -------
    numpy.ndarray, (k,) float64
        One angle per seam edge (empty when there is none).
    """
    topo = edge_topology(F, V.shape[0])
    ef = topo.edge_faces()[topo.face_count == 2]
    across = labels[ef[:, 0]] != labels[ef[:, 1]]
    N = face_normals(V, F)
    cosang = np.einsum("ij,ij->i", N[ef[across, 0]], N[ef[across, 1]])
    return np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
