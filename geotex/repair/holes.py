"""Closing holes and splitting non-manifold elements."""

from __future__ import annotations

import igl
import numpy as np
import pymeshlab

from geotex.mesh.meshlab import arrays_of, meshset_of
from geotex.mesh.topology import edge_topology, non_manifold_vertices

__all__ = ["filled_holes", "split_non_manifold"]


def split_non_manifold(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Duplicate vertices so every edge and vertex becomes manifold.

    Faces are kept; sheets that met along a non-manifold edge or at a
    non-manifold vertex are separated.

    Returns
    -------
    V : numpy.ndarray, (n', 3) float64
    F : numpy.ndarray, (m, 3) int64
    added : int
        Number of vertices added.
    """
    if F.shape[0] == 0:
        return V.copy(), F.copy(), 0
    topo = edge_topology(F, V.shape[0])
    if topo.non_manifold.size == 0 and non_manifold_vertices(F, V.shape[0], topo).size == 0:
        return V.copy(), F.copy(), 0
    SF, SVI = igl.split_nonmanifold(F)
    SF = np.asarray(SF, dtype=np.int64)
    SVI = np.asarray(SVI, dtype=np.int64)
    return V[SVI].copy(), SF, int(SVI.size - V.shape[0])


def filled_holes(V: np.ndarray, F: np.ndarray, *, max_hole_edges: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray, int]:
    """Close boundary loops with new triangles (pymeshlab's ear-cut hole filler).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        A mesh with manifold edges (split non-manifold parts first).
    max_hole_edges : int, optional
        Largest hole (in boundary edges) to close; all by default.

    Returns
    -------
    V : numpy.ndarray, (n', 3) float64
    F : numpy.ndarray, (m', 3) int64
    added_faces : int
    """
    topo = edge_topology(F, V.shape[0])
    n_boundary = int(topo.boundary.size)
    if n_boundary == 0:
        return V.copy(), F.copy(), 0
    limit = max_hole_edges if max_hole_edges is not None else n_boundary + 1
    ms = meshset_of(V, F)
    try:
        ms.meshing_close_holes(maxholesize=int(limit), selfintersection=False)
    except pymeshlab.PyMeshLabException:
        return V.copy(), F.copy(), 0
    V2, F2 = arrays_of(ms)
    return V2, F2, int(F2.shape[0] - F.shape[0])
