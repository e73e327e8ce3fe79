"""The composited lapped texture as a height field: a printable relief solid.

DESIGN §5.5: "a grey image mapped through any of these becomes a height
field displacement for printing".  The relief goes through the shared core
:func:`geotex.relief.displaced_solid`:

1. the base is refined by exact edge splits to the edge length
   (:func:`geotex.relief.refined_by_edge_splits`; every refined vertex knows
   its base face and barycentric coordinates, so no closest-point search);
2. the pastes are composited there (:func:`geotex.image.composite.composite_at`);
   the luminance is the height ``h`` in ``[0, 1]`` (inverted on request);
3. ``h`` is low-passed by a few uniform Laplacian steps over the refined
   mesh (unfiltered samples alias into spikes);
4. every vertex moves along the smoothed, crease-aware normal by ``depth * h``;
5. where the offset surface crosses itself (found by
   :func:`geotex.check.intersections.self_intersecting_pairs` through
   :func:`geotex.check.report.check_mesh`), the relief is halved on the
   crossing faces and two rings around them, and repeated (at most
   :data:`geotex.relief.RELIEF_ROUNDS` times, then flattened there).

The relief only grows outward from the base surface.
"""

from __future__ import annotations

import math

import igl
import numpy as np

from geotex.check.report import check_mesh
from geotex.errors import InputError
from geotex.image.composite import composite_at, luminance
from geotex.image.records import LappedTexture
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import clamped_barycentric
from geotex.relief import displaced_solid

__all__ = ["displace", "surface_points", "height_at"]

#: Refined meshes are kept below this many faces by default.
DEFAULT_MAX_FACES = 400_000

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
    return I, clamped_barycentric(np.asarray(C, dtype=np.float64), A, B, Cc)

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

def _judged(V, F):

    return V, F, check_mesh(V, F, manifold3d=False)

def displace(V, F, lapped: LappedTexture, *, depth: float, edge_length: float | None = None,
             refine: str = "split", smoothing: int = 1, invert: bool = False,
             max_faces: int = DEFAULT_MAX_FACES, fix_intersections: bool = True
             ) -> tuple[np.ndarray, np.ndarray]:
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
        Longest edge of the refined mesh.  Default: the texture scale over
        48 (about 4 texture pixels of a 192-pixel patch), but no finer than
        ``max_faces`` allows.
    refine : {"split", "none"}, optional
        ``"split"``: exact edge splits (:func:`geotex.relief.refined_by_edge_splits`);
        ``"none"``: the base's own vertices.
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
        On a non-positive depth, a lapped texture of another mesh, or a
        length that needs more than ``max_faces`` faces.
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
    if refine not in ("split", "none"):
        raise InputError(f"refine must be 'split' or 'none', got {refine!r}")
    area = 0.5 * float(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]],
                                               V[F[:, 2]] - V[F[:, 0]]), axis=1).sum())
    floor = math.sqrt(area / (0.14 * float(max_faces)))
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
    if refine == "none":
        L = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0))) * 2.0

    def heights(pts):
        h = luminance(composite_at(lapped, pts.face, pts.bary)[:, :3]).astype(np.float64)
        return 1.0 - h if invert else h

    res = displaced_solid(V, F, heights, depth=d, edge_length=L, smoothing=int(smoothing),
                          max_faces=int(max_faces),
                          judge=_judged if fix_intersections else None,
                          fix_intersections=fix_intersections)
    return res.vertices, res.faces
