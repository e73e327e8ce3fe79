"""The mutable state of one hierarchical pattern mapping run.

:class:`_State` holds the texture positions of every textured face's corners
(full-resolution pixels), which face is done, by which placement and on which
level, and per vertex the sums behind :meth:`_State.agreed` (the mean textured
position where the corners agree).  :func:`geotex.image.hpm.hpm_texture` owns
it; the fits (:mod:`geotex.image.hpm_fit`) and the gap filling
(:mod:`geotex.image.hpm_gaps`) read and update it.
"""

from __future__ import annotations

import numpy as np


class _State:
    """Mutable state of one mapping run (corner texture positions in full-res pixels)."""

    def __init__(self, V, F, m):
        self.corner = np.zeros((m, 3, 2))
        self.done = np.zeros(m, bool)
        self.patch = np.full(m, -1, np.int64)
        self.face_level = np.full(m, -1, np.int64)
        self.n_patch = 0
        n = V.shape[0]
        self.vacc = np.zeros((n, 2))        # sum of textured corner positions per vertex
        self.vcnt = np.zeros(n)             # number of textured corners per vertex
        self.vsq = np.zeros(n)              # sum of squared norms (to detect disagreement)
        self._agreed = None                 # cache of agreed()
        self._dirty = None                  # vertices marked since, whose rows it updates
        self.vpatch = np.full(n, -1, np.int64)  # last placement that textured each vertex

    def _agreed_rows(self, idx):
        c = np.maximum(self.vcnt[idx], 1.0)
        mean = self.vacc[idx] / c[:, None]
        spread = self.vsq[idx] / c - np.sum(mean * mean, axis=1)
        ok = (self.vcnt[idx] > 0) & (spread < 1e-6 * (1.0 + self.vsq[idx] / c))
        return np.where(ok[:, None], mean, np.nan)

    def agreed(self) -> np.ndarray:
        """Per-vertex mean textured position, nan where none or where corners disagree.

        The returned array is read-only and valid until the next :meth:`mark`
        (which updates it in place: do not keep it across one).
        """
        if self._agreed is None:
            self._agreed = self._agreed_rows(slice(None))
        elif self._dirty is not None:
            self._agreed.setflags(write=True)
            self._agreed[self._dirty] = self._agreed_rows(self._dirty)
        self._agreed.setflags(write=False)
        self._dirty = None
        return self._agreed

    def mark(self, F, faces, corner, patch, level):
        """Record the corner positions of newly textured faces."""
        self.corner[faces] = corner
        self.done[faces] = True
        self.patch[faces] = patch
        self.face_level[faces] = level
        cv = F[faces].ravel()
        self._dirty = cv if self._dirty is None else np.concatenate([self._dirty, cv])
        self.vpatch[cv] = patch
        n = self.vcnt.size
        self.vcnt += np.bincount(cv, minlength=n)
        cu = corner.reshape(-1, 2)
        self.vacc[:, 0] += np.bincount(cv, weights=cu[:, 0], minlength=n)
        self.vacc[:, 1] += np.bincount(cv, weights=cu[:, 1], minlength=n)
        self.vsq += np.bincount(cv, weights=np.sum(cu * cu, axis=1), minlength=n)
