"""Tile sizes for polycubes: the automatic search's schedule and thin spots.

With ``tile_size=None`` :func:`geotex.param.polycube.polycube` tries the sizes
of :func:`size_schedule`, from 1/12 of the largest extent down in steps of
``2**-1/4`` (about 16 %), and keeps the first (largest) whose voxel polycube
has the mesh's genus and whose fitted surface leaves no quad bare and covers
the base (:data:`MIN_COVERAGE` of its area within one tile; the share more
than :data:`BARE_DEPTH` tiles outside it, out of the texture's reach, is only
required at most :data:`MAX_BARE` when choosing among the grid shifts of one
size). The floor is 1/200
of the extent, or fewer tiles when the polycube would exceed :data:`MAX_QUADS`;
at most :data:`MAX_FITTED` sizes are fitted (:data:`EXTRA_FITTED` after the
first that covers the base), then the best attempt is kept.

:func:`thin_spot` finds where a shape is thinnest (the narrowest solid part or
gap), from the distance along the inward and outward normal of every face to
the opposite side (one ray per face and side, libigl's AABB): the error
messages name that point.
"""

from __future__ import annotations

import igl
import numpy as np

from geotex.mesh.geometry import face_normals

__all__ = ["AUTO_START", "AUTO_FLOOR", "AUTO_STEP", "MAX_QUADS", "MAX_FITTED", "EXTRA_FITTED",
           "MIN_COVERAGE", "SKIP_BELOW", "BARE_DEPTH", "MAX_BARE",
           "REACH_DEPTH",
           "size_schedule", "thin_spot", "face_thickness"]

#: The automatic search starts at ``extent / AUTO_START`` ...
AUTO_START = 12
#: ... and does not go below ``extent / AUTO_FLOOR``.
AUTO_FLOOR = 200
#: Ratio of two successive sizes tried.
AUTO_STEP = 2.0 ** -0.25
#: Largest polycube (tile quads) the search builds.
MAX_QUADS = 40000
#: Most sizes fitted by one search ...
MAX_FITTED = 6
#: ... and after the first that covers the base.
EXTRA_FITTED = 2
#: Fraction of the base area that must lie within one tile of the fitted surface.
MIN_COVERAGE = 0.99
#: A fit covering less than this skips the next size (the thin parts are far smaller).
SKIP_BELOW = 0.95
#: Depth (tiles) outside the fitted surface beyond which the base is bare: the
#: tallest catalog tile set rises a quarter tile, so no element reaches there.
BARE_DEPTH = 0.25
#: Largest share of the base area that may lie out of the texture's reach
#: (farther than :data:`BARE_DEPTH` outside the fitted surface) for a fit to cover it.
MAX_BARE = 0.002
#: Depth (tiles) outside the fitted surface beyond which the base pulls the fitted
#: surface outward after the fit (:func:`geotex.param.polycube_fit.reached_surface`):
#: below an eighth of a tile, about half the lowest catalog set's height.
REACH_DEPTH = 0.1


def size_schedule(start: float, floor: float) -> list[float]:
    """Sizes ``start * AUTO_STEP**i`` down to ``floor`` (inclusive, within 1e-9)."""
    out, i = [], 0
    while True:
        s = start * AUTO_STEP ** i
        if s < floor * (1 - 1e-9):
            return out
        out.append(float(s))
        i += 1


def face_thickness(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance from every face centroid to the opposite side, each ``(m,)`` float64.

    Returns
    -------
    solid : numpy.ndarray
        First hit of the ray along the inward normal: the thickness of the
        solid there.
    gap : numpy.ndarray
        First hit along the outward normal: the width of the gap in front of
        the face (``inf`` when the ray escapes).
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    tree = igl.AABB()
    tree.init(V, F)
    N = face_normals(V, F)
    C = V[F].mean(axis=1)
    eps = 1e-6 * float(np.ptp(V, axis=0).max())
    out = []
    for sign in (-1.0, 1.0):
        d = np.ascontiguousarray(sign * N)
        hit, t, _ = tree.intersect_ray_first(V, F, np.ascontiguousarray(C + eps * d), d)
        out.append(np.where(np.asarray(hit) >= 0, np.asarray(t, dtype=np.float64) + eps,
                            np.inf))
    return out[0], out[1]


def thin_spot(V: np.ndarray, F: np.ndarray) -> str:
    """Where the shape is thinnest and its narrowest gap, as a phrase.

    Faces below the 0.1 % quantile of either measure are ignored as noise
    (slivers at creases). E.g. ``"thinnest part 0.9 across near (1, 0, 0.2),
    narrowest gap 1.1 near (0.55, 0, 0)"``.
    """
    C = V[F].mean(axis=1)
    words = []
    for what, t in zip(("thinnest part", "narrowest gap"), face_thickness(V, F)):
        finite = np.isfinite(t)
        if not finite.any():
            continue
        t = np.where(finite & (t >= np.quantile(t[finite], 0.001)), t, np.inf)
        f = int(np.argmin(t))
        p = C[f]
        words.append(f"{what} {t[f]:.3g}{' across' if what[1] == 'h' else ''} near "
                     f"({p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g})")
    return ", ".join(words) or "no thin part found"
