"""Gap filling: whole exemplar elements dropped into the free parts of a tile.

Footprints (projections on the tile plane) are rasterized on a pixel grid of
:data:`PIXEL` tile units. An exemplar element, moved by a whole number of
pixels, may join the tile when its footprint grown by
:data:`~geotex.tiles.strips.GAP` covers no pixel of any footprint already in
the tile, and it stays :data:`CLEAR` inside the tile sides. Disjoint
footprints mean disjoint solids, so the added elements never touch what is
there (up to the pixel size, well under the gap), and they are copied
unchanged, so they stay closed.

Corner squares (:func:`fill_corners`) use height images instead of bare
footprints: at every pixel an element's lowest and highest face height, so
that elements may also overlap in projection when one lies above the other
(scales), the collision rule of the strips at the tile corners
(:func:`geotex.tiles.strips.corner_conflicts`).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from geotex.jit import compiled
from geotex.mesh.topology import compacted, concatenated, face_components

__all__ = ["PIXEL", "CLEAR", "footprint_pixels", "ExemplarPixels", "fill_gaps", "fill_corners",
           "grown_heights", "element_heights", "heights_touch", "pixel_heights"]

GAP = 0.02                   # clearance between elements (gap filling, interior)
PIXEL = 1.0 / 160.0
CLEAR = 0.5 * GAP            # clearance of added elements from the tile sides
WINDOWS = 48                 # random exemplar windows tried
QUARTER = 0.25               # side of the corner squares that fill_corners fills
CORNER_TRIES = 24            # elements tried per corner square
CORNER_PLACES = 4096         # best places tried per element
FREE_SHARE = 0.1             # least share of a corner element on free ground


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
        self.heights = element_heights(V, F, labels, len(lo))

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


def grown_heights(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Height images grown by one pixel (8-neighbourhood) over their last two axes.

    Parameters
    ----------
    low, high : numpy.ndarray, (..., n, m) float64
        Lowest and highest height over every pixel (``+inf`` / ``-inf`` where
        nothing is).

    Returns
    -------
    low, high : numpy.ndarray, (..., n, m) float64
        Minimum of the lows and maximum of the highs over each pixel and its
        eight neighbours (new arrays).
    """
    lo, hi = low.copy(), high.copy()
    for axis in (-2, -1):
        a, b = lo.copy(), hi.copy()
        sl = [slice(None)] * lo.ndim
        sr = [slice(None)] * lo.ndim
        sl[axis], sr[axis] = slice(1, None), slice(None, -1)
        lo[tuple(sl)] = np.minimum(lo[tuple(sl)], a[tuple(sr)])
        lo[tuple(sr)] = np.minimum(lo[tuple(sr)], a[tuple(sl)])
        hi[tuple(sl)] = np.maximum(hi[tuple(sl)], b[tuple(sr)])
        hi[tuple(sr)] = np.maximum(hi[tuple(sr)], b[tuple(sl)])
    return lo, hi


def element_heights(V: np.ndarray, F: np.ndarray, labels: np.ndarray, k: int
                    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Height images of every element over the pixel grid of :data:`PIXEL`.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
        Element (``0..k-1``) of every face.
    k : int

    Returns
    -------
    list of (origin (2,) int64, low (a, b) float64, high (a, b) float64)
        Per element: the pixel of its image's first entry, and the lowest and
        highest height of its faces at the centre of every pixel of its
        bounding box of pixels (``+inf`` / ``-inf`` where it is absent). An element too
        small to cover a pixel centre gets a 0 x 0 image.
    """
    out = []
    ii, jj, f = footprint_pixels(V, F)
    z = pixel_heights(V, F, ii, jj, f)
    e = labels[f]
    order = np.argsort(e, kind="stable")
    bounds = np.searchsorted(e[order], np.arange(k + 1))
    for n in range(k):
        sel = order[bounds[n]:bounds[n + 1]]
        if sel.size == 0:
            out.append((np.zeros(2, dtype=np.int64), np.zeros((0, 0)), np.zeros((0, 0))))
            continue
        i, j = ii[sel], jj[sel]
        o = np.array([i.min(), j.min()], dtype=np.int64)
        shape = (int(i.max() - o[0] + 1), int(j.max() - o[1] + 1))
        low = np.full(shape, np.inf)
        high = np.full(shape, -np.inf)
        np.minimum.at(low, (i - o[0], j - o[1]), z[sel])
        np.maximum.at(high, (i - o[0], j - o[1]), z[sel])
        out.append((o, low, high))
    return out


def pixel_heights(V: np.ndarray, F: np.ndarray, ii: np.ndarray, jj: np.ndarray, f: np.ndarray,
                  *, pixel: float = PIXEL) -> np.ndarray:
    """Height of the triangles at the centres of the pixels they cover.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    ii, jj, f : numpy.ndarray, (k,) int64
        Pixels and their covering triangles (:func:`footprint_pixels`).
    pixel : float

    Returns
    -------
    numpy.ndarray, (k,) float64
        The height of triangle ``f`` (its plane) over the centre of pixel ``(ii, jj)``.
    """
    T = V[F[f]]
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    px = (ii + 0.5) * pixel - T[:, 0, 0]
    py = (jj + 0.5) * pixel - T[:, 0, 1]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    a = (px * e2[:, 1] - py * e2[:, 0]) / det
    b = (e1[:, 0] * py - e1[:, 1] * px) / det
    return T[:, 0, 2] + a * e1[:, 2] + b * e2[:, 2]


def heights_touch(a, b, clear: float) -> bool:
    """Whether two placed height images come within ``clear`` of each other.

    ``a`` and ``b`` are ``(origin, low, high)`` (:func:`element_heights`);
    ``b`` is taken grown by a pixel already (:func:`grown_heights`). They
    touch when some pixel holds both and their height ranges overlap or are
    less than ``clear`` apart (the rule of
    :func:`geotex.tiles.strips.corner_conflicts`).
    """
    (oa, la, ha), (ob, lb, hb) = a, b
    i0, j0 = max(oa[0], ob[0]), max(oa[1], ob[1])
    i1 = min(oa[0] + la.shape[0], ob[0] + lb.shape[0])
    j1 = min(oa[1] + la.shape[1], ob[1] + lb.shape[1])
    if i1 <= i0 or j1 <= j0:
        return False
    sa = (slice(i0 - oa[0], i1 - oa[0]), slice(j0 - oa[1], j1 - oa[1]))
    sb = (slice(i0 - ob[0], i1 - ob[0]), slice(j0 - ob[1], j1 - ob[1]))
    return bool((np.maximum(la[sa], lb[sb]) <= np.minimum(ha[sa], hb[sb]) + clear).any())


def fill_corners(V: np.ndarray, F: np.ndarray, ex: ExemplarPixels, rng: np.random.Generator,
                 *, quarter: float = QUARTER, tries: int = CORNER_TRIES
                 ) -> tuple[tuple[np.ndarray, np.ndarray], int]:
    """Add exemplar elements in the tile's corner squares until they are as full as the rest.

    The corner squares (within ``quarter`` of a tile corner along both axes)
    are where the frame's strips end, and they are hard to reach for the
    interior: quilting cells there are held by frame elements, and copies
    whose elements would cross a side are dropped. Here, for each corner in
    turn, while the square's covered fraction (faces above ``w = 0``) is
    below that of the tile outside the corner squares, a random exemplar
    element is tried at every whole-pixel place where it reaches into the
    square and stays :data:`CLEAR` inside the tile sides (moved by whole
    pixels, its height image moves exactly), best first by the free pixels of
    the square it would cover, up to :data:`CORNER_PLACES` places. It joins
    at the first place where at least :data:`FREE_SHARE` of its pixels are on
    free ground and, at every pixel, its height range keeps :data:`CLEAR`
    from that of every element already there grown by :data:`GAP`
    (:func:`heights_touch`; heights at the pixel centres, so elements may
    overlap in projection one above the other, like scales, but never come
    closer than the gap side by side, as in :func:`fill_gaps`). Elements are
    copied unchanged, so they stay closed; nothing crosses a side, so the
    tile stays seamless and never collides with its neighbours.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        The tile ``[0, 1]^2`` as built so far.
    ex : ExemplarPixels
    rng : numpy.random.Generator
    quarter : float
        Side of a corner square.
    tries : int
        Elements tried per corner square.

    Returns
    -------
    added : tuple of (V (k, 3) float64, F (l, 3) int64)
        The new elements, in tile coordinates.
    count : int
        How many.
    """
    # lazy: scipy.signal takes ~0.7 s to import, and only tile building needs it
    from scipy.signal import correlate

    n = int(round(1.0 / PIXEL))
    q = int(round(quarter / PIXEL))
    c = int(np.ceil(CLEAR / PIXEL)) + 1          # pixels kept free along the sides
    cover = np.zeros((n, n), dtype=bool)
    placed = []
    if len(F):
        k, labels = face_components(F, len(V))
        up = V[F][:, :, 2].mean(axis=1) > 0.0
        ii, jj, _ = footprint_pixels(V, F[up], shape=(n, n))
        cover[ii, jj] = True
        placed = [_grown_by_gap(h) for h in element_heights(V, F, labels, k) if h[1].size]
    corner = np.zeros((n, n), dtype=bool)
    corner[np.ix_(np.r_[0:q, n - q:n], np.r_[0:q, n - q:n])] = True
    target = float(cover[~corner].mean())
    images = _packed(placed)
    shapes = np.array([h[1].shape for h in ex.heights], dtype=np.int64).reshape(-1, 2)
    usable = np.flatnonzero((shapes > 0).all(axis=1) & (shapes <= n - 2 * c - 2).all(axis=1))
    parts, count = [], 0
    for cu, cv in ((0, 0), (1, 0), (1, 1), (0, 1)) if usable.size else ():
        quad = np.zeros((n, n), dtype=bool)
        quad[(slice(n - q, n) if cu else slice(0, q), slice(n - q, n) if cv else slice(0, q))] = 1
        for _ in range(tries):
            if cover[quad].mean() >= target:
                break
            k = int(usable[rng.integers(usable.size)])
            o, low, high = ex.heights[k]
            mine = np.isfinite(low)
            # image origins (tile pixels) keeping the image c pixels inside the
            # sides and reaching into the corner square
            a, b = low.shape
            lo_i, hi_i = (max(c, n - q - a + 1), n - c - a) if cu else (c, min(q - 1, n - c - a))
            lo_j, hi_j = (max(c, n - q - b + 1), n - c - b) if cv else (c, min(q - 1, n - c - b))
            if hi_i < lo_i or hi_j < lo_j:
                continue
            gain = correlate((quad & ~cover).astype(np.float64),
                             (high > 0).astype(np.float64), mode="valid")
            free = correlate((~cover).astype(np.float64), mine.astype(np.float64),
                             mode="valid")
            gain = gain[lo_i:hi_i + 1, lo_j:hi_j + 1]
            ok = (free[lo_i:hi_i + 1, lo_j:hi_j + 1] >= FREE_SHARE * mine.sum() - 0.5) \
                & (gain > 0.5)
            order = np.argsort(-np.where(ok, gain, 0.0), axis=None, kind="stable")
            flat = order[:CORNER_PLACES][ok.ravel()[order[:CORNER_PLACES]]]
            places = np.c_[lo_i + flat // gain.shape[1], lo_j + flat % gain.shape[1]]
            start = 0
            while (hit := _first_free(places, low, high, images, start)) >= 0:
                start = hit + 1
                shift = (o - places[hit]) * PIXEL
                Vk, Fk = ex.element(k, shift)   # check again on the moved mesh itself
                real = element_heights(Vk, Fk, np.zeros(len(Fk), dtype=np.int64), 1)[0]
                if (not real[1].size or (Vk[:, :2] < CLEAR).any()
                        or (Vk[:, :2] > 1.0 - CLEAR).any()
                        or _first_free(real[0][None], real[1], real[2], images, 0) < 0):
                    continue
                up = Vk[Fk][:, :, 2].mean(axis=1) > 0.0
                ii, jj, _ = footprint_pixels(Vk, Fk[up], shape=(n, n))
                cover[ii, jj] = True
                placed.append(_grown_by_gap(real))
                images = _packed(placed)
                parts.append((Vk, Fk))
                count += 1
                break
    return concatenated(parts), count


def _grown_by_gap(h):
    """A placed height image grown by :data:`GAP` (a square of whole pixels) on every side."""
    o, low, high = h
    r = int(np.ceil(GAP / PIXEL))
    low = np.pad(low, r, constant_values=np.inf)
    high = np.pad(high, r, constant_values=-np.inf)
    for _ in range(r):
        low, high = grown_heights(low, high)
    return (o - r, low, high)


def _packed(placed):
    """Placed height images in flat arrays: (origins (p, 2), shapes (p, 2), offsets (p,),
    low, high (s,)), for :func:`_first_free`."""
    origins = np.array([h[0] for h in placed], dtype=np.int64).reshape(-1, 2)
    shapes = np.array([h[1].shape for h in placed], dtype=np.int64).reshape(-1, 2)
    offsets = np.concatenate([[0], np.cumsum(shapes.prod(axis=1))])[:-1].astype(np.int64)
    low = np.concatenate([h[1].ravel() for h in placed] + [np.zeros(0)])
    high = np.concatenate([h[2].ravel() for h in placed] + [np.zeros(0)])
    return origins, shapes, offsets, low, high


def _first_free(places, low, high, images, start) -> int:
    """The first of ``places`` (from ``start``) where the height image ``(low, high)``
    touches none of the packed ``images`` (:func:`heights_touch` with :data:`CLEAR`), or -1.

    Parameters
    ----------
    places : numpy.ndarray, (c, 2) int64
        Candidate origins (tile pixels) of the image, in the order tried.
    low, high : numpy.ndarray, (a, b) float64
    images : tuple
        :func:`_packed` placed images (each grown by the gap already).
    start : int
    """
    return int(_first_free_compiled(np.ascontiguousarray(places, dtype=np.int64),
                                    np.ascontiguousarray(low), np.ascontiguousarray(high),
                                    *images, CLEAR, int(start)))


@compiled
def _first_free_compiled(places, low, high, origins, shapes, offsets, plow, phigh, clear,
                         start):  # pragma: no cover - compiled
    a, b = low.shape
    for c in range(start, places.shape[0]):
        oi, oj = places[c, 0], places[c, 1]
        hit = False
        for p in range(origins.shape[0]):
            pi, pj, pa, pb = origins[p, 0], origins[p, 1], shapes[p, 0], shapes[p, 1]
            i0, j0 = max(oi, pi), max(oj, pj)
            i1, j1 = min(oi + a, pi + pa), min(oj + b, pj + pb)
            for i in range(i0, i1):
                row = offsets[p] + (i - pi) * pb - pj
                for j in range(j0, j1):
                    la, ha = low[i - oi, j - oj], high[i - oi, j - oj]
                    lb, hb = plow[row + j], phigh[row + j]
                    if max(la, lb) <= min(ha, hb) + clear:
                        hit = True
                        break
                if hit:
                    break
            if hit:
                break
        if not hit:
            return c
    return -1
