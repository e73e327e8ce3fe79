"""Shells: a base solid, its polycube map, offset directions and a safe height.

The shell over a base is ``{x + w d(x) : x on the fitted polycube surface,
0 <= w <= max_height}``: the polycube's sub-grid fitted onto the base
(:attr:`geotex.param.polycube.PolyCube.Y`) carries a unit offset direction
``d`` per vertex (smoothed area-weighted normals, interpolated linearly in
faces and renormalised). ``max_height`` is the largest height for which the
offset surface ``Y + h D`` neither flips a face nor intersects itself or the
fitted surface (bisection on the exact self-intersection test of
:mod:`geotex.check.intersections`).

The base mesh itself (the solid the texture elements are united with) is
kept beside the map, unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geotex.check.intersections import offset_surface_pairs, self_intersecting_pairs
from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_cross, vertex_normals
from geotex.mesh.topology import neighbour_mean
from geotex.param.polycube import POLYCUBE_STAGES, PolyCube, bare_fraction, polycube
from geotex.param.polycube_size import BARE_DEPTH, MAX_BARE
from geotex.progress import report

__all__ = ["Shell", "build_shell", "offset_directions", "max_offset_height", "SHELL_STAGES",
           "bare_area", "bare_warning"]

SHELL_STAGES = POLYCUBE_STAGES + ("offsets", "height")


@dataclass(frozen=True)
class Shell:
    """A base solid prepared to receive tiles.

    Attributes
    ----------
    name : str
    polycube : PolyCube
        The map from tile quads onto the base (its ``Y``, ``F`` are the fitted
        surface the tiles are laid on).
    D : (n, 3) float64
        Unit offset direction per fitted-surface vertex.
    max_height : float
        Largest safe texture height (world units).
    base_vertices : (p, 3) float64
    base_faces : (r, 3) int64
        The base solid, as given.
    source : str
        Where the base came from (file name), may be empty.
    recipe : dict
        How the shell was built (for rebuilding it).
    """

    name: str
    polycube: PolyCube
    D: np.ndarray
    max_height: float
    base_vertices: np.ndarray
    base_faces: np.ndarray
    source: str = ""
    recipe: dict = field(default_factory=dict)

    @property
    def tile_size(self) -> float:
        return self.polycube.tile_size

    @property
    def n_quads(self) -> int:
        return self.polycube.layout.n_quads

    @property
    def distortion(self) -> dict:
        return self.polycube.diagnostics.distortion

    @property
    def tile_search(self) -> dict:
        """How the tile size was chosen (see :attr:`PolyCubeDiagnostics.tile_search`)."""
        return self.polycube.diagnostics.tile_search


def bare_area(shell: Shell) -> float:
    """Share of the base area out of the texture's reach (0..1).

    The base farther than :data:`~geotex.param.polycube_size.BARE_DEPTH` tiles
    outside the fitted surface (:func:`~geotex.param.polycube.bare_fraction`):
    read from the polycube's coverage, or computed when a shell file made
    before it was recorded lacks it.
    """
    pc = shell.polycube
    value = pc.diagnostics.coverage.get("bare")
    if value is None:
        value = bare_fraction(shell.base_vertices, shell.base_faces, pc.Y, pc.F,
                              depth=BARE_DEPTH * pc.tile_size)
    return float(value)


def bare_warning(shell: Shell, remedy: str) -> str | None:
    """One line when more than :data:`~geotex.param.polycube_size.MAX_BARE` of the
    base is out of the texture's reach (:func:`bare_area`), else None.

    ``remedy`` ends the line (what the user can do, naming the flag).
    """
    share = bare_area(shell)
    if share <= MAX_BARE:
        return None
    return (f"warning: {100 * share:.1f}% of the base of {shell.name!r} gets no texture (thin "
            f"parts more than {BARE_DEPTH:g} tile outside the polycube surface, whose tiles "
            f"are buried in the base); {remedy}")


def offset_directions(V: np.ndarray, F: np.ndarray, *, smoothing: int = 3) -> np.ndarray:
    """Smoothed area-weighted vertex normals, unit, ``(n, 3)``.

    Each smoothing step replaces a normal by the mean of itself and the mean
    of its neighbours' normals, then renormalises.
    """
    N = vertex_normals(V, F)
    M = neighbour_mean(F, V.shape[0])
    for _ in range(smoothing):
        N = 0.5 * N + 0.5 * (M @ N)
        N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    return N


def _offset_ok(V, F, D, h, base_normals) -> bool:
    return _offset_defects(V, F, D, h, base_normals, first=True).size == 0


def _offset_defects(V, F, D, h, base_normals, *, first: bool = False) -> np.ndarray:
    """Faces of ``F`` whose offset by ``h`` flips or crosses the surface or another offset.

    Returns the sorted face indices; with ``first``, stops at the first defect
    found (then any non-empty answer only says "not ok").
    """
    Vo = V + h * D
    flipped = np.einsum("ij,ij->i", face_cross(Vo, F), base_normals) <= 0
    if first and flipped.any():
        return np.flatnonzero(flipped)[:1]
    n, m = V.shape[0], F.shape[0]
    pairs = self_intersecting_pairs(np.vstack([V, Vo]), np.vstack([F, F[:, ::-1] + n]),
                                    max_pairs=1 if first else None)
    return np.union1d(np.flatnonzero(flipped), pairs.ravel() % m)


def _bisected_height(V, F, D, base_normals, hi: float, steps: int, *, shrink: bool = False,
                     fails: tuple = ()) -> float:
    """Bisection on ``[0, hi]`` (``hi`` fails); with ``shrink``, each failed step keeps
    testing only the faces that failed there. ``fails``: heights known to fail on
    ``F`` (not tested again)."""
    lo = 0.0
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        bad = (np.zeros(1, dtype=np.int64) if mid in fails else
               _offset_defects(V, F, D, mid, base_normals, first=not shrink))
        if bad.size == 0:
            lo = mid
        else:
            hi = mid
            if shrink:
                F, base_normals = F[bad], base_normals[bad]
    return lo


def max_offset_height(V: np.ndarray, F: np.ndarray, D: np.ndarray, *, steps: int = 10,
                      upper: float | None = None) -> float:
    """Largest ``h`` (bisection) with ``V + h D`` free of flips and intersections.

    Parameters
    ----------
    V, F, D : numpy.ndarray
        Surface and unit offset directions.
    steps : int
        Bisection steps (``build_shell`` uses 6: within 1/32 tile of the limit).
    upper : float, optional
        Largest height of interest (default: a quarter of the largest extent);
        returned as is when it passes.

    Returns
    -------
    float
        A height that passed the test on the whole surface, within
        ``upper / 2**steps`` of the limit.

    Notes
    -----
    The bisection assumes that flips and crossings only spread as the height
    grows. Each of its steps therefore tests only the faces that failed at the
    last failing height (fewer and fewer), and the height found is tested once
    more on the whole surface; should that fail, the bisection is redone on
    the whole surface (without testing again the height that check failed
    at), so the answer never rests on the assumption.
    """
    base_normals = face_cross(V, F)
    hi = float(upper) if upper is not None else 0.25 * float(np.ptp(V, axis=0).max())
    bad = _offset_defects(V, F, D, hi, base_normals)
    if bad.size == 0:
        return hi
    lo = _bisected_height(V, F[bad], D, base_normals[bad], hi, steps, shrink=True)
    if lo == 0.0 or _offset_ok(V, F, D, lo, base_normals):
        return lo
    return _bisected_height(V, F, D, base_normals, hi, steps, fails=(lo,))


PINCH_PROBE = 0.125
"""Height, in tiles, that every textured quad's offset must reach (see :func:`build_shell`)."""


def _pinched_faces(Y, F, D, h, previous=None) -> tuple[np.ndarray, tuple]:
    """Faces of ``(Y, F)`` whose offset by ``h`` along ``D`` flips or crosses the surface.

    Also returns the state to pass back as ``previous`` (see
    :func:`~geotex.check.intersections.offset_surface_pairs`) when only some
    directions change.
    """
    Vo = Y + h * D
    flipped = np.einsum("ij,ij->i", face_cross(Vo, F), face_cross(Y, F)) <= 0
    m = F.shape[0]
    state = offset_surface_pairs(Y, F, D, h, previous=previous)
    pairs = state[1]
    pairs = pairs[(pairs < m).any(axis=1)]     # the offset crossing only itself: a crease
    return np.unique(np.concatenate([np.flatnonzero(flipped), pairs.ravel() % m])), state


def _unpinched(pc: PolyCube, D: np.ndarray, *, rounds: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Offset directions smoothed further where the offset cannot rise :data:`PINCH_PROBE` tiles.

    The safe height is one number for the whole shell, so a single face whose
    offset flips or crosses the surface right away (a fitted face spanning a
    crest thinner than itself, its corners' directions on both flanks) would
    cap the texture everywhere at almost nothing. Around such faces the
    directions are smoothed more (a wider neighbourhood each round); the
    quads of the faces still pinched after the best of ``rounds`` do not
    limit the safe height. They keep their tiles: an element that the map folds there
    is shrunk in place or left out by the mapping, one element rather than a
    bare quad.

    Returns
    -------
    D : numpy.ndarray, (n, 3) float64
        The directions.
    pinched : numpy.ndarray, (k,) int64
        Faces of ``pc.F`` still pinched.
    """
    used = np.flatnonzero(~pc.quad_folded[pc.layout.face_quad])
    F, h = pc.F[used], PINCH_PROBE * pc.tile_size
    n = pc.Y.shape[0]
    M = neighbour_mean(pc.F, n)
    ring = (M != 0).astype(np.float64)
    bad, state = _pinched_faces(pc.Y, F, D, h)
    best = (bad, D)
    for rnd in range(rounds):
        if bad.size == 0:
            break
        sel = np.zeros(n, dtype=bool)
        sel[F[bad].ravel()] = True
        for _ in range(2 + rnd):
            sel = (ring @ sel.astype(np.float64)) > 0
        D = D.copy()
        for _ in range(4 * pc.res):
            Ds = 0.5 * D[sel] + 0.5 * (M @ D)[sel]
            D[sel] = Ds / np.maximum(np.linalg.norm(Ds, axis=1, keepdims=True), 1e-300)
        bad, state = _pinched_faces(pc.Y, F, D, h, state)
        if bad.size < best[0].size:
            best = (bad, D)
    bad, D = best
    return D, used[bad]


def build_shell(V, F, *, tile_size: float | None = None, name: str = "shell", source: str = "",
                recipe: dict | None = None, progress=None, **polycube_options) -> Shell:
    """Build the shell of a closed base mesh.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    tile_size : float or None, optional
        Tile (quad) side length in the units of ``V``; None (the default)
        chooses the largest size that resolves the shape and covers it (see
        :func:`~geotex.param.polycube.polycube`; the attempts are in
        ``shell.polycube.diagnostics.tile_search``).
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
        The tile size cannot resolve the shape (see :func:`~geotex.param.polycube.polycube`).
    """
    if not isinstance(name, str) or not name:
        raise InputError("name must be a non-empty string")
    V, F = as_mesh_arrays(V, F, allow_empty=False)
    pc = polycube(V, F, tile_size=tile_size, progress=progress, **polycube_options)
    report(progress, "offsets")
    # Smoothing the directions over about a tile lets the shell rise higher in
    # concave creases; too much makes them lean, so a lighter smoothing is
    # tried as well when the first one does not reach half a tile.
    h, D, upper = -1.0, None, 2.0 * pc.tile_size
    textured = ~pc.quad_folded[pc.layout.face_quad]
    for steps in (8 * pc.res, 2 * pc.res):
        Dk, pinched = _unpinched(pc, offset_directions(pc.Y, pc.F, smoothing=steps))
        pinched_quad = np.zeros(pc.layout.n_quads, dtype=bool)
        pinched_quad[pc.layout.face_quad[pinched]] = True
        used = pc.F[textured & ~pinched_quad[pc.layout.face_quad]]
        if D is None:
            report(progress, "height")
        elif not _offset_ok(pc.Y, used, Dk, h + upper / 64, face_cross(pc.Y, used)):
            break          # the lighter smoothing cannot beat the first by a step: done
        # a texture taller than two tiles is never wanted: that bounds the search;
        # quads left bare, and quads still pinched, do not limit it
        hk = max_offset_height(pc.Y, used, Dk, upper=upper, steps=6)
        if hk > h:
            h, D = hk, Dk
        if h >= 0.5 * pc.tile_size:
            break
    return Shell(name=name, polycube=pc, D=D, max_height=float(h),
                 base_vertices=V, base_faces=F, source=source,
                 recipe=dict(recipe or {}))
