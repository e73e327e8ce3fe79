"""Union of mapped texture elements with the base solid (manifold3d).

Mapped elements are closed, but the shell map can bend neighbours into each
other where it is strongly distorted. manifold3d unites any number of
operands correctly as long as each operand is free of self-intersection, so
the elements are split into a few groups of pairwise separate ones: a greedy
colouring of the graph of elements that meet (one exact self-intersection
test of all elements finds those, and the elements the map folds onto
themselves, which are left out). Every group is one multi-component operand;
one batch boolean adds the groups to the base.
Pieces of the result that are not part of the body (elements that float above
a concave base) are left out, so the print is one solid.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import manifold3d
import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import GeotexError
from geotex.mesh.needles import SLIVER_TOLERANCE, needle_free
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.mesh.topology import compacted, face_components, greedy_colouring
from geotex.progress import report

__all__ = ["united_with_base", "element_contacts", "ElementContacts", "element_groups",
           "UnionStats", "SLIVER_TOLERANCE", "UNION_STAGES"]

#: Stage names passed to the ``progress`` callback of :func:`united_with_base`.
UNION_STAGES = ("union: folded elements", "union: boolean", "union: slivers")



@dataclass(frozen=True)
class UnionStats:
    """What the union did.

    Attributes
    ----------
    elements : int
        Elements added to the base.
    groups : int
        Operands the elements were split into (elements within one do not touch).
    floating : int
        Pieces that did not reach the base and were left out.
    folded : int
        Elements left out because the map folds them onto themselves.
    """

    elements: int
    groups: int
    floating: int = 0
    folded: int = 0


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


def element_contacts(X: np.ndarray, G: np.ndarray) -> ElementContacts:
    """Elements the map folds, and pairs of elements that meet (one exact test).

    Parameters
    ----------
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64

    Returns
    -------
    ElementContacts
    """
    _, label = face_components(G, X.shape[0])
    pairs = self_intersecting_pairs(X, G)
    a, b = label[pairs[:, 0]], label[pairs[:, 1]]
    same = a == b
    touching = np.unique(np.sort(np.stack([a[~same], b[~same]], axis=1), axis=1), axis=0)
    return ElementContacts(label, np.unique(a[same]), touching.reshape(-1, 2))


def element_groups(X: np.ndarray, G: np.ndarray, *, touching=None, moved=None, label=None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Split elements into groups whose members do not meet.

    Without ``touching``, members of a group have bounding boxes that do not
    overlap. With it (from :func:`element_contacts`), only elements that
    meet, and elements whose box overlaps one that has ``moved`` since,
    are kept apart, so most elements share the first group.

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
    element : numpy.ndarray, (l,) int64
        Element (connected component) of every face.
    group : numpy.ndarray, (n_elements,) int64
        Group of every element, ``0 .. n_groups - 1`` (greedy colouring, largest
        degree first, so deterministic).
    """
    # lazy: scipy.spatial (~0.1 s) is slow to import
    from scipy.spatial import cKDTree

    if label is None:
        n_el, label = face_components(G, X.shape[0])
    else:
        n_el = int(label.max()) + 1 if label.size else 0
    vlab = np.full(X.shape[0], -1, dtype=np.int64)
    vlab[G[:, 0]], vlab[G[:, 1]], vlab[G[:, 2]] = label, label, label
    used = vlab >= 0
    lo = np.full((n_el, 3), np.inf)
    hi = np.full((n_el, 3), -np.inf)
    for d in range(3):
        np.minimum.at(lo[:, d], vlab[used], X[used, d])
        np.maximum.at(hi[:, d], vlab[used], X[used, d])
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
    return label, greedy_colouring(n_el, cand)


def united_with_base(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray, *,
                     exclude=None, contacts: ElementContacts | None = None, moved=None,
                     progress=None) -> tuple[np.ndarray, np.ndarray, UnionStats]:
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
    progress : callable, optional
        Called with each stage of :data:`UNION_STAGES`.

    Returns
    -------
    V2 : numpy.ndarray, (p, 3) float64
    F2 : numpy.ndarray, (r, 3) int64
    stats : UnionStats

    Raises
    ------
    GeotexError
        manifold3d rejects the base or the elements (open elements, a bug).
    """
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
    label, group = element_groups(X, G, touching=contacts.touching, moved=moved,
                                  label=contacts.label)
    group[folded] = -1
    if exclude is not None:
        group[np.asarray(exclude, dtype=bool)] = -1
    solids = [base]
    for g in range(int(group.max()) + 1):
        solids.append(manifold_of(*compacted(X, G[group[label] == g])))
    bad = [s for s in solids[1:] if s.status() != manifold3d.Error.NoError]
    if bad:
        raise GeotexError("the mapped texture elements are not closed "
                          f"({bad[0].status().name}); the tile set may be broken "
                          "(check it with 'geotex tiles check')")
    report(progress, UNION_STAGES[1])
    solid = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
    solid.num_tri()                      # evaluate here (manifold3d is lazy)
    report(progress, UNION_STAGES[2])
    # the boolean leaves needle triangles (area ~1e-13 of the solid) where element
    # and base surfaces cross nearly tangentially; float32 rounding (STL) folds some
    # onto their neighbours. Local collapses and flips remove those lower than
    # SLIVER_TOLERANCE of the diagonal, keeping the solid closed and manifold and
    # changing the shape by less than that (manifold3d's simplify at the same
    # tolerance kept most of them, where a collapse would move a crease)
    diag = float(np.linalg.norm(np.ptp(np.vstack([V, X]), axis=0)))
    V2, F2, _ = needle_free(*arrays_of_manifold(solid), tolerance=SLIVER_TOLERANCE * diag)
    # elements that do not reach the base (where the fitted surface lies above a
    # concave base) would print as loose pieces: keep the body they are part of
    parts, label = face_components(F2, V2.shape[0])
    floating = 0
    if parts > 1:
        body = np.argmax(np.bincount(label))
        floating = parts - 1
        V2, F2 = compacted(V2, F2[label == body])
    return V2, F2, UnionStats(int((group >= 0).sum()) - floating, int(group.max()) + 1,
                              floating, int(folded.size))
