"""Resolving self-intersections: boolean union of shells, then local cut-and-fill."""

from __future__ import annotations

import manifold3d
import numpy as np
import pymeshlab

from geotex.check.intersections import self_intersecting_pairs
from geotex.mesh.meshlab import arrays_of, meshset_of
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.mesh.topology import face_components
from geotex.repair.holes import filled_holes

__all__ = ["union_of_shells", "without_intersecting_faces"]


def union_of_shells(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Return the boolean union of the closed shells of ``(V, F)``, or ``None``.

    Overlapping closed components (a handle pushed through a body, a lid
    sitting in a pot) are merged into one solid by manifold3d.  Returns
    ``None`` when manifold3d does not accept the input as manifold.
    """
    count, labels = face_components(F, V.shape[0])
    parts = []
    for c in range(count):
        Fc = F[labels == c]
        used, inv = np.unique(Fc, return_inverse=True)
        solid = manifold_of(V[used], inv.reshape(-1, 3))
        if solid.status() != manifold3d.Error.NoError:
            return None
        parts.append(solid)
    if not parts:
        return None
    out = manifold3d.Manifold.batch_boolean(parts, manifold3d.OpType.Add) \
        if len(parts) > 1 else parts[0]
    return arrays_of_manifold(out)


def without_intersecting_faces(V: np.ndarray, F: np.ndarray, *, rounds: int = 6,
                               max_fraction: float = 0.1
                               ) -> tuple[np.ndarray, np.ndarray, int]:
    """Delete intersecting faces (and a ring around them) and close the holes.

    A local, lossy repair for a shell that crosses itself.  Repeats up to
    ``rounds`` times while intersections remain.  A round that would delete
    more than ``max_fraction`` of the faces is not carried out: the mesh is
    returned as it is, with its remaining intersections counted.

    Returns
    -------
    V : numpy.ndarray, (n', 3) float64
    F : numpy.ndarray, (m', 3) int64
    remaining : int
        Self-intersecting pairs left at the end.
    """
    pairs = self_intersecting_pairs(V, F)
    for _ in range(rounds):
        if pairs.shape[0] == 0:
            break
        bad = np.zeros(F.shape[0], dtype=bool)
        bad[pairs.ravel()] = True
        # grow the selection by one vertex ring for cleaner holes
        ring = np.zeros(V.shape[0], dtype=bool)
        ring[F[bad].ravel()] = True
        bad |= ring[F].any(axis=1)
        if bad.sum() > max_fraction * F.shape[0]:
            break
        ms = meshset_of(V, F[~bad])
        ms.meshing_remove_unreferenced_vertices()
        try:
            ms.meshing_repair_non_manifold_edges()
            ms.meshing_repair_non_manifold_vertices()
        except pymeshlab.PyMeshLabException:
            pass
        V, F = arrays_of(ms)
        V, F, _ = filled_holes(V, F)
        pairs = self_intersecting_pairs(V, F)
    return V, F, int(pairs.shape[0])
