"""Nesting depth of closed components (which shells are cavities of which)."""

from __future__ import annotations

import igl
import numpy as np

__all__ = ["component_nesting_depth"]

#: Above this many closed components nesting is not computed (assumed depth 0).
MAX_NESTING_COMPONENTS = 256


#: Up to this many (face, probe) pairs winding numbers are summed exactly in numpy;
#: above it libigl's fast (hierarchical) winding number is used. libigl's exact
#: ``winding_number`` is far slower than either (7 s for 2 probes on 1.3M faces).
EXACT_PAIRS = 20_000_000


def _winding_numbers(V: np.ndarray, F: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Generalized winding numbers of points ``P`` (k, 3) w.r.t. triangles ``(V, F)``."""
    if F.shape[0] * P.shape[0] > EXACT_PAIRS:
        return np.asarray(igl.fast_winding_number(V, F, P))
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    out = np.empty(P.shape[0])
    for i, p in enumerate(P):  # solid angle of every triangle (Van Oosterom-Strackee)
        a, b, c = A - p, B - p, C - p
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc
               + np.einsum("ij,ij->i", b, c) * la + np.einsum("ij,ij->i", c, a) * lb)
        out[i] = np.arctan2(num, den).sum() / (2.0 * np.pi)
    return out


def component_nesting_depth(V: np.ndarray, F: np.ndarray, face_labels: np.ndarray,
                            count: int, closed: np.ndarray) -> np.ndarray:
    """Return how many other closed components enclose each component.

    A component's depth decides its correct orientation: shells at even depth
    bound material and must face outward (positive volume), shells at odd
    depth bound cavities and must face inward.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    face_labels : numpy.ndarray, (m,) int64
        Component of every face, ``0 .. count - 1``.
    count : int
        Number of components.
    closed : numpy.ndarray, (count,) bool
        Which components are closed (only those can enclose anything).

    Returns
    -------
    numpy.ndarray, (count,) int64
        Nesting depth; zeros when there are more than
        ``MAX_NESTING_COMPONENTS`` closed components.
    """
    depth = np.zeros(count, dtype=np.int64)
    closed_ids = np.flatnonzero(closed)
    if closed_ids.size < 2 or closed_ids.size > MAX_NESTING_COMPONENTS:
        return depth
    # one probe point per component: the centroid of its first face
    first_face = np.full(count, -1, dtype=np.int64)
    order = np.arange(F.shape[0])[::-1]
    first_face[face_labels[order]] = order
    probes = V[F[first_face]].mean(axis=1)
    scale = float(np.max(V.max(axis=0) - V.min(axis=0))) or 1.0
    center = 0.5 * (V.max(axis=0) + V.min(axis=0))
    Vn = (V - center) / scale
    Pn = (probes - center) / scale
    for c in closed_ids:
        Fc = F[face_labels == c]
        w = _winding_numbers(Vn, Fc, Pn)
        inside = np.abs(w) > 0.5
        inside[c] = False
        depth += inside
    return depth
