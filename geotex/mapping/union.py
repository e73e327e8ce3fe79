"""Union of mapped texture elements with the base solid (manifold3d).

Mapped elements are closed, but the shell map can bend two neighbours into
each other (strong distortion) or fold one onto itself. A boolean union of a
mesh that intersects itself is not well defined, so the elements are sorted
first, with geotex's exact self-intersection test:

* an element that intersects itself is dropped (counted);
* elements that intersect each other are grouped, and every group is united
  as separate solids (which manifold3d merges correctly);
* all other elements are disjoint and go in as one multi-component solid.

One batch boolean then adds everything to the base.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import GeotexError
from geotex.mesh.topology import face_components

__all__ = ["united_with_base", "UnionStats"]


@dataclass(frozen=True)
class UnionStats:
    """What the union did.

    Attributes
    ----------
    elements : int
        Elements added to the base.
    dropped : int
        Elements dropped because they intersect themselves.
    merged_groups : int
        Groups of mutually intersecting elements united among themselves.
    """

    elements: int
    dropped: int
    merged_groups: int


def _compact(X: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    used = np.unique(G)
    remap = np.full(X.shape[0], -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return X[used], remap[G]


def united_with_base(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray
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
    n_el, label = face_components(G, X.shape[0])
    pairs = self_intersecting_pairs(X, G)
    la, lb = label[pairs[:, 0]], label[pairs[:, 1]]
    broken = np.zeros(n_el, dtype=bool)
    broken[la[la == lb]] = True
    cross = (la != lb) & ~broken[la] & ~broken[lb]
    A = sp.coo_matrix((np.ones(int(cross.sum())), (la[cross], lb[cross])), shape=(n_el, n_el))
    _, group = connected_components(A, directed=False)
    size = np.bincount(group, minlength=n_el)
    loose = ~broken & (size[group] == 1)
    solids = [base]
    if loose.any():
        solids.append(manifold_of(*_compact(X, G[loose[label]])))
    grouped = np.flatnonzero(~broken & (size[group] > 1))
    groups = np.unique(group[grouped])
    for g in groups:
        for e in grouped[group[grouped] == g]:
            solids.append(manifold_of(*_compact(X, G[label == e])))
    bad = [s for s in solids[1:] if s.status() != manifold3d.Error.NoError]
    if bad:
        raise GeotexError("the mapped texture elements are not closed "
                          f"({bad[0].status().name}); the tile set may be broken "
                          "(check it with 'geotex tiles check')")
    solid = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
    V2, F2 = arrays_of_manifold(solid)
    return V2, F2, UnionStats(int((~broken).sum()), int(broken.sum()), int(groups.size))
