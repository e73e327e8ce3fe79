"""Union of mapped texture elements with the base solid (manifold3d).

Mapped elements are closed, but the shell map can bend neighbours into each
other where it is strongly distorted. manifold3d unites any number of
operands correctly as long as each operand is free of self-intersection, so
the elements are split into a few groups of pairwise separate ones: a greedy
colouring of the graph of elements whose bounding boxes overlap. Every group
is one multi-component operand; one batch boolean adds the groups to the base.
An element that the map folds onto itself (found by geotex's exact
self-intersection test) is left out.
Pieces of the result that are not part of the body (elements that float above
a concave base) are left out, so the print is one solid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import GeotexError
from geotex.mesh.topology import compacted, face_components
from geotex.progress import report

__all__ = ["united_with_base", "folded_elements", "element_groups", "UnionStats", "SLIVER_TOLERANCE",
           "UNION_STAGES"]

#: Stage names passed to the ``progress`` callback of :func:`united_with_base`.
UNION_STAGES = ("union: folded elements", "union: boolean", "union: slivers")

#: The union's result is simplified at this fraction of the bounding-box
#: diagonal (manifold3d ``simplify``: short edges and needle triangles
#: collapse). 1e-6 (0.1 micrometre on a 100 mm part) is about ten float32
#: steps, so what remains survives the rounding to float32 of an STL file;
#: at 1e-7 the rounding broke hundreds of slivers on chain mail.
SLIVER_TOLERANCE = 1e-6


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


def element_groups(X: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split elements into groups whose members' bounding boxes do not overlap.

    Parameters
    ----------
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64

    Returns
    -------
    element : numpy.ndarray, (l,) int64
        Element (connected component) of every face.
    group : numpy.ndarray, (n_elements,) int64
        Group of every element, ``0 .. n_groups - 1`` (greedy colouring, largest
        degree first, so deterministic).
    """
    import networkx as nx
    from scipy.spatial import cKDTree

    n_el, label = face_components(G, X.shape[0])
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
    graph = nx.Graph()
    graph.add_nodes_from(range(n_el))
    graph.add_edges_from(map(tuple, cand.tolist()))
    colour = nx.greedy_color(graph, strategy="largest_first")
    return label, np.array([colour[i] for i in range(n_el)], dtype=np.int64)


def folded_elements(X: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Elements whose faces cross each other (the map folded them), exact test.

    Returns
    -------
    label : numpy.ndarray, (l,) int64
        Element of every face (:func:`geotex.mesh.topology.face_components`).
    folded : numpy.ndarray, (k,) int64
        Sorted folded elements.
    """
    _, label = face_components(G, X.shape[0])
    pairs = self_intersecting_pairs(X, G)
    same = label[pairs[:, 0]] == label[pairs[:, 1]]
    return label, np.unique(label[pairs[same, 0]])


def united_with_base(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray, *,
                     exclude=None, folded=None, progress=None
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
    folded : array_like of int, optional
        Elements already known to be folded (:func:`folded_elements`); by
        default they are found here.
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
    import manifold3d

    from geotex.mesh.solid import arrays_of_manifold, manifold_of

    base = manifold_of(V, F)
    if base.status() != manifold3d.Error.NoError:
        raise GeotexError(f"the base is not a valid solid for manifold3d ({base.status().name});"
                          " run 'geotex repair' on it")
    if len(G) == 0:
        return np.array(V, dtype=np.float64), np.array(F, dtype=np.int64), UnionStats(0, 0, 0)
    label, group = element_groups(X, G)
    # an element the map folded onto itself cannot be united: leave it out
    report(progress, UNION_STAGES[0])
    if folded is None:
        folded = folded_elements(X, G)[1]
    folded = np.asarray(folded, dtype=np.int64)
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
    # and base surfaces cross nearly tangentially; they fold onto their neighbours.
    # Collapsing edges below SLIVER_TOLERANCE of the diagonal removes them,
    # keeping the solid manifold and changing the shape by less than that
    if SLIVER_TOLERANCE > 0:
        diag = float(np.linalg.norm(np.ptp(np.vstack([V, X]), axis=0)))
        solid = solid.simplify(SLIVER_TOLERANCE * diag)
    V2, F2 = arrays_of_manifold(solid)
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
