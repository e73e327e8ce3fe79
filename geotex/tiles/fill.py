"""Gap filling: whole exemplar elements dropped into the free parts of a tile.

Footprints (projections on the tile plane) are rasterized on a pixel grid of
:data:`PIXEL` tile units. An exemplar element, moved by a whole number of
pixels, may join the tile when its footprint grown by
:data:`~geotex.tiles.strips.GAP` covers no pixel of any footprint already in
the tile, and it stays :data:`CLEAR` inside the tile sides. Disjoint
footprints mean disjoint solids, so the added elements never touch what is
there (up to the pixel size, well under the gap), and they are copied
unchanged, so they stay closed.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from geotex.mesh.topology import compacted, concatenated

__all__ = ["PIXEL", "CLEAR", "footprint_pixels", "ExemplarPixels", "fill_gaps"]

GAP = 0.02                   # clearance between elements (gap filling, interior)
PIXEL = 1.0 / 160.0
CLEAR = 0.5 * GAP            # clearance of added elements from the tile sides
WINDOWS = 48                 # random exemplar windows tried


def footprint_pixels(V: np.ndarray, F: np.ndarray, *, pixel: float = PIXEL,
                     shape=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixels whose centre lies under a triangle's projection on the plane.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    pixel : float
        Pixel size; pixel ``(i, j)`` has its centre at ``((i + 0.5) pixel,
        (j + 0.5) pixel)``.
    shape : tuple of 2 int, optional
        Keep only pixels inside ``[0, shape[0]) x [0, shape[1])``.

    Returns
    -------
    i, j : numpy.ndarray, (k,) int64
        Covered pixels (with repeats, one row per covering triangle).
    face : numpy.ndarray, (k,) int64
        The covering triangle.
    """
    T = V[F][:, :, :2] / pixel - 0.5          # in pixel-centre units
    e1 = T[:, 1] - T[:, 0]
    e2 = T[:, 2] - T[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    faces = np.flatnonzero(np.abs(det) > 1e-12)
    lo = np.ceil(T[faces].min(axis=1)).astype(np.int64)
    hi = np.floor(T[faces].max(axis=1)).astype(np.int64)
    ni, nj = hi[:, 0] - lo[:, 0] + 1, hi[:, 1] - lo[:, 1] + 1
    cnt = np.maximum(ni, 0) * np.maximum(nj, 0)
    has = cnt > 0
    faces, lo, ni, nj, cnt = faces[has], lo[has], ni[has], nj[has], cnt[has]
    tri = np.repeat(np.arange(faces.size), cnt)
    local = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    ii = lo[tri, 0] + local // nj[tri]
    jj = lo[tri, 1] + local % nj[tri]
    f = faces[tri]
    px, py = ii - T[f, 0, 0], jj - T[f, 0, 1]
    d = det[f]
    a = (px * e2[f, 1] - py * e2[f, 0]) / d
    b = (e1[f, 0] * py - e1[f, 1] * px) / d
    inside = (a >= 0) & (b >= 0) & (a + b <= 1)
    if shape is not None:
        inside &= (ii >= 0) & (jj >= 0) & (ii < shape[0]) & (jj < shape[1])
    return ii[inside], jj[inside], f[inside]


class ExemplarPixels:
    """Footprint pixels of every exemplar element, grown by the gap (built once).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
        Element of every face.
    lo, hi : numpy.ndarray, (E, 3) float64
        Element bounding boxes.
    """

    def __init__(self, V, F, labels, lo, hi):
        self.V, self.F, self.labels, self.lo, self.hi = V, F, labels, lo, hi
        ii, jj, f = footprint_pixels(V, F)
        e = labels[f]
        key = np.unique(np.stack([e, ii, jj], 1), axis=0)
        r = int(np.ceil(GAP / PIXEL))
        disk = np.add.outer(np.arange(-r, r + 1) ** 2, np.arange(-r, r + 1) ** 2) <= r * r
        bounds = np.searchsorted(key[:, 0], np.arange(len(lo) + 1))
        self.grown = []
        for k in range(len(lo)):
            P = key[bounds[k]:bounds[k + 1], 1:]
            if len(P) == 0:
                self.grown.append(np.zeros((0, 2), dtype=np.int64))
                continue
            base = P.min(axis=0) - r
            mask = np.zeros(tuple(P.max(axis=0) - P.min(axis=0) + 2 * r + 1), dtype=bool)
            mask[tuple((P - base).T)] = True
            mask = ndimage.binary_dilation(mask, structure=disk)
            self.grown.append(np.argwhere(mask) + base)
        order = np.argsort(labels, kind="stable")
        fb = np.searchsorted(labels[order], np.arange(len(lo) + 1))
        self._faces = [order[fb[k]:fb[k + 1]] for k in range(len(lo))]

    def element(self, k: int, shift) -> tuple[np.ndarray, np.ndarray]:
        """Element ``k`` moved by ``-shift`` (a 2-vector)."""
        Vk, Fk = compacted(self.V, self.F[self._faces[k]])
        return Vk - np.r_[shift, 0.0], Fk


def fill_gaps(V: np.ndarray, F: np.ndarray, ex: ExemplarPixels, size,
              rng: np.random.Generator, *, windows: int = WINDOWS, lattice=None
              ) -> tuple[tuple[np.ndarray, np.ndarray], int]:
    """Add whole exemplar elements to the free parts of a tile ``[0, 1]^2``.

    Tries ``windows`` random unit windows of the exemplar (offsets whole
    pixels), in turn; an element of a window that lies ``CLEAR`` inside the
    tile joins when its grown footprint is free (see the module docstring).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        What the tile holds already.
    ex : ExemplarPixels
    size : tuple of 2 float
        Exemplar extent.
    rng : numpy.random.Generator
    windows : int
    lattice : tuple (pitch, phase_x, phase_y), optional
        Take windows at the exemplar's lattice points only (rounded to whole
        pixels), so the added elements keep the tile's lattice.

    Returns
    -------
    added : tuple of (V (k, 3) float64, F (l, 3) int64)
        The new elements, in tile coordinates.
    count : int
        How many.
    """
    n = int(round(1.0 / PIXEL))
    occ = np.zeros((n, n), dtype=bool)
    if len(F):
        ii, jj, _ = footprint_pixels(V, F, shape=(n, n))
        occ[ii, jj] = True
    mi = max(int(np.floor((size[0] - 1.0) / PIXEL)), 0)
    mj = max(int(np.floor((size[1] - 1.0) / PIXEL)), 0)
    if lattice is None:
        oi = rng.integers(0, mi + 1, windows)
        oj = rng.integers(0, mj + 1, windows)
    else:
        p, ph = lattice[0], np.asarray(lattice[1:])
        top = np.maximum(np.floor((np.array([mi, mj]) * PIXEL - ph) / p), 0).astype(np.int64)
        ki = rng.integers(0, top[0] + 1, windows)
        kj = rng.integers(0, top[1] + 1, windows)
        oi = np.minimum(np.round((ph[0] + ki * p) / PIXEL).astype(np.int64), mi)
        oj = np.minimum(np.round((ph[1] + kj * p) / PIXEL).astype(np.int64), mj)
    parts, count = [], 0
    lo, hi = ex.lo[:, :2], ex.hi[:, :2]
    for a, b in zip(oi.tolist(), oj.tolist()):
        o = np.array([a, b], dtype=np.float64) * PIXEL
        inside = np.flatnonzero(((lo - o) >= CLEAR).all(axis=1)
                                & ((hi - o) <= 1.0 - CLEAR).all(axis=1))
        for k in inside.tolist():
            P = ex.grown[k] - [a, b]
            P = P[((P >= 0) & (P < n)).all(axis=1)]
            if occ[P[:, 0], P[:, 1]].any():
                continue
            Vk, Fk = ex.element(k, o)
            ii, jj, _ = footprint_pixels(Vk, Fk, shape=(n, n))
            occ[ii, jj] = True
            parts.append((Vk, Fk))
            count += 1
    return concatenated(parts), count
