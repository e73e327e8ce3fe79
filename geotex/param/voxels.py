"""Voxel solids of closed meshes: occupancy, manifold boundaries, components.

A voxel solid is a boolean array ``S[i, j, k]`` over a regular grid of cubic
cells of side ``cell`` whose cell ``(i, j, k)`` spans
``origin + [i, i+1] x [j, j+1] x [k, k+1] * cell``. A cell is *inside* a closed
mesh when the generalized winding number at its centre exceeds 1/2 (libigl's
fast winding number), which is robust to small defects and gives the same
answer at any scale.

The boundary of a union of closed cubes is a 2-manifold exactly when, around
every grid corner, the solid cells of the corner's 2 x 2 x 2 block are
face-connected within the block and so are the empty ones
(:data:`MANIFOLD_BLOCKS`); edge contacts (two cubes sharing only an edge) and
corner contacts both break that rule. :func:`manifold_solid` removes every
such configuration by flipping cells.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.errors import InputError, SolverError

__all__ = ["MANIFOLD_BLOCKS", "voxel_grid", "occupancy", "non_manifold_corners",
           "manifold_solid", "largest_component"]

_OFFSETS = np.array([[b & 1, (b >> 1) & 1, (b >> 2) & 1] for b in range(8)], dtype=np.int64)


def _block_table() -> np.ndarray:
    """``ok[p]`` for every 8-bit occupancy pattern ``p`` of a 2 x 2 x 2 block."""
    ok = np.ones(256, dtype=bool)
    for p in range(256):
        for value in (0, 1):
            cells = [b for b in range(8) if (p >> b) & 1 == value]
            if not cells:
                continue
            seen, stack = {cells[0]}, [cells[0]]
            while stack:
                c = stack.pop()
                for n in (c ^ 1, c ^ 2, c ^ 4):      # the three face neighbours in the block
                    if (p >> n) & 1 == value and n not in seen:
                        seen.add(n)
                        stack.append(n)
            ok[p] &= len(seen) == len(cells)
    return ok


#: ``MANIFOLD_BLOCKS[p]``: the boundary surface is a disc around a grid corner whose
#: 2 x 2 x 2 block has occupancy bits ``p`` (bit ``x + 2y + 4z``).
MANIFOLD_BLOCKS = _block_table()


def voxel_grid(V: np.ndarray, *, cell: float, shift=(0.0, 0.0, 0.0)
               ) -> tuple[np.ndarray, tuple[int, int, int]]:
    """Grid covering the points ``V`` with at least one empty layer of cells.

    Unshifted, a grid plane passes through the lowest point on every axis, so
    a box whose sides are multiples of ``cell`` is resolved exactly.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    cell : float
        Cell side.
    shift : sequence of 3 float, optional
        Offset of the grid in cells (e.g. 0.5 moves it by half a cell), so
        several grids can be tried on the same shape.

    Returns
    -------
    origin : numpy.ndarray, (3,) float64
        Lower corner of cell ``(0, 0, 0)``.
    shape : tuple of 3 int
    """
    lo, hi = V.min(axis=0), V.max(axis=0)
    origin = lo - (2.0 - np.asarray(shift, dtype=np.float64)) * cell
    n = np.ceil((hi - origin) / cell - 1e-9).astype(np.int64) + 2
    return origin, tuple(int(k) for k in n)


def occupancy(V: np.ndarray, F: np.ndarray, *, cell: float, origin: np.ndarray,
              shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Cells of the grid whose centre is inside the closed mesh ``(V, F)``.

    Returns
    -------
    inside : numpy.ndarray, shape bool
    winding : numpy.ndarray, shape float64
        The winding number at every cell centre.
    """
    axes = [np.arange(k, dtype=np.float64) + 0.5 for k in shape]
    gx, gy, gz = np.meshgrid(*axes, indexing="ij")
    Q = origin + cell * np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1)
    w = np.asarray(igl.fast_winding_number(V, F, Q)).reshape(shape)
    return w > 0.5, w


def _corner_codes(S: np.ndarray) -> np.ndarray:
    """Occupancy pattern of the 2 x 2 x 2 block around every grid corner."""
    P = np.pad(S, 1)
    sh = tuple(k - 1 for k in P.shape)
    code = np.zeros(sh, dtype=np.int64)
    for b, (x, y, z) in enumerate(_OFFSETS):
        code |= P[x:x + sh[0], y:y + sh[1], z:z + sh[2]].astype(np.int64) << b
    return code


def non_manifold_corners(S: np.ndarray) -> np.ndarray:
    """Grid corners around which the boundary of ``S`` is not a disc.

    Returns
    -------
    numpy.ndarray, (k, 3) int64
        Corner ``(i, j, k)`` is the common corner of cells ``(i-1..i, j-1..j,
        k-1..k)``.
    """
    return np.argwhere(~MANIFOLD_BLOCKS[_corner_codes(S)]).astype(np.int64)


def manifold_solid(S: np.ndarray, winding: np.ndarray, *, strategy: str = "flip",
                   max_rounds: int = 200) -> tuple[np.ndarray, int]:
    """A copy of ``S`` whose boundary is a 2-manifold.

    Parameters
    ----------
    S : numpy.ndarray, bool (nx, ny, nz)
    winding : numpy.ndarray, float64 (nx, ny, nz)
        Winding numbers at the cell centres (decides which cell to flip).
    strategy : {"flip", "fill"}
        ``"flip"``: in every bad block flip the single cell whose winding
        number is closest to 1/2 (the least certain one; a cell flipped once
        is not preferred again); ``"fill"``: fill every empty cell of every
        bad block (only grows the solid).
    max_rounds : int

    Returns
    -------
    solid : numpy.ndarray, bool
    changed : int
        Cells that differ from ``S``.

    Raises
    ------
    SolverError
        If no manifold configuration is reached within ``max_rounds``.
    InputError
        If ``strategy`` is unknown.
    """
    P = np.pad(S, 1)
    score = np.pad(-np.abs(np.asarray(winding, dtype=np.float64) - 0.5), 1,
                   constant_values=-np.inf)
    for _ in range(max_rounds):
        inner = P[1:-1, 1:-1, 1:-1]
        bad = non_manifold_corners(inner)
        if bad.size == 0:
            return inner.copy(), int(np.count_nonzero(inner != S))
        cells = bad[:, None, :] + _OFFSETS[None]          # padded indices of the block cells
        if strategy == "fill":
            c = cells.reshape(-1, 3)
            P[c[:, 0], c[:, 1], c[:, 2]] = True
        elif strategy == "flip":
            sc = score[cells[..., 0], cells[..., 1], cells[..., 2]]
            pick = np.unique(cells[np.arange(len(bad)), np.argmax(sc, axis=1)], axis=0)
            P[pick[:, 0], pick[:, 1], pick[:, 2]] ^= True
            score[pick[:, 0], pick[:, 1], pick[:, 2]] -= 1.0
        else:
            raise InputError(f"unknown strategy {strategy!r}")
        # the padding layer stays empty: the solid never reaches the grid border
        P[0], P[-1], P[:, 0], P[:, -1], P[:, :, 0], P[:, :, -1] = (False,) * 6
    raise SolverError(f"the voxel solid did not become manifold in {max_rounds} rounds")


def largest_component(S: np.ndarray) -> tuple[np.ndarray, int]:
    """The largest face-connected component of ``S`` and the number of components."""
    cells = np.argwhere(S)
    if cells.shape[0] == 0:
        return S.copy(), 0
    index = np.full(S.shape, -1, dtype=np.int64)
    index[S] = np.arange(cells.shape[0])
    rows, cols = [], []
    for a in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[a], hi[a] = slice(0, -1), slice(1, None)
        A, B = index[tuple(lo)], index[tuple(hi)]
        both = (A >= 0) & (B >= 0)
        rows.append(A[both])
        cols.append(B[both])
    r, c = np.concatenate(rows), np.concatenate(cols)
    n = cells.shape[0]
    G = sp.coo_matrix((np.ones(r.size), (r, c)), shape=(n, n))
    k, lab = connected_components(G, directed=False)
    keep = lab == np.argmax(np.bincount(lab))
    out = np.zeros_like(S)
    out[tuple(cells[keep].T)] = True
    return out, int(k)
