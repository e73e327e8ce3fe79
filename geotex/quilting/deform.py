"""Laplacian editing with soft position targets and exactly fixed vertices.

Minimises ``sum ||L w - L v||^2 + mu sum_c ||w_c - p_c||^2`` over the free
vertices ``w``: ``L`` is the cotangent (or uniform) Laplacian of the rest
mesh ``(V, F)``, ``p_c`` the targets of the constrained vertices.  Fixed
vertices are eliminated from the system (their columns move to the right-hand
side) and copied back afterwards, so they are bit-identical to the input.  A
tiny multiple of ``||w - v||^2`` keeps components without any constraint at
rest (the Laplacian alone does not see translations).  One sparse LU
factorization serves the three coordinate columns.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.linalg import factor
from geotex.mesh.arrays import as_mesh_arrays

__all__ = ["laplacian_deformed", "uniform_laplacian"]

_REGULARIZATION = 1e-8


def uniform_laplacian(F: np.ndarray, n: int) -> sp.csr_matrix:
    """Graph Laplacian ``A - D`` of the mesh edges, ``(n, n)``, negative diagonal."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E = np.unique(np.sort(E, axis=1), axis=0)
    A = sp.coo_matrix((np.ones(2 * len(E)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])),
                      shape=(n, n)).tocsr()
    A.data[:] = 1.0
    return (A - sp.diags(np.asarray(A.sum(axis=1)).ravel())).tocsr()


def _index_set(idx, n: int, name: str) -> np.ndarray:
    arr = np.asarray(idx)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise InputError(f"{name} as a mask must have shape ({n},), got {arr.shape}")
        return np.flatnonzero(arr)
    arr = np.asarray(arr, dtype=np.int64).ravel()
    if arr.size and (arr.min() < 0 or arr.max() >= n):
        raise InputError(f"{name} holds vertex indices outside [0, {n})")
    return arr


def laplacian_deformed(V, F, targets=None, *, mu: float = 10.0, fixed=None,
                       laplacian: str = "cotan") -> np.ndarray:
    """Deform a mesh toward position targets while keeping its Laplacian coordinates.

    Parameters
    ----------
    V : array_like, (n, 3) float64
        Rest positions.
    F : array_like, (m, 3) int64
    targets : tuple (indices (k,) int, positions (k, 3) float), optional
        Constrained vertices and where they should go (soft, weight ``mu``).
        Repeated indices add up.  Targets of fixed vertices are ignored.
    mu : float, optional
        Weight of the targets relative to the Laplacian term (> 0).
    fixed : array_like of int or (n,) bool mask, optional
        Vertices that do not move at all (returned bit-exact).
    laplacian : {"cotan", "uniform"}, optional
        Cotangent weights (libigl) or the uniform graph Laplacian (robust on
        sliver triangles).

    Returns
    -------
    W : numpy.ndarray, (n, 3) float64
        New positions (a new array; the input is not modified).

    Raises
    ------
    InputError
        On malformed arrays, targets or options.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> W = laplacian_deformed(V, F, ([0], [V[0] * 1.2]), fixed=[5, 6])
    >>> bool((W[[5, 6]] == V[[5, 6]]).all() and abs(W[0] - V[0]).max() > 0.05)
    True
    """
    V, F = as_mesh_arrays(V, F)
    n = V.shape[0]
    if not mu > 0 or not np.isfinite(mu):
        raise InputError(f"mu must be a positive number, got {mu!r}")
    if laplacian not in ("cotan", "uniform"):
        raise InputError(f"laplacian must be 'cotan' or 'uniform', got {laplacian!r}")
    if targets is None:
        idx, pos = np.zeros(0, np.int64), np.zeros((0, 3))
    else:
        try:
            idx_raw, pos_raw = targets
        except (TypeError, ValueError):
            raise InputError("targets must be a pair (indices, positions)") from None
        idx = _index_set(idx_raw, n, "targets indices")
        pos = np.asarray(pos_raw, dtype=np.float64).reshape(-1, 3)
        if pos.shape[0] != idx.shape[0] or not np.isfinite(pos).all():
            raise InputError(f"targets need {idx.shape[0]} finite (k, 3) positions, "
                             f"got shape {pos.shape}")
    fix = np.zeros(n, dtype=bool)
    if fixed is not None:
        fix[_index_set(fixed, n, "fixed")] = True
    W = V.copy()
    active = ~fix[idx]
    idx, pos = idx[active], pos[active]
    free = np.flatnonzero(~fix)
    if idx.size == 0 or free.size == 0 or F.shape[0] == 0:
        return W
    if laplacian == "cotan":
        L = sp.csr_matrix(igl.cotmatrix(V, F))
        bad = ~np.isfinite(L.data)
        if bad.any():
            L = uniform_laplacian(F, n)
    else:
        L = uniform_laplacian(F, n)
    delta = L @ V
    Lf = L[:, free]
    Lx = L[:, np.flatnonzero(fix)]
    rhs_lap = delta - Lx @ V[fix]
    pos_in_free = np.full(n, -1, dtype=np.int64)
    pos_in_free[free] = np.arange(free.size)
    rows = pos_in_free[idx]
    S = sp.csr_matrix((np.ones(idx.size), (np.arange(idx.size), rows)),
                      shape=(idx.size, free.size))
    scale = float(abs(L.diagonal()).mean()) ** 2 or 1.0
    A = (Lf.T @ Lf + mu * scale * (S.T @ S)
         + _REGULARIZATION * scale * sp.identity(free.size)).tocsc()
    b = Lf.T @ rhs_lap + mu * scale * (S.T @ pos) + _REGULARIZATION * scale * V[free]
    W[free] = factor(A, what="Laplacian deformation").solve(b)
    return W
