"""Bring a target base to a texture's resolution, and carry a face field along.

Used by :func:`geotex.heighttilt.planar.transfer_planar`: texture detail
needs vertices, so the target is refined until its edges are about as long
as the texture's sample spacing (times the texture scale).
"""

from __future__ import annotations

import math

import igl
import numpy as np

from geotex.errors import InputError
from geotex.fields.directions import projected_direction_field, smooth_direction_field
from geotex.heighttilt.base import check_base_mesh
from geotex.mesh.geometry import mean_edge_length
from geotex.mesh.topology import edge_topology

__all__ = ["refine_base", "refine_field", "REFINE_METHODS"]

REFINE_METHODS = ("remesh", "subdivide", "none")
#: Isotropic remeshing passes.
REMESH_ITERATIONS = 6
#: Refuse to build meshes larger than this many faces.
MAX_FACES = 4_000_000


def _area(V, F) -> float:
    return 0.5 * float(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]],
                                                V[F[:, 2]] - V[F[:, 0]]), axis=1).sum())


def refine_base(V, F, edge_length, *, method: str = "remesh") -> tuple[np.ndarray, np.ndarray]:
    """Refine a base until its edges are about ``edge_length`` long.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    edge_length : float
        Wanted edge length (> 0).
    method : {"remesh", "subdivide", "none"}, optional
        ``"remesh"``: pymeshlab's isotropic explicit remeshing with this
        target length (``REMESH_ITERATIONS`` passes, reprojected on the input
        surface, features kept); skipped when the mean edge is already at
        most 1.2 times the target.  ``"subdivide"``: ``k`` midpoint
        subdivisions (each halves every edge and keeps the shape exactly),
        ``k`` the smallest with mean edge ``<= 1.2 * edge_length``.
        ``"none"``: the base as it is.

    Returns
    -------
    V, F : numpy.ndarray
        The refined base (validated like a height-and-tilt base).

    Raises
    ------
    InputError
        Invalid base, non-positive length, unknown method, a result that
        would exceed ``MAX_FACES`` faces, or a remesh that breaks the base
        (non-manifold or degenerate output).
    """
    V, F = check_base_mesh(V, F, name="V")
    if method not in REFINE_METHODS:
        raise InputError(f"refine must be one of {', '.join(map(repr, REFINE_METHODS))}, "
                         f"got {method!r}")
    try:
        L = float(edge_length)
    except (TypeError, ValueError):
        raise InputError(f"edge_length must be a positive number, got {edge_length!r}") from None
    if not (math.isfinite(L) and L > 0):
        raise InputError(f"edge_length must be a positive number, got {edge_length!r}")
    if method == "none":
        return V.copy(), F.copy()
    mean = mean_edge_length(V, F)
    expected = _area(V, F) / (0.433 * L * L)          # equilateral triangles of side L
    if mean <= 1.2 * L:
        return V.copy(), F.copy()
    if method == "subdivide":
        k = max(0, math.ceil(math.log2(mean / (1.2 * L))))
        if F.shape[0] * 4 ** k > MAX_FACES:
            raise InputError(f"refining to edge length {L:.3g} needs {F.shape[0] * 4 ** k} "
                             f"faces (limit {MAX_FACES}); use a larger scale")
        Vr, Fr = igl.upsample(V, F, k) if k else (V, F)
        return check_base_mesh(np.asarray(Vr, dtype=np.float64), np.asarray(Fr, dtype=np.int64),
                               name="subdivided target")
    if expected > MAX_FACES:
        raise InputError(f"refining to edge length {L:.3g} needs about {int(expected)} faces "
                         f"(limit {MAX_FACES}); use a larger scale")
    # lazy: pymeshlab (here and through geotex.mesh.meshlab) takes ~0.25 s to import
    import pymeshlab

    from geotex.mesh.meshlab import arrays_of, meshset_of

    ms = meshset_of(V, F)
    try:
        ms.meshing_isotropic_explicit_remeshing(iterations=REMESH_ITERATIONS,
                                                targetlen=pymeshlab.PureValue(L))
    except pymeshlab.PyMeshLabException as exc:
        raise InputError(f"isotropic remeshing failed: {exc}; try refining by "
                         "subdivision instead") from None
    Vr, Fr = arrays_of(ms)
    try:
        Vr, Fr = check_base_mesh(Vr, Fr, name="remeshed target")
    except InputError as exc:
        raise InputError(f"isotropic remeshing broke the base ({exc}); "
                         "try refine='subdivide'") from None
    t0, t1 = edge_topology(F, V.shape[0]), edge_topology(Fr, Vr.shape[0])
    if (t0.boundary.size == 0) != (t1.boundary.size == 0):
        raise InputError("isotropic remeshing opened or closed the surface; "
                         "try refine='subdivide'")
    return Vr, Fr


def refine_field(V, F, Vr, Fr, field, *, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """A per-face direction field on the refined base ``(Vr, Fr)``.

    Parameters
    ----------
    V, F : numpy.ndarray
        The base before refinement.
    Vr, Fr : numpy.ndarray
        The refined base.
    field : {"up", "smooth"} or array_like (len(F), 3)
        ``"up"``: ``up`` projected on every refined face (filled smoothly
        where it is normal to the surface); ``"smooth"``: the smoothest unit
        vector field of the refined base; an array: one vector per face of
        ``F``, given to every refined face whose centroid is closest to it.

    Returns
    -------
    numpy.ndarray, (len(Fr), 3) float64

    Raises
    ------
    InputError
        Unknown name, array of the wrong shape or with non-finite values,
        bad ``up``.
    """
    if isinstance(field, str):
        if field == "up":
            return projected_direction_field(Vr, Fr, up)[0]
        if field == "smooth":
            return smooth_direction_field(Vr, Fr).vectors
        raise InputError(f"field must be 'up', 'smooth' or one vector per face, got {field!r}")
    vec = getattr(field, "vectors", field)
    try:
        arr = np.asarray(vec, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("field must be 'up', 'smooth' or a numeric (m, 3) array") from None
    if arr.shape != (F.shape[0], 3) or not np.isfinite(arr).all():
        raise InputError(f"field must have shape ({F.shape[0]}, 3) (one finite vector per "
                         f"face of the target), got {arr.shape}")
    if Fr.shape == F.shape and np.array_equal(Fr, F) and np.array_equal(Vr, V):
        return arr.copy()
    C = Vr[Fr].mean(axis=1)
    _, idx, _ = igl.point_mesh_squared_distance(C, V, F)
    return arr[np.asarray(idx, dtype=np.int64)]
