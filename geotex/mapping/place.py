"""Tile geometry into shell space: gather, weld across quads, shell map.

A tile vertex ``(u, v, w)`` on quad ``q`` is located in the shell's fitted
polycube surface (face + barycentric coordinates), which gives a base point
``x`` and an interpolated unit offset direction ``d``; its shell position is
``x + w * scale * d``. Vertices on a tile side are welded *combinatorially*
before mapping: two tiles that meet on a global edge carry bit-identical side
vertices ``(t, w)`` (``t`` the coordinate along the edge, running the same way in
both quads), so the key ``(edge, t, w)`` merges them exactly and the shared
vertex is mapped once. Elements left open (next to a quad that received no
tile) are dropped.

By default every small element is then mapped as one shape
(:func:`geotex.mapping.shape.shaped_positions`): its centre follows the
map, its footprint a similarity of the tile's, so studs stay round where the
polycube's quads are rectangles or rhombi. ``shaped=False`` maps point by
point (:func:`shell_positions`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from geotex.check.intersections import self_intersecting_pairs_between
from geotex.mapping.seat import _own_crossings, smoothed_folds
from geotex.mapping.shape import LEAN_SLIDES, SPREAD, _unit, map_jacobian, shaped_positions
from geotex.mesh.geometry import group_boxes
from geotex.mesh.topology import compacted, concatenated, vertex_components
from geotex.param.polycube_fit import SurfaceProjector
from geotex.shells.locate import interpolated
from geotex.tiles.tileset import TileSet

__all__ = ["gathered_tiles", "side_keys", "MappedTiles", "mapped_tiles", "shell_positions",
           "reseated_elements", "depth_scale", "RESEAT_SLIDES"]

#: Slides (tile sides) along the surface tried by :func:`reseated_elements`
#: for a folded shaped element at full size, before it is shrunk.
RESEAT_SLIDES = (0.05, 0.1)


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(s, s + c)`` for every pair, vectorized."""
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    offsets = np.cumsum(counts) - counts
    return np.repeat(starts - offsets, counts) + np.arange(total)


def gathered_tiles(tiles: TileSet, tile_of_quad: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Copies of the chosen tiles, one per quad (``-1``: none), in tile coordinates.

    Returns
    -------
    uvw : numpy.ndarray, (N, 3) float64
    quad_of_vertex : numpy.ndarray, (N,) int64
    faces : numpy.ndarray, (M, 3) int64
    source : numpy.ndarray, (N,) int64
        Index of every copied vertex in ``tiles.vertices``.
    """
    tile_of_quad = np.asarray(tile_of_quad, dtype=np.int64)
    quads = np.flatnonzero(tile_of_quad >= 0)
    t = tile_of_quad[quads]
    nv = np.diff(tiles.vertex_offsets)[t]
    nf = np.diff(tiles.face_offsets)[t]
    source = _ranges(tiles.vertex_offsets[t], nv)
    fidx = _ranges(tiles.face_offsets[t], nf)
    faces = tiles.faces[fidx] + np.repeat(np.cumsum(nv) - nv, nf)[:, None]
    return tiles.vertices[source], np.repeat(quads, nv), faces, source


def side_keys(uvw: np.ndarray, quad_of_vertex: np.ndarray, quad_edge: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Weld keys of the vertices that lie on a tile side.

    Returns
    -------
    on_side : numpy.ndarray, (N,) bool
    keys : numpy.ndarray, (k, 2) int64
        ``(global edge, bits of (t, w))`` of the side vertices, in order: ``t``
        (the coordinate along the side) and ``w`` are float32 values in a tile
        set, so their two 32-bit patterns identify them exactly.
    """
    u, v, w = uvw.T
    side = np.full(len(uvw), -1, dtype=np.int64)
    side[u == 0.0] = 3
    side[u == 1.0] = 1
    side[v == 0.0] = 0
    side[v == 1.0] = 2
    on = side >= 0
    s = side[on]
    t = np.where((s == 0) | (s == 2), u[on], v[on]).astype(np.float32)
    bits = (t.view(np.uint32).astype(np.int64) << 32) | w[on].astype(np.float32).view(
        np.uint32).astype(np.int64)
    edge = quad_edge[quad_of_vertex[on], s]
    return on, np.stack([edge, bits], axis=1)


@dataclass(frozen=True)
class MappedTiles:
    """Tile geometry mapped into a shell.

    Attributes
    ----------
    vertices : numpy.ndarray, (N, 3) float64
    faces : numpy.ndarray, (M, 3) int64
        Closed elements only.
    welded : int
        Side vertices merged with their twin across a quad edge.
    dropped_faces : int
        Faces of elements left open (beside a quad without a tile).
    quads : numpy.ndarray, (N,) int64
        Quad every vertex was mapped through.
    tile_points : numpy.ndarray, (N, 3) float64
        Its ``(u, v, w)`` in that quad's tile frame.
    tile_faces : numpy.ndarray, (M,) int64
        Index in ``tiles.faces`` of the tile face every face copies.
    element : numpy.ndarray, (N,) int64
        Element (connected component) of every vertex, ``0 .. e - 1``.
    shaped : bool
        Whether the elements were mapped as shapes (see :func:`mapped_tiles`).
    shift : numpy.ndarray, (N, 3) float64
        World move of every vertex's element by the spreading of overlapping
        shaped elements (zero with the plain map).
    leaned : numpy.ndarray, (e,) bool
        Elements laid across their leaning offset direction.
    """

    vertices: np.ndarray
    faces: np.ndarray
    welded: int
    dropped_faces: int
    quads: np.ndarray
    tile_points: np.ndarray
    tile_faces: np.ndarray
    element: np.ndarray
    shaped: bool = True
    shift: np.ndarray | None = None
    leaned: np.ndarray | None = None


def mapped_tiles(shell, tiles: TileSet, tile_of_quad: np.ndarray, *, scale: float,
                 anchor: float | None = None, shaped: bool = True,
                 projector: SurfaceProjector | None = None, jacobian=None) -> MappedTiles:
    """Map the chosen tiles of every quad into the shell and weld them.

    Parameters
    ----------
    shell : Shell
    tiles : TileSet
    tile_of_quad : numpy.ndarray, (q,) int64
        Tile of every quad, ``-1`` for a quad left bare.
    scale : float
        World length of one unit of ``w``.
    anchor : float, optional
        World depth the elements reach below the surface: the part below
        ``w = 0`` is stretched so the deepest point (``-tiles.depth``) lands
        there (never shrunk). A deep anchor makes the elements' side walls,
        not their flat bottoms, cross the base, so the union meets steep
        intersections instead of nearly coincident faces.
    shaped : bool, optional
        Map every element narrower than
        :data:`~geotex.mapping.shape.MAX_EXTENT` tiles as one shape, similar
        to its tile shape (:func:`~geotex.mapping.shape.shaped_positions`);
        Shaped elements that would overlap are pushed apart along the surface
        (:func:`~geotex.mapping.shape.spread_centres`); elements laid across
        their leaning offset direction that cross an element standing upright
        (exact test of the leaned elements' faces) are mapped again upright (a
        leaned and an upright stud meeting at a graze left the union with
        crossing faces on the main job's Spot). False maps every point
        through the quad map (:func:`shell_positions`).
    projector : SurfaceProjector, optional
        Closest points on the shell's fitted surface, passed to
        :func:`~geotex.mapping.shape.shaped_positions` (built there when
        needed and not given).
    jacobian : numpy.ndarray, (m, 3, 2) float64, optional
        :func:`~geotex.mapping.shape.map_jacobian` of the shell's polycube,
        passed on likewise (computed once here when not given).

    Returns
    -------
    MappedTiles
    """
    pc = shell.polycube
    uvw, quad_of_vertex, faces, _ = gathered_tiles(tiles, tile_of_quad)
    t = np.asarray(tile_of_quad, dtype=np.int64)
    t = t[t >= 0]
    tile_faces = _ranges(tiles.face_offsets[t], np.diff(tiles.face_offsets)[t])
    # weld side vertices with their twins across quad edges
    on, keys = side_keys(uvw, quad_of_vertex, pc.layout.quad_edge)
    side_idx = np.flatnonzero(on)
    order = np.lexsort((keys[:, 1], keys[:, 0]))
    ks = keys[order]
    start = np.ones(order.size, dtype=bool)
    start[1:] = (ks[1:] != ks[:-1]).any(axis=1)
    group = np.cumsum(start) - 1
    first = order[start]                                  # representative of every key
    target = np.arange(len(uvw))
    target[side_idx[order]] = side_idx[first[group]]
    # an element with a side vertex that found no twin is open: drop it, with
    # every piece welded to it (a chain-mail ring cut at a tile corner spans up
    # to four tiles, so one open piece would leave the others open)
    sizes = np.bincount(group)
    lonely = side_idx[order[sizes[group] == 1]]
    faces = target[faces]
    keep_face = np.ones(len(faces), dtype=bool)
    if lonely.size:
        _, piece = vertex_components(faces, len(uvw))
        open_piece = np.zeros(int(piece.max()) + 1, dtype=bool)
        open_piece[piece[lonely]] = True
        keep_face = ~open_piece[piece[faces[:, 0]]]
        faces = faces[keep_face]
        tile_faces = tile_faces[keep_face]
    used = np.zeros(len(uvw), dtype=bool)
    used[faces.ravel()] = True
    new_index = np.cumsum(used) - 1
    kept = np.flatnonzero(used)
    faces = new_index[faces]
    _, element = vertex_components(faces, kept.size)
    below = depth_scale(tiles, scale, anchor)
    if shaped:
        if jacobian is None:                                # once for every call
            jacobian = map_jacobian(pc)
        if projector is None:
            projector = SurfaceProjector(pc.Y, pc.F)
        X, shift, leaned = shaped_positions(
            shell, quad_of_vertex[kept], uvw[kept], element, scale=scale, depth_scale=below,
            spread=SPREAD, return_shift=True, return_leaned=True, projector=projector,
            jacobian=jacobian)
        X, shift, leaned = _seated_leaned(
            shell, X, quad_of_vertex[kept], uvw[kept], element, faces, leaned,
            scale=scale, depth_scale=below, shift=shift, projector=projector,
            jacobian=jacobian)
    else:
        X = shell_positions(shell, quad_of_vertex[kept], uvw[kept], scale=scale,
                            depth_scale=below)
        shift = np.zeros_like(X)
        leaned = np.zeros(int(element.max()) + 1 if element.size else 0, dtype=bool)
    return MappedTiles(X, faces, int(on.sum() - start.sum()), int((~keep_face).sum()),
                       quad_of_vertex[kept], uvw[kept], tile_faces, element, bool(shaped),
                       shift, leaned)


def _seated_leaned(shell, X, quads, uvw, element, faces, leaned, *, scale, depth_scale, shift,
                   projector, jacobian):
    """Leaned elements that cross upright ones slid off them, else stood upright.

    A leaned element that crosses an upright one (exact test) is tried slid
    along the surface away from the upright ones it crosses by each of
    :data:`~geotex.mapping.shape.LEAN_SLIDES` (every try of every such
    element mapped in one call and tested in one exact test), and kept at
    the first try that crosses no upright element; one no try seats
    is mapped upright (on the main job's Spot, studs on the top of the head,
    where the offset directions lean 40-65 degrees from the surface: upright,
    their cross-section across their axis is squashed by the cosine, to half
    the median footprint). The upright elements are those not ``leaned`` on
    entry; tries are not tested against each other (leaned elements may
    meet).

    Returns
    -------
    X : numpy.ndarray, (N, 3) float64
    shift : numpy.ndarray, (N, 3) float64
        ``shift`` with the slides added.
    leaned : numpy.ndarray, (e,) bool
    """
    n = leaned.size
    crowded, away, lo, hi = _crowded_leaned(X, faces, element, leaned, away=True)
    trials = np.asarray(LEAN_SLIDES, dtype=np.float64)
    if not crowded.any() or trials.size == 0:
        if crowded.any():
            X, _, _ = _remapped(shell, X, quads, uvw, element, crowded, scale=scale,
                                depth_scale=depth_scale, shift=shift, lean=False,
                                projector=projector, jacobian=jacobian)
        return X, shift, leaned & ~crowded
    ids = np.flatnonzero(crowded)
    p, k = ids.size, trials.size
    vs = np.flatnonzero(crowded[element])
    local = np.searchsorted(ids, element[vs])
    # every try of every crowded element, as elements of their own
    copy_el = (local[None, :] + p * np.arange(k)[:, None]).ravel()
    slide = np.repeat(trials, p)[:, None] * float(shell.tile_size) * np.tile(away[ids], (k, 1))
    Xc, Sc, landed = shaped_positions(
        shell, np.tile(quads[vs], k), np.tile(uvw[vs], (k, 1)), copy_el, scale=scale,
        depth_scale=depth_scale, shift=np.tile(shift[vs], (k, 1)),
        lean=np.ones(p * k, dtype=bool), slide=slide, return_shift=True, return_leaned=True,
        projector=projector, jacobian=jacobian)
    # their faces, and those of the upright elements whose boxes overlap theirs
    label = element[faces[:, 0]]
    mine = np.flatnonzero(crowded[label])
    at = np.full(X.shape[0], -1, dtype=np.int64)
    at[vs] = np.arange(vs.size)
    Fc = (at[faces[mine]][None, :, :] + vs.size * np.arange(k)[:, None, None]).reshape(-1, 3)
    part_c = np.tile(local[at[faces[mine, 0]]], k) + p * np.repeat(np.arange(k), mine.size)
    clo, chi = group_boxes(Xc, copy_el, p * k)
    up = np.flatnonzero(~leaned)
    up = up[np.all((lo[up] <= chi.max(axis=0)) & (hi[up] >= clo.min(axis=0)), axis=1)]
    near = np.zeros(n, dtype=bool)
    for c0 in range(0, p * k, 256):                 # (tries x upright boxes, in slices)
        sl = slice(c0, c0 + 256)
        near[up[np.all((clo[sl, None, :] <= hi[None, up, :])
                       & (lo[None, up, :] <= chi[sl, None, :]), axis=2).any(axis=0)]] = True
    theirs = np.flatnonzero(near[label])
    V2, F2 = concatenated([(Xc, Fc), compacted(X, faces[theirs])])
    part = np.concatenate([part_c, p * k + label[theirs]])
    side = part < p * k
    pairs = self_intersecting_pairs_between(V2, F2, part, side=side)
    hit = np.zeros(p * k, dtype=bool)
    a, b = part[pairs[:, 0]], part[pairs[:, 1]]
    hit[np.where(side[pairs[:, 0]], a, b)] = True
    # the first try of each that crosses no upright element (one whose slid
    # shape landed off its lines was laid upright: not kept)
    ok = (landed & ~hit).reshape(k, p)
    first = np.argmax(ok, axis=0)
    seated = ok[first, np.arange(p)]
    X, shift = X.copy(), shift.copy()
    rows = first[local] * vs.size + np.arange(vs.size)
    take = seated[local]
    X[vs[take]], shift[vs[take]] = Xc[rows[take]], Sc[rows[take]]
    crowded[ids[seated]] = False
    if crowded.any():
        X, _, _ = _remapped(shell, X, quads, uvw, element, crowded, scale=scale,
                            depth_scale=depth_scale, shift=shift, lean=False,
                            projector=projector, jacobian=jacobian)
        leaned = leaned & ~crowded
    return X, shift, leaned


def _remapped(shell, X, quads, uvw, element, which, *, scale, depth_scale, shift, lean,
              projector=None, jacobian=None):
    """``X`` with the elements ``which`` (a mask) mapped again, leaned or upright.

    Also returns which elements (a mask over all) were laid leaned, and the
    shift of every point.
    """
    vs = np.flatnonzero(which[element])
    ids, local = np.unique(element[vs], return_inverse=True)
    n = ids.size
    X, S = X.copy(), shift.copy()
    X[vs], S[vs], leaned = shaped_positions(
        shell, quads[vs], uvw[vs], local, scale=scale, depth_scale=depth_scale, shift=shift[vs],
        lean=np.full(n, bool(lean)), return_shift=True, return_leaned=True,
        projector=projector, jacobian=jacobian)
    out = np.zeros(which.size, dtype=bool)
    out[ids[leaned]] = True
    return X, out, S


def _crowded_leaned(X, faces, element, leaned, *, away=False):
    """Leaned elements that cross an element standing as the map's offsets do.

    The exact test runs on the leaned elements and the elements whose boxes
    overlap theirs, one part per element, and examines only the pairs of a
    leaned and an upright element (the rows of the whole test that decide).
    With ``away``, also the unit direction (world, ``(n, 3)``) from the
    centres of the upright elements each one crosses to its own centre
    (their boxes' centres; zero for the others) and the elements' boxes
    ``lo, hi`` (``(n, 3)`` each; None when nothing leans).
    """
    n = leaned.size
    out = np.zeros(n, dtype=bool)
    far = np.zeros((n, 3))
    if not leaned.any():
        return (out, far, None, None) if away else out
    lo, hi = group_boxes(X, element, n)
    lean = np.flatnonzero(leaned)
    near = cKDTree(0.5 * (lo + hi)).query_ball_point(
        0.5 * (lo[lean] + hi[lean]), float(np.linalg.norm(hi - lo, axis=1).max()))
    i, j = np.repeat(lean, [len(c) for c in near]), np.concatenate(
        [np.asarray(c, dtype=np.int64) for c in near])
    overlap = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1) & (i != j)
    cand = np.union1d(lean, j[overlap])
    label = element[faces[:, 0]]
    sub = np.flatnonzero(np.isin(label, cand))
    pairs = sub[self_intersecting_pairs_between(X, faces[sub], label[sub],
                                                side=leaned[label[sub]])]
    a, b = label[pairs[:, 0]], label[pairs[:, 1]]
    mine, other = np.where(leaned[a], a, b), np.where(leaned[a], b, a)
    out[mine] = True
    if not away:
        return out
    ends = np.unique(np.stack([mine, other], axis=1), axis=0)
    centre = 0.5 * (lo + hi)
    v = _unit(centre[ends[:, 0]] - centre[ends[:, 1]])
    far = _unit(np.stack([np.bincount(ends[:, 0], weights=v[:, c], minlength=n)
                          for c in range(3)], axis=1).astype(np.float64))
    return out, far, lo, hi


def depth_scale(tiles: TileSet, scale: float, anchor) -> float:
    """World length of one unit of ``w`` below the surface (the anchor's stretch)."""
    if anchor is None or tiles.depth <= 0:
        return float(scale)
    return float(scale) * max(1.0, float(anchor) / (tiles.depth * float(scale)))


def shell_positions(shell, quads: np.ndarray, uvw: np.ndarray, *, scale: float,
                    depth_scale: float | None = None) -> np.ndarray:
    """Shell positions of tile points: ``x + w d`` at the located base point.

    Parameters
    ----------
    shell : Shell
    quads : numpy.ndarray, (k,) int64
    uvw : numpy.ndarray, (k, 3) float64
        Tile coordinates; ``w`` in tile units.
    scale : float
        World length of one unit of ``w`` above the surface.
    depth_scale : float, optional
        The same below the surface (default ``scale``).

    Returns
    -------
    numpy.ndarray, (k, 3) float64
    """
    pc = shell.polycube
    face, bary = pc.locate(quads, uvw[:, :2])
    YD = interpolated(np.hstack([pc.Y, shell.D]), pc.F, face, bary)
    d = YD[:, 3:]
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    below = float(scale if depth_scale is None else depth_scale)
    w = np.where(uvw[:, 2] < 0, uvw[:, 2] * below, uvw[:, 2] * float(scale))
    return YD[:, :3] + w[:, None] * d


def reseated_elements(shell, mapped: "MappedTiles", label: np.ndarray, elements, *,
                      scale: float, depth_scale: float, factors=None, slides=RESEAT_SLIDES,
                      projector: SurfaceProjector | None = None, jacobian=None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Shrink folded elements about their centre and map them again.

    An element the shell map folds onto itself (where the map bends it
    around a crease) is scaled about the centre of its footprint and in
    height by each of ``factors`` in turn, mapped again (as a shape when
    ``mapped.shaped``, see :func:`~geotex.mapping.shape.shaped_positions`,
    then carried along its axis onto the surface and raised along it:
    ``cast``, which seats 18 of Blub's 37 folded studs at their full size)
    and kept at the first size whose mapped faces do not cross each other
    (exact test). With ``mapped.shaped``, the elements no size seats are then
    smoothed over their folded stretch
    (:func:`~geotex.mapping.seat.smoothed_folds`, kept only where they cross
    nothing).

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
    label : numpy.ndarray, (M,) int64
        Element of every face of ``mapped.faces``.
    elements : array_like of int
        The folded elements.
    scale, depth_scale : float
        As in :func:`shell_positions`.
    factors : sequence of float, optional
        Shrink factors tried; default 1, 0.75, 0.55, 0.4, 0.3 with
        ``mapped.shaped`` (size 1 is cast), else without 1 (the plain map
        again).
    slides : sequence of float, optional
        With ``mapped.shaped``, after size 1 the element is tried at full
        size slid along the surface by each of these distances (tile sides)
        six ways (the world axes laid in its tangent plane), before it is
        shrunk (default :data:`RESEAT_SLIDES`).
    projector : SurfaceProjector, optional
        Closest points on the shell's fitted surface (the one
        :func:`mapped_tiles` used); built here, once for every size, if not
        given.
    jacobian : numpy.ndarray, (m, 3, 2) float64, optional
        :func:`~geotex.mapping.shape.map_jacobian` of the shell's polycube
        (computed here, once for every size, if not given).

    Returns
    -------
    X : numpy.ndarray, (N, 3) float64
        Mapped positions with the re-seated elements moved.
    still_folded : numpy.ndarray, (k,) int64
        Elements that could not be re-seated.
    """
    if factors is None:
        factors = ((1.0,) if mapped.shaped else ()) + (0.75, 0.55, 0.4, 0.3)
    X = mapped.vertices.copy()
    G = mapped.faces
    still = np.unique(np.asarray(elements, dtype=np.int64))
    if still.size == 0:
        return X, still
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(int(label.max()) + 2))
    if projector is None:                                   # one for every size
        projector = SurfaceProjector(shell.polycube.Y, shell.polycube.F)
    if jacobian is None and mapped.shaped:
        jacobian = map_jacobian(shell.polycube)
    trials = [(float(f), None) for f in factors]
    if mapped.shaped and slides and 1.0 in factors:
        # at full size slid along the surface (six ways, the world axes laid in
        # its tangent plane) before it is shrunk
        at = [float(f) for f in factors].index(1.0) + 1
        ways = np.vstack([np.eye(3), -np.eye(3)])
        trials[at:at] = [(1.0, float(t) * shell.tile_size * w) for t in slides for w in ways]
    for f, way in trials:
        if still.size == 0:
            break
        # every still folded element at once, numbered 0 .. len(still) - 1
        counts = starts[still + 1] - starts[still]
        rows = order[_ranges(starts[still], counts)]
        faces = G[rows]
        verts, local = np.unique(faces, return_inverse=True)
        local = local.reshape(-1, 3)
        vel = np.empty(verts.size, dtype=np.int64)
        vel[local.ravel()] = np.repeat(np.repeat(np.arange(still.size), counts), 3)
        Xe = shaped_positions(shell, mapped.quads[verts], mapped.tile_points[verts], vel,
                              scale=scale, depth_scale=depth_scale,
                              shrink=np.full(still.size, float(f)), similar=mapped.shaped,
                              shift=None if mapped.shift is None else mapped.shift[verts],
                              lean=None if mapped.leaned is None else mapped.leaned[still],
                              slide=None if way is None else np.tile(way, (still.size, 1)),
                              projector=projector, cast=mapped.shaped, jacobian=jacobian)
        fstart = np.cumsum(counts) - counts
        left = []
        for j, e in enumerate(still):
            fj = local[fstart[j]:fstart[j] + counts[j]]
            vj, lj = np.unique(fj, return_inverse=True)
            if _own_crossings(Xe[vj], lj.reshape(-1, 3)).size == 0:
                X[verts[vj]] = Xe[vj]
            else:
                left.append(e)
        still = np.asarray(left, dtype=np.int64)
    if mapped.shaped and still.size:
        # shaped elements (scales on Spot: 3 of 19 folded at a crumpled quad,
        # folded near their tips even at 0.3 of their size) are smoothed over
        # the folded stretch instead of left out; strands and rings are laid
        # back on a smoothed map first by the caller
        # (:func:`~geotex.mapping.seat.remapped_folds`)
        X, still = smoothed_folds(X, G, label, still)
    return X, still
