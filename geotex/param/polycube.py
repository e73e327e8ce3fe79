"""PolyCube parameterization with chart planes on a grid of spacing ``tile_size``.

Pipeline (one module per step):

1. input check (closed, manifold, oriented outward, one component, no
   self-intersections) - :func:`geotex.check.check_mesh`;
2. face labels +-X/+-Y/+-Z from normals, smoothed and repaired
   (:mod:`~geotex.param.polycube_labels`);
3. chart layout and integer chart planes (:mod:`~geotex.param.polycube_layout`);
4. deformed positions ``P`` on the polycube surface
   (:mod:`~geotex.param.polycube_embed`).  Problems found on the way are
   repaired and the steps repeated: faces that would lie flat along a
   polycube edge and chart-interior edges joining two points of one polycube
   edge are split (:mod:`~geotex.param.polycube_refine`, which changes the
   base mesh but not its surface), invalid chart configurations and charts
   that cannot be separated are relabelled, folds are untangled locally or
   refined or relabelled.  The result must be free of folds and of
   self-intersections, or an error is raised;
5. grid quads with global edge ids (:mod:`~geotex.param.polycube_quads`);
6. distortion between the base and the polycube.

``P`` is stored in *tile units*: the polycube point is ``P * tile_size``; the
coordinate of every vertex along the axis of a chart it touches is an exact
integer.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geotex.check import check_mesh
from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import GeotexError, InputError
from geotex.mesh.arrays import as_mesh_arrays, as_vertices
from geotex.param.distortion import distortion_summary
from geotex.param.polycube_cuts import reflex_cuts
from geotex.param.polycube_embed import embed_polycube, folded_faces, untangle
from geotex.param.polycube_labels import (face_graph, fix_labels, flood_labels,
                                          initial_labels, merge_chart,
                                          smooth_labels)
from geotex.param.polycube_layout import (LayoutError, chart_layout, flat_border_faces,
                                          solve_planes)
from geotex.param.polycube_quads import (chart_axes, enumerate_quads, face_coords_2d,
                                         quad_edges)
from geotex.param.polycube_refine import (border_chords, flat_face_chords, split_edges,
                                          split_faces)
from geotex.progress import report

__all__ = ["PolyCube", "polycube", "POLYCUBE_STAGES", "validate_input"]

POLYCUBE_STAGES = ("check", "labels", "layout", "embed", "quads", "distortion")


@dataclass(frozen=True)
class PolyCube:
    """A polycube parameterization of a closed triangle mesh.

    Attributes
    ----------
    tile_size : float
    V : (n, 3) float64
        The base mesh the map is defined on: the input, plus vertices inserted
        where a face would have been flat along a polycube edge (each split
        keeps the surface geometry; the input vertices keep their indices).
    F : (m, 3) int64
        Faces of that mesh (split faces keep their index for one child).
    labels : (m,) int64
        Face labels 0..5 (``+X -X +Y -Y +Z -Z``).
    chart : (m,) int64
        Chart of every face.
    chart_label : (c,) int64
    planes : (c,) int64
        Chart plane along the chart's axis, in tiles.
    P : (n, 3) float64
        Deformed vertex positions in tile units (polycube point ``P * tile_size``).
    quad_chart : (q,) int64
    quad_ij : (q, 2) int64
        Lower cell corner in the chart's in-plane axes (see
        :mod:`geotex.param.polycube_quads` for the frame convention).
    quad_corners : (q, 4, 3) int64
        Quad corners ``c0..c3`` in tile units, counter-clockwise about the
        outward normal.
    quad_edge : (q, 4) int64
        Global edge id of quad edge ``k`` (from ``c_k`` to ``c_(k+1)%4``;
        0 south, 1 east, 2 north, 3 west).
    quad_edge_forward : (q, 4) bool
        Whether the quad runs along the edge toward increasing coordinate
        (the neighbouring quad always runs the other way).
    edge_axis : (E,) int64
        Axis class of every global edge (0 X, 1 Y, 2 Z).
    edge_quads, edge_sides : (E, 2) int64
        The two quads of every edge and the local edge index in each.
    distortion : dict
        ``area`` and ``angle`` statistics (``mean``, ``p95``) and counts.
    attempts : int
        Labelling rounds that were needed.
    """

    tile_size: float
    V: np.ndarray
    F: np.ndarray
    labels: np.ndarray
    chart: np.ndarray
    chart_label: np.ndarray
    planes: np.ndarray
    P: np.ndarray
    quad_chart: np.ndarray
    quad_ij: np.ndarray
    quad_corners: np.ndarray
    quad_edge: np.ndarray
    quad_edge_forward: np.ndarray
    edge_axis: np.ndarray
    edge_quads: np.ndarray
    edge_sides: np.ndarray
    distortion: dict = field(default_factory=dict)
    attempts: int = 1

    @property
    def positions(self) -> np.ndarray:
        """Polycube vertex positions in world units, ``(n, 3)``."""
        return self.P * self.tile_size

    @property
    def n_quads(self) -> int:
        return int(self.quad_chart.size)

    @property
    def quad_axes(self) -> np.ndarray:
        """In-plane axes ``(a1, a2)`` of every quad's frame (``e1``, ``e2``), ``(q, 2)``."""
        _, a1, a2 = chart_axes(self.chart_label[self.quad_chart])
        return np.stack([a1, a2], axis=1)


def validate_input(V, F, *, name: str = "mesh"):
    """Check that ``(V, F)`` can be parameterized; return the arrays.

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
    return V, F


def polycube(V, F, *, tile_size: float, smoothness: float = 1.0, min_chart_area=None,
             max_attempts: int = 30, max_shift: float = 1.0, check_input: bool = True,
             reference=None,
             progress=None) -> PolyCube:
    """Compute a polycube parameterization whose chart planes lie on a grid.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A closed, edge-manifold, outward-oriented, single-component mesh
        without self-intersections.
    tile_size : float
        Grid spacing: chart planes and polycube corners are multiples of it.
    smoothness : float, optional
        Weight of the boundary-length term of the label smoothing.
    min_chart_area : float, optional
        Smaller charts are merged into a neighbour (default ``0.3 tile_size**2``).
    max_attempts : int, optional
        Relabelling rounds allowed when the embedding folds.
    max_shift : float, optional
        Largest move of a chart plane from the chart's mean coordinate, in
        tiles (larger means the tile size is too large for that part).
    reference : array_like, (n, 3) float64, optional
        Positions (same connectivity) from which labels, chart planes and the
        shape of chart interiors are taken, e.g. a smoothed or pre-deformed
        copy of ``V``; default ``V``.
    check_input : bool, optional
        Run the input check (skip only when the caller already did).
    progress : callable, optional
        Called with each stage of ``POLYCUBE_STAGES``.

    Returns
    -------
    PolyCube

    Raises
    ------
    InputError
        On a bad mesh (see :func:`validate_input`) or a bad ``tile_size``.
    GeotexError
        When no valid polycube is found: the message says why (tile size too
        large for a part, a chart that keeps folding, ...).

    Examples
    --------
    >>> from geotex.mesh.primitives import box
    >>> pc = polycube(*box(divisions=2), tile_size=0.5)
    >>> pc.n_quads
    24
    """
    report(progress, "check")
    if check_input:
        V, F = validate_input(V, F)
    else:
        V, F = as_mesh_arrays(V, F, allow_empty=False)
    ts = _tile_size(tile_size, V)
    if min_chart_area is None:
        min_chart_area = 0.3 * ts * ts
    report(progress, "labels")
    Vd = V if reference is None else as_vertices(reference, name="reference")
    if Vd.shape != V.shape:
        raise InputError(f"reference must have the shape of V {V.shape}, got {Vd.shape}")
    W = np.hstack([V, Vd])  # split together: input and reference positions
    g = face_graph(Vd, F)
    labels = smooth_labels(g, initial_labels(g.normals), smoothness=smoothness)
    labels = fix_labels(Vd, F, g, labels, min_chart_area=min_chart_area)
    last_error = shift_error = None
    seen = set()
    refine_left = 4
    for attempt in range(1, max_attempts + 1):
        if "layout" not in seen:
            seen.add("layout")
            report(progress, "layout")
        V, Vd = W[:, :3], W[:, 3:]
        try:
            layout = chart_layout(Vd, F, g, labels)
            flat, new = flat_border_faces(F, labels, layout)
            if flat.size:
                chords, rest = flat_face_chords(F, labels, layout.vertex_chart, layout.chart,
                                                g.neighbors, flat)
                last_error = GeotexError(f"{flat.size} faces lie flat along a polycube edge")
                if rest.size:
                    W, F, labels = split_faces(W, F, labels, rest)
                if chords.size:
                    W, F, labels = split_edges(W, F, labels, chords)
                g = face_graph(W[:, 3:], F)
                continue
            chords = border_chords(g.edges, g.edge_faces, layout.chart, labels,
                                   layout.vertex_chart)
            if chords.size:
                last_error = GeotexError(f"{chords.shape[0]} edges cut across polycube edges")
                W, F, labels = split_edges(W, F, labels, chords)
                g = face_graph(W[:, 3:], F)
                continue
            planes = solve_planes(layout, ts, max_shift=max_shift)
            straight = _collinear_faces(F, labels, layout, planes)
            if straight.size:
                last_error = GeotexError(f"{straight.size} faces lie on one polycube line")
                W, F, labels = split_faces(W, F, labels, straight)
                g = face_graph(W[:, 3:], F)
                continue
        except LayoutError as exc:
            last_error = exc
            if str(exc).startswith("tile size too large"):
                shift_error = exc
            if exc.merge:
                labels = merge_chart(g, labels, exc.faces)
            else:
                labels = flood_labels(g, labels, exc.faces)
            labels = fix_labels(Vd, F, g, labels, min_chart_area=min_chart_area)
            continue
        if "embed" not in seen:
            seen.add("embed")
            report(progress, "embed")
        bad = None
        try:
            P, bad = _best_embedding(V, Vd, F, g, layout, planes, labels, ts)
        except GeotexError as exc:
            last_error, bad = exc, None
        else:
            if bad.size:
                last_error = GeotexError(f"{bad.size} faces fold in the polycube map")
            else:
                pairs = self_intersecting_pairs(P, F, max_pairs=64)
                bad = np.unique(pairs.ravel())
                if bad.size:
                    last_error = GeotexError(f"the polycube intersects itself "
                                             f"({pairs.shape[0]}+ face pairs)")
        if bad is not None and bad.size == 0:
            return _finish(V, F, ts, labels, layout, planes, P, attempt, progress)
        if bad is not None and 0 < bad.size <= max(64, F.shape[0] // 100) and refine_left > 0:
            # few folds: refine them (more room for the untangling) before relabelling
            refine_left -= 1
            ring = np.unique(np.concatenate([bad, g.neighbors[bad].ravel()]))
            W, F, labels = split_faces(W, F, labels, ring)
            g = face_graph(W[:, 3:], F)
            continue
        labels = fix_labels(Vd, F, g, labels, min_chart_area=min_chart_area,
                            extra_bad_faces=bad if bad is not None else None)
    if shift_error is not None:
        raise GeotexError(f"{shift_error} (no valid polycube found after {max_attempts} "
                          f"labelling rounds; last problem: {last_error})")
    raise GeotexError(f"no valid polycube found after {max_attempts} labelling rounds: "
                      f"{last_error}; try another tile size or a smoother, simpler mesh")


def _collinear_faces(F, labels, layout, planes) -> np.ndarray:
    """Faces whose corners all have one equal fixed coordinate off the face's axis."""
    vc = layout.vertex_chart[F]  # (m, 3, 3)
    fixed = (vc >= 0).all(axis=1)  # (m, 3 axes)
    val = np.where(vc >= 0, planes[np.maximum(vc, 0)], 0)
    same = fixed & (val[:, 0] == val[:, 1]) & (val[:, 0] == val[:, 2])
    same[np.arange(F.shape[0]), labels // 2] = False
    return np.flatnonzero(same.any(axis=1))


def _best_embedding(V, Vd, F, g, layout, planes, labels, ts):
    """Try the interior maps, then again with reflex-corner cuts; untangle the best."""
    best = None
    extra = None
    variants = ((False, None), (True, None), (False, Vd / ts), (True, Vd / ts))
    for stage in range(2):
        for uniform, ref in variants:
            try:
                P = embed_polycube(V, F, g.edges, layout.vertex_chart, planes, uniform=uniform,
                                   reference=ref, extra=extra)
            except GeotexError:
                if extra is None:
                    raise
                continue
            bad = folded_faces(P, F, labels)
            if bad.size == 0:
                return P, bad
            if best is None or bad.size < best[1].size:
                best = (P, bad, extra)
        if stage == 0:
            extra = reflex_cuts(best[0], Vd, F, labels, layout.chart, layout.vertex_chart,
                                g.neighbors, g.edges)
            if np.isnan(extra).all():
                break
    P, bad, extra = best
    if bad.size <= max(200, F.shape[0] // 20):
        fixed = layout.vertex_chart >= 0
        if extra is not None:
            fixed = fixed | ~np.isnan(extra)
        P = untangle(P, F, labels, fixed.sum(axis=1) == 1, sweeps=30, grow=1)
        bad = folded_faces(P, F, labels)
    return P, bad


def _tile_size(tile_size, V) -> float:
    try:
        ts = float(tile_size)
    except (TypeError, ValueError):
        raise InputError(f"tile_size must be a positive number, got {tile_size!r}") from None
    if not np.isfinite(ts) or ts <= 0:
        raise InputError(f"tile_size must be a positive number, got {tile_size!r}")
    extent = float((V.max(axis=0) - V.min(axis=0)).max())
    if ts > extent / 2:
        raise InputError(f"tile_size {ts:g} is too large for the mesh (largest extent "
                         f"{extent:.4g}): use at most {extent / 2:.4g}, so the polycube "
                         "is at least two tiles long")
    return ts


def _finish(V, F, ts, labels, layout, planes, P, attempt, progress) -> PolyCube:
    report(progress, "quads")
    qc, qij, corners = enumerate_quads(P, F, labels, layout.chart, layout.chart_label, planes)
    qe, qf, eax, eq, es = quad_edges(corners)
    report(progress, "distortion")
    T = face_coords_2d(P, F, labels) * ts
    m = F.shape[0]
    s = distortion_summary(V, F, T.reshape(-1, 2), uv_faces=np.arange(3 * m).reshape(m, 3))
    dist = {"area_mean": s.area_normalized.mean, "area_p95": s.area_normalized.p95,
            "angle_mean": s.angle.mean, "angle_p95": s.angle.p95,
            "area_ratio": s.area_ratio, "flipped": s.n_flipped}
    return PolyCube(tile_size=ts, V=V, F=F, labels=labels, chart=layout.chart,
                    chart_label=layout.chart_label, planes=planes, P=P, quad_chart=qc,
                    quad_ij=qij, quad_corners=corners, quad_edge=qe, quad_edge_forward=qf,
                    edge_axis=eax, edge_quads=eq, edge_sides=es, distortion=dist,
                    attempts=attempt)
