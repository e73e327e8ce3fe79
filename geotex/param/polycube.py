"""PolyCube parameterization of closed meshes, on a grid whose cell is the tile.

The polycube is the boundary of a voxel solid (PolyCube-Maps, Tarini et al.
2004): every boundary face of a voxel is one or more tile quads, so the
polycube is valid by construction, its charts lie on grid planes, and any
genus is handled as long as the voxels resolve the shape. Pipeline, one
module per step:

1. input check (closed, manifold, oriented outward, one component, no
   self-intersections) - :func:`validate_input`;
2. voxel solid at cell ``tiles_per_cell * tile_size`` by winding numbers,
   made manifold, largest component (:mod:`~geotex.param.voxels`); a few grid
   shifts and two repair strategies are tried and the first candidate whose
   boundary has the Euler characteristic of the mesh is used;
3. tile quads and their triangle sub-grid (:mod:`~geotex.param.polycube_surface`),
   their connectivity and global quad edges
   (:class:`~geotex.param.polycube_quads.QuadLayout`);
4. the sub-grid fitted onto the base (:mod:`~geotex.param.polycube_fit`): the
   fitted positions ``Y`` are the inverse map polycube -> base;
5. distortion of the map and how well the fitted surface covers the base.

With ``tile_size=None`` steps 2-5 run for a schedule of sizes, largest first,
until one resolves the genus, leaves no quad bare and covers the base
(:mod:`~geotex.param.polycube_size`); the attempts are recorded in
:attr:`PolyCubeDiagnostics.tile_search`.

Unlike a deformation of the input, the map is defined on the polycube's own
triangulation: the tile point ``(u, v)`` of quad ``q`` lies in sub-cell
``(floor(u res), floor(v res))`` of ``layout.quad_grid[q]`` and its base point is
interpolated from the fitted positions there (:meth:`PolyCube.locate`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geotex.check import check_mesh
from geotex.check.intersections import offset_surface_pairs, self_intersecting_pairs
from geotex.errors import GeotexError, InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_areas, vertex_normals
from geotex.mesh.topology import (edge_topology, faces_within_rings, neighbour_mean,
                                  vertex_components)
from geotex.param.distortion import distortion_summary
from geotex.param.polycube_fit import (SurfaceFit, SurfaceProjector, fitted_surface,
                                       folded_faces, reached_surface)
from geotex.param.polycube_quads import QuadLayout, chart_axes
from geotex.param.polycube_size import (AUTO_FLOOR, AUTO_START, AUTO_STEP, BARE_DEPTH,
                                        EXTRA_FITTED, MAX_FITTED, MAX_QUADS, MIN_COVERAGE,
                                        MAX_BARE, REACH_DEPTH, SKIP_BELOW,
                                        size_schedule, thin_spot)
from geotex.param.polycube_surface import boundary_quads, subdivided_quads
from geotex.param.voxels import (largest_component, manifold_solid, occupancy,
                                 voxel_grid)
from geotex.progress import report

__all__ = ["PolyCube", "PolyCubeDiagnostics", "polycube", "POLYCUBE_STAGES", "validate_input",
           "GRID_SHIFTS", "bare_fraction"]

POLYCUBE_STAGES = ("check", "voxels", "fit", "distortion")

#: Grid offsets (in cells) tried in turn when a grid does not resolve the topology.
GRID_SHIFTS = ((0.0, 0.0, 0.0), (0.5, 0.5, 0.5), (0.25, 0.25, 0.25), (0.5, 0.0, 0.25))


@dataclass(frozen=True)
class PolyCubeDiagnostics:
    """How a polycube was found and how good its map is (JSON-ready dicts).

    Attributes
    ----------
    distortion : dict
        Area and angle distortion (mean, p95), folds, area ratio.
    coverage : dict
        How close the base is to the fitted surface (in tiles).
    voxels : dict
        The voxel candidate that was used (cell, shift, repair strategy, ...).
    tile_search : dict
        How the tile size was found: ``automatic``, and every ``attempts``
        entry (``tile_size``, ``result``; ``quads``, ``bare``,
        ``within_tile`` and ``bare_area`` when fitted); automatic searches add ``start``,
        ``floor`` and ``chosen``.
    """

    distortion: dict = field(default_factory=dict)
    coverage: dict = field(default_factory=dict)
    voxels: dict = field(default_factory=dict)
    tile_search: dict = field(default_factory=dict)


@dataclass(frozen=True)
class PolyCube:
    """A polycube parameterization of a closed triangle mesh.

    Attributes
    ----------
    tile_size : float
        World length of a tile side (one polycube grid unit).
    res : int
        Sub-cells along a tile side in the triangle sub-grid.
    origin : (3,) float64
        World position of the polycube's tile coordinate ``(0, 0, 0)``.
    P : (n, 3) float64
        Sub-grid vertices on the polycube, in tile units.
    Y : (n, 3) float64
        The same vertices fitted onto the base mesh (world units): the map.
    F : (m, 3) int64
        Sub-grid triangles, ``2 res^2`` per quad, quad by quad.
    quad_folded : (q,) bool
        Quads whose fitted image folds over or crosses another part of the
        fitted surface (where the voxels bridge a gap narrower than a tile);
        they are left bare by mapping.
    layout : QuadLayout
        The quads' connectivity: labels, corners, sub-grid, global edges
        (:class:`~geotex.param.polycube_quads.QuadLayout`).
    diagnostics : PolyCubeDiagnostics
        Distortion, coverage, the voxel candidate and the tile-size search.
    """

    tile_size: float
    res: int
    origin: np.ndarray
    P: np.ndarray
    Y: np.ndarray
    F: np.ndarray
    quad_folded: np.ndarray
    layout: QuadLayout
    diagnostics: PolyCubeDiagnostics = field(default_factory=PolyCubeDiagnostics)

    @property
    def positions(self) -> np.ndarray:
        """Polycube vertex positions in world units, ``(n, 3)``."""
        return self.origin + self.P * self.tile_size

    def locate(self, quad_ids: np.ndarray, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sub-grid face and barycentric coordinates of tile points.

        Parameters
        ----------
        quad_ids : numpy.ndarray, (k,) int64
        uv : numpy.ndarray, (k, 2) float64
            Tile coordinates in ``[0, 1]`` (clamped).

        Returns
        -------
        face : numpy.ndarray, (k,) int64
            Faces of :attr:`F`.
        bary : numpy.ndarray, (k, 3) float64
        """
        r = self.res
        x = np.clip(uv, 0.0, 1.0) * r
        cell = np.minimum(np.floor(x).astype(np.int64), r - 1)
        s, t = (x - cell).T
        upper = t > s
        face = quad_ids * (2 * r * r) + cell[:, 0] * r + cell[:, 1] + upper * (r * r)
        bary = np.where(upper[:, None], np.stack([1.0 - t, s, t - s], axis=1),
                        np.stack([1.0 - s, s - t, t], axis=1))
        return face, bary


def validate_input(V, F, *, name: str = "mesh"):
    """Check that ``(V, F)`` can be parameterized; return the arrays and the report.

    Raises
    ------
    InputError
        Open, non-manifold, inconsistently or inward oriented, several
        components, degenerate faces or self-intersections.
    """
    V, F = as_mesh_arrays(V, F, allow_empty=False)
    if F.shape[0] < 4:
        raise InputError(f"{name}: needs a closed mesh with at least 4 faces")
    r = check_mesh(V, F, self_intersections=True, max_examples=1)
    problems = []
    if r.boundary_edges:
        problems.append(f"open ({r.boundary_edges} boundary edges)")
    if r.non_manifold_edges or r.non_manifold_vertices:
        problems.append(f"non-manifold ({r.non_manifold_edges} edges, "
                        f"{r.non_manifold_vertices} vertices)")
    if not r.orientation_consistent:
        problems.append("inconsistently oriented")
    elif r.outward is False:
        problems.append("oriented inside out")
    if r.components != 1:
        problems.append(f"{r.components} connected components (one is needed)")
    if r.degenerate_faces:
        problems.append(f"{r.degenerate_faces} degenerate faces")
    if r.self_intersecting_pairs:
        problems.append(f"{r.self_intersecting_pairs} self-intersecting face pairs")
    if problems:
        raise InputError(f"{name} cannot get a polycube: " + ", ".join(problems)
                         + "; run 'geotex repair' first (and split it into parts if it has "
                           "several components)")
    return V, F, r


def _tile_size(tile_size, V) -> float:
    try:
        ts = float(tile_size)
    except (TypeError, ValueError):
        raise InputError(f"tile size must be a positive number, got {tile_size!r}") from None
    if not np.isfinite(ts) or ts <= 0:
        raise InputError(f"tile size must be a positive number, got {tile_size!r}")
    extent = float((V.max(axis=0) - V.min(axis=0)).max())
    if ts > extent / 2:
        raise InputError(f"tile size {ts:g} is too large for the mesh (largest extent "
                         f"{extent:.4g}): use at most {extent / 2:.4g}, so the polycube "
                         "is at least two tiles long")
    if ts < extent / 400:
        raise InputError(f"tile size {ts:g} is too small for the mesh (largest extent "
                         f"{extent:.4g}): use at least {extent / 400:.4g} (at most 400 "
                         "tiles across)")
    return ts


def _surface_topology(F: np.ndarray, n: int) -> tuple[int, int]:
    """Euler characteristic and number of components of a closed surface."""
    chi = n - edge_topology(F, n).edges.shape[0] + F.shape[0]
    return int(chi), int(vertex_components(F, n)[0])


def _candidates(V, F, *, cell, k, res, chi, max_quads=None):
    """Voxel polycubes in trial order (grid shifts x repair strategies), lazily.

    The topology is read from the quads alone; the triangle sub-grid is built
    only for candidates with the mesh's topology (and at most ``max_quads``
    quads: larger ones are yielded with ``"too_large"`` set).
    """
    for shift in GRID_SHIFTS:
        origin, shape = voxel_grid(V, cell=cell, shift=shift)
        inside, winding = occupancy(V, F, cell=cell, origin=origin, shape=shape)
        solid0, _ = largest_component(inside)
        for strategy in ("flip", "fill"):
            try:
                solid, _ = manifold_solid(solid0, winding, strategy=strategy)
            except GeotexError:
                continue
            solid, _ = largest_component(solid)
            if not solid.any():
                continue
            corners, labels = boundary_quads(solid, tiles_per_cell=k)
            P1, F1, _ = subdivided_quads(corners, labels, res=1)
            topo = _surface_topology(F1, P1.shape[0])
            c = {"origin": origin, "corners": corners, "labels": labels,
                 "chi": topo[0], "parts": topo[1], "ok": topo == (chi, 1),
                 "too_large": max_quads is not None and labels.size > max_quads,
                 "info": {"cell": cell, "tiles_per_cell": k, "shift": list(shift),
                          "strategy": strategy, "cells": int(solid.sum()),
                          "changed": int(np.count_nonzero(solid != inside))}}
            if c["ok"] and not c["too_large"]:
                c["P"], c["F"], c["grid"] = subdivided_quads(corners, labels, res=res)
            yield c


def _genus_found(seen) -> str:
    return ", ".join(f"genus {(2 - x) // 2}" + (f" in {p} parts" if p > 1 else "")
                     for x, p in sorted(set(seen))) or "nothing"


def _attempt(V, F, *, lo, ts, chi, k, r, iterations, max_quads=None, progress=None):
    """Voxel candidates and fits at one tile size; the best candidate or why none.

    Returns a dict: ``ts``, ``Vt`` (the base in tile units), ``seen`` (topology of
    every candidate), ``best`` (``(candidate, fit, bare quads)`` or None),
    ``fitted`` and ``too_large``.
    """
    Vt = (V - lo) / ts
    out = {"ts": ts, "Vt": Vt, "seen": [], "best": None, "fitted": 0, "too_large": False}
    projector = samples = None
    done = []                 # (candidate, fit, bad, cov) of the candidates fitted so far
    for c in _candidates(Vt, F, cell=float(k), k=k, res=r, chi=chi, max_quads=max_quads):
        out["seen"].append((c["chi"], c["parts"]))
        if c["too_large"]:
            out["too_large"] = True
            break
        if not c["ok"]:
            continue
        if projector is None:
            report(progress, "fit")
            projector = SurfaceProjector(Vt, F)
        out["fitted"] += 1
        # two repair strategies often give the same voxel solid: the same polycube
        # fits the same way, so its fit is reused (it counts as a fitted candidate,
        # and its equal key never replaces the first)
        same = next((d for d in done if _same_polycube(d[0], c)), None)
        if same is not None:
            _, fit, bad, cov = same
        else:
            P = c["origin"] + c["P"]
            plain = fitted_surface(P, c["F"], projector, iterations=iterations)
            if samples is None:
                samples = _face_samples(Vt, F)
            # the plain fit's tree and closest points serve the reach step's first
            # test and, when the fit stays as it was, the coverage
            surface = SurfaceProjector(plain.Y, c["F"])
            closest = surface.closest(samples[0])
            fit, bad = _reached(plain, P, c["F"], projector, samples, c["labels"].size, r,
                                surface=surface, closest=closest)
            cov = (_coverage(samples, surface, closest) if fit is plain
                   else _coverage(samples, SurfaceProjector(fit.Y, c["F"])))
            done.append((c, fit, bad, cov))
        key = _key(cov, int(bad.sum()))
        if out["best"] is None or key < out["key"]:
            out["best"], out["key"], out["coverage"] = (c, fit, bad), key, cov
        if key[:3] == (False, 0, False) or out["fitted"] == 3:
            break
    return out


def _key(cov: dict, bare_quads: int) -> tuple:
    """Order of fits, best first: :data:`MIN_COVERAGE` of the base within a tile,
    then fewer bare quads, then at most :data:`MAX_BARE` of the base out of the
    texture's reach (:func:`bare_fraction`), then more of it within a tile.

    Ties keep the first fit (the first grid shift, the largest tile): where no
    fit brings the area out of reach under :data:`MAX_BARE` (a detail smaller
    than any tile tried), the choice is the one made without that rule.
    """
    return (cov["within_tile"] < MIN_COVERAGE, bare_quads, cov["bare"] > MAX_BARE,
            -cov["within_tile"])


def _same_polycube(a: dict, b: dict) -> bool:
    """Whether two voxel candidates are the same polycube (origin, quad corners, labels)."""
    return all(np.array_equal(a[key], b[key]) for key in ("origin", "corners", "labels"))


def _resolves(V, F, *, lo, ts, chi, k):
    """Whether some voxel candidate at tile size ``ts`` has the mesh's topology.

    None when the polycube would have more than :data:`MAX_QUADS` quads.
    """
    for c in _candidates((V - lo) / ts, F, cell=float(k), k=k, res=1, chi=chi,
                         max_quads=MAX_QUADS):
        if c["too_large"]:
            return None
        if c["ok"]:
            return True
    return False


def _first_resolving(V, F, *, lo, ts, chi, k, floor):
    """The first size of the schedule below ``ts`` that resolves the topology, or None."""
    for s in size_schedule(ts * AUTO_STEP, floor):
        ok = _resolves(V, F, lo=lo, ts=s, chi=chi, k=k)
        if ok is None:
            return None
        if ok:
            return s
    return None


def _record(a) -> dict:
    """One attempt of the tile-size search, for the record."""
    rec = {"tile_size": float(a["ts"])}
    if a["best"] is None:
        rec["result"] = ("too many quads" if a["too_large"]
                         else "voxel polycube has " + _genus_found(a["seen"]))
        return rec
    c, _, bad = a["best"]
    rec.update(quads=int(c["labels"].size), bare=int(bad.sum()),
               within_tile=float(a["coverage"]["within_tile"]),
               bare_area=float(a["coverage"]["bare"]))
    key = _key(a["coverage"], rec["bare"])
    rec["result"] = ("ok" if key[:3] == (False, 0, False) else
                     "out of reach" if key[:2] == (False, 0) else "not covered")
    return rec


def polycube(V, F, *, tile_size: float | None = None, tiles_per_cell: int = 1, res: int = 4,
             iterations: int = 40, check_input: bool = True, progress=None) -> PolyCube:
    """PolyCube parameterization of a closed mesh with tile-sized grid quads.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        Closed, manifold, outward oriented, one component, no self-intersections.
    tile_size : float or None, optional
        Side of a tile (one polycube quad) in the units of ``V``. None (the
        default) chooses it: the largest size of
        :func:`~geotex.param.polycube_size.size_schedule` (from 1/12 of the
        largest extent down to 1/200, steps of ``2**-1/4``) whose voxel
        polycube has the mesh's genus, leaves no quad bare and has 99 % of the
        base area within one tile of the fitted surface; when no size
        qualifies (at most 6 sizes are fitted, 2 after the first that covers
        the base), the fitted size that covers the base with the fewest bare
        quads. The area out of the texture's reach (:func:`bare_fraction`) is
        recorded (``coverage["bare"]``), not required. At any size, up to three
        voxel candidates (grid shifts) are fitted until one also keeps it at most
        :data:`~geotex.param.polycube_size.MAX_BARE`. The attempts are in
        :attr:`PolyCubeDiagnostics.tile_search`.
    tiles_per_cell : int, optional
        Tiles along the side of a voxel: larger gives larger, flatter charts
        but resolves less of the shape.
    res : int, optional
        Sub-grid cells per tile side (accuracy of the map).
    iterations : int, optional
        Most fitting rounds (fewer when the fit has converged).
    check_input : bool, optional
        Run the full input check (closed, manifold, no self-intersections).
    progress : callable, optional
        Called with each stage name of ``POLYCUBE_STAGES``.

    Returns
    -------
    PolyCube

    Raises
    ------
    InputError
        Bad mesh (with a hint to run ``geotex repair``) or tile size.
    GeotexError
        The voxels cannot resolve the shape's topology: at the given tile size
        (the message names the genus found, where the shape is thinnest and
        the largest smaller size that resolves it), or, when the size is
        automatic, at any size down to 1/200 of the extent.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(3)
    >>> pc = polycube(V, F, tile_size=0.5)
    >>> pc.layout.n_quads > 0, bool(pc.quad_folded.any())
    (True, False)
    """
    report(progress, "check")
    if check_input:
        V, F, rep = validate_input(V, F)
        chi = int(rep.euler_characteristic)
    else:
        V, F = as_mesh_arrays(V, F, allow_empty=False)
        chi = _surface_topology(F, V.shape[0])[0]
    auto = tile_size is None
    ts = None if auto else _tile_size(tile_size, V)
    k = int(tiles_per_cell)
    r = int(res)
    if k < 1 or k > 8:
        raise InputError(f"tiles_per_cell must be an integer in [1, 8], got {tiles_per_cell!r}")
    if r < 1 or r > 16:
        raise InputError(f"res must be an integer in [1, 16], got {res!r}")
    # work in tile units relative to the lowest corner: the result does not
    # depend on where the mesh sits or on its unit
    lo = V.min(axis=0)
    extent = float((V.max(axis=0) - lo).max())
    genus = (2 - chi) // 2
    report(progress, "voxels")
    opts = dict(lo=lo, chi=chi, k=k, r=r, iterations=iterations, progress=progress)
    if not auto:
        a = _attempt(V, F, ts=ts, **opts)
        search = {"automatic": False, "attempts": [_record(a)]}
        if a["best"] is None:
            works = _first_resolving(V, F, lo=lo, ts=ts, chi=chi, k=k, floor=extent / 400)
            hint = (f"tile size {works:.4g} resolves it" if works is not None
                    else f"no tile size down to 1/400 of the extent or {MAX_QUADS} quads "
                         "resolves it")
            raise GeotexError(
                f"tile size {ts:g} is too large to resolve the shape: the mesh has genus "
                f"{genus} but its voxel polycube has {_genus_found(a['seen'])} (thin parts or "
                f"narrow gaps are smaller than a tile; {thin_spot(V, F)}); {hint}")
    else:
        a, search = _search(V, F, extent=extent, genus=genus, opts=opts)
    c, fit, folded_quads = a["best"]
    ts = a["ts"]
    report(progress, "distortion")
    corners, labels, Fq = c["corners"], c["labels"], c["F"]
    layout = QuadLayout.of_quads(corners, labels, c["grid"])
    diagnostics = PolyCubeDiagnostics(
        distortion=_distortion(c["P"], fit.Y, Fq, labels, layout.face_quad, fit),
        coverage=a["coverage"],
        voxels=dict(c["info"], cell=k * ts, candidates=len(a["seen"]), fitted=a["fitted"]),
        tile_search=search)
    return PolyCube(tile_size=ts, res=r, origin=lo + c["origin"] * ts, P=c["P"],
                    Y=lo + fit.Y * ts, F=Fq, quad_folded=folded_quads, layout=layout,
                    diagnostics=diagnostics)


def _search(V, F, *, extent, genus, opts):
    """The automatic tile size: the first good attempt of the schedule, or the best.

    After a fit that leaves more than :data:`SKIP_BELOW` of the base uncovered
    the next size of the schedule is skipped. At most :data:`MAX_FITTED` sizes are fitted, and at most
    :data:`EXTRA_FITTED` more once one covers the base (only bare quads are
    left to remove then, which smaller tiles rarely do on very thin parts).
    The best attempt covers the base within a tile, then has the fewest bare
    quads, then the best coverage. The area out of the texture's reach
    (:func:`bare_fraction`) is recorded but does not make the search go on:
    requiring it at most :data:`MAX_BARE` halves Spot's tiles (6.67 -> 4.71 mm
    at 80 mm) and doubles its output (benchmarks/results/bare.md); within a
    size, the grid shifts are still tried for it (:func:`_key`).
    """
    start, floor = extent / AUTO_START, extent / AUTO_FLOOR
    attempts, best, best_key, fitted, covered, skip = [], None, None, 0, None, False
    for ts in size_schedule(start, floor):
        if skip:                    # the last fit left a part uncovered: larger steps
            skip = False
            continue
        a = _attempt(V, F, ts=ts, max_quads=MAX_QUADS, **opts)
        rec = _record(a)
        attempts.append(rec)
        if a["too_large"]:
            break
        if a["best"] is None:
            continue
        fitted += 1
        key = (rec["within_tile"] < MIN_COVERAGE, rec["bare"], -rec["within_tile"])
        if best is None or key < best_key:
            best, best_key = a, key
        if rec["within_tile"] >= MIN_COVERAGE and covered is None:
            covered = fitted
        skip = rec["within_tile"] < SKIP_BELOW
        if (key[:2] == (False, 0) or fitted >= MAX_FITTED
                or (covered is not None and fitted - covered >= EXTRA_FITTED)):
            break
    search = {"automatic": True, "start": start, "floor": floor, "attempts": attempts}
    if best is None:
        raise GeotexError(
            f"the shape is too thin for a polycube: the mesh has genus {genus} but no voxel "
            f"polycube down to tile size {attempts[-1]['tile_size']:.4g} "
            f"(1/{AUTO_FLOOR} of the largest extent or {MAX_QUADS} quads) has it "
            f"({thin_spot(V, F)}); thicken the shape there or widen the gap")
    search["chosen"] = float(best["ts"])
    return best, search


def _reached(fit, P, F, projector, samples, n_quads, res, *, tries: int = 3, surface=None,
             closest=None) -> tuple[SurfaceFit, np.ndarray]:
    """The fit moved out to the base's protrusions (:func:`reached_surface`) and its
    bare quads (:func:`_bad_quads`), never with a quad bare that the fit had textured.

    Where moving out makes quads bare (the two sides of a thin fin pulled onto its
    rim meet their own offset), their vertices and ``res`` rings around (wider at
    each of ``tries``) go back to the fit's positions; if quads are still newly
    bare then, the fit is kept as it was (the same object). ``surface`` and
    ``closest`` are passed to :func:`reached_surface`.
    """
    out = reached_surface(fit, P, F, projector, *samples, depth=REACH_DEPTH, surface=surface,
                          closest=closest)
    if out is fit:
        return fit, _bad_quads(fit, F, n_quads, res)[0]
    # one box for the tests of the fit and of every moved-out surface (which
    # moves vertices between the two): each test after the first searches
    # only around the vertices that moved since the last
    used = np.unique(F)
    both = np.concatenate([fit.Y[used], out.Y[used]])
    box = np.stack([both.min(axis=0) - BAD_CLEARANCE, both.max(axis=0) + BAD_CLEARANCE])
    plain, state = _bad_quads(fit, F, n_quads, res, box=box)
    n = fit.Y.shape[0]
    ring = (neighbour_mean(F, n) != 0).astype(np.float64)
    per_quad = 2 * res * res
    for t in range(tries + 1):
        bad, state = _bad_quads(out, F, n_quads, res, box=box, previous=state)
        new = np.flatnonzero(bad & ~plain)
        if new.size == 0:
            return out, bad
        if t == tries:
            break
        back = np.zeros(n, dtype=bool)
        back[F[(new[:, None] * per_quad + np.arange(per_quad)).ravel()].ravel()] = True
        for _ in range(res * (t + 1)):
            back = (ring @ back.astype(np.float64)) > 0
        Y, face = out.Y.copy(), out.base_face.copy()
        Y[back], face[back] = fit.Y[back], fit.base_face[back]
        out = SurfaceFit(Y=Y, base_face=face, folded=folded_faces(Y, F, projector, face),
                         repaired=fit.repaired,
                         reached=int(np.count_nonzero((Y != fit.Y).any(axis=1))))
    return fit, plain


BAD_CLEARANCE = 0.05
"""Offset, in tiles, that :func:`_bad_quads` tests the fitted surface against."""


def _bad_quads(fit, F, n_quads, res, *, box=None, previous=None) -> tuple[np.ndarray, tuple]:
    """Quads whose fitted image folds over or comes too close to another part of itself.

    The second happens where the voxels bridge a gap narrower than a tile: the
    two sides of the bridge land on (nearly) the same surface. It is found as
    the faces where the fitted surface crosses itself or its own offset by
    :data:`BAD_CLEARANCE` tiles along the vertex normals. Such quads are left bare.

    Also returns the state of the search
    (:func:`~geotex.check.intersections.offset_surface_pairs`, normalised by
    ``box``, searched again only around moved vertices after ``previous``),
    None when neither is given (the search normalised by the stacked
    surface's own box).
    """
    Y = fit.Y
    n, m = Y.shape[0], F.shape[0]
    normals = vertex_normals(Y, F)
    state = None
    if box is None and previous is None:
        lifted = Y + BAD_CLEARANCE * normals
        pairs = self_intersecting_pairs(np.vstack([Y, lifted]), np.vstack([F, F[:, ::-1] + n]))
    else:
        state = offset_surface_pairs(Y, F, normals, BAD_CLEARANCE, previous=previous, box=box)
        pairs = state[1]
    # the offset crossing only itself is a concave crease tighter than the
    # clearance (it limits the shell's height, not the map): not a bridge
    pairs = pairs[(pairs < m).any(axis=1)] % m
    # nor is a crossing within a couple of rings (a sliver face at a sharp corner
    # whose offset pokes through its neighbours): the two sides of a bridge are
    # at least a voxel, ``res`` rings, apart on the surface
    pairs = pairs[~faces_within_rings(F, n, pairs, max(1, res // 2))]
    faces = np.concatenate([np.flatnonzero(fit.folded), pairs.ravel()])
    bad = np.zeros(n_quads, dtype=bool)
    bad[faces // (2 * res * res)] = True
    return bad, state


def _distortion(P, Y, F, labels, face_quad, fit) -> dict:
    """Distortion of the map base -> polycube (each face in its quad's plane)."""
    _, a1, a2 = chart_axes(labels[face_quad])
    X = P[F]                                     # (m, 3, 3)
    rows = np.arange(F.shape[0])[:, None]
    uv = np.stack([X[rows, np.arange(3)[None], a1[:, None]],
                   X[rows, np.arange(3)[None], a2[:, None]]], axis=-1).reshape(-1, 2)
    s = distortion_summary(Y, F, uv, uv_faces=np.arange(3 * F.shape[0]).reshape(-1, 3))
    return {"area_mean": s.area_normalized.mean, "area_p95": s.area_normalized.p95,
            "angle_mean": s.angle.mean, "angle_p95": s.angle.p95,
            "area_ratio": s.area_ratio, "folded_faces": int(fit.folded.sum()),
            "folded_before_repair": int(fit.repaired), "collapsed": s.n_collapsed,
            "reached": int(fit.reached)}


def _coverage(samples, surface, closest=None) -> dict:
    """Distance from the base to the fitted surface, in tiles (area-weighted).

    Measured from every base face centroid to its closest point on the fitted
    surface (a :class:`SurfaceProjector`; ``samples``: :func:`_face_samples` of
    the base; ``closest``: the surface's closest points of them, when known):
    mean and max distance, the fractions of the base area within a quarter
    tile and within one tile, and ``bare`` (:func:`bare_fraction`, from the
    same closest-point queries).
    """
    S, a4 = samples
    C = (surface.closest(S) if closest is None else closest)[0]
    d4 = np.linalg.norm(C - S, axis=1)
    d = d4[::4]                                   # the centroids
    a = a4[::4] * 4.0
    return {"mean": float(np.average(d, weights=a)), "max": float(d.max()),
            "within_quarter_tile": float(a[d <= 0.25].sum() / a.sum()),
            "within_tile": float(a[d <= 1.0].sum() / a.sum()),
            "bare": _outside_share(S, a4, d4, surface, BARE_DEPTH)}


def _face_samples(V, F) -> tuple[np.ndarray, np.ndarray]:
    """Four points per face (centroid first, then ``(2/3, 1/6, 1/6)`` and its
    rotations), ``(4 m, 3)``, and the quarter face area each carries."""
    w = np.full((4, 3), 1.0 / 6.0)
    w[0] = 1.0 / 3.0
    w[[1, 2, 3], [0, 1, 2]] = 2.0 / 3.0
    S = np.einsum("pj,mjc->mpc", w, V[F]).reshape(-1, 3)
    return S, np.repeat(face_areas(V, F) / 4.0, 4)


def _outside_share(S, a, d, surface, depth) -> float:
    """Share of the weights ``a`` of points ``S`` farther than ``depth`` (``d``:
    their distances) outside the closed ``surface`` (a :class:`SurfaceProjector`;
    winding number < 1/2)."""
    far = d > depth
    far[far] = surface.winding_numbers(S[far]) < 0.5
    return float(a[far].sum() / a.sum())


def bare_fraction(V, F, Y, Fq, *, depth: float = BARE_DEPTH) -> float:
    """Share of the base area farther than ``depth`` outside the fitted surface.

    Tiles are laid on the fitted surface ``(Y, Fq)`` and rise at most their
    height (a quarter tile for the tallest catalog set) above it, so where the
    base sticks out of that surface by more than ``depth`` every element is
    buried in the base and the base is left bare (a thin protrusion the voxels
    did not resolve). Sampled at four points per base face (the centroid and
    the three points ``(2/3, 1/6, 1/6)``), each carrying a quarter of the
    face's area; outside means a winding number of the fitted surface below
    one half.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        The base.
    Y : numpy.ndarray, (k, 3) float64
    Fq : numpy.ndarray, (l, 3) int64
        The fitted surface (closed), in the same units as ``V``.
    depth : float, optional
        In the units of ``V`` (tiles when ``V`` is in tile units).

    Returns
    -------
    float
        In ``[0, 1]``.
    """
    S, a = _face_samples(V, F)
    surface = SurfaceProjector(Y, Fq)
    d = np.linalg.norm(surface.closest(S)[0] - S, axis=1)
    return _outside_share(S, a, d, surface, depth)
