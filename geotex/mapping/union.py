"""Union of mapped texture elements with the base solid (manifold3d).

Mapped elements are closed, but the shell map can bend neighbours into each
other where it is strongly distorted. manifold3d unites any number of
operands correctly as long as each operand is free of self-intersection. One
exact self-intersection test of all elements finds the elements the map folds
onto themselves (left out) and the few pairs that meet. Those few are
coloured into groups of pairwise separate ones and united among themselves in
a small boolean; every other element meets nothing, so all of them and that
small union form one operand without any boolean, and one boolean adds it to
the base (each extra operand of a batch boolean is another pass over the
whole result).
Pieces of the result that are not part of the body (elements that float above
a concave base) are left out, so the print is one solid.

Where the elements that meet nothing are most of the work, the last boolean
is replaced by the own local union (:func:`~geotex.mapping.crossing.crossing_union`:
faces cut along their crossings with the base, no boolean): the base united
with the meeting elements' groups is its base, the lone elements its
elements (``union="auto"``, rules :data:`OWN_SHARE` and
:data:`OWN_ELEMENTS_PER_BASE_FACE`). It has no guard of its
own: the main job's exact check of the written coordinates is its guard, and
:func:`~geotex.mapping.texture.textured_solid` redoes a union that fails it by
the boolean (``benchmarks/results/union_own.md``).

The boolean's time is the element-base intersections, not the triangle count:
cutting elements in tile space and sending only their bottoms with a lid
through it was measured and does not pay (``benchmarks/bench_union_split.py``,
``benchmarks/results/union_split.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import manifold3d
import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import GeotexError, InputError
from geotex.mapping.crossing import crossing_union
from geotex.mesh.geometry import component_volumes, group_boxes
from geotex.mesh.needles import SLIVER_TOLERANCE, needle_free
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.mesh.topology import compacted, concatenated, face_components, greedy_colouring
from geotex.progress import report

__all__ = ["united_with_base", "element_contacts", "ElementContacts", "element_groups",
           "element_pairs",
           "UnionStats", "SLIVER_TOLERANCE", "UNION_STAGES", "UNION_METHODS", "OWN_SHARE",
           "OWN_ELEMENTS_PER_BASE_FACE", "OWN_DART_LENGTH", "OWN_NEEDLE_ROUNDS"]

#: Stage names passed to the ``progress`` callback of :func:`united_with_base`.
UNION_STAGES = ("union: folded elements", "union: boolean", "union: slivers")

#: Values of ``union`` in :func:`united_with_base`.
UNION_METHODS = ("auto", "own", "boolean")

#: ``union="auto"`` uses the own local union when the elements that meet
#: nothing have at least this many faces per face of the rest (the base and
#: the elements that meet another): its cost grows with every face of both
#: operands, the boolean's with the crossings (``benchmarks/results/union_own.md``).
OWN_SHARE = 1.0

#: ... and at most this many lone elements per base face: a base face that
#: many elements cross is split into one polygon with many holes. Before its
#: pieces' diagonals were flipped, their ear-clipped slivers folded in the
#: float32 rounding at 1.8 per face (the Spot catalog shell with studs); with
#: the flips the check accepted the own union at 1.8 (catalog Spot), 2.4
#: (``geotex demo``: 0.3-0.8 s less CPU than the boolean) and 4.1 per face
#: (49 spheres on a 12-face box, tests/test_union_own.py); at 6.8 per face one
#: element had no proved sign and the whole union went to the boolean.
OWN_ELEMENTS_PER_BASE_FACE = 5.0

#: The own union's result loses needles whose shortest edge is below this many
#: times the sliver tolerance by collapsing that edge (the boolean's: below the
#: tolerance itself). Its cut points come as close together as the crossings
#: of the surfaces do (an element edge through a base face next to where a
#: base edge crosses the element face), where manifold3d merges them. Needles
#: left (the boolean's in brackets): Spot 15k at 3.704 mm 110 at 1x, 9 at 8x
#: (27); Kitten 15k at 3.114 mm 146, 15 (15); Kitten 15k at 5.61 mm 6 at 8x,
#: 1 at 16x (5); torus catalog shell with studs 4, 1 (2). The shape moves by
#: less than 1.6e-5 of the diagonal (2 micrometres at 120 mm).
OWN_DART_LENGTH = 16.0

#: ... in up to this many rounds (a cluster of needles takes several: Kitten
#: 15k at 3.114 mm kept 47 after 8 rounds, 15 after 16).
OWN_NEEDLE_ROUNDS = 32



@dataclass(frozen=True)
class UnionStats:
    """What the union did.

    Attributes
    ----------
    elements : int
        Elements added to the base.
    groups : int
        Groups the elements were coloured into (elements within one do not
        touch; the elements of the groups after the first are united among
        themselves before the base is added).
    floating : int
        Pieces that did not reach the base and were left out.
    cavities : int
        Closed voids (inward-facing parts) between elements and the base,
        filled.
    folded : int
        Elements left out because the map folds them onto themselves.
    method : str
        The union that made the result: ``"own"`` (the local union of
        :mod:`~geotex.mapping.crossing`) or ``"boolean"`` (manifold3d).
    fallbacks : int
        1 when the own union was tried and could not unite every element
        (no proved sign, a face it could not split): the boolean made the
        result instead; else 0.
    """

    elements: int
    groups: int
    floating: int = 0
    folded: int = 0
    cavities: int = 0
    method: str = "boolean"
    fallbacks: int = 0


class ElementContacts(NamedTuple):
    """Which mapped elements cross themselves or each other (exact test).

    Attributes
    ----------
    label : numpy.ndarray, (l,) int64
        Element (connected component) of every face
        (:func:`geotex.mesh.topology.face_components`).
    folded : numpy.ndarray, (k,) int64
        Sorted elements whose own faces cross (the map folded them).
    touching : numpy.ndarray, (p, 2) int64
        Pairs ``i < j`` of distinct elements whose faces meet, sorted.
    """

    label: np.ndarray
    folded: np.ndarray
    touching: np.ndarray


def element_contacts(X: np.ndarray, G: np.ndarray, *, label=None) -> ElementContacts:
    """Elements the map folds, and pairs of elements that meet (one exact test).

    The exact test of all faces (:func:`~geotex.check.intersections.self_intersecting_pairs`)
    is given the elements as its parts: it sweeps every element and every pair
    of elements whose boxes overlap instead of a grid over the whole mesh,
    with the same answer.

    Parameters
    ----------
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64
    label : numpy.ndarray, (l,) int64, optional
        Element of every face when already known (the map numbers its
        elements as :func:`geotex.mesh.topology.face_components` does:
        ``MappedTiles.element[G[:, 0]]``); found here otherwise.

    Returns
    -------
    ElementContacts

    Raises
    ------
    InputError
        ``label`` is not one integer per face.
    """
    if label is None:
        _, label = face_components(G, X.shape[0])
    else:
        label = np.asarray(label)
        if label.shape != (G.shape[0],) or not np.issubdtype(label.dtype, np.integer):
            raise InputError(f"label must be one integer per face, shape ({G.shape[0]},), "
                             f"got {label.dtype} {label.shape}")
        label = label.astype(np.int64, copy=False)
    # elements are many small closed parts: the exact test sweeps each element
    # and each pair of elements whose boxes meet (same pairs, same predicates as
    # the test on its global grid, at about half the cost)
    pairs = self_intersecting_pairs(X, G, parts=label)
    a, b = label[pairs[:, 0]], label[pairs[:, 1]]
    same = a == b
    touching = np.unique(np.sort(np.stack([a[~same], b[~same]], axis=1), axis=1), axis=0)
    return ElementContacts(label, np.unique(a[same]), touching.reshape(-1, 2))


def element_pairs(X: np.ndarray, G: np.ndarray, *, touching=None, moved=None, label=None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of elements that must not share an operand of the union.

    Without ``touching``, every pair whose bounding boxes overlap. With it
    (from :func:`element_contacts`), the pairs that meet, and the box
    overlaps of elements that have ``moved`` since.

    Parameters
    ----------
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64
    touching : numpy.ndarray, (p, 2) int64, optional
        Pairs of elements that meet.
    moved : array_like of int, optional
        Elements moved after ``touching`` was found (their contacts are
        judged by bounding boxes).
    label : numpy.ndarray, (l,) int64, optional
        Element of every face when already known
        (:attr:`ElementContacts.label`); found here otherwise.

    Returns
    -------
    label : numpy.ndarray, (l,) int64
        Element (connected component) of every face.
    pairs : numpy.ndarray, (q, 2) int64
        Element pairs (a pair may repeat).
    """
    # lazy: scipy.spatial (~0.1 s) is slow to import
    from scipy.spatial import cKDTree

    if label is None:
        n_el, label = face_components(G, X.shape[0])
    else:
        n_el = int(label.max()) + 1 if label.size else 0
    vlab = np.full(X.shape[0], -1, dtype=np.int64)
    vlab[G[:, 0]], vlab[G[:, 1]], vlab[G[:, 2]] = label, label, label
    lo, hi = group_boxes(X, vlab, n_el)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    radius = 2.0 * float(np.linalg.norm(half, axis=1).max())
    cand = cKDTree(centre).query_pairs(radius, output_type="ndarray")
    if cand.size:
        overlap = np.all(np.abs(centre[cand[:, 0]] - centre[cand[:, 1]])
                         <= half[cand[:, 0]] + half[cand[:, 1]], axis=1)
        cand = cand[overlap]
    if touching is not None:
        was_moved = np.zeros(n_el, dtype=bool)
        if moved is not None:
            was_moved[np.asarray(moved, dtype=np.int64)] = True
        cand = np.concatenate([np.asarray(touching, dtype=np.int64).reshape(-1, 2),
                               cand[was_moved[cand].any(axis=1)]])
    return label, np.asarray(cand, dtype=np.int64).reshape(-1, 2)


def element_groups(X: np.ndarray, G: np.ndarray, *, touching=None, moved=None, label=None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Split elements into groups whose members do not meet.

    Without ``touching``, members of a group have bounding boxes that do not
    overlap. With it (from :func:`element_contacts`), only elements that
    meet, and elements whose box overlaps one that has ``moved`` since,
    are kept apart, so most elements share the first group
    (:func:`element_pairs` lists the pairs kept apart).

    Parameters
    ----------
    X, G, touching, moved, label
        As in :func:`element_pairs`.

    Returns
    -------
    element : numpy.ndarray, (l,) int64
        Element (connected component) of every face.
    group : numpy.ndarray, (n_elements,) int64
        Group of every element, ``0 .. n_groups - 1`` (greedy colouring, largest
        degree first, so deterministic).
    """
    label, pairs = element_pairs(X, G, touching=touching, moved=moved, label=label)
    n_el = int(label.max()) + 1 if label.size else 0
    return label, greedy_colouring(n_el, pairs)


def _check_elements(solids) -> None:
    """Raise if manifold3d rejects an operand built from the elements."""
    bad = [s for s in solids if s.status() != manifold3d.Error.NoError]
    if bad:
        raise GeotexError("the mapped texture elements are not closed "
                          f"({bad[0].status().name}); the tile set may be broken "
                          "(check it with 'geotex tiles check')")


def united_with_base(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray, *,
                     exclude=None, contacts: ElementContacts | None = None, moved=None,
                     union: str = "boolean", progress=None
                     ) -> tuple[np.ndarray, np.ndarray, UnionStats]:
    """One solid: the base plus every usable closed element.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Base solid (closed, outward).
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64
        Elements (each connected component closed and outward).
    exclude : numpy.ndarray, (n_elements,) bool, optional
        Elements to leave out, numbered as by
        :func:`geotex.mesh.topology.face_components` of ``G``.
    contacts : ElementContacts, optional
        Folded and touching elements (:func:`element_contacts`) when already
        known; by default they are found here.
    moved : array_like of int, optional
        Elements moved since ``contacts`` was found (re-seated); an element
        folded in ``contacts`` that is not moved is left out.
    union : {"boolean", "own", "auto"}, optional
        How the elements that meet nothing are added: by manifold3d's boolean
        (default), or by the own local union with the base united with the
        other elements (:func:`~geotex.mapping.crossing.crossing_union`; the
        boolean instead when it cannot unite every one of them), or the own
        union where they have at least :data:`OWN_SHARE` faces per face of
        the rest and are at most :data:`OWN_ELEMENTS_PER_BASE_FACE` per base
        face. The own union does not test its result for crossing
        faces: check it (:func:`~geotex.mapping.texture.textured_solid`
        does, and redoes it by the boolean when it fails).
    progress : callable, optional
        Called with each stage of :data:`UNION_STAGES`.

    Returns
    -------
    V2 : numpy.ndarray, (p, 3) float64
    F2 : numpy.ndarray, (r, 3) int64
    stats : UnionStats

    Raises
    ------
    InputError
        ``union`` is not one of :data:`UNION_METHODS`.
    GeotexError
        manifold3d rejects the base or the elements (open elements, a bug).
    """
    if union not in UNION_METHODS:
        raise InputError(f"union must be one of {', '.join(UNION_METHODS)}, got {union!r}")
    base = manifold_of(V, F)
    if base.status() != manifold3d.Error.NoError:
        raise GeotexError(f"the base is not a valid solid for manifold3d ({base.status().name});"
                          " run 'geotex repair' on it")
    if len(G) == 0:
        return np.array(V, dtype=np.float64), np.array(F, dtype=np.int64), UnionStats(0, 0, 0)
    # an element the map folded onto itself cannot be united: leave it out
    report(progress, UNION_STAGES[0])
    if contacts is None:
        contacts = element_contacts(X, G)
    moved = np.zeros(0, dtype=np.int64) if moved is None else np.asarray(moved, np.int64)
    folded = np.setdiff1d(contacts.folded, moved)
    label, pairs = element_pairs(X, G, touching=contacts.touching, moved=moved,
                                 label=contacts.label)
    n_el = int(label.max()) + 1
    usable = np.ones(n_el, dtype=bool)
    usable[folded] = False
    if exclude is not None:
        usable[np.asarray(exclude, dtype=bool)] = False
    pairs = pairs[usable[pairs].all(axis=1)]
    group = greedy_colouring(n_el, pairs)
    group[~usable] = -1
    # elements that meet another are united among themselves first, in a small
    # boolean of their groups; every other element meets nothing, so they and
    # that union are one operand as they are (no boolean), and one boolean
    # adds it to the base. Each extra operand of a batch boolean costs a pass
    # over the whole result: on Spot with studs this saves 17-20% of the boolean
    meets = np.zeros(n_el, dtype=bool)
    meets[pairs.ravel()] = True
    lone = usable & ~meets
    n_lone = int(np.count_nonzero(lone[label]))
    if union == "auto":
        rest = len(F) + int(np.count_nonzero(meets[label]))
        fine = int(lone.sum()) <= OWN_ELEMENTS_PER_BASE_FACE * len(F)
        union = "own" if n_lone > 0 and n_lone >= OWN_SHARE * rest and fine else "boolean"
    solids = []
    if meets.any():
        solids = [manifold_of(*compacted(X, G[((group == g) & meets)[label]]))
                  for g in range(int(group.max()) + 1)]
        _check_elements(solids)
    report(progress, UNION_STAGES[1])
    method, fallbacks = "boolean", 0
    if union == "own" and n_lone:
        VF = _own_union(base, solids, X, G, label, lone)
        if VF is None:
            fallbacks = 1
        else:
            method = "own"
    if method == "boolean":
        pieces = [compacted(X, G[lone[label]])]
        if solids:
            pieces.append(arrays_of_manifold(manifold3d.Manifold.batch_boolean(
                solids, manifold3d.OpType.Add)))
        solid = base
        if usable.any():
            elements = manifold_of(*concatenated(pieces))
            _check_elements([elements])
            solid = manifold3d.Manifold.batch_boolean([base, elements], manifold3d.OpType.Add)
        VF = arrays_of_manifold(solid)       # evaluated here (manifold3d is lazy)
    report(progress, UNION_STAGES[2])
    # the boolean leaves needle triangles (area ~1e-13 of the solid) where element
    # and base surfaces cross nearly tangentially; float32 rounding (STL) folds some
    # onto their neighbours. Local collapses and flips remove those lower than
    # SLIVER_TOLERANCE of the diagonal, keeping the solid closed and manifold and
    # changing the shape by less than that (manifold3d's simplify at the same
    # tolerance kept most of them, where a collapse would move a crease)
    diag = float(np.linalg.norm(np.ptp(np.vstack([V, X]), axis=0)))
    local = {}
    if method == "own":
        local = {"dart_length": OWN_DART_LENGTH * SLIVER_TOLERANCE * diag,
                 "rounds": OWN_NEEDLE_ROUNDS}
    V2, F2, _ = needle_free(*VF, tolerance=SLIVER_TOLERANCE * diag, **local)
    # elements that do not reach the base (where the fitted surface lies above a
    # concave base) would print as loose pieces: keep the body they are part of
    # (a closed void between an element and the base is a part too, facing
    # inward: dropping it fills the void, it is no element left out)
    parts, label = face_components(F2, V2.shape[0])
    floating = cavities = 0
    if parts > 1:
        body = np.argmax(np.bincount(label))
        cavities = int((component_volumes(V2, F2, label, parts) < 0).sum())
        floating = parts - 1 - cavities
        V2, F2 = compacted(V2, F2[label == body])
    return V2, F2, UnionStats(int((group >= 0).sum()) - floating, int(group.max()) + 1,
                              floating, int(folded.size), cavities, method, fallbacks)


def _own_union(base, solids, X, G, label, lone):
    """The own local union of ``base`` and ``solids`` (one boolean) with the ``lone`` elements.

    Returns the arrays ``(V, F)``, or None when it cannot unite every lone
    element (it stops before stitching; the caller uses the boolean).
    """
    if solids:
        base = manifold3d.Manifold.batch_boolean([base] + solids, manifold3d.OpType.Add)
    Vb, Fb = arrays_of_manifold(base)
    faces = lone[label]
    XA, GA = compacted(X, G[faces])
    _, element = np.unique(label[faces], return_inverse=True)
    try:
        r = crossing_union(Vb, Fb, XA, GA, element=element.astype(np.int64),
                           flat_test=False, all_or_none=True)
    except InputError:
        raise
    except GeotexError:
        # inputs that break its assumptions (it says so): the boolean decides
        return None
    return None if r.left_out.size else (r.vertices, r.faces)
