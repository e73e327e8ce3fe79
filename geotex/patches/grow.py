"""Growing disc-shaped surface patches face by face (lapped textures §3.3).

A patch starts at a seed face and grows one triangle at a time in order of
increasing distance from the seed, measured along the dual graph (shortest
path between face centroids through faces already in the patch).  A face only
joins when the patch stays a topological disc and the caller's predicates
(radius, normal cone, an arbitrary vectorized test) accept it.

The module also holds the topology checks shared by the other patch modules:
per-region Euler characteristic, boundary loops and connectivity, computed for
all regions of a face labelling at once.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.errors import InputError
from geotex.mesh.arrays import as_faces, as_mesh_arrays
from geotex.mesh.topology import edge_topology, half_edges, non_manifold_vertices

__all__ = ["FaceAdjacency", "face_adjacency", "Patch", "grow_patch", "is_disc", "check_triangles"]


# ---------------------------------------------------------------------------
# precomputed adjacency
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class FaceAdjacency:
    """Face-to-face adjacency and per-face geometry, computed once per mesh.

    Reuse one instance for many :func:`grow_patch` / :func:`effect_area`
    calls on the same mesh (lapped texturing grows thousands of patches).

    Attributes
    ----------
    n_vertices : int
    n_faces : int
    face_edges : numpy.ndarray, (m, 3) int64
        Unique edge (geotex edge order) of side ``k`` of every face; side ``k``
        runs from ``F[f, k]`` to ``F[f, (k + 1) % 3]`` and is opposite
        ``F[f, (k + 2) % 3]``.
    face_neighbors : numpy.ndarray, (m, 3) int64
        Face across side ``k``; ``-1`` on boundary and non-manifold edges
        (growth never crosses those).
    neighbor_distance : numpy.ndarray, (m, 3) float64
        Centroid-to-centroid distance across side ``k`` (``inf`` where there
        is no neighbour).
    edge_face_count : numpy.ndarray, (e,) int64
        Faces using each unique edge.
    centroids, normals : numpy.ndarray, (m, 3) float64
        Face centroids and unit normals (zero for degenerate faces).
    areas : numpy.ndarray, (m,) float64
    vertex_face_count : numpy.ndarray, (n,) int64
        Faces incident to each vertex.
    closable : numpy.ndarray, (n,) bool
        Vertices whose incident faces form one closed fan (interior,
        manifold): only such a vertex may become interior to a patch.
    """

    n_vertices: int
    n_faces: int
    face_edges: np.ndarray
    face_neighbors: np.ndarray
    neighbor_distance: np.ndarray
    edge_face_count: np.ndarray
    centroids: np.ndarray
    normals: np.ndarray
    areas: np.ndarray
    vertex_face_count: np.ndarray
    closable: np.ndarray


def check_triangles(F: np.ndarray, name: str = "F") -> None:
    """Refuse faces with a repeated vertex index.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
        Faces.
    name : str
        How the message names ``F``.

    Raises
    ------
    InputError
        If a face repeats a vertex index.
    """
    bad = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    if bad.any():
        raise InputError(f"{name} has faces with a repeated vertex index (first at face "
                         f"{int(np.flatnonzero(bad)[0])}); remove them first "
                         "(geotex.repair)")


def face_adjacency(V, F) -> FaceAdjacency:
    """Precompute the face adjacency used by patch growing.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64

    Returns
    -------
    FaceAdjacency

    Raises
    ------
    InputError
        On malformed arrays or faces with a repeated vertex index.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(2)
    >>> adj = face_adjacency(V, F)
    >>> bool((adj.face_neighbors >= 0).all())
    True
    """
    V, F = as_mesh_arrays(V, F)
    check_triangles(F)
    n, m = V.shape[0], F.shape[0]
    topo = edge_topology(F, n)
    FE = topo.half_to_edge.reshape(m, 3) if m else np.zeros((0, 3), np.int64)
    count = topo.face_count
    ef = topo.edge_faces()
    rows = np.arange(m, dtype=np.int64)[:, None]
    FF = np.full((m, 3), -1, dtype=np.int64)
    if m:
        two = count[FE] == 2
        other = ef[FE, 0] + ef[FE, 1] - rows
        FF[two] = other[two]
    P = V[F] if m else np.zeros((0, 3, 3))
    C = P.mean(axis=1)
    cr = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) if m else np.zeros((0, 3))
    ln = np.linalg.norm(cr, axis=1)
    N = np.divide(cr, ln[:, None], out=np.zeros_like(cr), where=ln[:, None] > 0)
    W = np.full((m, 3), np.inf)
    has = FF >= 0
    if m:
        W[has] = np.linalg.norm(C[FF[has]] - np.broadcast_to(C[:, None, :], (m, 3, 3))[has],
                                axis=1)
    vfc = np.bincount(F.ravel(), minlength=n).astype(np.int64)
    closable = vfc > 0
    if m:
        odd = topo.edges[count != 2].ravel()
        closable[odd] = False
        closable[non_manifold_vertices(F, n, topo)] = False
    for arr in (FE, FF, W, C, N, ln, vfc, closable, count):
        arr.setflags(write=False)
    return FaceAdjacency(n_vertices=n, n_faces=m, face_edges=FE, face_neighbors=FF,
                         neighbor_distance=W, edge_face_count=count, centroids=C,
                         normals=N, areas=0.5 * ln, vertex_face_count=vfc,
                         closable=closable)


def _adjacency_for(V, F, adjacency) -> tuple[np.ndarray, np.ndarray, FaceAdjacency]:
    V, F = as_mesh_arrays(V, F)
    if adjacency is None:
        return V, F, face_adjacency(V, F)
    if not isinstance(adjacency, FaceAdjacency):
        raise InputError("adjacency must be a FaceAdjacency from face_adjacency(V, F)")
    if adjacency.n_faces != F.shape[0] or adjacency.n_vertices != V.shape[0]:
        raise InputError(
            f"adjacency was computed for a mesh with {adjacency.n_vertices} vertices and "
            f"{adjacency.n_faces} faces, not {V.shape[0]} and {F.shape[0]}")
    return V, F, adjacency


# ---------------------------------------------------------------------------
# region topology (shared with clusters and the parameterization checks)
# ---------------------------------------------------------------------------

class RegionTopology(NamedTuple):
    """Topology of every region of a face labelling (all arrays ``(c,)``)."""

    faces: np.ndarray
    edges: np.ndarray
    vertices: np.ndarray
    euler: np.ndarray
    loops: np.ndarray
    components: np.ndarray
    manifold: np.ndarray

    @property
    def disc(self) -> np.ndarray:
        """Regions that are one connected topological disc."""
        return ((self.faces > 0) & (self.euler == 1) & (self.loops == 1)
                & (self.components == 1) & self.manifold)


def region_topology(F: np.ndarray, labels: np.ndarray, n_regions: int,
                    n_vertices: int) -> RegionTopology:
    """Euler characteristic, boundary loops and connectivity of every region.

    A region is a manifold disc exactly when it is edge-connected, every edge
    is used by at most two of its faces, its boundary edges form exactly one
    cycle through vertices of boundary degree two (no pinch), and
    ``V - E + F == 1``.  (A connected surface with ``b`` boundary loops has
    ``chi = 2 - 2g - b`` when orientable and ``2 - k - b`` otherwise; any
    pinched vertex lowers ``chi`` further, so ``chi == 1`` with one loop
    leaves only the disc.)  The test ignores orientation.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
        Region of every face, in ``[0, n_regions)``.
    n_regions, n_vertices : int

    Returns
    -------
    RegionTopology
    """
    C = int(n_regions)
    m = F.shape[0]
    if m == 0:
        z = np.zeros(C, np.int64)
        return RegionTopology(z, z, z, z, z, z, np.ones(C, bool))
    n = max(int(n_vertices), 1)
    lab3 = np.repeat(labels, 3)
    he = half_edges(F)
    lo = np.minimum(he[:, 0], he[:, 1])
    hi = np.maximum(he[:, 0], he[:, 1])
    ek = (lo * n + hi) * C + lab3
    uk, inv, cnt = np.unique(ek, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    ulab = uk % C
    n_e = np.bincount(ulab, minlength=C)
    manifold = np.bincount(ulab[cnt > 2], minlength=C) == 0
    vk = np.unique(F.ravel() * C + lab3)
    n_v = np.bincount(vk % C, minlength=C)
    n_f = np.bincount(labels, minlength=C)
    # edge-connectivity of the faces inside each region
    order = np.argsort(inv, kind="stable")
    same = inv[order[1:]] == inv[order[:-1]]
    fa, fb = order[:-1][same] // 3, order[1:][same] // 3
    g = sp.coo_matrix((np.ones(fa.size, np.int8), (fa, fb)), shape=(m, m)).tocsr()
    _, comp = connected_components(g, directed=False)
    _, first = np.unique(comp, return_index=True)
    n_comp = np.bincount(labels[first], minlength=C)
    # boundary loops: components of the graph of boundary edges per region
    bnd = cnt == 1
    bkey = uk[bnd] // C
    bl = ulab[bnd]
    a, b = bkey // n, bkey % n
    nodes, ninv = np.unique(np.concatenate([a * C + bl, b * C + bl]), return_inverse=True)
    ninv = ninv.ravel()
    loops = np.zeros(C, np.int64)
    if nodes.size:
        k = bkey.size
        deg = np.bincount(ninv, minlength=nodes.size)
        pinched = np.bincount(nodes[deg != 2] % C, minlength=C) > 0
        manifold &= ~pinched
        bg = sp.coo_matrix((np.ones(k, np.int8), (ninv[:k], ninv[k:])),
                           shape=(nodes.size, nodes.size)).tocsr()
        _, bcomp = connected_components(bg, directed=False)
        _, bfirst = np.unique(bcomp, return_index=True)
        loops = np.bincount(nodes[bfirst] % C, minlength=C)
    return RegionTopology(faces=n_f, edges=n_e, vertices=n_v, euler=n_v - n_e + n_f,
                          loops=loops, components=n_comp, manifold=manifold)


def disc_problem(F: np.ndarray, n_vertices: int) -> str | None:
    """Return why the faces ``F`` are not one topological disc, or ``None``."""
    if F.shape[0] == 0:
        return "it has no faces"
    t = region_topology(F, np.zeros(F.shape[0], np.int64), 1, n_vertices)
    if t.components[0] != 1:
        return f"it has {int(t.components[0])} edge-connected components"
    if not t.manifold[0]:
        return "it has non-manifold edges or pinched boundary vertices"
    if t.loops[0] == 0:
        return "it is a closed surface (no boundary loop); cut it open first"
    if t.loops[0] != 1:
        return f"it has {int(t.loops[0])} boundary loops (an annulus or a surface with holes)"
    if t.euler[0] != 1:
        return f"its Euler characteristic is {int(t.euler[0])}, not 1 (it has handles)"
    return None


def is_disc(F) -> bool:
    """Return whether the faces ``F`` form one connected topological disc.

    Parameters
    ----------
    F : array_like, (m, 3) int64

    Returns
    -------
    bool
        ``True`` when ``V - E + F == 1``, there is exactly one boundary loop,
        the faces are edge-connected and every edge has at most two faces.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane, icosphere
    >>> is_disc(grid_plane(3, 3)[1]), is_disc(icosphere(1)[1])
    (True, False)
    """
    F = as_faces(F)
    if F.shape[0] == 0:
        return False
    return disc_problem(F, int(F.max()) + 1) is None


def boundary_loops(F) -> list[np.ndarray]:
    """Return the boundary loops of faces ``F`` as ordered vertex arrays.

    Each loop starts at its smallest vertex id and runs in the direction of
    the face half-edges along it (counter-clockwise seen from the normal side
    when ``F`` is consistently oriented).  Loops are listed by their starting
    vertex.  Works for pinched boundaries too (the decomposition into loops is
    then one of several possible).

    Parameters
    ----------
    F : array_like, (m, 3) int64

    Returns
    -------
    list of numpy.ndarray, each (b,) int64

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> boundary_loops(grid_plane(1, 1)[1])[0].tolist()
    [0, 2, 3, 1]
    """
    F = as_faces(F)
    m = F.shape[0]
    if m == 0:
        return []
    n = int(F.max()) + 1
    topo = edge_topology(F, n)
    bnd = topo.face_count == 1
    if not bnd.any():
        return []
    he = half_edges(F)
    hid = np.flatnonzero(bnd[topo.half_to_edge])
    dir_pairs = {(int(he[h, 0]), int(he[h, 1])) for h in hid}
    edges = topo.edges[bnd]
    # vertex -> incident boundary edges (CSR)
    ends = edges.ravel()
    order = np.argsort(ends, kind="stable")
    ptr = np.searchsorted(ends[order], np.arange(n + 1))
    inc = (order // 2).tolist()
    ptr = ptr.tolist()
    el = edges.tolist()
    used = [False] * len(el)
    loops = []
    for start_edge in np.lexsort((edges[:, 1], edges[:, 0])).tolist():
        if used[start_edge]:
            continue
        a, b = el[start_edge]
        v0, v1 = (a, b) if (a, b) in dir_pairs else (b, a)
        used[start_edge] = True
        loop = [v0]
        cur = v1
        while cur != v0:
            loop.append(cur)
            nxt = None
            for e in inc[ptr[cur]:ptr[cur + 1]]:
                if not used[e]:
                    nxt = e
                    break
            if nxt is None:
                break
            used[nxt] = True
            x, y = el[nxt]
            cur = y if x == cur else x
        lp = np.asarray(loop, dtype=np.int64)
        loops.append(np.roll(lp, -int(np.argmin(lp))))
    loops.sort(key=lambda lp: int(lp[0]))
    return loops


# ---------------------------------------------------------------------------
# patch growing
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Patch:
    """A disc-shaped surface patch grown around a seed face.

    Attributes
    ----------
    seed_face : int
    faces : numpy.ndarray, (k,) int64
        Global face ids in growth order (``faces[0] == seed_face``).
    distances : numpy.ndarray, (k,) float64
        Dual-graph distance of every face from the seed (centroid to
        centroid, through patch faces), in growth order.
    vertices : numpy.ndarray, (p,) int64
        Sorted global vertex ids; local vertex ``i`` is ``vertices[i]``.
    F : numpy.ndarray, (k, 3) int64
        Patch faces in local vertex ids (rows in growth order).
    boundary_loop : numpy.ndarray, (b,) int64
        Ordered global vertex ids of the boundary (the longest loop when the
        patch is not a disc), counter-clockwise seen from the normal side.
    is_disc : bool
        Verified afterwards: ``V - E + F == 1``, one boundary loop, connected,
        manifold.
    """

    seed_face: int
    faces: np.ndarray
    distances: np.ndarray
    vertices: np.ndarray
    F: np.ndarray
    boundary_loop: np.ndarray
    is_disc: bool

    @property
    def n_faces(self) -> int:
        """Number of faces in the patch."""
        return int(self.faces.shape[0])

    def local_mesh(self, V) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(V[vertices], F)``: the patch as a stand-alone mesh."""
        return np.ascontiguousarray(np.asarray(V, dtype=np.float64)[self.vertices]), self.F


def _face_index(value, m: int, name: str) -> int:
    try:
        idx = int(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a face index, got {value!r}") from None
    if idx != value or not 0 <= idx < m:
        raise InputError(f"{name} must be a face index in [0, {m}), got {value!r}")
    return idx


def _optional_nonnegative(value, name: str) -> float | None:
    if value is None:
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if math.isnan(x) or x < 0:
        raise InputError(f"{name} must be >= 0, got {value!r}")
    return x


def _call_accept(accept, ids: np.ndarray) -> np.ndarray:
    out = np.asarray(accept(ids.copy()))
    if out.shape != ids.shape:
        raise InputError(f"accept must return one boolean per face id it is given: got shape "
                         f"{out.shape} for {ids.shape[0]} faces")
    return out.astype(bool)


def _make_patch(F: np.ndarray, faces: np.ndarray, distances: np.ndarray, seed: int) -> Patch:
    """Assemble a :class:`Patch` from face ids (used by the growing routines)."""
    sub = F[faces]
    verts = np.unique(sub)
    Fl = np.searchsorted(verts, sub).astype(np.int64)
    loops = boundary_loops(sub)
    loop = max(loops, key=len) if loops else np.zeros(0, np.int64)
    disc = disc_problem(Fl, verts.size) is None
    for arr in (faces, distances, verts, Fl, loop):
        arr.setflags(write=False)
    return Patch(seed_face=int(seed), faces=faces, distances=distances, vertices=verts, F=Fl,
                 boundary_loop=loop, is_disc=bool(disc))


def grow_patch(V, F, seed_face, *, max_radius=None, max_normal_angle=None,
               accept: Callable[[np.ndarray], np.ndarray] | None = None,
               max_faces: int | None = None,
               adjacency: FaceAdjacency | None = None,
               on_join: Callable[[int], None] | None = None) -> Patch:
    """Grow a topological disc around a seed face (lapped textures §3.3).

    Faces are visited in order of increasing distance from the seed face: a
    Dijkstra search over the dual graph whose edge lengths are
    centroid-to-centroid distances, relaxed only from faces already in the
    patch.  A visited face joins when all of these hold:

    * **disc** – it shares one or two edges with the patch (never an edge
      with three or more faces).  With one shared edge, its opposite vertex
      must not be on the patch yet (otherwise the patch would pinch or close
      into an annulus).  With two shared edges the common vertex ``c`` becomes
      interior, so ``c`` must be a closed-fan manifold vertex whose every
      other face is already in the patch (otherwise a hole would be left at
      ``c``).  A face failing only this test is reconsidered whenever one of
      its neighbours joins later.
    * **radius** – its distance is at most ``max_radius``.  Growth stops once
      the nearest waiting face is farther.
    * **normal cone** – the angle between its normal and the seed normal is
      at most ``max_normal_angle`` (radians).
    * **accept** – ``accept(face_ids)`` returns ``True`` for it.

    ``accept`` is called in small batches: once with the (one to three) faces
    newly reached from every face that joins, each face exactly once; its
    verdict is final.  It must return a boolean array of the same length.
    The seed face always belongs to the patch; the predicates govern growth.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    seed_face : int
    max_radius : float, optional
        Largest dual-graph distance from the seed face centroid (mesh units).
    max_normal_angle : float, optional
        Normal cone half-angle in radians, in ``[0, pi]``.
    accept : callable, optional
        ``accept(face_ids: (j,) int64) -> (j,) bool``.
    max_faces : int, optional
        Stop after this many faces.
    adjacency : FaceAdjacency, optional
        Precomputed :func:`face_adjacency` of ``(V, F)`` (reuse it across calls).
    on_join : callable, optional
        ``on_join(face_id: int)`` is called as each face joins (the seed
        first), before ``accept`` sees the faces newly reached from it; a
        caller can map the new face (e.g. extend a parameterization) and then
        judge its neighbours in ``accept``.

    Returns
    -------
    Patch

    Raises
    ------
    InputError
        On a bad seed, negative radius, an angle outside ``[0, pi]``,
        ``max_faces < 1``, an ``accept`` result of the wrong shape, or
        malformed arrays.

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(3)
    >>> p = grow_patch(V, F, 0, max_radius=0.5)
    >>> p.is_disc, int(p.faces[0])
    (True, 0)
    """
    V, F, adj = _adjacency_for(V, F, adjacency)
    m = F.shape[0]
    if m == 0:
        raise InputError("F is empty: the mesh has no faces to grow a patch on")
    seed = _face_index(seed_face, m, "seed_face")
    radius = _optional_nonnegative(max_radius, "max_radius")
    cos_limit = None
    if max_normal_angle is not None:
        ang = _optional_nonnegative(max_normal_angle, "max_normal_angle")
        if ang > math.pi + 1e-12:
            raise InputError(
                f"max_normal_angle must be in [0, pi] radians, got {max_normal_angle!r}")
        cos_limit = math.cos(ang) - 1e-12
    limit = m
    if max_faces is not None:
        try:
            limit = int(max_faces)
        except (TypeError, ValueError):
            raise InputError(f"max_faces must be an integer, got {max_faces!r}") from None
        if limit < 1 or limit != max_faces:
            raise InputError(f"max_faces must be an integer >= 1, got {max_faces!r}")
    if accept is not None and not callable(accept):
        raise InputError("accept must be a callable taking face ids and returning booleans")
    if on_join is not None and not callable(on_join):
        raise InputError("on_join must be a callable taking a face id")

    FE, FF, W = adj.face_edges, adj.face_neighbors, adj.neighbor_distance
    normals = adj.normals
    s0, s1, s2 = (float(x) for x in normals[seed])
    efc, vfc, closable = adj.edge_face_count, adj.vertex_face_count, adj.closable
    # per-face state: 0 unseen, 1 waiting (reached, predicates passed), 2 in patch,
    # 3 rejected for good.  Counters are flat arrays indexed by Python ints, so
    # every step is O(1) apart from the heap.
    state = bytearray(m)
    dist = [math.inf] * m
    ecount = [0] * efc.shape[0]          # Python lists: scalar access is the hot path
    vcount = [0] * adj.n_vertices
    order: list[int] = []
    dists: list[float] = []
    heap: list[tuple[float, int]] = []

    def add(f: int, d: float) -> None:
        state[f] = 2
        order.append(f)
        dists.append(d)
        for e in FE[f].tolist():
            ecount[e] += 1
        for v in F[f].tolist():
            vcount[v] += 1
        if on_join is not None:
            on_join(f)
        nb = FF[f].tolist()
        fresh = [g for g in nb if g >= 0 and state[g] == 0]
        if fresh:
            ok = [True] * len(fresh)
            if cos_limit is not None:
                for i, g in enumerate(fresh):
                    n0, n1, n2 = normals[g].tolist()
                    ok[i] = n0 * s0 + n1 * s1 + n2 * s2 >= cos_limit
            if accept is not None:
                verdict = _call_accept(accept, np.asarray(fresh, dtype=np.int64)).tolist()
                ok = [a and b for a, b in zip(ok, verdict)]
            for g, good in zip(fresh, ok):
                state[g] = 1 if good else 3
        w = W[f].tolist()
        for k in range(3):
            g = nb[k]
            if g >= 0 and state[g] == 1:
                dg = d + w[k]
                old = dist[g]
                if dg < old:
                    dist[g] = dg
                    old = dg
                heapq.heappush(heap, (old, g))

    def disc_ok(f: int) -> int:
        """1 accept, 0 wait (may become valid later), -1 reject for good."""
        fe = FE[f].tolist()
        shared = [ecount[e] > 0 for e in fe]
        k = shared.count(True)
        if k == 3:
            return -1
        if k == 0:
            return 0
        for e, sh in zip(fe, shared):
            if sh and efc[e] != 2:
                return -1
        fv = F[f].tolist()
        if k == 1:
            side = shared.index(True)
            return 1 if vcount[fv[(side + 2) % 3]] == 0 else 0
        c = fv[(shared.index(False) + 2) % 3]
        return 1 if (closable[c] and vcount[c] + 1 == vfc[c]) else 0

    dist[seed] = 0.0
    add(seed, 0.0)
    while heap and len(order) < limit:
        d, f = heapq.heappop(heap)
        if state[f] != 1 or d > dist[f]:
            continue
        if radius is not None and d > radius:
            break
        verdict = disc_ok(f)
        if verdict == 1:
            add(f, d)
        elif verdict < 0:
            state[f] = 3
    faces = np.asarray(order, dtype=np.int64)
    return _make_patch(F, faces, np.asarray(dists, dtype=np.float64), seed)
