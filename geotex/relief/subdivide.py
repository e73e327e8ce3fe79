"""Adaptive edge-split refinement that keeps the base's shape exactly.

Every round splits, at its midpoint, each edge longer than the target
length; a face with one split edge becomes 2 triangles, with two split edges
3 (the quad cut along its shorter diagonal), with three 4.  Midpoints lie on
the base's flat faces, so the refined mesh is the base surface itself: sharp
creases (any dihedral angle) stay exactly where they were, and a closed
manifold stays closed and manifold.  Large refinements run compiled, one base
face at a time (see the notes above :func:`_refined_per_face`); small ones,
and bases with a face repeating a vertex or two faces on the same three
vertices (where vertices of different base faces can meet inside a face), run
as vectorized numpy rounds.  Both give the same arrays bit for bit.

Every refined face remembers its base face (``parent``) and, on request, the
barycentric coordinates of its corners in that face (``corner_bary``), so
per-corner data of the base (UVs, normals, masks) can be carried over
without a closest-point search.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled, helper
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import first_use_order

__all__ = ["RefinedMesh", "refined_by_edge_splits", "MAX_ROUNDS"]

#: Split rounds at most (each halves the longest edges).
MAX_ROUNDS = 40


@dataclass(frozen=True)
class RefinedMesh:
    """A base refined by edge splits.

    Attributes
    ----------
    vertices : numpy.ndarray, (p, 3) float64
        The base's vertices first (same indices), then the midpoints in
        order of first use in ``faces``.
    faces : numpy.ndarray, (k, 3) int64
        Grouped by base face (ascending ``parent``).
    parent : numpy.ndarray, (k,) int64
        Base face each refined face lies in.
    corner_bary : numpy.ndarray or None, (k, 3, 3) float32
        Barycentric coordinates of each refined face's corners in its parent
        face (only when asked for).
    rounds : int
        Split rounds done.
    """

    vertices: np.ndarray
    faces: np.ndarray
    parent: np.ndarray
    corner_bary: np.ndarray | None
    rounds: int


def _sq_rows(d: np.ndarray) -> np.ndarray:
    """Squared lengths of the rows of ``d`` (k, 3), summed as ``(x² + z²) + y²``:
    the order ``numpy.einsum("ij,ij->i")`` used on the machine this was written
    on, spelled out so the compiled path can repeat it exactly."""
    return (d[:, 0] * d[:, 0] + d[:, 2] * d[:, 2]) + d[:, 1] * d[:, 1]


def _rolled(A: np.ndarray, r: np.ndarray) -> np.ndarray:
    idx = (r[:, None] + np.arange(3)[None, :]) % 3
    return np.take_along_axis(A, idx if A.ndim == 2 else idx[:, :, None], axis=1)


def refined_by_edge_splits(V, F, max_edge: float, *, max_faces: int = 8_000_000,
                           corner_bary: bool = False) -> RefinedMesh:
    """Split edges at their midpoints until none is longer than ``max_edge``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    max_edge : float
        Longest edge allowed in the result (> 0, mesh units).
    max_faces : int, optional
        Stop with an error when a round would produce more faces.
    corner_bary : bool, optional
        Also return each refined corner's barycentric coordinates in its
        base face.

    Returns
    -------
    RefinedMesh

    Raises
    ------
    InputError
        On a non-positive ``max_edge`` or when the result would exceed
        ``max_faces`` faces.
    """
    V, F = as_mesh_arrays(V, F)
    L = float(max_edge)
    if not (math.isfinite(L) and L > 0):
        raise InputError(f"max_edge must be a positive number, got {max_edge!r}")
    L2 = L * L
    if F.shape[0] and _per_face_ok(V, F, L2):
        return _refined_compiled(V, F, L2, L, max_faces, corner_bary)
    parent = np.arange(F.shape[0], dtype=np.int64)
    B = None
    if corner_bary:
        B = np.broadcast_to(np.eye(3, dtype=np.float32), (F.shape[0], 3, 3)).copy()
    n = V.shape[0]
    Vall = V
    rounds = 0
    # faces already short on every side never change again; keep them aside
    done_F, done_P, done_B = [], [], []
    while F.shape[0] and rounds < MAX_ROUNDS:
        # a side's length is the same from both faces, so "long" needs no edge list
        A, B1, C = Vall[F[:, 0]], Vall[F[:, 1]], Vall[F[:, 2]]
        split = np.empty(F.shape, dtype=bool)             # side k: corner k -> k+1
        for k, (p, q) in enumerate(((A, B1), (B1, C), (C, A))):
            d = q - p
            split[:, k] = _sq_rows(d) > L2
        if not split.any():
            break
        cnt = split.sum(axis=1)
        grow = int((3 * (cnt == 3) + 2 * (cnt == 2) + (cnt == 1)).sum())
        total = sum(x.shape[0] for x in done_F) + F.shape[0] + grow
        if total > max_faces:
            raise InputError(_too_many(L, max_faces))
        # one midpoint per split edge: number the split sides' edges uniquely
        fi, k = np.nonzero(split)
        a = F[fi, k]
        b = F[fi, (k + 1) % 3]
        key = np.minimum(a, b) * np.int64(n) + np.maximum(a, b)
        uniq, inv = np.unique(key, return_inverse=True)
        lo, hi = uniq // n, uniq % n
        mid = 0.5 * (Vall[lo] + Vall[hi])
        M = np.full(F.shape, -1, dtype=np.int64)
        M[fi, k] = n + inv.ravel()
        n += mid.shape[0]
        Vall = np.concatenate([Vall, mid])
        outF, outP, outB = [], [], []
        c0 = cnt == 0
        # faces whose sides are all short: finished unless a neighbour splits them
        # later, which cannot happen (their sides are short and never split)
        done_F.append(F[c0]); done_P.append(parent[c0])
        if B is not None:
            done_B.append(B[c0])
        # one split side: rotate it to side 0 (a-b, midpoint m), faces (a,m,c) (m,b,c)
        s1 = np.flatnonzero(cnt == 1)
        if s1.size:
            r = np.argmax(split[s1], axis=1)
            f = _rolled(F[s1], r)
            m = _rolled(M[s1], r)[:, 0]
            a, b, c = f[:, 0], f[:, 1], f[:, 2]
            outF += [np.stack([a, m, c], 1), np.stack([m, b, c], 1)]
            outP += [parent[s1]] * 2
            if B is not None:
                bb = _rolled(B[s1], r)
                bm = 0.5 * (bb[:, 0] + bb[:, 1])
                outB += [np.stack([bb[:, 0], bm, bb[:, 2]], 1),
                         np.stack([bm, bb[:, 1], bb[:, 2]], 1)]
        # two split sides: rotate the short side to side 2 (c-a); m0 on a-b, m1 on b-c
        s2 = np.flatnonzero(cnt == 2)
        if s2.size:
            r = (np.argmin(split[s2], axis=1) + 1) % 3
            f = _rolled(F[s2], r)
            m = _rolled(M[s2], r)
            a, b, c = f[:, 0], f[:, 1], f[:, 2]
            m0, m1 = m[:, 0], m[:, 1]
            # quad a, m0, m1, c: cut along the shorter diagonal
            d1 = Vall[a] - Vall[m1]
            d2 = Vall[m0] - Vall[c]
            use_a = _sq_rows(d1) <= _sq_rows(d2)
            q1 = np.where(use_a[:, None], np.stack([a, m0, m1], 1), np.stack([a, m0, c], 1))
            q2 = np.where(use_a[:, None], np.stack([a, m1, c], 1), np.stack([m0, m1, c], 1))
            outF += [np.stack([m0, b, m1], 1), q1, q2]
            outP += [parent[s2]] * 3
            if B is not None:
                bb = _rolled(B[s2], r)
                ba, bbb, bc = bb[:, 0], bb[:, 1], bb[:, 2]
                b0, b1 = 0.5 * (ba + bbb), 0.5 * (bbb + bc)
                u = use_a[:, None, None]
                outB += [np.stack([b0, bbb, b1], 1),
                         np.where(u, np.stack([ba, b0, b1], 1), np.stack([ba, b0, bc], 1)),
                         np.where(u, np.stack([ba, b1, bc], 1), np.stack([b0, b1, bc], 1))]
        # three split sides: the usual 1 -> 4
        s3 = np.flatnonzero(cnt == 3)
        if s3.size:
            f, m = F[s3], M[s3]
            a, b, c = f[:, 0], f[:, 1], f[:, 2]
            m0, m1, m2 = m[:, 0], m[:, 1], m[:, 2]
            outF += [np.stack([a, m0, m2], 1), np.stack([m0, b, m1], 1),
                     np.stack([m2, m1, c], 1), np.stack([m0, m1, m2], 1)]
            outP += [parent[s3]] * 4
            if B is not None:
                bb = B[s3]
                ba, bbb, bc = bb[:, 0], bb[:, 1], bb[:, 2]
                b0, b1, b2 = 0.5 * (ba + bbb), 0.5 * (bbb + bc), 0.5 * (bc + ba)
                outB += [np.stack([ba, b0, b2], 1), np.stack([b0, bbb, b1], 1),
                         np.stack([b2, b1, bc], 1), np.stack([b0, b1, b2], 1)]
        F = np.concatenate(outF) if outF else F[:0]
        parent = np.concatenate(outP) if outP else parent[:0]
        if B is not None:
            B = np.concatenate(outB) if outB else B[:0]
        rounds += 1
    done_F.append(F); done_P.append(parent)
    if B is not None:
        done_B.append(B)
    Fout = np.ascontiguousarray(np.concatenate(done_F), dtype=np.int64)
    Pout = np.concatenate(done_P)
    Bout = np.concatenate(done_B) if B is not None else None
    # the rounds leave faces grouped by round and split kind, and midpoints by
    # round: put each base face's children together and number the midpoints
    # by first use, so later passes over the mesh read nearby memory
    group = np.argsort(Pout, kind="stable")
    Fout, Pout = Fout[group], Pout[group]
    Bout = Bout[group] if Bout is not None else None
    order = first_use_order(Fout, Vall.shape[0], start=V.shape[0])
    new_index = np.empty_like(order)
    new_index[order] = np.arange(order.size)
    Fout = new_index[Fout]
    return RefinedMesh(np.ascontiguousarray(Vall[order]), Fout, Pout, Bout, rounds)


def _too_many(L: float, max_faces: int) -> str:
    return (f"refining to edges of {L:.4g} needs more than {max_faces} faces; use a "
            "longer edge length (coarser resolution) or raise the face cap")


def _estimated_faces(V, F, L2: float) -> float:
    """About how many faces the refinement makes (``area / (0.14 L²)``, see
    :func:`geotex.relief.core.edge_length_for_faces`)."""
    with np.errstate(over="ignore", invalid="ignore"):        # huge parts: inf, fine here
        area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]),
                                    axis=1).sum()
    return float(area) / (0.14 * L2) + F.shape[0]


def _per_face_ok(V, F, L2: float) -> bool:
    """Whether the compiled per-face path applies: a large result, no face
    repeating a vertex, no two faces on the same three vertices."""
    if _estimated_faces(V, F, L2) < max(JIT_MIN_SIZE, 1):
        return False
    if ((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])).any():
        return False
    S = np.sort(F, axis=1)
    S = S[np.lexsort(S.T[::-1])]
    return not (S[1:] == S[:-1]).all(axis=1).any()


def _refined_compiled(V, F, L2: float, L: float, max_faces: int,
                      corner_bary: bool) -> RefinedMesh:
    n = V.shape[0]
    a = F.ravel()
    b = F[:, [1, 2, 0]].ravel()
    _, side_edge = np.unique(np.minimum(a, b) * np.int64(n) + np.maximum(a, b),
                             return_inverse=True)
    side_edge = np.ascontiguousarray(side_edge.reshape(-1, 3), dtype=np.int64)
    est = _estimated_faces(V, F, L2)
    # room for 1.5x the estimate (cylinders reach 1.0x, Spot 0.45x): growing copies and
    # faults the rows twice, while rows never written cost address space only
    cap = int(min(max(1.5 * est, 1024.0), float(max_faces) + 1.0))
    Fo, Po, Bo, Vo, nf, nv, rounds, failed = _refined_per_face(
        V, F, side_edge, float(L2), int(max_faces), MAX_ROUNDS, bool(corner_bary), cap)
    if failed:
        raise InputError(_too_many(L, max_faces))
    # the used rows, as views: the rows past them were never written, so they hold
    # address space but no memory (copying would touch every page twice)
    return RefinedMesh(Vo[:nv], Fo[:nf], Po[:nf], Bo[:nf] if corner_bary else None,
                       int(rounds))


# ---------------------------------------------------------------------------
# Compiled path: one base face at a time.
#
# Edge splitting never looks past a face: whether a side splits depends only on
# its length, a midpoint only on its two ends, so every base face can be refined
# on its own through all rounds and its faces written out in the final order
# (base faces ascending, then the rounds' order restricted to the face, which is
# what the numpy path's stable sort by parent gives).  Refined vertices are
# identified by integer barycentric coordinates (multiples of 2**-40: exact
# through MAX_ROUNDS halvings); a vertex on a base edge is shared with the
# other faces of that edge through a hash table keyed by (edge, position along
# it), and vertices are numbered by first use as they are written out.  The
# same floating-point operations in the same order as the numpy path: the
# result is equal bit for bit (tested).

#: Integer barycentric unit of the compiled path (2**MAX_ROUNDS).
_ONE = 1 << MAX_ROUNDS


@helper
def _side_sq(P, p, q):
    """Squared length of ``P[q] - P[p]`` summed as :func:`_sq_rows` sums it."""
    dx = P[q, 0] - P[p, 0]
    dy = P[q, 1] - P[p, 1]
    dz = P[q, 2] - P[p, 2]
    return (dx * dx + dz * dz) + dy * dy


@helper
def _rows_i(a, need):
    """``a`` (k, 3) int64 with room for ``need`` rows (doubling)."""
    if need <= a.shape[0]:
        return a
    b = np.empty((max(need, 2 * a.shape[0]), 3), dtype=np.int64)
    b[:a.shape[0]] = a
    return b


@helper
def _rows_f(a, need):
    if need <= a.shape[0]:
        return a
    b = np.empty((max(need, 2 * a.shape[0]), 3), dtype=np.float64)
    b[:a.shape[0]] = a
    return b


@helper
def _rows_f32(a, need):
    if need <= a.shape[0]:
        return a
    b = np.empty((max(need, 2 * a.shape[0]), 3), dtype=np.float32)
    b[:a.shape[0]] = a
    return b


@helper
def _rows_b(a, need):
    if need <= a.shape[0]:
        return a
    b = np.empty((max(need, 2 * a.shape[0]), 3, 3), dtype=np.float32)
    b[:a.shape[0]] = a
    return b


@helper
def _rows_bool(a, need):
    if need <= a.shape[0]:
        return a
    b = np.zeros((max(need, 2 * a.shape[0]), 3), dtype=np.bool_)
    b[:a.shape[0]] = a
    return b


@helper
def _rows_1(a, need):
    if need <= a.shape[0]:
        return a
    b = np.empty(max(need, 2 * a.shape[0]), dtype=np.int64)
    b[:a.shape[0]] = a
    return b


@helper
def _slot(k0, k1, mask):
    """Hash slot of the key pair (both >= 0): splitmix64's finaliser of a
    mix of the two, so keys with many trailing zero bits (dyadic positions)
    still spread over the low bits."""
    h = np.uint64(k0) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(k1)
    h ^= h >> np.uint64(30)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(27)
    h *= np.uint64(0x94D049BB133111EB)
    h ^= h >> np.uint64(31)
    return np.int64(h & np.uint64(mask))


@compiled
def _refined_per_face(V, F, side_edge, L2, max_faces, max_rounds, want_bary, cap):
    """The compiled :func:`refined_by_edge_splits` (see the notes above).

    Returns ``(faces, parent, corner_bary, vertices, n_faces, n_vertices,
    rounds, failed)``; the arrays have room to spare (first ``n_*`` rows
    used); ``failed`` when more than ``max_faces`` faces would be made."""
    one = np.int64(_ONE)
    n0 = V.shape[0]
    Fo = np.empty((cap, 3), dtype=np.int64)
    Po = np.empty(cap, dtype=np.int64)
    Bo = np.empty((cap if want_bary else 1, 3, 3), dtype=np.float32)
    Vo = np.empty((n0 + cap // 2 + 16, 3), dtype=np.float64)
    Vo[:n0] = V
    nf = 0
    nv = n0
    # base-edge vertices: (edge, position) -> vertex
    emask = np.int64(4095)
    ek0 = np.full(4096, -1, dtype=np.int64)
    ek1 = np.zeros(4096, dtype=np.int64)
    ev = np.zeros(4096, dtype=np.int64)
    eused = 0
    # this face's vertices: integer barycentrics, positions, float32 barycentrics
    LI = np.empty((64, 3), dtype=np.int64)
    LP = np.empty((64, 3), dtype=np.float64)
    LB = np.empty((64, 3), dtype=np.float32)
    lg = np.empty(64, dtype=np.int64)
    # (I0, I1) -> local vertex, valid where the stamp is this face
    lmask = np.int64(255)
    lk0 = np.zeros(256, dtype=np.int64)
    lk1 = np.zeros(256, dtype=np.int64)
    lv = np.zeros(256, dtype=np.int64)
    lstamp = np.full(256, -1, dtype=np.int64)
    cur = np.empty((64, 3), dtype=np.int64)
    nxt = np.empty((64, 3), dtype=np.int64)
    done = np.empty((64, 3), dtype=np.int64)
    split = np.zeros((64, 3), dtype=np.bool_)
    cnt = np.zeros(64, dtype=np.int64)
    M = np.zeros((64, 3), dtype=np.int64)
    rounds = 0
    half32 = np.float32(0.5)
    for f in range(F.shape[0]):
        lnv = 3
        for c in range(3):
            for x in range(3):
                LI[c, x] = one if x == c else 0
                LP[c, x] = V[F[f, c], x]
                LB[c, x] = np.float32(1.0) if x == c else np.float32(0.0)
        for c in range(3):
            h = _slot(LI[c, 0], LI[c, 1], lmask)
            while lstamp[h] == f:
                h = (h + 1) & lmask
            lstamp[h] = f
            lk0[h] = LI[c, 0]
            lk1[h] = LI[c, 1]
            lv[h] = c
        ncur = 1
        cur[0, 0] = 0
        cur[0, 1] = 1
        cur[0, 2] = 2
        ndone = 0
        r = 0
        while ncur > 0 and r < max_rounds:
            split = _rows_bool(split, ncur)
            if cnt.shape[0] < ncur:
                cnt = _rows_1(cnt, ncur)
            grow = 0
            for i in range(ncur):
                c = 0
                for k in range(3):
                    s = _side_sq(LP, cur[i, k], cur[i, (k + 1) % 3]) > L2
                    split[i, k] = s
                    if s:
                        c += 1
                cnt[i] = c
                grow += c
            if grow == 0:
                break
            if nf + ndone + ncur + grow > max_faces:
                return Fo, Po, Bo, Vo, nf, nv, rounds, True
            # midpoints, one per split side, shared with the face across it
            M = _rows_i(M, ncur)
            for i in range(ncur):
                for k in range(3):
                    if not split[i, k]:
                        continue
                    p = cur[i, k]
                    q = cur[i, (k + 1) % 3]
                    i0 = (LI[p, 0] + LI[q, 0]) >> 1
                    i1 = (LI[p, 1] + LI[q, 1]) >> 1
                    h = _slot(i0, i1, lmask)
                    found = -1
                    while lstamp[h] == f:
                        if lk0[h] == i0 and lk1[h] == i1:
                            found = lv[h]
                            break
                        h = (h + 1) & lmask
                    if found < 0:
                        found = lnv
                        if lnv + 1 > LI.shape[0]:
                            LI = _rows_i(LI, lnv + 1)
                            LP = _rows_f(LP, lnv + 1)
                            LB = _rows_f32(LB, lnv + 1)
                        LI[lnv, 0] = i0
                        LI[lnv, 1] = i1
                        LI[lnv, 2] = (LI[p, 2] + LI[q, 2]) >> 1
                        for x in range(3):
                            LP[lnv, x] = 0.5 * (LP[p, x] + LP[q, x])
                            LB[lnv, x] = half32 * (LB[p, x] + LB[q, x])
                        lnv += 1
                        if 2 * lnv > lmask:                  # grow, re-insert all
                            size = 4 * (lmask + 1)
                            lmask = np.int64(size - 1)
                            lk0 = np.zeros(size, dtype=np.int64)
                            lk1 = np.zeros(size, dtype=np.int64)
                            lv = np.zeros(size, dtype=np.int64)
                            lstamp = np.full(size, -1, dtype=np.int64)
                            for u in range(lnv):
                                g = _slot(LI[u, 0], LI[u, 1], lmask)
                                while lstamp[g] == f:
                                    g = (g + 1) & lmask
                                lstamp[g] = f
                                lk0[g] = LI[u, 0]
                                lk1[g] = LI[u, 1]
                                lv[g] = u
                        else:
                            lstamp[h] = f
                            lk0[h] = i0
                            lk1[h] = i1
                            lv[h] = found
                    M[i, k] = found
            # the numpy path's block order: faces with one split side (first
            # children, then second), two (the corner child, then the quad's two),
            # three (four children); unsplit faces are done
            n1 = 0
            n2 = 0
            n3 = 0
            for i in range(ncur):
                if cnt[i] == 1:
                    n1 += 1
                elif cnt[i] == 2:
                    n2 += 1
                elif cnt[i] == 3:
                    n3 += 1
            nn = 2 * n1 + 3 * n2 + 4 * n3
            nxt = _rows_i(nxt, nn)
            done = _rows_i(done, ndone + ncur)
            j1 = 0
            j2 = 2 * n1
            j3 = 2 * n1 + 3 * n2
            for i in range(ncur):
                c = cnt[i]
                if c == 0:
                    for x in range(3):
                        done[ndone, x] = cur[i, x]
                    ndone += 1
                elif c == 1:
                    ro = 0 if split[i, 0] else (1 if split[i, 1] else 2)
                    a = cur[i, ro]
                    b = cur[i, (ro + 1) % 3]
                    cc = cur[i, (ro + 2) % 3]
                    m = M[i, ro]
                    nxt[j1, 0] = a
                    nxt[j1, 1] = m
                    nxt[j1, 2] = cc
                    nxt[n1 + j1, 0] = m
                    nxt[n1 + j1, 1] = b
                    nxt[n1 + j1, 2] = cc
                    j1 += 1
                elif c == 2:
                    short = 0 if not split[i, 0] else (1 if not split[i, 1] else 2)
                    ro = (short + 1) % 3
                    a = cur[i, ro]
                    b = cur[i, (ro + 1) % 3]
                    cc = cur[i, (ro + 2) % 3]
                    m0 = M[i, ro]
                    m1 = M[i, (ro + 1) % 3]
                    # quad a, m0, m1, c: cut along the shorter diagonal
                    use_a = _side_sq(LP, m1, a) <= _side_sq(LP, cc, m0)
                    nxt[j2, 0] = m0
                    nxt[j2, 1] = b
                    nxt[j2, 2] = m1
                    o1 = j2 + n2
                    o2 = j2 + 2 * n2
                    if use_a:
                        nxt[o1, 0] = a
                        nxt[o1, 1] = m0
                        nxt[o1, 2] = m1
                        nxt[o2, 0] = a
                        nxt[o2, 1] = m1
                        nxt[o2, 2] = cc
                    else:
                        nxt[o1, 0] = a
                        nxt[o1, 1] = m0
                        nxt[o1, 2] = cc
                        nxt[o2, 0] = m0
                        nxt[o2, 1] = m1
                        nxt[o2, 2] = cc
                    j2 += 1
                else:
                    a = cur[i, 0]
                    b = cur[i, 1]
                    cc = cur[i, 2]
                    m0 = M[i, 0]
                    m1 = M[i, 1]
                    m2 = M[i, 2]
                    nxt[j3, 0] = a
                    nxt[j3, 1] = m0
                    nxt[j3, 2] = m2
                    nxt[j3 + n3, 0] = m0
                    nxt[j3 + n3, 1] = b
                    nxt[j3 + n3, 2] = m1
                    nxt[j3 + 2 * n3, 0] = m2
                    nxt[j3 + 2 * n3, 1] = m1
                    nxt[j3 + 2 * n3, 2] = cc
                    nxt[j3 + 3 * n3, 0] = m0
                    nxt[j3 + 3 * n3, 1] = m1
                    nxt[j3 + 3 * n3, 2] = m2
                    j3 += 1
            cur, nxt = nxt, cur
            ncur = nn
            r += 1
        done = _rows_i(done, ndone + ncur)
        for i in range(ncur):
            for x in range(3):
                done[ndone, x] = cur[i, x]
            ndone += 1
        if r > rounds:
            rounds = r
        # write the face's triangles, numbering new vertices by first use
        if lg.shape[0] < lnv:
            lg = _rows_1(lg, lnv)
        for u in range(lnv):
            lg[u] = -1
        if nf + ndone > Fo.shape[0]:
            Fo = _rows_i(Fo, nf + ndone)
            Po = _rows_1(Po, nf + ndone)
            if want_bary:
                Bo = _rows_b(Bo, nf + ndone)
        for i in range(ndone):
            for c in range(3):
                u = done[i, c]
                g = lg[u]
                if g < 0:
                    g = -1
                    side = -1
                    for x in range(3):
                        if LI[u, x] == one:
                            g = F[f, x]
                        elif LI[u, x] == 0:
                            side = (x + 1) % 3          # the side opposite corner x
                    if g < 0 and side >= 0:
                        e = side_edge[f, side]
                        ga = F[f, side]
                        gb = F[f, (side + 1) % 3]
                        t = LI[u, (side + 1) % 3] if gb > ga else LI[u, side]
                        h = _slot(e, t, emask)
                        while ek0[h] >= 0:
                            if ek0[h] == e and ek1[h] == t:
                                g = ev[h]
                                break
                            h = (h + 1) & emask
                        if g < 0:
                            g = nv
                            nv += 1
                            Vo = _rows_f(Vo, nv)
                            for x in range(3):
                                Vo[g, x] = LP[u, x]
                            ek0[h] = e
                            ek1[h] = t
                            ev[h] = g
                            eused += 1
                            if 2 * eused > emask:            # grow, re-insert all
                                size = 4 * (emask + 1)
                                emask = np.int64(size - 1)
                                o0, o1, ov = ek0, ek1, ev
                                ek0 = np.full(size, -1, dtype=np.int64)
                                ek1 = np.zeros(size, dtype=np.int64)
                                ev = np.zeros(size, dtype=np.int64)
                                for s in range(o0.shape[0]):
                                    if o0[s] >= 0:
                                        h = _slot(o0[s], o1[s], emask)
                                        while ek0[h] >= 0:
                                            h = (h + 1) & emask
                                        ek0[h] = o0[s]
                                        ek1[h] = o1[s]
                                        ev[h] = ov[s]
                    elif g < 0:
                        g = nv
                        nv += 1
                        Vo = _rows_f(Vo, nv)
                        for x in range(3):
                            Vo[g, x] = LP[u, x]
                    lg[u] = g
                Fo[nf, c] = g
                if want_bary:
                    for x in range(3):
                        Bo[nf, c, x] = LB[u, x]
            Po[nf] = f
            nf += 1
    return Fo, Po, Bo, Vo, nf, nv, rounds, False
