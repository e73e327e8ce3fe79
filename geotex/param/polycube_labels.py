"""Polycube face labels: +-X / +-Y / +-Z per face, smoothed and made valid.

Label ``l`` in ``0..5`` stands for the direction ``LABEL_DIRECTIONS[l]``:
``0 +X, 1 -X, 2 +Y, 3 -Y, 4 +Z, 5 -Z``; its axis is ``l // 2`` and its sign
``+1`` for even ``l``, ``-1`` for odd ``l``; ``l ^ 1`` is the opposite label.

A *chart* is a connected component (across edges) of faces with equal labels.
The labelling is valid for a polycube when no two edge-adjacent faces carry
opposite labels, every vertex touched by three or more charts sees three
different axes, no vertex sees two opposite labels, a vertex on the border of
only two charts has exactly two border edges (no pinch), and charts are not
tiny.  :func:`fix_labels` repairs violations by relabelling small sets of
faces, iterating until none is left.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.mesh.geometry import face_areas, face_normals
from geotex.mesh.topology import edge_topology

__all__ = ["LABEL_DIRECTIONS", "LABEL_NAMES", "FaceGraph", "face_graph", "initial_labels",
           "smooth_labels", "charts_of", "fix_labels", "flood_labels", "merge_chart"]

LABEL_DIRECTIONS = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1],
                             [0, 0, -1]], dtype=np.float64)
LABEL_NAMES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


@dataclass(frozen=True)
class FaceGraph:
    """Face adjacency of a closed edge-manifold mesh.

    Attributes
    ----------
    neighbors : (m, 3) int64
        Face across edge ``k`` (from ``F[f, k]`` to ``F[f, (k+1) % 3]``).
    edge_length : (m, 3) float64
        Length of that edge.
    edges : (e, 2) int64
        Unique edges (see :mod:`geotex.mesh.topology`).
    edge_faces : (e, 2) int64
        The two faces of every edge.
    half_to_edge : (3m,) int64
    normals : (m, 3) float64
    areas : (m,) float64
    """

    neighbors: np.ndarray
    edge_length: np.ndarray
    edges: np.ndarray
    edge_faces: np.ndarray
    half_to_edge: np.ndarray
    normals: np.ndarray
    areas: np.ndarray


def face_graph(V: np.ndarray, F: np.ndarray) -> FaceGraph:
    """Return the :class:`FaceGraph` of a closed, edge-manifold mesh."""
    topo = edge_topology(F, V.shape[0])
    ef = topo.edge_faces()
    h2e = topo.half_to_edge.reshape(-1, 3)
    m = F.shape[0]
    own = np.repeat(np.arange(m), 3).reshape(-1, 3)
    a, b = ef[h2e, 0], ef[h2e, 1]
    nb = np.where(a == own, b, a)
    Fn = np.roll(F, -1, axis=1)
    length = np.linalg.norm(V[Fn] - V[F], axis=2)
    return FaceGraph(neighbors=nb, edge_length=length, edges=topo.edges, edge_faces=ef,
                     half_to_edge=topo.half_to_edge, normals=face_normals(V, F),
                     areas=face_areas(V, F))


def initial_labels(normals: np.ndarray) -> np.ndarray:
    """Label of the axis direction closest to each face normal, ``(m,)`` int64."""
    return np.argmax(normals @ LABEL_DIRECTIONS.T, axis=1).astype(np.int64)


def _data_cost(g: FaceGraph) -> np.ndarray:
    return g.areas[:, None] * (1.0 - g.normals @ LABEL_DIRECTIONS.T)


def smooth_labels(g: FaceGraph, labels: np.ndarray, *, smoothness: float = 1.0,
                  iterations: int = 30) -> np.ndarray:
    """Iterated conditional modes on data ``area (1 - n.d)`` + boundary length.

    Opposite labels across an edge cost 20 times more than other label changes.
    Faces are updated in two alternating halves (by index parity of a greedy
    colouring proxy) so the iteration does not oscillate.
    """
    labels = labels.copy()
    m = labels.size
    data = _data_cost(g)
    h = float(np.mean(g.edge_length))
    w = smoothness * g.edge_length * h
    rows = np.arange(m)
    groups = [np.arange(m) % 2 == 0, np.arange(m) % 2 == 1]
    for _ in range(iterations):
        changed = 0
        for sel in groups:
            cost = data.copy()
            for k in range(3):
                nbl = labels[g.neighbors[:, k]]
                cost += w[:, k, None]
                cost[rows, nbl] -= w[:, k]
                cost[rows, nbl ^ 1] += 20.0 * w[:, k]
            new = np.argmin(cost, axis=1)
            upd = sel & (new != labels)
            changed += int(upd.sum())
            labels[upd] = new[upd]
        if not changed:
            break
    return labels


def charts_of(g: FaceGraph, labels: np.ndarray) -> tuple[int, np.ndarray]:
    """Connected components of equal labels across edges: ``(count, chart (m,))``."""
    ef = g.edge_faces
    same = labels[ef[:, 0]] == labels[ef[:, 1]]
    m = labels.size
    A = sp.coo_matrix((np.ones(int(same.sum())), (ef[same, 0], ef[same, 1])), shape=(m, m))
    n, comp = connected_components(A, directed=False)
    return n, comp.astype(np.int64)


def _vertex_faces(F: np.ndarray, n: int) -> sp.csr_matrix:
    m = F.shape[0]
    return sp.csr_matrix((np.ones(3 * m), (F.ravel(), np.repeat(np.arange(m), 3))),
                         shape=(n, m))


def _best_neighbor_label(g, labels, faces, chart_mask_faces):
    """Best label for a set of faces among the labels across its border."""
    data = _data_cost(g)[faces].sum(axis=0)
    nb = g.neighbors[faces]
    outside = ~chart_mask_faces[nb]
    border_labels = labels[nb[outside]]
    border_len = g.edge_length[faces][outside]
    length = np.bincount(border_labels, weights=border_len, minlength=6)
    cand = np.flatnonzero(length > 0)
    present = set(int(x) for x in cand)
    ok = [c for c in cand if (c ^ 1) not in present and c != labels[faces[0]]]
    if not ok:
        ok = [c for c in cand if c != labels[faces[0]]]
    if not ok:
        return None
    ok = np.asarray(ok)
    score = data[ok] - 2.0 * length[ok] * float(np.mean(g.edge_length))
    return int(ok[np.argmin(score)])


def fix_labels(V: np.ndarray, F: np.ndarray, g: FaceGraph, labels: np.ndarray, *,
               min_chart_area: float, max_rounds: int = 60,
               extra_bad_faces: np.ndarray | None = None) -> np.ndarray:
    """Relabel faces until the labelling is valid for a polycube (or rounds run out).

    Parameters
    ----------
    min_chart_area : float
        Charts with a smaller area are merged into a neighbouring chart.
    extra_bad_faces : (k,) int64, optional
        Faces to relabel first (e.g. faces that folded in a previous embedding).

    Returns
    -------
    (m,) int64
        The repaired labels (the caller validates them again).
    """
    labels = labels.copy()
    n = V.shape[0]
    VF = _vertex_faces(F, n)
    if extra_bad_faces is not None and len(extra_bad_faces):
        labels = _relabel_faces(g, labels, np.asarray(extra_bad_faces, np.int64))
    for _ in range(max_rounds):
        nch, chart = charts_of(g, labels)
        # 1. small charts and island charts (one neighbouring chart) -> merge
        area = np.bincount(chart, weights=g.areas, minlength=nch)
        ef = g.edge_faces
        ca, cb = chart[ef[:, 0]], chart[ef[:, 1]]
        cut = ca != cb
        pairs = np.unique(np.sort(np.stack([ca[cut], cb[cut]], 1), axis=1), axis=0)
        n_nb = np.bincount(pairs.ravel(), minlength=nch)
        bad_chart = (area < min_chart_area) | (n_nb < 3)
        if bad_chart.any():
            order = np.argsort(area + np.where(n_nb < 2, -1e300, 0.0), kind="stable")
            c = int([c for c in order if bad_chart[c]][0])
            faces = np.flatnonzero(chart == c)
            mask = np.zeros(labels.size, bool)
            mask[faces] = True
            new = _best_neighbor_label(g, labels, faces, mask)
            if new is not None:
                labels[faces] = new
                continue
        # 2. opposite labels across an edge
        opp = cut & ((labels[ef[:, 0]] ^ 1) == labels[ef[:, 1]])
        bad = np.zeros(labels.size, bool)
        if opp.any():
            e = ef[opp]
            small = np.where(area[chart[e[:, 0]]] <= area[chart[e[:, 1]]], e[:, 0], e[:, 1])
            bad[small] = True
        # 3. vertex configurations
        badv = _bad_vertex_faces(F, VF, labels, chart, cut, g)
        if not bad.any() and not badv.any():
            return labels
        if bad.any():
            labels = _relabel_faces(g, labels, np.flatnonzero(bad))
        else:
            labels = _flood_fans(F, VF, labels, chart, area, badv)
    return labels


def _bad_vertex_faces(F, VF, labels, chart, cut, g) -> np.ndarray:
    """Vertices in an invalid chart configuration, ``(n,)`` bool."""
    n = VF.shape[0]
    m = labels.size
    # charts per vertex
    vf = VF.tocoo()
    key = np.unique(np.stack([vf.row, chart[vf.col]], 1), axis=0)
    n_charts = np.bincount(key[:, 0], minlength=n)
    lab_of_chart = np.zeros(chart.max() + 1, np.int64)
    lab_of_chart[chart] = labels
    lk = np.unique(np.stack([key[:, 0], lab_of_chart[key[:, 1]]], 1), axis=0)
    has = np.zeros((n, 6), bool)
    has[lk[:, 0], lk[:, 1]] = True
    axes = has[:, 0::2] | has[:, 1::2]
    n_axes = axes.sum(1)
    opposite = (has[:, 0::2] & has[:, 1::2]).any(1)
    # border edges per vertex (pinch test for two-chart vertices)
    be = g.edges[cut]
    n_border = np.bincount(be.ravel(), minlength=n)
    badv = opposite | ((n_charts >= 3) & (n_axes < 3)) | ((n_charts == 2) & (n_border != 2))
    # two charts of the same label around one vertex
    badv |= n_charts > np.bincount(lk[:, 0], minlength=n)
    return badv


def _flood_fans(F, VF, labels, chart, area, badv) -> np.ndarray:
    """Give every face around each bad vertex the label of its largest chart there."""
    labels = labels.copy()
    vs = np.flatnonzero(badv)
    sub = VF[vs].tocoo()
    v_of = vs[sub.row]
    f_of = sub.col
    a = area[chart[f_of]]
    order = np.lexsort((-a, v_of))
    v_sorted = v_of[order]
    first = np.ones(order.size, bool)
    first[1:] = v_sorted[1:] != v_sorted[:-1]
    best = np.zeros(VF.shape[0], np.int64)
    best[v_sorted[first]] = labels[f_of[order][first]]
    labels[f_of] = best[v_of]
    return labels


def flood_labels(g: FaceGraph, labels: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Give all listed faces one label, ``(m,)`` int64.

    The area-weighted majority label, or, when the faces carry two opposite
    labels (a thin part whose two sides meet), the label of another axis that
    best matches their summed normal, which bridges the two sides.
    """
    labels = labels.copy()
    faces = np.asarray(faces, np.int64)
    if faces.size:
        w = np.bincount(labels[faces], weights=g.areas[faces], minlength=6)
        both = (w[0::2] > 0) & (w[1::2] > 0)
        if both.any():
            # opposite labels meet: bridge them with the best label of another axis
            n = (g.normals[faces] * g.areas[faces, None]).sum(axis=0)
            score = LABEL_DIRECTIONS @ n
            score[np.repeat(both, 2)] = -np.inf
            labels[faces] = int(np.argmax(score))
        else:
            labels[faces] = int(np.argmax(w))
    return labels


def merge_chart(g: FaceGraph, labels: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Relabel one chart's faces with the best label found across its border."""
    labels = labels.copy()
    mask = np.zeros(labels.size, bool)
    mask[faces] = True
    new = _best_neighbor_label(g, labels, faces, mask)
    if new is not None:
        labels[faces] = new
    return labels


def _relabel_faces(g: FaceGraph, labels: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Give each listed face the label most of its surroundings (by length) carry."""
    labels = labels.copy()
    data = _data_cost(g)
    h = float(np.mean(g.edge_length))
    # majority over the 2-ring of faces: neighbours and neighbours' neighbours
    nb1 = g.neighbors[faces]
    nb2 = g.neighbors[nb1.ravel()].reshape(len(faces), -1)
    ring = np.concatenate([nb1, nb2], axis=1)
    votes = np.zeros((len(faces), 6))
    for k in range(ring.shape[1]):
        votes[np.arange(len(faces)), labels[ring[:, k]]] += 1.0
    score = votes * h * h - data[faces] * 0.5
    labels[faces] = np.argmax(score, axis=1)
    return labels
