"""Base shape of a textured mesh by implicit mean-curvature flow (same connectivity)."""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError, SolverError
from geotex.heighttilt.validation import check_base_mesh
from geotex.linalg import factor
from geotex.mesh.geometry import mean_edge_length

__all__ = ["smoothed_base"]


def smoothed_base(V, F, *, steps: int = 3, time_step: float | None = None) -> np.ndarray:
    """Smooth a textured mesh by implicit mean-curvature flow, keeping correspondence.

    Each step solves ``(M_k - dt L) V_{k+1} = M_k V_k`` (Desbrun et al. 1999)
    with the cotangent Laplacian ``L`` of the *input* mesh (``igl.cotmatrix``,
    negative semi-definite, scale free) and the Voronoi mass matrix ``M_k``
    (``igl.massmatrix``) *recomputed at every step* on the current positions,
    so that shrinking regions keep a consistent area weighting.  The vertices
    move, the faces stay: vertex ``i`` of the result corresponds to vertex
    ``i`` of ``V``.  Boundary vertices of open meshes move too (their
    Laplacian rows are the one-sided cotangent sums).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    steps : int, optional
        Number of implicit steps (>= 0; 0 returns a copy).
    time_step : float, optional
        Dimensionless step.  The actual ``dt = time_step * l**2`` with ``l``
        the mean edge length of the input, which makes the flow invariant
        under uniform scaling (``M`` scales as length squared, ``L`` not at
        all) and under rigid motions.  Default 1.0: about one ring of
        neighbours is smoothed per step.

    Returns
    -------
    numpy.ndarray, (n, 3) float64
        The base shape ``Vs``.

    Raises
    ------
    InputError
        Empty mesh, zero-area faces, non-manifold edges, unreferenced
        vertices (see :func:`check_base_mesh`), a negative ``steps`` or a
        non-positive ``time_step``.
    SolverError
        If the implicit flow diverges (non-finite positions).

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> smoothed_base(V, F).shape
    (162, 3)
    """
    V, F = check_base_mesh(V, F)
    if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise InputError(f"steps must be a non-negative integer, got {steps!r}")
    if time_step is None:
        time_step = 1.0
    try:
        ts = float(time_step)
    except (TypeError, ValueError):
        raise InputError(f"time_step must be a positive number, got {time_step!r}") from None
    if not (np.isfinite(ts) and ts > 0):
        raise InputError(f"time_step must be a positive number, got {time_step!r}")
    dt = ts * mean_edge_length(V, F) ** 2
    L = sp.csc_matrix(igl.cotmatrix(V, F))
    Vk = V.copy()
    for _ in range(int(steps)):
        M = sp.csc_matrix(igl.massmatrix(Vk, F, igl.MASSMATRIX_TYPE_VORONOI))
        lu = factor(M - dt * L, what="smoothed_base")
        rhs = M @ Vk
        Vk = np.column_stack([lu.solve(rhs[:, d]) for d in range(3)])
        if not np.isfinite(Vk).all():
            raise SolverError("smoothed_base diverged (non-finite positions); "
                              "use a smaller time_step or fewer steps")
    return np.ascontiguousarray(Vk)
