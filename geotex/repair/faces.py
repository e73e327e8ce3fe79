"""Removing degenerate and duplicate faces."""

from __future__ import annotations

import numpy as np

from geotex.mesh.geometry import degenerate_faces

__all__ = ["without_degenerate_faces", "without_duplicate_faces"]


def without_degenerate_faces(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, int]:
    """Drop faces with a repeated vertex or zero area.

    Returns
    -------
    F : numpy.ndarray, (m', 3) int64
    removed : int
    """
    bad = degenerate_faces(V, F)
    keep = np.ones(F.shape[0], dtype=bool)
    keep[bad] = False
    return F[keep].copy(), int(bad.size)


def without_duplicate_faces(F: np.ndarray) -> tuple[np.ndarray, int]:
    """Resolve faces that share one vertex set.

    Within each group of faces on the same three vertices, copies of opposite
    orientation cancel in pairs (so the double wall between two glued solids
    disappears); if copies remain, the first of the surviving orientation is
    kept.

    Returns
    -------
    F : numpy.ndarray, (m', 3) int64
        Surviving faces in their original order.
    removed : int
    """
    m = F.shape[0]
    if m == 0:
        return F.copy(), 0
    _, first, group = np.unique(np.sort(F, axis=1), axis=0, return_index=True,
                                return_inverse=True)
    group = group.ravel()
    if first.size == m:
        return F.copy(), 0
    # orientation parity: rotate so the smallest index comes first, then compare
    start = np.argmin(F, axis=1)
    rot = np.take_along_axis(F, (start[:, None] + np.arange(3)) % 3, axis=1)
    positive = rot[:, 1] < rot[:, 2]
    net = (np.bincount(group, weights=positive, minlength=first.size)
           - np.bincount(group, weights=~positive, minlength=first.size)).astype(np.int64)
    wanted = np.where(net > 0, True, False)[group] == positive
    candidates = np.flatnonzero((net[group] != 0) & wanted)
    # first candidate of each group
    _, keep_idx = np.unique(group[candidates], return_index=True)
    keep = np.sort(candidates[keep_idx])
    return F[keep].copy(), int(m - keep.size)
