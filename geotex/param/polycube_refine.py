"""Local refinement for the polycube: split mesh edges that would lie flat.

A face whose three corners all lie on one polycube edge (a staircase border
along mesh edges) would be collinear on the polycube.  Splitting its *chord*
(a non-border edge whose two ends touch the same neighbouring chart) at the
midpoint adds a vertex inside the chart and removes the flat face without
changing the surface geometry (the new triangles lie in the old ones).
"""

from __future__ import annotations

import numpy as np

__all__ = ["flat_face_chords", "split_edges"]


def flat_face_chords(F: np.ndarray, labels: np.ndarray, vertex_chart: np.ndarray,
                     chart: np.ndarray, neighbors: np.ndarray, faces: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """One chord per flat face.

    A chord is a face edge whose ends touch a common chart of another axis and
    whose neighbouring face lies in the same chart (it is not a border edge).

    Returns
    -------
    chords : (k, 2) int64
        Vertex pairs of the chords found.
    no_chord : (j,) int64
        Flat faces without a chord (to be relabelled instead).
    """
    a = labels[faces] // 2
    cand = np.zeros((faces.size, 3), bool)
    for k in range(3):
        vi, vj = vertex_chart[F[faces, k]], vertex_chart[F[faces, (k + 1) % 3]]
        common = (vi >= 0) & (vi == vj)
        common[np.arange(faces.size), a] = False
        inside = chart[neighbors[faces, k]] == chart[faces]
        cand[:, k] = common.any(axis=1) & inside
    has = cand.any(axis=1)
    k = np.argmax(cand, axis=1)[has]
    f = faces[has]
    chords = np.stack([F[f, k], F[f, (k + 1) % 3]], axis=1)
    return chords, faces[~has]


def split_edges(V: np.ndarray, F: np.ndarray, labels: np.ndarray, edges: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split each listed edge at its midpoint.

    Parameters
    ----------
    edges : (k, 2) int64
        Edges to split; no face may hold two of them (the caller picks a
        subset; extra ones are ignored).

    Returns
    -------
    V2 : (n + s, 3) float64
    F2 : (m + 2 s, 3) int64
    labels2 : (m + 2 s,) int64
        Children keep their parent face's label.
    """
    n, m = V.shape[0], F.shape[0]
    e = np.unique(np.sort(np.asarray(edges, np.int64).reshape(-1, 2), axis=1), axis=0)
    if e.size == 0:
        return V, F, labels
    key = e[:, 0] * n + e[:, 1]
    Fn = np.roll(F, -1, axis=1)
    fk = np.minimum(F, Fn) * n + np.maximum(F, Fn)  # (m, 3)
    pos = np.searchsorted(key, fk)
    pos = np.minimum(pos, key.size - 1)
    hit = key[pos] == fk
    # at most one split edge per face: drop edges touching a face with several
    several = hit.sum(axis=1) > 1
    if several.any():
        drop = np.unique(pos[several][hit[several]])
        keep = np.ones(key.size, bool)
        keep[drop] = False
        if not keep.any():
            keep[0] = True
        return split_edges(V, F, labels, e[keep])
    mid_index = n + np.arange(e.shape[0])
    V2 = np.vstack([V, 0.5 * (V[e[:, 0]] + V[e[:, 1]])])
    f, k = np.nonzero(hit)
    mvert = mid_index[pos[f, k]]
    a = F[f, k]
    b = F[f, (k + 1) % 3]
    c = F[f, (k + 2) % 3]
    F2 = F.copy()
    F2[f] = np.stack([a, mvert, c], axis=1)
    extra = np.stack([mvert, b, c], axis=1)
    F2 = np.vstack([F2, extra])
    labels2 = np.concatenate([labels, labels[f]])
    return V2, F2, labels2


def split_faces(V: np.ndarray, F: np.ndarray, labels: np.ndarray, faces: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split each listed face into three at its centroid (children keep the label).

    Returns
    -------
    V2 : (n + k, 3), F2 : (m + 2k, 3), labels2 : (m + 2k,)
    """
    faces = np.unique(np.asarray(faces, np.int64))
    if faces.size == 0:
        return V, F, labels
    n = V.shape[0]
    c = n + np.arange(faces.size)
    V2 = np.vstack([V, V[F[faces]].mean(axis=1)])
    a, b, d = F[faces, 0], F[faces, 1], F[faces, 2]
    F2 = F.copy()
    F2[faces] = np.stack([a, b, c], 1)
    F2 = np.vstack([F2, np.stack([b, d, c], 1), np.stack([d, a, c], 1)])
    return V2, F2, np.concatenate([labels, labels[faces], labels[faces]])


def border_chords(edges: np.ndarray, edge_faces: np.ndarray, chart: np.ndarray,
                  labels: np.ndarray, vertex_chart: np.ndarray) -> np.ndarray:
    """Chart-interior edges whose two ends lie on one polycube line, ``(k, 2)`` int64.

    Both ends touch a common chart of another axis, so both end up on the same
    straight polycube edge; the triangles between such a chord and the border
    would be squeezed flat.  Splitting the chord adds a free interior vertex.
    """
    fa, fb = edge_faces[:, 0], edge_faces[:, 1]
    inside = chart[fa] == chart[fb]
    vi, vj = vertex_chart[edges[:, 0]], vertex_chart[edges[:, 1]]
    common = (vi >= 0) & (vi == vj)
    common[np.arange(edges.shape[0]), labels[fa] // 2] = False
    return edges[inside & common.any(axis=1)]
