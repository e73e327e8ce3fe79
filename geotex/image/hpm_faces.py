"""Per-fit helpers of hierarchical pattern mapping (:mod:`geotex.image.hpm`).

A mapping of a 10k-face base makes about 3000 fits at its face level, most
of them of one triangle; each fit used to redo, with generic small-array
numpy code, work that depends on the mesh only or that a compiled loop does
without temporaries.  What is here gives :func:`geotex.image.hpm.hpm_texture`
the same values bit for bit (tested):

* :func:`textured_band`: the textured faces within a surface distance of a
  cluster (a multi-source Dijkstra along mesh edges stopped at the band
  width, then the faces whose three vertices it reached), compiled: it
  visits the band's neighbourhood only instead of the whole mesh
  (:func:`scipy.sparse.csgraph.dijkstra` validates the graph and allocates
  and scans per-vertex arrays on every call);
* :func:`field_coefficients`: for every face, the coefficients that carry
  its field vector through its linear map (the least-squares solve of
  ``field_angle`` in :func:`geotex.image.hpm.hpm_texture`), once for the
  mesh instead of once per fit.
"""

from __future__ import annotations

import heapq

import numpy as np

from geotex.jit import compiled

__all__ = ["textured_band", "field_coefficients", "vertex_faces"]


def vertex_faces(F: np.ndarray, n: int):
    """The faces around every vertex, as a CSR pair.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n : int
        Number of vertices.

    Returns
    -------
    ptr : numpy.ndarray, (n + 1,) int64
    faces : numpy.ndarray, (3 m,) int64
        ``faces[ptr[v]:ptr[v + 1]]`` are the faces with corner ``v``, ascending.
    """
    flat = F.ravel()
    order = np.argsort(flat, kind="stable")
    ptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(flat, minlength=n), out=ptr[1:])
    return ptr, (order // 3).astype(np.int64)


def textured_band(graph, src, limit: float, vf, F, done):
    """Faces ``done`` whose three vertices lie within ``limit`` of ``src`` along ``G``.

    The same faces as ``np.flatnonzero(done & np.isfinite(dijkstra(G,
    directed=True, indices=src, min_only=True, limit=limit))[F].all(axis=1))``
    (a vertex is reached when its shortest distance, summed edge by edge
    from a source, is at most ``limit``: the distances are the same sums,
    whatever the order the vertices are reached in).

    Parameters
    ----------
    graph : tuple
        ``(indptr, indices, data)`` of ``G``, a CSR matrix (n, n) of the edge
        lengths with both directions stored, as int64, int64 and float64.
    src : numpy.ndarray, (s,) int64
        Source vertices (distance 0).
    limit : float
    vf : tuple
        :func:`vertex_faces` of ``F``.
    F : numpy.ndarray, (m, 3) int64
    done : numpy.ndarray, (m,) bool

    Returns
    -------
    numpy.ndarray, (k,) int64
        Ascending face indices.
    """
    indptr, indices, data = graph
    return _band_compiled(indptr, indices, data, np.asarray(src, np.int64), float(limit),
                          vf[0], vf[1], F, done)


@compiled
def _band_compiled(indptr, indices, weights, src, limit, vf_ptr, vf_faces, F, done):
    n = indptr.size - 1
    dist = np.full(n, np.inf)
    scanned = np.zeros(n, np.bool_)
    heap = [(0.0, np.int64(0))]
    heap.pop()
    for s in src:
        if dist[s] > 0.0:
            dist[s] = 0.0
            heapq.heappush(heap, (0.0, s))
    reached = []
    while len(heap):
        d, v = heapq.heappop(heap)
        if scanned[v] or d > dist[v]:
            continue
        scanned[v] = True
        reached.append(v)
        for j in range(indptr[v], indptr[v + 1]):
            u = indices[j]
            if not scanned[u]:
                nv = d + weights[j]
                if nv <= limit and nv < dist[u]:
                    dist[u] = nv
                    heapq.heappush(heap, (nv, u))
    seen = np.zeros(F.shape[0], np.bool_)
    out = []
    for v in reached:
        for j in range(vf_ptr[v], vf_ptr[v + 1]):
            fc = vf_faces[j]
            if seen[fc]:
                continue
            seen[fc] = True
            if done[fc] and scanned[F[fc, 0]] and scanned[F[fc, 1]] and scanned[F[fc, 2]]:
                out.append(fc)
    res = np.empty(len(out), np.int64)
    for i in range(len(out)):
        res[i] = out[i]
    res.sort()
    return res


def field_coefficients(V: np.ndarray, F: np.ndarray, fvec: np.ndarray) -> np.ndarray:
    """Per face, the coefficients of its field vector in its two edge vectors.

    With ``E = [P1 - P0, P2 - P0]`` (3 x 2) the face's edges and ``G = E^T E``
    (regularised by ``1e-12 trace G``), ``coef = G^-1 E^T v``: the field
    vector ``v`` of the face is ``E coef`` (its part in the face's plane), so
    a linear map of the face that takes ``E`` to ``D`` (2 x 2) takes it to
    ``D coef``.  The operations of the per-fit computation it replaces,
    on all faces at once (each face's values do not depend on the others);
    a face collapsed to a point (``G = 0``) gets ``coef = 0`` (no direction).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    fvec : numpy.ndarray, (m, 3) float64

    Returns
    -------
    numpy.ndarray, (m, 2, 1) float64
    """
    P = V[F]
    E = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]], axis=2)        # (m, 3, 2)
    G = np.einsum("kji,kjl->kil", E, E)
    G = G + 1e-12 * np.trace(G, axis1=1, axis2=2)[:, None, None] * np.eye(2)
    G[np.trace(G, axis1=1, axis2=2) == 0] = np.eye(2)      # a face collapsed to a point
    return np.linalg.solve(G, np.einsum("kji,kj->ki", E, fvec)[:, :, None])
