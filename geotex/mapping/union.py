"""Union of mapped texture elements with the base solid (manifold3d)."""

from __future__ import annotations

import numpy as np

from geotex.errors import GeotexError

__all__ = ["united_with_base"]


def united_with_base(V: np.ndarray, F: np.ndarray, X: np.ndarray, G: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, int]:
    """One solid: the base plus every closed element, overlaps merged.

    Each element is a separate manifold3d solid and all of them are added in one
    batch boolean, so elements that touch or overlap each other (near polycube
    edges) are merged correctly rather than passed to manifold3d as a
    self-intersecting mesh.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Base solid (closed, outward).
    X : numpy.ndarray, (k, 3) float64
    G : numpy.ndarray, (l, 3) int64
        Elements (each connected component closed).

    Returns
    -------
    V2 : numpy.ndarray, (p, 3) float64
    F2 : numpy.ndarray, (r, 3) int64
    elements : int
        Number of elements added.

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
        return np.array(V, dtype=np.float64), np.array(F, dtype=np.int64), 0
    elements = manifold_of(X, G)
    if elements.status() != manifold3d.Error.NoError:
        raise GeotexError("the mapped texture elements are not closed "
                          f"({elements.status().name}); the tile set may be broken "
                          "(check it with 'geotex tiles check')")
    parts = elements.decompose()
    solid = manifold3d.Manifold.batch_boolean([base, *parts], manifold3d.OpType.Add)
    V2, F2 = arrays_of_manifold(solid)
    return V2, F2, len(parts)
