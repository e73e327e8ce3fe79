"""Elements that keep their shape on objects: a per-element similarity shell map.

The polycube map from tile coordinates onto the base is far from conformal
where the base is oblique to the voxel grid: a staircase of voxel faces has
more quads across the steps than along them, so its fitted quads are
rectangles (about ``1 : 0.7`` on a 45-degree slope), and near polycube
corners of valence 3, 5 or 6 the quads are rhombi. Mapped point by point, a
round stud becomes an ellipse whose size and direction follow the quads (the
"star" where charts meet).

:func:`shaped_positions` maps every small element (a connected component of
the welded tile geometry) as a unit instead. Its points are expressed in
the frame of its *home* quad (the quad holding most of them; points in a
quad across one of its sides are unfolded across that side). With the map's
Jacobian averaged over the element in that frame, ``J = U S V^T`` (tile units
to world), the element's tile shape is placed by the similarity
``y = c + s U V^T (uv - uv_mean)`` (``c`` the mean of its plain-mapped
base points: the least-squares placement), laid back on the fitted surface
(closest point, on faces facing the way the offset does) and raised along
the offset directions there. Where those directions lean more than
:data:`MIN_LEAN` degrees from the surface (they are smoothed over several
tiles; up to 60 degrees on Spot's head) the shape is laid instead in the
plane normal to its mean offset direction, carried along it onto the fitted
surface (through the map's tangent plane, then to where its lines meet the
surface), and raised along that one axis, so that its cross-section
across the way it rises keeps its shape and size (laid in the surface's
plane it stood sheared, squashed by the cosine); ``cast`` does the same for
upright shapes where the surface curves away from the tangent plane (to
re-seat folded elements); ``lean`` keeps chosen
elements in the tangent plane (:func:`~geotex.mapping.place.mapped_tiles`
slides leaned elements that cross an upright neighbour off it along the
surface, ``slide``, and stands those it cannot upright again). A mean offset
direction leaning more than :data:`MAX_AXIS_LEAN` from the map's normal is
turned towards it first (on a coarse shell the smoothed offsets can lie
nearly along the surface). ``s`` is ``sqrt(s1 s2)`` (the map's own area
scale) blended with the shell's mean tile side by ``evening`` (1, the
default: every element gets the same size; 0: sizes follow the quads' areas,
as with the plain map). Where quads are squashed the elements keep their
shape and size and so would press into each other; :func:`spread_centres`
pushes such elements apart along the surface (``spread`` rounds) before
they are laid on it. Where quads are stretched they lie farther apart.

This departs from the paper (which maps tile geometry point by point through
the polycube's inverse projection): tile sides still meet exactly (an element
cut by a tile side is welded before it is mapped, and it moves as one piece),
but an element no longer fills exactly the part of its quad that it fills in
the tile. Elements wider than ``max_extent`` tiles (weave strands, long scales)
and elements reaching past a side of a quad next to their home quad (around
a polycube corner) keep the plain map.

:func:`element_footprints` measures what this is for: the area and the
elongation of every element's footprint (its projection onto its tangent
plane).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled
from geotex.mesh.geometry import clamped_barycentric, face_normals
from geotex.param.polycube_fit import SurfaceProjector
from geotex.param.polycube_quads import chart_axes
from geotex.shells.locate import interpolated

__all__ = ["map_jacobian", "element_directions", "shaped_positions", "spread_centres", "ElementFootprints",
           "element_footprints", "MAX_EXTENT", "EVENING", "SPREAD", "GAP", "TILE_SLACK",
           "LEAN_MISS", "MIN_LEAN", "LEAN_SLIDES", "MAX_AXIS_LEAN"]

#: Elements wider than this (tile sides, in ``u`` or ``v``) keep the plain
#: point-by-point map.
MAX_EXTENT = 0.75

#: Default blend between the map's local area scale (0) and the shell's mean scale (1).
EVENING = 1.0

#: Rounds of :func:`spread_centres` run by :func:`~geotex.mapping.place.mapped_tiles`.
SPREAD = 60

#: Clearance kept between spread elements: centres at least ``GAP * (r_i + r_j)`` apart.
GAP = 1.05

#: A shape laid normal to its leaning offset direction (see
#: :func:`shaped_positions`) whose points land farther than this (in its own
#: size) from the map's tangent plane is laid in that plane instead.
LEAN_MISS = 0.1

#: Shapes are laid normal to their offset direction only where it leans more
#: than this (degrees) from the map's tangent plane normal (cross-section
#: squashed by more than 6 %); elsewhere the tangent plane is kept, since
#: rising along one axis there made the anchors below the surface of
#: neighbouring studs meet (285 -> 1354 elements meeting on Spot at 0 degrees;
#: with leaned studs that cross an upright one stood upright again by
#: :func:`~geotex.mapping.place.mapped_tiles`, 20 degrees gave the lowest
#: footprint spread: Spot 1.48 x planar against 1.51 at 30, Blub 1.53 / 1.52 / 1.54
#: at 20 / 30 / 10; with the shapes carried along their axis (:data:`CAST_ROUNDS`)
#: Spot 1.32 and Blub 1.48 at 20, Blub 1.49 at 25 and 1.41 at 15, where 778 of
#: its studs lean and 1,297 meet another).
MIN_LEAN = 20.0

#: Slides (tile sides) tried, in order, for a leaned element that crosses an
#: upright neighbour, along the surface away from it, before it is stood
#: upright (:func:`~geotex.mapping.place.mapped_tiles`). On the main job's
#: Spot 41 of the 48 leaned studs that cross an upright one seat slid (printed
#: footprint CV 1.48 x the planar tiling; 0.05, 0.1, 0.15 the same, 0.1
#: alone 1.53). Laying them with their cross-section narrowed along the lean
#: instead (the width kept by 0.67 or 0.33 of the way from the cosine to 1)
#: seated 1-2 more: 1.48 as well.
LEAN_SLIDES = (0.05, 0.15)

#: Largest lean (degrees) of the axis a leaned shape rises along, from the
#: map's tangent plane normal: steeper mean offset directions are turned
#: towards that normal. On the 80 mm Spot of the main job (338 tiles, the
#: offsets smoothed over several of them) they lean up to 85 degrees on the
#: top of the head, where studs raised along them lay nearly flat on the
#: surface (upright: footprint 0.02-0.1 of the median) or their shapes,
#: carried along them, landed on triangles they graze and were laid upright
#: (:data:`LEAN_MISS`). 50: printed footprint CV 1.48 x the planar tiling
#: there, 1.66 x at 65, 1.55 x at 40 (more studs tilted off their offsets).
MAX_AXIS_LEAN = 50.0

#: Rounds of carrying a leaned shape's points along its axis onto the fitted
#: surface (:func:`_cast_feet`; 0: closest points of the tangent plane's
#: points, as before: on Blub's fins 54 studs then landed off the plane and
#: were laid upright, squashed by the cosine, and leaned ones were squashed
#: where the surface curves: footprint elongation p95 1.13 against 1.005 cast,
#: on a torus with offsets leaning 40 degrees).
CAST_ROUNDS = 3

#: With ``cast``, points of upright shapes whose closest points lie farther
#: than this (in the shape's size) from their line along the axis are carried
#: along it.
CAST_TOL = 0.02

#: Pairs closer than this fraction of their tile distance are pushed, to at most
#: ``2 - TILE_SLACK`` times it (a map without distortion moves nothing).
TILE_SLACK = 0.98


def _unit(X: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(X, axis=-1, keepdims=True)
    return np.divide(X, n, out=np.zeros_like(X), where=n > 0)


def map_jacobian(pc) -> np.ndarray:
    """Jacobian of the map tile -> fitted surface, per sub-grid face.

    Parameters
    ----------
    pc : PolyCube

    Returns
    -------
    numpy.ndarray, (m, 3, 2) float64
        ``J[f]`` maps the tile coordinates ``(u, v)`` of face ``f``'s quad to
        world units. Zero on faces whose polycube triangle is degenerate.
    """
    F = pc.F
    _, a1, a2 = chart_axes(pc.layout.quad_label[pc.layout.face_quad])
    rows = np.arange(F.shape[0])
    P = pc.P[F]                                              # (m, 3, 3) tile units
    uv = np.stack([P[rows[:, None], np.arange(3)[None], a1[:, None]],
                   P[rows[:, None], np.arange(3)[None], a2[:, None]]], axis=-1)   # (m, 3, 2)
    B = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)            # (m, 2, 2)
    E = np.stack([pc.Y[F[:, 1]] - pc.Y[F[:, 0]], pc.Y[F[:, 2]] - pc.Y[F[:, 0]]], axis=2)
    det = B[:, 0, 0] * B[:, 1, 1] - B[:, 0, 1] * B[:, 1, 0]
    ok = np.abs(det) > 0
    inv = np.zeros_like(B)
    inv[ok, 0, 0], inv[ok, 1, 1] = B[ok, 1, 1] / det[ok], B[ok, 0, 0] / det[ok]
    inv[ok, 0, 1], inv[ok, 1, 0] = -B[ok, 0, 1] / det[ok], -B[ok, 1, 0] / det[ok]
    return E @ inv


def _tangent_frames(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents per unit normal, ``(k, 3)`` each, right-handed with it."""
    helper = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = _unit(np.cross(n, helper))
    return e1, np.cross(n, e1)


def _group_mean(values: np.ndarray, group: np.ndarray, n: int) -> np.ndarray:
    """Mean of ``values`` (k, ...) per group ``0 .. n - 1``."""
    flat = values.reshape(values.shape[0], -1)
    count = np.maximum(np.bincount(group, minlength=n), 1).astype(np.float64)
    out = np.stack([np.bincount(group, weights=flat[:, j], minlength=n)
                    for j in range(flat.shape[1])], axis=1) / count[:, None]
    return out.reshape((n,) + values.shape[1:])


def shaped_positions(shell, quads, uvw, element, *, scale: float,
                     depth_scale: float | None = None, evening: float = EVENING,
                     max_extent: float = MAX_EXTENT, shrink=None, similar: bool = True,
                     spread: int = 0, shift=None, return_shift: bool = False,
                     lean=None, return_leaned: bool = False, projector=None,
                     cast: bool = False, jacobian=None, slide=None):
    """Shell positions of tile points, every small element mapped as one similar shape.

    Parameters
    ----------
    shell : Shell
    quads : array_like, (k,) int64
        Quad every point is mapped through.
    uvw : array_like, (k, 3) float64
        Tile coordinates; ``w`` in tile units.
    element : array_like, (k,) int64
        Element (``0 .. e - 1``) of every point; the points of one element
        move together.
    scale : float
        World length of one unit of ``w`` above the surface.
    depth_scale : float, optional
        The same below the surface (default ``scale``).
    evening : float, optional
        In ``[0, 1]``: 0 keeps the map's local area scale, 1 gives every
        element the shell's mean scale (see the module docstring).
    max_extent : float, optional
        Elements whose footprint is wider than this many tile sides (in
        ``u`` or ``v``) keep the plain map
        (:func:`geotex.mapping.place.shell_positions`).
    shrink : array_like, (e,) float64, optional
        Factor per element applied to its footprint (about its centre) and
        its height (1: none); used to re-seat elements that the map folds.
    similar : bool, optional
        False: no similarity; the footprint is only shrunk by ``shrink``
        (with no shrink, the plain map).
    spread : int, optional
        Rounds of :func:`spread_centres`: similar elements that would overlap
        (their footprint circles closer than :data:`GAP`) are pushed apart
        along the surface.
    shift : array_like, (k, 3) float64, optional
        World translation of every point's element (one per element), added
        before the points are laid back on the surface (the shifts found by
        an earlier call with ``return_shift``).
    return_shift : bool, optional
        Also return the shift of every point's element.
    lean : array_like, (e,) bool, optional
        Elements that may be laid across their leaning offset direction (see
        the module docstring; default: every element). False keeps an element
        in the map's tangent plane, raised along the offsets point by point.
    return_leaned : bool, optional
        Also return which elements were laid across their offset direction.
    slide : array_like, (e, 3) float64, optional
        World move of every element along the map's tangent plane (its part
        along the plane's normal is dropped), added to ``shift`` (returned in
        it); used to slide a leaned element off an upright neighbour it
        crosses (:func:`~geotex.mapping.place.mapped_tiles`) and a folded
        one off the fold (:func:`~geotex.mapping.place.reseated_elements`).
    projector : SurfaceProjector, optional
        Closest points on the fitted surface ``(pc.Y, pc.F)``
        (:class:`geotex.param.polycube_fit.SurfaceProjector`), for points
        whose walk gets lost; built here when needed and not given (pass one
        to calls on the same shell to build it once).
    cast : bool, optional
        Also carry the upright similar shapes' points along the element's
        mean offset direction onto the fitted surface, where their closest
        points leave those lines by more than :data:`CAST_TOL` of the
        element's size, and raise them along that one direction (as leaned
        shapes are); an element whose points land farther than
        :data:`LEAN_MISS` from their lines keeps its closest points. Used to
        re-seat folded elements (:func:`~geotex.mapping.place.reseated_elements`).
    jacobian : numpy.ndarray, (m, 3, 2) float64, optional
        :func:`map_jacobian` of the shell's polycube, computed here when not
        given (pass one to calls on the same shell to compute it once).

    Returns
    -------
    X : numpy.ndarray, (k, 3) float64
    shift : numpy.ndarray, (k, 3) float64
        Only with ``return_shift``.
    leaned : numpy.ndarray, (e,) bool
        Only with ``return_leaned``.

    Raises
    ------
    InputError
        Mismatched array lengths, ``evening`` outside ``[0, 1]``, a
        non-positive ``max_extent``, a ``slide`` not of one row per
        element, or a ``jacobian`` not of the polycube's faces.
    """
    pc = shell.polycube
    if jacobian is not None and np.shape(jacobian) != (pc.F.shape[0], 3, 2):
        raise InputError(f"jacobian must have shape ({pc.F.shape[0]}, 3, 2) (map_jacobian of "
                         f"the shell's polycube), got {np.shape(jacobian)}")
    quads = np.asarray(quads, dtype=np.int64)
    uvw = np.asarray(uvw, dtype=np.float64)
    element = np.asarray(element, dtype=np.int64)
    k = quads.size
    if uvw.shape != (k, 3) or element.shape != (k,):
        raise InputError(f"quads, uvw and element must describe the same {k} points "
                         f"(got uvw {uvw.shape}, element {element.shape})")
    if not 0.0 <= float(evening) <= 1.0:
        raise InputError(f"evening must lie in [0, 1], got {evening!r}")
    if not float(max_extent) > 0:
        raise InputError(f"max_extent must be positive, got {max_extent!r}")
    if k == 0:
        return _returned(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=bool),
                         return_shift, return_leaned)
    n_el = int(element.max()) + 1
    if element.min() < 0:
        raise InputError("element labels must be non-negative")
    f = np.ones(n_el) if shrink is None else np.asarray(shrink, dtype=np.float64)
    if f.shape != (n_el,):
        raise InputError(f"shrink must have one factor per element ({n_el}), got {f.shape}")
    may_lean = np.ones(n_el, dtype=bool) if lean is None else np.asarray(lean, dtype=bool)
    if may_lean.shape != (n_el,):
        raise InputError(f"lean must have one flag per element ({n_el}), got {may_lean.shape}")
    lean = np.zeros(n_el, dtype=bool)
    face, bary = pc.locate(quads, uvw[:, :2])
    YD = interpolated(np.hstack([pc.Y, shell.D]), pc.F, face, bary)
    y, d = YD[:, :3], _unit(YD[:, 3:])
    # the shell's mean tile side (world): the size every element gets with evening = 1
    cross = np.cross(pc.Y[pc.F[:, 1]] - pc.Y[pc.F[:, 0]], pc.Y[pc.F[:, 2]] - pc.Y[pc.F[:, 0]])
    mean_side = float(np.sqrt(0.5 * np.linalg.norm(cross, axis=1).sum() / pc.layout.n_quads))
    J = (map_jacobian(pc) if jacobian is None else np.asarray(jacobian))[face]   # (k, 3, 2)
    home, uvh, unfolded = _home_frame(pc.layout, quads, uvw[:, :2], element, n_el)
    # the map's Jacobian in the home quad's frame, over the element's points there
    at_home = quads == home[element]
    cnt = np.maximum(np.bincount(element[at_home], minlength=n_el), 1)
    Jm = np.stack([np.bincount(element[at_home], weights=J[at_home, i, j], minlength=n_el)
                   for i in range(3) for j in range(2)], axis=1).reshape(n_el, 3, 2)
    Jm /= cnt[:, None, None]
    Uj, sig, Vt = np.linalg.svd(Jm, full_matrices=False)
    R = Uj @ Vt                                                      # (e, 3, 2), rotation part
    uv_mean = _group_mean(uvh, element, n_el)
    y_mean = _group_mean(y, element, n_el)
    span = np.zeros(n_el)
    np.maximum.at(span, element, np.abs(uvh - uv_mean[element]).max(axis=1))
    ok = ((sig[:, 1] > 1e-9 * mean_side) & (2.0 * span <= float(max_extent)) & unfolded
          & bool(similar))
    scl = np.sqrt(sig[:, 0] * sig[:, 1]) ** (1.0 - float(evening)) * mean_side ** float(evening)
    moved = (ok | (f != 1.0))[element]
    w = uvw[:, 2] * f[element]
    offset = np.zeros((n_el, 3))
    if shift is not None:
        sh = np.asarray(shift, dtype=np.float64)
        if sh.shape != (k, 3):
            raise InputError(f"shift must have shape ({k}, 3), got {sh.shape}")
        offset[element] = sh
    if slide is not None:
        sl = np.asarray(slide, dtype=np.float64)
        if sl.shape != (n_el, 3):
            raise InputError(f"slide must have shape ({n_el}, 3), got {sl.shape}")
        tn = _unit(np.cross(R[:, :, 0], R[:, :, 1]))
        offset += sl - np.einsum("ij,ij->i", sl, tn)[:, None] * tn
    offset[~ok] = 0.0
    if spread and ok.any():
        # footprint radius of every element, world
        r2 = np.zeros(n_el)
        np.maximum.at(r2, element, ((uvh - uv_mean[element]) ** 2).sum(axis=1))
        radius = f * scl * np.sqrt(r2)
        normal = _unit(np.cross(R[:, :, 0], R[:, :, 1]))
        # world offset -> its length in the tile, scaled as the element is
        ideal = ((f * scl)[:, None, None] / np.maximum(sig, 1e-300)[:, :, None]
                 * np.transpose(Uj, (0, 2, 1)))
        sel = np.flatnonzero(ok)
        offset[sel] += spread_centres(y_mean[sel] + offset[sel], radius[sel], normal[sel],
                                      rounds=int(spread), ideal=ideal[sel])
    if moved.any():
        idx = np.flatnonzero(moved)
        el = element[idx]
        sim = ok[el]
        i1, e_s = idx[sim], el[sim]
        flat = np.zeros((idx.size, 3))
        # similar shapes: the least-squares placement of the element's tile shape,
        # scaled and turned as the map is around it
        flat[sim] = (f[e_s] * scl[e_s])[:, None] * np.einsum("ijk,ik->ij", R[e_s],
                                                             uvh[i1] - uv_mean[e_s])
        centre = y_mean[el] + offset[el]
        # the others (only shrunk): about their centre, in world
        flat[~sim] = f[el[~sim]][:, None] * (y[idx[~sim]] - y_mean[el[~sim]])
        # Where the offset directions lean from the fitted surface (up to 60
        # degrees on Spot's head, where they are smoothed over several tiles) a
        # shape laid in the surface's own plane stands sheared along them, its
        # cross-section across its axis squashed by the cosine. There the shape
        # is laid in the plane normal to its mean offset direction and carried
        # along that direction into the map's plane, and it rises along that one
        # axis (followed point by point, the directions, turning by up to 15
        # degrees across a stud where the base curves, flared its top)
        axis = _unit(_group_mean(d, element, n_el))
        if MAX_AXIS_LEAN < 90.0:
            # offsets lying nearly along the surface (smoothed over several tiles
            # on a coarse shell: up to 85 degrees on the top of the 80 mm Spot's
            # head) turned towards the map's normal, to at most MAX_AXIS_LEAN
            tn = _unit(np.cross(R[:, :, 0], R[:, :, 1]))
            ca = np.einsum("ij,ij->i", tn, axis)
            cmax = np.cos(np.radians(MAX_AXIS_LEAN))
            steep = ca < cmax
            if steep.any():
                side = _unit(axis[steep] - ca[steep, None] * tn[steep])
                axis[steep] = cmax * tn[steep] + np.sqrt(1.0 - cmax * cmax) * side
        Rl, lift = _leaned_frames(R, axis, min_lean=MIN_LEAN)
        lean[e_s] = True
        lean &= lift[:, 1].any(axis=1) & may_lean
        j1 = np.flatnonzero(lean[el])
        flat_l = (f[el[j1]] * scl[el[j1]])[:, None] * np.einsum(
            "ijk,ik->ij", Rl[el[j1]], uvh[idx[j1]] - uv_mean[el[j1]])
        flat_l -= np.einsum("ij,ij->i", flat_l, lift[el[j1], 0])[:, None] * lift[el[j1], 1]
        target = centre + flat
        target[j1] += flat_l - flat[j1]
        fface, fb, projector = _feet(pc, quads[idx], uvw[idx, :2], target, d[idx], projector)
        # the leaned shape's points are carried along its axis onto the
        # surface (from the tangent plane, closest points squashed it where
        # the surface curves: Blub's fins); one whose points land far from
        # their lines (a crease or a crumpled patch of the fitted surface
        # turning away from the axis) is laid as before
        if CAST_ROUNDS and j1.size:
            fface[j1], fb[j1], miss, projector = _cast_feet(
                pc, quads[idx[j1]], uvw[idx[j1], :2], target[j1], axis[el[j1]],
                fface[j1], fb[j1], projector, rounds=CAST_ROUNDS)
        else:
            miss = np.linalg.norm(interpolated(pc.Y, pc.F, fface[j1], fb[j1]) - target[j1],
                                  axis=1)
        far = np.zeros(n_el)
        np.maximum.at(far, el[j1], miss / np.maximum(f[el[j1]] * scl[el[j1]], 1e-300))
        lean &= far <= LEAN_MISS
        back = j1[~lean[el[j1]]]
        if back.size:
            fface[back], fb[back], _ = _feet(pc, quads[idx[back]], uvw[idx[back], :2],
                                             centre[back] + flat[back], d[idx[back]],
                                             projector)
        # with ``cast`` (re-seating a folded element) the upright shapes too are
        # carried along their axis where closest points leave its lines, and
        # rise along it: in a valley or over a fin's edge closest points pile
        # up and offsets that cross fold the element
        cast_el = np.zeros(n_el, dtype=bool)
        if cast and CAST_ROUNDS:
            u = np.flatnonzero(sim & ~lean[el])
            size = f[el[u]] * scl[el[u]]
            tgt = centre[u] + flat[u]
            ax = axis[el[u]]
            c = _off_line(interpolated(pc.Y, pc.F, fface[u], fb[u]) - tgt, ax) > CAST_TOL * size
            if c.any():
                uc = u[c]
                cf, cb, miss, projector = _cast_feet(
                    pc, quads[idx[uc]], uvw[idx[uc], :2], tgt[c], ax[c], fface[uc], fb[uc],
                    projector, rounds=CAST_ROUNDS)
                bad = np.zeros(n_el, dtype=bool)
                bad[el[uc][miss > LEAN_MISS * size[c]]] = True
                good = ~bad[el[uc]]
                fface[uc[good]], fb[uc[good]] = cf[good], cb[good]
                cast_el[el[uc[good]]] = True
        y[idx] = interpolated(pc.Y, pc.F, fface, fb)
        d[idx] = _unit(interpolated(shell.D, pc.F, fface, fb))
        up = (lean | cast_el)[el]
        d[idx[up]] = axis[el[up]]
    below = float(scale if depth_scale is None else depth_scale)
    height = np.where(w < 0, w * below, w * float(scale))
    X = y + height[:, None] * d
    return _returned(X, offset[element], lean, return_shift, return_leaned)


def _returned(X, shift, leaned, return_shift, return_leaned):
    out = (X,) + ((shift,) if return_shift else ()) + ((leaned,) if return_leaned else ())
    return out if len(out) > 1 else X


def _leaned_frames(R: np.ndarray, direction: np.ndarray, *, min_lean: float = 0.0,
                   max_lean: float = 70.0) -> tuple[np.ndarray, np.ndarray]:
    """Frames of the similarity turned normal to each element's offset direction.

    Parameters
    ----------
    R : numpy.ndarray, (e, 3, 2) float64
        Orthonormal frames of the map's tangent planes (the rotation part of
        its Jacobian).
    direction : numpy.ndarray, (e, 3) float64
        Mean offset direction of every element (need not be unit).

    Returns
    -------
    frames : numpy.ndarray, (e, 3, 2) float64
        ``R`` projected into the plane normal to the direction and made
        orthonormal again (the nearest rotation: the element keeps its turn).
        Where the direction leans more than ``max_lean`` degrees from the
        tangent plane's normal, or is zero, ``R`` itself.
    lift : numpy.ndarray, (e, 2, 3) float64
        ``(n / (n . d), d)`` per element, ``n`` the tangent plane's unit normal
        and ``d`` the unit direction: a point ``p`` of the turned plane goes to
        ``p - (p . lift[0]) lift[1]``, along ``d`` into the tangent plane
        (zero where the frame was kept).
    """
    n = _unit(np.cross(R[:, :, 0], R[:, :, 1]))
    d = _unit(np.asarray(direction, dtype=np.float64))
    cos = np.einsum("ij,ij->i", n, d)
    ok = (cos >= np.cos(np.radians(float(max_lean)))) & (cos < np.cos(np.radians(float(min_lean))))
    A = R - d[:, :, None] * np.einsum("ij,ijk->ik", d, R)[:, None, :]
    U, _, Vt = np.linalg.svd(A, full_matrices=False)
    frames = np.where(ok[:, None, None], U @ Vt, R)
    lift = np.zeros((R.shape[0], 2, 3))
    lift[ok, 0] = n[ok] / cos[ok, None]
    lift[ok, 1] = d[ok]
    return frames, lift


def spread_centres(centre, radius, normal, *, rounds: int = SPREAD, gap: float = GAP,
                   ideal=None) -> np.ndarray:
    """Tangential moves that push overlapping discs apart.

    Elements keep one size while the polycube's quads vary in area, so where
    the quads are squashed their centres lie closer than in the tile. Each
    round, every pair of discs (centre, radius, in the plane normal to
    ``normal``) closer than ``gap * (r_i + r_j)`` is pushed apart by half the
    shortfall, shared equally, along the line between the centres projected
    into the tangent plane. With ``ideal``, only pairs squeezed below
    :data:`TILE_SLACK` of their distance in the tile (scaled as the elements
    are) are pushed, and to at most ``2 - TILE_SLACK`` times that distance:
    elements that touch or overlap in the tile itself stay as they are, and an
    undistorted map moves nothing.

    Parameters
    ----------
    centre : numpy.ndarray, (e, 3) float64
    radius : numpy.ndarray, (e,) float64
    normal : numpy.ndarray, (e, 3) float64
        Unit normals.
    rounds : int
    gap : float
    ideal : numpy.ndarray, (e, 2, 3) float64, optional
        Per element, the linear map taking a world offset from its centre to
        that offset's length in the tile times the element's scale; the
        distance of a pair in the tile is the mean of both maps applied to
        the pair's starting offset.

    Returns
    -------
    numpy.ndarray, (e, 3) float64
        The move of every centre.
    """
    start = np.asarray(centre, dtype=np.float64)
    c = start.copy()
    radius = np.asarray(radius, dtype=np.float64)
    if c.shape[0] < 2:
        return np.zeros_like(c)
    reach = 2.0 * gap * float(radius.max())
    normal = np.asarray(normal, dtype=np.float64)
    # from JIT_MIN_SIZE coordinates moved over all rounds, each round's pushes are
    # summed by a compiled loop over the pairs (the same operations in the same
    # order). np.einsum sums three products in an order that follows the memory
    # layout of its operands (x0 y0 + x2 y2 first where the summed axis is the
    # innermost, left to right where it is not: the layout of the ideal maps
    # shaped_positions makes), so the loop takes only the layouts it knows
    ideal_a = None if ideal is None else np.asarray(ideal)
    across = ideal_a is not None and ideal_a.dtype == np.float64 and ideal_a.ndim == 3 and (
        np.transpose(ideal_a, (0, 2, 1)).flags.c_contiguous)
    fast = (3 * c.shape[0] * int(rounds) >= JIT_MIN_SIZE and normal.flags.c_contiguous
            and (ideal_a is None or across or (ideal_a.dtype == np.float64
                                                and ideal_a.flags.c_contiguous)))
    if fast:
        nrm_c = normal
        rad_c = np.ascontiguousarray(radius)
        ideal_c = np.zeros((1, 2, 3)) if ideal is None else ideal_a
    for _ in range(int(rounds)):
        pairs = cKDTree(c).query_pairs(reach, output_type="ndarray")
        if pairs.size == 0:
            break
        if fast:
            if not _spread_round(c, start, rad_c, nrm_c, ideal_c, ideal is not None, across,
                                 float(gap), TILE_SLACK, 2.0 - TILE_SLACK,
                                 np.ascontiguousarray(pairs, dtype=np.int64)):
                break
            continue
        i, j = pairs[:, 0], pairs[:, 1]
        v = c[j] - c[i]
        nrm = _unit(normal[i] + normal[j])
        v -= np.einsum("ij,ij->i", v, nrm)[:, None] * nrm
        dist = np.linalg.norm(v, axis=1)
        want = gap * (radius[i] + radius[j])
        hit = dist > 0
        if ideal is not None:
            d0 = start[j] - start[i]
            tile = 0.5 * (np.linalg.norm(np.einsum("kab,kb->ka", ideal[i], d0), axis=1)
                          + np.linalg.norm(np.einsum("kab,kb->ka", ideal[j], d0), axis=1))
            # only pairs squeezed below their tile distance, to a little beyond it
            want = np.minimum(want, (2.0 - TILE_SLACK) * tile)
            hit &= dist < TILE_SLACK * tile
        short = want - dist
        hit &= short > 0
        if not hit.any():
            break
        push = (0.25 * short[hit] / dist[hit])[:, None] * v[hit]
        # summed per element in pair order, the i ends first (as np.add.at
        # twice would, bit for bit, at a fraction of its cost)
        ends = np.concatenate([i[hit], j[hit]])
        both = np.concatenate([-push, push])
        move = np.stack([np.bincount(ends, weights=both[:, a], minlength=c.shape[0])
                         for a in range(3)], axis=1)
        # stay in each element's own tangent plane
        move -= np.einsum("ij,ij->i", move, normal)[:, None] * normal
        c += move
    return c - start


@compiled
def _spread_round(c, start, radius, normal, ideal, with_ideal, across, gap, slack, beyond,
                  pairs):
    """One round of :func:`spread_centres` over its ``pairs``, moving ``c`` in place.

    The numpy round's operations in its order: the 3-term dot products as
    ``np.einsum`` sums them on C-ordered operands (``(x0 y0 + x2 y2) + x1
    y1``; left to right for ``ideal`` stored ``across``, its rows innermost,
    as :func:`shaped_positions` makes it), the norms as
    ``np.linalg.norm`` (``(x0^2 + x1^2) + x2^2``), the pushes summed per
    element as ``np.bincount`` sums them (every pair's ``i`` end in pair
    order, then every ``j`` end). Returns False (and moves nothing) when no
    pair is pushed.
    """
    m = pairs.shape[0]
    push = np.zeros((m, 3))
    hit = np.zeros(m, dtype=np.bool_)
    any_hit = False
    for p in range(m):
        i, j = pairs[p, 0], pairs[p, 1]
        v0, v1, v2 = c[j, 0] - c[i, 0], c[j, 1] - c[i, 1], c[j, 2] - c[i, 2]
        s0, s1, s2 = normal[i, 0] + normal[j, 0], normal[i, 1] + normal[j, 1], \
            normal[i, 2] + normal[j, 2]
        n = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        if n > 0:
            s0, s1, s2 = s0 / n, s1 / n, s2 / n
        else:
            s0, s1, s2 = 0.0, 0.0, 0.0
        dot = v0 * s0 + v2 * s2 + v1 * s1
        v0, v1, v2 = v0 - dot * s0, v1 - dot * s1, v2 - dot * s2
        dist = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        want = gap * (radius[i] + radius[j])
        h = dist > 0
        if with_ideal:
            d0, d1, d2 = start[j, 0] - start[i, 0], start[j, 1] - start[i, 1], \
                start[j, 2] - start[i, 2]
            if across:
                ti0 = ideal[i, 0, 0] * d0 + ideal[i, 0, 1] * d1 + ideal[i, 0, 2] * d2
                ti1 = ideal[i, 1, 0] * d0 + ideal[i, 1, 1] * d1 + ideal[i, 1, 2] * d2
                tj0 = ideal[j, 0, 0] * d0 + ideal[j, 0, 1] * d1 + ideal[j, 0, 2] * d2
                tj1 = ideal[j, 1, 0] * d0 + ideal[j, 1, 1] * d1 + ideal[j, 1, 2] * d2
            else:
                ti0 = ideal[i, 0, 0] * d0 + ideal[i, 0, 2] * d2 + ideal[i, 0, 1] * d1
                ti1 = ideal[i, 1, 0] * d0 + ideal[i, 1, 2] * d2 + ideal[i, 1, 1] * d1
                tj0 = ideal[j, 0, 0] * d0 + ideal[j, 0, 2] * d2 + ideal[j, 0, 1] * d1
                tj1 = ideal[j, 1, 0] * d0 + ideal[j, 1, 2] * d2 + ideal[j, 1, 1] * d1
            tile = 0.5 * (np.sqrt(ti0 * ti0 + ti1 * ti1) + np.sqrt(tj0 * tj0 + tj1 * tj1))
            cap = beyond * tile
            if np.isnan(want) or np.isnan(cap):
                want = np.nan
            elif cap < want:
                want = cap
            h = h and dist < slack * tile
        short = want - dist
        h = h and short > 0
        if h:
            f = 0.25 * short / dist
            push[p, 0], push[p, 1], push[p, 2] = f * v0, f * v1, f * v2
            hit[p] = True
            any_hit = True
    if not any_hit:
        return False
    move = np.zeros(c.shape)
    for p in range(m):
        if hit[p]:
            i = pairs[p, 0]
            for a in range(3):
                move[i, a] += -push[p, a]
    for p in range(m):
        if hit[p]:
            j = pairs[p, 1]
            for a in range(3):
                move[j, a] += push[p, a]
    for e in range(c.shape[0]):
        m0, m1, m2 = move[e, 0], move[e, 1], move[e, 2]
        dot = m0 * normal[e, 0] + m2 * normal[e, 2] + m1 * normal[e, 1]
        c[e, 0] += m0 - dot * normal[e, 0]
        c[e, 1] += m1 - dot * normal[e, 1]
        c[e, 2] += m2 - dot * normal[e, 2]
    return True


def _cast_feet(pc, quads, uv, target, direction, face, bary, projector, *, rounds: int):
    """Feet of ``target`` carried along ``direction`` onto the fitted surface.

    From the closest points ``(face, bary)``, each round intersects the line
    ``target + t direction`` with the plane of the foot's triangle and finds
    the closest point of that intersection (:func:`_feet`): on a smooth patch
    the feet converge to where the line meets the surface, so a shape laid
    across its axis keeps its cross-section along it (closest points pull it
    together in a valley and spread it over a ridge).

    Returns
    -------
    face : (k,) int64
    bary : (k, 3) float64
    miss : (k,) float64
        Distance of every foot from its line (infinite where the foot's
        triangle turns away from the line: less than 0.2 in cosine).
    projector : SurfaceProjector or None
        As :func:`_feet` returns it.
    """
    face, bary = face.copy(), bary.copy()
    for _ in range(int(rounds)):
        nf = face_normals(pc.Y, pc.F[face])
        cos = np.einsum("ij,ij->i", nf, direction)
        ok = cos > 0.2
        if not ok.any():
            break
        foot = interpolated(pc.Y, pc.F, face[ok], bary[ok])
        t = np.einsum("ij,ij->i", foot - target[ok], nf[ok]) / cos[ok]
        x = target[ok] + t[:, None] * direction[ok]
        face[ok], bary[ok], projector = _feet(pc, quads[ok], uv[ok], x, direction[ok],
                                              projector)
    facing = np.einsum("ij,ij->i", face_normals(pc.Y, pc.F[face]), direction) > 0.2
    miss = _off_line(interpolated(pc.Y, pc.F, face, bary) - target, direction)
    return face, bary, np.where(facing, miss, np.inf), projector


def _off_line(rel: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Length of the part of every ``rel`` across its unit ``direction``, ``(k,)``."""
    return np.linalg.norm(rel - np.einsum("ij,ij->i", rel, direction)[:, None] * direction,
                          axis=1)


def _feet(pc, quads, uv, target, direction, projector):
    """Face and barycentrics of ``target``'s foot on the fitted surface, and the projector.

    The nearest point found by walking the point's own quad
    (:func:`_walked_feet`), else the closest point on faces that face the way
    ``direction`` does (``projector``, built here if None and needed, and
    returned for the next call).
    """
    fface, fb, lost = _walked_feet(pc, quads, uv, target)
    if lost.any():
        if projector is None:
            projector = SurfaceProjector(pc.Y, pc.F)
        foot, fface[lost] = projector.project(target[lost], direction[lost])
        fb[lost] = clamped_barycentric(foot, *(pc.Y[pc.F[fface[lost], i]] for i in range(3)))
    return fface, fb, projector


def _walked_feet(pc, quads, uv, target, *, steps: int = 4):
    """Closest points of ``target`` on the fitted surface, walking each point's quad.

    From the tile point ``uv`` of quad ``quads``, repeat: locate the sub-grid
    face, find the closest point of ``target`` in the plane of its fitted
    triangle and the tile point that the triangle's linear map gives there;
    done once that point lies in the face itself. Points whose walk leaves
    the quad or does not settle within ``steps`` are ``lost`` (the caller
    finds them by a search).

    Returns
    -------
    face : (k,) int64
    bary : (k, 3) float64
    lost : (k,) bool
    """
    r = pc.res
    k = quads.size
    if 3 * k >= JIT_MIN_SIZE:
        # one pass per point without temporaries: the same operations in the same order
        face = np.zeros(k, dtype=np.int64)
        bary = np.zeros((k, 3))
        lost = np.ones(k, dtype=bool)
        _walk_loops(np.ascontiguousarray(quads, dtype=np.int64),
                    np.ascontiguousarray(uv, dtype=np.float64),
                    np.ascontiguousarray(target, dtype=np.float64),
                    np.ascontiguousarray(pc.Y, dtype=np.float64),
                    np.ascontiguousarray(pc.F, dtype=np.int64), int(r),
                    int(steps), face, bary, lost)
        return face, bary, lost
    face = np.zeros(k, dtype=np.int64)
    bary = np.zeros((k, 3))
    lost = np.ones(k, dtype=bool)
    todo = np.arange(k)
    cur = np.clip(uv, 0.0, 1.0)
    for _ in range(steps):
        if todo.size == 0:
            break
        f, _ = pc.locate(quads[todo], cur[todo])
        corners = pc.F[f]
        Y0 = pc.Y[corners[:, 0]]
        E1, E2 = pc.Y[corners[:, 1]] - Y0, pc.Y[corners[:, 2]] - Y0
        g = target[todo] - Y0
        a, b, c = (np.einsum("ij,ij->i", E1, E1), np.einsum("ij,ij->i", E1, E2),
                   np.einsum("ij,ij->i", E2, E2))
        det = a * c - b * b
        det = np.where(np.abs(det) > 0, det, 1.0)
        p, q = np.einsum("ij,ij->i", E1, g), np.einsum("ij,ij->i", E2, g)
        b1, b2 = (c * p - b * q) / det, (a * q - b * p) / det
        inside = (b1 >= -1e-9) & (b2 >= -1e-9) & (b1 + b2 <= 1.0 + 1e-9)
        done = todo[inside]
        face[done] = f[inside]
        bary[done] = np.stack([1.0 - b1 - b2, b1, b2], axis=1)[inside]
        lost[done] = False
        # the tile point of the plane's foot (the triangle's map, extended)
        local = f % (2 * r * r)
        upper = local >= r * r
        cell = local % (r * r)
        ci, cj = cell // r, cell % r
        # corners in tile units: lower (i,j),(i+1,j),(i+1,j+1); upper (i,j),(i+1,j+1),(i,j+1)
        du1, dv1 = np.where(upper, 1.0, 1.0), np.where(upper, 1.0, 0.0)
        du2, dv2 = np.where(upper, 0.0, 1.0), np.where(upper, 1.0, 1.0)
        nu = (ci + b1 * du1 + b2 * du2) / r
        nv = (cj + b1 * dv1 + b2 * dv2) / r
        within = ~inside & (nu >= 0.0) & (nu <= 1.0) & (nv >= 0.0) & (nv <= 1.0)
        cur[todo[within]] = np.stack([nu, nv], axis=1)[within]
        todo = todo[within]
    return face, bary, lost


@compiled
def _walk_loops(quads, uv, target, Y, F, r, steps, face, bary, lost):
    """Compiled :func:`_walked_feet` (fills ``face``, ``bary``, ``lost``), point by point.

    Every point takes the numpy path's steps with the same floating-point
    operations in the same order (``pc.locate``'s face; the 3-term dot
    products in ``np.einsum``'s order, ``(x0 y0 + x2 y2) + x1 y1``, as numpy
    2.x sums three terms), so the results are equal bit for bit
    (``tests/test_compiled_paths.py`` compares them).
    """
    rr = r * r
    for k in range(quads.shape[0]):
        cu = min(max(uv[k, 0], 0.0), 1.0)
        cv = min(max(uv[k, 1], 0.0), 1.0)
        for _ in range(steps):
            # pc.locate's face of (cu, cv)
            xu = min(max(cu, 0.0), 1.0) * r
            xv = min(max(cv, 0.0), 1.0) * r
            c0 = min(np.int64(np.floor(xu)), r - 1)
            c1 = min(np.int64(np.floor(xv)), r - 1)
            up = 1 if (xv - c1) > (xu - c0) else 0
            f = quads[k] * (2 * rr) + c0 * r + c1 + up * rr
            i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
            y0, y1, y2 = Y[i0, 0], Y[i0, 1], Y[i0, 2]
            e10, e11, e12 = Y[i1, 0] - y0, Y[i1, 1] - y1, Y[i1, 2] - y2
            e20, e21, e22 = Y[i2, 0] - y0, Y[i2, 1] - y1, Y[i2, 2] - y2
            g0, g1, g2 = target[k, 0] - y0, target[k, 1] - y1, target[k, 2] - y2
            a = e10 * e10 + e12 * e12 + e11 * e11
            b = e10 * e20 + e12 * e22 + e11 * e21
            c = e20 * e20 + e22 * e22 + e21 * e21
            det = a * c - b * b
            if not abs(det) > 0:
                det = 1.0
            p = e10 * g0 + e12 * g2 + e11 * g1
            q = e20 * g0 + e22 * g2 + e21 * g1
            b1 = (c * p - b * q) / det
            b2 = (a * q - b * p) / det
            if b1 >= -1e-9 and b2 >= -1e-9 and b1 + b2 <= 1.0 + 1e-9:
                face[k] = f
                bary[k, 0] = 1.0 - b1 - b2
                bary[k, 1] = b1
                bary[k, 2] = b2
                lost[k] = False
                break
            local = f % (2 * rr)
            upper = local >= rr
            cell = local % rr
            ci, cj = cell // r, cell % r
            du1, dv1 = 1.0, (1.0 if upper else 0.0)
            du2, dv2 = (0.0 if upper else 1.0), 1.0
            nu = (ci + b1 * du1 + b2 * du2) / r
            nv = (cj + b1 * dv1 + b2 * dv2) / r
            if not (nu >= 0.0 and nu <= 1.0 and nv >= 0.0 and nv <= 1.0):
                break
            cu, cv = nu, nv


def _home_frame(layout, quads, uv, element, n_el):
    """Every element's home quad (the one with most of its points) and its points there.

    Points in a quad that shares a side with the home quad are unfolded
    across that side into the home frame (the tile coordinate ``t`` along a
    side is the same in both quads, and the two quads lie on opposite sides
    of it); elements with points elsewhere are not ``unfolded``.

    Returns
    -------
    home : (e,) int64
    uvh : (k, 2) float64
    unfolded : (e,) bool
    """
    pair = element * layout.n_quads + quads
    keys, counts = np.unique(pair, return_counts=True)
    el_of = keys // layout.n_quads
    # per element the pair with most points (ties: the lowest quad)
    order = np.lexsort((-counts, el_of))
    first = np.ones(order.size, dtype=bool)
    first[1:] = el_of[order][1:] != el_of[order][:-1]
    home = np.zeros(n_el, dtype=np.int64)
    home[el_of[order][first]] = keys[order][first] % layout.n_quads
    h = home[element]
    uvh = uv.copy()
    away = np.flatnonzero(quads != h)
    found = np.ones(quads.size, dtype=bool)
    if away.size:
        E = layout.quad_edge[h[away]]                                # (a, 4) home sides
        eq, es = layout.edge_quads[E], layout.edge_sides[E]          # (a, 4, 2)
        q = quads[away]
        mine = eq[:, :, 0] == q[:, None]
        hit = mine | (eq[:, :, 1] == q[:, None])
        ok = hit.any(axis=1)
        side_h = np.argmax(hit, axis=1)                              # home side crossed
        rows = np.arange(away.size)
        pick = np.where(mine[rows, side_h], 0, 1)
        side_q = es[rows, side_h, pick]                              # the same side in q
        u, v = uv[away, 0], uv[away, 1]
        t = np.select([side_q == 0, side_q == 1, side_q == 2], [u, v, u], v)
        n = np.select([side_q == 0, side_q == 1, side_q == 2], [v, 1.0 - u, 1.0 - v], u)
        n = -n                                                       # beyond the home side
        uh = np.select([side_h == 0, side_h == 1, side_h == 2], [t, 1.0 - n, t], n)
        vh = np.select([side_h == 0, side_h == 1, side_h == 2], [n, t, 1.0 - n], t)
        uvh[away] = np.where(ok[:, None], np.stack([uh, vh], axis=1), uv[away])
        found[away] = ok
    unfolded = np.ones(n_el, dtype=bool)
    unfolded[element[~found]] = False
    return home, uvh, unfolded


@dataclass(frozen=True)
class ElementFootprints:
    """Footprints of elements: their projection onto their tangent planes.

    Attributes
    ----------
    area : numpy.ndarray, (e,) float64
        Footprint area (half the projected area of the closed element's faces).
    aspect : numpy.ndarray, (e,) float64
        Elongation ``sqrt(l1 / l2) >= 1`` of the footprint's second moments.
    """

    area: np.ndarray
    aspect: np.ndarray

    @property
    def cv(self) -> float:
        """Coefficient of variation of the areas (std / mean)."""
        return float(self.area.std() / self.area.mean()) if self.area.size else 0.0


def element_directions(shell, mapped, label) -> np.ndarray:
    """Mean offset direction ``d`` of the shell under every mapped element.

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
        Tiles mapped over ``shell`` (:func:`geotex.mapping.place.mapped_tiles`).
    label : numpy.ndarray, (m,) int64
        Element ``0 .. e - 1`` of every face of ``mapped.faces``.

    Returns
    -------
    numpy.ndarray, (e, 3) float64
        Not normalised (the sum over the element's face corners); the
        projection direction :func:`element_footprints` takes.
    """
    pc = shell.polycube
    face, bary = pc.locate(mapped.quads, mapped.tile_points[:, :2])
    d = interpolated(shell.D, pc.F, face, bary)
    label = np.asarray(label, dtype=np.int64)
    n = int(label.max()) + 1 if label.size else 0
    vlabel = np.zeros(mapped.vertices.shape[0], dtype=np.int64)
    vlabel[mapped.faces.ravel()] = np.repeat(label, 3)
    return np.stack([np.bincount(vlabel, weights=d[:, j], minlength=n) for j in range(3)], 1)


def element_footprints(V, F, label, normal) -> ElementFootprints:
    """Area and elongation of every element's footprint.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        Closed elements.
    label : array_like, (m,) int64
        Element ``0 .. e - 1`` of every face.
    normal : array_like, (e, 3) float64
        Direction each element is projected along (its base's normal).

    Returns
    -------
    ElementFootprints

    Raises
    ------
    InputError
        Mismatched shapes.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    label = np.asarray(label, dtype=np.int64)
    normal = _unit(np.asarray(normal, dtype=np.float64))
    if label.shape != (F.shape[0],) or normal.ndim != 2 or normal.shape[1] != 3:
        raise InputError("label needs one entry per face and normal one row (3) per element")
    n_el = normal.shape[0]
    if label.size and (label.min() < 0 or label.max() >= n_el):
        raise InputError("face labels must lie in [0, number of normals)")
    e1, e2 = _tangent_frames(normal)
    P = V[F]                                                        # (m, 3, 3)
    q = np.stack([np.einsum("mij,mj->mi", P, e1[label]),
                  np.einsum("mij,mj->mi", P, e2[label])], axis=2)    # (m, 3, 2)
    a = 0.5 * np.abs((q[:, 1, 0] - q[:, 0, 0]) * (q[:, 2, 1] - q[:, 0, 1])
                     - (q[:, 2, 0] - q[:, 0, 0]) * (q[:, 1, 1] - q[:, 0, 1]))
    ssum = q.sum(axis=1)
    second = (np.einsum("mia,mib->mab", q, q) + ssum[:, :, None] * ssum[:, None, :]) / 12.0
    area = np.bincount(label, weights=a, minlength=n_el)
    safe = np.maximum(area, 1e-300)
    first = np.stack([np.bincount(label, weights=a * c, minlength=n_el)
                      for c in (ssum[:, 0] / 3, ssum[:, 1] / 3)], axis=1) / safe[:, None]
    M = np.stack([np.bincount(label, weights=a * second[:, i, j], minlength=n_el)
                  for i, j in ((0, 0), (0, 1), (1, 1))], axis=1) / safe[:, None]
    cxx = M[:, 0] - first[:, 0] ** 2
    cxy = M[:, 1] - first[:, 0] * first[:, 1]
    cyy = M[:, 2] - first[:, 1] ** 2
    half = 0.5 * (cxx + cyy)
    r = np.sqrt(np.maximum(0.25 * (cxx - cyy) ** 2 + cxy ** 2, 0.0))
    l1, l2 = half + r, np.maximum(half - r, 1e-300)
    return ElementFootprints(area=0.5 * area, aspect=np.sqrt(np.maximum(l1, 0.0) / l2))
