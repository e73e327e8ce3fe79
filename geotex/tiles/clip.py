"""Split a triangle mesh by an axis-aligned plane into two open halves.

The halves share their cut exactly: every mesh edge that crosses the plane gets
one new vertex, used by both halves, whose coordinate along the plane's axis is
set to the plane value exactly. Welding the two halves back (by position) gives
the original surface refined along the cut, which is what makes Wang tiles
seamless: two neighbouring tiles receive the two halves of one edge strip.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from geotex.mesh.topology import compacted, edge_topology

__all__ = ["split_by_plane", "refined_by_plane", "PlaneCut"]


def refined_by_plane(V: np.ndarray, F: np.ndarray, *, axis: int, value: float,
                     snap: float = 1e-7, ordered: bool = False) -> PlaneCut:
    """Refine a mesh along the plane ``x[axis] = value``, keeping it in one piece.

    Every edge that crosses the plane gets one new vertex (its ``axis``
    coordinate set to ``value`` exactly) and every crossed face is split in
    three, so each face lies on one side. :func:`split_by_plane` is this
    followed by separating the sides.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    axis, value, snap, ordered
        As in :func:`split_by_plane`.

    Returns
    -------
    PlaneCut
    """
    V = np.array(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    d = V[:, axis] - value
    near = np.abs(d) < snap
    V[near, axis] = value + snap
    d[near] = V[near, axis] - value
    positive = d > 0

    topo = edge_topology(F, len(V))
    e0, e1 = topo.edges[:, 0], topo.edges[:, 1]
    crossing = positive[e0] != positive[e1]
    cut_edges = np.flatnonzero(crossing)
    a, b = e0[cut_edges], e1[cut_edges]
    if ordered:
        a, b = np.where(positive[a], b, a), np.where(positive[a], a, b)
    t = d[a] / (d[a] - d[b])
    P = V[a] + t[:, None] * (V[b] - V[a])
    P[:, axis] = value
    cut_vertex = np.full(len(topo.edges), -1, dtype=np.int64)
    cut_vertex[cut_edges] = len(V) + np.arange(len(cut_edges))
    W = np.vstack([V, P])

    side = positive[F]
    n_pos = side.sum(axis=1)
    whole_pos = F[n_pos == 3]
    whole_neg = F[n_pos == 0]
    mixed = np.flatnonzero((n_pos == 1) | (n_pos == 2))
    # rotate each mixed face so that its lone vertex (the odd one out) comes first
    s = side[mixed]
    lone_is_pos = n_pos[mixed] == 1
    lone = np.where(lone_is_pos[:, None], s, ~s).argmax(axis=1)
    k = (lone[:, None] + np.arange(3)) % 3
    corners = np.take_along_axis(F[mixed], k, axis=1)
    he = np.take_along_axis(topo.half_to_edge.reshape(-1, 3)[mixed], k, axis=1)
    L, A, B = corners.T
    p = cut_vertex[he[:, 0]]            # on edge L-A
    q = cut_vertex[he[:, 2]]            # on edge B-L
    lone_tri = np.stack([L, p, q], axis=1)
    pair = np.vstack([np.stack([p, A, B], axis=1), np.stack([p, B, q], axis=1)])
    pair_pos = np.concatenate([~lone_is_pos, ~lone_is_pos])
    above = np.vstack([whole_pos, lone_tri[lone_is_pos], pair[pair_pos]])
    below = np.vstack([whole_neg, lone_tri[~lone_is_pos], pair[~pair_pos]])
    # the below side's faces run q -> p along the cut where the lone vertex is
    # below (in L, p, q) and p -> q where it is above (in p, B, q): its cap runs back
    cap = np.where(lone_is_pos[:, None], np.stack([p, q], axis=1), np.stack([q, p], axis=1))
    return PlaneCut(W, np.vstack([below, above]),
                    np.arange(len(below) + len(above)) >= len(below), cap.reshape(-1, 2))


class PlaneCut(NamedTuple):
    """A mesh refined along a plane (:func:`refined_by_plane`).

    Attributes
    ----------
    vertices : numpy.ndarray, (n + c, 3) float64
        The input vertices (those within ``snap`` of the plane pushed off it),
        then one new vertex per crossing edge, on the plane.
    faces : numpy.ndarray, (k, 3) int64
        Faces below the plane, then those above (input orientation).
    above : numpy.ndarray, (k,) bool
        Faces above the plane.
    cut : numpy.ndarray, (e, 2) int64
        The cut as directed edges ``a -> b`` between new vertices, running the
        way a lid that closes the part below would run (opposite to the
        below part's faces, the same way as the part above's).
    """

    vertices: np.ndarray
    faces: np.ndarray
    above: np.ndarray
    cut: np.ndarray


def split_by_plane(V: np.ndarray, F: np.ndarray, *, axis: int, value: float,
                   snap: float = 1e-7, ordered: bool = False
                   ) -> tuple[tuple[np.ndarray, np.ndarray],
                                                  tuple[np.ndarray, np.ndarray]]:
    """Cut a mesh with the plane ``x[axis] = value`` into its two sides.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    axis : int
        0, 1 or 2.
    value : float
        Plane position along ``axis``.
    snap : float
        Vertices closer than this to the plane are first pushed to
        ``value + snap`` so that no cut triangle degenerates.
    ordered : bool
        Compute every cut vertex from the crossing edge's endpoint below the
        plane, whatever the vertex numbering: a mesh and its mirror image
        (two axes swapped) cut by the mirrored planes give mirror-image cut
        vertices bit for bit. Default False: from the edge's first vertex.

    Returns
    -------
    below, above : tuple of (V, F)
        The parts with ``x[axis] <= value`` and ``x[axis] >= value``; both are
        compacted, keep the input orientation, and their vertices on the plane
        are bit-identical.
    """
    cut = refined_by_plane(V, F, axis=axis, value=value, snap=snap, ordered=ordered)
    return (compacted(cut.vertices, cut.faces[~cut.above]),
            compacted(cut.vertices, cut.faces[cut.above]))
