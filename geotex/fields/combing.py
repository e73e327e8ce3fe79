"""Combing N-direction fields: pick one of the N representatives per face consistently.

An N-direction field stores an unordered set of N vectors per face.  Algorithms
that need a single vector per face (patch orientation, parameterization) must
choose representatives so that neighbours agree.  Singularities make a global
choice impossible; the mismatch is pushed onto a set of *cut* edges.

Method: a breadth-first spanning tree of the dual graph (faces joined across
interior edges; one tree per connected component, rooted at its lowest face,
so face 0 is the root of its component) is walked from the root, and every
child picks the representative closest to its parent's representative
transported across the shared edge.  The choice is an integer offset per tree
edge; the offsets are summed along the tree with pointer doubling (``log
depth`` vectorized passes).  Dual edges outside the tree whose combed vectors
still differ by a rotation of ``2 pi j / N`` (``j != 0``) are the cut edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components

from geotex.errors import InputError
from geotex.fields.directions import DirectionField, _check_symmetry
from geotex.fields.frames import (FaceConnection, _checked_arrays, _connection, tangent_angles,
                                  vectors_from_angles)
from geotex.fields.singularities import _field_phases

__all__ = ["CombedField", "comb_direction_field", "combed_vectors"]


@dataclass(frozen=True, eq=False)
class CombedField:
    """Result of :func:`comb_direction_field`.

    Attributes
    ----------
    vectors : numpy.ndarray, (m, 3) float64
        The combed representative per face (unit, tangent).
    rotations : numpy.ndarray, (m,) int64
        ``k_f`` in ``[0, N)``: the combed vector is the input representative
        turned by ``2 pi k_f / N`` about the face normal.
    cut_edges : numpy.ndarray, (c,) int64
        Unique-edge indices (``geotex.mesh.topology`` order), ascending, of the
        interior edges across which the combed vectors jump.
    jumps : numpy.ndarray, (c,) int64
        ``j`` in ``[1, N)`` per cut edge: crossing from face ``f`` to ``g`` (as
        in :class:`geotex.fields.frames.FaceConnection`), ``g``'s combed vector
        must be turned by ``2 pi j / N`` to match ``f``'s transported one.
    tree_parent : numpy.ndarray, (m,) int64
        Parent face in the spanning tree, ``-1`` for component roots.
    """

    vectors: np.ndarray
    rotations: np.ndarray
    cut_edges: np.ndarray
    jumps: np.ndarray
    tree_parent: np.ndarray


def _matching(conn: FaceConnection, theta: np.ndarray, N: int) -> np.ndarray:
    """Rotation steps (mod N) that best align ``g`` with ``f`` transported, per dual edge."""
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    steps = np.rint((theta[f] + conn.angle - theta[g]) * N / (2.0 * np.pi)).astype(np.int64)
    return np.mod(steps, N)


def _spanning_tree(conn: FaceConnection) -> tuple[np.ndarray, np.ndarray]:
    """BFS tree of the dual graph: (parent face or -1, dual-edge index or -1) per face."""
    m = conn.n_faces
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    key = np.minimum(f, g) * m + np.maximum(f, g)
    _, first = np.unique(key, return_index=True)       # one dual edge per face pair
    a, b = f[first], g[first]
    # a virtual root m joined to the lowest face of every component
    adj = sp.coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(m, m)).tocsr()
    ncomp, label = connected_components(adj, directed=False)
    roots = np.full(ncomp, m, dtype=np.int64)
    np.minimum.at(roots, label, np.arange(m))
    rows = np.concatenate([a, b, np.full(ncomp, m), roots])
    cols = np.concatenate([b, a, roots, np.full(ncomp, m)])
    eid = np.concatenate([first, first, np.full(2 * ncomp, -1)]) + 2     # > 0 for storage
    G = sp.csr_matrix((eid, (rows, cols)), shape=(m + 1, m + 1))
    _, pred = breadth_first_order(G, m, directed=False, return_predecessors=True)
    parent = pred[:m].astype(np.int64)
    edge = np.asarray(G[parent, np.arange(m)]).ravel().astype(np.int64) - 2
    parent[parent == m] = -1
    return parent, edge


def _comb(conn: FaceConnection, theta: np.ndarray, N: int):
    m = conn.n_faces
    parent, edge = _spanning_tree(conn)
    step = np.zeros(m + 1, dtype=np.int64)          # slot m: the virtual root
    inner = np.flatnonzero(parent >= 0)
    e = edge[inner]
    match = _matching(conn, theta, N)[e]
    child_is_g = conn.faces[e, 1] == inner
    # turning the child by `match` aligns g with f; from g's side the sign flips
    step[inner] = np.where(child_is_g, match, -match)
    anc = np.where(parent >= 0, parent, m)
    anc = np.append(anc, m)
    acc = step.copy()
    while np.any(anc[:m] != m):
        acc = np.mod(acc + acc[anc], N)
        anc = anc[anc]
    return np.mod(acc[:m], N), parent


def _mesh_and_connection(V, F, connection):
    if connection is None:
        V, F = _checked_arrays(V, F)
        return V, F, _connection(V, F)
    F = np.asarray(F, dtype=np.int64)
    if not isinstance(connection, FaceConnection) or connection.n_faces != F.shape[0]:
        raise InputError("connection must be the FaceConnection of this mesh "
                         "(geotex.fields.frames.face_connection(V, F))")
    return np.asarray(V, dtype=np.float64), F, connection


def comb_direction_field(V, F, field, *, symmetry: int | None = None,
                         connection: FaceConnection | None = None) -> CombedField:
    """Comb an N-direction field along a spanning tree of the dual graph.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    field : DirectionField or array_like, (m, 3)
        The field, or one representative vector per face.
    symmetry : int, optional
        ``N`` for array input (default 1); must match for a DirectionField.
    connection : FaceConnection, optional
        :func:`geotex.fields.frames.face_connection` of this mesh, when the
        caller has it already (skips recomputing and re-checking the mesh).

    Returns
    -------
    CombedField

    Raises
    ------
    InputError
        On malformed, degenerate or inconsistently oriented meshes, or a field
        of the wrong shape.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> V, F = grid_plane(3, 3)
    >>> vec = np.tile([1.0, 0.0, 0.0], (len(F), 1))
    >>> vec[::2] = [0.0, 1.0, 0.0]                    # same cross, other arm
    >>> combed = comb_direction_field(V, F, vec, symmetry=4)
    >>> bool(np.allclose(combed.vectors, combed.vectors[0])), combed.cut_edges.size
    (True, 0)
    """
    V, F, conn = _mesh_and_connection(V, F, connection)
    if isinstance(field, DirectionField):
        _field_phases(conn, field, symmetry)          # validates shape and symmetry
        N = field.symmetry
        vectors = field.vectors
    else:
        N = _check_symmetry(1 if symmetry is None else symmetry)
        vectors = np.asarray(field)
        if np.iscomplexobj(vectors) or vectors.shape != (F.shape[0], 3):
            raise InputError(f"field must be a DirectionField or an ({F.shape[0]}, 3) array "
                             "of vectors, one per face")
        _field_phases(conn, vectors, N)               # validates finiteness
        vectors = vectors.astype(np.float64)
    theta = tangent_angles(conn.T1, conn.T2, vectors)
    rot, parent = _comb(conn, theta, N)
    theta_c = theta + 2.0 * np.pi * rot / N
    jumps = _matching(conn, theta_c, N)
    cut = np.flatnonzero(jumps)
    return CombedField(vectors=vectors_from_angles(conn.T1, conn.T2, theta_c),
                       rotations=rot, cut_edges=conn.edges[cut], jumps=jumps[cut],
                       tree_parent=parent)


def combed_vectors(V, F, field, *, symmetry: int | None = None) -> np.ndarray:
    """Return only the combed vectors of :func:`comb_direction_field`, ``(m, 3)``."""
    return comb_direction_field(V, F, field, symmetry=symmetry).vectors
