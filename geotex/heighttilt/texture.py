"""The height-and-tilt texture record and its ``.npz`` file format."""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, field

import numpy as np

from geotex.errors import InputError, MeshFileError
from geotex.io.records import read_record, write_record
from geotex.mesh.arrays import as_faces
from geotex.mesh.topology import edge_topology

__all__ = ["HeightTiltTexture", "save_texture", "load_texture", "FORMAT_TAG"]

FORMAT_TAG = "geotex.heighttilt/1"


@dataclass(frozen=True, eq=False)
class HeightTiltTexture:
    """A height-and-tilt geometric texture over a fixed connectivity.

    Attributes
    ----------
    height : numpy.ndarray, (n,) float64
        Pseudo-height per vertex, ``sign(d . n) |d|`` with sign(0) = +1.
    tilt : numpy.ndarray, (e,) float64
        Tilt 1-form coefficients in geotex's unique edge order of ``faces``
        (``edge_topology(faces, n).edges``).
    faces : numpy.ndarray, (m, 3) int64
        Connectivity the texture belongs to.
    residual : numpy.ndarray, (n, 2) float64
        The part of the vertex tilt the 1-form does not reproduce, as
        components in the vertex frames
        ``geotex.heighttilt.base.tilt_frames(Vs, faces, tilt)``: ``T1`` along
        the direction the 1-form itself decodes to, so the numbers do not
        depend on the indexing (zero for a purely 1-form texture; see
        :func:`geotex.heighttilt.base.encode_tilt`).
    metadata : dict
        JSON-serialisable extra information.

    Raises
    ------
    InputError
        On construction with arrays of inconsistent shapes or non-finite values.
    """

    height: np.ndarray
    tilt: np.ndarray
    faces: np.ndarray
    residual: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        h = np.array(self.height, dtype=np.float64)
        if h.ndim != 1 or h.shape[0] == 0:
            raise InputError(f"height must be a non-empty (n,) array, got shape {h.shape}")
        n = h.shape[0]
        Fa = np.array(as_faces(self.faces, n, name="faces"), dtype=np.int64)
        if Fa.shape[0] == 0:
            raise InputError("faces is empty: a texture needs a connectivity")
        e = edge_topology(Fa, n).edges.shape[0]
        t = np.array(self.tilt, dtype=np.float64)
        if t.shape != (e,):
            raise InputError(f"tilt must have shape ({e},), one coefficient per unique edge "
                             f"of faces, got {t.shape}")
        r = (np.zeros((n, 2)) if self.residual is None
             else np.array(self.residual, dtype=np.float64))
        if r.shape != (n, 2):
            raise InputError(f"residual must have shape ({n}, 2), got {r.shape}")
        for name, a in (("height", h), ("tilt", t), ("residual", r)):
            if not np.isfinite(a).all():
                raise InputError(f"{name} has non-finite values")
            a.setflags(write=False)
        Fa.setflags(write=False)
        if not isinstance(self.metadata, dict):
            raise InputError(f"metadata must be a dict, got {type(self.metadata).__name__}")
        object.__setattr__(self, "height", h)
        object.__setattr__(self, "tilt", t)
        object.__setattr__(self, "faces", Fa)
        object.__setattr__(self, "residual", r)
        object.__setattr__(self, "metadata", dict(self.metadata))

    @classmethod
    def _trusted(cls, height, tilt, faces, residual, metadata, topology=None
                 ) -> "HeightTiltTexture":
        """Build from arrays the caller has already checked (shapes, finiteness).

        Skips the edge count of ``__post_init__`` (a sort of the half-edges),
        which the extraction and transfer code know already.  Arrays are
        copied and frozen.  ``topology`` (the ``EdgeTopology`` of ``faces``)
        is remembered, not saved: reconstruction reuses it instead of sorting
        the half-edges again.
        """
        tex = object.__new__(cls)
        if topology is not None:
            object.__setattr__(tex, "_topology", topology)
        for name, a, dtype in (("height", height, np.float64), ("tilt", tilt, np.float64),
                               ("faces", faces, np.int64), ("residual", residual, np.float64)):
            arr = np.array(a, dtype=dtype)
            arr.setflags(write=False)
            object.__setattr__(tex, name, arr)
        object.__setattr__(tex, "metadata", dict(metadata))
        return tex

    @property
    def n_vertices(self) -> int:
        """Number of vertices ``n``."""
        return int(self.height.shape[0])

    def replace(self, **changes) -> "HeightTiltTexture":
        """Return a copy with some fields replaced (validated again)."""
        kw = dict(height=self.height, tilt=self.tilt, faces=self.faces,
                  residual=self.residual, metadata=self.metadata)
        kw.update(changes)
        return HeightTiltTexture(**kw)


def save_texture(path, tex: HeightTiltTexture) -> None:
    """Write a texture to an ``.npz`` file atomically.

    The archive holds ``height``, ``tilt``, ``faces``, ``residual`` and
    ``header``: a JSON string with the format tag, the counts
    (vertices, faces, edges) and the metadata.

    Parameters
    ----------
    path : str or os.PathLike
    tex : HeightTiltTexture

    Raises
    ------
    InputError
        If ``tex`` is not a texture or its metadata is not JSON serialisable.
    MeshFileError
        If the file cannot be written.
    """
    if not isinstance(tex, HeightTiltTexture):
        raise InputError(f"tex must be a HeightTiltTexture, got {type(tex).__name__}")
    try:
        header = json.dumps({"format": FORMAT_TAG, "vertices": tex.n_vertices,
                             "faces": int(tex.faces.shape[0]), "edges": int(tex.tilt.shape[0]),
                             "metadata": tex.metadata}, sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise InputError(f"tex.metadata is not JSON serialisable: {exc}") from None
    write_record(path, dict(height=tex.height, tilt=tex.tilt, faces=tex.faces,
                            residual=tex.residual, header=np.array(header)), compressed=False)


def load_texture(path) -> HeightTiltTexture:
    """Read a texture written by :func:`save_texture`.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    HeightTiltTexture

    Raises
    ------
    MeshFileError
        If the file is missing, not an ``.npz`` archive, lacks an array, has a
        wrong format tag, or its arrays disagree with the header counts or
        with each other.
    """
    if not os.path.isfile(path):
        raise MeshFileError(path, "no such texture file")
    if not zipfile.is_zipfile(path):
        raise MeshFileError(path, "not a readable .npz texture file: not a zip archive "
                            "(truncated, or another kind of file; textures are written "
                            "by 'geotex heighttilt extract')")
    arrays, header = read_record(path, kind="texture", record="height-and-tilt texture",
                                 format=FORMAT_TAG, metadata_key="header",
                                 arrays=("height", "tilt", "faces", "residual"),
                                 hint="textures are written by 'geotex heighttilt extract'")
    counts = (arrays["height"].shape, arrays["faces"].shape[:1], arrays["tilt"].shape)
    if counts != ((header.get("vertices"),), (header.get("faces"),), (header.get("edges"),)):
        raise MeshFileError(path, "array sizes do not match the header counts "
                            f"(vertices, faces, edges = {header.get('vertices')}, "
                            f"{header.get('faces')}, {header.get('edges')})")
    try:
        return HeightTiltTexture(height=arrays["height"], tilt=arrays["tilt"],
                                 faces=arrays["faces"], residual=arrays["residual"],
                                 metadata=header.get("metadata") or {})
    except InputError as exc:
        raise MeshFileError(path, f"inconsistent texture: {exc}") from None
