"""Consistent and outward face orientation."""

from __future__ import annotations

import igl
import numpy as np

from geotex.check.nesting import component_nesting_depth
from geotex.mesh.geometry import component_volumes
from geotex.mesh.topology import edge_topology, face_components

__all__ = ["consistently_oriented", "outward_oriented"]


def consistently_oriented(F: np.ndarray) -> tuple[np.ndarray, int]:
    """Flip faces so that neighbours agree, per connected patch (BFS).

    Returns
    -------
    F : numpy.ndarray, (m, 3) int64
    flipped : int
        Number of faces whose orientation changed.
    """
    if F.shape[0] == 0:
        return F.copy(), 0
    FF, _ = igl.bfs_orient(F)
    FF = np.asarray(FF, dtype=np.int64)
    flipped = int(np.count_nonzero((FF != F).any(axis=1)))
    return FF, flipped


def outward_oriented(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, int]:
    """Orient each closed component outward (cavities inward), open ones by centroid.

    Closed components are flipped when the sign of their volume disagrees with
    their nesting depth (even depth bounds material, odd depth a cavity).
    Open components use libigl's ``orient_outward`` heuristic.

    Returns
    -------
    F : numpy.ndarray, (m, 3) int64
    flipped_components : int
    """
    m = F.shape[0]
    if m == 0:
        return F.copy(), 0
    n = V.shape[0]
    count, labels = face_components(F, n)
    topo = edge_topology(F, n)
    closed = np.ones(count, dtype=bool)
    open_edges = np.flatnonzero(topo.face_count != 2)
    if open_edges.size:
        ef = topo.edge_faces()
        closed[labels[ef[open_edges, 0]]] = False
    scale = float(np.max(V.max(axis=0) - V.min(axis=0))) or 1.0
    vol = component_volumes(V / scale, F, labels, count)
    depth = component_nesting_depth(V, F, labels, count, closed)
    expected = np.where(depth % 2 == 0, 1.0, -1.0)
    flip_comp = closed & (np.sign(vol) == -expected) & (vol != 0)
    out = F.copy()
    if (~closed).any():
        # libigl wants the component ids as an (m, 1) column
        oo, _ = igl.orient_outward(V, F, labels.reshape(-1, 1))
        oo = np.asarray(oo, dtype=np.int64)
        open_faces = ~closed[labels]
        out[open_faces] = oo[open_faces]
        flip_open = np.zeros(count, dtype=bool)
        changed = (oo != F).any(axis=1) & open_faces
        flip_open[np.unique(labels[changed])] = True
    else:
        flip_open = np.zeros(count, dtype=bool)
    flip_faces = flip_comp[labels]
    out[flip_faces] = out[flip_faces][:, ::-1]
    return out, int(flip_comp.sum() + flip_open.sum())
