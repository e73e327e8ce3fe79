"""What a hierarchical pattern mapping returns, and its image and mesh files.

:class:`HPMLevel` (what happened on one cluster level) and :class:`HPMResult`
(the split-vertex uv of :func:`geotex.image.hpm.hpm_texture` and its report),
:func:`read_hpm_image` (the texture sample from a file) and :func:`hpm_mesh`
(the base with the uv and the image, ready for a GLB or OBJ+MTL+PNG writer).
All are re-exported by :mod:`geotex.image.hpm`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from PIL import Image

from geotex.errors import InputError, MissingFileError
from geotex.image.patches import load_image
from geotex.mesh.record import Mesh

__all__ = ["HPMLevel", "HPMResult", "read_hpm_image", "hpm_mesh"]


@dataclass
class HPMLevel:
    """What happened on one level of the hierarchy."""

    level: int
    clusters: int
    placed: int = 0
    subdivided: int = 0
    errors: list = field(default_factory=list)
    filled_faces: int = 0
    continued: int = 0
    refused: dict = field(default_factory=dict)
    projected: int = 0
    free_border: int = 0
    matched_faces: int = 0
    forced: int = 0
    lattice_snapped: int = 0
    field_refused: int = 0
    quick: int = 0

    @property
    def mean_error(self) -> float:
        """Mean relative matching error of the placed clusters (nan if none)."""
        return float(np.mean(self.errors)) if self.errors else float("nan")

    def as_dict(self) -> dict:
        """JSON-ready summary."""
        return {"level": self.level, "clusters": self.clusters, "placed": self.placed,
                "subdivided": self.subdivided,
                "mean_error": None if not self.errors else self.mean_error,
                "filled_faces": self.filled_faces, "continued": self.continued,
                "refused": dict(sorted(self.refused.items())), "projected": self.projected,
                "free_border": self.free_border, "matched_faces": self.matched_faces,
                "forced": self.forced, "lattice_snapped": self.lattice_snapped,
                "field_refused": self.field_refused, "quick": self.quick}


@dataclass(frozen=True, eq=False)
class HPMResult:
    """Texture coordinates of a hierarchical pattern mapping.

    Attributes
    ----------
    uv : numpy.ndarray, (k, 2) float64
        Texture coordinates into the input image (``u`` right, ``v`` up,
        ``[0, 1]`` over the image).
    uv_faces : numpy.ndarray, (m, 3) int64
        Per-corner indices into ``uv``; a vertex has several uv only where
        the mapping jumps.
    patch : numpy.ndarray, (m,) int64
        Placement that textured every face (``-1``: filled at face level).
    face_level : numpy.ndarray, (m,) int64
        Hierarchy level of that placement (the last level for filled faces).
    levels : list of HPMLevel
    pattern : dict
        The sample's pattern estimate and what was derived from it
        (:func:`geotex.image.fftmatch.pattern_scale`): ``periodic``,
        ``period_px``, ``correlation_length_px``, ``coherence``,
        ``min_patch`` (surface units, 0 when not used), ``band_width``
        (surface units) and, for a periodic sample, ``patch_periods``: the
        area-weighted median equivalent-disc diameter of the placements, in
        pattern periods (below 1 the patches are smaller than the pattern,
        whose structure may then break at their borders, paper §5.2:
        Fertility with the rope net 0.93 at 0.3 x its diagonal, where the
        net is broken, 1.27 at 0.15, where it reads as a net; Bob with the
        basket weave 1.11 at 0.35, 1.37 at 0.2; Spot (23k faces) with
        bricks 0.87 at 0.35, where the rows still read as rows).
    """

    uv: np.ndarray
    uv_faces: np.ndarray
    patch: np.ndarray
    face_level: np.ndarray
    levels: list
    pattern: dict = field(default_factory=dict)

    def report(self) -> dict:
        """Per-level counts and mean matching errors, JSON-ready."""
        return {"levels": [lv.as_dict() for lv in self.levels],
                "placements": int(self.patch.max() + 1) if self.patch.size else 0,
                "vertices_split": int(self.uv.shape[0]), "pattern": dict(self.pattern)}


def _split_uv(corner, F, width, height):
    """Split-vertex texture coordinates from per-corner pixel positions.

    ``corner`` (m, 3, 2) full-resolution pixel positions of every face's
    corners, ``F`` (m, 3) the faces, ``width`` and ``height`` the image's
    size.  A vertex is split only where its corners' positions differ; the
    uv rows come in the order of their first corner.

    Returns
    -------
    uv : numpy.ndarray, (k, 2) float64
        In ``[0, 1]``, v up (image rows grow downwards).
    uv_faces : numpy.ndarray, (m, 3) int64
    """
    m = F.shape[0]
    uvpix = corner.reshape(-1, 2)
    uv = np.stack([uvpix[:, 0] / width, 1.0 - uvpix[:, 1] / height], 1)
    key = np.column_stack([F.ravel(), uv])
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    uv_out = uv[first[order]]
    uv_faces = rank[inv.ravel()].reshape(m, 3).astype(np.int64)
    return uv_out, uv_faces


def _median_patch_diameter(patch, A):
    """Area-weighted median, over the placed faces, of the equivalent-disc diameter of
    the placement that textured each (``patch`` (m,) placement per face, -1 for none;
    ``A`` (m,) face areas); None when no face was placed."""
    placed_ = patch >= 0
    if not placed_.any():
        return None
    pa = np.bincount(patch[placed_], weights=A[placed_])
    dia = 2.0 * np.sqrt(pa[patch[placed_]] / np.pi)
    o = np.argsort(dia, kind="stable")
    cw = np.cumsum(A[placed_][o])
    return float(dia[o][np.searchsorted(cw, 0.5 * cw[-1])])


def read_hpm_image(path) -> np.ndarray:
    """Read the texture sample: a grey or RGB(A) picture, as ``(h, w, 3)`` uint8.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    numpy.ndarray, (h, w, 3) uint8

    Raises
    ------
    MissingFileError
        If the file does not exist.
    InputError
        If it is not a readable picture, or not grey/RGB (e.g. CMYK, float).
    """
    from pathlib import Path

    p = Path(path)
    if not p.is_file():
        raise MissingFileError(f"{p}: no such image file")
    try:
        with Image.open(p) as im:
            mode = im.mode
    except Exception as exc:  # pillow raises many types for unreadable images
        raise InputError(f"{p}: cannot read the image ({type(exc).__name__}); "
                         "give a PNG or JPEG file") from None
    if mode not in ("1", "L", "LA", "P", "PA", "RGB", "RGBA"):
        raise InputError(f"{p}: the image is {mode}, not 8-bit RGB or grey; convert it to an "
                         "8-bit RGB or grey PNG/JPEG first")
    arr = load_image(p)
    if min(arr.shape[:2]) < 8:
        raise InputError(f"{p}: the image is {arr.shape[1]} x {arr.shape[0]} pixels; give one "
                         "of at least 8 x 8")
    return np.ascontiguousarray(arr[:, :, :3])


def hpm_mesh(V, F, result: HPMResult, image, *, name: str = ""):
    """The textured mesh record: the base with ``result``'s uv and the image itself.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    result : HPMResult
    image : numpy.ndarray, (h, w, 3) uint8
    name : str, optional

    Returns
    -------
    geotex.mesh.record.Mesh
    """
    return Mesh(V, F, uv=result.uv, uv_faces=result.uv_faces,
                texture=np.ascontiguousarray(image[:, :, :3]), name=name,
                metadata={"hpm": result.report()})
