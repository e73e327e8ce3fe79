"""Bridge between ``(V, F)`` arrays and pymeshlab mesh sets (float64 / int64 on our side).

The manifold3d bridge is :mod:`geotex.mesh.solid`.
"""

from __future__ import annotations

import numpy as np
import pymeshlab

__all__ = ["meshset_of", "arrays_of"]


def meshset_of(V: np.ndarray, F: np.ndarray) -> pymeshlab.MeshSet:
    """Return a pymeshlab ``MeshSet`` holding one copy of ``(V, F)``."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, dtype=np.float64),
                               face_matrix=np.asarray(F).astype(np.int32)))
    return ms


def arrays_of(ms: pymeshlab.MeshSet) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(V, F)`` of the current mesh of ``ms`` as float64 / int64 copies."""
    cm = ms.current_mesh()
    return (np.ascontiguousarray(cm.vertex_matrix(), dtype=np.float64),
            np.ascontiguousarray(cm.face_matrix(), dtype=np.int64))
