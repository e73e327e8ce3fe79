"""Elements re-seated instead of dropped: folds laid back, floating pieces seated.

Two kinds of mapped elements used to be left out of the union
(:mod:`geotex.mapping.union`):

* **folded** elements, whose own faces cross where the map bends them at an
  irregular polycube corner (a weave strand loop folded in 4-9 faces of
  16k-31k was left out whole). :func:`remapped_folds` maps the points about
  the crossing faces again through the map averaged over a disc (the fitted
  surface itself folds there), the element alone first, then with its
  neighbours, then with the height lowered there, last with the elements
  linked through it blended by the distance in space; :func:`smoothed_folds`
  takes umbrella steps over a few rings about the crossing faces as a last
  try. A result is kept only if no moved face crosses any face (exact test).
* **floating** pieces, which neither cross the base nor lie inside it, so the
  union would leave them as loose parts. On the catalog shells they are
  chain-mail ring pieces at polycube corners where three quads meet: the four
  quadrants of a corner ring become three, which weld into a small triangular
  loop at the top and a low piece inside the base. :func:`floating_elements`
  finds them (winding numbers against the base, then the exact test for the
  elements wholly outside); :func:`lowered_elements` moves each down its
  offset directions (its tile ``w`` lowered, mapped again) by the smallest of
  a few steps at which it crosses the base and meets no other element; a
  piece that cannot drop without cutting the rings linked through it is
  stood on the base with a thin post by :func:`propped_elements`.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from geotex.check.intersections import (self_intersecting_pairs,
                                       self_intersecting_pairs_between)
from geotex.mapping.shape import shaped_positions
from geotex.mesh.geometry import group_boxes
from geotex.mesh.topology import compacted, concatenated, edge_topology
from geotex.shells.locate import interpolated

__all__ = ["floating_elements", "lowered_elements", "rooted_elements", "propped_elements",
           "stood_elements", "smoothed_folds", "ROOT_STEPS", "STAND_RADIUS", "STAND_FLAT",
           "remapped_folds", "LOWER_STEPS", "POST_SIDES", "REMAP_RADII",
           "REMAP_HEIGHTS", "REMAP_REACH"]

#: Drops tried by :func:`lowered_elements`, as fractions of the way from the
#: element's lowest tile point down to the tile set's anchor depth.
LOWER_STEPS = (0.35, 0.7, 1.0, 1.4)

#: Disc radii (tile units) of the smoothed map tried by :func:`remapped_folds`.
REMAP_RADII = (0.08, 0.15, 0.25)

#: Height factors :func:`remapped_folds` tries over its largest disc.
REMAP_HEIGHTS = (0.8, 0.6, 0.45)

#: Distances (tiles) about a folded element's crossing points within which
#: :func:`remapped_folds` last moves every mapped point, blended by the
#: distance in space (the whole neighbourhood, across quads).
REMAP_REACH = (0.5, 1.0)

#: Multiples of the estimated stretch :func:`rooted_elements` tries.
ROOT_STEPS = (1.0, 1.5, 2.5)

#: Sides of the prism :func:`propped_elements` stands an element on.
POST_SIDES = 8

#: Radius of the post :func:`stood_elements` stands a shaped element on, over
#: the spread of the element's points across its offset direction.
STAND_RADIUS = 0.15

#: Flattest element :func:`stood_elements` stands: least over largest singular
#: value of its centred points (Blub's squashed scales 0.003-0.02, whole
#: scales 0.1-0.3; posts under the squashed ones left needles in the union).
STAND_FLAT = 0.05


def _element_boxes(X, G, label, n_el):
    """Bounding box ``(lo, hi)`` of every element, ``(n_el, 3)`` each."""
    vlab = np.full(X.shape[0], -1, dtype=np.int64)
    if len(G):
        vlab[G[:, 0]], vlab[G[:, 1]], vlab[G[:, 2]] = label, label, label
    return group_boxes(X, vlab, n_el)


def _seating_boxes(shell, X: np.ndarray, G: np.ndarray, label: np.ndarray):
    """Boxes of the elements and of the base faces, and the faces of each element.

    Returns ``(lo, hi)`` of every element, ``(fl, fh)`` of every base face,
    and ``order, starts``: the faces of element ``e`` are
    ``order[starts[e]:starts[e + 1]]``.
    """
    n_el = int(label.max()) + 1
    V0, F0 = shell.base_vertices, shell.base_faces
    lo, hi = _element_boxes(X, G, label, n_el)
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(n_el + 1))
    return (lo, hi) + _face_boxes(V0, F0) + (order, starts)


def _crossings_near(Xc, Fc, e: int, X, G, boxes, V0, F0) -> tuple[np.ndarray, bool]:
    """Exact crossings of a candidate ``(Xc, Fc)`` for element ``e``.

    It is tested against the base faces and the other elements whose boxes
    overlap its box (``boxes`` from :func:`_seating_boxes`). Returns the parts
    met (1 is the base, ``2 ..`` those elements) and whether it crosses itself.
    """
    lo, hi, fl, fh, order, starts = boxes
    blo, bhi = Xc.min(axis=0), Xc.max(axis=0)
    others = np.flatnonzero(_overlapping(lo, hi, blo, bhi))
    others = others[others != e]
    parts = [(Xc, Fc), (V0, F0[_overlapping(fl, fh, blo, bhi)])]
    parts += [(X, G[order[starts[o]:starts[o + 1]]]) for o in others]
    return _crossing_parts(parts, 0)


def _overlapping(lo, hi, box_lo, box_hi) -> np.ndarray:
    """Rows of ``(lo, hi)`` whose boxes overlap the box ``(box_lo, box_hi)`` (a mask)."""
    out = (lo[:, 0] <= box_hi[0]) & (hi[:, 0] >= box_lo[0])
    rows = np.flatnonzero(out)             # the other axes on the few that overlap on x
    out[rows] = np.all((lo[rows, 1:] <= box_hi[1:]) & (hi[rows, 1:] >= box_lo[1:]), axis=1)
    return out


def _face_boxes(X: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounding box ``(lo, hi)`` of every face, ``(m, 3)`` each."""
    a, b, c = X[G[:, 0]], X[G[:, 1]], X[G[:, 2]]
    return np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)


def _crossing_parts(parts_mesh, probe: int) -> tuple[np.ndarray, np.ndarray]:
    """Exact crossings of part ``probe`` of ``[(V, F), ...]``: with itself, with others.

    Returns the sorted other parts met and whether the probe crosses itself
    (only the probe's pairs are examined).
    """
    parts_mesh = [compacted(V, F) if len(F) else (V[:0], F) for V, F in parts_mesh]
    V, F = concatenated(parts_mesh)
    part = np.repeat(np.arange(len(parts_mesh)), [len(f) for _, f in parts_mesh])
    at_probe = part == probe
    pairs = self_intersecting_pairs_between(V, F, part, side=at_probe, within=at_probe)
    a, b = part[pairs[:, 0]], part[pairs[:, 1]]
    other = np.where(a == probe, b, a)              # (every pair has a face of the probe)
    return np.unique(other[other != probe]), bool(np.any(other == probe))


def _own_crossings(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Every crossing pair of faces of one small part (an element), sorted.

    The rows of ``self_intersecting_pairs(V, F)``, found by sweeping the one
    part (no grid, no fan stage: a few ms less per element).
    """
    m = len(F)
    return self_intersecting_pairs_between(V, F, np.zeros(m, dtype=np.int64),
                                           within=np.ones(m, dtype=bool))


def _clean_move(X: np.ndarray, G: np.ndarray, moved: np.ndarray, fbox, pool: np.ndarray
                ) -> bool:
    """Whether no face at a ``moved`` vertex crosses any face (exact test, local).

    ``fbox`` is ``(lo, hi)`` of every face of ``G`` at its current positions
    except the moved ones; ``pool`` holds every face that may be at a moved
    vertex or near one. Only faces of the pool whose boxes overlap the moved
    faces' box are tested, so the test costs what the neighbourhood of the
    move costs.
    """
    at = np.zeros(X.shape[0], dtype=bool)
    at[moved] = True
    Gp = G[pool]
    changed = at[Gp].any(axis=1)
    P = X[Gp[changed]]
    blo, bhi = P.min(axis=(0, 1)), P.max(axis=(0, 1))
    rows = np.flatnonzero(_overlapping(fbox[0][pool], fbox[1][pool], blo, bhi) | changed)
    V2, F2 = compacted(X, Gp[rows])
    mine = changed[rows]           # only the pairs with a moved face are examined
    pairs = self_intersecting_pairs_between(V2, F2, mine.astype(np.int64), side=mine,
                                            within=mine)
    return not pairs.size


def _pool(X: np.ndarray, G: np.ndarray, fbox, points: np.ndarray, margin: float) -> np.ndarray:
    """Faces at ``points`` or whose boxes come within ``margin`` of their box."""
    at = np.zeros(X.shape[0], dtype=bool)
    at[points] = True
    lo, hi = X[points].min(axis=0) - margin, X[points].max(axis=0) + margin
    return np.flatnonzero(_overlapping(fbox[0], fbox[1], lo, hi)
                          | at[G[:, 0]] | at[G[:, 1]] | at[G[:, 2]])


def floating_elements(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray, *,
                      label: np.ndarray, touching: np.ndarray, usable=None,
                      heights=None) -> np.ndarray:
    """Elements that would float: neither crossing the base nor inside it.

    An element whose vertices lie both inside and outside the base (generalized
    winding number, libigl) crosses it; one with every vertex inside is
    absorbed by the union; for one with every vertex outside the exact test
    decides whether its faces still cross the base's. Elements joined through
    ``touching`` count as one piece: it floats if none of them crosses the base.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        The base solid.
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64
        The mapped elements.
    label : numpy.ndarray, (l,) int64
        Element of every face (:class:`~geotex.mapping.union.ElementContacts`).
    touching : numpy.ndarray, (p, 2) int64
        Pairs of elements that meet.
    usable : numpy.ndarray, (e,) bool, optional
        Elements that go into the union (default all).
    heights : numpy.ndarray, (k,) float64, optional
        Height of every vertex above the surface (the tile frame's ``w``).
        With it, the winding number is first taken at each element's lowest
        and highest vertex only: lowest inside and highest outside means the
        element crosses the base, and only the other elements are tested
        vertex by vertex (same answer; on elements standing in the base, as
        studs do, about 2 points per element instead of all).

    Returns
    -------
    numpy.ndarray, (f,) int64
        Sorted floating elements (usable ones only).
    """
    n_el = int(label.max()) + 1 if label.size else 0
    if n_el == 0:
        return np.zeros(0, dtype=np.int64)
    use = np.ones(n_el, dtype=bool) if usable is None else np.asarray(usable, dtype=bool)
    vlab = np.full(X.shape[0], -1, dtype=np.int64)
    vlab[G[:, 0]], vlab[G[:, 1]], vlab[G[:, 2]] = label, label, label
    used = np.flatnonzero(vlab >= 0)
    Vc = np.ascontiguousarray(V, dtype=np.float64)
    Fc = np.ascontiguousarray(F, dtype=np.int64)

    def inside(points):
        return np.asarray(igl.fast_winding_number(Vc, Fc, np.ascontiguousarray(points))) > 0.5

    crossing = np.zeros(n_el, dtype=bool)
    if heights is not None and used.size:
        lab = vlab[used]
        order = used[np.lexsort((np.asarray(heights)[used], lab))]
        ls = vlab[order]
        new = np.r_[True, ls[1:] != ls[:-1]]
        low, high = order[new], order[np.r_[new[1:], True]]
        probe = inside(X[np.concatenate([low, high])])
        crossing[ls[new]] = probe[:low.size] & ~probe[low.size:]
        used = used[~crossing[vlab[used]]]
    inside_v = inside(X[used]) if used.size else np.zeros(0, dtype=bool)
    n_in = np.bincount(vlab[used], weights=inside_v, minlength=n_el)
    n_all = np.bincount(vlab[used], minlength=n_el)
    attached = crossing | ((n_in > 0) & (n_in < n_all))
    n_in[crossing] = 1                  # (some vertex inside: not wholly outside)
    outside = (n_in == 0) & use
    cand = np.flatnonzero(outside)
    if cand.size:
        # wholly outside: their faces may still cross the base's (exact test)
        lo, hi = _element_boxes(X, G, label, n_el)
        pad = 1e-9 * float(np.linalg.norm(np.ptp(V, axis=0)))
        fl, fh = _face_boxes(V, F)
        near = np.zeros(len(F), dtype=bool)
        for e in cand:
            near |= np.all((fl <= hi[e] + pad) & (fh >= lo[e] - pad), axis=1)
        if near.any():
            sel = np.isin(label, cand)
            XX, GG = concatenated([compacted(V, F[near]), compacted(X, G[sel])])
            part = np.concatenate([np.full(int(near.sum()), -1), label[sel]]) + 1
            pairs = self_intersecting_pairs(XX, GG, parts=part)
            a, b = part[pairs[:, 0]], part[pairs[:, 1]]
            hit = np.concatenate([b[a == 0], a[b == 0]]) - 1
            attached[hit[hit >= 0]] = True
    tp = np.asarray(touching, dtype=np.int64).reshape(-1, 2)
    tp = tp[use[tp].all(axis=1)]
    graph = sp.coo_matrix((np.ones(len(tp)), (tp[:, 0], tp[:, 1])), shape=(n_el, n_el))
    _, comp = connected_components(graph, directed=False)
    comp_attached = np.zeros(int(comp.max()) + 1, dtype=bool)
    comp_attached[comp[attached & use]] = True
    return np.flatnonzero(outside & ~comp_attached[comp])


def lowered_elements(shell, mapped, label: np.ndarray, elements, *, scale: float,
                     depth_scale: float, depth: float, steps=LOWER_STEPS
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Lower floating elements along the shell's offset directions onto the base.

    Every element's tile points are lowered by ``s (w_min + depth)`` tile
    units (``w_min`` its lowest tile point, so ``s = 1`` brings that to
    ``-depth``, where its neighbours are anchored) for each ``s`` of
    ``steps`` in turn, mapped again as :func:`~geotex.mapping.place.mapped_tiles`
    mapped them, and kept at the first step where the element crosses the
    base and crosses neither itself nor any other element (exact tests
    against the base faces and the elements whose boxes overlap it).

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
    label : numpy.ndarray, (M,) int64
        Element of every face of ``mapped.faces``.
    elements : array_like of int
        The floating elements (:func:`floating_elements`).
    scale, depth_scale : float
        As in :func:`~geotex.mapping.place.shell_positions`.
    depth : float
        Depth of the tile set below ``w = 0`` (``tiles.depth``), tile units.
    steps : sequence of float
        Fractions tried, in order.

    Returns
    -------
    X : numpy.ndarray, (N, 3) float64
        Mapped positions with the lowered elements moved.
    still_floating : numpy.ndarray, (k,) int64
        Elements no step seated cleanly (left where they were).
    """
    X = mapped.vertices.copy()
    G = mapped.faces
    todo = np.unique(np.asarray(elements, dtype=np.int64))
    if todo.size == 0:
        return X, todo
    boxes = _seating_boxes(shell, X, G, label)
    lo, hi, fl, fh, order, starts = boxes
    V0, F0 = shell.base_vertices, shell.base_faces
    left = []
    for e in todo:
        faces = G[order[starts[e]:starts[e + 1]]]
        verts, local = np.unique(faces, return_inverse=True)
        local = local.reshape(-1, 3)
        uvw = mapped.tile_points[verts]
        wmin = float(uvw[:, 2].min())
        drop = wmin + float(depth)
        seated = False
        for s in steps:
            low = uvw.copy()
            low[:, 2] -= float(s) * drop
            Xe = shaped_positions(shell, mapped.quads[verts], low,
                                  np.zeros(verts.size, dtype=np.int64), scale=scale,
                                  depth_scale=depth_scale, similar=mapped.shaped,
                                  shift=None if mapped.shift is None else mapped.shift[verts],
                                  lean=None if mapped.leaned is None else mapped.leaned[[e]])
            met, folded = _crossings_near(Xe, local, e, X, G, boxes, V0, F0)
            if not folded and met.size == 1 and met[0] == 1:
                X[verts] = Xe
                lo[e], hi[e] = Xe.min(axis=0), Xe.max(axis=0)
                seated = True
                break
        if not seated:
            left.append(e)
    return X, np.asarray(left, dtype=np.int64)


def _root_reach(shell, mapped, X: np.ndarray, verts, depth: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean offset direction of each element and how far its lowest point is from ``depth``.

    ``verts`` lists the vertices of every element. Returns ``d`` (``(k, 3)``,
    unit: the shell's offset directions at its tile points, averaged), the
    stretch along ``d`` that brings its lowest tile point ``depth`` below the
    base, ``(dist + depth) / max(d . n, 0.25)`` (``dist`` and ``n`` the
    distance to the base and its normal there), and that point's tile ``w``.
    """
    pc = shell.polycube
    V0, F0 = shell.base_vertices, shell.base_faces
    k = len(verts)
    allv = np.concatenate(verts)
    el = np.repeat(np.arange(k), [v.size for v in verts])
    w = mapped.tile_points[allv, 2]
    # every element's mean offset direction, at its tile points
    face, bary = pc.locate(mapped.quads[allv], mapped.tile_points[allv, :2])
    D = interpolated(shell.D, pc.F, face, bary)
    D /= np.maximum(np.linalg.norm(D, axis=1, keepdims=True), 1e-300)
    d = np.stack([np.bincount(el, weights=D[:, i], minlength=k) for i in range(3)], 1)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    # each element's lowest tile point: its distance to the base and the normal there
    low = np.lexsort((w, el))
    first = np.r_[0, np.cumsum([v.size for v in verts])[:-1]]
    bottom = allv[low[first]]
    wmin = mapped.tile_points[bottom, 2]
    sq, fi, _ = igl.point_mesh_squared_distance(X[bottom], V0, F0)
    n = np.cross(V0[F0[fi, 1]] - V0[F0[fi, 0]], V0[F0[fi, 2]] - V0[F0[fi, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    reach = (np.sqrt(sq) + float(depth)) / np.maximum((d * n).sum(axis=1), 0.25)
    return d, reach, wmin


def rooted_elements(shell, mapped, X: np.ndarray, label: np.ndarray, elements, *,
                    depth: float, steps=ROOT_STEPS
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Extend the roots of floating elements along their offset direction into the base.

    An element that lies wholly above the base (where the map laid it, e.g.
    shrunk where the offset directions lean far from the surface's normal)
    keeps its shape above the surface: only its root, the points below the
    surface (tile ``w < 0``), is stretched down the element's mean offset
    direction ``d`` (the shell's offset directions at its tile points,
    averaged), each point by ``t w / w_min`` (``w_min`` the element's lowest
    tile point), so the lowest point moves by ``t`` and the surface points
    (``w = 0``) stay. ``t`` is the stretch that would bring the lowest point
    ``depth`` below the base, ``(dist + depth) / max(d . n, 0.25)`` (``dist``
    and ``n`` the distance to the base and its normal there), times each of
    ``steps`` in turn; the first result that crosses the base and neither
    itself nor any other element (exact tests) is kept. If every stretch
    meets another element (the long root of a lifted element reaching the
    roots of its neighbours where the base is concave), the first that
    crosses the base and not itself is kept, and the pairs it meets are
    returned for the union to unite them among themselves.

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
        Tile points and quads of every vertex (``mapped.vertices`` is not used).
    X : numpy.ndarray, (N, 3) float64
        Current positions of the mapped vertices.
    label : numpy.ndarray, (M,) int64
        Element of every face of ``mapped.faces``.
    elements : array_like of int
        The floating elements (:func:`floating_elements`).
    depth : float
        World depth below the base the lowest point is taken to (the
        anchor depth of the other elements).
    steps : sequence of float
        Multiples of the estimated stretch tried, in order.

    Returns
    -------
    X : numpy.ndarray, (N, 3) float64
        Positions with the rooted elements' roots moved (a copy).
    still_floating : numpy.ndarray, (k,) int64
        Elements no stretch seated (or with no root), left as they were.
    touching : numpy.ndarray, (p, 2) int64
        Pairs ``i < j`` of elements a kept root now meets (sorted).
    """
    X = np.array(X, dtype=np.float64, copy=True)
    G = mapped.faces
    todo = np.unique(np.asarray(elements, dtype=np.int64))
    if todo.size == 0:
        return X, todo, np.zeros((0, 2), dtype=np.int64)
    V0, F0 = shell.base_vertices, shell.base_faces
    boxes = _seating_boxes(shell, X, G, label)
    lo, hi, _, _, order, starts = boxes
    rows = [order[starts[e]:starts[e + 1]] for e in todo]
    verts = [np.unique(G[r]) for r in rows]
    d, reach, wmin = _root_reach(shell, mapped, X, verts, depth)
    left, pairs = [], []
    for j, e in enumerate(todo):
        v = verts[j]
        faces = G[rows[j]]
        local = np.searchsorted(v, faces)
        wj = mapped.tile_points[v, 2]
        if not wmin[j] < 0:
            left.append(e)
            continue
        pull = np.where(wj < 0, wj / wmin[j], 0.0)
        kept = None
        for s in steps:
            Xe = X[v] - (float(s) * reach[j] * pull)[:, None] * d[j]
            met, folded = _crossings_near(Xe, local, e, X, G, boxes, V0, F0)
            if folded or met.size == 0 or met[0] != 1:
                continue
            if kept is None or met.size == 1:      # meeting only the base is best
                kept = (Xe, met)
            if met.size == 1:
                break
        if kept is None:
            left.append(e)
            continue
        Xe, met = kept
        X[v] = Xe
        lo[e], hi[e] = Xe.min(axis=0), Xe.max(axis=0)
        # parts 2.. are the elements whose boxes overlapped, in index order
        others = np.flatnonzero(_overlapping(lo, hi, Xe.min(axis=0), Xe.max(axis=0)))
        others = others[others != e]
        pairs += [(min(e, o), max(e, o)) for o in others[met[1:] - 2]]
    touching = np.unique(np.asarray(pairs, dtype=np.int64).reshape(-1, 2), axis=0)
    return X, np.asarray(left, dtype=np.int64), touching


def smoothed_folds(X: np.ndarray, G: np.ndarray, label: np.ndarray, folded, *,
                   rings=(2, 4, 8), iterations=(4, 12, 30)) -> tuple[np.ndarray, np.ndarray]:
    """Smooth the folded stretch of each folded element until it crosses nothing.

    The faces of a folded element that cross each other (exact test) and
    every vertex within ``r`` edges of them form the region; its inner
    vertices take ``k`` umbrella steps (each moves a vertex half way to the
    mean of its neighbours) with the region's rim fixed, for each pair
    ``(r, k)`` of ``zip(rings, iterations)`` in turn, and the first result that
    crosses neither itself nor any other element whose box overlaps it is kept.

    Parameters
    ----------
    X : numpy.ndarray, (N, 3) float64
    G : numpy.ndarray, (M, 3) int64
    label : numpy.ndarray, (M,) int64
        Element of every face.
    folded : array_like of int
        Elements whose own faces cross.
    rings, iterations : sequence of int
        Region sizes and smoothing steps tried together, in order.

    Returns
    -------
    X : numpy.ndarray, (N, 3) float64
        Positions with the smoothed elements moved.
    still_folded : numpy.ndarray, (k,) int64
    """
    X = np.array(X, dtype=np.float64, copy=True)
    todo = np.unique(np.asarray(folded, dtype=np.int64))
    if todo.size == 0:
        return X, todo
    n_el = int(label.max()) + 1
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(n_el + 1))
    fbox = None                    # the faces' boxes, once a move is to be tested
    left = []
    for e in todo:
        faces = G[order[starts[e]:starts[e + 1]]]
        verts, local = np.unique(faces, return_inverse=True)
        local = local.reshape(-1, 3)
        n = verts.size
        Xe0 = X[verts]
        pairs = _own_crossings(Xe0, local)
        seed = np.zeros(n, dtype=bool)
        seed[local[pairs.ravel()].ravel()] = True
        E = edge_topology(local, n).edges
        adj = sp.csr_matrix((np.ones(2 * len(E)), (np.concatenate([E[:, 0], E[:, 1]]),
                                                    np.concatenate([E[:, 1], E[:, 0]]))),
                            shape=(n, n))
        deg = np.asarray(adj.sum(axis=1)).ravel()
        done = False
        for r, k in zip(rings, iterations):
            region = seed.copy()
            for _ in range(int(r)):
                region |= (adj @ region.astype(np.float64)) > 0
            rim = region & ((adj @ (~region).astype(np.float64)) > 0)
            inner = region & ~rim
            Xe = Xe0.copy()
            for _ in range(int(k)):
                mean = (adj @ Xe) / np.maximum(deg, 1)[:, None]
                Xe[inner] = 0.5 * (Xe[inner] + mean[inner])
            if not inner.any():
                continue
            if _own_crossings(Xe, local).size:
                continue
            if fbox is None:       # (no move kept yet: the boxes of X as given)
                fbox = list(_face_boxes(X, G))
            # tried in place, put back if the move crosses anything
            X[verts] = Xe
            pool = _pool(X, G, fbox, verts[region], float(np.ptp(Xe0[region], axis=0).max()))
            if _clean_move(X, G, verts[inner], fbox, pool):
                Pm = X[faces]
                fbox[0][order[starts[e]:starts[e + 1]]] = Pm.min(axis=1)
                fbox[1][order[starts[e]:starts[e + 1]]] = Pm.max(axis=1)
                done = True
                break
            X[verts] = Xe0
        if not done:
            left.append(e)
    return X, np.asarray(left, dtype=np.int64)


def _post(centre: np.ndarray, radius: float, top: float, bottom: float, sides: int,
          layers: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed prism in tile coordinates: axis along ``w``, outward faces."""
    a = 2.0 * np.pi * np.arange(sides) / sides
    ring = centre[None, :] + radius * np.stack([np.cos(a), np.sin(a)], axis=1)
    w = np.linspace(bottom, top, layers + 1)
    P = np.concatenate([np.column_stack([ring, np.full(sides, z)]) for z in w]
                       + [np.array([[centre[0], centre[1], bottom], [centre[0], centre[1], top]])])
    i = np.arange(sides)
    j = (i + 1) % sides
    faces = []
    for k in range(layers):
        lo_, hi_ = k * sides, (k + 1) * sides
        faces += [np.stack([lo_ + i, lo_ + j, hi_ + j], axis=1),
                  np.stack([lo_ + i, hi_ + j, hi_ + i], axis=1)]
    nb, nt = len(P) - 2, len(P) - 1
    faces += [np.stack([np.full(sides, nb), j, i], axis=1),
              np.stack([np.full(sides, nt), layers * sides + i, layers * sides + j], axis=1)]
    return P, np.vstack(faces).astype(np.int64)


def propped_elements(shell, mapped, X: np.ndarray, label: np.ndarray, elements, *,
                     scale: float, depth_scale: float, depth: float, sides: int = POST_SIDES,
                     candidates: int = 12) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray]:
    """Stand floating elements on the base with a thin post each.

    A floating piece held between linked neighbours (a chain-mail ring piece
    at a polycube corner where three quads meet, whose neighbours pass
    through it) cannot be lowered without cutting them. A prism of
    ``sides`` sides, radius half the wire's (the spread of the element's
    points within ``1.5`` wire radii of the chosen point, in the tile), is
    stood in the tile frame of one quad from inside the element's wire at a
    point of it down to ``-depth``, mapped as the elements are, and kept if
    it crosses the base and no element but its own (exact tests). Points are
    tried lowest first among ``candidates`` spread over the element.

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
        Tile points and quads of every vertex (``mapped.vertices`` is not used).
    X : numpy.ndarray, (N, 3) float64
        Current positions of the mapped vertices.
    label : numpy.ndarray, (M,) int64
        Element of every face of ``mapped.faces``.
    elements : array_like of int
        Floating elements.
    scale, depth_scale, depth : float
        As in :func:`lowered_elements`.
    sides : int
        Sides of every post.
    candidates : int
        Points of an element tried.

    Returns
    -------
    posts_vertices : numpy.ndarray, (a, 3) float64
    posts_faces : numpy.ndarray, (b, 3) int64
        The posts, each a closed solid (vertex numbers from 0).
    propped : numpy.ndarray, (p,) int64
        The element every post props, in post order.
    still_floating : numpy.ndarray, (k,) int64
    """
    G = mapped.faces
    todo = np.unique(np.asarray(elements, dtype=np.int64))
    PV, PF, propped, left = [], [], [], []
    if todo.size == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), todo, todo
    boxes = _seating_boxes(shell, X, G, label)
    lo, hi, fl, fh, order, starts = boxes
    V0, F0 = shell.base_vertices, shell.base_faces
    n_post = 0
    for e in todo:
        verts = np.unique(G[order[starts[e]:starts[e + 1]]])
        uvw, quads = mapped.tile_points[verts], mapped.quads[verts]
        # candidate points: the lowest ones, spread along the element
        by_height = np.argsort(uvw[:, 2], kind="stable")
        picks = by_height[np.linspace(0, verts.size - 1, 4 * candidates).astype(np.int64)]
        done = False
        tried = 0
        for p in picks:
            if tried >= candidates:
                break
            q = quads[p]
            same = quads == q
            d = np.linalg.norm(uvw[same] - uvw[p], axis=1)
            # the wire around the point: the nearby points of its quad
            near = uvw[same][d <= 2.0 * np.median(np.sort(d)[1:8])]
            c = near.mean(axis=0)
            r = 0.5 * float(np.sqrt(((near - c) ** 2).sum(axis=1).mean()))
            if not (r > 0 and r <= c[0] <= 1 - r and r <= c[1] <= 1 - r):
                continue
            tried += 1
            P, Fp = _post(c[:2], r, float(c[2]), -float(depth), sides, 4)
            Xp = shaped_positions(shell, np.full(len(P), q, dtype=np.int64), P,
                                  np.zeros(len(P), dtype=np.int64), scale=scale,
                                  depth_scale=depth_scale, similar=False)
            met, folded = _crossings_near(Xp, Fp, e, X, G, boxes, V0, F0)
            if folded or not (met.size == 1 and met[0] == 1):
                continue
            own, _ = _crossing_parts([(Xp, Fp), (X, G[order[starts[e]:starts[e + 1]]])], 0)
            if own.size == 0:
                continue
            PV.append(Xp)
            PF.append(Fp + n_post)
            n_post += len(Xp)
            propped.append(e)
            done = True
            break
        if not done:
            left.append(e)
    if not PV:
        return (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                np.zeros(0, dtype=np.int64), np.asarray(left, dtype=np.int64))
    return (np.vstack(PV), np.vstack(PF), np.asarray(propped, dtype=np.int64),
            np.asarray(left, dtype=np.int64))


def stood_elements(shell, mapped, X: np.ndarray, label: np.ndarray, elements, *,
                   depth: float, steps=ROOT_STEPS, radius: float = STAND_RADIUS,
                   flat: float = STAND_FLAT, sides: int = POST_SIDES, candidates: int = 6
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Stand floating shaped elements on the base with a post along their offset direction.

    For a shaped element (a scale, a stud) that no longer root seats
    (:func:`rooted_elements`: its stretched root crosses its own faces, as
    a thin or shrunk scale's does where it sits well above the base), a
    prism of ``sides`` sides is stood under it in space, its axis along the
    element's mean offset direction ``d``: from the mean height along ``d``
    of the element's points about the axis (inside the element) down past
    its lowest point by the stretch that brings that ``depth`` below the base
    (as :func:`rooted_elements` estimates it) times each of ``steps``. Its
    radius is ``radius`` times the spread of the element's points across
    ``d``. The axis is tried through the element's centre across ``d``, then
    half way from there to each of its lowest points (up to ``candidates``
    in all); a post is kept if it crosses the base and its own element and
    no other element (exact tests). The element keeps its shape and place.
    An element flatter than ``flat`` (its smallest principal spread over its
    largest: a scale the map squashed to a sheet) gets no post.

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
        Tile points and quads of every vertex (``mapped.vertices`` is not used).
    X : numpy.ndarray, (N, 3) float64
        Current positions of the mapped vertices.
    label : numpy.ndarray, (M,) int64
        Element of every face of ``mapped.faces``.
    elements : array_like of int
        Floating elements.
    depth : float
        World depth below the base the post reaches (as in
        :func:`rooted_elements`).
    steps : sequence of float
        Multiples of the estimated stretch tried for the post's length.
    radius : float
        Post radius over the spread of the element's points across ``d``.
    flat : float
        Smallest ratio of the element's least to its largest singular value
        (of its centred points) that gets a post.
    sides : int
        Sides of every post.
    candidates : int
        Axes tried per element.

    Returns
    -------
    posts_vertices : numpy.ndarray, (a, 3) float64
    posts_faces : numpy.ndarray, (b, 3) int64
        The posts, each a closed solid (vertex numbers from 0).
    propped : numpy.ndarray, (p,) int64
        The element every post stands, in post order.
    still_floating : numpy.ndarray, (k,) int64
    """
    G = mapped.faces
    todo = np.unique(np.asarray(elements, dtype=np.int64))
    none = (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64))
    if todo.size == 0:
        return none + (todo,)
    V0, F0 = shell.base_vertices, shell.base_faces
    boxes = _seating_boxes(shell, X, G, label)
    _, _, _, _, order, starts = boxes
    rows = [order[starts[e]:starts[e + 1]] for e in todo]
    verts = [np.unique(G[r]) for r in rows]
    d, reach, _ = _root_reach(shell, mapped, X, verts, depth)
    PV, PF, propped, left = [], [], [], []
    n_post = 0
    for j, e in enumerate(todo):
        P = X[verts[j]]
        # a frame (e1, e2, d) about the element's centre
        e1 = np.cross(d[j], np.eye(3)[int(np.argmin(np.abs(d[j])))])
        e1 /= np.linalg.norm(e1)
        frame = np.stack([e1, np.cross(d[j], e1), d[j]])
        o = P.mean(axis=0)
        sv = np.linalg.svd(P - o, compute_uv=False)
        if not sv[2] >= float(flat) * sv[0]:
            # a sheet (a scale the map squashed flat): a post's top inside it
            # lies in near-coincident faces, which the union turns into needles
            left.append(e)
            continue
        L = (P - o) @ frame.T
        r = float(radius) * float(np.sqrt((L[:, :2] ** 2).sum(axis=1).mean()))
        lowest = np.argsort(L[:, 2], kind="stable")[:max(int(candidates) - 1, 0)]
        axes = np.vstack([np.zeros((1, 2)), 0.5 * L[lowest, :2]])
        done = False
        for c in axes:
            about = ((L[:, :2] - c) ** 2).sum(axis=1) <= (2.0 * r) ** 2
            if not r > 0 or not about.any():
                continue
            top = float(L[about, 2].mean())
            for s in steps:
                bottom = float(L[:, 2].min()) - float(s) * float(reach[j])
                Pp, Fp = _post(c, r, top, bottom, sides, 4)
                Xp = o + Pp @ frame
                met, folded = _crossings_near(Xp, Fp, e, X, G, boxes, V0, F0)
                if folded or not (met.size == 1 and met[0] == 1):
                    continue
                own, _ = _crossing_parts([(Xp, Fp), (X, G[rows[j]])], 0)
                if own.size == 0:
                    continue
                PV.append(Xp)
                PF.append(Fp + n_post)
                n_post += len(Xp)
                propped.append(e)
                done = True
                break
            if done:
                break
        if not done:
            left.append(e)
    if not PV:
        return none + (np.asarray(left, dtype=np.int64),)
    return (np.vstack(PV), np.vstack(PF), np.asarray(propped, dtype=np.int64),
            np.asarray(left, dtype=np.int64))


def _blurred_map(shell, quads: np.ndarray, uv: np.ndarray, radius: float, rings: int = 2
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Base point and unit offset direction averaged over a disc of the tile.

    The disc (centre, then ``rings`` rings of 6, 12, ... points) of ``radius``
    tile units about every point is clamped into its quad, located on the
    fitted surface, and the base points and offset directions are averaged.
    """
    pc = shell.polycube
    offs = [np.zeros((1, 2))]
    for k in range(1, rings + 1):
        a = 2.0 * np.pi * np.arange(6 * k) / (6 * k)
        offs.append((k / rings) * np.stack([np.cos(a), np.sin(a)], axis=1))
    offs = radius * np.vstack(offs)
    n, s = len(uv), len(offs)
    pts = np.clip((uv[:, None, :] + offs[None, :, :]).reshape(-1, 2), 0.0, 1.0)
    face, bary = pc.locate(np.repeat(quads, s), pts)
    YD = interpolated(np.hstack([pc.Y, shell.D]), pc.F, face, bary).reshape(n, s, 6).mean(axis=1)
    d = YD[:, 3:]
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    return YD[:, :3], d


def remapped_folds(shell, mapped, X: np.ndarray, label: np.ndarray, folded, *, scale: float,
                   depth_scale: float, radii=REMAP_RADII, heights=REMAP_HEIGHTS,
                   reach=REMAP_REACH) -> tuple[np.ndarray, np.ndarray]:
    """Lay the folded stretch of each folded element back on a smoothed map.

    Where the fitted surface itself folds (its sub-grid triangles turn over
    at an irregular polycube corner), a strand or ring lying on it folds too,
    and smoothing the element cannot undo that. Here every mapped point (of
    any element) in the quad of a folded element's crossing faces is mapped
    again through the map averaged over a disc of radius ``r`` tile units
    (``x = mean y + w mean d``), blended in over ``2 r`` about the crossing
    faces (weight 1 within ``r``, smooth to 0 at ``2 r``), for each ``r`` of
    ``radii`` in turn: the folded element's points alone first, then all of
    them, so that linked neighbours move with it and stay apart. The first
    result in which no moved face crosses any face (exact test, local) is
    kept. If none is, the largest
    disc is tried again with the height there lowered by each factor of
    ``heights`` (where the offset directions converge over a concave region
    a ring folds near its top, not on the surface). Last, for each distance
    ``a`` of ``reach`` (tiles), all of these are tried on every point within
    ``2 a`` of the crossing points in space of the element and of the
    elements whose faces reach into its box, weighted by that distance (1
    within ``a``): a folded chain-mail ring at a crumpled quad of Spot
    (sub-grid normals 72 degrees apart) cut the rings linked through it that
    reach into the next quads, which the moves within its quad left where
    they were. A folded element that crosses nothing of its own when its
    turn comes, because a kept move of an earlier one moved its points
    (elements folded in the same quad), counts as laid back; so does one
    whose tries failed but which a later one's kept move carried along
    until its own faces cross nothing.

    Parameters
    ----------
    shell : Shell
    mapped : MappedTiles
        Tile points, quads and elements of every vertex.
    X : numpy.ndarray, (N, 3) float64
        Current positions.
    label : numpy.ndarray, (M,) int64
        Element of every face of ``mapped.faces``.
    folded : array_like of int
    scale, depth_scale : float
        As in :func:`~geotex.mapping.place.shell_positions`.
    radii : sequence of float
        Disc radii tried, tile units.
    heights : sequence of float
        Height factors tried with the largest disc.
    reach : sequence of float
        Distances (tile sides) of the last, neighbourhood-wide tries.

    Returns
    -------
    X : numpy.ndarray, (N, 3) float64
    still_folded : numpy.ndarray, (k,) int64
    """
    X_given = np.asarray(X, dtype=np.float64)
    X = np.array(X_given, copy=True)
    G = mapped.faces
    todo = np.unique(np.asarray(folded, dtype=np.int64))
    if todo.size == 0:
        return X, todo
    n_el = int(label.max()) + 1
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(n_el + 1))
    vel = mapped.element
    # points moved by a kept move (an element laid back moves its neighbours
    # in the quad too, so a later folded element may already be unfolded)
    shifted = np.zeros(X.shape[0], dtype=bool)
    uvw_all, quad_all = mapped.tile_points, mapped.quads
    w_all = np.where(uvw_all[:, 2] < 0, uvw_all[:, 2] * float(depth_scale),
                     uvw_all[:, 2] * float(scale))
    fbox = list(_face_boxes(X, G))
    trials = [(float(r), 1.0) for r in radii] + [(float(radii[-1]), float(f)) for f in heights]
    left, crossed = [], []
    for e in todo:
        faces = G[order[starts[e]:starts[e + 1]]]
        verts, local = np.unique(faces, return_inverse=True)
        local = local.reshape(-1, 3)
        pairs = _own_crossings(X[verts], local)
        seed = verts[np.unique(local[pairs.ravel()].ravel())]
        if seed.size == 0:
            # it crosses nothing of its own. Laid back already if a kept move of an
            # earlier element moved its points and it crossed itself as given (two
            # strands folded in one quad at Spot's horn: the first one's move
            # unfolds the second, every moved face tested); otherwise the contact
            # test counted it folded on the whole layout (e.g. by a face it shares
            # with no other element's numbering): nothing to lay back here, it
            # stays as it was judged
            if not (shifted[verts].any() and _own_crossings(X_given[verts], local).size):
                left.append(e)
            continue
        seed_quads = np.unique(quad_all[seed])
        region = np.flatnonzero(np.isin(quad_all, seed_quads))
        # distance (tile units, same quad only) to the nearest crossing point
        dist = np.full(region.size, np.inf)
        for q in seed_quads:
            sq = seed[quad_all[seed] == q]
            inq = np.flatnonzero(quad_all[region] == q)
            diff = uvw_all[region[inq], None, :2] - uvw_all[None, sq, :2]
            dist[inq] = np.sqrt((diff ** 2).sum(axis=2)).min(axis=1)
        # every face a move can reach: the quads' points move by less than a tile
        pool = _pool(X, G, fbox, region, 2.0 * float(shell.tile_size))
        done = False
        # the folded element alone first, then with its neighbours in the quad,
        # then every element about it, blended by the distance in space
        # (linked rings reaching into the quads around it move with it)
        stages = [(True, None), (False, None)] + [(False, float(a)) for a in reach]
        for alone, world in stages:
            if world is not None:
                R = world * float(shell.tile_size)
                dw, _ = cKDTree(X[seed]).query(X, distance_upper_bound=2.0 * R)
                # the element and those whose faces reach into its box (the rings
                # linked through it); the others stay where they are
                Pe = X[faces]
                mates = np.unique(label[_overlapping(fbox[0], fbox[1], Pe.min(axis=(0, 1)),
                                                     Pe.max(axis=(0, 1)))])
                near = np.flatnonzero(np.isfinite(dw) & np.isin(vel, mates))
                wpool = _pool(X, G, fbox, near, 2.0 * float(shell.tile_size))
            for r, f in trials:
                if world is None:
                    rg, t, pl = region, np.clip((2.0 * r - dist) / r, 0.0, 1.0), pool
                else:
                    rg, t, pl = near, np.clip((2.0 * R - dw[near]) / R, 0.0, 1.0), wpool
                t = t * t * (3.0 - 2.0 * t)
                keep = (t > 0) & ((vel[rg] == e) if alone else True)
                mv, tm = rg[keep], t[keep]
                y, d = _blurred_map(shell, quad_all[mv], uvw_all[mv, :2], r)
                # the height lowered by f where the map is laid back (1: kept)
                wl = w_all[mv] * (1.0 - tm * (1.0 - f))
                # tried in place, put back if the move crosses anything
                before = X[mv]
                X[mv] = before + tm[:, None] * (y + wl[:, None] * d - before)
                if not _clean_move(X, G, mv, fbox, pl):
                    X[mv] = before
                    continue
                shifted[mv] = True
                at = np.zeros(X.shape[0], dtype=bool)
                at[mv] = True
                changed = np.flatnonzero(at[G].any(axis=1))
                Pm = X[G[changed]]
                fbox[0][changed], fbox[1][changed] = Pm.min(axis=1), Pm.max(axis=1)
                done = True
                break
            if done:
                break
        if not done:
            left.append(e)
            crossed.append(e)
    # a folded element no try laid back may have been laid back with a later
    # one's neighbours (every point of the quads moves, each move clean by the
    # exact test): a weave loop on Blub
    if crossed:
        again = {e for e in crossed
                 if _own_crossings(*compacted(X, G[order[starts[e]:starts[e + 1]]])).size == 0}
        left = [e for e in left if e not in again]
    return X, np.asarray(left, dtype=np.int64)
