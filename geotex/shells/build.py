"""Shells: a base mesh, its polycube, offset directions and a safe height.

The shell over a base mesh is ``{x + w h d(x) : x on the base, 0 <= w <= 1}``
with ``d`` the offset direction field (smoothed area-weighted vertex normals,
unit, interpolated linearly inside faces and renormalised) and ``h`` at most
``max_height``: the largest height for which the offset surface ``V + h D``
neither flips a face nor intersects itself or the base (bisection on the
exact self-intersection test of :mod:`geotex.check.intersections`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import InputError
from geotex.mesh.geometry import face_cross
from geotex.param.polycube import POLYCUBE_STAGES, PolyCube, polycube
from geotex.param.polycube_quads import QuadLocator
from geotex.progress import report

__all__ = ["Shell", "build_shell", "offset_directions", "max_offset_height", "SHELL_STAGES"]

SHELL_STAGES = POLYCUBE_STAGES + ("offsets", "height")


@dataclass
class Shell:
    """A base mesh prepared to receive tiles.

    Attributes
    ----------
    name : str
    polycube : PolyCube
        Its ``V``, ``F`` are the base mesh of the shell.
    D : (n, 3) float64
        Unit offset direction per base vertex.
    max_height : float
        Largest safe texture height (world units).
    source : str
        Where the base came from (file name), may be empty.
    recipe : dict
        How the shell was built (for rebuilding it).
    locator : QuadLocator
        Point location index (rebuilt from the data, never stored).
    """

    name: str
    polycube: PolyCube
    D: np.ndarray
    max_height: float
    source: str = ""
    recipe: dict = field(default_factory=dict)
    locator: QuadLocator | None = None

    def __post_init__(self):
        if self.locator is None:
            pc = self.polycube
            self.locator = QuadLocator.build(pc.P, pc.F, pc.labels, pc.chart, pc.quad_chart,
                                             pc.quad_ij)

    @property
    def V(self) -> np.ndarray:
        return self.polycube.V

    @property
    def F(self) -> np.ndarray:
        return self.polycube.F

    @property
    def tile_size(self) -> float:
        return self.polycube.tile_size

    @property
    def n_quads(self) -> int:
        return self.polycube.n_quads

    @property
    def distortion(self) -> dict:
        return self.polycube.distortion


def offset_directions(V: np.ndarray, F: np.ndarray, *, smoothing: int = 3) -> np.ndarray:
    """Smoothed area-weighted vertex normals, unit, ``(n, 3)``.

    Each smoothing step replaces a normal by the mean of itself and the mean
    of its neighbours' normals, then renormalises.
    """
    n = V.shape[0]
    C = face_cross(V, F)  # area-weighted (twice the area) face normals
    N = np.zeros((n, 3))
    for k in range(3):
        np.add.at(N, F[:, k], C)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])
    A = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n)).tocsr()
    A = ((A + A.T) > 0).astype(np.float64)
    deg = np.asarray(A.sum(axis=1)).ravel()
    for _ in range(smoothing):
        N = 0.5 * N + 0.5 * (A @ N) / deg[:, None]
        N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    return N


def _offset_ok(V, F, D, h, base_normals) -> bool:
    Vo = V + h * D
    C = face_cross(Vo, F)
    if np.any(np.einsum("ij,ij->i", C, base_normals) <= 0):
        return False
    n = V.shape[0]
    Vc = np.vstack([V, Vo])
    Fc = np.vstack([F, F[:, ::-1] + n])
    return self_intersecting_pairs(Vc, Fc, max_pairs=1).shape[0] == 0


def max_offset_height(V: np.ndarray, F: np.ndarray, D: np.ndarray, *, steps: int = 12
                      ) -> float:
    """Largest ``h`` (bisection) with ``V + h D`` free of flips and intersections.

    The upper bound is a quarter of the largest extent of the mesh (returned
    as is when it passes); otherwise the interval ``[0, bound]`` is bisected
    ``steps`` times and the largest height that passed is returned, so the
    result is safe (it passed the test) and within ``bound / 2**steps`` of the
    limit.
    """
    base_normals = face_cross(V, F)
    hi = 0.25 * float((V.max(axis=0) - V.min(axis=0)).max())
    if _offset_ok(V, F, D, hi, base_normals):
        return hi
    lo = 0.0
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if _offset_ok(V, F, D, mid, base_normals):
            lo = mid
        else:
            hi = mid
    return lo


def build_shell(V, F, *, tile_size: float, name: str = "shell", source: str = "",
                recipe: dict | None = None, progress=None, **polycube_options) -> Shell:
    """Build the shell of a closed base mesh.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    tile_size : float
        Tile (quad) side length in the units of ``V``.
    name, source : str, optional
        Recorded in the shell file.
    recipe : dict, optional
        Recorded in the shell file (how to rebuild it).
    progress : callable, optional
        Called with each stage of ``SHELL_STAGES``.
    **polycube_options
        Passed to :func:`geotex.param.polycube.polycube`.

    Returns
    -------
    Shell

    Raises
    ------
    InputError
        Bad mesh or tile size.
    GeotexError
        No valid polycube (see :func:`~geotex.param.polycube.polycube`).
    """
    if not isinstance(name, str) or not name:
        raise InputError("name must be a non-empty string")
    pc = polycube(V, F, tile_size=tile_size, progress=progress, **polycube_options)
    report(progress, "offsets")
    D = offset_directions(pc.V, pc.F)
    report(progress, "height")
    h = max_offset_height(pc.V, pc.F, D)
    return Shell(name=name, polycube=pc, D=D, max_height=float(h), source=source,
                 recipe=dict(recipe or {}))
