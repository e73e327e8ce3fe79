"""The thin mesh record used by the file and user-facing layers."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_faces, as_vertices

__all__ = ["Mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh with optional texture coordinates and texture image.

    The record only carries arrays; algorithms are free functions over
    ``(mesh.vertices, mesh.faces)``.  Arrays are converted and validated once,
    on construction.

    Parameters
    ----------
    vertices : array_like, (n, 3) float64
        Vertex positions.
    faces : array_like, (m, 3) int64
        Triangles as vertex indices, counter-clockwise seen from outside.
    uv : array_like, (k, 2) float64, optional
        Texture coordinates, indexed by ``uv_faces``.
    uv_faces : array_like, (m, 3) int64, optional
        Per-corner indices into ``uv``; required with ``uv``.
    texture : numpy.ndarray, (h, w, 3 or 4) uint8, optional
        Texture image (row 0 is the top of the image; ``v = 0`` is the bottom).
    name : str, optional
        Free-form name (file stem, object name).
    metadata : dict, optional
        Free-form metadata (unit, source file, ...).

    Raises
    ------
    InputError
        If any array has the wrong shape or out-of-range indices.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray | None = None
    uv_faces: np.ndarray | None = None
    texture: np.ndarray | None = None
    name: str = ""
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        V = as_vertices(self.vertices, name="vertices")
        F = as_faces(self.faces, V.shape[0], name="faces")
        object.__setattr__(self, "vertices", V)
        object.__setattr__(self, "faces", F)
        if (self.uv is None) != (self.uv_faces is None):
            raise InputError("uv and uv_faces must be given together")
        if self.uv is not None:
            uv = np.ascontiguousarray(self.uv, dtype=np.float64)
            if uv.ndim != 2 or uv.shape[1] != 2:
                raise InputError(f"uv must have shape (k, 2), got {uv.shape}")
            if not np.isfinite(uv).all():
                raise InputError("uv has non-finite texture coordinates")
            FT = as_faces(self.uv_faces, uv.shape[0], name="uv_faces")
            if FT.shape[0] != F.shape[0]:
                raise InputError(
                    f"uv_faces has {FT.shape[0]} rows but faces has {F.shape[0]}")
            object.__setattr__(self, "uv", uv)
            object.__setattr__(self, "uv_faces", FT)
        if self.texture is not None:
            tex = np.ascontiguousarray(self.texture)
            if tex.dtype != np.uint8 or tex.ndim != 3 or tex.shape[2] not in (3, 4):
                raise InputError("texture must be an (h, w, 3 or 4) uint8 image")
            object.__setattr__(self, "texture", tex)

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.vertices.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of triangles."""
        return int(self.faces.shape[0])

    @property
    def has_uv(self) -> bool:
        """Whether texture coordinates are present."""
        return self.uv is not None

    def with_geometry(self, vertices, faces) -> "Mesh":
        """Return a copy with new vertices and faces and no texture data."""
        return Mesh(vertices, faces, name=self.name, metadata=dict(self.metadata))

    def replace(self, **changes) -> "Mesh":
        """Return a copy with the given fields replaced (validated again)."""
        return replace(self, **changes)
