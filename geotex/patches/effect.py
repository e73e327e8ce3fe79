"""Effect areas around constraints (material-space textures §2.1).

When a user places or edits a constraint (orientation, scale, material), only
an *effect area* around it is updated; everything outside stays locked.  The
paper (after Kobbelt et al. 1998) determines the area by "a classical greedy
algorithm that visits the triangles in order of increasing distance to the
nearest constraint", the user's brush size being the distance threshold.

Rule implemented here:

* distance: multi-source Dijkstra over the dual graph (centroid-to-centroid
  lengths across manifold edges), every constraint face at distance 0;
* faces are taken in order of increasing distance (ties by face index) while
  the distance is at most ``max_distance`` and the accumulated area stays
  within ``budget_area``; growth stops at the first face that does not fit the
  budget, so the area is always a distance ball (never a ragged set that skips
  a large face to take smaller ones further away) and every face is connected
  to a constraint face through faces of the area;
* blocked faces are never entered and blocked edges never crossed: the brush
  does not bleed over them, and faces reachable only through them stay out.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from geotex.errors import InputError
from geotex.mesh.topology import edge_topology
from geotex.patches.grow import FaceAdjacency, _adjacency_for

__all__ = ["effect_area"]


def _face_set(value, m: int, name: str) -> np.ndarray:
    """Face ids from ids or an (m,) boolean mask; sorted unique int64."""
    arr = np.asarray(value)
    if arr.dtype == bool:
        if arr.shape != (m,):
            raise InputError(f"{name} as a mask must have shape ({m},), got {arr.shape}")
        return np.flatnonzero(arr)
    arr = arr.ravel()
    if arr.size and arr.dtype.kind not in "iu":
        raise InputError(f"{name} must hold integer face ids or be a boolean mask")
    arr = arr.astype(np.int64)
    if arr.size and (arr.min() < 0 or arr.max() >= m):
        raise InputError(f"{name} has face ids outside [0, {m})")
    return np.unique(arr)


def _edge_ids(value, F: np.ndarray, n: int) -> np.ndarray:
    """Unique-edge ids from (k, 2) vertex pairs or 1-D unique-edge indices."""
    topo = edge_topology(F, n)
    arr = np.asarray(value)
    if arr.size and arr.dtype.kind not in "iu":
        raise InputError("blocked_edges must hold integers (edge ids or vertex pairs)")
    arr = arr.astype(np.int64)
    if arr.ndim == 1:
        if arr.size and (arr.min() < 0 or arr.max() >= topo.edges.shape[0]):
            raise InputError(f"blocked_edges has edge ids outside [0, {topo.edges.shape[0]})")
        return arr, topo
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InputError(f"blocked_edges must be (k,) edge ids or (k, 2) vertex pairs, "
                         f"got shape {arr.shape}")
    if arr.size and (arr.min() < 0 or arr.max() >= n):
        raise InputError(f"blocked_edges has vertex ids outside [0, {n})")
    key = np.minimum(arr[:, 0], arr[:, 1]) * n + np.maximum(arr[:, 0], arr[:, 1])
    ekey = topo.edges[:, 0] * n + topo.edges[:, 1]
    pos = np.minimum(np.searchsorted(ekey, key), max(ekey.size - 1, 0))
    if arr.size and (ekey[pos] != key).any():
        bad = arr[np.flatnonzero(ekey[pos] != key)[0]].tolist()
        raise InputError(f"blocked_edges contains {bad}, which is not an edge of F")
    return pos, topo


def effect_area(V, F, seed_faces, *, budget_area=None, max_distance=None, blocked=None,
                blocked_edges=None, adjacency: FaceAdjacency | None = None,
                return_distance: bool = False):
    """Grow the effect area of a constraint greedily by distance.

    See the module docstring for the rule (material-space textures §2.1).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    seed_faces : int or array_like of int, or (m,) bool mask
        The constraint faces; always part of the result.
    budget_area : float, optional
        Largest total area of the effect area (the seeds count towards it;
        when the seeds alone exceed it, only the seeds are returned).
    max_distance : float, optional
        Brush radius: largest dual-graph distance from the nearest seed.
        ``numpy.inf`` asks for an unbounded area.  At least one of
        ``budget_area`` and ``max_distance`` is required.
    blocked : array_like of int or (m,) bool mask, optional
        Faces the area never enters.
    blocked_edges : (k, 2) vertex pairs or (k,) unique-edge ids, optional
        Edges the growth never crosses.
    adjacency : FaceAdjacency, optional
        Precomputed :func:`geotex.patches.face_adjacency` of ``(V, F)``.
    return_distance : bool, optional
        Also return the distance of every returned face.

    Returns
    -------
    faces : numpy.ndarray, (k,) int64
        Face ids in visiting order (increasing distance, ties by index).
    distance : numpy.ndarray, (k,) float64
        Only with ``return_distance``.

    Raises
    ------
    InputError
        When neither limit is given, a limit is negative, seeds are empty,
        out of range or blocked, or an argument is malformed.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(3)
    >>> faces = effect_area(V, F, [0], max_distance=0.3)
    >>> int(faces[0])
    0
    """
    V, F, adj = _adjacency_for(V, F, adjacency)
    m, n = F.shape[0], V.shape[0]
    if budget_area is None and max_distance is None:
        raise InputError("effect_area needs budget_area or max_distance (numpy.inf for no limit)")
    budget = math.inf if budget_area is None else float(budget_area)
    limit = math.inf if max_distance is None else float(max_distance)
    if math.isnan(budget) or budget < 0:
        raise InputError(f"budget_area must be >= 0, got {budget_area!r}")
    if math.isnan(limit) or limit < 0:
        raise InputError(f"max_distance must be >= 0, got {max_distance!r}")
    seeds = _face_set(np.atleast_1d(seed_faces) if np.ndim(seed_faces) == 0 else seed_faces,
                      m, "seed_faces")
    if seeds.size == 0:
        raise InputError("seed_faces is empty: give at least one constraint face")
    open_face = np.ones(m, bool)
    if blocked is not None:
        bl = _face_set(blocked, m, "blocked")
        if np.isin(seeds, bl).any():
            raise InputError("seed_faces and blocked share a face; a constraint face cannot "
                             "be blocked")
        open_face[bl] = False
    FF, W, FE = adj.face_neighbors, adj.neighbor_distance, adj.face_edges
    rows = np.repeat(np.arange(m, dtype=np.int64), 3)
    cols = FF.ravel()
    w = W.ravel()
    keep = (cols >= 0)
    keep[keep] &= open_face[rows[keep]] & open_face[cols[keep]]
    if blocked_edges is not None:
        eids, _ = _edge_ids(blocked_edges, F, n)
        cut = np.zeros(adj.edge_face_count.shape[0], bool)
        cut[eids] = True
        keep &= ~cut[FE.ravel()]
    # zero lengths (coincident centroids) would vanish from a sparse matrix
    scale = float(np.mean(w[keep])) if keep.any() else 1.0
    w = np.maximum(w[keep], 1e-15 * scale)
    G = sp.csr_matrix((w, (rows[keep], cols[keep])), shape=(m, m))
    d = dijkstra(G, directed=True, indices=seeds, min_only=True,
                 limit=limit if math.isfinite(limit) else np.inf)
    d = np.asarray(d, dtype=np.float64)
    d[seeds] = 0.0
    reach = np.flatnonzero(np.isfinite(d) & (d <= limit))
    order = reach[np.lexsort((reach, d[reach]))]
    if math.isfinite(budget):
        cum = np.cumsum(adj.areas[order])
        n_seed = seeds.size
        over = np.flatnonzero(cum[n_seed:] > budget * (1 + 1e-12))
        stop = n_seed + (int(over[0]) if over.size else order.size - n_seed)
        order = order[:stop]
    order = order.astype(np.int64)
    if return_distance:
        return order, d[order]
    return order
