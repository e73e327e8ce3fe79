"""Bridge between ``(V, F)`` arrays and manifold3d solids (float64 throughout)."""

from __future__ import annotations

import manifold3d
import numpy as np

__all__ = ["manifold_of", "arrays_of_manifold", "manifold_status"]


def manifold_of(V: np.ndarray, F: np.ndarray) -> manifold3d.Manifold:
    """Return a manifold3d solid built from ``(V, F)`` (check ``.status()``)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    if not V.flags.writeable:
        V = V.copy()
    mesh = manifold3d.Mesh64(vert_properties=V,
                             tri_verts=np.ascontiguousarray(F, dtype=np.uint64))
    return manifold3d.Manifold(mesh)


def arrays_of_manifold(solid: manifold3d.Manifold) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(V, F)`` of a manifold3d solid as float64 / int64 arrays (own copies)."""
    mesh = solid.to_mesh64()
    # copies: manifold3d hands out read-only views, which it refuses to take back
    V = np.array(np.asarray(mesh.vert_properties)[:, :3], dtype=np.float64, order="C")
    F = np.array(mesh.tri_verts, dtype=np.int64, order="C")
    return V, F


def manifold_status(V: np.ndarray, F: np.ndarray) -> str:
    """Return manifold3d's verdict on ``(V, F)``: ``"NoError"`` or the error name."""
    if F.shape[0] == 0:
        return "Empty"
    return manifold_of(V, F).status().name
