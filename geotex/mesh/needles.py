"""Needle triangles removed from a closed manifold mesh by local edge operations.

A boolean union leaves triangles whose height is a tiny fraction of the
model (where two surfaces cross nearly tangentially). Rounding their
corners to a file's float32 can fold them onto a neighbour. manifold3d's
``simplify`` collapses most of them but keeps some where the collapse would
move a crease; :func:`needle_free` removes the rest:

* a *dart* (one edge shorter than the tolerance) loses that edge: one end
  moves onto the other (the mesh changes by less than the tolerance), when
  the link condition holds (the two ends share exactly the two opposite
  vertices, so the mesh stays a manifold) and no surrounding face turns over;
* a *cap* (every edge long, one corner almost on the opposite edge) has its
  longest edge flipped, when the flipped edge does not exist already and
  both new faces face the way the old ones did.

Operations in one round touch disjoint vertex neighbourhoods; rounds repeat
while needles remain and something changed. Only the few needle faces are
visited in Python; everything else is vectorized.
"""

from __future__ import annotations

import numpy as np

from geotex.mesh.geometry import face_cross
from geotex.mesh.topology import compacted

__all__ = ["needle_free", "needle_faces"]

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
    edge = V[np.roll(F, -1, axis=1)] - V[F]
    longest = np.linalg.norm(edge, axis=2).max(axis=1)
    area2 = np.linalg.norm(face_cross(V, F), axis=1)
    return np.divide(area2, longest, out=np.zeros_like(area2), where=longest > 0)


def needle_free(V: np.ndarray, F: np.ndarray, *, tolerance: float
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """Remove needle triangles from a closed manifold mesh by collapses and flips.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Closed, consistently oriented, edge-manifold mesh.
    tolerance : float
        Faces lower than this (see :func:`needle_faces`) are needles; dart
        edges shorter than this are collapsed.

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
    needles = needle_faces(V, F, tolerance=tolerance)
    if needles.size == 0:
        return V, F, 0
    # every operation stays within one ring of a needle's corners, and a later
    # round's needles are faces an earlier one changed: work on the faces within
    # two rings, and only around vertices whose whole fan lies in that region
    near = np.zeros(V.shape[0], dtype=bool)
    near[F[needles].ravel()] = True
    near[F[near[F].any(axis=1)].ravel()] = True
    region = np.flatnonzero(near[F].any(axis=1))
    complete = (np.bincount(F[region].ravel(), minlength=V.shape[0])
                == np.bincount(F.ravel(), minlength=V.shape[0]))
    sub = F[region]
    done = 0
    for _ in range(_MAX_ROUNDS):
        local = needle_faces(V, sub, tolerance=tolerance)
        local = local[complete[sub[local]].all(axis=1)]
        if local.size == 0:
            break
        applied = _one_round(V, sub, local, tolerance)
        if applied == 0:
            break
        done += applied
        sub = sub[sub[:, 0] >= 0]
    if done == 0:
        return V, F, 0
    keep = np.ones(F.shape[0], dtype=bool)
    keep[region] = False
    V2, F2 = compacted(V, np.concatenate([F[keep], sub]))
    return V2, F2, done


def _one_round(V, F, needles, tolerance) -> int:
    """Apply disjoint operations in place (deleted faces get -1); return their count."""
    flat = F.ravel()
    order = np.argsort(flat, kind="stable")
    starts = np.searchsorted(flat[order], np.arange(V.shape[0] + 1))
    locked = np.zeros(V.shape[0], dtype=bool)

    def faces_of(u):
        return order[starts[u]:starts[u + 1]] // 3

    applied = 0
    for f in needles.tolist():
        tri = F[f]
        if tri[0] < 0 or locked[tri].any():
            continue
        edge = V[np.roll(tri, -1)] - V[tri]
        length = np.linalg.norm(edge, axis=1)
        k = int(np.argmin(length))
        if length[k] < tolerance:
            ok = _collapse(V, F, tri[k], tri[(k + 1) % 3], faces_of, locked)
        else:
            ok = _flip(V, F, f, int(np.argmax(length)), faces_of, locked)
        applied += ok
    return applied


def _normals_kept(V, old, new) -> bool:
    """Every new face is non-degenerate and on the same side as the old one."""
    a = face_cross(V, old)
    b = face_cross(V, new)
    return bool(np.all(np.einsum("ij,ij->i", a, b) > 0))


def _shares_a_face(T, U) -> bool:
    """Whether a face of ``T`` has the vertex set of a face of ``U``."""
    S, R = np.sort(T, axis=1), np.sort(U, axis=1)
    return bool((S[:, None, :] == R[None, :, :]).all(axis=2).any())


def _collapse(V, F, u, v, faces_of, locked) -> bool:
    """Move ``u`` onto ``v`` (or ``v`` onto ``u``) if the mesh stays manifold and unfolded."""
    fu, fv = faces_of(u), faces_of(v)
    fu, fv = fu[F[fu, 0] >= 0], fv[F[fv, 0] >= 0]
    shared = np.intersect1d(fu, fv)
    if shared.size != 2:
        return False
    ring_u = np.setdiff1d(np.unique(F[fu]), [u])
    ring_v = np.setdiff1d(np.unique(F[fv]), [v])
    opposite = np.setdiff1d(np.unique(F[shared]), [u, v])
    if not np.array_equal(np.intersect1d(ring_u, ring_v), opposite):
        return False
    for gone, keep, around in ((u, v, fu), (v, u, fv)):
        moved = np.setdiff1d(around, shared)
        new = np.where(F[moved] == gone, keep, F[moved])
        # a face already on these three vertices (a tetrahedron's) would double up
        others = np.setdiff1d(fv if keep == v else fu, shared)
        if not _shares_a_face(new, F[others]) and _normals_kept(V, F[moved], new):
            F[moved] = new
            F[shared] = -1
            locked[np.unique(F[np.concatenate([fu, fv])].ravel())] = True
            locked[[u, v]] = True
            return True
    return False


def _flip(V, F, f, k, faces_of, locked) -> bool:
    """Flip edge ``k`` of face ``f`` (its longest) if the result is valid and better."""
    a, b, c = F[f, k], F[f, (k + 1) % 3], F[f, (k + 2) % 3]
    around = faces_of(a)
    around = around[F[around, 0] >= 0]
    other = [g for g in around.tolist() if g != f and b in F[g]]
    if len(other) != 1:
        return False
    g = other[0]
    d = int(np.setdiff1d(F[g], [a, b])[0])
    if locked[d] or np.any(F[faces_of(c)] == d):
        return False
    old = F[[f, g]]
    new = np.array([[a, d, c], [d, b, c]])
    # the needle's own normal is unreliable: judge by its well-shaped neighbour
    if not _normals_kept(V, old[[1, 1]], new):
        return False
    if _heights(V, new).min() <= _heights(V, old).min():
        return False
    F[f], F[g] = new
    locked[[a, b, c, d]] = True
    return True
