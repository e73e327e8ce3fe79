"""Periodic global parameterization (PGP) steered by a cross field and a scale field.

Ray et al. 2006, in the simplified form of the material-space textures paper
(§2.3, eqs. 1-4), with the coordinate swaps of a 4-direction field kept.

Unknowns
--------
Every vertex ``v`` carries two periodic functions as one real 4-vector
``X_v = (cos 2 pi u, sin 2 pi u, cos 2 pi v, sin 2 pi v)`` (tile units: one
period per tile).  ``(u, v)`` are measured along the vertex's *own* axes: the
cross-field arms of a reference face of its fan.

Corner rotations
----------------
The cross field is combed (:func:`geotex.fields.combing.comb_direction_field`);
across every interior edge the combed arms of the two faces differ by a
rotation of ``j * 90`` degrees (``j`` = the matching).  Walking each vertex fan
from its reference corner and adding the matchings gives ``k_(f,v)`` in
``0..3``: at face ``f`` the vertex's ``u`` axis is ``f``'s combed arm ``k``.
The canonical coordinates of the corner in ``f``'s frame are then
``U + i V = i^k (u + i v)`` - a rotation by ``k * 90`` degrees, which on
``X_v`` is a signed permutation with conjugation (``P_k``, 4x4, orthogonal).

Energy (eq. 3, per face instead of per edge)
--------------------------------------------
Inside face ``f`` the field predicts the change of ``(U, V)`` along
``x_i -> x_j``: ``omega = (<a_f, x_j - x_i>, <b_f, x_j - x_i>) / S_f`` with
``(a_f, b_f)`` the combed arms and ``S_f`` the mean of the vertex scales
(eq. 1).  PGP minimises, over the three directed edges of every face,
``sum_f A_f |P_kj X_j - R(2 pi omega) P_ki X_i|^2`` (``R`` rotates each of
the two cos/sin pairs), against the mass ``M = diag(vertex area) x I_4``.  Each
interior edge gets ``A_T + A_T'``, as in the paper's ``F_PGP``; the paper
averages ``omega`` over the two faces instead of summing two terms.  The
minimiser is the smallest eigenvector of the real symmetric ``A X = l M X``
(a few steps of inverse iteration with one sparse factorization).  The ``u``
and ``v`` halves of the unknowns couple only through odd corner rotations;
the system is split into its connected blocks (on a flat patch with a
constant field: two, one per coordinate) and each is solved on its own.

Large meshes use a two-level solve instead: vertices are grouped in
clusters (grid cells of a few edge lengths, split into connected parts);
every vertex follows its cluster's 4-vector carried along a spanning tree by
the per-edge transfers ``T_ij = P_kj^T R(2 pi omega) P_ki`` (``X_j ~ T_ij
X_i``); the coarse problem ``P^T A P`` is solved directly and the prolonged
vector is smoothed by damped Jacobi sweeps.

Extraction (eq. 4)
------------------
Per corner the raw canonical coordinate is ``i^k (arg X_v / 2 pi)``.  Every
edge gets one predicted step ``alpha``: the two faces' predictions averaged
in a common frame (the paper's ``alpha_ij``), and one integer
``p = rint(raw_b - raw_a - alpha)``, the same on both sides of the edge.
Corners 1 and 2 of a face are placed from corner 0 with the integers of
edges 0-1 and 2-0.  The sum of the three integers around a face is its
winding: non-zero means the periodic function has a zero inside the face (a
*dislocation* of the grid).  Singular faces are those with a non-zero winding,
a vertex where the cross field is singular (a cone, index ``k / 4``), a corner
whose fan matching does not close (at cones of fractional index), or a vertex
whose periodic function vanishes.  Everywhere else, the corner coordinates on
the two sides of an edge differ exactly by a rotation by a multiple of 90
degrees and an integer translation; :attr:`PeriodicParameterization.seam_residual`
measures the largest deviation.
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Real

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components

from geotex.errors import InputError
from geotex.fields.combing import comb_direction_field
from geotex.fields.directions import DirectionField
from geotex.fields.frames import face_connection, tangent_angles
from geotex.fields.singularities import vertex_indices
from geotex.linalg import factor
from geotex.mesh.topology import edge_topology, non_manifold_vertices

__all__ = ["PeriodicParameterization", "periodic_parameterization"]

#: a vertex whose periodic function has a modulus below this fraction of the
#: RMS modulus has no reliable phase (its faces are marked singular)
VANISHING_MODULUS = 1e-6

#: inverse-iteration steps of the eigen solve (see ``_smallest``)
INVERSE_ITERATIONS = 8

#: ``solver="auto"`` switches to the multilevel solve from this many vertices
MULTILEVEL_VERTICES = 20000
#: cluster size of the multilevel solve, in mean edge lengths (grid cell)
CLUSTER_EDGES = 4.0
#: damped Jacobi sweeps after the coarse solve
SMOOTHING_SWEEPS = 30

# P_k as (source index, sign) per output slot: the canonical 4-vector of a
# vertex seen in a face whose arm k is the vertex's u axis
_PERM = np.array([[0, 1, 2, 3], [2, 3, 0, 1], [0, 1, 2, 3], [2, 3, 0, 1]])
_SIGN = np.array([[1, 1, 1, 1], [1, -1, 1, 1], [1, -1, 1, -1], [1, 1, 1, -1]], dtype=np.float64)


def _rotation_blocks() -> np.ndarray:
    """``P_k`` as dense (4, 4, 4) matrices."""
    P = np.zeros((4, 4, 4))
    for k in range(4):
        P[k, np.arange(4), _PERM[k]] = _SIGN[k]
    return P


_P = _rotation_blocks()
# cos and sin of k quarter turns
_QCOS = np.array([1.0, 0.0, -1.0, 0.0])
_QSIN = np.array([0.0, 1.0, 0.0, -1.0])
# inverse permutation and the sign of the entry it hits: P_k[_PINV[k, d], d] = _PSIGN[k, d]
_PINV = np.argsort(_PERM, axis=1)
_PSIGN = np.take_along_axis(_SIGN, _PINV, axis=1)


@dataclass(frozen=True, eq=False)
class PeriodicParameterization:
    """Result of :func:`periodic_parameterization`.

    Attributes
    ----------
    coords : numpy.ndarray, (m, 3, 2) float64
        ``(s, t)`` per face corner, in tile units (one tile per unit),
        continuous inside every face.  ``s`` runs along the face's combed
        cross-field arm, ``t`` along the arm turned by +90 degrees.  On
        ``singular`` faces the corners follow the field's local map from
        corner 0 (the face's own predicted steps) instead of the periodic
        functions, so baked textures show a correctly sized piece of the
        tile there, with a small jump at the face's edges.
    singular : numpy.ndarray, (m,) bool
        Faces where the coordinates cannot agree (see the module docstring).
    cones : tuple of (int, float)
        ``(vertex, index)`` of the cross field's singular vertices.
    dislocations : tuple of (int, int, int)
        ``(face, winding of s, winding of t)`` of faces inside which a
        periodic function winds (grid dislocations; index 0 each).
    index_sum : float
        Sum of the cone indices: the Euler characteristic on closed meshes
        (dislocations do not change it).
    seam_residual : float
        Largest deviation, over interior edges with no singular face, of the
        corner coordinates across the edge from an exact grid symmetry
        (rotation by a multiple of 90 degrees plus an integer translation),
        in tile units; 0.0 when there is no such edge.
    gradient_error : float
        Area-weighted mean, over non-singular faces, of
        ``|grad s - a/S| + |grad t - b/S|`` relative to ``1/S``: how far the
        tiles are from the field's orientation and size.
    distortion : dict
        Area-weighted over non-singular faces: ``scale_error_mean`` and
        ``scale_error_p95`` (largest of ``| |grad s| S - 1 |`` and the same
        for ``t``), ``angle_mean_deg`` and ``angle_p95_deg`` (angle between
        ``grad s`` and the field's arm).
    scale : numpy.ndarray, (n,) float64
        Tile size per vertex (surface units) that was used.
    eigenvalues : tuple of float
        Smallest eigenvalue of each solved block (0 for an exact solution).
    functions : numpy.ndarray, (n, 4) float64
        The solved periodic functions ``X_v`` (module docstring), in each
        vertex's own axes.
    axes : numpy.ndarray, (m, 3) float64
        The combed cross-field arm ``a_f`` of every face (its ``s`` axis); a
        vertex's own ``u`` axis is the arm of the face of its first corner.
        With ``functions``, what :func:`updated_parameterization` starts from.
    """

    coords: np.ndarray
    singular: np.ndarray
    cones: tuple
    dislocations: tuple
    index_sum: float
    seam_residual: float
    gradient_error: float
    distortion: dict
    scale: np.ndarray
    eigenvalues: tuple
    functions: np.ndarray
    axes: np.ndarray


def _scale_per_vertex(scale, n: int) -> np.ndarray:
    if isinstance(scale, Real) and not isinstance(scale, bool):
        value = float(scale)
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"scale must be a positive finite number (tile size in surface "
                             f"units), got {scale!r}")
        return np.full(n, value)
    try:
        arr = np.asarray(scale, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("scale must be a positive number or an (n,) array of them") from None
    if arr.shape != (n,):
        raise InputError(f"scale must be a positive number or have shape ({n},), "
                         f"got shape {arr.shape}")
    if not (np.isfinite(arr).all() and (arr > 0).all()):
        raise InputError("scale must be positive and finite at every vertex")
    return arr.copy()


def _field_vectors(field, m: int) -> np.ndarray:
    if isinstance(field, DirectionField):
        if field.symmetry not in (1, 2, 4):
            raise InputError(f"field must have symmetry 1, 2 or 4 (its arms are used as a "
                             f"cross), got {field.symmetry}")
        vec = np.asarray(field.vectors, dtype=np.float64)
    else:
        try:
            vec = np.asarray(field, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError("field must be a DirectionField or an (m, 3) array of "
                             "vectors") from None
    if vec.shape != (m, 3):
        raise InputError(f"field must have one vector per face, shape ({m}, 3), "
                         f"got {vec.shape}")
    if not np.isfinite(vec).all():
        raise InputError("field has non-finite vectors")
    return vec


def _corner_rotations(F: np.ndarray, conn, jump: np.ndarray, slots: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """``k`` per corner (m, 3) from fan walks, and a per-dual-edge 'does not close' mask.

    A vertex's reference corner (``k = 0``) is its first corner in ``F``.
    """
    m = F.shape[0]
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    a = np.concatenate([3 * f + slots[:, 0], 3 * f + slots[:, 1]])
    b = np.concatenate([3 * g + slots[:, 2], 3 * g + slots[:, 3]])
    st = np.concatenate([jump, jump])
    root = 3 * m
    _, ref = np.unique(F.ravel(), return_index=True)
    rows = np.concatenate([a, b, np.full(ref.size, root)])
    cols = np.concatenate([b, a, ref])
    # k_b - k_a = j along a -> b; stored as value + 1 so that 0 survives
    vals = np.concatenate([np.mod(st, 4), np.mod(-st, 4), np.zeros(ref.size, np.int64)]) + 1
    G = sp.csr_matrix((vals, (rows, cols)), shape=(root + 1, root + 1))
    G.sum_duplicates()
    _, pred = breadth_first_order(G, root, directed=True, return_predecessors=True)
    pred = pred.astype(np.int64)
    child = np.flatnonzero(pred[:root] >= 0)
    step = np.zeros(root + 1, dtype=np.int64)
    # the stored value of every tree edge (pred -> child): G is canonical CSR,
    # so its entries' (row, column) keys are sorted
    gkey = np.repeat(np.arange(root + 1, dtype=np.int64), np.diff(G.indptr)) * (root + 1)
    gkey += G.indices
    pos = np.searchsorted(gkey, pred[child] * (root + 1) + child)
    step[child] = G.data[pos].astype(np.int64) - 1
    anc = np.where(pred >= 0, pred, root)
    anc[root] = root
    acc = step.copy()
    while np.any(anc[:root] != root):
        acc = np.mod(acc + acc[anc], 4)
        anc = anc[anc]
    k = np.mod(acc[:root], 4)
    bad = np.mod(k[b] - k[a] - st, 4) != 0
    half = a.size // 2
    return k.reshape(m, 3), bad[:half] | bad[half:]


def _arm_steps(arms: np.ndarray, d: np.ndarray, S_face: np.ndarray) -> np.ndarray:
    """``(<a_f, d_f>, <b_f, d_f>) / S_f`` per face, (m, 2): a step in tile units."""
    a, b = arms[:, 0], arms[:, 1]
    return np.stack([d[:, 0] * a[:, 0] + d[:, 1] * a[:, 1] + d[:, 2] * a[:, 2],
                     d[:, 0] * b[:, 0] + d[:, 1] * b[:, 1] + d[:, 2] * b[:, 2]], axis=1) \
        / S_face[:, None]


def _transfer_codes() -> np.ndarray:
    """``T = P_kj^T D P_ki`` as codes: (16 = 4 kj + ki, 16 entries) indices into
    ``[0, c0, s0, c1, s1, -c0, -s0, -c1, -s1]`` (``D``: the two rotations)."""
    src = np.zeros((4, 4), dtype=np.int64)               # D's entries as codes
    src[0, 0], src[0, 1], src[1, 0], src[1, 1] = 1, 6, 2, 1
    src[2, 2], src[2, 3], src[3, 2], src[3, 3] = 3, 8, 4, 3
    negate = np.array([0, 5, 6, 7, 8, 1, 2, 3, 4])
    out = np.zeros((16, 16), dtype=np.intp)
    for kj in range(4):
        for ki in range(4):
            # P signed permutations: T[a, d] = s_j(a) s_i(d) D[r_j(a), r_i(d)]
            code = src[_PINV[kj][:, None], _PINV[ki][None, :]]
            neg = (_PSIGN[kj][:, None] * _PSIGN[ki][None, :]) < 0
            out[4 * kj + ki] = np.where(neg, negate[code], code).ravel()
    return out


_TCODES = _transfer_codes()


def _transfers(V, F, k, arms, S_face):
    """Per directed face edge ``i -> j``: ``(i, j, T)`` with ``X_j ~ T X_i`` (T orthogonal 4x4).

    ``canonical_j = D canonical_i`` with ``D`` the rotations by the field's
    predicted phase steps and ``canonical = P_k X``, so ``T = P_kj^T D P_ki``;
    its entries are gathered from ``(0, +-cos, +-sin)`` by :data:`_TCODES`.
    """
    m = F.shape[0]
    T = np.empty((3 * m, 4, 4))
    vals = np.zeros((m, 9))
    for e, (ca, cb) in enumerate(((0, 1), (1, 2), (2, 0))):
        om = (2.0 * np.pi) * _arm_steps(arms, V[F[:, cb]] - V[F[:, ca]], S_face)
        c, s = np.cos(om), np.sin(om)
        vals[:, 1], vals[:, 2], vals[:, 3], vals[:, 4] = c[:, 0], s[:, 0], c[:, 1], s[:, 1]
        vals[:, 5:] = -vals[:, 1:5]
        code = _TCODES[4 * k[:, cb] + k[:, ca]]
        T[e * m:(e + 1) * m] = np.take_along_axis(vals, code, axis=1).reshape(m, 4, 4)
    return F.T.ravel(), F[:, [1, 2, 0]].T.ravel(), T


def _energy(I, J, T, weight, n):
    """The 4n x 4n symmetric energy: sum w |X_j - T X_i|^2 over directed face edges.

    The off-diagonal 4x4 block of every mesh edge ``(lo, hi)`` (row ``hi``)
    sums ``-w T`` of its directed face edges ``lo -> hi`` and ``-w T^T`` of
    those ``hi -> lo`` (one stable sort of the edge keys, then a segmented
    sum); the diagonal blocks are ``w I``.  The blocks are laid out as a
    block-sparse matrix in row order (a second sort, of one key per block)
    and returned as CSR without stored zeros.
    """
    w = np.tile(weight, 3)
    fwd = I < J
    lo, hi = np.where(fwd, I, J), np.where(fwd, J, I)
    key = lo * n + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    start = np.flatnonzero(np.diff(ks, prepend=-1))                  # keys are >= 0
    Ts = T[order]
    back = ~fwd[order]
    Ts[back] = np.transpose(Ts[back], (0, 2, 1))
    Ts *= -w[order][:, None, None]
    L = np.add.reduceat(Ts, start, axis=0) if start.size else Ts      # (E, 4, 4) at (hi, lo)
    elo, ehi = lo[order][start], hi[order][start]
    diag = np.bincount(I, weights=w, minlength=n) + np.bincount(J, weights=w, minlength=n)
    verts = np.arange(n)
    br = np.concatenate([ehi, elo, verts])
    bc = np.concatenate([elo, ehi, verts])
    src = np.argsort(br * n + bc)                                    # keys are unique
    blocks = np.concatenate([L, np.transpose(L, (0, 2, 1)),
                             diag[:, None, None] * np.eye(4)])[src]
    indptr = np.searchsorted(br[src], np.arange(n + 1))
    A = sp.bsr_matrix((blocks, bc[src], indptr), shape=(4 * n, 4 * n), blocksize=(4, 4)).tocsr()
    A.eliminate_zeros()          # exact zeros: u and v blocks that do not couple
    return A


def _smallest(A: sp.csr_matrix, mass: np.ndarray, rng: np.random.Generator
              ) -> tuple[np.ndarray, float]:
    """Approximate smallest generalized eigenpair of ``A x = l diag(mass) x`` (A PSD).

    Small blocks use a dense solver.  Larger ones use :data:`INVERSE_ITERATIONS`
    steps of inverse iteration with one factorization of ``A + eps M`` (positive
    definite even where ``A`` is singular) from a start vector drawn from
    ``rng``: the lowest modes dominate after a few steps, and the seam
    exactness does not depend on how far the iteration is taken (only the
    smoothness of the periodic functions does).  On a 12k-face torus ARPACK
    to 1e-10 took 157 solves for an eigenvalue 0.6 % lower and the same
    gradient error.
    """
    size = A.shape[0]
    if size <= 64:
        w, vecs = scipy.linalg.eigh(A.toarray(), np.diag(mass), subset_by_index=[0, 0])
        return vecs[:, 0], float(w[0])
    eps = 1e-8 * float(A.diagonal().mean()) / float(mass.mean())
    lu = factor((A + eps * sp.diags(mass)).tocsc(), hpd=True, what="periodic_parameterization")
    x = rng.standard_normal(size)
    for _ in range(INVERSE_ITERATIONS):
        x = lu.solve(mass * x)
        x /= np.sqrt(float(np.dot(x, mass * x)))
    return x, float(x @ (A @ x))


def _solve_direct(A: sp.csr_matrix, vmass: np.ndarray, n: int, rng) -> tuple[np.ndarray, tuple]:
    """Solve every connected block of half-nodes (vertex, u or v part) separately."""
    coo = A.tocoo()
    hr, hc = coo.row // 2, coo.col // 2
    H = sp.csr_matrix((np.ones(hr.size, np.int8), (hr, hc)), shape=(2 * n, 2 * n))
    ncomp, label = connected_components(H, directed=False)
    live = np.zeros(2 * n, dtype=bool)
    live[hr[coo.data != 0]] = True
    X = np.zeros(4 * n)
    lams = []
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(ncomp + 1))
    for c in range(ncomp):
        halves = order[starts[c]:starts[c + 1]]
        if not live[halves[0]]:
            continue
        idx = np.stack([2 * halves, 2 * halves + 1], axis=1).ravel()
        mass = np.repeat(vmass[halves // 2], 2)
        x, lam = _smallest(A[idx][:, idx], mass, rng)
        X[idx] = x
        lams.append(max(lam, 0.0))
    return X.reshape(n, 4), tuple(lams)


def _clusters(V, I, J, n, size):
    """Vertex clusters: cells of a grid of step ``size``, split into edge-connected parts."""
    cell = np.floor((V - V.min(axis=0)) / size).astype(np.int64)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]      # one id per cell
    same = key[I] == key[J]
    G = sp.csr_matrix((np.ones(int(same.sum()), np.int8), (I[same], J[same])), shape=(n, n))
    return connected_components(G, directed=False)


def _prolongation(I, J, T, n, label, count):
    """``P`` (4n x 4 count): each vertex = its cluster's 4-vector carried along a BFS tree."""
    root = n
    first = np.full(count, n, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n))
    same = label[I] == label[J]
    e = np.flatnonzero(same)
    rows = np.concatenate([I[e], J[e], np.full(count, root)])
    cols = np.concatenate([J[e], I[e], first])
    code = np.concatenate([2 * e + 1, 2 * e + 2, np.zeros(count, np.int64)])   # >0 stored
    G = sp.csr_matrix((code + 1, (rows, cols)), shape=(n + 1, n + 1))   # structure only
    _, pred = breadth_first_order(G, root, directed=True, return_predecessors=True)
    pred = pred.astype(np.int64)
    child = np.flatnonzero(pred[:n] >= 0)
    Q = np.broadcast_to(np.eye(4), (n + 1, 4, 4)).copy()
    # the code of the tree edge parent -> child (one directed face edge, either way)
    lookup = sp.coo_matrix((code + 1, (rows, cols)), shape=(n + 1, n + 1))
    lr, lc = lookup.row.astype(np.int64), lookup.col.astype(np.int64)   # int32 overflows
    _, keep = np.unique(lr * (n + 1) + lc, return_index=True)
    kr, kc, kv = lr[keep], lc[keep], lookup.data[keep] - 1
    pos = np.searchsorted(kr * (n + 1) + kc, pred[child] * (n + 1) + child)
    cval = kv[pos]
    tree = pred[child] != root
    cc, cv = child[tree], cval[tree]
    fwd = cv % 2 == 1
    eidx = (cv - 1 - (~fwd)) // 2
    step = T[eidx]
    step[~fwd] = np.transpose(step[~fwd], (0, 2, 1))            # inverse = transpose
    Q[cc] = step
    # depth below the cluster's first vertex (pointer jumping on integers), then
    # Q_v = step_v Q_parent level by level: every vertex is multiplied once
    anc = np.where(pred >= 0, pred, root)
    anc[root] = root
    depth = np.zeros(n + 1, dtype=np.int64)
    depth[cc] = 1
    while np.any(anc[:n] != root):
        depth = depth + depth[anc]
        anc = anc[anc]
    order = cc[np.argsort(depth[cc], kind="stable")]
    bounds = np.searchsorted(depth[order], np.arange(1, int(depth.max()) + 2))
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        v = order[lo:hi]
        Q[v] = np.matmul(Q[v], Q[pred[v]])
    Q = Q[:n]
    # CSR directly: row 4v + a holds Q_v[a, :] in the columns of v's cluster
    cols = np.broadcast_to(4 * label[:, None, None] + np.arange(4), (n, 4, 4))
    return sp.csr_matrix((Q.ravel(), cols.ravel(), np.arange(0, 16 * n + 1, 4)),
                         shape=(4 * n, 4 * count))


def _solve_multilevel(A, vmass, V, I, J, T, n, rng, cell, sweeps):
    """Coarse eigenvector on field-transported clusters, then damped Jacobi sweeps."""
    count, label = _clusters(V, I, J, n, cell)
    P = _prolongation(I, J, T, n, label, count)
    Ac = (P.T @ A @ P).tocsr()
    Ac.data[np.abs(Ac.data) < 1e-14 * np.abs(Ac.data).max()] = 0.0
    cmass = np.bincount(label, weights=vmass, minlength=count)
    Y, lams = _solve_direct(Ac, cmass, count, rng)
    x = P @ Y.ravel()
    dinv = 1.0 / np.maximum(A.diagonal(), 1e-300)
    mass = np.repeat(vmass, 4)
    for _ in range(sweeps):
        x = x - 0.5 * dinv * (A @ x)
    x /= np.sqrt(max(float(np.dot(x, mass * x)), 1e-300))
    return x.reshape(n, 4), (float(x @ (A @ x)),)


def _rotate(coords: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Apply ``U + i V = i^k (u + i v)`` to (..., 2) coordinates (exact: factors 0, +-1)."""
    u, v = coords[..., 0], coords[..., 1]
    k = np.mod(k, 4)
    c, s = _QCOS[k], _QSIN[k]
    return np.stack([c * u - s * v, s * u + c * v], axis=-1)


def _weighted_quantile(x: np.ndarray, w: np.ndarray, q: float) -> float:
    order = np.argsort(x, kind="stable")
    cum = np.cumsum(w[order])
    return float(x[order][min(int(np.searchsorted(cum, q * cum[-1])), x.size - 1)])


def _distortion(size_err: np.ndarray, angle: np.ndarray, area: np.ndarray) -> dict:
    if size_err.size == 0:
        return {"scale_error_mean": 0.0, "scale_error_p95": 0.0,
                "angle_mean_deg": 0.0, "angle_p95_deg": 0.0}
    return {"scale_error_mean": float(np.average(size_err, weights=area)),
            "scale_error_p95": _weighted_quantile(size_err, area, 0.95),
            "angle_mean_deg": float(np.average(angle, weights=area)),
            "angle_p95_deg": _weighted_quantile(angle, area, 0.95)}


def _edge_slots(F: np.ndarray, conn) -> np.ndarray:
    """Per interior edge ``(lo, hi)`` of ``conn``: the slots of ``lo`` and ``hi`` in its
    face ``f`` and in its face ``g``, (e, 4) int64 (``f`` holds ``lo -> hi``)."""
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    lo, hi = conn.vertices[:, 0], conn.vertices[:, 1]
    Ff, Fg = F[f], F[g]
    return np.stack([np.argmax(Ff == lo[:, None], axis=1), np.argmax(Ff == hi[:, None], axis=1),
                     np.argmax(Fg == lo[:, None], axis=1), np.argmax(Fg == hi[:, None], axis=1)],
                    axis=1)


def _shared_edge_prediction(conn, slots, k, pred):
    """Average the two faces' predicted steps of every interior edge (eq. 3's alpha_ij).

    ``pred[f, c]`` is the step from corner ``c`` to ``c + 1`` in ``f``'s
    canonical frame.  Both predictions are taken to the frame of the edge's
    first vertex, averaged and taken back, so that the two faces round the
    edge's phase difference to the same integer.
    """
    out = pred.copy()
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    cf = slots[:, 0]                                     # f holds lo -> hi at slot cf
    cg = slots[:, 3]                                     # g holds hi -> lo at slot cg
    kf = k[f, cf]
    kg = k[g, slots[:, 2]]                               # corner of lo in g
    back_f = _rotate(pred[f, cf], -kf)
    back_g = _rotate(-pred[g, cg], -kg)
    mean = 0.5 * (back_f + back_g)
    out[f, cf] = _rotate(mean, kf)
    out[g, cg] = -_rotate(mean, kg)
    return out


def _edge_residuals(coords, conn, slots, edges) -> np.ndarray:
    """Deviation from the nearest grid symmetry across each of ``edges`` (ids into ``conn``)."""
    f, g = conn.faces[edges, 0], conn.faces[edges, 1]
    sl = slots[edges]
    # the two corners (lo, hi) of the edge in f and in g, each (e, 2) = (s, t)
    fl, fh = coords[f, sl[:, 0]], coords[f, sl[:, 1]]
    gl, gh = coords[g, sl[:, 2]], coords[g, sl[:, 3]]
    best = np.full(f.size, np.inf)
    for c, s in ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)):    # i^r (s + i t)
        dul = gl[:, 0] - (c * fl[:, 0] - s * fl[:, 1])
        duh = gh[:, 0] - (c * fh[:, 0] - s * fh[:, 1])
        dvl = gl[:, 1] - (s * fl[:, 0] + c * fl[:, 1])
        dvh = gh[:, 1] - (s * fh[:, 0] + c * fh[:, 1])
        tu = np.rint(0.5 * (dul + duh))
        tv = np.rint(0.5 * (dvl + dvh))
        res = np.maximum(np.maximum(np.abs(dul - tu), np.abs(duh - tu)),
                         np.maximum(np.abs(dvl - tv), np.abs(dvh - tv)))
        np.minimum(best, res, out=best)
    return best


def _seam_residual(coords, conn, slots, ok_edge) -> float:
    edges = np.flatnonzero(ok_edge)
    if edges.size == 0:
        return 0.0
    return float(_edge_residuals(coords, conn, slots, edges).max())


def _face_measures(V, F, coords, axes, S_face, good, areas) -> tuple[float, dict]:
    """``gradient_error`` and ``distortion`` over the faces ``good`` (see the class).

    Works in the frame ``(t1, t2)`` of each face with ``t1`` along its first
    edge ``e1`` and ``t2 = n x t1`` (both measures are frame-invariant), from
    dot products only, so it needs no face connection: the tiles' gradients
    from the corner coordinates against the field's ``a / S`` and
    ``(n x a) / S``.  With ``e1 = (x1, 0)``, ``e2 = (x2, y2)`` and
    ``(e1 x e2) x e1 = e2 |e1|^2 - e1 (e1 . e2)``.  ``areas`` (m,): the face areas.
    """
    P = V[F[good]]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    area = areas[good]
    area2 = 2.0 * area
    e11, e12 = np.einsum("ij,ij->i", e1, e1), np.einsum("ij,ij->i", e1, e2)
    a = axes[good]
    ae1, ae2 = np.einsum("ij,ij->i", a, e1), np.einsum("ij,ij->i", a, e2)
    S = S_face[good]
    x1 = np.sqrt(e11)
    x2, y2 = e12 / x1, area2 / x1
    # a = (a1, a2) and n x a = (-a2, a1) in the frame, over S
    a1 = ae1 / (x1 * S)
    a2 = (ae2 * e11 - ae1 * e12) / (area2 * x1 * S)
    C = coords[good]
    dC1, dC2 = C[:, 1] - C[:, 0], C[:, 2] - C[:, 0]                   # (k, 2 coords)
    g1 = dC1 / x1[:, None]                                            # d/dt1 of (s, t)
    g2 = (dC2 - x2[:, None] * g1) / y2[:, None]                       # d/dt2
    err = (np.hypot(g1[:, 0] - a1, g2[:, 0] - a2) + np.hypot(g1[:, 1] + a2, g2[:, 1] - a1)) * S
    gerr = float(np.average(err, weights=area)) if err.size else 0.0
    size_err = np.maximum(np.abs(np.hypot(g1[:, 0], g2[:, 0]) * S - 1.0),
                          np.abs(np.hypot(g1[:, 1], g2[:, 1]) * S - 1.0))
    angle = np.degrees(np.abs(np.arctan2(g1[:, 0] * a2 - g2[:, 0] * a1,
                                         g1[:, 0] * a1 + g2[:, 0] * a2)))
    return gerr, _distortion(size_err, angle, area)


def _corner_coordinates(st, X):
    """Eq. 4 on ``st``'s mesh: raw coordinates, predicted steps, coordinates, windings.

    Returns ``raw`` (m, 3, 2) (per corner ``i^k arg X / 2 pi``), ``pred``
    (m, 3, 2) (the field's local map from corner 0), ``coords`` (m, 3, 2)
    (corners 1 and 2 placed from corner 0 with the edges' integers) and
    ``wind`` (m, 2) int64.
    """
    V, F, k, arms, S_face = st.V, st.F, st.k, st.arms, st.S_face
    raw_v = np.stack([np.arctan2(X[:, 1], X[:, 0]), np.arctan2(X[:, 3], X[:, 2])],
                     axis=1) / (2.0 * np.pi)                            # (n, 2)
    raw = _rotate(raw_v[F], k)                                          # (m, 3, 2)
    P = V[F]
    pred = np.zeros((F.shape[0], 3, 2))                                  # (m, 3, 2)
    pred[:, 1] = _arm_steps(arms, P[:, 1] - P[:, 0], S_face)
    pred[:, 2] = _arm_steps(arms, P[:, 2] - P[:, 0], S_face)
    omega = _shared_edge_prediction(st.conn, st.slots, k, np.roll(pred, -1, axis=1) - pred)
    step = np.rint(np.roll(raw, -1, axis=1) - raw - omega)          # slot c: corner c -> c+1
    coords = raw.copy()
    coords[:, 1] = raw[:, 1] - step[:, 0]
    coords[:, 2] = raw[:, 2] + step[:, 2]
    wind = (step[:, 0] + step[:, 1] + step[:, 2]).astype(np.int64)    # (m, 2)
    return raw, pred, coords, wind


def _touching(mask: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Faces with a corner where the vertex ``mask`` holds, (m,) bool."""
    return mask[F[:, 0]] | mask[F[:, 1]] | mask[F[:, 2]]


def _vanishing(X: np.ndarray, vmass: np.ndarray) -> np.ndarray:
    """Vertices whose periodic function has no reliable phase, (n,) bool."""
    mu = np.hypot(X[:, 0], X[:, 1])
    mv = np.hypot(X[:, 2], X[:, 3])
    rms = np.sqrt(np.sum(vmass * (mu ** 2 + mv ** 2)) / max(2 * vmass.sum(), 1e-300))
    return np.minimum(mu, mv) < VANISHING_MODULUS * rms


def periodic_parameterization(V, F, field, *, scale, solver: str = "auto",
                              seed=None, symmetry: int = 4) -> PeriodicParameterization:
    """Return per-corner tile coordinates that agree across edges up to grid symmetries.

    See the module docstring for the method (Ray et al. 2006; material-space
    textures §2.3, eqs. 1-4).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        Consistently oriented, edge- and vertex-manifold (boundaries allowed).
    field : DirectionField or array_like, (m, 3)
        Orientation: a direction field of symmetry 1, 2 or 4, or one tangent
        vector per face; its four arms (the vector turned by multiples of 90
        degrees) orient the tiles.
    scale : float or array_like, (n,)
        Tile size in surface units (one period of ``s`` and ``t``), for the
        whole mesh or per vertex (e.g. :func:`geotex.fields.scalar.scale_field`).
    solver : {"auto", "direct", "multilevel"}, optional
        ``"direct"``: inverse iteration with one sparse factorization of the
        whole system.  ``"multilevel"``: the same on clusters of about
        ``CLUSTER_EDGES`` edge lengths, whose vertices follow the cluster's
        4-vector carried along the field's predicted phases, then
        ``SMOOTHING_SWEEPS`` damped Jacobi sweeps on the full system (a
        slightly higher energy; the seams stay exact either way).
        ``"auto"``: multilevel from ``MULTILEVEL_VERTICES`` vertices on.
    seed : int, optional
        Start vector of the eigen solver; ``None`` means 0 (reproducible).
    symmetry : {4, 2}, optional
        The grid symmetries the coordinates may jump by across edges: 4,
        quarter turns (any field); 2, half turns only, for tiles that are not
        symmetric under a quarter turn (bricks, planks): the ``s`` axis then
        follows ``field``'s own vector (or its opposite) everywhere, where a
        quarter-turn combing may swap ``s`` and ``t`` over whole regions.
        Needs a field without quarter-turn structure: vectors, or a field of
        symmetry 1 or 2.

    Returns
    -------
    PeriodicParameterization

    Raises
    ------
    InputError
        On malformed, degenerate, inconsistently oriented or non-manifold
        meshes, a field of the wrong shape or symmetry, a non-positive
        scale or an unknown solver.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(4, 4)
    >>> p = periodic_parameterization(V, F, np.tile([1.0, 0, 0], (len(F), 1)), scale=0.5)
    >>> bool(p.seam_residual < 1e-9), bool(p.singular.any())
    (True, False)
    """
    st = _setup(V, F, field, scale, symmetry)
    if solver not in ("auto", "direct", "multilevel"):
        raise InputError(f"solver must be 'auto', 'direct' or 'multilevel', got {solver!r}")
    n = st.V.shape[0]
    I, J, T = _transfers(st.V, st.F, st.k, st.arms, st.S_face)
    A = _energy(I, J, T, st.weight, n)
    rng = np.random.default_rng(0 if seed is None else seed)
    if solver == "direct" or (solver == "auto" and n < MULTILEVEL_VERTICES):
        X, lams = _solve_direct(A, st.vmass, n, rng)
    else:
        edge = float(np.linalg.norm(st.V[J] - st.V[I], axis=1).mean())
        X, lams = _solve_multilevel(A, st.vmass, st.V, I, J, T, n, rng, CLUSTER_EDGES * edge,
                                    SMOOTHING_SWEEPS)
    return _extracted(st, X, lams)


@dataclass(frozen=True, eq=False)
class _Setup:
    """Everything the solve and the extraction need besides the functions."""

    V: np.ndarray
    F: np.ndarray
    conn: object
    combed: object
    arms: np.ndarray          # (m, 2, 3) combed arms a, b
    S: np.ndarray             # (n,) tile size per vertex
    S_face: np.ndarray        # (m,)
    k: np.ndarray             # (m, 3) corner rotations
    open_fan: np.ndarray      # dual edges whose fan matching does not close
    weight: np.ndarray        # (m,) relative face areas
    vmass: np.ndarray         # (n,)
    slots: np.ndarray         # (e, 4) corner slots of the interior edges (_edge_slots)


def _setup(V, F, field, scale, symmetry: int = 4) -> _Setup:
    """Validate the mesh, comb the field, and find the corner rotations."""
    conn = face_connection(V, F)                      # validates the mesh and orientation
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n, m = V.shape[0], F.shape[0]
    topo = edge_topology(F, n)
    if (topo.face_count > 2).any():
        raise InputError("F has non-manifold edges (more than two faces); repair the mesh "
                         "first, e.g. with geotex repair")
    bow = non_manifold_vertices(F, n, topo)
    if bow.size:
        raise InputError(f"F has {bow.size} non-manifold vertex(es), first {int(bow[0])}; "
                         "repair the mesh first, e.g. with geotex repair")
    if symmetry not in (2, 4) or isinstance(symmetry, bool):
        raise InputError(f"symmetry must be 4 (quarter turns) or 2 (half turns), got {symmetry!r}")
    if symmetry == 2 and isinstance(field, DirectionField) and field.symmetry == 4:
        raise InputError("symmetry 2 needs a field of symmetry 1 or 2 (or vectors); a cross "
                         "field turns by quarter turns")
    return _prepared(V, F, conn, _field_vectors(field, m), _scale_per_vertex(scale, n),
                     symmetry)


def _prepared(V, F, conn, vectors, S, symmetry: int = 4) -> _Setup:
    """Comb the field and find the corner rotations on a checked mesh (``conn`` its
    connection, ``vectors`` (m, 3) and ``S`` (n,) checked); ``symmetry`` 2 combs
    by half turns only."""
    n = V.shape[0]
    combed = comb_direction_field(V, F, vectors, symmetry=symmetry, connection=conn)
    jump = np.zeros(conn.edges.size, dtype=np.int64)
    jump[np.searchsorted(conn.edges, combed.cut_edges)] = combed.jumps * (4 // symmetry)
    theta = tangent_angles(conn.T1, conn.T2, combed.vectors)
    a = np.cos(theta)[:, None] * conn.T1 + np.sin(theta)[:, None] * conn.T2
    b = np.cross(conn.N, a)
    slots = _edge_slots(F, conn)
    k, open_fan = _corner_rotations(F, conn, jump, slots)
    weight = conn.areas / conn.areas.mean()
    vmass = np.bincount(F.ravel(), weights=np.repeat(weight / 3.0, 3), minlength=n)
    return _Setup(V, F, conn, combed, np.stack([a, b], axis=1), S, S[F].mean(axis=1), k,
                  open_fan, weight, vmass, slots)


def _extracted(st: _Setup, X: np.ndarray, lams) -> PeriodicParameterization:
    """Per-corner coordinates, singular faces and the measures (eq. 4)."""
    F, conn = st.F, st.conn
    raw, pred, coords, wind = _corner_coordinates(st, X)
    vanish = _vanishing(X, st.vmass)
    index = vertex_indices(st.V, F, st.combed.vectors, symmetry=4, connection=conn)
    cone = np.nan_to_num(index) != 0
    winds = (wind[:, 0] != 0) | (wind[:, 1] != 0)
    singular = winds | _touching(cone, F) | _touching(vanish, F)
    fo, go = conn.faces[st.open_fan, 0], conn.faces[st.open_fan, 1]
    singular[fo] = True
    singular[go] = True

    ok_edge = ~(singular[conn.faces[:, 0]] | singular[conn.faces[:, 1]])
    residual = _seam_residual(coords, conn, st.slots, ok_edge)
    # singular faces: the periodic functions cannot be followed there (a full
    # period can wind inside the face); lay the field's own local map instead,
    # anchored at corner 0, so the face shows one correctly sized, oriented
    # piece of the tile (a small jump at its edges) rather than a squeezed period
    coords[singular] = raw[singular, :1] + pred[singular]
    gerr, dist = _face_measures(st.V, F, coords, st.arms[:, 0], st.S_face, ~singular, conn.areas)

    cv = np.flatnonzero(cone)
    disl = np.flatnonzero(winds)
    return PeriodicParameterization(
        coords=np.ascontiguousarray(coords), singular=singular,
        cones=tuple((int(v), float(index[v])) for v in cv),
        dislocations=tuple((int(f), int(wind[f, 0]), int(wind[f, 1])) for f in disl),
        index_sum=float(np.sum(index[cv])) if cv.size else 0.0,
        seam_residual=residual, gradient_error=gerr, distortion=dist, scale=st.S,
        eigenvalues=tuple(lams), functions=np.ascontiguousarray(X),
        axes=np.ascontiguousarray(st.arms[:, 0]))
