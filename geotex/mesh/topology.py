"""Combinatorial structure of triangle meshes, computed with vectorized numpy.

Edge order convention
---------------------
Unique (undirected) edges are rows ``(i, j)`` with ``i < j``, sorted
lexicographically; per-edge data anywhere in geotex is indexed in this order.
Half-edge ``3 * f + k`` runs from ``F[f, k]`` to ``F[f, (k + 1) % 3]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled

__all__ = [
    "greedy_colouring",
    "EdgeTopology",
    "edge_topology",
    "half_edges",
    "vertex_components",
    "face_components",
    "non_manifold_vertices",
    "unpaired_edge_vertices",
    "duplicate_face_groups",
    "has_twin_faces",
    "repeated_positions",
    "referenced_vertices",
    "numbered_by_first_use",
    "position_welded_faces",
    "neighbour_mean",
    "compacted",
    "concatenated",
]


def half_edges(F: np.ndarray) -> np.ndarray:
    """Return the directed edges of every face.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64

    Returns
    -------
    numpy.ndarray, (3m, 2) int64
        Row ``3 * f + k`` is ``(F[f, k], F[f, (k + 1) % 3])``.
    """
    return np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)


@dataclass(frozen=True)
class EdgeTopology:
    """Unique edges of a triangle mesh and their incidence.

    Attributes
    ----------
    edges : numpy.ndarray, (e, 2) int64
        Unique undirected edges, ``edges[:, 0] < edges[:, 1]``, sorted.
    half_to_edge : numpy.ndarray, (3m,) int64
        Unique edge of every half-edge (see module docstring for the order).
    face_count : numpy.ndarray, (e,) int64
        Number of faces that use each edge (1 boundary, 2 manifold, >2 not).
    forward_count : numpy.ndarray, (e,) int64
        Number of half-edges running from ``edges[:, 0]`` to ``edges[:, 1]``.
    half_order : numpy.ndarray or None, (3m,) int64
        Half-edges grouped by edge (in edge order), ascending within an edge:
        the half-edges of edge ``i`` are
        ``half_order[start[i]:start[i] + face_count[i]]`` with
        ``start = cumsum(face_count) - face_count``.  ``None`` when the
        topology was built elsewhere; :meth:`grouped_half_edges` computes it.
    """

    edges: np.ndarray
    half_to_edge: np.ndarray
    face_count: np.ndarray
    forward_count: np.ndarray
    half_order: np.ndarray | None = field(default=None, repr=False, compare=False)

    def grouped_half_edges(self) -> np.ndarray:
        """Return :attr:`half_order` (computed when it was not stored), ``(3m,)`` int64."""
        if self.half_order is not None:
            return self.half_order
        return np.argsort(self.half_to_edge, kind="stable")

    def edge_starts(self) -> np.ndarray:
        """Return where each edge's half-edges start in :attr:`half_order`, ``(e,)`` int64."""
        return np.cumsum(self.face_count) - self.face_count

    @property
    def boundary(self) -> np.ndarray:
        """Indices of boundary edges (used by exactly one face)."""
        return np.flatnonzero(self.face_count == 1)

    @property
    def non_manifold(self) -> np.ndarray:
        """Indices of edges used by more than two faces."""
        return np.flatnonzero(self.face_count > 2)

    @property
    def inconsistent(self) -> np.ndarray:
        """Indices of two-face edges traversed twice in the same direction."""
        return np.flatnonzero((self.face_count == 2) & (self.forward_count != 1))

    def edge_faces(self) -> np.ndarray:
        """Return the two faces of every edge, ``-1`` where there is none.

        Returns
        -------
        numpy.ndarray, (e, 2) int64
            For edges with more than two faces, the first two (in face order).
        """
        order = self.grouped_half_edges()
        start = self.edge_starts()
        out = np.full((self.edges.shape[0], 2), -1, dtype=np.int64)
        out[:, 0] = order[start] // 3
        two = self.face_count >= 2
        out[two, 1] = order[start[two] + 1] // 3
        return out


def edge_topology(F: np.ndarray, n_vertices: int | None = None) -> EdgeTopology:
    """Compute unique edges and how faces use them.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n_vertices : int, optional
        Number of vertices (defaults to ``F.max() + 1``).

    Returns
    -------
    EdgeTopology
    """
    F = np.asarray(F, dtype=np.int64)
    n = int(n_vertices if n_vertices is not None else (F.max() + 1 if F.size else 0))
    if F.size and F.size >= JIT_MIN_SIZE and F.min() >= 0:
        n_loop = int(F.max()) + 1                # the loops index the referenced vertices
        h = F.size
        start = np.zeros(n_loop + 1, np.int64)
        order, high, inv = (np.empty(h, np.int64) for _ in range(3))
        edges = np.empty((h, 2), np.int64)
        counts, forward = np.zeros(h, np.int64), np.zeros(h, np.int64)
        e = _edge_topology_loops(np.ascontiguousarray(F), n_loop, start, order, high, inv,
                                 edges, counts, forward)
        del start, high
        edges, counts, forward = edges[:e].copy(), counts[:e].copy(), forward[:e].copy()
        return EdgeTopology(edges=edges, half_to_edge=inv, face_count=counts,
                            forward_count=forward, half_order=order)
    N = max(n, 1)
    a = F.ravel()                       # half-edge 3f + k runs a -> b
    b = F[:, [1, 2, 0]].ravel()         # a copy: overwritten below
    fwd = a < b
    key = np.minimum(a, b)
    key *= N
    np.maximum(a, b, out=b)
    key += b
    del b
    h = key.shape[0]
    shift = max(h - 1, 0).bit_length()
    if (N * N - 1).bit_length() + shift <= 63:
        # the half-edge index in the low bits makes every key unique: one sort of
        # int64 values (much faster than an argsort) gives the edges in order and
        # the half-edges ascending within every edge
        order = np.arange(h, dtype=np.int64)
        key <<= shift
        key |= order
        key.sort()
        np.bitwise_and(key, (1 << shift) - 1, out=order)
        key >>= shift
        ks = key
        del key
        new, first, run, counts = _runs(ks)
    else:
        order = np.argsort(key)         # one 1-D sort of int64 keys
        ks = key[order]
        del key
        new, first, run, counts = _runs(ks)
        # make the order ascending within every edge (the sort is not stable)
        two = first[counts == 2]
        swap = two[order[two] > order[two + 1]]
        order[swap], order[swap + 1] = order[swap + 1], order[swap].copy()
        if np.any(counts > 2):
            sel = np.flatnonzero(np.repeat(counts > 2, counts))
            sub = order[sel]
            order[sel] = sub[np.lexsort((sub, run[sel]))]
    del new
    inv = np.empty(ks.shape[0], dtype=np.int64)
    inv[order] = run
    del run
    uniq = ks[first]
    del ks
    edges = np.empty((uniq.shape[0], 2), dtype=np.int64)
    np.floor_divide(uniq, N, out=edges[:, 0])
    uniq -= edges[:, 0] * N
    edges[:, 1] = uniq
    del uniq
    forward = np.bincount(inv[fwd], minlength=first.shape[0]).astype(np.int64, copy=False)
    return EdgeTopology(edges=edges, half_to_edge=inv, face_count=counts,
                        forward_count=forward, half_order=order)


@compiled
def _edge_topology_loops(F, n, start, order, high, half_to_edge, edges, counts, forward):
    """:func:`edge_topology` as loops (the same arrays): a counting sort of the
    half-edges by their lower vertex, then each vertex's few half-edges sorted
    by the higher one (insertion sort; a stable merge sort for long lists), so
    the work is linear in the faces instead of one sort of all half-edges.
    Arrays are allocated by the caller (numpy's large allocations use huge
    pages: page faults on fresh memory cost more than the loops here) and
    given zeroed where they accumulate (``start``, ``counts``, ``forward``);
    returns the number of edges."""
    m = F.shape[0]
    for f in range(m):
        for k in range(3):
            a = F[f, k]
            b = F[f, (k + 1) % 3]
            start[min(a, b) + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:n].copy()
    for f in range(m):
        for k in range(3):
            a = F[f, k]
            b = F[f, (k + 1) % 3]
            lo = min(a, b)
            p = fill[lo]
            fill[lo] = p + 1
            order[p] = 3 * f + k
            high[p] = max(a, b)
    for v in range(n):
        s, e = start[v], start[v + 1]
        if e - s <= 64:
            for i in range(s + 1, e):
                key, h = high[i], order[i]
                j = i - 1
                while j >= s and high[j] > key:
                    high[j + 1] = high[j]
                    order[j + 1] = order[j]
                    j -= 1
                high[j + 1] = key
                order[j + 1] = h
        else:
            idx = np.argsort(high[s:e], kind="mergesort")
            high[s:e] = high[s:e][idx]
            order[s:e] = order[s:e][idx]
    ne = -1
    for v in range(n):
        previous = -1
        for p in range(start[v], start[v + 1]):
            if high[p] != previous:
                ne += 1
                previous = high[p]
                edges[ne, 0] = v
                edges[ne, 1] = previous
            h = order[p]
            half_to_edge[h] = ne
            counts[ne] += 1
            f, k = h // 3, h % 3
            if F[f, k] < F[f, (k + 1) % 3]:
                forward[ne] += 1
    return ne + 1


def _runs(ks: np.ndarray):
    """Runs of equal values in sorted ``ks``: starts mask, first indices, run ids, lengths."""
    new = np.empty(ks.shape[0], dtype=bool)
    if ks.shape[0]:
        new[0] = True
        np.not_equal(ks[1:], ks[:-1], out=new[1:])
    first = np.flatnonzero(new)
    run = np.cumsum(new, dtype=np.int64)
    run -= 1
    counts = np.diff(np.append(first, ks.shape[0])).astype(np.int64, copy=False)
    return new, first, run, counts


def first_use_order(F: np.ndarray, n_vertices: int, *, start: int = 0) -> np.ndarray:
    """Vertex numbering by first use in ``F``, from vertex ``start`` on.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n_vertices : int
    start : int, optional
        Vertices below ``start`` keep their numbers.

    Returns
    -------
    numpy.ndarray, (n_vertices,) int64
        ``order``: new vertex ``i`` is old vertex ``order[i]`` (vertices from
        ``start`` on in order of first appearance in ``F``, then the unused
        ones in index order).
    """
    F = np.asarray(F, dtype=np.int64)
    if F.size >= JIT_MIN_SIZE:
        return _first_use_loops(np.ascontiguousarray(F).ravel(), int(n_vertices), int(start))
    flat = F.ravel()
    flat = flat[flat >= start]
    _, idx = np.unique(flat, return_index=True)
    used = flat[np.sort(idx)]
    rest = np.ones(n_vertices, dtype=bool)
    rest[:start] = False
    rest[used] = False
    return np.concatenate([np.arange(start, dtype=np.int64), used, np.flatnonzero(rest)])


def numbered_by_first_use(F: np.ndarray, n_vertices: int) -> bool:
    """Whether every vertex is used and the vertices are numbered by first use in ``F``.

    That is, :func:`first_use_order` of ``F`` is the identity and no vertex
    is unreferenced.  A running maximum over the corners (compiled, one
    pass without temporaries, from ``JIT_MIN_SIZE`` corners), no sort.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
        Indices in ``0 .. n_vertices - 1``.
    n_vertices : int

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> numbered_by_first_use(np.array([[0, 1, 2], [2, 1, 3]]), 4)
    True
    >>> numbered_by_first_use(np.array([[0, 2, 1], [2, 1, 3]]), 4)
    False
    """
    flat = np.asarray(F).ravel()
    if flat.size == 0:
        return n_vertices == 0
    if flat[0] != 0:
        return False
    if flat.size >= JIT_MIN_SIZE:
        return bool(_first_use_numbered_loops(np.ascontiguousarray(flat, dtype=np.int64),
                                              int(n_vertices)))
    # a corner either repeats a vertex already seen (at most the running
    # maximum: all of 0 .. maximum were seen) or is the next new one
    top = np.maximum.accumulate(flat)
    if int(top[-1]) != n_vertices - 1:
        return False
    top += 1
    return bool(np.all(flat[1:] <= top[:-1]))


@compiled
def _first_use_numbered_loops(flat, n):
    """:func:`numbered_by_first_use` as one pass over the corners."""
    top = -1
    for c in range(flat.shape[0]):
        v = flat[c]
        if v > top + 1:
            return False
        if v > top:
            top = v
    return top == n - 1


@compiled
def _first_use_loops(flat, n, start):
    """:func:`first_use_order` as one pass over the corners."""
    order = np.empty(n, dtype=np.int64)
    seen = np.zeros(n, dtype=np.bool_)
    for v in range(start):
        order[v] = v
        seen[v] = True
    k = start
    for c in range(flat.shape[0]):
        v = flat[c]
        if not seen[v]:
            seen[v] = True
            order[k] = v
            k += 1
    for v in range(start, n):
        if not seen[v]:
            order[k] = v
            k += 1
    return order


def compacted(V: np.ndarray, F: np.ndarray, *, return_index: bool = False):
    """Drop unreferenced vertices: the submesh of the faces ``F``.

    Parameters
    ----------
    V : numpy.ndarray, (n, k) float64
        Vertex positions (or any per-vertex rows).
    F : numpy.ndarray, (m, 3) int64
        Faces, for example a subset of a mesh's faces.
    return_index : bool, optional
        Also return the kept vertices' indices in ``V``.

    Returns
    -------
    V2 : numpy.ndarray, (p, k) float64
        The referenced vertices in their original order (a copy).
    F2 : numpy.ndarray, (m, 3) int64
    kept : numpy.ndarray, (p,) int64
        Only with ``return_index``: ``V2 == V[kept]``, for carrying other
        per-vertex data along.
    """
    F = np.asarray(F)
    if 8 * F.size < len(V):          # a small part of a large mesh: no O(n) pass
        kept = np.unique(F)
        F2 = np.searchsorted(kept, F).astype(np.int64)
    else:
        used = np.zeros(len(V), dtype=bool)
        used[F.ravel()] = True
        kept = np.flatnonzero(used)
        F2 = (np.cumsum(used) - 1)[F].astype(np.int64)
    V2 = V[kept]
    return (V2, F2, kept) if return_index else (V2, F2)


def concatenated(parts) -> tuple[np.ndarray, np.ndarray]:
    """Stack meshes ``[(V, F), ...]`` into one ``(V, F)`` (faces re-indexed, no welding).

    Parameters
    ----------
    parts : iterable of (V (n_i, 3) float64, F (m_i, 3) int64)
        Parts without faces are skipped.

    Returns
    -------
    V : numpy.ndarray, (sum n_i, 3) float64
    F : numpy.ndarray, (sum m_i, 3) int64
    """
    parts = [(V, F) for V, F in parts if len(F)]
    if not parts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    offsets = np.cumsum([0] + [len(V) for V, _ in parts[:-1]])
    return (np.vstack([V for V, _ in parts]),
            np.vstack([F + o for (_, F), o in zip(parts, offsets)]).astype(np.int64))


def neighbour_mean(F: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """Averaging operator over edge neighbours, ``(n, n)``: row ``i`` holds ``1/deg(i)``.

    ``neighbour_mean(F, n) @ X`` replaces every vertex value by the mean of its
    neighbours' (zero for vertices on no edge).
    """
    E = edge_topology(F, n_vertices).edges
    i = np.concatenate([E[:, 0], E[:, 1]])
    j = np.concatenate([E[:, 1], E[:, 0]])
    deg = np.bincount(i, minlength=n_vertices).astype(np.float64)
    w = 1.0 / deg[i]
    return sp.csr_matrix((w, (i, j)), shape=(n_vertices, n_vertices))


def faces_within_rings(F: np.ndarray, n_vertices: int, pairs: np.ndarray, rings: int
                       ) -> np.ndarray:
    """Which face pairs lie within ``rings`` vertex rings of each other.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n_vertices : int
    pairs : numpy.ndarray, (p, 2) int64
        Face index pairs.
    rings : int
        0: the faces share a vertex; ``k``: a vertex of the second face is at
        most ``k`` edges from a vertex of the first.

    Returns
    -------
    numpy.ndarray, (p,) bool
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    p = pairs.shape[0]
    if p == 0:
        return np.zeros(0, dtype=bool)
    E = edge_topology(F, n_vertices).edges
    step = sp.csr_matrix((np.ones(2 * E.shape[0] + n_vertices),
                          (np.concatenate([E[:, 0], E[:, 1], np.arange(n_vertices)]),
                           np.concatenate([E[:, 1], E[:, 0], np.arange(n_vertices)]))),
                         shape=(n_vertices, n_vertices))
    cols = np.repeat(np.arange(p), 3)
    reach = sp.csc_matrix((np.ones(3 * p), (F[pairs[:, 0]].ravel(), cols)), shape=(n_vertices, p))
    for _ in range(rings):
        reach = step @ reach
    reach = reach.tocsr()
    hit = np.asarray(reach[F[pairs[:, 1]].ravel(), cols] != 0).reshape(p, 3)
    return hit.any(axis=1)


def referenced_vertices(F: np.ndarray, n_vertices: int) -> np.ndarray:
    """Return a boolean mask, ``(n_vertices,)``, of vertices used by some face."""
    mask = np.zeros(n_vertices, dtype=bool)
    mask[np.asarray(F).ravel()] = True
    return mask


def vertex_components(F: np.ndarray, n_vertices: int) -> tuple[int, np.ndarray]:
    """Label vertices by the connected component of the face graph.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n_vertices : int

    Returns
    -------
    count : int
        Number of components that contain at least one face.
    labels : numpy.ndarray, (n_vertices,) int64
        Component of every vertex, ``-1`` for unreferenced vertices; labels
        are ``0 .. count - 1`` in order of first appearance in ``F``.
    """
    F = np.asarray(F, dtype=np.int64)
    labels = np.full(n_vertices, -1, dtype=np.int64)
    if F.shape[0] == 0:
        return 0, labels
    if F.size >= JIT_MIN_SIZE:
        count = _component_loops(np.ascontiguousarray(F), labels)
        return int(count), labels
    rows = np.concatenate([F[:, 0], F[:, 1]])
    cols = np.concatenate([F[:, 1], F[:, 2]])
    adj = sp.coo_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)),
                        shape=(n_vertices, n_vertices)).tocsr()
    _, raw = connected_components(adj, directed=False)
    used = referenced_vertices(F, n_vertices)
    # relabel in order of first appearance in F for determinism and compactness
    first = raw[F.ravel()]
    _, idx = np.unique(first, return_index=True)
    ordered = first[np.sort(idx)]
    remap = np.full(raw.max() + 1, -1, dtype=np.int64)
    remap[ordered] = np.arange(ordered.size)
    labels[used] = remap[raw[used]]
    return int(ordered.size), labels


@compiled
def _component_loops(F, labels):
    """:func:`vertex_components` by union-find: ``labels`` (all -1 on entry)
    filled in order of first appearance in ``F``; returns the count."""
    n = labels.shape[0]
    parent = np.arange(n)

    def find(v):
        r = v
        while parent[r] != r:
            r = parent[r]
        while parent[v] != r:                       # path compression
            nxt = parent[v]
            parent[v] = r
            v = nxt
        return r

    for f in range(F.shape[0]):
        for k in range(2):
            a = find(F[f, k])
            b = find(F[f, k + 1])
            if a != b:
                if a < b:
                    parent[b] = a
                else:
                    parent[a] = b
    root_label = np.full(n, -1, dtype=np.int64)
    count = 0
    for f in range(F.shape[0]):
        for k in range(3):
            v = F[f, k]
            r = find(v)
            if root_label[r] < 0:
                root_label[r] = count
                count += 1
            labels[v] = root_label[r]
    return count


def face_components(F: np.ndarray, n_vertices: int) -> tuple[int, np.ndarray]:
    """Label faces by connected component (faces sharing a vertex are connected).

    Returns
    -------
    count : int
    labels : numpy.ndarray, (m,) int64
    """
    count, vlab = vertex_components(F, n_vertices)
    return count, vlab[np.asarray(F)[:, 0]] if len(F) else np.zeros(0, np.int64)


def unpaired_edge_vertices(topo: EdgeTopology, n: int) -> np.ndarray:
    """Return the vertices on an edge not used exactly once in each direction.

    Parameters
    ----------
    topo : EdgeTopology
        Of the faces (:func:`edge_topology`).
    n : int
        Number of vertices.

    Returns
    -------
    numpy.ndarray, (n,) bool
        True at both ends of every boundary, non-manifold or inconsistently
        oriented edge (see ``unpaired_vertices`` of
        :func:`geotex.check.intersections.self_intersecting_pairs`).
    """
    out = np.zeros(n, dtype=bool)
    out[topo.edges[(topo.face_count != 2) | (topo.forward_count != 1)].ravel()] = True
    return out


#: Vertices with more corners than this skip the fan walk of
#: :func:`non_manifold_vertices` and go to the general test.
_MAX_FAN_WALK = 64


def non_manifold_vertices(F: np.ndarray, n_vertices: int,
                          topo: EdgeTopology | None = None) -> np.ndarray:
    """Return vertices whose incident faces do not form one edge-connected fan.

    Two corners at the same vertex are connected when their faces share an
    edge through that vertex that has exactly two faces.  A vertex is
    non-manifold when its corners fall into more than one group (a "bow tie").
    Vertices on non-manifold edges are reported by the edge test instead.

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    n_vertices : int
    topo : EdgeTopology, optional
        Reuse an already computed edge topology.

    Returns
    -------
    numpy.ndarray, (k,) int64
        Sorted vertex indices.

    Notes
    -----
    At a vertex whose edges all have two faces running opposite ways (and no
    face repeats it), "the next corner across the outgoing edge" is a
    permutation of its corners whose cycles are the fans: one vectorized walk
    from the first corner decides whether there is exactly one.  The other
    vertices (boundary, non-manifold or inconsistent edges, repeated indices,
    more than ``_MAX_FAN_WALK`` corners) get the general test, connected
    components of the corner graph restricted to their corners.
    """
    F = np.asarray(F, dtype=np.int64)
    m = F.shape[0]
    if m == 0:
        return np.zeros(0, dtype=np.int64)
    topo = topo if topo is not None else edge_topology(F, n_vertices)
    # half-edge and corner ids as int32 when they fit (the same values): this
    # function's temporaries are the memory peak of a large check
    idx = np.int32 if 3 * m < 2 ** 31 else np.int64
    two = topo.face_count == 2
    e2 = np.flatnonzero(two)
    s2 = topo.edge_starts()[e2]
    order = topo.grouped_half_edges()
    a = order[s2].astype(idx)                         # the two half-edges of each
    s2 += 1
    b = order[s2].astype(idx)
    del s2
    corner_vertex = F.ravel()
    valence = np.bincount(corner_vertex, minlength=n_vertices)
    # vertices the walk cannot decide
    general = valence > _MAX_FAN_WALK
    general[topo.edges[~(two & (topo.forward_count == 1))].ravel()] = True
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    general[F[repeated].ravel()] = True

    bad_parts = []
    walk = np.flatnonzero(~general & (valence > 0))
    if walk.size:
        # corner 3f + k starts half-edge 3f + k; across it (twin t) the next
        # corner at the same vertex is the one ending t: 3 (t // 3) + (t + 1) % 3
        twin = np.full(3 * m, -1, dtype=idx)
        twin[a] = b
        twin[b] = a
        nxt = twin // 3
        nxt *= 3
        np.remainder(twin, 3, out=twin)
        twin += 1
        np.remainder(twin, 3, out=twin)
        nxt += twin
        del twin
        first = np.empty(n_vertices, dtype=idx)
        first[corner_vertex[::-1]] = np.arange(3 * m - 1, -1, -1, dtype=idx)
        s = first[walk]
        cur = nxt[s]
        need = valence[walk]
        steps = 1
        while walk.size:
            back = cur == s
            short = back & (steps < need)     # cycle closed before all corners
            if short.any():
                bad_parts.append(walk[short])
            keep = ~back
            walk, s, cur, need = walk[keep], s[keep], nxt[cur[keep]], need[keep]
            steps += 1

    gv = np.flatnonzero(general)
    if gv.size:
        # general test on the corners of the remaining vertices: only two-face
        # edges with an end among them give graph edges
        ends = topo.edges[e2]
        sel = general[ends[:, 0]] | general[ends[:, 1]]
        del ends
        a, b = a[sel], b[sel]
        he_start = corner_vertex                   # vertex where each half-edge starts
        same_dir = he_start[a] == he_start[b]
        a_e = a // 3 * 3 + (a % 3 + 1) % 3
        b_e = b // 3 * 3 + (b % 3 + 1) % 3
        rows = np.concatenate([a, a_e])
        cols = np.concatenate([np.where(same_dir, b, b_e), np.where(same_dir, b_e, b)])
        keep = general[corner_vertex[rows]]
        rows, cols = rows[keep], cols[keep]
        nodes = np.flatnonzero(general[corner_vertex])
        index = np.full(3 * m, -1, dtype=idx)
        index[nodes] = np.arange(nodes.size, dtype=idx)
        k = nodes.size
        g = sp.coo_matrix((np.ones(rows.size, dtype=np.int8), (index[rows], index[cols])),
                          shape=(k, k)).tocsr()
        _, lab = connected_components(g, directed=False)
        pairs = np.unique(corner_vertex[nodes] * k + lab)
        fans = np.bincount(pairs // k, minlength=n_vertices)
        bad = np.flatnonzero(fans > 1)
        if bad.size and topo.non_manifold.size:
            on_nm_edge = np.zeros(n_vertices, dtype=bool)
            on_nm_edge[topo.edges[topo.non_manifold].ravel()] = True
            bad = bad[~on_nm_edge[bad]]
        bad_parts.append(bad)
    if not bad_parts:
        return np.zeros(0, dtype=np.int64)
    return np.sort(np.concatenate(bad_parts)).astype(np.int64)


def duplicate_face_groups(F: np.ndarray, topo: EdgeTopology | None = None) -> np.ndarray:
    """Return faces that repeat an earlier face's vertex set (any orientation).

    Parameters
    ----------
    F : numpy.ndarray, (m, 3) int64
    topo : EdgeTopology, optional
        ``edge_topology(F)``: when no edge has more than two faces and no face
        repeats an index, the faces are distinct exactly when no face has the
        same neighbour across all three edges (:func:`has_twin_faces`), which
        is answered without sorting the faces.

    Returns
    -------
    numpy.ndarray, (k,) int64
        Indices of every face whose sorted vertex triple already occurred at a
        lower face index.
    """
    F = np.asarray(F, dtype=np.int64)
    if F.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    if (topo is not None and F.size >= JIT_MIN_SIZE and not (topo.face_count > 2).any()
            and not ((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])).any()
            and not has_twin_faces(topo)):
        return np.zeros(0, dtype=np.int64)
    s = np.sort(F, axis=1)
    n = int(s[:, 2].max()) + 1
    if n < 2 ** 21:             # one int64 key per face: a 1-D sort, not a row sort
        key = (s[:, 0] * n + s[:, 1]) * n + s[:, 2]
        _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    else:
        _, first, inv = np.unique(s, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    return np.flatnonzero(first[inv] != np.arange(F.shape[0]))


def has_twin_faces(topo: EdgeTopology) -> bool:
    """Whether some face has one and the same neighbouring face across all three edges.

    With no edge of more than two faces and no repeated index in a face, that
    is exactly when two faces have the same vertex set.

    Parameters
    ----------
    topo : EdgeTopology
        Of a mesh whose edges have at most two faces.

    Returns
    -------
    bool

    Raises
    ------
    InputError
        If an edge has more than two faces.
    """
    if (topo.face_count > 2).any():
        raise InputError("has_twin_faces needs edges of at most two faces")
    return bool(_twin_faces_loops(topo.half_to_edge, topo.grouped_half_edges(), topo.face_count))


@compiled
def _twin_faces_loops(half_to_edge, half_order, face_count):
    """:func:`has_twin_faces` as a loop (``half_order`` groups the half-edges by edge)."""
    ne = face_count.shape[0]
    start = np.empty(ne, np.int64)
    acc = 0
    for e in range(ne):
        start[e] = acc
        acc += face_count[e]
    m = half_to_edge.shape[0] // 3
    for f in range(m):
        first = -2
        same = True
        for k in range(3):
            h = 3 * f + k
            e = half_to_edge[h]
            other = -1
            if face_count[e] == 2:
                a = half_order[start[e]]
                other = half_order[start[e] + 1] // 3 if a == h else a // 3
            if other < 0 or (first != -2 and other != first):
                same = False
                break
            first = other
        if same:
            return True
    return False


def repeated_positions(V: np.ndarray) -> int:
    """Number of rows of ``V`` that repeat an earlier row exactly (``-0.0 == 0.0``).

    Rows are grouped by a hash of their bit patterns; only rows whose hash
    repeats are compared exactly, so the count is exact and the cost is one
    1-D sort.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64

    Returns
    -------
    int
    """
    V = np.ascontiguousarray(V, dtype=np.float64) + 0.0
    if V.shape[0] < 2:
        return 0
    B = V.view(np.uint64).reshape(-1, 3)
    with np.errstate(over="ignore"):
        key = (B[:, 0] * np.uint64(0x9E3779B97F4A7C15)) ^ (B[:, 1] * np.uint64(
            0xC2B2AE3D27D4EB4F)) ^ (B[:, 2] * np.uint64(0x165667B19E3779F9))
    _, inv, counts = np.unique(key, return_inverse=True, return_counts=True)
    shared = counts[inv.ravel()] > 1
    if not shared.any():
        return 0
    rows = V[shared]
    return int(rows.shape[0] - np.unique(rows, axis=0).shape[0])


def position_welded_faces(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Return ``F`` re-indexed so vertices at exactly equal positions share an index.

    Used where geometry, not bookkeeping, matters: an unwelded seam is not a
    self-intersection.  The index of each position is the lowest original
    vertex index at that position, so ``V`` can still be used with the result.

    Returns
    -------
    numpy.ndarray, (m, 3) int64
    """
    if V.shape[0] == 0:
        return np.asarray(F, dtype=np.int64).copy()
    _, first, inv = np.unique(V, axis=0, return_index=True, return_inverse=True)
    return first[inv.ravel()][F]


def greedy_colouring(n: int, pairs) -> np.ndarray:
    """Colours of ``n`` graph nodes such that no pair of ``pairs`` shares one (greedy).

    Nodes are coloured in order of decreasing degree (ties: ascending index),
    each with the smallest colour none of its coloured neighbours has; nodes
    without an edge get colour 0. (networkx's ``greedy_color`` with the
    ``largest_first`` strategy gives the same colours; this avoids importing
    networkx, ~0.25 s, on the main job's path for a graph of a few dozen edges.)

    Parameters
    ----------
    n : int
        Number of nodes.
    pairs : array_like, (k, 2) int64
        Edges (repeats and loops ignored).

    Returns
    -------
    numpy.ndarray, (n,) int64
        Colour of every node, ``0 .. max``.

    Examples
    --------
    >>> greedy_colouring(4, [[0, 1], [1, 2], [0, 2]]).tolist()
    [0, 1, 2, 0]
    """
    colour = np.zeros(n, dtype=np.int64)
    pairs = np.unique(np.sort(np.asarray(pairs, dtype=np.int64).reshape(-1, 2), axis=1), axis=0)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    if pairs.size == 0:
        return colour
    degree = np.bincount(pairs.ravel(), minlength=n)
    neighbours: dict[int, list[int]] = {}
    for a, b in pairs.tolist():
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    order = np.flatnonzero(degree)
    order = order[np.argsort(-degree[order], kind="stable")]
    done = np.zeros(n, dtype=bool)
    for u in order.tolist():
        taken = {int(colour[v]) for v in neighbours[u] if done[v]}
        c = 0
        while c in taken:
            c += 1
        colour[u] = c
        done[u] = True
    return colour
