"""The composited lapped texture as a height field: a printable relief solid.

DESIGN §5.5: "a grey image mapped through any of these becomes a height
field displacement for printing".  Steps:

1. refine a copy of the base so its edges are short enough to carry the
   texture (pymeshlab isotropic remeshing through
   :func:`geotex.heighttilt.refine.refine_base`, or midpoint subdivision);
2. locate every refined vertex on the base (closest point, libigl AABB) and
   composite the pastes there (:func:`geotex.image.composite.composite_at`);
   the luminance is the height ``h`` in ``[0, 1]`` (inverted on request);
3. low-pass ``h`` by a few uniform Laplacian steps over the refined mesh (the
   vertex spacing is coarser than the texture's pixels; unfiltered samples
   alias into spikes);
4. move every vertex along its area-weighted normal by ``depth * h``;
5. where the offset surface crosses itself (concave creases narrower than
   the relief, found by :func:`geotex.check.intersections.self_intersecting_pairs`),
   halve the relief on the crossing faces and two rings around them, and
   repeat (at most ``RELIEF_ROUNDS`` times, then flatten those places to
   the base), so the solid stays printable when the refined base is.

The relief only grows outward from the base surface.
"""

from __future__ import annotations

import math

import igl
import numpy as np
import scipy.sparse as sp

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import InputError
from geotex.heighttilt.refine import refine_base
from geotex.image.composite import composite_at, luminance
from geotex.image.records import LappedTexture
from geotex.mesh.arrays import as_mesh_arrays

__all__ = ["displace", "surface_points", "height_at"]

#: Refined meshes are kept below this many faces by default.
DEFAULT_MAX_FACES = 400_000
#: Rounds of local relief reduction where the offset surface crosses itself.
RELIEF_ROUNDS = 6


def surface_points(V, F, P) -> tuple[np.ndarray, np.ndarray]:
    """Closest face and barycentric coordinates of points on a mesh.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    P : numpy.ndarray, (q, 3) float64

    Returns
    -------
    faces : numpy.ndarray, (q,) int64
    bary : numpy.ndarray, (q, 3) float64
        Clamped to the triangle (non-negative, summing to 1).
    """
    _, I, C = igl.point_mesh_squared_distance(np.ascontiguousarray(P), V, F)
    I = np.asarray(I, dtype=np.int64).ravel()
    A, B, Cc = V[F[I, 0]], V[F[I, 1]], V[F[I, 2]]
    v0, v1, v2 = B - A, Cc - A, np.asarray(C) - A
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    den = np.where(den > 0, den, 1.0)
    b1 = (d11 * d20 - d01 * d21) / den
    b2 = (d00 * d21 - d01 * d20) / den
    bary = np.clip(np.stack([1.0 - b1 - b2, b1, b2], axis=1), 0.0, None)
    bary /= bary.sum(axis=1, keepdims=True)
    return I, bary


def height_at(V, F, lapped: LappedTexture, P, *, invert: bool = False) -> np.ndarray:
    """Composited luminance of the lapped texture at points near the surface.

    Returns
    -------
    numpy.ndarray, (q,) float64
        In ``[0, 1]`` (``1 - luminance`` with ``invert``).
    """
    faces, bary = surface_points(V, F, P)
    h = luminance(composite_at(lapped, faces, bary)[:, :3]).astype(np.float64)
    return 1.0 - h if invert else h


def _smooth(F: np.ndarray, n: int, h: np.ndarray, steps: int) -> np.ndarray:
    if steps <= 0:
        return h
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(2 * e.shape[0]), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                      shape=(n, n)).tocsr()
    A.data[:] = 1.0
    deg = np.asarray(A.sum(axis=1)).ravel()
    M = sp.diags(1.0 / np.maximum(deg, 1.0)) @ A
    for _ in range(steps):
        h = 0.5 * h + 0.5 * (M @ h)
    return h


def displace(V, F, lapped: LappedTexture, *, depth: float, edge_length: float | None = None,
             refine: str = "remesh", smoothing: int = 1, invert: bool = False,
             max_faces: int = DEFAULT_MAX_FACES, fix_intersections: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Displace a refined copy of the base by the composited texture.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        The base the pastes were made on (a closed manifold for a printable
        result).
    lapped : LappedTexture
    depth : float
        Relief height for luminance 1 (mesh units, > 0).
    edge_length : float, optional
        Target edge length of the refined mesh.  Default: the texture scale
        over 48 (about 4 texture pixels of a 192-pixel patch), but no finer
        than ``max_faces`` allows.
    refine : {"remesh", "subdivide", "none"}, optional
        See :func:`geotex.heighttilt.refine.refine_base`.
    smoothing : int, optional
        Laplacian low-pass steps on the heights.
    invert : bool, optional
        Dark is high instead of light.
    max_faces : int, optional
    fix_intersections : bool, optional
        Lower the relief locally where the offset surface crosses itself
        (step 5 of the module docstring).

    Returns
    -------
    V, F : numpy.ndarray
        The displaced solid, ``(p, 3)`` float64 and ``(k, 3)`` int64.

    Raises
    ------
    InputError
        On a non-positive depth, a lapped texture of another mesh, or a base
        that cannot be refined.
    """
    V, F = as_mesh_arrays(V, F)
    if F.shape[0] != lapped.n_faces or V.shape[0] != lapped.n_vertices:
        raise InputError(f"the lapped texture was made for {lapped.n_vertices} vertices and "
                         f"{lapped.n_faces} faces, not {V.shape[0]} and {F.shape[0]}")
    try:
        d = float(depth)
    except (TypeError, ValueError):
        raise InputError(f"depth must be a positive number, got {depth!r}") from None
    if not (math.isfinite(d) and d > 0):
        raise InputError(f"depth must be a positive number, got {depth!r}")
    if int(smoothing) != smoothing or smoothing < 0:
        raise InputError(f"smoothing must be an integer >= 0, got {smoothing!r}")
    area = 0.5 * float(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]],
                                               V[F[:, 2]] - V[F[:, 0]]), axis=1).sum())
    floor = math.sqrt(area / (0.433 * float(max_faces)))
    if edge_length is None:
        sc = lapped.metadata.get("scale")
        if not isinstance(sc, (int, float)):
            sc = 0.15 * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
        L = max(float(sc) / 48.0, floor)
    else:
        try:
            L = float(edge_length)
        except (TypeError, ValueError):
            raise InputError(f"edge_length must be a positive number, got {edge_length!r}"
                             ) from None
        if not (math.isfinite(L) and L > 0):
            raise InputError(f"edge_length must be a positive number, got {edge_length!r}")
        if L < floor:
            raise InputError(f"edge_length {L:.3g} needs more than {max_faces} faces; "
                             f"use at least {floor:.3g} or raise max_faces")
    Vr, Fr = refine_base(V, F, L, method=refine)
    h = height_at(V, F, lapped, Vr, invert=invert)
    h = _smooth(Fr, Vr.shape[0], h, int(smoothing))
    N = np.asarray(igl.per_vertex_normals(Vr, Fr, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA),
                   dtype=np.float64)
    Vd = Vr + (d * h)[:, None] * N
    if fix_intersections:
        gain = np.ones(Vr.shape[0])
        n = Vr.shape[0]
        for r in range(RELIEF_ROUNDS + 1):
            pairs = self_intersecting_pairs(Vd, Fr)
            if len(pairs) == 0:
                break
            hit = np.zeros(n, dtype=bool)
            hit[Fr[np.unique(np.asarray(pairs).ravel())].ravel()] = True
            for _ in range(2):
                hit[Fr[hit[Fr].any(axis=1)].ravel()] = True
            gain[hit] = 0.0 if r == RELIEF_ROUNDS - 1 else 0.5 * gain[hit]
            Vd = Vr + (d * h * gain)[:, None] * N
    return np.ascontiguousarray(Vd), np.ascontiguousarray(Fr)
