"""Union of a solid with closed elements that each cross only the solid (no boolean).

Most mapped texture elements meet nothing but the base. Their union with the
base is then local: every element face that crosses a base face is cut along
the segment where the two meet, and so is the base face; the pieces of
element faces inside the base and of base faces inside an element are
dropped, and the rest, stitched along the cuts, is the union. manifold3d's
boolean spends most of its time on exactly these crossings
(``benchmarks/results/union_split.md``). :func:`geotex.mapping.united_with_base`
uses it where the elements that meet nothing are most of the work
(``union="auto"``), without its own test of the flat pieces and with every
element or none: the main job's exact check of the written coordinates is its
guard, and a result that fails it is redone by manifold3d's boolean
(``benchmarks/results/union_own.md``).

Steps:

1. crossing face pairs (base face, element face) by the exact intersection
   test (:func:`~geotex.check.intersections.self_intersecting_pairs_between`,
   every element a part and the base one: the test sweeps the base and large
   elements in compact runs, so it stays local);
2. for every pair, which edges of one face cross the other face, decided by
   filtered orientation predicates (a sign is used only where the
   floating-point error bound proves it); a crossing point is keyed by
   (edge, crossed face), so the two faces of an edge and both surfaces share
   it. A pair whose signs cannot be proved (a corner on the other surface,
   coplanar faces, an edge through the other face's edge) leaves its element
   out: the caller unites it by a boolean;
3. each cut segment is directed along ``n_element x n_base``: to its left
   lies the part of the base face outside the element and the part of the
   element face inside the base. Every cut face is split along its segments
   (a planar graph of its edges and cuts in the face's plane, its faces
   walked, each triangulated by ear clipping, then its diagonals flipped
   toward better shapes: the triangles of one piece are coplanar, so this
   changes no geometry, and it joins a chain of nearly collinear cut points
   to the far corner instead of fanning flat triangles over it, which the
   float32 rounding folded: Spot 15k with studs at 3.7 mm had 4 crossing
   face pairs in its float32 result before); a piece is kept by the side of
   the cut it lies on;
4. with ``flat_test``, the flat pieces (slivers between nearly collinear
   cut points) are tested against the faces near them by the exact
   intersection test
   (:func:`~geotex.check.intersections.self_intersecting_pairs_touching`):
   a piece that meets another leaves its elements out, and the faces are
   split again without them;
5. faces not cut are kept or dropped with the cut face across an uncut edge
   (flood fill); the base where no element comes is kept, an element that
   crosses nothing is kept whole outside the base (a loose piece, as a
   boolean leaves it) and dropped inside it (winding number of a corner).
"""

from __future__ import annotations

from typing import NamedTuple

import igl
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from geotex.check.intersections import (self_intersecting_pairs_between,
                                        self_intersecting_pairs_touching)
from geotex.errors import GeotexError, InputError
from geotex.jit import compiled, helper
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import compacted, concatenated, edge_topology

__all__ = ["crossing_union", "CrossingUnion"]

#: Relative error bound of the orientation filter (Shewchuk's static bound for
#: orient3d is ~8e-16 of the permanent; this is far above it).
_FILTER = 1e-13
#: Pieces flatter than this (:func:`_shape_quality`) are tested against the
#: faces near them. Measured on Spot with studs (170k pieces): every piece that
#: met another had a quality below 1e-6; 2.2k pieces lie below 1e-3.
_FLAT = 1e-3


class CrossingUnion(NamedTuple):
    """Result of :func:`crossing_union`.

    Attributes
    ----------
    vertices : numpy.ndarray, (p, 3) float64
    faces : numpy.ndarray, (r, 3) int64
        The base united with every element not in ``left_out`` (closed,
        outward).
    left_out : numpy.ndarray, (k,) int64
        Sorted elements not united (a predicate could not decide how they
        cross the base, or a cut face could not be split): the caller adds
        them by a boolean.
    """

    vertices: np.ndarray
    faces: np.ndarray
    left_out: np.ndarray


@helper
def _orient(p, q, r, s):
    """Sign of the orientation of ``s`` against ``p, q, r``; 0 where the filter cannot tell."""
    ax, ay, az = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    bx, by, bz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    cx, cy, cz = s[0] - p[0], s[1] - p[1], s[2] - p[2]
    det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    perm = (abs(ax) * (abs(by * cz) + abs(bz * cy)) + abs(ay) * (abs(bx * cz) + abs(bz * cx))
            + abs(az) * (abs(bx * cy) + abs(by * cx)))
    if abs(det) <= _FILTER * perm:
        return 0
    return 1 if det > 0 else -1


@helper
def _pair_events(P, F, i, j, ev_edge, ev_face, ev_t):
    """Where the edges of face ``i`` cross face ``j`` and those of ``j`` cross ``i``.

    Fills the half-edge, the crossed face and the parameter along the
    half-edge of each crossing; returns their number (0: the faces do not
    cross, 2: they cross along a segment, -1: a filtered predicate could not
    decide, or the crossing is not a segment between two such points).
    """
    n = 0
    for side in range(2):
        a = i if side == 0 else j
        b = j if side == 0 else i
        B0, B1, B2 = P[F[b, 0]], P[F[b, 1]], P[F[b, 2]]
        s = np.empty(3, np.int64)
        for k in range(3):
            s[k] = _orient(B0, B1, B2, P[F[a, k]])
            if s[k] == 0:
                return -1
        if s[0] == s[1] and s[1] == s[2]:
            return 0
        for k in range(3):
            k1 = (k + 1) % 3
            if s[k] == s[k1]:
                continue
            u, v = P[F[a, k]], P[F[a, k1]]
            o0 = _orient(u, v, B0, B1)
            o1 = _orient(u, v, B1, B2)
            o2 = _orient(u, v, B2, B0)
            if o0 == 0 or o1 == 0 or o2 == 0:
                return -1
            if o0 == o1 and o1 == o2:
                if n == 2:
                    return -1
                # t along the half-edge F[a,k] -> F[a,k1] (plane distances)
                nx = (B1[1] - B0[1]) * (B2[2] - B0[2]) - (B1[2] - B0[2]) * (B2[1] - B0[1])
                ny = (B1[2] - B0[2]) * (B2[0] - B0[0]) - (B1[0] - B0[0]) * (B2[2] - B0[2])
                nz = (B1[0] - B0[0]) * (B2[1] - B0[1]) - (B1[1] - B0[1]) * (B2[0] - B0[0])
                du = nx * (u[0] - B0[0]) + ny * (u[1] - B0[1]) + nz * (u[2] - B0[2])
                dv = nx * (v[0] - B0[0]) + ny * (v[1] - B0[1]) + nz * (v[2] - B0[2])
                ev_edge[n] = 3 * a + k
                ev_face[n] = b
                ev_t[n] = du / (du - dv)
                n += 1
    if n != 2 and n != 0:
        return -1
    return n


@compiled
def _pair_event_loops(P, F, pairs):
    """:func:`_pair_events` of every row of ``pairs``."""
    m = pairs.shape[0]
    status = np.empty(m, np.int64)
    half = np.empty((m, 2), np.int64)
    face = np.empty((m, 2), np.int64)
    tt = np.empty((m, 2))
    e1 = np.empty(2, np.int64)
    f1 = np.empty(2, np.int64)
    t1 = np.empty(2)
    for r in range(m):
        st = _pair_events(P, F, pairs[r, 0], pairs[r, 1], e1, f1, t1)
        status[r] = st
        for c in range(2):
            half[r, c] = e1[c]
            face[r, c] = f1[c]
            tt[r, c] = t1[c]
    return status, half, face, tt


@helper
def _angle_sorted(ang, idx, n):
    """Sort ``idx[:n]`` by ``ang`` (insertion sort: a handful of items)."""
    for a in range(1, n):
        x = idx[a]
        b = a - 1
        while b >= 0 and ang[idx[b]] > ang[x]:
            idx[b + 1] = idx[b]
            b -= 1
        idx[b + 1] = x


@helper
def _earclip(xy, poly, n, out, no, block):
    """Triangles of the counter-clockwise polygon ``poly[:n]`` into ``out`` from row ``no``.

    Ear clipping, each time the ear of the best shape (area over the squared
    edge lengths) that no other corner touches or comes within ``block`` of
    the ear's size to: cut points of one flat face are collinear, and an ear
    over one of them would leave a flat triangle beside it. Returns the next
    free row, or -1 when no ear is found.
    """
    rem = poly[:n].copy()
    m = n
    while m > 3:
        best = -1
        bq = 0.0
        for a in range(m):
            p, q, r = rem[(a - 1) % m], rem[a], rem[(a + 1) % m]
            cr = _cross(xy, p, q, r)
            if cr <= 0:
                continue
            l2 = ((xy[q, 0] - xy[p, 0]) ** 2 + (xy[q, 1] - xy[p, 1]) ** 2
                  + (xy[r, 0] - xy[q, 0]) ** 2 + (xy[r, 1] - xy[q, 1]) ** 2
                  + (xy[p, 0] - xy[r, 0]) ** 2 + (xy[p, 1] - xy[r, 1]) ** 2)
            quality = cr / l2
            if quality <= bq:
                continue
            ok = True
            for b in range(m):
                s = rem[b]
                if s == p or s == q or s == r:
                    continue
                # a point on the ear's edges, or this close to them, blocks it
                # too: cut points are rounded, and an ear over a nearly
                # collinear one leaves a flat triangle that folds (measured:
                # 1e-12 left 15 crossing pairs on Spot with studs, 1e-8 one,
                # 1e-6 none; the caller tries 1e-6, then 1e-12)
                tol = -block * l2
                if (_cross(xy, p, q, s) >= tol and _cross(xy, q, r, s) >= tol
                        and _cross(xy, r, p, s) >= tol):
                    ok = False
                    break
            if ok:
                best = a
                bq = quality
        if best < 0:
            return -1
        out[no, 0], out[no, 1], out[no, 2] = rem[(best - 1) % m], rem[best], rem[(best + 1) % m]
        no += 1
        for b in range(best, m - 1):
            rem[b] = rem[b + 1]
        m -= 1
    out[no, 0], out[no, 1], out[no, 2] = rem[0], rem[1], rem[2]
    return no + 1


@helper
def _cross(xy, a, b, c):
    """Twice the signed area of the 2-D triangle of points ``a, b, c`` of ``xy``."""
    return ((xy[b, 0] - xy[a, 0]) * (xy[c, 1] - xy[a, 1])
            - (xy[b, 1] - xy[a, 1]) * (xy[c, 0] - xy[a, 0]))


@helper
def _quality(xy, a, b, c):
    """Twice the area over the summed squared edges of 2-D triangle ``a, b, c`` (< 0 turned)."""
    l2 = ((xy[b, 0] - xy[a, 0]) ** 2 + (xy[b, 1] - xy[a, 1]) ** 2
          + (xy[c, 0] - xy[b, 0]) ** 2 + (xy[c, 1] - xy[b, 1]) ** 2
          + (xy[a, 0] - xy[c, 0]) ** 2 + (xy[a, 1] - xy[c, 1]) ** 2)
    if l2 <= 0:
        return 0.0
    return _cross(xy, a, b, c) / l2


@helper
def _flipped(xy, tris, nt):
    """Flip diagonals of the triangles ``tris[:nt]`` of one polygon toward better shapes.

    All triangles lie in one plane (the pieces of one cut face), so flipping
    the edge two of them share changes no geometry. An edge shared as
    ``a -> b`` by one and ``b -> a`` by another is flipped when both new
    triangles turn the right way and the worse of them has a better shape
    (:func:`_quality`) than the worse of the old two: ear clipping fans flat
    triangles over a chain of nearly collinear cut points, which the float32
    rounding folds; flipped, each chain point is joined to the far corner.
    Returns the number of flips.
    """
    flips = 0
    for _ in range(4 * nt + 4):
        changed = False
        for c in range(nt):
            for e in range(3):
                a, b, x = tris[c, e], tris[c, (e + 1) % 3], tris[c, (e + 2) % 3]
                d = -1
                y = -1
                for c2 in range(nt):
                    if c2 == c:
                        continue
                    for e2 in range(3):
                        if tris[c2, e2] == b and tris[c2, (e2 + 1) % 3] == a:
                            d = c2
                            y = tris[c2, (e2 + 2) % 3]
                if d < 0 or x == y:
                    continue
                old = min(_quality(xy, a, b, x), _quality(xy, b, a, y))
                new = min(_quality(xy, a, y, x), _quality(xy, y, b, x))
                if new <= old * (1.0 + 1e-9) or new <= 0.0:
                    continue
                # the new diagonal must not exist already (a polygon with
                # bridged holes passes some corners twice)
                dup = False
                for c3 in range(nt):
                    for e3 in range(3):
                        p, q = tris[c3, e3], tris[c3, (e3 + 1) % 3]
                        if (p == x and q == y) or (p == y and q == x):
                            dup = True
                if dup:
                    continue
                tris[c, 0], tris[c, 1], tris[c, 2] = a, y, x
                tris[d, 0], tris[d, 1], tris[d, 2] = y, b, x
                flips += 1
                changed = True
                break
        if not changed:
            break
    return flips


@helper
def _bridged(xy, nv, hf, ht, hk, hedge, nh, comp, maxh):
    """Connect every part of a face's cut that does not reach its edges to them.

    A cut loop inside one face (an element's whole footprint inside one base
    face) gets a bridge (two half-edges of kind 3, no cut) to the nearest
    point of the face's edges that it sees; returns the half-edge count, or
    -1 when no bridge is found.
    """
    for v in range(nv):
        comp[v] = v
    changed = True
    while changed:
        changed = False
        for h in range(nh):
            a, b = comp[hf[h]], comp[ht[h]]
            if a != b:
                m = min(a, b)
                comp[hf[h]] = m
                comp[ht[h]] = m
                changed = True
    while True:
        hv = -1
        for v in range(nv):
            if comp[v] != 0:
                hv = v
                break
        if hv < 0:
            return nh
        c = comp[hv]
        best = -1
        bestd = np.inf
        bh = -1
        for a in range(nv):
            if comp[a] != c:
                continue
            for b in range(nv):
                if comp[b] != 0:
                    continue
                dd = (xy[a, 0] - xy[b, 0]) ** 2 + (xy[a, 1] - xy[b, 1]) ** 2
                if dd >= bestd:
                    continue
                ok = True
                for h in range(0, nh, 2):
                    p, q = hf[h], ht[h]
                    if p == a or p == b or q == a or q == b:
                        continue
                    o1 = _cross(xy, a, b, p)
                    o2 = _cross(xy, a, b, q)
                    o3 = _cross(xy, p, q, a)
                    o4 = _cross(xy, p, q, b)
                    if (o1 * o2 <= 0) and (o3 * o4 <= 0):
                        ok = False
                        break
                if ok:
                    bestd = dd
                    best = b
                    bh = a
        if best < 0 or nh + 2 > maxh:
            return -1
        hf[nh], ht[nh], hk[nh], hedge[nh] = bh, best, 3, -1
        nh += 1
        hf[nh], ht[nh], hk[nh], hedge[nh] = best, bh, 3, -1
        nh += 1
        for v in range(nv):
            if comp[v] == c:
                comp[v] = 0


@compiled
def _split_loops(P, F, faces, seg_start, seg_list, seg_pq, bp_start, bp_list,
                bp_edge, bp_t, out_tri, out_keep, edge_keep):
    """Split every face of ``faces`` along its cut segments; see :func:`_pieces`.

    ``seg_list[seg_start[r]:seg_start[r + 1]]``: the cut segments of ``faces[r]``
    (rows of ``seg_pq``, directed so that the part of the face to keep lies on
    their left). ``bp_*[bp_start[r]:bp_start[r + 1]]``: the cut points on the
    face's edges (point, edge ``k`` of the face, parameter along the half-edge).
    Fills ``out_tri`` / ``out_keep`` with the pieces' triangles and
    ``edge_keep[r, k]`` with whether the piece at the start of edge ``k`` is
    kept; returns the triangles of every face, a status per face (0, or < 0:
    too many points -2, a piece without cut or not triangulated -3, a part of
    the cut not connected to the face's edges -4) and the triangle count.
    """
    nf = faces.shape[0]
    counts = np.zeros(nf, np.int64)
    status = np.zeros(nf, np.int64)
    no = 0
    MAXV = 1024
    gid = np.empty(MAXV, np.int64)
    xy = np.empty((MAXV, 2))
    # half-edges: from, to, kind (0 boundary, 1 segment forward (p->q), 2 segment reverse)
    MAXH = 4 * MAXV
    hf = np.empty(MAXH, np.int64)
    ht = np.empty(MAXH, np.int64)
    hk = np.empty(MAXH, np.int64)
    hedge = np.empty(MAXH, np.int64)   # boundary edge k for boundary half-edges going ccw
    ang = np.empty(MAXH)
    used = np.empty(MAXH, np.bool_)
    nxt = np.empty(MAXH, np.int64)
    outs = np.empty((MAXV, 16), np.int64)
    comp = np.empty(MAXV, np.int64)
    nout = np.empty(MAXV, np.int64)
    poly = np.empty(MAXH, np.int64)
    tris = np.empty((MAXH, 3), np.int64)
    for r in range(nf):
        f = faces[r]
        c0, c1, c2 = P[F[f, 0]], P[F[f, 1]], P[F[f, 2]]
        nx = (c1[1] - c0[1]) * (c2[2] - c0[2]) - (c1[2] - c0[2]) * (c2[1] - c0[1])
        ny = (c1[2] - c0[2]) * (c2[0] - c0[0]) - (c1[0] - c0[0]) * (c2[2] - c0[2])
        nz = (c1[0] - c0[0]) * (c2[1] - c0[1]) - (c1[1] - c0[1]) * (c2[0] - c0[0])
        ax = 0
        if abs(ny) > abs(nx) and abs(ny) >= abs(nz):
            ax = 1
        elif abs(nz) > abs(nx) and abs(nz) > abs(ny):
            ax = 2
        nd = nx if ax == 0 else (ny if ax == 1 else nz)
        u = (ax + 1) % 3
        w = (ax + 2) % 3
        if nd < 0:
            u, w = w, u
        nv = 0
        for k in range(3):
            gid[nv] = F[f, k]
            nv += 1
        # boundary chain per edge, sorted by t
        nh = 0
        fail = False
        b0, b1 = bp_start[r], bp_start[r + 1]
        for k in range(3):
            prev = k
            # collect the edge's boundary points, sort by t
            ids = np.empty(b1 - b0, np.int64)
            ts = np.empty(b1 - b0)
            cnt = 0
            for s in range(b0, b1):
                if bp_edge[s] == k:
                    ids[cnt] = bp_list[s]
                    ts[cnt] = bp_t[s]
                    cnt += 1
            order = np.argsort(ts[:cnt])
            for c in range(cnt):
                if nv >= MAXV:
                    fail = True
                    break
                gid[nv] = ids[order[c]]
                cur = nv
                nv += 1
                hf[nh], ht[nh], hk[nh], hedge[nh] = prev, cur, 0, k
                nh += 1
                hf[nh], ht[nh], hk[nh], hedge[nh] = cur, prev, 0, -1
                nh += 1
                prev = cur
            hf[nh], ht[nh], hk[nh], hedge[nh] = prev, (k + 1) % 3, 0, k
            nh += 1
            hf[nh], ht[nh], hk[nh], hedge[nh] = (k + 1) % 3, prev, 0, -1
            nh += 1
        if fail:
            status[r] = -2
            continue
        for s in range(seg_start[r], seg_start[r + 1]):
            g = seg_list[s]
            lp = -1
            lq = -1
            for v in range(nv):
                if gid[v] == seg_pq[g, 0]:
                    lp = v
                if gid[v] == seg_pq[g, 1]:
                    lq = v
            if lp < 0:
                if nv >= MAXV:
                    fail = True
                    break
                gid[nv] = seg_pq[g, 0]
                lp = nv
                nv += 1
            if lq < 0:
                if nv >= MAXV:
                    fail = True
                    break
                gid[nv] = seg_pq[g, 1]
                lq = nv
                nv += 1
            if nh + 2 > MAXH:
                fail = True
                break
            hf[nh], ht[nh], hk[nh], hedge[nh] = lp, lq, 1, -1
            nh += 1
            hf[nh], ht[nh], hk[nh], hedge[nh] = lq, lp, 2, -1
            nh += 1
        if fail:
            status[r] = -2
            continue
        for v in range(nv):
            xy[v, 0] = P[gid[v], u]
            xy[v, 1] = P[gid[v], w]
            nout[v] = 0
        nh = _bridged(xy, nv, hf, ht, hk, hedge, nh, comp, MAXH)
        if nh < 0:
            status[r] = -4
            continue
        for h in range(nh):
            a = hf[h]
            ang[h] = np.arctan2(xy[ht[h], 1] - xy[a, 1], xy[ht[h], 0] - xy[a, 0])
            if nout[a] >= 16:
                fail = True
                break
            outs[a, nout[a]] = h
            nout[a] += 1
        if fail:
            status[r] = -2
            continue
        for v in range(nv):
            _angle_sorted(ang, outs[v], nout[v])
        # twin of h is h ^ 1; next(h) = at ht[h], clockwise neighbour of twin
        for h in range(nh):
            v = ht[h]
            tw = h ^ 1
            pos = -1
            for c in range(nout[v]):
                if outs[v, c] == tw:
                    pos = c
            nxt[h] = outs[v, (pos - 1) % nout[v]]
            used[h] = False
        for k in range(3):
            edge_keep[r, k] = -1
        nt0 = no
        for h0 in range(nh):
            if used[h0]:
                continue
            # walk the face
            npoly = 0
            h = h0
            area = 0.0
            keep = -1
            bad = False
            while True:
                used[h] = True
                poly[npoly] = hf[h]
                npoly += 1
                area += xy[hf[h], 0] * xy[ht[h], 1] - xy[ht[h], 0] * xy[hf[h], 1]
                if hk[h] == 1 or hk[h] == 2:
                    kk = 1 if hk[h] == 1 else 0
                    if keep == -1:
                        keep = kk
                    elif keep != kk:
                        bad = True
                h = nxt[h]
                if h == h0 or npoly >= MAXH:
                    break
            if area <= 0:
                continue      # the outer face
            if bad or keep == -1:
                fail = True
                break
            # boundary edges of this piece
            h = h0
            while True:
                if hedge[h] >= 0 and hf[h] < 3:
                    edge_keep[r, hedge[h]] = keep
                h = nxt[h]
                if h == h0:
                    break
            nt = _earclip(xy, poly, npoly, tris, 0, 1e-6)
            if nt < 0:
                nt = _earclip(xy, poly, npoly, tris, 0, 1e-12)
            if nt < 0:
                fail = True
                break
            _flipped(xy, tris, nt)
            for c in range(nt):
                out_tri[no, 0] = gid[tris[c, 0]]
                out_tri[no, 1] = gid[tris[c, 1]]
                out_tri[no, 2] = gid[tris[c, 2]]
                out_keep[no] = keep
                no += 1
        if fail:
            status[r] = -3
            no = nt0
            continue
        counts[r] = no - nt0
    return counts, status, no


def _cut_points(W, H, h2e, pairs, half, crossed, t):
    """Crossing points keyed by (edge, crossed face): coordinates and the id of each pair's two."""
    key = h2e[half.ravel()] * len(H) + crossed.ravel()
    ukey, first, inv = np.unique(key, return_index=True, return_inverse=True)
    hs = half.ravel()[first]
    a0 = W[H[hs // 3, hs % 3]]
    a1 = W[H[hs // 3, (hs % 3 + 1) % 3]]
    points = a0 + t.ravel()[first][:, None] * (a1 - a0)
    return ukey // len(H), points, (len(W) + inv.ravel()).reshape(-1, 2)


def _normals(W, H, f):
    c = W[H[f]]
    return np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])


def _pieces(W, H, nbf, pairs, half, crossed, t, topo, edge_faces):
    """Cut faces split into pieces: ``(P, split, counts, status, tri, keep, edge_keep)``."""
    h2e = topo.half_to_edge
    cut_edge, points, pid = _cut_points(W, H, h2e, pairs, half, crossed, t)
    P = np.vstack([W, points])
    # along n_element x n_base the base outside the element lies left, the
    # element inside the base right: base faces take the segment that way,
    # element faces reversed, so the part to keep is on the left of both
    d = np.cross(_normals(W, H, pairs[:, 1]), _normals(W, H, pairs[:, 0]))
    along = np.einsum("ij,ij->i", P[pid[:, 1]] - P[pid[:, 0]], d) > 0
    seg_b = np.where(along[:, None], pid, pid[:, ::-1])
    seg_pq = np.ascontiguousarray(np.concatenate([seg_b, seg_b[:, ::-1]]))
    seg_face = np.concatenate([pairs[:, 0], pairs[:, 1]])
    # every cut point lies on the edges of both faces of its edge
    bfaces = edge_faces[cut_edge].ravel()
    bpoint = np.repeat(len(W) + np.arange(cut_edge.size), 2)
    bk = np.argmax(h2e[3 * bfaces[:, None] + np.arange(3)] == np.repeat(cut_edge, 2)[:, None],
                   axis=1)
    A = P[H[bfaces, bk]]
    B = P[H[bfaces, (bk + 1) % 3]]
    bt = np.einsum("ij,ij->i", P[bpoint] - A, B - A) / np.einsum("ij,ij->i", B - A, B - A)
    split = np.unique(np.concatenate([seg_face, bfaces]))
    r_seg = np.searchsorted(split, seg_face)
    o = np.argsort(r_seg, kind="stable")
    seg_start = np.searchsorted(r_seg[o], np.arange(split.size + 1))
    seg_list = o.astype(np.int64)
    r_bp = np.searchsorted(split, bfaces)
    o = np.argsort(r_bp, kind="stable")
    bp_start = np.searchsorted(r_bp[o], np.arange(split.size + 1))
    bp_list, bp_edge, bp_t = bpoint[o], bk[o].astype(np.int64), bt[o]
    cap = 2 * (3 * split.size + 2 * seg_face.size + 2 * bfaces.size) + 16
    tri = np.empty((cap, 3), dtype=np.int64)
    keep = np.empty(cap, dtype=np.int64)
    edge_keep = np.empty((split.size, 3), dtype=np.int64)
    counts, status, n = _split_loops(P, H, split, seg_start, seg_list, seg_pq, bp_start,
                                     bp_list, bp_edge, bp_t, tri, keep, edge_keep)
    return P, split, counts, status, tri[:n], keep[:n], edge_keep


def crossing_union(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray, *,
                   element: np.ndarray, flat_test: bool = True,
                   all_or_none: bool = False) -> CrossingUnion:
    """Union of a solid with closed elements that cross the solid but not each other.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        The base: closed, manifold, outward.
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64
        The elements: each connected component closed, manifold and outward,
        and no two of them meeting (:func:`geotex.mapping.union.element_contacts`
        finds those that do; they are not checked here).
    element : numpy.ndarray, (l,) int64
        Element of every face of ``G``, ``0 .. n_elements - 1``.
    flat_test : bool, optional
        Test the flat pieces of the cut faces against the faces near them
        (exact test) and leave out the elements of those that cross another
        (default). False skips it (0.4 s at ~370k faces): the caller must
        then check the result.
    all_or_none : bool, optional
        Stop as soon as one element would be left out, before the faces are
        kept or dropped and stitched: the result then has no vertices and no
        faces, and ``left_out`` lists the elements found so far (the caller
        unites the whole by a boolean instead).

    Returns
    -------
    CrossingUnion
        The united solid and the elements left out (with ``all_or_none``
        and elements left out: empty arrays and those elements).

    Raises
    ------
    InputError
        ``element`` is not one non-negative integer per face of ``G``.
    GeotexError
        The cut faces disagree on which side of the cut a part of a surface
        lies, or faces no element crosses fail (inputs that break the
        assumptions above).

    Notes
    -----
    Elements that cross nothing are kept whole outside the base (loose
    pieces, as a boolean leaves them) and dropped inside it. Same inputs,
    same bytes.
    """
    V, F = as_mesh_arrays(V, F)
    X, G = as_mesh_arrays(X, G)
    element = np.asarray(element)
    if (element.shape != (len(G),) or not np.issubdtype(element.dtype, np.integer)
            or (element.size and element.min() < 0)):
        raise InputError(f"element must be one non-negative integer per face, shape ({len(G)},), "
                         f"got {element.dtype} {element.shape}")
    element = element.astype(np.int64, copy=False)
    n_el = int(element.max()) + 1 if element.size else 0
    if n_el == 0:
        return CrossingUnion(V.copy(), F.copy(), np.zeros(0, dtype=np.int64))
    W, H = concatenated([(V, F), (X, G)])
    nbf = len(F)
    lab = np.concatenate([np.full(nbf, -1, dtype=np.int64), element])
    pairs = self_intersecting_pairs_between(
        W, H, lab + 1,
        side=np.concatenate([np.zeros(nbf, dtype=np.int64), np.ones(len(G), dtype=np.int64)]))
    status, half, crossed, t = _pair_event_loops(W, H, pairs)
    out = np.zeros(n_el, dtype=bool)
    out[lab[pairs[status < 0, 1]]] = True
    if all_or_none and out.any():
        return _none_united(out)
    cross = status == 2
    pairs, half, crossed, t = pairs[cross], half[cross], crossed[cross], t[cross]
    topo = edge_topology(H, len(W))
    edge_faces = topo.edge_faces()
    while True:
        use = ~out[lab[pairs[:, 1]]]
        P, split, counts, st, tri, keep, edge_keep = _pieces(
            W, H, nbf, pairs[use], half[use], crossed[use], t[use], topo, edge_faces)
        if np.any(st < 0):
            # a face not split: leave out its element, or every element
            # crossing that base face, and split again without them
            _leave_out(out, split[st < 0], nbf, lab, pairs)
            if all_or_none:
                return _none_united(out)
            continue
        kept = _kept_faces(V, F, X, G, H, nbf, lab, element, pairs[use], split, edge_keep, out,
                           topo, edge_faces)
        piece = keep == 1
        F2 = np.concatenate([H[kept], tri[piece]])
        if not flat_test:
            break
        # the exact test of the flat pieces against the faces near them: a
        # piece that crosses anything leaves out the elements it came from
        source = np.concatenate([np.flatnonzero(kept), np.repeat(split, counts)[piece]])
        rows = int(kept.sum()) + np.flatnonzero(_shape_quality(P, tri[piece]) < _FLAT)
        bad = (self_intersecting_pairs_touching(P, F2, rows) if rows.size
               else np.zeros((0, 2), dtype=np.int64))
        if bad.size == 0:
            break
        _leave_out(out, np.unique(source[bad.ravel()]), nbf, lab, pairs)
        if all_or_none:
            return _none_united(out)
    V2, F2 = compacted(P, F2)
    return CrossingUnion(V2, F2, np.flatnonzero(out))


def _none_united(out: np.ndarray) -> CrossingUnion:
    """The result of ``all_or_none`` when elements would be left out: no solid."""
    return CrossingUnion(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.flatnonzero(out))


def _shape_quality(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Twice the area over the longest edge squared of every triangle of ``T`` (0 flat)."""
    a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.maximum.reduce([np.einsum("ij,ij->i", b - a, b - a),
                                 np.einsum("ij,ij->i", c - b, c - b),
                                 np.einsum("ij,ij->i", a - c, a - c)])
    return area / np.maximum(longest, np.finfo(np.float64).tiny)


def _leave_out(out, faces, nbf, lab, pairs):
    """Mark the elements of ``faces``, and those crossing its base faces, as left out."""
    before = int(out.sum())
    out[lab[faces[faces >= nbf]]] = True
    out[lab[pairs[np.isin(pairs[:, 0], faces[faces < nbf]), 1]]] = True
    if int(out.sum()) == before:
        raise GeotexError("crossing_union: faces that no element crosses cannot be split or "
                          "meet others (a bug, or a base that crosses itself: the caller "
                          "falls back to a boolean)")


def _kept_faces(V, F, X, G, H, nbf, lab, element, pairs, split, edge_keep, out, topo,
                edge_faces):
    """Faces not cut that the union keeps (flood fill from the cut faces)."""
    n_el = out.size
    # faces not cut: kept or dropped with the cut face across an uncut edge
    is_split = np.zeros(len(H), dtype=bool)
    is_split[split] = True
    two = edge_faces[edge_faces[:, 1] >= 0]
    free = ~is_split[two[:, 0]] & ~is_split[two[:, 1]]
    graph = coo_matrix((np.ones(int(free.sum())), (two[free, 0], two[free, 1])),
                       shape=(len(H), len(H)))
    n_comp, comp = connected_components(graph, directed=False)
    side = np.full(n_comp, -1, dtype=np.int64)
    he = topo.half_to_edge[3 * split[:, None] + np.arange(3)]
    across = np.where(edge_faces[he, 0] == split[:, None], edge_faces[he, 1], edge_faces[he, 0])
    m = ~is_split[across] & (edge_keep >= 0)
    side[comp[across[m]]] = edge_keep[m]
    if np.any(side[comp[across[m]]] != edge_keep[m]):
        raise GeotexError("crossing_union: the cut faces disagree on a part of the surface "
                          "(a bug: the caller falls back to a boolean)")
    kept = np.where(side[comp] >= 0, side[comp] == 1, np.arange(len(H)) < nbf) & ~is_split
    kept[nbf:] &= ~out[element]
    # an element that crosses nothing is kept as it is where it lies outside
    # the base (a loose piece, as a boolean leaves it) and dropped inside
    alone = np.ones(n_el, dtype=bool)
    alone[lab[pairs[:, 1]]] = False
    alone &= ~out
    if alone.any():
        first = np.full(n_el, -1, dtype=np.int64)
        first[element[::-1]] = np.arange(len(G))[::-1]
        probe = np.ascontiguousarray(X[G[first[alone], 0]])
        outside = np.zeros(n_el, dtype=bool)
        outside[np.flatnonzero(alone)] = np.asarray(igl.fast_winding_number(V, F, probe)) < 0.5
        kept[nbf:] |= outside[element]
    return kept
