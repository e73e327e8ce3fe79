"""Merging coincident vertices and dropping unreferenced ones."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from geotex.mesh.topology import compacted

__all__ = ["welded", "without_unreferenced_vertices", "default_weld_tolerance"]


def default_weld_tolerance(V: np.ndarray) -> float:
    """Return ``1e-6`` times the bounding-box diagonal (0 for an empty mesh)."""
    if V.shape[0] == 0:
        return 0.0
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    return 1e-6 * diag if np.isfinite(diag) else 0.0


def welded(V: np.ndarray, F: np.ndarray, *, tolerance: float = 0.0
           ) -> tuple[np.ndarray, np.ndarray, int]:
    """Merge vertices closer than ``tolerance`` (exact duplicates when 0).

    Vertices are merged transitively (clusters of vertices chained by
    close pairs); each cluster becomes the position of its lowest-index
    vertex, so the result does not depend on floating-point averaging.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    tolerance : float, optional
        Absolute merge distance.

    Returns
    -------
    V : numpy.ndarray, (n', 3) float64
        Surviving vertices in order of their first (lowest) index.
    F : numpy.ndarray, (m, 3) int64
        Faces re-indexed (may now contain repeated indices).
    merged : int
        ``n - n'``.
    """
    n = V.shape[0]
    if n == 0:
        return V.copy(), F.copy(), 0
    if tolerance > 0:
        pairs = cKDTree(V).query_pairs(tolerance, output_type="ndarray")
        g = sp.coo_matrix((np.ones(len(pairs), np.int8), (pairs[:, 0], pairs[:, 1])),
                          shape=(n, n))
        _, label = connected_components(g, directed=False)
    else:
        _, label = np.unique(V, axis=0, return_inverse=True)
        label = label.ravel()
    # representative = lowest index in each cluster, clusters ordered by it
    rep = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(rep, label, np.arange(n))
    order = np.argsort(rep, kind="stable")
    new_id = np.empty_like(order)
    new_id[order] = np.arange(order.size)
    mapping = new_id[label]
    return V[rep[order]].copy(), mapping[F], int(n - order.size)


def without_unreferenced_vertices(V: np.ndarray, F: np.ndarray
                                  ) -> tuple[np.ndarray, np.ndarray, int]:
    """Drop vertices no face uses, keeping the order of the others.

    Returns
    -------
    V : numpy.ndarray, (n', 3) float64
    F : numpy.ndarray, (m, 3) int64
    removed : int
    """
    V2, F2 = compacted(V, F)
    return V2, F2, int(V.shape[0] - V2.shape[0])
