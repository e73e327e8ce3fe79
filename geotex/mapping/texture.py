"""The main job: a tile set laid over a shell, united with its base, checked.

``textured_solid(shell, tiles)`` colours the polycube's quad edges at random
within each axis class, picks the matching tile for every quad, maps and welds
the tile geometry into the shell (:mod:`~geotex.mapping.place`), unites the
closed elements with the base solid (:mod:`~geotex.mapping.union`) and runs
the printability check on the result. Where the own local union is used
(``union="own"``, or ``"auto"``, the default, where the elements that meet
nothing are most of the work; :mod:`~geotex.mapping.crossing`), that check is
its guard: a result it rejects is redone by manifold3d's boolean of the same
operands.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from geotex.check.report import CHECK_STAGES, CheckReport
from geotex.errors import GeotexError, InputError
from geotex.mapping.assign import edge_colors, tiles_for_quads
from geotex.mapping.place import MappedTiles, depth_scale, mapped_tiles, reseated_elements
from geotex.mapping.seat import (floating_elements, lowered_elements, propped_elements,
                                 remapped_folds, rooted_elements, smoothed_folds,
                                 stood_elements)
from geotex.mapping.shape import map_jacobian
from geotex.mapping.union import (UNION_METHODS, UNION_STAGES, ElementContacts,
                                  element_contacts, united_with_base)
from geotex.mesh.topology import face_components
from geotex.param.polycube_fit import SurfaceProjector
from geotex.printing.stored import printable_stored_solid
from geotex.progress import report
from geotex.tiles.directional import oriented_tileset

__all__ = ["TexturedSolid", "TextureStats", "textured_solid", "MAP_STAGES", "MAP_PROGRESS",
           "texture_height"]

MAP_STAGES = ("assign", "map", "union", "validate")

#: Everything the ``progress`` callback of :func:`textured_solid` is called
#: with, in order (the stages and their steps); a retried union repeats steps.
MAP_PROGRESS = ("assign", "map", "union") + UNION_STAGES + ("validate", "float32") \
    + CHECK_STAGES

#: Depth (in tiles) the elements are anchored below the surface (see
#: :func:`~geotex.mapping.place.mapped_tiles`).
ANCHOR = 0.2

#: Unions redone without the elements next to defects the check found.
RETRIES = 2

#: ``max_examples`` that keeps every defect the check finds (to locate them).
ALL_DEFECTS = 1 << 40


@dataclass(frozen=True, kw_only=True)
class TextureStats:
    """Counts and timings of one :func:`textured_solid` run.

    Attributes
    ----------
    quads, bare_quads : int
        Quads of the shell, and those left bare (their map folds).
    height : float
        World height of the texture, mm.
    seed : int
        Seed of the edge colouring.
    mapped_vertices, mapped_faces : int
        Size of the tile geometry mapped into the shell.
    welded : int
        Vertices welded across tile sides.
    open_faces_dropped : int
        Faces of open pieces dropped after the map.
    elements, union_operands : int
        Closed elements united with the base, and the union's operand groups.
    elements_floating, elements_folded : int
        Elements left out: not reaching the base, folded by the shell map.
    elements_reseated : int
        Folded elements shrunk in place, or smoothed over the folded stretch,
        that then fit.
    elements_lowered, elements_propped : int
        Floating elements lowered onto the base (strands, rings) or whose
        roots were extended into it (shaped elements), or stood on it with a post
        (strands and rings on a post in the tile frame, shaped elements on one
        along their offset direction; :mod:`~geotex.mapping.seat`).
    cavities_filled : int
        Closed voids between elements and the base that the union's result
        enclosed, filled (not counted as floating elements).
    union_retries : int
        Unions redone without the elements next to defects.
    union_method : str
        The union that made the result: ``"own"`` (the local union of
        :mod:`~geotex.mapping.crossing`) or ``"boolean"`` (manifold3d).
    union_fallbacks : int
        Own unions replaced by the boolean: one that could not unite every
        element, one whose result the check rejected.
    float32_collapsed_faces, elements_left_out_at_defects : int or None
        Faces collapsed by the float32 rounding, and elements left out at
        defects (None when the result was not checked).
    vertices, faces : int
        Size of the result.
    seconds : dict of str -> float
        Seconds per stage of :data:`MAP_STAGES` that ran (rounded to 1 ms).
    """

    quads: int
    bare_quads: int
    height: float
    seed: int
    mapped_vertices: int
    mapped_faces: int
    welded: int
    open_faces_dropped: int
    elements: int
    union_operands: int
    elements_floating: int
    elements_folded: int
    elements_reseated: int
    union_retries: int
    elements_lowered: int = 0
    elements_propped: int = 0
    cavities_filled: int = 0
    union_method: str = "boolean"
    union_fallbacks: int = 0
    float32_collapsed_faces: int | None = None
    elements_left_out_at_defects: int | None = None
    vertices: int
    faces: int
    seconds: dict

    def to_dict(self) -> dict:
        """The stats as a JSON-ready dict, in field order (unchecked runs lack the
        two check-only counts)."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        for k in ("float32_collapsed_faces", "elements_left_out_at_defects"):
            if out[k] is None:
                del out[k]
        out["seconds"] = dict(self.seconds)
        return out


@dataclass(frozen=True)
class TexturedSolid:
    """A base with a geometric texture, as one solid.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
    faces : numpy.ndarray, (m, 3) int64
    tile_of_quad : numpy.ndarray, (q,) int64
        Tile chosen for every quad (``-1``: left bare, its map folds).
    report : CheckReport or None
        Validity report of the solid as a file stores it (None when not
        checked): the vertices are then float32 values, so STL and 3MF store
        exactly the judged coordinates.
    stats : TextureStats
        Counts and timings of every stage.
    elements : MappedTiles or None
        With ``keep_elements``: the mapped elements as the job ends them
        (re-seated, lowered or rooted; before the union, without posts),
        numbered by ``elements.element``.
    left_out : numpy.ndarray, (e,) bool, or None
        With ``keep_elements``: elements of ``elements`` left out of the
        union (still folded, or at defects) or found floating with no seat
        (the union drops those that no neighbour holds:
        ``stats.elements_floating``).
    """

    vertices: np.ndarray
    faces: np.ndarray
    tile_of_quad: np.ndarray
    report: CheckReport | None
    stats: TextureStats
    elements: MappedTiles | None = None
    left_out: np.ndarray | None = None


def texture_height(shell, tiles, height=None) -> float:
    """World height of the texture's top: given, or the tile's own proportions.

    Without ``height`` the tile keeps its proportions (``tiles.height`` tile
    units times the tile size), lowered to the shell's safe ``max_height``.

    Raises
    ------
    InputError
        ``height`` not positive or above the shell's ``max_height``.
    GeotexError
        The shell's safe height is zero.
    """
    if not shell.max_height > 0:
        raise GeotexError(f"shell {shell.name!r} has no room for a texture: its offset surface "
                          "crosses itself at any height (a fold or a gap narrower than the "
                          "offset); rebuild the shell with a smaller tile size")
    if height is None:
        return float(min(tiles.height * shell.tile_size, shell.max_height))
    try:
        h = float(height)
    except (TypeError, ValueError):
        raise InputError(f"height must be a positive number, got {height!r}") from None
    if not np.isfinite(h) or h <= 0:
        raise InputError(f"height must be a positive number, got {height!r}")
    if h > shell.max_height * (1 + 1e-12):
        raise InputError(f"height {h:g} is above the shell's safe height "
                         f"{shell.max_height:.4g} (taller texture would intersect itself); "
                         "use a smaller height or a larger tile size")
    return h


def _defect_points(V, F, rep) -> np.ndarray:
    """Positions of the defects a report lists: crossing, degenerate and non-manifold."""
    ex = rep.examples
    faces = [np.asarray(ex.get("self_intersecting_pairs", []), dtype=np.int64).ravel(),
             np.asarray(ex.get("degenerate_faces", []), dtype=np.int64)]
    pts = [V[F[f]].mean(axis=1) for f in faces if f.size]
    for key in ("non_manifold_edges", "boundary_edges", "inconsistent_edges"):
        e = np.asarray(ex.get(key, []), dtype=np.int64).reshape(-1, 2)
        if e.size:
            pts.append(V[e].mean(axis=1))
    nmv = np.asarray(ex.get("non_manifold_vertices", []), dtype=np.int64)
    if nmv.size:
        pts.append(V[nmv])
    return np.vstack(pts) if pts else np.zeros((0, 3))


def _elements_near(points, X, G, exclude=None) -> np.ndarray:
    """Elements of ``(X, G)`` with a vertex among the 4 nearest to each point."""
    # lazy: scipy.spatial takes ~0.1 s to import
    from scipy.spatial import cKDTree

    n_el, label = face_components(G, X.shape[0])
    out = np.zeros(n_el, dtype=bool) if exclude is None else exclude.copy()
    if len(points) == 0:
        return out
    vlab = np.full(X.shape[0], -1, dtype=np.int64)
    vlab[G.ravel()] = np.repeat(label, 3)
    used = np.flatnonzero(vlab >= 0)
    _, nearest = cKDTree(X[used]).query(points, k=4)
    out[vlab[used[np.asarray(nearest).ravel()]]] = True
    return out


def textured_solid(shell, tiles, *, height=None, seed: int = 0, check: bool = True,
                   shaped: bool | None = None, union: str = "auto", progress=None,
                   on_stored=None, keep_elements: bool = False) -> TexturedSolid:
    """Lay ``tiles`` over ``shell`` and unite them with its base.

    Parameters
    ----------
    shell : Shell
    tiles : TileSet
        A complete or isotropic set (a planar set has no tiles for vertical
        quad edges).
    height : float, optional
        World height of the texture (see :func:`texture_height`).
    seed : int, optional
        Seed of the random edge colouring: same inputs and seed, same bytes.
    check : bool, optional
        Round the result to float32 (what an STL stores), collapse the slivers
        the rounding breaks and run the full validity check on it.
    shaped : bool, optional
        Map every small element as one shape similar to its tile shape, of
        one size (:func:`~geotex.mapping.shape.shaped_positions`); False maps
        tile points one by one through the quad map (elements then take the
        quads' shapes and sizes). Default: the set's
        ``metadata["shell_map"]`` (``"plain"`` or ``"shaped"``); without it,
        plain for lattice sets (``metadata["lattice"]``, e.g. knurl: elements
        packed edge to edge, whose lattice stays closed only if they follow
        the quads) and for periodic sets (``metadata["periodic"]``: the linked
        rings of chain mail and the strands of weave interlock, and shaped
        rings of one size, moved one by one, cut into their neighbours where
        the quads are squashed: on Spot the union then fused them and took
        about three times as long), shaped for the others.
    union : {"auto", "own", "boolean"}, optional
        How the elements are united with the base
        (:func:`~geotex.mapping.union.united_with_base`). The own local union
        is used only with ``check``, whose exact test of the stored
        coordinates is its guard: a result the check rejects is united again
        by manifold3d's boolean of the same operands (nothing left out)
        before elements next to defects are left out. Without ``check``,
        ``"auto"`` is the boolean. The default is ``"auto"``: with the
        diagonals of its pieces flipped within their faces and its needles
        collapsed up to :data:`~geotex.mapping.union.OWN_DART_LENGTH` times
        the sliver tolerance, the check accepted the own union on every row
        of the main job's benchmark and the catalog shells (18 rows, no
        fallback; ``benchmarks/results/union_own.md``).
    progress : callable, optional
        Called with each stage and step of :data:`MAP_PROGRESS` (the times in
        ``stats.seconds`` are per stage of :data:`MAP_STAGES`).
    on_stored : callable, optional
        With ``check``: called with the float32-exact arrays ``(V, F)`` each
        time the check is about to judge them (a retried union calls it
        again); the result holds the arrays of the last call. The CLI passes
        a :class:`geotex.printing.StagedWrite`, so the STL is written while
        it is judged.
    keep_elements : bool, optional
        Also return the elements as the job ends them and which were left out
        (``TexturedSolid.elements`` and ``left_out``; what
        ``benchmarks/bench_shell_shape.py`` measures).

    Returns
    -------
    TexturedSolid

    Raises
    ------
    InputError
        Planar tile set, bad height, seed or union.
    GeotexError
        manifold3d rejects the base or the elements.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed!r}")
    if union not in UNION_METHODS:
        raise InputError(f"union must be one of {', '.join(UNION_METHODS)}, got {union!r}")
    if not check and union == "auto":
        union = "boolean"       # the own union's guard is the check
    h = texture_height(shell, tiles, height)
    if tiles.directional:
        tiles = oriented_tileset(tiles)     # a directional base set, turned to its flow
    if shaped is None:
        packed = any(tiles.metadata.get(k) is not None for k in ("lattice", "periodic"))
        shaped = tiles.metadata.get("shell_map", "plain" if packed else "shaped") != "plain"
    pc = shell.polycube
    times = {}
    t0 = time.perf_counter()
    report(progress, "assign")
    colors = edge_colors(pc.layout.edge_axis, tiles.n_colors, seed=int(seed))
    tile_of_quad = tiles_for_quads(tiles, pc.layout.quad_axes, pc.layout.quad_edge, colors,
                                   bare=pc.quad_folded)
    times["assign"] = time.perf_counter() - t0
    report(progress, "map")
    t = time.perf_counter()
    scale = h / tiles.height
    # closest points on the fitted surface and the map's Jacobian: built once for
    # the map and the re-seating
    projector = SurfaceProjector(pc.Y, pc.F) if shaped else None
    jacobian = map_jacobian(pc) if shaped else None
    mapped = mapped_tiles(shell, tiles, tile_of_quad, scale=scale,
                          anchor=ANCHOR * shell.tile_size, shaped=shaped, projector=projector,
                          jacobian=jacobian)
    times["map"] = time.perf_counter() - t
    report(progress, "union")
    t = time.perf_counter()
    # elements the map folds onto themselves are shrunk in place where that
    # helps, else laid back on a locally smoothed map with their neighbours,
    # else smoothed over the folded stretch (strands, rings)
    # (the map numbers its elements as face_components would: no second labelling)
    contacts = element_contacts(mapped.vertices, mapped.faces,
                                label=mapped.element[mapped.faces[:, 0]])
    folded = contacts.folded
    below = depth_scale(tiles, scale, ANCHOR * shell.tile_size)
    X, still = reseated_elements(shell, mapped, contacts.label, folded, scale=scale,
                                 depth_scale=below, projector=projector, jacobian=jacobian)
    # shrunk elements may now meet others: the union judges them by their boxes
    moved = np.setdiff1d(folded, still)
    # strands and rings follow the point-by-point map (periodic and lattice sets):
    # they are re-seated rather than dropped. Shaped elements (studs, scales) keep
    # their one shape and size: one still folded after shrinking and smoothing is
    # left out, one floating gets a longer root below (remapping studs point by
    # point and standing floating ones on posts cost 1-2 s more at ~400k)
    reseat = not mapped.shaped
    if reseat:
        X, still = remapped_folds(shell, mapped, X, contacts.label, still, scale=scale,
                                  depth_scale=below)
        X, still = smoothed_folds(X, mapped.faces, contacts.label, still)
    mapped = dataclasses.replace(mapped, vertices=X)
    # the remapped and smoothed ones (and the neighbours moved with them) were
    # kept only where the exact test found them crossing nothing: no contacts
    # to add, and a strand loop's box, overlapping most elements, would split
    # the union into many operands
    contacts = contacts._replace(folded=np.union1d(moved, still))
    # elements that would float are lowered onto the base, or stood on it
    # (strands, rings), or their roots are extended into it or they are stood
    # on a post along their offset direction (shaped elements keep their
    # shape above the surface). A moved element's contacts found before the
    # move no longer hold: it is not held up by them
    n_el = int(contacts.label.max()) + 1 if contacts.label.size else 0
    usable = np.ones(n_el, dtype=bool)
    usable[still] = False
    stale = np.isin(contacts.touching, moved).any(axis=1)
    floating = floating_elements(shell.base_vertices, shell.base_faces, X, mapped.faces,
                                 label=contacts.label, touching=contacts.touching[~stale],
                                 usable=usable, heights=mapped.tile_points[:, 2])
    if reseat:
        X, unseated = lowered_elements(shell, mapped, contacts.label, floating, scale=scale,
                                       depth_scale=below, depth=tiles.depth)
    else:
        X, unseated, met = rooted_elements(shell, mapped, X, contacts.label, floating,
                                           depth=tiles.depth * below)
        if met.size:                # roots that reach a neighbour's: united together
            touching = np.unique(np.vstack([contacts.touching, met]), axis=0)
            contacts = contacts._replace(touching=touching)
    lowered = np.setdiff1d(floating, unseated)
    if reseat:
        PV, PF, propped, _ = propped_elements(shell, mapped, X, contacts.label, unseated,
                                              scale=scale, depth_scale=below, depth=tiles.depth)
    else:
        # a shaped element no root seats (its stretched root crosses itself:
        # 9 of Blub's 22 floating scales, thin or shrunk ones in its concave
        # creases) is stood on a post along its offset direction, keeping its
        # shape and place
        PV, PF, propped, _ = stood_elements(shell, mapped, X, contacts.label, unseated,
                                            depth=tiles.depth * below)
    # (lowered elements and posts were kept only where they cross nothing else)
    mapped = dataclasses.replace(mapped, vertices=X)
    G = mapped.faces
    if propped.size:
        # every post is an element of its own that meets the one it props
        n_post = propped.size
        post_label = n_el + np.repeat(np.arange(n_post), len(PF) // n_post)
        X = np.vstack([X, PV])
        G = np.vstack([G, PF + len(mapped.vertices)])
        touching = np.vstack([contacts.touching,
                              np.stack([propped, n_el + np.arange(n_post)], axis=1)])
        order = np.lexsort((touching[:, 1], touching[:, 0]))
        contacts = ElementContacts(np.concatenate([contacts.label, post_label]),
                                   contacts.folded, touching[order])
    V, F, united = united_with_base(shell.base_vertices, shell.base_faces, X, G,
                                    contacts=contacts, moved=moved, union=union,
                                    progress=progress)
    fallbacks = united.fallbacks
    times["union"] = time.perf_counter() - t
    rep = None
    exclude = None
    retried = 0
    cleanup = {}
    if check:
        report(progress, "validate")
        t = time.perf_counter()
        # judged as an STL stores it (float32; every other format stores these
        # values exactly); rebuilt by manifold3d only if the rounding broke it.
        # The union's own cleanup (needle_free) keeps that rare, and manifold3d's
        # verdict, a subset of the check's, is not asked again
        report(progress, "float32")
        solid = printable_stored_solid(V, F, precision=np.float32, manifold3d=False,
                                       max_examples=ALL_DEFECTS, progress=progress,
                                       on_stored=on_stored)
        if not solid.report.printable and united.method == "own":
            # the check is the own union's guard: the boolean of the same
            # operands (nothing left out) replaces a result it rejects
            fallbacks += 1
            V, F, united = united_with_base(shell.base_vertices, shell.base_faces, X, G,
                                            contacts=contacts, moved=moved, union="boolean",
                                            progress=progress)
            solid = printable_stored_solid(V, F, precision=np.float32, manifold3d=False,
                                           max_examples=ALL_DEFECTS, progress=progress,
                                           on_stored=on_stored)
        # the boolean can leave needle faces where an element grazes the base
        # or a neighbour; leave the elements there out and unite again
        while not solid.report.printable and retried < RETRIES:
            points = _defect_points(solid.vertices, solid.faces, solid.report)
            if len(points) == 0:
                break
            exclude = _elements_near(points, X, G, exclude)
            V, F, united = united_with_base(shell.base_vertices, shell.base_faces,
                                            X, G, exclude=exclude, contacts=contacts,
                                            moved=moved, union="boolean", progress=progress)
            solid = printable_stored_solid(V, F, precision=np.float32, manifold3d=False,
                                           max_examples=ALL_DEFECTS, progress=progress,
                                           on_stored=on_stored)
            retried += 1
        V, F = solid.vertices, solid.faces
        rep = dataclasses.replace(solid.report, examples={
            k: v[:5] for k, v in solid.report.examples.items()})
        cleanup = {"float32_collapsed_faces": solid.collapsed_faces,
                   "elements_left_out_at_defects": int(exclude.sum()) if exclude is not None
                   else 0}
        times["validate"] = time.perf_counter() - t
    stats = TextureStats(
        quads=pc.layout.n_quads, bare_quads=int((tile_of_quad < 0).sum()), height=h, seed=int(seed),
        mapped_vertices=int(X.shape[0]), mapped_faces=int(G.shape[0]),
        welded=mapped.welded, open_faces_dropped=mapped.dropped_faces,
        elements=united.elements, union_operands=united.groups,
        elements_floating=united.floating, elements_folded=united.folded,
        elements_reseated=int(folded.size - still.size), union_retries=retried,
        elements_lowered=int(lowered.size), elements_propped=int(propped.size),
        cavities_filled=united.cavities, union_method=united.method,
        union_fallbacks=fallbacks, **cleanup,
        vertices=int(V.shape[0]), faces=int(F.shape[0]),
        seconds={k: round(v, 3) for k, v in times.items()})
    if not keep_elements:
        return TexturedSolid(V, F, tile_of_quad, rep, stats)
    left_out = np.zeros(n_el, dtype=bool)
    left_out[still] = True
    left_out[np.setdiff1d(unseated, propped)] = True
    if exclude is not None:
        left_out |= exclude[:n_el]
    return TexturedSolid(V, F, tile_of_quad, rep, stats, mapped, left_out)
