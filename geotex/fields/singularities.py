"""Singularities (vertex indices) of per-face N-direction fields.

A per-face field is smooth inside faces and turns only across edges, so its
singularities sit at vertices.  For an interior vertex ``v`` with one-ring faces
``f_0 .. f_{k-1}`` in counter-clockwise order, let ``phi_f = N theta_f`` be the
field's N-fold angle in the frame of face ``f`` and ``rho`` the transport angle
of the discrete connection (:mod:`geotex.fields.frames`).  The index is::

    index(v) = ( sum_i wrap(phi_{i+1} - phi_i - N rho_{i -> i+1}) + N K_v ) / (2 pi N)

with ``wrap`` reducing to ``(-pi, pi]`` and ``K_v = 2 pi - (sum of corner
angles at v)`` the angle defect.  The value is an exact multiple of ``1 / N``
(it is rounded to the nearest one), and because every wrapped difference is
computed once per edge and added to one end with ``+`` and to the other with
``-``, the indices over a closed mesh sum to exactly ``sum K_v / 2 pi = chi``,
the Euler characteristic (discrete Gauss-Bonnet).

Boundary vertices (and vertices on non-manifold edges) have no index: their
one-ring is not a closed loop.  They are skipped, so on a mesh with boundary the
interior indices sum to ``chi`` minus the boundary turning, not to ``chi``.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from geotex.errors import InputError
from geotex.fields.frames import (FaceConnection, _checked_arrays, _connection, tangent_angles,
                                  wrap_angle)

__all__ = ["singularities", "index_sum", "vertex_indices", "angle_defects"]


def angle_defects(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Return ``2 pi - (sum of corner angles)`` per vertex, ``(n,)`` float64.

    Unreferenced vertices get ``2 pi``; boundary vertices get the value of the
    same formula (not the geodesic curvature).
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    P = V[F]
    ang = np.empty(F.shape, dtype=np.float64)
    for k in range(3):
        a = P[:, (k + 1) % 3] - P[:, k]
        b = P[:, (k + 2) % 3] - P[:, k]
        ang[:, k] = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1),
                               np.einsum("ij,ij->i", a, b))
    return 2.0 * np.pi - np.bincount(F.ravel(), weights=ang.ravel(), minlength=V.shape[0])


def _field_phases(conn: FaceConnection, field, symmetry) -> tuple[np.ndarray, int]:
    """Return (N-fold angle per face, N) of a DirectionField, vectors or complex values."""
    m = conn.n_faces
    if hasattr(field, "values") and hasattr(field, "symmetry"):
        if symmetry is not None and int(symmetry) != int(field.symmetry):
            raise InputError(f"symmetry={symmetry} disagrees with field.symmetry="
                             f"{field.symmetry}; leave symmetry out for a DirectionField")
        values = np.asarray(field.values)
        N = int(field.symmetry)
        if values.shape != (m,):
            raise InputError(f"field has {values.shape[0]} values but F has {m} faces; "
                             "pass the field computed on this mesh")
        return np.angle(values), N
    N = 1 if symmetry is None else symmetry
    if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
        raise InputError(f"symmetry must be a positive integer, got {symmetry!r}")
    N = int(N)
    arr = np.asarray(field)
    if np.iscomplexobj(arr):
        if arr.shape != (m,):
            raise InputError(f"field must have shape ({m},) for complex values, got {arr.shape}")
        if not np.isfinite(arr).all():
            raise InputError("field has non-finite values")
        return np.angle(arr), N
    try:
        vec = np.asarray(arr, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("field must be a DirectionField, an (m, 3) array of vectors "
                         "or (m,) complex values") from None
    if vec.shape != (m, 3):
        raise InputError(f"field must have shape ({m}, 3) (one vector per face), got {vec.shape}")
    if not np.isfinite(vec).all():
        raise InputError("field has non-finite vectors")
    return N * tangent_angles(conn.T1, conn.T2, vec), N


def _index_numerators(V: np.ndarray, F: np.ndarray, conn: FaceConnection, phi: np.ndarray,
                      N: int) -> np.ndarray:
    """Return ``k_v`` with ``index(v) = k_v / N`` (0 for non-interior vertices)."""
    n = V.shape[0]
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    delta = wrap_angle(phi[g] - phi[f] - N * conn.angle)
    turn = (np.bincount(conn.vertices[:, 1], weights=delta, minlength=n)
            - np.bincount(conn.vertices[:, 0], weights=delta, minlength=n))
    total = turn + N * angle_defects(V, F)
    k = np.rint(total / (2.0 * np.pi)).astype(np.int64)
    k[~conn.interior_vertex] = 0
    return k


def vertex_indices(V, F, field, *, symmetry: int | None = None,
                   connection: FaceConnection | None = None) -> np.ndarray:
    """Return the index of the field at every vertex.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    field : DirectionField or array_like
        A :class:`geotex.fields.directions.DirectionField`, an ``(m, 3)`` array
        with one representative tangent vector per face, or ``(m,)`` complex
        values ``exp(i N theta)`` in the face frames.
    symmetry : int, optional
        ``N`` for array input (default 1); must match for a DirectionField.
    connection : FaceConnection, optional
        :func:`geotex.fields.frames.face_connection` of this mesh, when the
        caller has it already (skips recomputing and re-checking the mesh).

    Returns
    -------
    numpy.ndarray, (n,) float64
        ``k / N`` at interior vertices, NaN at boundary, non-manifold and
        unreferenced vertices.

    Raises
    ------
    InputError
        On malformed arrays, degenerate or inconsistently oriented faces, or a
        field of the wrong shape.
    """
    if connection is None:
        V, F = _checked_arrays(V, F)
        conn = _connection(V, F)
    else:
        V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
        if not isinstance(connection, FaceConnection) or connection.n_faces != F.shape[0]:
            raise InputError("connection must be the FaceConnection of this mesh "
                             "(geotex.fields.frames.face_connection(V, F))")
        conn = connection
    phi, N = _field_phases(conn, field, symmetry)
    k = _index_numerators(V, F, conn, phi, N)
    out = k / N
    out[~conn.interior_vertex] = np.nan
    return out


def singularities(V, F, field, *, symmetry: int | None = None) -> list[tuple[int, float]]:
    """Return the singular vertices of a per-face N-direction field.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    field : DirectionField or array_like
        See :func:`vertex_indices`.
    symmetry : int, optional
        ``N`` for array input (default 1).

    Returns
    -------
    list of (int, float)
        ``(vertex, index)`` for every interior vertex with a non-zero index,
        in vertex order; ``index`` is exactly ``k / N`` (a float).

    Raises
    ------
    InputError
        See :func:`vertex_indices`.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> from geotex.fields.directions import smooth_direction_field
    >>> V, F = icosphere(2)
    >>> field = smooth_direction_field(V, F, symmetry=4)
    >>> float(sum(index for _, index in singularities(V, F, field)))
    2.0
    """
    V, F = _checked_arrays(V, F)
    conn = _connection(V, F)
    phi, N = _field_phases(conn, field, symmetry)
    return _singularity_list(_index_numerators(V, F, conn, phi, N), N)


def _singularity_list(k: np.ndarray, N: int) -> list[tuple[int, float]]:
    nz = np.flatnonzero(k)
    return [(int(v), int(k[v]) / N) for v in nz]


def index_sum(V, F, field, *, symmetry: int | None = None) -> Fraction:
    """Return the exact sum of all vertex indices as a :class:`fractions.Fraction`.

    On a closed, consistently oriented mesh this equals the Euler
    characteristic ``V - E + F`` (2 for a sphere, 0 for a torus, ``2 - 2g``).

    Parameters
    ----------
    V, F, field, symmetry
        See :func:`vertex_indices`.

    Returns
    -------
    fractions.Fraction

    Raises
    ------
    InputError
        See :func:`vertex_indices`.
    """
    V, F = _checked_arrays(V, F)
    conn = _connection(V, F)
    phi, N = _field_phases(conn, field, symmetry)
    return Fraction(int(_index_numerators(V, F, conn, phi, N).sum()), N)
