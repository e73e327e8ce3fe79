"""Direction fields by radial basis functions of surface distance (lapped textures §3.2).

The user gives directions at a few faces.  Each constraint face ``c_i`` carries
a radial basis function ``phi(d(c_i, f) / r_i)`` of the surface distance
``d``, measured by Dijkstra's algorithm on the dual graph (face centroids
joined through the midpoints of shared edges; one
``scipy.sparse.csgraph.dijkstra`` call from all constraint faces at once).
The 3D vector coefficients ``W`` solve the interpolation system

    sum_i phi(d(c_i, c_j) / r_i) W_i + smoothing * W_j / weight_j = t_j

so the interpolant reproduces every constraint direction ``t_j`` at its face
when ``smoothing`` is 0.  The field at face ``f`` is ``sum_i phi(...) W_i``
projected onto the face plane and normalized.  Faces where that projection
vanishes (the interpolated vector is normal to the face, or the distance is
infinite because the face is on a component without constraints) are filled
by the smooth field solve of :mod:`geotex.fields.directions` with all other
faces held fixed.

The approach is simple and fast; it does not know about the surface's
connection, so on strongly curved surfaces prefer
:func:`geotex.fields.directions.smooth_direction_field`.
"""

from __future__ import annotations

from numbers import Real

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from geotex.errors import InputError
from geotex.fields.directions import DirectionField, _fill, _resolve_constraints
from geotex.fields.frames import _checked_arrays, _connection, tangent_angles
from geotex.fields.singularities import _index_numerators, _singularity_list
from geotex.options import positive_number

__all__ = ["rbf_direction_field", "KERNELS", "surface_distances"]

KERNELS = ("gaussian", "inverse_multiquadric", "thin_plate")


def _kernel(name: str, s: np.ndarray) -> np.ndarray:
    """Evaluate a kernel at scaled distances ``s >= 0`` (``inf`` gives 0)."""
    finite = np.isfinite(s)
    s0 = np.where(finite, s, 0.0)
    if name == "gaussian":
        out = np.exp(-s0 * s0)
    elif name == "inverse_multiquadric":
        out = 1.0 / np.sqrt(1.0 + s0 * s0)
    else:  # thin_plate
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(s0 > 0, s0 * s0 * np.log(np.where(s0 > 0, s0, 1.0)), 0.0)
    return np.where(finite, out, 0.0)


def surface_distances(V, F, faces) -> np.ndarray:
    """Return dual-graph (Dijkstra) distances from the given faces to every face.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    faces : array_like, (k,) int
        Source faces.

    Returns
    -------
    numpy.ndarray, (k, m) float64
        Length of the shortest path of centroid - edge midpoint - centroid
        steps across interior edges; ``inf`` for faces on other components.

    Raises
    ------
    InputError
        On malformed, degenerate or inconsistently oriented meshes or face
        indices out of range.
    """
    V, F = _checked_arrays(V, F)
    src = np.asarray(faces)
    if src.ndim != 1 or (src.size and src.dtype.kind not in "iu"):
        raise InputError("faces must be a 1-D array of face indices")
    src = src.astype(np.int64)
    if src.size and (src.min() < 0 or src.max() >= F.shape[0]):
        raise InputError(f"faces must lie in [0, {F.shape[0]})")
    return _distances(_connection(V, F), src)


def _distances(conn, src: np.ndarray) -> np.ndarray:
    m = conn.n_faces
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    # a zero-length dual edge is impossible (non-degenerate faces), so csr keeps it
    G = sp.csr_matrix((conn.dual_length, (f, g)), shape=(m, m))
    return np.atleast_2d(dijkstra(G, directed=False, indices=src))


def rbf_direction_field(V, F, constraints, *, kernel: str = "gaussian", radius=None,
                        smoothing: float = 0.0, tolerance: float = 1e-3,
                        max_snap_distance=None) -> DirectionField:
    """Interpolate constraint directions with radial basis functions of surface distance.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    constraints : sequence of Constraint or dict
        At least one; see :class:`geotex.fields.directions.Constraint`.  A
        constraint's ``radius`` overrides the global one for its basis
        function; its ``weight`` sets how closely it is fitted when
        ``smoothing > 0``.  Constraints on the same face must agree.
    kernel : {"gaussian", "inverse_multiquadric", "thin_plate"}, optional
        ``exp(-s^2)``, ``1 / sqrt(1 + s^2)`` or ``s^2 log s`` of
        ``s = distance / radius``; the thin-plate system is augmented with a
        constant vector term, and its constraints cannot carry their own
        radius (mixing radii would add an unbalanced ``d^2`` term).
    radius : float, optional
        Basis radius (surface distance).  Default: the largest distance from
        any face to its nearest constraint, so every face is within one radius
        of a constraint.
    smoothing : float, optional
        Non-negative regularization; 0 interpolates exactly.
    tolerance : float, optional
        Faces where the projected interpolant is shorter than ``tolerance``
        times the interpolant are filled by the smooth solve.
    max_snap_distance : float, optional
        Largest distance of a point constraint from the surface (default 1 %
        of the bounding-box diagonal).

    Returns
    -------
    DirectionField
        ``symmetry`` 1, ``values`` of modulus 1.  At constraint faces the
        vector is the constraint's projected direction exactly.

    Raises
    ------
    InputError
        On malformed meshes, no constraints, invalid constraints (see
        :func:`geotex.fields.directions.smooth_direction_field`), conflicting
        constraints on one face, an unknown kernel, a per-constraint radius
        with ``kernel="thin_plate"``, or a non-positive radius,
        negative smoothing or non-positive tolerance.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(6, 6)
    >>> field = rbf_direction_field(V, F, [{"face": 0, "direction": [1, 0, 0]},
    ...                                    {"face": 71, "direction": [0, 1, 0]}])
    >>> field.vectors[71].round(12).tolist()
    [0.0, 1.0, 0.0]
    """
    V, F = _checked_arrays(V, F)
    if kernel not in KERNELS:
        raise InputError(f"kernel must be one of {', '.join(KERNELS)}, got {kernel!r}")
    if isinstance(smoothing, bool) or not isinstance(smoothing, Real) \
            or not np.isfinite(smoothing) or smoothing < 0:
        raise InputError(f"smoothing must be a finite number >= 0, got {smoothing!r}")
    tol = positive_number(tolerance, name="tolerance")
    conn = _connection(V, F)
    res = _resolve_constraints(V, F, conn, constraints, max_snap_distance=max_snap_distance)
    if res.faces.size == 0:
        raise InputError("constraints is empty; give at least one constraint "
                         "(or use smooth_direction_field for a field without constraints)")
    faces, first, inverse = np.unique(res.faces, return_index=True, return_inverse=True)
    clash = np.flatnonzero(np.abs(res.tangents - res.tangents[first][inverse]).max(axis=1) > 1e-12)
    if clash.size:
        i = int(clash[0])
        raise InputError(f"constraints[{i}] and constraints[{int(first[inverse[i]])}] give "
                         f"different directions for face {int(res.faces[i])}; give one "
                         "direction per face")
    T = res.tangents[first]
    w = res.weights[first]
    r_own = res.radii[first]
    D = _distances(conn, faces)                       # (k, m)
    if radius is None:
        nearest = D.min(axis=0)
        nearest = nearest[np.isfinite(nearest)]
        r_default = float(nearest.max()) if nearest.size else 0.0
        if not r_default > 0:                          # every face is a constraint face
            r_default = float(conn.dual_length.mean()) if conn.dual_length.size else 1.0
    else:
        r_default = positive_number(radius, name="radius")
    if kernel == "thin_plate" and not np.isnan(res.radii).all():
        i = int(np.flatnonzero(~np.isnan(res.radii))[0])
        raise InputError(f"constraints[{i}] radius cannot be used with kernel='thin_plate' "
                         "(its basis has no extent); drop the radius or use 'gaussian'")
    r = np.where(np.isnan(r_own), r_default, r_own)
    k = faces.size
    B = _kernel(kernel, D[:, faces].T / r[None, :])    # B[j, i] = phi_i(d(c_i, c_j))
    B = B + np.diag(smoothing / w)
    rhs = T
    if kernel == "thin_plate":
        B = np.block([[B, np.ones((k, 1))], [np.ones((1, k)), np.zeros((1, 1))]])
        rhs = np.vstack([T, np.zeros((1, 3))])
    try:
        coef = np.linalg.solve(B, rhs)
    except np.linalg.LinAlgError:
        coef = np.linalg.lstsq(B, rhs, rcond=None)[0]
    Phi = _kernel(kernel, D.T / r[None, :])           # (m, k)
    vec = Phi @ coef[:k]
    if kernel == "thin_plate":
        vec = vec + coef[k]
    Nrm = conn.N
    t = vec - np.einsum("ij,ij->i", vec, Nrm)[:, None] * Nrm
    tlen = np.linalg.norm(t, axis=1)
    vlen = np.linalg.norm(vec, axis=1)
    reachable = np.isfinite(D).any(axis=0)
    undefined = ~reachable | ~(tlen > tol * vlen) | ~(vlen > 1e-12)
    undefined[faces] = False
    out = np.zeros_like(vec)
    ok = ~undefined
    out[ok] = t[ok] / tlen[ok, None]
    out[faces] = T
    out = _fill(V, F, conn, out, undefined)
    phase = tangent_angles(conn.T1, conn.T2, out)
    values = np.exp(1j * phase)
    kv = _index_numerators(V, F, conn, phase, 1)
    return DirectionField(vectors=out, symmetry=1, values=values,
                          singularities=tuple(_singularity_list(kv, 1)), normals=conn.N,
                          constrained=faces.astype(np.int64))
