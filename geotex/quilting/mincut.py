"""Minimum s-t cut of a small undirected graph with scipy's max-flow (Dinic).

The graph is given as node pairs with float weights; a set of nodes is tied
to the SOURCE and another to the SINK with infinite weight (two extra
terminal nodes are added).  ``scipy.sparse.csgraph.maximum_flow`` needs
int32 capacities, so weights are scaled so that their sum stays near
``2**29`` (every positive weight becomes at least 1) and an infinite tie is
``2**31 - 1``: no flow can reach it, because every source-sink path must
cross a finite edge.  The source side of the cut is the set of nodes
reachable from the source in the residual graph (breadth-first search).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from geotex.errors import InputError

__all__ = ["MinCut", "min_cut", "min_cut_keep"]

_FINITE_TOTAL = 2 ** 29  # plus at most one per edge from rounding up
_INFINITE = 2 ** 31 - 1


@dataclass(frozen=True)
class MinCut:
    """Result of :func:`min_cut`.

    Attributes
    ----------
    keep : numpy.ndarray, (n,) bool
        True for nodes on the source side.
    value : float
        Sum of the (float) weights of the edges that cross the cut.
    flow : int
        Maximum flow in the scaled integer capacities.
    """

    keep: np.ndarray
    value: float
    flow: int


def _node_set(nodes, n: int, name: str) -> np.ndarray:
    arr = np.asarray(nodes)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise InputError(f"{name} as a mask must have shape ({n},), got {arr.shape}")
        return np.flatnonzero(arr)
    arr = np.unique(np.asarray(arr, dtype=np.int64).ravel())
    if arr.size and (arr[0] < 0 or arr[-1] >= n):
        raise InputError(f"{name} holds node indices outside [0, {n})")
    return arr


def min_cut(n_nodes: int, edges, weights, *, source, sink) -> MinCut:
    """Minimum cut separating the ``source`` nodes from the ``sink`` nodes.

    Parameters
    ----------
    n_nodes : int
        Number of graph nodes.
    edges : array_like, (k, 2) int
        Undirected edges (each listed once; repeated pairs add up).
    weights : array_like, (k,) float
        Non-negative finite edge weights (the cost of cutting the edge).
    source, sink : array_like of int, or (n_nodes,) bool mask
        Nodes tied to the SOURCE (kept) and to the SINK (removed) with infinite
        weight.  Both must be non-empty and disjoint.

    Returns
    -------
    MinCut

    Raises
    ------
    InputError
        On malformed edges or weights, negative or non-finite weights, empty
        or overlapping terminal sets.
    """
    n = int(n_nodes)
    if n < 2:
        raise InputError(f"n_nodes must be at least 2, got {n_nodes}")
    E = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    w = np.asarray(weights, dtype=np.float64).ravel()
    if w.shape[0] != E.shape[0]:
        raise InputError(f"weights must have one value per edge ({E.shape[0]}), got {w.shape[0]}")
    if E.size and (E.min() < 0 or E.max() >= n):
        raise InputError(f"edges reference nodes outside [0, {n})")
    if not np.isfinite(w).all() or (w < 0).any():
        raise InputError("weights must be finite and non-negative")
    src = _node_set(source, n, "source")
    snk = _node_set(sink, n, "sink")
    if src.size == 0 or snk.size == 0:
        raise InputError("source and sink must each hold at least one node")
    if np.intersect1d(src, snk).size:
        raise InputError("a node cannot be tied to both the source and the sink")

    # scale finite weights to int32 capacities whose sum stays below 2**30
    total = float(w.sum())
    scale = _FINITE_TOTAL / total if total > 0 else 1.0
    cap = np.where(w > 0, np.maximum(np.floor(w * scale), 1), 0).astype(np.int64)
    S, T = n, n + 1
    rows = np.concatenate([E[:, 0], E[:, 1], np.full(src.size, S), snk])
    cols = np.concatenate([E[:, 1], E[:, 0], src, np.full(snk.size, T)])
    vals = np.concatenate([cap, cap, np.full(src.size + snk.size, _INFINITE, np.int64)])
    keep_entry = vals > 0
    C = sp.csr_matrix((vals[keep_entry], (rows[keep_entry], cols[keep_entry])),
                      shape=(n + 2, n + 2), dtype=np.int64)
    C.sum_duplicates()
    C.data = np.minimum(C.data, _INFINITE)
    C = C.astype(np.int32)
    result = maximum_flow(C, S, T, method="dinic")
    residual = (C.astype(np.int64) - result.flow.astype(np.int64)).tocsr()
    residual.data[residual.data < 0] = 0
    residual.eliminate_zeros()
    reach = breadth_first_order(residual, S, directed=True, return_predecessors=False)
    keep = np.zeros(n + 2, dtype=bool)
    keep[reach] = True
    keep = keep[:n]
    crossing = keep[E[:, 0]] != keep[E[:, 1]]
    return MinCut(keep=keep, value=float(w[crossing].sum()), flow=int(result.flow_value))


def min_cut_keep(n_nodes: int, edges, weights, *, source, sink) -> np.ndarray:
    """Return the source side of the minimum cut; see :func:`min_cut`.

    Returns
    -------
    numpy.ndarray, (n_nodes,) bool
        True for nodes kept (on the source side).

    Examples
    --------
    >>> import numpy as np
    >>> edges = np.array([[0, 1], [1, 2], [2, 3]])
    >>> min_cut_keep(4, edges, [5.0, 1.0, 5.0], source=[0], sink=[3]).tolist()
    [True, True, False, False]
    """
    return min_cut(n_nodes, edges, weights, source=source, sink=sink).keep
