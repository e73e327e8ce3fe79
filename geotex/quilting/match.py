"""Where to place the next exemplar copy: matching energy over translations, ICP refinement.

The energy of placing the exemplar ``M`` translated by ``t`` under the region
``P_T`` of the texture built so far (its vertices ``v`` with normals
``n(v)``) is

    E(t) = sum_v (1 + lam * dist(v - t, M)) * (1 + |n(v) - n(f)|)

where ``f`` is the face of ``M`` closest to ``v - t`` (the minimum over faces
is approximated by the closest face, as the closest face almost always
minimises both factors).  All candidate translations are evaluated in one
vectorized closest-point query; the best few are refined by translation-only
ICP (in the plane) and re-scored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.mesh.geometry import face_normals
from geotex.quilting.icp import ClosestPoints, icp_translation

__all__ = ["ExemplarIndex", "matching_energy", "best_translation", "Match"]

_QUERY_CHUNK = 400_000


class ExemplarIndex:
    """Closest-point index and face normals of the exemplar (built once).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    """

    def __init__(self, V, F):
        self.points = ClosestPoints(V, F)
        self.normals = face_normals(self.points.V, self.points.F)


@dataclass(frozen=True)
class Match:
    """Chosen translation and how it was found.

    Attributes
    ----------
    t : numpy.ndarray, (3,) float64
        Translation of the exemplar.
    energy : float
        Mean per-vertex energy at ``t`` (``nan`` when there was nothing to match).
    icp_iterations : int
        ICP updates spent on the refined candidates.
    candidates : int
        Number of cell-multiple translations scored.
    alternatives : numpy.ndarray, (a, 4) float64
        Every refined and unrefined finalist ``(tx, ty, tz, energy)``, best
        first (the caller may prefer one that causes fewer collisions).
    """

    t: np.ndarray
    energy: float
    icp_iterations: int
    candidates: int
    alternatives: np.ndarray = None


def matching_energy(P, N, index: ExemplarIndex, translations, *, lam: float) -> np.ndarray:
    """Mean matching energy of every candidate translation.

    Parameters
    ----------
    P : numpy.ndarray, (k, 3) float64
        Vertices of the region to match.
    N : numpy.ndarray, (k, 3) float64
        Their unit normals.
    index : ExemplarIndex
    translations : numpy.ndarray, (c, 3) float64
    lam : float
        Weight of the distance (1 / length).

    Returns
    -------
    numpy.ndarray, (c,) float64
        ``E(t) / k`` for every candidate.
    """
    P = np.asarray(P, np.float64).reshape(-1, 3)
    N = np.asarray(N, np.float64).reshape(-1, 3)
    T = np.asarray(translations, np.float64).reshape(-1, 3)
    k = P.shape[0]
    if k == 0:
        raise InputError("matching_energy needs at least one point")
    out = np.empty(T.shape[0])
    per = max(1, _QUERY_CHUNK // k)
    for s in range(0, T.shape[0], per):
        Q = (P[None] - T[s:s + per, None]).reshape(-1, 3)
        d2, face, _ = index.points.query(Q)
        dn = np.linalg.norm(np.tile(N, (Q.shape[0] // k, 1)) - index.normals[face], axis=1)
        e = (1.0 + lam * np.sqrt(d2)) * (1.0 + dn)
        out[s:s + per] = e.reshape(-1, k).mean(axis=1)
    return out


def best_translation(P, N, index: ExemplarIndex, candidates, *, lam: float, refine: int = 3,
                     lo=None, hi=None, max_iterations: int = 10,
                     max_points: int = 1500, icp_points: int = 400) -> Match:
    """Best exemplar translation for the region ``P`` among ``candidates``, ICP-refined.

    Parameters
    ----------
    P, N : numpy.ndarray, (k, 3) float64
        Region vertices and unit normals (``k >= 1``).
    index : ExemplarIndex
    candidates : numpy.ndarray, (c, 3) float64
        Cell-multiple translations.
    lam : float
    refine : int, optional
        How many of the best candidates are refined by ICP.
    lo, hi : array_like (2,), optional
        Box the refined ``t[:2]`` is clamped to (so the placed copy still
        covers what it must).
    max_iterations : int, optional
        ICP iterations per refined candidate.
    max_points : int, optional
        Larger regions are evenly subsampled to this many points.
    icp_points : int, optional
        About this many of them drive the ICP (every k-th point); ICP stops
        when an update is below ``1e-4`` of the region's diagonal.

    Returns
    -------
    Match
    """
    C = np.asarray(candidates, np.float64).reshape(-1, 3)
    if C.shape[0] == 0:
        raise InputError("best_translation needs at least one candidate")
    P = np.asarray(P, np.float64).reshape(-1, 3)
    N = np.asarray(N, np.float64).reshape(-1, 3)
    if P.shape[0] > max_points:  # an even, deterministic subsample
        keep = np.linspace(0, P.shape[0] - 1, max_points).round().astype(np.int64)
        P, N = P[keep], N[keep]
    E = matching_energy(P, N, index, C, lam=lam)
    order = np.argsort(E, kind="stable")[:max(1, refine)]
    best_t, best_e, iters = C[order[0]].copy(), float(E[order[0]]), 0
    refined = []
    step = max(1, P.shape[0] // icp_points)
    scale = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) or 1.0
    for c in order:
        s, info = icp_translation(P[::step], t0=-C[c], target=index.points,
                                  free=(True, True, False), max_iterations=max_iterations,
                                  method="plane",
                                  tol=1e-4 * scale)
        iters += info.iterations
        t = -s
        if lo is not None:
            t[:2] = np.clip(t[:2], lo, hi)
        refined.append(t)
    R = np.array(refined)
    ER = matching_energy(P, N, index, R, lam=lam)
    j = int(np.argmin(ER))
    if ER[j] < best_e:
        best_t, best_e = R[j], float(ER[j])
    alt = np.r_[np.c_[R, ER], np.c_[C[order], E[order]]]
    alt = alt[np.argsort(alt[:, 3], kind="stable")]
    return Match(t=best_t, energy=best_e, icp_iterations=iters, candidates=C.shape[0],
                 alternatives=alt)
