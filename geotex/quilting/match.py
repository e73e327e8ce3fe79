"""Where to place the next exemplar copy: matching energy over translations, ICP refinement.

The energy of placing the exemplar ``M`` translated by ``t`` under the region
``P_T`` of the texture built so far (its vertices ``v`` with normals
``n(v)``) is::

    E(t) = sum_v (1 + lam * dist(v - t, M)) * (1 + |n(v) - n(f)|)

where ``f`` is the face of ``M`` closest to ``v - t`` (the minimum over faces
is approximated by the closest face, as the closest face almost always
minimises both factors).  Only the vertices that the translated exemplar
covers count (``v - t`` inside its rectangle ``[0, lx] x [0, ly]``): a
vertex beyond the copy cannot correspond to anything in it, and counting it
would favour copies that stay over the texture already built instead of
the pattern's phase (for a weave, shifts by an odd number of pitches along
one axis swap over and under; they score clearly worse once only the
covered vertices count: mean energy 1.65 against 1.30 measured on the
default weave).  The energy is the mean over those vertices; a candidate
covering fewer than ``min_overlap`` of the best-covered candidate's count is
discarded.  All candidate translations are evaluated in one vectorized
closest-point query; the best few are refined by translation-only ICP (in
the plane, with the covered vertices only) and re-scored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.mesh.geometry import face_normals
from geotex.quilting.icp import ClosestPoints, icp_translation

__all__ = ["ExemplarIndex", "matching_energy", "best_translation", "Match", "covered_by"]

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


def covered_by(P, translations, footprint) -> np.ndarray:
    """Which points the exemplar translated by each ``t`` covers, ``(c, k)`` bool.

    Point ``v`` is covered by the copy at ``t`` when ``(v - t)[:2]`` lies in
    the exemplar's rectangle ``[0, lx] x [0, ly]``; with ``footprint=None``
    every point counts.
    """
    P = np.asarray(P, np.float64).reshape(-1, 3)
    T = np.asarray(translations, np.float64).reshape(-1, 3)
    if footprint is None:
        return np.ones((T.shape[0], P.shape[0]), dtype=bool)
    lx, ly = (float(s) for s in footprint)
    x = P[None, :, 0] - T[:, None, 0]
    y = P[None, :, 1] - T[:, None, 1]
    return (x >= 0.0) & (x <= lx) & (y >= 0.0) & (y <= ly)


def matching_energy(P, N, index: ExemplarIndex, translations, *, lam: float,
                    footprint=None) -> np.ndarray:
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
    footprint : tuple (lx, ly), optional
        Exemplar rectangle: only the vertices the translated exemplar covers
        count (see :func:`covered_by`).  Default: every vertex counts.

    Returns
    -------
    numpy.ndarray, (c,) float64
        ``E(t)`` divided by the number of vertices counted, for every
        candidate (``inf`` when the copy covers none of them).

    Raises
    ------
    InputError
        If ``P`` is empty.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> idx = ExemplarIndex(V, F)
    >>> E = matching_energy(V + [0.5, 0, 0], V, idx, [[0.5, 0, 0], [0.0, 0, 0]], lam=1.0)
    >>> bool(E[0] < 1.2 < E[1])
    True
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
        Ts = T[s:s + per]
        inside = covered_by(P, Ts, footprint)
        cand, pt = np.nonzero(inside)            # only the covered points are queried
        d2, face, _ = index.points.query(P[pt] - Ts[cand])
        dn = np.linalg.norm(N[pt] - index.normals[face], axis=1)
        e = (1.0 + lam * np.sqrt(d2)) * (1.0 + dn)
        count = inside.sum(axis=1)
        total = np.bincount(cand, weights=e, minlength=Ts.shape[0])
        with np.errstate(invalid="ignore", divide="ignore"):
            out[s:s + per] = np.where(count > 0, total / count, np.inf)
    return out


def best_translation(P, N, index: ExemplarIndex, candidates, *, lam: float, refine: int = 3,
                     lo=None, hi=None, max_iterations: int = 10,
                     max_points: int = 1500, icp_points: int = 400, footprint=None,
                     min_overlap: float = 0.3) -> Match:
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
    footprint : tuple (lx, ly), optional
        Exemplar rectangle: only the region vertices a candidate copy covers
        are scored and drive its ICP (see :func:`matching_energy`).
    min_overlap : float, optional
        With ``footprint``: candidates covering fewer than this fraction of
        the largest covered count are discarded (unless none is left).

    Returns
    -------
    Match

    Raises
    ------
    InputError
        If there is no candidate or no point.
    """
    C = np.asarray(candidates, np.float64).reshape(-1, 3)
    if C.shape[0] == 0:
        raise InputError("best_translation needs at least one candidate")
    P = np.asarray(P, np.float64).reshape(-1, 3)
    N = np.asarray(N, np.float64).reshape(-1, 3)
    if P.shape[0] > max_points:  # an even, deterministic subsample
        keep = np.linspace(0, P.shape[0] - 1, max_points).round().astype(np.int64)
        P, N = P[keep], N[keep]
    if P.shape[0] == 0:
        raise InputError("best_translation needs at least one point")
    E = matching_energy(P, N, index, C, lam=lam, footprint=footprint)
    inside = covered_by(P, C, footprint)
    count = inside.sum(axis=1)
    few = count < min_overlap * count.max()
    if not few.all():
        E = np.where(few, np.inf, E)
    order = np.argsort(E, kind="stable")[:max(1, refine)]
    best_t, best_e, iters = C[order[0]].copy(), float(E[order[0]]), 0
    refined = []
    scale = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) or 1.0
    for c in order:
        Pc = P[inside[c]] if inside[c].sum() >= 3 else P
        step = max(1, Pc.shape[0] // icp_points)
        s, info = icp_translation(Pc[::step], t0=-C[c], target=index.points,
                                  free=(True, True, False), max_iterations=max_iterations,
                                  method="plane",
                                  tol=1e-4 * scale)
        iters += info.iterations
        t = -s
        if lo is not None:
            t[:2] = np.clip(t[:2], lo, hi)
        refined.append(t)
    R = np.array(refined)
    ER = matching_energy(P, N, index, R, lam=lam, footprint=footprint)
    j = int(np.argmin(ER))
    if ER[j] < best_e:
        best_t, best_e = R[j], float(ER[j])
    alt = np.r_[np.c_[R, ER], np.c_[C[order], E[order]]]
    alt = alt[np.argsort(alt[:, 3], kind="stable")]
    return Match(t=best_t, energy=best_e, icp_iterations=iters, candidates=C.shape[0],
                 alternatives=alt)
