"""Compiled loops of hierarchical pattern mapping, with their numpy paths.

* :func:`_sample`: bilinear samples of the matching image (mask colours, band
  errors, the lattice moves, the relaxation), compiled per sample by
  :func:`_sample_compiled` (the numpy path's operations in its order: the same
  values bit for bit);
* :func:`_relax_error_compiled` and :func:`_relax_search_compiled`: the error
  and the greedy search of the edge relaxation
  (:func:`geotex.image.hpm_fit._relax`), through the same ``_bilinear`` helper;
* :func:`_window_minima`: the lowest FFT energy in a window around each
  continuation or lattice move;
* :func:`_block_mean`: the image reduced by block means for the coarse levels.

They are together because a compiled function may only call the
:func:`geotex.jit.helper` functions of its own module.
"""

from __future__ import annotations

import numpy as np

from geotex.jit import compiled, helper


def _block_mean(img: np.ndarray, f: int) -> np.ndarray:
    if f == 1:
        return img.copy()
    h, w = (img.shape[0] // f) * f, (img.shape[1] // f) * f
    x = img[:h, :w].reshape(h // f, f, w // f, f, img.shape[2])
    return x.mean(axis=(1, 3))


def _sample(img: np.ndarray, xy: np.ndarray, fast: bool = False) -> np.ndarray:
    """Bilinear samples of ``img`` (h, w, c) at pixel positions ``xy`` (x, y), clamped.

    With ``fast`` the compiled loop :func:`_sample_compiled` gives the same
    values bit for bit without the numpy temporaries (positions with a NaN
    keep the numpy path).
    """
    h, w = img.shape[:2]
    if fast and h > 1 and w > 1 and not np.isnan(xy).any():
        return _sample_compiled(img, np.ascontiguousarray(xy, dtype=np.float64))
    x = np.clip(xy[:, 0] - 0.5, 0.0, w - 1.0)
    y = np.clip(xy[:, 1] - 0.5, 0.0, h - 1.0)
    x0 = np.minimum(np.floor(x).astype(np.int64), w - 2) if w > 1 else np.zeros(x.size, np.int64)
    y0 = np.minimum(np.floor(y).astype(np.int64), h - 2) if h > 1 else np.zeros(y.size, np.int64)
    fx = (x - x0)[:, None]
    fy = (y - y0)[:, None]
    # row gathers from the flattened image (np.take: cheaper than 2-d fancy indexing,
    # the same values)
    flat = img.reshape(h * w, -1)
    i00 = y0 * w + x0
    dx = np.minimum(x0 + 1, w - 1) - x0
    dy = (np.minimum(y0 + 1, h - 1) - y0) * w
    top = np.take(flat, i00, axis=0) * (1 - fx) + np.take(flat, i00 + dx, axis=0) * fx
    bot = np.take(flat, i00 + dy, axis=0) * (1 - fx) + np.take(flat, i00 + dy + dx, axis=0) * fx
    return top * (1 - fy) + bot * fy


@helper
def _bilinear(img, px, py, out, i):
    """Row ``i`` of ``out``: the bilinear sample of ``img`` at ``(px, py)``, as
    :func:`_sample` computes it (image of at least 2 x 2 pixels, no NaN)."""
    h, w, nc = img.shape
    x = min(max(px - 0.5, 0.0), w - 1.0)
    y = min(max(py - 0.5, 0.0), h - 1.0)
    x0 = min(int(np.floor(x)), w - 2)
    y0 = min(int(np.floor(y)), h - 2)
    fx = x - x0
    fy = y - y0
    x1 = min(x0 + 1, w - 1)
    y1 = min(y0 + 1, h - 1)
    for k in range(nc):
        top = img[y0, x0, k] * (1 - fx) + img[y0, x1, k] * fx
        bot = img[y1, x0, k] * (1 - fx) + img[y1, x1, k] * fx
        out[i, k] = top * (1 - fy) + bot * fy


@compiled
def _sample_compiled(img, xy):
    """:func:`_sample` for an image of at least 2 x 2 pixels and positions without NaN:
    the same operations in the same order per sample, so the same values."""
    n = xy.shape[0]
    out = np.empty((n, img.shape[2]))
    for i in range(n):
        _bilinear(img, xy[i, 0], xy[i, 1], out, i)
    return out


@compiled
def _relax_error_compiled(full, cand, owner, b, target, ts, nv):
    """The error of :func:`_relax` per movable vertex (its ``err``) without temporaries:
    per sample along each shared edge the numpy path's operations in its order (the
    colour sum in channel order, as ``np.sum`` over fewer than 8 channels), accumulated
    per vertex in row order as ``np.bincount``: the same values."""
    out = np.zeros(nv)
    _relax_error_into(full, cand, owner, b, target, ts, out)
    return out


@compiled
def _relax_search_compiled(full, cur, off, owner, b, target, ts, e0):
    """:func:`_relax`'s greedy search: for each offset block ``off[i]`` (k, 2) in turn,
    the candidates ``cur + off[i]``, their errors (:func:`_relax_error_compiled`'s
    values) and the moves of the vertices whose error falls, as the numpy loop does.
    Returns the new positions (k, 2)."""
    cur = cur.copy()
    e0 = e0.copy()
    n = cur.shape[0]
    e1 = np.zeros(n)
    cand = np.empty_like(cur)
    for i in range(off.shape[0]):
        for v in range(n):
            cand[v, 0] = cur[v, 0] + off[i, v, 0]
            cand[v, 1] = cur[v, 1] + off[i, v, 1]
            e1[v] = 0.0
        _relax_error_into(full, cand, owner, b, target, ts, e1)
        for v in range(n):
            if e1[v] < e0[v]:
                cur[v, 0] = cand[v, 0]
                cur[v, 1] = cand[v, 1]
                e0[v] = e1[v]
    return cur


@helper
def _relax_error_into(full, cand, owner, b, target, ts, out):
    """Body of :func:`_relax_error_compiled`: adds the errors to ``out`` (zeros)."""
    nt = ts.size
    s = np.empty((1, full.shape[2]))
    for e in range(owner.size):
        o = owner[e]
        for j in range(nt):
            u = 1 - ts[j]
            _bilinear(full, cand[o, 0] * u + b[e, 0] * ts[j], cand[o, 1] * u + b[e, 1] * ts[j],
                      s, 0)
            r = e * nt + j
            d = s[0, 0] - target[r, 0]
            acc = d * d
            for k in range(1, s.shape[1]):
                d = s[0, k] - target[r, k]
                acc += d * d
            out[o] += acc * u


@compiled
def _window_minima(E, ix, iy, win):
    """Per point ``(ix[i], iy[i])``: the lowest value of ``E`` (h, w) in the window of
    ``win`` pixels around it (clipped to ``E``) and its row and column, the first in
    row-major order among equal values (as ``np.argmin`` of the window); ``inf`` (and
    row, column 0) where the window is empty or holds no finite value."""
    n = ix.size
    h, w = E.shape
    val = np.full(n, np.inf)
    by = np.zeros(n, np.int64)
    bx = np.zeros(n, np.int64)
    for i in range(n):
        for y in range(max(iy[i] - win, 0), min(max(iy[i] + win + 1, 0), h)):
            for x in range(max(ix[i] - win, 0), min(max(ix[i] + win + 1, 0), w)):
                if E[y, x] < val[i]:
                    val[i] = E[y, x]
                    by[i] = y
                    bx[i] = x
    return val, by, bx
