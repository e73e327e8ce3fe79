"""Paste records of a lapped texture (lapped textures §3.5, §4) and their file.

A :class:`Paste` is one paste operation: the texture patch, the surface
faces, and the texture coordinates of their vertices.  A
:class:`LappedTexture` is the ordered list of pastes (later pastes lie on top)
with the texture patches they use; it is everything the compositing step
needs, and it is saved as one ``.npz`` (:func:`save_lapped`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geotex.errors import MeshFileError
from geotex.image.patches import TexturePatch
from geotex.io.records import read_record, write_record

__all__ = ["Paste", "LappedTexture", "save_lapped", "load_lapped", "LAPPED_FORMAT"]

#: Format tag of lapped-texture files.
LAPPED_FORMAT = "geotex-lapped-texture/1"


@dataclass(frozen=True, eq=False)
class Paste:
    """One paste operation.

    Attributes
    ----------
    patch : int
        Index of the texture patch in :attr:`LappedTexture.patches`.
    faces : numpy.ndarray, (k,) int64
        Surface faces (growth order; ``faces[0]`` is the seed face).
    corner_uv : numpy.ndarray, (k, 3, 2) float64
        Texture coordinates of the corners of every face (in the corner
        order of ``F[faces]``); neighbouring faces of one paste share the
        coordinates of their common vertices.
    directions : numpy.ndarray, (k, 3) float64
        The unit tangent "up" direction the paste was aligned to on each face
        (the field's representative, or the propagated direction of an
        isotropic paste).
    seed_point : numpy.ndarray, (3,) float64
        Surface point mapped to the patch centre.
    rounds : int
        Grow-and-optimize rounds used.
    """

    patch: int
    faces: np.ndarray
    corner_uv: np.ndarray
    directions: np.ndarray
    seed_point: np.ndarray
    rounds: int = 1

    @property
    def n_faces(self) -> int:
        """Faces in the paste."""
        return int(self.faces.shape[0])

    @property
    def seed_face(self) -> int:
        """The face the paste was centred on."""
        return int(self.faces[0])


@dataclass(frozen=True, eq=False)
class LappedTexture:
    """All pastes over one mesh, in compositing order (later on top).

    Attributes
    ----------
    pastes : tuple of Paste
    patches : tuple of TexturePatch
    n_vertices, n_faces : int
        Size of the mesh the pastes refer to.
    coverage : numpy.ndarray, (m,) float64
        Covered fraction of every face (1.0 everywhere when complete).
    metadata : dict
        Options used (scale, field, seed, ...).
    """

    pastes: tuple
    patches: tuple
    n_vertices: int
    n_faces: int
    coverage: np.ndarray
    metadata: dict

    @property
    def complete(self) -> bool:
        """Whether every face is fully covered."""
        return bool(np.all(self.coverage >= 1.0))

    @property
    def n_pastes(self) -> int:
        """Number of paste operations."""
        return len(self.pastes)

    def layers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """All pasted faces stacked: ``(face, paste, patch, corner_uv)``.

        Returns
        -------
        face, paste, patch : numpy.ndarray, (t,) int64
            Entries in paste order (within a paste, growth order).
        corner_uv : numpy.ndarray, (t, 3, 2) float64
        """
        if not self.pastes:
            z = np.zeros(0, np.int64)
            return z, z, z, np.zeros((0, 3, 2))
        face = np.concatenate([p.faces for p in self.pastes])
        counts = [p.n_faces for p in self.pastes]
        paste = np.repeat(np.arange(len(self.pastes), dtype=np.int64), counts)
        patch = np.repeat(np.array([p.patch for p in self.pastes], np.int64), counts)
        uv = np.concatenate([p.corner_uv for p in self.pastes])
        return face, paste, patch, uv


def save_lapped(path, lapped: LappedTexture) -> Path:
    """Write the paste records and texture patches to an ``.npz`` file (atomic).

    Arrays: ``face``, ``paste``, ``corner_uv``, ``directions`` (stacked as in
    :meth:`LappedTexture.layers`), per paste ``patch``, ``seed_point`` and
    ``rounds``, per texture patch ``patch_<i>_rgba`` / ``_center`` / ``_hull``,
    ``coverage``, and ``metadata`` (JSON with ``format``, mesh size and the
    options used).

    Returns
    -------
    pathlib.Path
    """
    face, paste, _, uv = lapped.layers()
    arrays = dict(face=face, paste=paste, corner_uv=uv,
                  directions=(np.concatenate([p.directions for p in lapped.pastes])
                              if lapped.pastes else np.zeros((0, 3))),
                  patch=np.array([p.patch for p in lapped.pastes], np.int64),
                  seed_point=np.array([p.seed_point for p in lapped.pastes]).reshape(-1, 3),
                  rounds=np.array([p.rounds for p in lapped.pastes], np.int64),
                  coverage=lapped.coverage)
    for i, tp in enumerate(lapped.patches):
        arrays[f"patch_{i}_rgba"] = tp.rgba
        arrays[f"patch_{i}_center"] = tp.center
        arrays[f"patch_{i}_hull"] = tp.hull
    meta = {"format": LAPPED_FORMAT, "n_vertices": lapped.n_vertices,
            "n_faces": lapped.n_faces, "n_patches": len(lapped.patches), **lapped.metadata}
    arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    return write_record(path, arrays, compressed=True, kind="paste record")


def load_lapped(path) -> LappedTexture:
    """Read a file written by :func:`save_lapped`.

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MeshFileError
        If it is not a lapped-texture file or is damaged.
    """
    path = Path(path)
    d, meta = read_record(path, kind="lapped-texture", format=LAPPED_FORMAT,
                          arrays=_lapped_arrays, hint="write one with 'geotex lapped'")
    try:
        patches = []
        for i in range(int(meta["n_patches"])):
            rgba = d[f"patch_{i}_rgba"]
            L = float(max(rgba.shape[:2]))
            patches.append(TexturePatch(
                rgba=rgba, size=np.array([rgba.shape[1] / L, rgba.shape[0] / L]),
                center=d[f"patch_{i}_center"], hull=d[f"patch_{i}_hull"]))
        face, paste, uv, dirs = d["face"], d["paste"], d["corner_uv"], d["directions"]
        starts = np.searchsorted(paste, np.arange(d["patch"].shape[0] + 1))
        pastes = tuple(
            Paste(patch=int(d["patch"][i]), faces=face[starts[i]:starts[i + 1]],
                  corner_uv=uv[starts[i]:starts[i + 1]],
                  directions=dirs[starts[i]:starts[i + 1]], seed_point=d["seed_point"][i],
                  rounds=int(d["rounds"][i]))
            for i in range(d["patch"].shape[0]))
        n_vertices, n_faces = int(meta["n_vertices"]), int(meta["n_faces"])
    except (ValueError, KeyError, TypeError, IndexError) as exc:
        raise MeshFileError(path, f"damaged or not a lapped-texture file "
                                  f"({type(exc).__name__}: inconsistent arrays or "
                                  "metadata)") from None
    extra = {k: v for k, v in meta.items()
             if k not in ("format", "n_vertices", "n_faces", "n_patches")}
    return LappedTexture(pastes=pastes, patches=tuple(patches), n_vertices=n_vertices,
                         n_faces=n_faces, coverage=d["coverage"], metadata=extra)


def _lapped_arrays(meta: dict) -> list[str]:
    """Names of the arrays a lapped-texture file with this metadata holds."""
    return (["face", "paste", "corner_uv", "directions", "patch", "seed_point", "rounds",
             "coverage"]
            + [f"patch_{i}_{part}" for i in range(int(meta["n_patches"]))
               for part in ("rgba", "center", "hull")])
