"""Face-cluster hierarchies, built top-down (hierarchical pattern mapping §3.1).

The coarsest level holds the whole surface (one cluster per connected
component).  Every cluster is then split, level after level, into a variable
number ``n`` of sub-clusters by seeded growth: ``n`` seed faces are chosen
inside the cluster (the first at random, the others by farthest-point
sampling, which keeps the sub-clusters compact), and every face joins the
seed it is closest to along the dual graph of the cluster (centroid-to-centroid
distances, edges crossing the cluster's border removed).  This is the paper's
growth ("each untreated face sharing an edge with a growing sub-region joins
the sub-region whose seed is nearest") computed for every cluster of a level
at once by one multi-source Dijkstra (:func:`scipy.sparse.csgraph.dijkstra`).
``n`` adapts to the cluster's area so that clusters of one level have a
nearly uniform size: ``branching ** level`` clusters on a level, until that
would make clusters of at most ``leaf_faces`` faces; the finest cluster
level then has at most about ``2 * leaf_faces`` faces per cluster (one more
split to ``leaf_faces`` faces is made when needed), so that a cluster that
cannot be textured at that level leaves only a few faces to the face level.

After growth, borders are regularized by exchanging triangles: a face two of
whose three neighbours (inside the same parent) belong to one other
sub-cluster moves to it (a notch in the border disappears); exchanges that
would break a sub-cluster's disc topology are undone.  A sub-cluster that is
not a disc (an annulus around a handle, a ring around another sub-cluster)
gets one more seed and the growth of its parent is redone, until every
sub-cluster is a disc.  Splitting stops when clusters have at most
``leaf_faces`` faces; the last level is the single faces.

Control vertices (paper §3.1) are the points of a cluster's contour shared by
at least three regions of the level; the outside of an open mesh counts as a
region.  A cluster with fewer than three such junctions gets extra corners
on its boundary loop by farthest-point sampling, and a cluster whose control
points are nearly aligned (the second singular value of the centred points
below ``0.15`` times the first; the paper's *non-alignment property*, needed
for stable barycentric coordinates) gets the loop vertex farthest from their
line as an extra corner.

Children are numbered by parent, so the descendants of a cluster form one
contiguous range of clusters on every finer level (``child_ptr``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

from geotex.errors import InputError, SolverError
from geotex.mesh.arrays import as_faces, as_mesh_arrays
from geotex.mesh.topology import edge_topology
from geotex.patches.grow import check_triangles, face_adjacency, region_topology

__all__ = ["ClusterLevel", "ClusterHierarchy", "cluster_hierarchy", "is_disc_partition",
           "disc_clusters"]

ALIGNMENT_RATIO = 0.15


@dataclass(frozen=True, eq=False)
class ClusterLevel:
    """One level of a face-cluster hierarchy.

    Attributes
    ----------
    labels : numpy.ndarray, (m,) int64
        Cluster of every face, ``0 .. n_clusters - 1``; clusters are numbered
        by parent (the children of one parent are consecutive).
    n_clusters : int
    adjacency : scipy.sparse.csr_matrix, (c, c) int64
        Symmetric; entry ``(a, b)`` is the number of mesh edges clusters ``a``
        and ``b`` share (zero diagonal).
    parent : numpy.ndarray, (c,) int64
        Cluster of the next coarser level containing each cluster, ``-1`` on
        the coarsest level; non-decreasing.
    child_ptr : numpy.ndarray, (c + 1,) int64
        Children of cluster ``c`` on the next finer level are
        ``child_ptr[c] .. child_ptr[c + 1] - 1`` (empty on the face level).
    area : numpy.ndarray, (c,) float64
        Surface area of every cluster.
    disc : numpy.ndarray, (c,) bool
        Whether each cluster is a topological disc (all clusters below the
        coarsest level are).
    loop_ptr : numpy.ndarray, (c + 1,) int64
    loop_vertices : numpy.ndarray, (sum,) int64
        Boundary loop of disc cluster ``c`` is
        ``loop_vertices[loop_ptr[c]:loop_ptr[c + 1]]``: ordered global vertex
        ids, counter-clockwise seen from the normal side, starting at the
        smallest vertex id (empty for a cluster that is not a disc).
    control_ptr : numpy.ndarray, (c + 1,) int64
    control_vertices : numpy.ndarray, (sum,) int64
        Control vertices of each cluster in boundary-loop order (same CSR
        layout).
    control_is_junction : numpy.ndarray, (sum,) bool
        ``True`` for control vertices where at least three regions meet,
        ``False`` for the corners added (fewer than three junctions, or
        aligned junctions).
    junction : numpy.ndarray, (n,) bool
        Vertices where at least three regions of this level meet (the mesh
        outside counting as one region).
    """

    labels: np.ndarray
    n_clusters: int
    adjacency: sp.csr_matrix
    parent: np.ndarray
    child_ptr: np.ndarray
    area: np.ndarray
    disc: np.ndarray
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

    def graph(self) -> "networkx.Graph":
        """Return the cluster adjacency as a networkx graph.

        Nodes carry ``area``; edges carry ``shared_edges``.
        """
        import networkx as nx       # lazy: ~0.25 s, and only this method needs it

        G = nx.Graph()
        G.add_nodes_from((int(c), {"area": float(a)}) for c, a in enumerate(self.area))
        A = self.adjacency.tocoo()
        keep = A.row < A.col
        G.add_edges_from((int(a), int(b), {"shared_edges": int(w)})
                         for a, b, w in zip(A.row[keep], A.col[keep], A.data[keep]))
        return G


@dataclass(frozen=True, eq=False)
class ClusterHierarchy:
    """A face-cluster hierarchy, coarsest level first.

    Attributes
    ----------
    levels : tuple of ClusterLevel
        ``levels[0]`` is the whole surface (one cluster per connected
        component), ``levels[-1]`` the single faces.
    """

    levels: tuple

    def __len__(self) -> int:
        return len(self.levels)

    def __getitem__(self, level: int) -> ClusterLevel:
        return self.levels[level]

    def children(self, level: int, cluster: int) -> np.ndarray:
        """Return the clusters of ``level + 1`` that make up ``cluster`` of ``level``."""
        if level >= len(self.levels) - 1:
            raise InputError("the last level holds single faces, which have no children")
        ptr = self.levels[level].child_ptr
        return np.arange(ptr[int(cluster)], ptr[int(cluster) + 1], dtype=np.int64)

    def descendants(self, level: int, cluster: int, deeper: int) -> tuple[int, int]:
        """Return the range ``(lo, hi)`` of clusters of level ``deeper`` inside ``cluster``."""
        lo, hi = int(cluster), int(cluster) + 1
        for lv in range(level, deeper):
            ptr = self.levels[lv].child_ptr
            lo, hi = int(ptr[lo]), int(ptr[hi])
        return lo, hi


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

def _cluster_loops(F, labels, C, n, FF, keep):
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
    is_b = ((nb < 0) | (labels[np.maximum(nb, 0)] != lab)) & keep[lab]
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


def _align_fix(V, loop, ctrl_idx) -> list[int]:
    """Add the loop vertex farthest from the principal line of aligned control points."""
    P = V[loop]
    C = P[ctrl_idx]
    c0 = C.mean(axis=0)
    _, s, vt = np.linalg.svd(C - c0, full_matrices=False)
    d = P - c0
    off = d - np.outer(d @ vt[0], vt[0])
    dist = np.linalg.norm(off, axis=1)
    dist[ctrl_idx] = -1.0
    k = int(np.argmax(dist))
    return sorted(set(ctrl_idx) | {k})


def _build_level(V, F, labels, C, parent, child_ptr, ctx) -> ClusterLevel:
    n = V.shape[0]
    FF, on_border, areas, ef2 = ctx["FF"], ctx["on_border"], ctx["areas"], ctx["ef2"]
    la, lb = labels[ef2[:, 0]], labels[ef2[:, 1]]
    cross = la != lb
    rows = np.concatenate([la[cross], lb[cross]])
    cols = np.concatenate([lb[cross], la[cross]])
    adjacency = sp.coo_matrix((np.ones(rows.size, np.int64), (rows, cols)),
                              shape=(C, C)).tocsr()
    adjacency.sum_duplicates()
    disc = region_topology(F, labels, C, n).disc
    lab3 = np.repeat(labels, 3)
    vk = np.unique(F.ravel() * C + lab3)
    regions = np.bincount(vk // C, minlength=n) + on_border
    junction = regions >= 3
    loop_ptr, loop_vertices = _cluster_loops(F, labels, C, n, FF, disc)
    is_j = junction[loop_vertices]
    seg = np.repeat(np.arange(C), np.diff(loop_ptr))
    counts = np.bincount(seg[is_j], minlength=C)
    keep = is_j.copy()
    for c in np.flatnonzero((counts < 3) & disc):
        lo, hi = loop_ptr[c], loop_ptr[c + 1]
        picked = _farthest_corners(V[loop_vertices[lo:hi]], np.flatnonzero(is_j[lo:hi]).tolist(), 3)
        keep[lo + np.asarray(picked, dtype=np.int64)] = True
    # non-alignment property: second singular value of the control points vs the first
    for _ in range(16):
        ks = seg[keep]
        P = V[loop_vertices[keep]]
        cnt = np.maximum(np.bincount(ks, minlength=C), 1)
        mean = np.stack([np.bincount(ks, weights=P[:, i], minlength=C) for i in range(3)],
                        1).astype(np.float64)
        mean /= cnt[:, None]
        D = P - mean[ks]
        cov = np.zeros((C, 3, 3))
        for i in range(3):
            for j in range(3):
                cov[:, i, j] = np.bincount(ks, weights=D[:, i] * D[:, j], minlength=C)
        ev = np.linalg.eigvalsh(cov)
        s1 = np.sqrt(np.maximum(ev[:, 2], 0.0))
        s2 = np.sqrt(np.maximum(ev[:, 1], 0.0))
        bad = disc & (s2 < ALIGNMENT_RATIO * s1) & (np.diff(loop_ptr) > np.bincount(ks, minlength=C))
        if not bad.any():
            break
        for c in np.flatnonzero(bad):
            lo, hi = loop_ptr[c], loop_ptr[c + 1]
            picked = _align_fix(V, loop_vertices[lo:hi], np.flatnonzero(keep[lo:hi]).tolist())
            keep[lo + np.asarray(picked, dtype=np.int64)] = True
    control_vertices = loop_vertices[keep]
    control_is_junction = is_j[keep]
    control_ptr = np.searchsorted(seg[keep], np.arange(C + 1)).astype(np.int64)
    area = np.bincount(labels, weights=areas, minlength=C)
    out = ClusterLevel(labels=labels, n_clusters=int(C), adjacency=adjacency, parent=parent,
                       child_ptr=child_ptr, area=area, disc=disc, loop_ptr=loop_ptr,
                       loop_vertices=loop_vertices, control_ptr=control_ptr,
                       control_vertices=control_vertices,
                       control_is_junction=control_is_junction, junction=junction)
    for arr in (labels, parent, child_ptr, area, disc, loop_ptr, loop_vertices, control_ptr,
                control_vertices, control_is_junction, junction):
        arr.setflags(write=False)
    return out


# ---------------------------------------------------------------------------
# top-down splitting
# ---------------------------------------------------------------------------

def _dual_graph(plab, ctx) -> sp.csr_matrix:
    """Dual graph restricted to face pairs inside the same parent cluster."""
    ef2, w = ctx["ef2"], ctx["dual_w"]
    same = plab[ef2[:, 0]] == plab[ef2[:, 1]]
    a, b, ww = ef2[same, 0], ef2[same, 1], w[same]
    m = plab.size
    return sp.csr_matrix((np.concatenate([ww, ww]), (np.concatenate([a, b]),
                                                      np.concatenate([b, a]))), shape=(m, m))


def _first_per_group(group: np.ndarray, score: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Index of the maximal ``score`` among ``mask`` entries of every group (-1 if none)."""
    idx = np.flatnonzero(mask)
    out = np.full(int(group.max()) + 1 if group.size else 0, -1, np.int64)
    if idx.size == 0:
        return out
    o = idx[np.lexsort((idx, -score[idx], group[idx]))]
    g = group[o]
    first = np.ones(o.size, bool)
    first[1:] = g[1:] != g[:-1]
    out[g[first]] = o[first]
    return out


def _grow(G, seeds, m):
    dist, _, src = dijkstra(G, directed=False, indices=seeds, min_only=True,
                            return_predecessors=True)
    return dist, src


def _split_level(plab, Cp, want, ctx, rng):
    """Split every parent cluster into ``want[p]`` sub-clusters by seeded growth.

    Returns child labels numbered by (parent, seed order) and the child parents.
    """
    m = plab.size
    G = _dual_graph(plab, ctx)
    order = np.argsort(plab, kind="stable")
    cnt = np.bincount(plab, minlength=Cp)
    off = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    first = order[off + np.minimum((rng.random(Cp) * cnt).astype(np.int64), cnt - 1)]
    seeds = [first]
    seed_parent = [np.arange(Cp)]
    for r in range(2, int(want.max()) + 1):
        dist, _ = _grow(G, np.concatenate(seeds), m)
        need = want[plab] >= r
        far = _first_per_group(plab, dist, need & np.isfinite(dist) & (dist > 0))
        new = far[far >= 0]
        if new.size == 0:
            break
        seeds.append(new)
        seed_parent.append(plab[new])
    seeds_a = np.concatenate(seeds)
    sp_a = np.concatenate(seed_parent)
    for _attempt in range(12):
        dist, src = _grow(G, seeds_a, m)
        if (src < 0).any():
            raise SolverError("cluster growth did not reach every face; the mesh has faces "
                              "connected only through non-manifold edges")
        pos = np.empty(m, np.int64)
        pos[seeds_a] = np.arange(seeds_a.size)
        raw = pos[src]
        raw = _regularize(raw, plab, seeds_a, ctx, m)
        # number children by (parent, seed order)
        rank = np.lexsort((np.arange(seeds_a.size), sp_a))
        inv = np.empty_like(rank)
        inv[rank] = np.arange(rank.size)
        lab = inv[raw]
        C = seeds_a.size
        disc = region_topology(ctx["F"], lab, C, ctx["n"]).disc
        if disc.all():
            return lab, sp_a[rank], C
        # one more seed inside every non-disc child: its face farthest from its seed
        bad_face = ~disc[lab]
        far = _first_per_group(lab, dist, bad_face & (dist > 0))
        new = far[far >= 0]
        if new.size == 0:
            break
        seeds_a = np.concatenate([seeds_a, new])
        sp_a = np.concatenate([sp_a, plab[new]])
    raise SolverError("could not split the surface into disc-shaped clusters; the mesh may "
                      "have a very thin handle or be badly shaped: remesh it first")


def _regularize(raw, plab, seeds, ctx, m, passes: int = 2):
    """Exchange triangles along sub-cluster borders (a face two of whose neighbours are
    in one other sub-cluster moves to it); moves that break a disc are undone."""
    FF = ctx["FF"]
    lab = raw.copy()
    is_seed = np.zeros(m, bool)
    is_seed[seeds] = True
    C = int(seeds.size)
    for _ in range(passes):
        valid = FF >= 0
        nb = np.where(valid, lab[np.maximum(FF, 0)], -1)
        same_parent = valid & (plab[np.maximum(FF, 0)] == plab[:, None])
        nb = np.where(same_parent, nb, -1)
        target = np.full(m, -1, np.int64)
        for i, j in ((0, 1), (1, 2), (0, 2)):
            ok = (nb[:, i] == nb[:, j]) & (nb[:, i] >= 0) & (nb[:, i] != lab)
            target = np.where(ok & (target < 0), nb[:, i], target)
        move = (target >= 0) & ~is_seed
        if not move.any():
            break
        new = lab.copy()
        new[move] = target[move]
        disc = region_topology(ctx["F"], new, C, ctx["n"]).disc
        old_disc = region_topology(ctx["F"], lab, C, ctx["n"]).disc
        broken = ~disc & old_disc
        if broken.any():
            undo = move & (broken[lab] | broken[target])
            new[undo] = lab[undo]
            disc = region_topology(ctx["F"], new, C, ctx["n"]).disc
            if (~disc & old_disc).any():
                break
        lab = new
    return lab


def cluster_hierarchy(V, F, *, branching: float = 6.0, leaf_faces: int = 4,
                      seed: int | None = 0) -> ClusterHierarchy:
    """Build a top-down face-cluster hierarchy whose clusters are discs.

    See the module docstring for the algorithm (hierarchical pattern mapping
    §3.1, general meshes).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A consistently oriented mesh without faces that repeat a vertex.
        Non-manifold edges are never crossed by a cluster.
    branching : float, optional
        Target ratio between the number of clusters of two successive levels
        (``> 1``); the number of sub-clusters of each cluster adapts to its
        area.
    leaf_faces : int, optional
        Clusters stop being split when the level's target size is at most
        this many faces; the next level is then the single faces.  If the
        last level built has more than twice this many faces per cluster, one
        more level of clusters of this size is made first.
    seed : int, optional
        Seed of the random first seed face of every cluster.

    Returns
    -------
    ClusterHierarchy
        ``levels[0]`` is the whole surface (one cluster per edge-connected
        component), ``levels[-1]`` the single faces; every level is a
        partition and ``levels[l].parent[levels[l].labels] ==
        levels[l - 1].labels``.

    Raises
    ------
    InputError
        On malformed arrays, an empty mesh, faces repeating a vertex, an
        inconsistently oriented mesh or out-of-range options.
    SolverError
        When some sub-cluster cannot be made a disc.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> H = cluster_hierarchy(V, F)
    >>> H[-1].n_clusters, all(is_disc_partition(F, lv.labels) for lv in H.levels[1:])
    (320, True)
    """
    V, F = as_mesh_arrays(V, F)
    m, n = F.shape[0], V.shape[0]
    if m == 0:
        raise InputError("F is empty: the mesh has no faces to cluster")
    check_triangles(F)
    if not (math.isfinite(float(branching)) and float(branching) > 1.0):
        raise InputError(f"branching must be a finite number > 1, got {branching!r}")
    if int(leaf_faces) != leaf_faces or leaf_faces < 1:
        raise InputError(f"leaf_faces must be an integer >= 1, got {leaf_faces!r}")
    topo = edge_topology(F, n)
    if topo.inconsistent.size:
        raise InputError("F is not consistently oriented (an edge is traversed twice in the "
                         "same direction); orient it first (geotex.repair)")
    rng = np.random.default_rng(seed)
    adj = face_adjacency(V, F)
    ef = topo.edge_faces()
    two = topo.face_count == 2
    on_border = np.zeros(n, np.int64)
    on_border[topo.edges[~two].ravel()] = 1
    ef2 = ef[two]
    scale = float(np.linalg.norm(np.ptp(V, axis=0))) or 1.0
    dual_w = np.linalg.norm(adj.centroids[ef2[:, 0]] - adj.centroids[ef2[:, 1]], axis=1)
    dual_w = np.maximum(dual_w, 1e-9 * scale)
    ctx = {"F": F, "n": n, "FF": adj.face_neighbors, "areas": adj.areas, "ef2": ef2,
           "dual_w": dual_w, "on_border": on_border}
    G = sp.csr_matrix((np.ones(ef2.shape[0]), (ef2[:, 0], ef2[:, 1])), shape=(m, m))
    C0, comp = connected_components(G, directed=False)
    lab0, C0 = _compact(comp.astype(np.int64))
    total = float(adj.areas.sum()) or 1.0
    built = [(lab0, C0, np.full(C0, -1, np.int64))]
    lab, C = lab0, C0
    level = 1
    size = float(m)                      # target faces per cluster of the last level built
    while True:
        target_clusters = float(branching) ** level
        if m / target_clusters <= leaf_faces:
            # the branching would reach the leaf size on this level: split once more to
            # clusters of ``leaf_faces`` faces if the last level is more than twice that
            # (else its clusters go straight to single faces: up to ``branching *
            # leaf_faces`` faces at once, 23 on a 30k-face mesh with the defaults)
            if size <= 2 * leaf_faces or m <= leaf_faces * C:
                break
            target_clusters = m / float(leaf_faces)
        target_area = total / target_clusters
        area = np.bincount(lab, weights=adj.areas, minlength=C)
        nf = np.bincount(lab, minlength=C)
        disc = region_topology(F, lab, C, n).disc
        want = np.clip(np.rint(area / target_area), 1, None).astype(np.int64)
        want = np.where(disc, want, np.maximum(want, 4))
        want = np.minimum(want, nf)
        lab_new, par, C_new = _split_level(lab, C, want, ctx, rng)
        built.append((lab_new, C_new, par))
        lab, C = lab_new, C_new
        size = m / target_clusters
        level += 1
    # face level, numbered by parent
    forder = np.lexsort((np.arange(m), lab))
    flab = np.empty(m, np.int64)
    flab[forder] = np.arange(m)
    built.append((flab, m, lab[forder]))
    out = []
    for i, (lb, c, par) in enumerate(built):
        if i + 1 < len(built):
            child_ptr = np.searchsorted(built[i + 1][2], np.arange(c + 1)).astype(np.int64)
        else:
            child_ptr = np.zeros(c + 1, np.int64)
        out.append(_build_level(V, F, lb, c, par, child_ptr, ctx))
    return ClusterHierarchy(levels=tuple(out))
