"""Scalar fields over meshes: harmonic interpolation of locked values, clamping.

The material-space texturing paper interpolates user constraints on texture
scale ``S`` and material coordinate ``m`` by Laplacian smoothing with the
constrained vertices locked, then clamps: ``m`` to ``[0, 1]`` and ``S`` to
values of at least ``epsilon > 0``.  This module does exactly that with one
sparse solve.

The interpolant ``u`` solves ``(L u)_i = 0`` at every unlocked vertex with
``u`` fixed at the locked ones (a discrete harmonic function, the minimiser of
the Dirichlet energy ``u' (-L) u``).  With the cotangent Laplacian it
reproduces linear functions on planar meshes exactly (linear precision); with
non-negative weights (the uniform graph Laplacian, or cotangent weights on a
Delaunay mesh) it obeys the maximum principle, so values stay within the
range of the locked values.  Obtuse meshes can have negative cotangent
weights and overshoot slightly, which is why the paper clamps.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.linalg import factor
from geotex.mesh.arrays import as_faces, as_mesh_arrays
from geotex.mesh.topology import edge_topology, vertex_components

__all__ = ["interpolate_scalar", "scale_field", "material_field", "vertex_to_face"]


def _locks(locked_vertices, locked_values, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Validate locks; return sorted unique indices and their values."""
    idx = np.asarray(locked_vertices)
    if idx.ndim != 1:
        raise InputError(f"locked_vertices must be a 1-D array of vertex indices, "
                         f"got shape {idx.shape}")
    if idx.size and idx.dtype.kind not in "iu":
        if idx.dtype.kind == "f" and np.all(np.isfinite(idx)) and np.all(idx == np.round(idx)):
            pass
        else:
            raise InputError(f"locked_vertices must hold integer vertex indices, "
                             f"got dtype {idx.dtype}")
    idx = idx.astype(np.int64)
    try:
        val = np.asarray(locked_values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"locked_values must be a numeric 1-D array: {exc}") from None
    if val.ndim != 1:
        raise InputError(f"locked_values must be a 1-D array, got shape {val.shape}")
    if val.shape[0] != idx.shape[0]:
        raise InputError(f"locked_values has {val.shape[0]} entries but locked_vertices "
                         f"has {idx.shape[0]}: give one value per locked vertex")
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        bad = int(idx[(idx < 0) | (idx >= n)][0])
        raise InputError(f"locked_vertices has index {bad} outside [0, {n})")
    if not np.isfinite(val).all():
        bad = int(np.flatnonzero(~np.isfinite(val))[0])
        raise InputError(f"locked_values has a non-finite value ({val[bad]}) for vertex "
                         f"{int(idx[bad])}")
    uniq, first, inv = np.unique(idx, return_index=True, return_inverse=True)
    uval = val[first]
    clash = np.flatnonzero(uval[inv] != val)
    if clash.size:
        k = int(clash[0])
        raise InputError(f"locked_vertices lists vertex {int(idx[k])} more than once with "
                         f"different values ({uval[inv[k]]} and {val[k]})")
    return uniq, uval


def _clamp_range(clamp) -> tuple[float, float] | None:
    if clamp is None:
        return None
    try:
        lo, hi = clamp
        lo = -np.inf if lo is None else float(lo)
        hi = np.inf if hi is None else float(hi)
    except (TypeError, ValueError):
        raise InputError(f"clamp must be None or a pair (low, high), either may be None, "
                         f"got {clamp!r}") from None
    if np.isnan(lo) or np.isnan(hi) or lo > hi:
        raise InputError(f"clamp must satisfy low <= high, got {clamp!r}")
    return lo, hi


def _laplacian(V: np.ndarray, F: np.ndarray, kind: str) -> sp.csr_matrix:
    """Return ``-L`` (positive semi-definite, rows summing to zero), ``(n, n)``."""
    n = V.shape[0]
    if kind == "cotan":
        L = sp.csr_matrix(igl.cotmatrix(V, F), dtype=np.float64)      # (n, n)
        if not np.isfinite(L.data).all():
            raise InputError("V, F: the cotangent Laplacian is not finite (degenerate "
                             "faces); repair the mesh or use laplacian='uniform'")
        return (-L).tocsr()
    if kind == "uniform":
        E = edge_topology(F, n).edges
        W = sp.coo_matrix((np.ones(2 * E.shape[0]),
                           (np.concatenate([E[:, 0], E[:, 1]]),
                            np.concatenate([E[:, 1], E[:, 0]]))), shape=(n, n)).tocsr()
        return (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
    raise InputError(f"laplacian must be 'cotan' or 'uniform', got {kind!r}")


def _check_components(F: np.ndarray, n: int, locked: np.ndarray) -> None:
    count, labels = vertex_components(F, n)
    has_lock = np.zeros(count + 1, dtype=bool)          # slot ``count``: isolated
    lab = labels[locked]
    has_lock[np.where(lab >= 0, lab, count)] = True
    missing = np.flatnonzero(~has_lock[:count])
    if missing.size:
        comp = int(missing[0])
        members = np.flatnonzero(labels == comp)
        raise InputError(
            f"locked_vertices: component {comp} ({members.size} vertices, e.g. vertex "
            f"{int(members[0])}) has no locked vertex ({missing.size} of {count} components "
            "lack one); lock at least one vertex in every connected component")
    free_isolated = np.flatnonzero(labels < 0)
    if free_isolated.size:
        is_locked = np.zeros(n, dtype=bool)
        is_locked[locked] = True
        free_isolated = free_isolated[~is_locked[free_isolated]]
    if free_isolated.size:
        raise InputError(
            f"locked_vertices: vertex {int(free_isolated[0])} is used by no face and is not "
            f"locked ({free_isolated.size} such vertices); lock them or remove unreferenced "
            "vertices first")


def interpolate_scalar(V, F, locked_vertices, locked_values, *, laplacian: str = "cotan",
                       clamp=None) -> np.ndarray:
    """Interpolate locked vertex values harmonically over the mesh.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    locked_vertices : array_like, (k,) int64
        Vertices whose value is prescribed.  A vertex may be listed more than
        once only with the same value.
    locked_values : array_like, (k,) float64
        Their values (finite).
    laplacian : {"cotan", "uniform"}, optional
        ``"cotan"`` (default): libigl's cotangent Laplacian (``igl.cotmatrix``),
        geometry aware, exact for linear functions on planar meshes.
        ``"uniform"``: graph Laplacian with unit edge weights, obeys the
        maximum principle on any mesh.
    clamp : tuple (low, high), optional
        Clip the result to ``[low, high]``; either end may be None.  Locked
        values must lie inside the range.

    Returns
    -------
    numpy.ndarray, (n,) float64
        Locked vertices carry exactly their locked values; the others solve
        ``(L u)_i = 0``.  Solved as one sparse system in the unlocked
        unknowns (locked columns moved to the right-hand side), by a sparse
        Cholesky-like SuperLU factorization (symmetric mode).

    Raises
    ------
    InputError
        On malformed arrays; a locked index out of range; a length mismatch
        between ``locked_vertices`` and ``locked_values``; non-finite or
        conflicting locked values; locked values outside ``clamp``; an unknown
        Laplacian; a non-finite cotangent Laplacian (degenerate faces); a
        connected component (or a vertex used by no face) without any locked
        vertex, for which the interpolant is undefined (the message names
        the component and one of its vertices).

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(4, 4)
    >>> u = interpolate_scalar(V, F, [0, 24], [0.0, 2.0])
    >>> float(u[0]), float(u[24])
    (0.0, 2.0)
    """
    V, F = as_mesh_arrays(V, F)
    n = V.shape[0]
    if laplacian not in ("cotan", "uniform"):
        raise InputError(f"laplacian must be 'cotan' or 'uniform', got {laplacian!r}")
    rng = _clamp_range(clamp)
    locked, values = _locks(locked_vertices, locked_values, n)
    if rng is not None and values.size and (values.min() < rng[0] or values.max() > rng[1]):
        bad = int(np.flatnonzero((values < rng[0]) | (values > rng[1]))[0])
        raise InputError(f"locked_values: {values[bad]} (vertex {int(locked[bad])}) lies "
                         f"outside clamp [{rng[0]}, {rng[1]}]")
    _check_components(F, n, locked)
    u = np.empty(n)
    u[locked] = values
    is_locked = np.zeros(n, dtype=bool)
    is_locked[locked] = True
    free = np.flatnonzero(~is_locked)
    if free.size:
        Q = _laplacian(V, F, laplacian)
        Qf = Q[free]
        A = Qf[:, free].tocsc()
        rhs = -(Qf[:, locked] @ values)
        try:
            x = np.asarray(factor(A, hpd=True, what="scalar field").solve(rhs), dtype=np.float64)
        except RuntimeError:                              # exactly singular factor
            x = np.full(free.size, np.nan)
        if not np.isfinite(x).all():
            raise InputError("V, F: the Laplacian system is singular (degenerate faces?); "
                             "repair the mesh or use laplacian='uniform'")
        u[free] = x
    if rng is not None:
        np.clip(u, rng[0], rng[1], out=u)
    return u


def scale_field(V, F, locked_vertices, locked_values, *, epsilon: float | None = None,
                laplacian: str = "cotan") -> np.ndarray:
    """Interpolate a texture scale field and keep it positive.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    locked_vertices : array_like, (k,) int64
    locked_values : array_like, (k,) float64
        Prescribed scales, each ``>= epsilon``.
    epsilon : float, optional
        Lower limit (> 0); interpolated values below it are raised to it.
        Default ``1e-3 * max(locked_values)``.
    laplacian : {"cotan", "uniform"}, optional

    Returns
    -------
    numpy.ndarray, (n,) float64
        Every value ``>= epsilon``; locked vertices keep their values.

    Raises
    ------
    InputError
        As :func:`interpolate_scalar`, and when ``epsilon <= 0`` (or is not
        finite), when no locked value is positive (default epsilon), or when a
        locked value is below ``epsilon``.
    """
    vals = np.asarray(locked_values, dtype=np.float64) if _is_numeric(locked_values) else None
    if epsilon is None:
        if vals is None or vals.ndim != 1 or vals.size == 0 or not np.isfinite(vals).all():
            eps = None                         # interpolate_scalar reports the problem
        else:
            eps = 1e-3 * float(vals.max())
            if not eps > 0:
                raise InputError("locked_values: a scale field needs positive values "
                                 f"(largest is {float(vals.max())})")
    else:
        try:
            eps = float(epsilon)
        except (TypeError, ValueError):
            raise InputError(f"epsilon must be a positive number, got {epsilon!r}") from None
        if not (np.isfinite(eps) and eps > 0):
            raise InputError(f"epsilon must be a positive number, got {epsilon!r}")
    if eps is not None and vals is not None and vals.shape == np.shape(locked_vertices) \
            and vals.size and vals.min() < eps:
        k = int(np.argmin(vals))
        raise InputError(f"locked_values: scale {vals[k]} at vertex "
                         f"{int(np.asarray(locked_vertices)[k])} is below epsilon {eps}; "
                         "scales must be positive and at least epsilon")
    clamp = None if eps is None else (eps, None)
    return interpolate_scalar(V, F, locked_vertices, locked_values, laplacian=laplacian,
                              clamp=clamp)


def material_field(V, F, locked_vertices, locked_values, *, laplacian: str = "cotan"
                   ) -> np.ndarray:
    """Interpolate a material coordinate field and clamp it to ``[0, 1]``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    locked_vertices : array_like, (k,) int64
    locked_values : array_like, (k,) float64
        Prescribed material coordinates, each in ``[0, 1]``.
    laplacian : {"cotan", "uniform"}, optional

    Returns
    -------
    numpy.ndarray, (n,) float64
        Values in ``[0, 1]``; locked vertices keep their values.

    Raises
    ------
    InputError
        As :func:`interpolate_scalar`, and when a locked value lies outside
        ``[0, 1]``.
    """
    return interpolate_scalar(V, F, locked_vertices, locked_values, laplacian=laplacian,
                              clamp=(0.0, 1.0))


def _is_numeric(x) -> bool:
    try:
        np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        return False
    return True


def vertex_to_face(F, values) -> np.ndarray:
    """Average per-vertex values over the three corners of every face.

    Parameters
    ----------
    F : array_like, (m, 3) int64
    values : array_like, (n, ...) float64
        Per-vertex data (scalars or any trailing shape); ``n`` must exceed
        every index in ``F``.

    Returns
    -------
    numpy.ndarray, (m, ...) float64
        ``(values[F[:, 0]] + values[F[:, 1]] + values[F[:, 2]]) / 3``.

    Raises
    ------
    InputError
        On malformed faces, indices beyond ``values``, or non-numeric values.
    """
    try:
        val = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"values must be a numeric (n, ...) array: {exc}") from None
    if val.ndim < 1:
        raise InputError("values must have one row per vertex, got a scalar")
    F = as_faces(F, val.shape[0])
    return (val[F[:, 0]] + val[F[:, 1]] + val[F[:, 2]]) / 3.0
