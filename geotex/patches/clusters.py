"""Face-cluster hierarchies (hierarchical pattern mapping §3.1).

Every level of the hierarchy is a partition of the faces into clusters, each a
topological disc bounded by mesh edges; level 0 is the single faces and every
coarser level is obtained by merging adjacent clusters of the level below.

The paper builds its general hierarchy top-down (seeded region growing inside
each cluster).  We build it bottom-up, which gives the same three properties
the paper asks for ((a) each level is a partition, (b) borders run along mesh
edges, (c) the deepest level is the faces) and makes the disc property easy to
guarantee: two disc clusters ``A`` and ``B`` that share at least one edge unite
into a disc exactly when ``chi(A ∩ B) = #shared vertices - #shared edges = 1``
(their common border is one path: ``chi(A ∪ B) = chi(A) + chi(B) - chi(A ∩ B)``),
so the test needs only two counts per adjacent pair.

Merging is greedy: each round takes a greedy matching of the valid pairs by a
cost that prefers small, flat and compact unions,
``cost = area * compactness * (1 + normal_weight * (1 - |sum_f a_f n_f| / area))``
with ``compactness = perimeter**2 / (4 pi area)``, so clusters stay of nearly
uniform size and not elongated (the paper's requirement for stable
barycentric flattening).  Rounds repeat until the level has about ``1/ratio``
of the clusters of the level below.

Control vertices (paper §3.1) are the points of a cluster's contour shared by
at least three regions of the level; the outside of an open mesh counts as a
region, so where two clusters meet on the mesh border the vertex is a control
vertex too.  A cluster with fewer than three such junctions (e.g. one of two
hemispheres of a closed sphere) gets extra corners picked on its boundary loop
by farthest-point sampling, so that every cluster has a control polygon with
at least three corners, as the paper's flattening needs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import networkx as nx
import numpy as np
import scipy.sparse as sp

from geotex.errors import InputError
from geotex.mesh.arrays import as_faces, as_mesh_arrays
from geotex.mesh.topology import edge_topology
from geotex.patches.grow import check_triangles, face_adjacency, region_topology

__all__ = ["ClusterLevel", "ClusterHierarchy", "cluster_hierarchy", "is_disc_partition",
           "disc_clusters"]


@dataclass(frozen=True, eq=False)
class ClusterLevel:
    """One level of a face-cluster hierarchy.

    Attributes
    ----------
    labels : numpy.ndarray, (m,) int64
        Cluster of every face; clusters are numbered ``0 .. n_clusters - 1`` in
        order of their lowest face index.
    n_clusters : int
    adjacency : scipy.sparse.csr_matrix, (c, c) int64
        Symmetric; entry ``(a, b)`` is the number of mesh edges clusters ``a``
        and ``b`` share (zero diagonal).
    parent : numpy.ndarray, (c,) int64
        Cluster of the next coarser level containing each cluster, ``-1`` on
        the coarsest level.
    area : numpy.ndarray, (c,) float64
        Surface area of every cluster.
    loop_ptr : numpy.ndarray, (c + 1,) int64
    loop_vertices : numpy.ndarray, (sum,) int64
        Boundary loop of cluster ``c`` is
        ``loop_vertices[loop_ptr[c]:loop_ptr[c + 1]]``: ordered global vertex
        ids, counter-clockwise seen from the normal side, starting at the
        smallest vertex id.
    control_ptr : numpy.ndarray, (c + 1,) int64
    control_vertices : numpy.ndarray, (sum,) int64
        Control vertices of each cluster in boundary-loop order (same CSR
        layout).
    control_is_junction : numpy.ndarray, (sum,) bool
        ``True`` for control vertices where at least three regions meet,
        ``False`` for the corners added to clusters with fewer than three.
    junction : numpy.ndarray, (n,) bool
        Vertices where at least three regions of this level meet (the mesh
        outside counting as one region).
    """

    labels: np.ndarray
    n_clusters: int
    adjacency: sp.csr_matrix
    parent: np.ndarray
    area: np.ndarray
    loop_ptr: np.ndarray
    loop_vertices: np.ndarray
    control_ptr: np.ndarray
    control_vertices: np.ndarray
    control_is_junction: np.ndarray
    junction: np.ndarray

    def faces(self, cluster: int) -> np.ndarray:
        """Return the faces of one cluster, ``(k,)`` int64, ascending."""
        return np.flatnonzero(self.labels == int(cluster))

    def boundary_loop(self, cluster: int) -> np.ndarray:
        """Return the ordered boundary loop of one cluster, ``(b,)`` int64."""
        c = int(cluster)
        return self.loop_vertices[self.loop_ptr[c]:self.loop_ptr[c + 1]]

    def controls(self, cluster: int) -> np.ndarray:
        """Return the control vertices of one cluster in loop order, ``(j,)`` int64."""
        c = int(cluster)
        return self.control_vertices[self.control_ptr[c]:self.control_ptr[c + 1]]

    def neighbors(self, cluster: int) -> np.ndarray:
        """Return the clusters sharing an edge with ``cluster``, ascending."""
        c = int(cluster)
        return self.adjacency.indices[self.adjacency.indptr[c]:self.adjacency.indptr[c + 1]]

    def graph(self) -> nx.Graph:
        """Return the cluster adjacency as a networkx graph.

        Nodes carry ``area``; edges carry ``shared_edges``.
        """
        G = nx.Graph()
        G.add_nodes_from((int(c), {"area": float(a)}) for c, a in enumerate(self.area))
        A = self.adjacency.tocoo()
        keep = A.row < A.col
        G.add_edges_from((int(a), int(b), {"shared_edges": int(w)})
                         for a, b, w in zip(A.row[keep], A.col[keep], A.data[keep]))
        return G


@dataclass(frozen=True, eq=False)
class ClusterHierarchy:
    """A face-cluster hierarchy, finest level first.

    Attributes
    ----------
    levels : tuple of ClusterLevel
        ``levels[0]`` is the single faces, ``levels[-1]`` the coarsest level.
    """

    levels: tuple

    def __len__(self) -> int:
        return len(self.levels)

    def __getitem__(self, level: int) -> ClusterLevel:
        return self.levels[level]

    def children(self, level: int, cluster: int) -> np.ndarray:
        """Return the clusters of ``level - 1`` that make up ``cluster`` of ``level``."""
        if level <= 0:
            raise InputError("level 0 clusters are single faces and have no children")
        return np.flatnonzero(self.levels[level - 1].parent == int(cluster))


# ---------------------------------------------------------------------------
# partition checks
# ---------------------------------------------------------------------------

def _compact(labels: np.ndarray) -> tuple[np.ndarray, int]:
    """Renumber labels ``0..c-1`` in order of their first face."""
    uniq, first, inv = np.unique(labels, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return rank[inv.ravel()].astype(np.int64), int(uniq.size)


def _labels_arg(F: np.ndarray, labels) -> np.ndarray:
    lab = np.asarray(labels)
    if lab.shape != (F.shape[0],):
        raise InputError(f"labels must have shape ({F.shape[0]},) (one per face), got {lab.shape}")
    if lab.size and lab.dtype.kind not in "iu":
        raise InputError(f"labels must be integers, got dtype {lab.dtype}")
    return lab.astype(np.int64)


def disc_clusters(F, labels) -> np.ndarray:
    """Return, for every cluster of a face labelling, whether it is a disc.

    Parameters
    ----------
    F : array_like, (m, 3) int64
    labels : array_like, (m,) int
        Any integer labels; clusters are the distinct values, in ascending
        order of label value.

    Returns
    -------
    numpy.ndarray, (c,) bool
        ``True`` where the cluster is edge-connected, manifold, has exactly
        one boundary loop and Euler characteristic 1.

    Raises
    ------
    InputError
        On malformed ``F`` or ``labels``.
    """
    F = as_faces(F)
    lab = _labels_arg(F, labels)
    if F.shape[0] == 0:
        return np.zeros(0, bool)
    _, dense = np.unique(lab, return_inverse=True)
    dense = dense.ravel().astype(np.int64)
    c = int(dense.max()) + 1
    return region_topology(F, dense, c, int(F.max()) + 1).disc


def is_disc_partition(F, labels) -> bool:
    """Return whether every cluster of a face labelling is one topological disc.

    Parameters
    ----------
    F : array_like, (m, 3) int64
    labels : array_like, (m,) int
        Cluster of every face (so the clusters cover all faces by definition).

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(2, 2)
    >>> is_disc_partition(F, np.arange(len(F)))
    True
    """
    flags = disc_clusters(F, labels)
    return bool(flags.size and flags.all())


# ---------------------------------------------------------------------------
# level construction helpers
# ---------------------------------------------------------------------------

def _cluster_loops(F, labels, C, n, FF):
    """Ordered boundary loops of every cluster of a disc partition (vectorized).

    Boundary half-edges are chained by their start vertex inside each cluster;
    each chain is a cycle, whose order is recovered by pointer jumping
    (minimum label by doubling, then list ranking), ``O(b log b)``.
    """
    m = F.shape[0]
    fidx = np.repeat(np.arange(m), 3)
    side = np.tile(np.arange(3), m)
    nb = FF.ravel()
    lab = labels[fidx]
    is_b = (nb < 0) | (labels[np.maximum(nb, 0)] != lab)
    f, k, lab = fidx[is_b], side[is_b], lab[is_b]
    s = F[f, k]
    t = F[f, (k + 1) % 3]
    key = lab * n + s
    order = np.argsort(key, kind="stable")
    key, s, t, lab = key[order], s[order], t[order], lab[order]
    N = key.size
    succ = np.searchsorted(key, lab * n + t)
    if (succ >= N).any() or (key[np.minimum(succ, N - 1)] != lab * n + t).any() \
            or np.unique(key).size != N:
        raise InputError("F must be a consistently oriented manifold mesh to order "
                         "cluster borders; orient it first (geotex.repair)")
    rep = np.arange(N)
    jump = succ.copy()
    steps = max(1, int(math.ceil(math.log2(max(N, 2)))) + 1)
    for _ in range(steps):
        rep = np.minimum(rep, rep[jump])
        jump = jump[jump]
    # list ranking: distance to the last node of the cycle opened at rep
    last = succ == rep
    nxt = np.where(last, np.arange(N), succ)
    d = (~last).astype(np.int64)
    for _ in range(steps):
        d = d + d[nxt]
        nxt = nxt[nxt]
    o = np.lexsort((-d, rep, lab))
    loop_vertices = s[o]
    loop_ptr = np.searchsorted(lab[o], np.arange(C + 1))
    return loop_ptr.astype(np.int64), loop_vertices.astype(np.int64)


def _farthest_corners(P: np.ndarray, chosen: list[int], want: int) -> list[int]:
    """Farthest-point sampling on loop positions ``P`` starting from ``chosen``."""
    chosen = list(chosen) or [0]
    d = np.min(np.linalg.norm(P[:, None, :] - P[chosen][None, :, :], axis=2), axis=1)
    while len(chosen) < min(want, P.shape[0]):
        i = int(np.argmax(d))
        chosen.append(i)
        d = np.minimum(d, np.linalg.norm(P - P[i], axis=1))
    return sorted(chosen)


def _build_level(V, F, labels, C, ctx, parent=None) -> ClusterLevel:
    n = V.shape[0]
    FF, on_border, areas, ef2 = ctx["FF"], ctx["on_border"], ctx["areas"], ctx["ef2"]
    la, lb = labels[ef2[:, 0]], labels[ef2[:, 1]]
    cross = la != lb
    rows = np.concatenate([la[cross], lb[cross]])
    cols = np.concatenate([lb[cross], la[cross]])
    adjacency = sp.coo_matrix((np.ones(rows.size, np.int64), (rows, cols)),
                              shape=(C, C)).tocsr()
    adjacency.sum_duplicates()
    lab3 = np.repeat(labels, 3)
    vk = np.unique(F.ravel() * C + lab3)
    regions = np.bincount(vk // C, minlength=n) + on_border
    junction = regions >= 3
    loop_ptr, loop_vertices = _cluster_loops(F, labels, C, n, FF)
    is_j = junction[loop_vertices]
    seg = np.repeat(np.arange(C), np.diff(loop_ptr))
    counts = np.bincount(seg[is_j], minlength=C)
    keep = is_j.copy()
    for c in np.flatnonzero(counts < 3):
        lo, hi = loop_ptr[c], loop_ptr[c + 1]
        loop = loop_vertices[lo:hi]
        picked = _farthest_corners(V[loop], np.flatnonzero(is_j[lo:hi]).tolist(), 3)
        keep[lo + np.asarray(picked, dtype=np.int64)] = True
    control_vertices = loop_vertices[keep]
    control_is_junction = is_j[keep]
    control_ptr = np.searchsorted(seg[keep], np.arange(C + 1)).astype(np.int64)
    area = np.bincount(labels, weights=areas, minlength=C)
    if parent is None:
        parent = np.full(C, -1, np.int64)
    out = ClusterLevel(labels=labels, n_clusters=int(C), adjacency=adjacency, parent=parent,
                       area=area, loop_ptr=loop_ptr, loop_vertices=loop_vertices,
                       control_ptr=control_ptr, control_vertices=control_vertices,
                       control_is_junction=control_is_junction, junction=junction)
    for arr in (labels, parent, area, loop_ptr, loop_vertices, control_ptr,
                control_vertices, control_is_junction, junction):
        arr.setflags(write=False)
    return out


def _pair_candidates(F, labels, C, ctx, normal_weight):
    """Valid merge pairs ``(a, b, cost)`` of adjacent clusters (vectorized)."""
    n = ctx["n"]
    ef2, elen2 = ctx["ef2"], ctx["elen2"]
    la, lb = labels[ef2[:, 0]], labels[ef2[:, 1]]
    cross = la != lb
    a = np.minimum(la[cross], lb[cross])
    b = np.maximum(la[cross], lb[cross])
    pk, pinv = np.unique(a * C + b, return_inverse=True)
    if pk.size == 0:
        return (np.zeros(0, np.int64),) * 2 + (np.zeros(0),)
    pinv = pinv.ravel()
    se = np.bincount(pinv, minlength=pk.size)
    slen = np.bincount(pinv, weights=elen2[cross], minlength=pk.size)
    # shared vertices: all pairs of clusters meeting at each vertex
    lab3 = np.repeat(labels, 3)
    vk = np.unique(F.ravel() * C + lab3)
    vv, vc = vk // C, vk % C
    group_max = int(np.bincount(vv, minlength=n).max())
    keys = []
    for d in range(1, group_max):
        same = vv[d:] == vv[:-d]
        keys.append(vc[:-d][same] * C + vc[d:][same])
    allk = np.concatenate(keys) if keys else np.zeros(0, np.int64)
    sk, sc = np.unique(allk, return_counts=True)
    if sk.size:
        pos = np.minimum(np.searchsorted(sk, pk), sk.size - 1)
        sv = np.where(sk[pos] == pk, sc[pos], 0)
    else:
        sv = np.zeros(pk.size, np.int64)
    valid = (sv - se) == 1
    pa, pb = pk[valid] // C, pk[valid] % C
    st = ctx["stats"]
    area, nsum, perim = st
    au = area[pa] + area[pb]
    nu = np.linalg.norm(nsum[pa] + nsum[pb], axis=1)
    flat_dev = np.clip(1.0 - nu / au, 0.0, 1.0)
    pu = perim[pa] + perim[pb] - 2.0 * slen[valid]
    compact = pu * pu / (4.0 * math.pi * au)
    cost = au * compact * (1.0 + normal_weight * flat_dev)
    return pa, pb, cost


def _cluster_stats(labels, C, ctx):
    areas, an = ctx["areas"], ctx["area_normals"]
    area = np.bincount(labels, weights=areas, minlength=C)
    nsum = np.stack([np.bincount(labels, weights=an[:, i], minlength=C) for i in range(3)], 1)
    FF, side_len = ctx["FF"], ctx["side_len"]
    nb = FF.ravel()
    lab3 = np.repeat(labels, 3)
    border = (nb < 0) | (labels[np.maximum(nb, 0)] != lab3)
    perim = np.bincount(lab3[border], weights=side_len[border], minlength=C)
    return area, nsum, perim


def _greedy_matching(pa, pb, cost, C):
    """Greedy matching by cost (ties by pair order), as iterated local dominance."""
    P = pa.size
    rank = np.empty(P, np.int64)
    rank[np.lexsort((pb, pa, cost))] = np.arange(P)
    matched = np.zeros(C, bool)
    alive = np.ones(P, bool)
    chosen = []
    while alive.any():
        idx = np.flatnonzero(alive)
        best = np.full(C, P, np.int64)
        np.minimum.at(best, pa[idx], rank[idx])
        np.minimum.at(best, pb[idx], rank[idx])
        r = rank[idx]
        sel = idx[(best[pa[idx]] == r) & (best[pb[idx]] == r)]
        chosen.append(sel)
        matched[pa[sel]] = True
        matched[pb[sel]] = True
        alive &= ~(matched[pa] | matched[pb])
    sel = np.concatenate(chosen) if chosen else np.zeros(0, np.int64)
    return sel[np.argsort(rank[sel], kind="stable")]


def cluster_hierarchy(V, F, *, levels: int | None = None, min_clusters: int = 1,
                      ratio: float = 4.0, normal_weight: float = 10.0) -> ClusterHierarchy:
    """Build a face-cluster hierarchy whose clusters are all discs.

    See the module docstring for the algorithm (bottom-up greedy merging of
    adjacent clusters whose union is a disc) and the definition of control
    vertices (hierarchical pattern mapping §3.1).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A consistently oriented mesh without faces that repeat a vertex.
        Non-manifold edges are allowed but never merged across.
    levels : int, optional
        Maximum number of levels, including level 0 (single faces).  By
        default levels are added until ``min_clusters`` is reached or no
        adjacent pair can merge into a disc (a closed surface always keeps at
        least two clusters).
    min_clusters : int, optional
        Stop coarsening at this many clusters.
    ratio : float, optional
        Each level aims at ``1 / ratio`` of the clusters of the level below
        (``> 1``).
    normal_weight : float, optional
        Weight of the planarity penalty ``1 - |sum a_f n_f| / area`` in the
        merge cost (``>= 0``).

    Returns
    -------
    ClusterHierarchy
        ``levels[0].labels == arange(m)``; every level is a disc partition and
        ``levels[l + 1].labels == levels[l].parent[levels[l].labels]``.

    Raises
    ------
    InputError
        On malformed arrays, an empty mesh, faces repeating a vertex, an
        inconsistently oriented mesh, or out-of-range options.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> H = cluster_hierarchy(V, F)
    >>> H[0].n_clusters, all(is_disc_partition(F, lv.labels) for lv in H.levels)
    (320, True)
    """
    V, F = as_mesh_arrays(V, F)
    m, n = F.shape[0], V.shape[0]
    if m == 0:
        raise InputError("F is empty: the mesh has no faces to cluster")
    check_triangles(F)
    if levels is not None and (int(levels) != levels or levels < 1):
        raise InputError(f"levels must be an integer >= 1, got {levels!r}")
    if int(min_clusters) != min_clusters or min_clusters < 1:
        raise InputError(f"min_clusters must be an integer >= 1, got {min_clusters!r}")
    if not (float(ratio) > 1.0 and math.isfinite(float(ratio))):
        raise InputError(f"ratio must be a finite number > 1, got {ratio!r}")
    if not (float(normal_weight) >= 0.0 and math.isfinite(float(normal_weight))):
        raise InputError(f"normal_weight must be a finite number >= 0, got {normal_weight!r}")
    topo = edge_topology(F, n)
    if topo.inconsistent.size:
        raise InputError("F is not consistently oriented (an edge is traversed twice in the "
                         "same direction); orient it first (geotex.repair)")
    adj = face_adjacency(V, F)
    FE = adj.face_edges
    count = topo.face_count
    ef = topo.edge_faces()
    two = count == 2
    ed = topo.edges
    elen = np.linalg.norm(V[ed[:, 1]] - V[ed[:, 0]], axis=1)
    on_border = np.zeros(n, np.int64)
    on_border[ed[~two].ravel()] = 1
    ctx = {
        "n": n, "FF": adj.face_neighbors, "areas": adj.areas,
        "area_normals": adj.normals * adj.areas[:, None], "ef2": ef[two], "elen2": elen[two],
        "side_len": elen[FE.ravel()], "on_border": on_border,
    }
    labels = np.arange(m, dtype=np.int64)
    C = m
    built: list[tuple[np.ndarray, int]] = [(labels, C)]
    while (levels is None or len(built) < levels) and C > min_clusters:
        target = max(int(min_clusters), int(math.ceil(C / float(ratio))))
        cur, cc = labels, C
        while cc > target:
            ctx["stats"] = _cluster_stats(cur, cc, ctx)
            pa, pb, cost = _pair_candidates(F, cur, cc, ctx, float(normal_weight))
            if pa.size == 0:
                break
            sel = _greedy_matching(pa, pb, cost, cc)[: cc - target]
            if sel.size == 0:
                break
            root = np.arange(cc, dtype=np.int64)
            root[pb[sel]] = pa[sel]
            cur, cc = _compact(root[cur])
        if cc == C:
            break
        labels, C = cur, cc
        built.append((labels, C))
    out = []
    for i, (lab, c) in enumerate(built):
        parent = None
        if i + 1 < len(built):
            nxt = built[i + 1][0]
            parent = np.empty(c, np.int64)
            parent[lab] = nxt
        out.append(_build_level(V, F, lab, c, ctx, parent))
    return ClusterHierarchy(levels=tuple(out))
