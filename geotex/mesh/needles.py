"""Needle triangles removed from a closed manifold mesh by local edge operations.

A boolean union leaves triangles whose height is a tiny fraction of the
model (where two surfaces cross nearly tangentially). Rounding their
corners to a file's float32 can fold them onto a neighbour (manifold3d's
``simplify`` keeps most of them, where a collapse would move a crease).
:func:`needle_free` removes them:

* a *dart* (one edge shorter than the tolerance, or than a given
  ``dart_length``) loses that edge: one end moves onto the other (the mesh
  changes by less than that length), when
  the link condition holds (the two ends share exactly the two opposite
  vertices, so the mesh stays a manifold), no two faces would double up and
  no surrounding face turns over;
* a *cap* (every edge long, one corner almost on the opposite edge) has its
  longest edge flipped, when the flipped edge does not exist already and
  both new faces face the way the old ones did.

Every needle proposes its operation; the valid ones whose footprints (the
vertices whose faces they read or change) are disjoint run together, lowest
needle first, all vectorized (a million-face union can hold ten thousand
needles); rounds repeat while needles remain and something changed.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from geotex.jit import JIT_MIN_SIZE, compiled
from geotex.mesh.geometry import face_cross
from geotex.mesh.topology import compacted

__all__ = ["needle_free", "needle_faces", "SLIVER_TOLERANCE"]

#: Needle triangles a boolean leaves lower than this fraction of the bounding-box
#: diagonal are removed (:func:`geotex.mesh.needles.needle_free`). 1e-6 (0.1
#: micrometre on a 100 mm part) is about ten float32 steps, so what remains
#: survives the rounding to float32 of an STL file; at 1e-7 the rounding broke
#: hundreds of slivers on chain mail.
SLIVER_TOLERANCE = 1e-6

_MAX_ROUNDS = 8


def needle_faces(V: np.ndarray, F: np.ndarray, *, tolerance: float) -> np.ndarray:
    """Faces whose height (twice the area over the longest edge) is below ``tolerance``.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    tolerance : float
        Length, in the units of ``V``.

    Returns
    -------
    numpy.ndarray, (k,) int64
        Needle faces, lowest height first (ties by index).
    """
    height = _heights(V, F)
    needles = np.flatnonzero(height < tolerance)
    return needles[np.argsort(height[needles], kind="stable")]


def _heights(V, F):
    if F.shape[0] == 0:
        return np.zeros(0)
    if F.size >= JIT_MIN_SIZE:
        out = np.empty(F.shape[0])
        _height_loops(np.ascontiguousarray(V, dtype=np.float64),
                      np.ascontiguousarray(F, dtype=np.int64), out)
        return out
    edge = V[np.roll(F, -1, axis=1)] - V[F]
    longest = np.linalg.norm(edge, axis=2).max(axis=1)
    area2 = np.linalg.norm(face_cross(V, F), axis=1)
    return np.divide(area2, longest, out=np.zeros_like(area2), where=longest > 0)


@compiled
def _height_loops(V, F, out):
    """:func:`_heights` face by face (the same products and sums, bit for bit)."""
    for f in range(F.shape[0]):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        longest = 0.0
        for a, b in ((i, j), (j, k), (k, i)):
            x = V[b, 0] - V[a, 0]
            y = V[b, 1] - V[a, 1]
            z = V[b, 2] - V[a, 2]
            longest = max(longest, np.sqrt(x * x + y * y + z * z))
        a0, a1, a2 = V[j, 0] - V[i, 0], V[j, 1] - V[i, 1], V[j, 2] - V[i, 2]
        b0, b1, b2 = V[k, 0] - V[i, 0], V[k, 1] - V[i, 1], V[k, 2] - V[i, 2]
        c0 = a1 * b2 - a2 * b1
        c1 = a2 * b0 - a0 * b2
        c2 = a0 * b1 - a1 * b0
        area2 = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        out[f] = area2 / longest if longest > 0.0 else 0.0


def needle_free(V: np.ndarray, F: np.ndarray, *, tolerance: float, dart_length=None,
                rounds: int = _MAX_ROUNDS) -> tuple[np.ndarray, np.ndarray, int]:
    """Remove needle triangles from a closed manifold mesh by collapses and flips.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Closed, consistently oriented, edge-manifold mesh.
    tolerance : float
        Faces lower than this (see :func:`needle_faces`) are needles; dart
        edges shorter than this are collapsed.
    dart_length : float, optional
        A needle whose shortest edge is shorter than this is a dart (its
        edge collapsed, moving the mesh by up to this much); default
        ``tolerance``. A local union whose cut points fall close together
        leaves needles on edges a little longer than ``tolerance``.
    rounds : int, optional
        At most this many rounds of operations (each round's operations
        have disjoint footprints, so a cluster of needles takes several).

    Returns
    -------
    V2 : numpy.ndarray, (p, 3) float64
        Unreferenced vertices removed; positions of kept vertices unchanged.
    F2 : numpy.ndarray, (r, 3) int64
    operations : int
        Collapses plus flips applied (0: the input arrays' copies unchanged).

    Notes
    -----
    Needles whose removal would break the manifold or turn a face over are
    left in place; the caller judges the result (for example with
    :func:`geotex.check.report.check_mesh`).
    """
    V = np.array(V, dtype=np.float64)
    F = np.array(F, dtype=np.int64)
    dart_length = tolerance if dart_length is None else float(dart_length)
    height = _heights(V, F)
    needles = np.flatnonzero(height < tolerance)
    if needles.size == 0:
        return V, F, 0
    # every operation stays within one ring of a needle's corners, and a later
    # round's needles are faces an earlier one changed: work on the faces within
    # two rings, and only around vertices whose whole fan lies in that region
    near = np.zeros(V.shape[0], dtype=bool)
    near[F[needles].ravel()] = True
    region, complete = _region(F, near)
    sub = F[region]
    height = height[region]
    done = 0
    for _ in range(rounds):
        local = np.flatnonzero(height < tolerance)
        local = local[np.argsort(height[local], kind="stable")]
        if local.size == 0:
            break
        # one round reads the fans of the needles' corners only
        corner = np.zeros(V.shape[0], dtype=bool)
        corner[sub[local].ravel()] = True
        work = np.flatnonzero(corner[np.maximum(sub, 0)].any(axis=1) & (sub[:, 0] >= 0))
        at = np.full(sub.shape[0], -1, dtype=np.int64)
        at[work] = np.arange(work.size)
        W = sub[work]
        applied, changed = _one_round(V, W, at[local], dart_length, complete)
        sub[work] = W
        changed = work[changed]
        if applied == 0:
            break
        done += applied
        height[changed] = _heights(V, np.maximum(sub[changed], 0))
        height[sub[:, 0] < 0] = np.inf
    sub = sub[sub[:, 0] >= 0]
    if done == 0:
        return V, F, 0
    # the faces outside the region in order, then the region's: the mesh
    # compacted in one pass (only collapsed vertices drop out)
    V2, F2 = _spliced(V, F, region, sub)
    return V2, F2, done


def _region(F: np.ndarray, near: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces within one ring of the vertices ``near``, and the vertices whose
    every face is among them (``(k,)`` int64 faces in order, ``(n,)`` bool)."""
    if F.size < JIT_MIN_SIZE:
        near = near.copy()
        near[F[near[F].any(axis=1)].ravel()] = True
        region = np.flatnonzero(near[F].any(axis=1))
        complete = (np.bincount(F[region].ravel(), minlength=near.size)
                    == np.bincount(F.ravel(), minlength=near.size))
        return region, complete
    region = np.empty(F.shape[0], dtype=np.int64)
    complete = np.empty(near.size, dtype=np.bool_)
    k = _region_loops(np.ascontiguousarray(F), near, region, complete)
    return region[:k], complete


@compiled
def _region_loops(F, near, region, complete):
    """:func:`_region` in two passes over ``F``; returns the region's size."""
    ring = near.copy()
    for f in range(F.shape[0]):
        if near[F[f, 0]] or near[F[f, 1]] or near[F[f, 2]]:
            ring[F[f, 0]] = True
            ring[F[f, 1]] = True
            ring[F[f, 2]] = True
    complete[:] = True
    k = 0
    for f in range(F.shape[0]):
        if ring[F[f, 0]] or ring[F[f, 1]] or ring[F[f, 2]]:
            region[k] = f
            k += 1
        else:
            complete[F[f, 0]] = False
            complete[F[f, 1]] = False
            complete[F[f, 2]] = False
    return k


def _spliced(V, F, region, sub) -> tuple[np.ndarray, np.ndarray]:
    """``compacted(V, [F without the faces region; sub])`` (same arrays)."""
    if F.size < JIT_MIN_SIZE:
        keep = np.ones(F.shape[0], dtype=bool)
        keep[region] = False
        return compacted(V, np.concatenate([F[keep], sub]))
    out = np.empty((F.shape[0] - region.size + sub.shape[0], 3), dtype=np.int64)
    kept = np.empty(V.shape[0], dtype=np.int64)
    p = _spliced_loops(np.ascontiguousarray(F), region, np.ascontiguousarray(sub), out, kept)
    return V[kept[:p]], out


@compiled
def _spliced_loops(F, region, sub, out, kept):
    """:func:`_spliced`: ``out`` gets the faces, ``kept[:p]`` the used vertices
    in order; returns ``p``."""
    n = kept.shape[0]
    inside = np.zeros(F.shape[0], dtype=np.bool_)
    for i in range(region.shape[0]):
        inside[region[i]] = True
    used = np.zeros(n, dtype=np.bool_)
    for f in range(F.shape[0]):
        if not inside[f]:
            for c in range(3):
                used[F[f, c]] = True
    for f in range(sub.shape[0]):
        for c in range(3):
            used[sub[f, c]] = True
    index = np.empty(n, dtype=np.int64)
    p = 0
    for v in range(n):
        if used[v]:
            index[v] = p
            kept[p] = v
            p += 1
    k = 0
    for f in range(F.shape[0]):
        if not inside[f]:
            for c in range(3):
                out[k, c] = index[F[f, c]]
            k += 1
    for f in range(sub.shape[0]):
        for c in range(3):
            out[k, c] = index[sub[f, c]]
        k += 1
    return p


def _one_round(V, F, needles, dart_length, complete) -> tuple[int, np.ndarray]:
    """Apply, in place, a set of valid operations with disjoint footprints.

    A needle whose shortest edge is below ``dart_length`` is a dart.

    Deleted faces get -1. Every needle proposes one operation; invalid ones
    are dropped, then an operation is applied when it has the lowest needle
    (by height) among all operations whose footprints (the vertices whose
    faces it reads or changes) share a vertex with its own.
    Returns the number applied and the faces changed or deleted.
    """
    n, q = V.shape[0], needles.size
    T = F[needles]
    nxt = np.roll(T, -1, axis=1)
    length = np.linalg.norm(V[nxt] - V[T], axis=2)
    rows = np.arange(q)
    kmin, kmax = np.argmin(length, axis=1), np.argmax(length, axis=1)
    dart = length[rows, kmin] < dart_length
    k = np.where(dart, kmin, kmax)
    # the operation's edge (a, b) in the needle's direction, and its apex c
    a, b, c = T[rows, k], T[rows, (k + 1) % 3], T[rows, (k + 2) % 3]
    # the other face g on the edge (it runs b -> a) and its apex d
    keys = F * n + np.roll(F, -1, axis=1)
    live = F[:, 0] >= 0
    flat = np.where(live[:, None], keys, -1).ravel()
    order = np.argsort(flat, kind="stable")
    pos = np.searchsorted(flat[order], b * n + a)
    pos = np.minimum(pos, flat.size - 1)
    found = flat[order[pos]] == b * n + a
    g = order[pos] // 3
    d = F[g, (order[pos] % 3 + 2) % 3]
    f = needles
    adjacency = _adjacency(F[live], n)
    valid = found & (d != c) & complete[a] & complete[b] & complete[c]
    cd_edge = _adjacent(adjacency, c, d)
    # faces around every vertex (of the live faces)
    corner = np.where(live[:, None], F, n).ravel()
    vorder = np.argsort(corner, kind="stable")
    starts = np.searchsorted(corner[vorder], np.arange(n + 1))

    def around(verts):
        """(operation, face) for every face around ``verts[i]``."""
        counts = starts[verts + 1] - starts[verts]
        op = np.repeat(np.arange(verts.size), counts)
        first = np.repeat(starts[verts] - np.cumsum(counts) + counts, counts)
        return op, vorder[first + np.arange(op.size)] // 3

    # darts: collapse (a, b); the link condition and no face turned over
    common = np.asarray(adjacency[a].multiply(adjacency[b]).sum(axis=1)).ravel()
    keep_b = _turns_none(V, F, a, b, f, g, around)      # a moves onto b
    keep_a = _turns_none(V, F, b, a, f, g, around)      # b moves onto a
    # faces (a, c, d) and (b, c, d) both present (a tetrahedron's): they would double up
    doubled = _has_face(F, a, c, d, around) & _has_face(F, b, c, d, around)
    dart_ok = valid & dart & (common == 2) & ~doubled & (keep_b | keep_a)
    gone = np.where(keep_b, a, b)
    stay = np.where(keep_b, b, a)
    # caps: flip (a, b) to (c, d) when both new faces face g's way and are higher
    new1 = np.stack([a, d, c], axis=1)
    new2 = np.stack([d, b, c], axis=1)
    cg = face_cross(V, F[g])
    higher = (np.minimum(_heights(V, new1), _heights(V, new2))
              > np.minimum(_heights(V, T), _heights(V, F[g])))
    cap_ok = (valid & ~dart & ~cd_edge & higher
              & (np.einsum("ij,ij->i", face_cross(V, new1), cg) > 0)
              & (np.einsum("ij,ij->i", face_cross(V, new2), cg) > 0))
    ok = dart_ok | cap_ok
    # footprints: a dart reads and writes the faces around both ends, a flip the
    # two faces' corners
    op_u, face_u = around(a)
    op_v, face_v = around(b)
    fp_op = np.concatenate([np.repeat(op_u, 3), np.repeat(op_v, 3), np.repeat(rows, 4)])
    fp_vert = np.concatenate([F[face_u].ravel(), F[face_v].ravel(),
                              np.stack([a, b, c, d], axis=1).ravel()])
    used = (dart[fp_op] | (np.arange(fp_op.size) >= 3 * (op_u.size + op_v.size))) & ok[fp_op]
    fp_op, fp_vert = fp_op[used], fp_vert[used]
    lowest = np.full(n, q, dtype=np.int64)
    np.minimum.at(lowest, fp_vert, fp_op)
    win = ok & (np.bincount(fp_op, weights=(lowest[fp_vert] != fp_op).astype(float),
                            minlength=q) == 0)
    # apply the collapses: faces around the vertex that goes get the one that stays
    wd = np.flatnonzero(win & dart)
    op_g, face_g = around(gone[wd])
    Fg = F[face_g]
    F[face_g] = np.where(Fg == gone[wd][op_g, None], stay[wd][op_g, None], Fg)
    F[f[wd]] = -1
    F[g[wd]] = -1
    wc = np.flatnonzero(win & ~dart)
    F[f[wc]] = new1[wc]
    F[g[wc]] = new2[wc]
    return int(wd.size + wc.size), np.unique(np.concatenate([face_g, f[wc], g[wc]]))


def _adjacency(F, n):
    """Symmetric vertex adjacency, ``(n, n)`` CSR of ones."""
    i = F.ravel()
    j = np.roll(F, -1, axis=1).ravel()
    A = sp.csr_matrix((np.ones(2 * i.size), (np.concatenate([i, j]), np.concatenate([j, i]))),
                      shape=(n, n))
    A.data[:] = 1.0
    return A


def _adjacent(A, i, j) -> np.ndarray:
    """Whether vertices ``i[k]`` and ``j[k]`` share an edge."""
    return np.asarray(A[i, j]).ravel() > 0


def _has_face(F, x, y, z, around) -> np.ndarray:
    """Whether a face on the vertices ``x[k], y[k], z[k]`` exists (read around ``x``)."""
    op, face = around(x)
    T = F[face]
    hit = (T == y[op, None]).any(axis=1) & (T == z[op, None]).any(axis=1)
    return np.bincount(op, weights=hit.astype(float), minlength=x.size) > 0


def _turns_none(V, F, gone, stay, f, g, around) -> np.ndarray:
    """Whether moving ``gone[k]`` onto ``stay[k]`` turns no face around it over.

    The faces ``f[k]`` and ``g[k]`` on the collapsed edge disappear and are
    not judged.
    """
    op, face = around(gone)
    kept = (face != f[op]) & (face != g[op])
    op, face = op[kept], face[kept]
    old = F[face]
    new = np.where(old == gone[op, None], stay[op, None], old)
    dot = np.einsum("ij,ij->i", face_cross(V, old), face_cross(V, new))
    return np.bincount(op, weights=(dot <= 0).astype(float), minlength=gone.size) == 0
