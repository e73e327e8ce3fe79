"""Nesting depth of closed components (which shells are cavities of which)."""

from __future__ import annotations

import igl
import numpy as np

__all__ = ["component_nesting_depth"]

#: Above this many closed components nesting is not computed (assumed depth 0).
MAX_NESTING_COMPONENTS = 256


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
        w = igl.winding_number(Vn, Fc, Pn)
        inside = np.abs(w) > 0.5
        inside[c] = False
        depth += inside
    return depth
