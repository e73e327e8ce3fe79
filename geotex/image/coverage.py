"""Face coverage by rasterization (lapped textures §3.6).

The paper renders every pasted face into an off-screen buffer and counts, per
face, the pixels that some paste made opaque.  geotex rasterizes each face
on a fixed lattice in the face itself: ``r x r`` sub-triangles (barycentric
midpoint subdivision) and one sample at the centroid of each, ``r^2``
samples per face.  A sample is covered once a paste maps it to a texel with
alpha at or above the patch's ``opaque`` level.  The lattice is the same for
every face, so a paste's update is one vectorized evaluation of ``(k, r^2)``
texture coordinates and alpha lookups; a face is covered when all its
samples are, and an uncovered sample is remembered as the centre of a future
paste (the paper keeps "an uncovered point inside the face" the same way).
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.image.patches import TexturePatch, sample_alpha

__all__ = ["sample_lattice", "Coverage"]


def sample_lattice(resolution: int) -> np.ndarray:
    """Barycentric centroids of the ``r^2`` sub-triangles of a face.

    Parameters
    ----------
    resolution : int
        ``r >= 1``.

    Returns
    -------
    numpy.ndarray, (r^2, 3) float64
        Rows sum to 1, all entries in ``(0, 1)``.

    Examples
    --------
    >>> sample_lattice(1).round(12).tolist()       # the centroid
    [[0.333333333333, 0.333333333333, 0.333333333333]]
    >>> sample_lattice(4).shape
    (16, 3)
    """
    try:
        r = int(resolution)
    except (TypeError, ValueError):
        raise InputError(f"samples must be an integer >= 1, got {resolution!r}") from None
    if r < 1 or r != resolution:
        raise InputError(f"samples must be an integer >= 1, got {resolution!r}")
    pts = []
    for i in range(r):
        for j in range(r - i):
            pts.append(((i + 1 / 3) / r, (j + 1 / 3) / r))          # upward triangles
            if i + j < r - 1:
                pts.append(((i + 2 / 3) / r, (j + 2 / 3) / r))      # downward triangles
    b = np.array(pts, dtype=np.float64)
    return np.ascontiguousarray(np.stack([1.0 - b[:, 0] - b[:, 1], b[:, 0], b[:, 1]], axis=1))


class Coverage:
    """Covered samples of every face of a mesh.

    Parameters
    ----------
    n_faces : int
    resolution : int, optional
        Lattice resolution ``r`` (``r^2`` samples per face).

    Attributes
    ----------
    bary : numpy.ndarray, (s, 3) float64
        The sample lattice.
    covered : numpy.ndarray, (m, s) bool
    count : numpy.ndarray, (m,) int64
        Covered samples per face.
    """

    def __init__(self, n_faces: int, *, resolution: int = 4):
        self.bary = sample_lattice(resolution)
        self.covered = np.zeros((int(n_faces), self.bary.shape[0]), dtype=bool)
        self.count = np.zeros(int(n_faces), dtype=np.int64)

    @property
    def n_samples(self) -> int:
        """Samples per face."""
        return int(self.bary.shape[0])

    @property
    def covered_faces(self) -> np.ndarray:
        """``(m,)`` bool: faces whose every sample is covered."""
        return self.count == self.n_samples

    @property
    def complete(self) -> bool:
        """Whether every face is covered."""
        return bool(np.all(self.count == self.n_samples))

    def fraction(self) -> np.ndarray:
        """``(m,)`` float64: covered fraction of every face."""
        return self.count / float(self.n_samples)

    def update(self, faces, corner_uv, patch: TexturePatch) -> int:
        """Rasterize one paste: mark samples the patch makes opaque.

        Parameters
        ----------
        faces : array_like, (k,) int64
            Faces of the paste.
        corner_uv : array_like, (k, 3, 2) float64
            Texture coordinates of their corners.
        patch : TexturePatch

        Returns
        -------
        int
            Samples newly covered.
        """
        faces = np.asarray(faces, dtype=np.int64)
        Q = np.asarray(corner_uv, dtype=np.float64)
        uv = np.einsum("sj,kjc->ksc", self.bary, Q)
        hit = sample_alpha(patch, uv) >= patch.opaque
        before = self.count[faces]
        self.covered[faces] |= hit
        self.count[faces] = self.covered[faces].sum(axis=1)
        return int((self.count[faces] - before).sum())

    def mark(self, face: int, sample: int) -> None:
        """Mark one sample covered (used for a paste's own centre)."""
        if not self.covered[face, sample]:
            self.covered[face, sample] = True
            self.count[face] += 1
