"""Per-face tangent frames and the discrete connection between adjacent faces.

Every tangent-direction field in geotex is stored per face, in the face's own
orthonormal frame ``(T1, T2, N)``: ``T1`` runs along the face's first edge
``V[F[f, 1]] - V[F[f, 0]]``, ``N`` is the unit normal of the counter-clockwise
corner order and ``T2 = N x T1``.  A tangent vector at face ``f`` is then an
angle ``theta`` (or the complex number ``exp(i theta)``) in that frame.

The *connection* says how to compare angles of two faces ``f`` and ``g`` that
share an edge: unfold ``g`` about the shared edge into the plane of ``f``
(Levi-Civita transport of the flattened hinge).  Both frames see the shared
edge vector ``d``; if ``d`` has angle ``a_f`` in ``f``'s frame and ``a_g`` in
``g``'s frame, a vector at angle ``theta`` in ``f`` is carried to angle
``theta + (a_g - a_f)`` in ``g``.  Around an interior vertex the transport
angles add up to the angle defect (the discrete Gaussian curvature) modulo
``2 pi``; this is what makes singularity indices sum to the Euler
characteristic.
"""

from __future__ import annotations

from dataclasses import dataclass

import igl
import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import degenerate_faces
from geotex.mesh.topology import edge_topology, non_manifold_vertices

__all__ = [
    "face_frames",
    "FaceConnection",
    "face_connection",
    "tangent_angles",
    "vectors_from_angles",
    "wrap_angle",
]


def _checked_arrays(V, F) -> tuple[np.ndarray, np.ndarray]:
    V, F = as_mesh_arrays(V, F, allow_empty=False)
    bad = degenerate_faces(V, F)
    if bad.size:
        raise InputError(
            f"F has {bad.size} degenerate face(s) (zero area or a repeated vertex), "
            f"first at face {int(bad[0])}: {F[bad[0]].tolist()}; remove them first, "
            "e.g. with geotex.repair.without_degenerate_faces")
    return V, F


def face_frames(V, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return an orthonormal, right-handed tangent frame for every face.

    Parameters
    ----------
    V : array_like, (n, 3) float64
        Vertex positions.
    F : array_like, (m, 3) int64
        Triangles (counter-clockwise seen from the side the normal points to).

    Returns
    -------
    T1 : numpy.ndarray, (m, 3) float64
        Unit vector along the first edge ``V[F[:, 1]] - V[F[:, 0]]``.
    T2 : numpy.ndarray, (m, 3) float64
        ``N x T1``, so that ``T1 x T2 = N``.
    N : numpy.ndarray, (m, 3) float64
        Unit face normal.

    Raises
    ------
    InputError
        If the arrays are malformed or empty, or a face is degenerate (the
        message gives the first bad face index).

    Examples
    --------
    >>> from geotex.mesh.primitives import icosphere
    >>> T1, T2, N = face_frames(*icosphere(1))
    >>> bool(np.allclose(np.cross(T1, T2), N))
    True
    """
    V, F = _checked_arrays(V, F)
    return _frames(V, F)


def _frames(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    T1, T2, N = igl.local_basis(V, F)
    return (np.ascontiguousarray(T1, dtype=np.float64),
            np.ascontiguousarray(T2, dtype=np.float64),
            np.ascontiguousarray(N, dtype=np.float64))


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Reduce angles to ``(-pi, pi]``, elementwise (returns a new array)."""
    a = np.asarray(a, dtype=np.float64)
    r = np.mod(a + np.pi, 2.0 * np.pi) - np.pi      # [-pi, pi)
    return np.where(r == -np.pi, np.pi, r)


def tangent_angles(T1: np.ndarray, T2: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Return the angle of each vector in its face frame, ``(m,)`` in ``(-pi, pi]``.

    The normal component of ``vectors`` is ignored.
    """
    return np.arctan2(np.einsum("ij,ij->i", vectors, T2), np.einsum("ij,ij->i", vectors, T1))


def vectors_from_angles(T1: np.ndarray, T2: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Return the unit tangent vectors ``cos(a) T1 + sin(a) T2``, ``(m, 3)``."""
    angles = np.asarray(angles, dtype=np.float64)
    return np.cos(angles)[:, None] * T1 + np.sin(angles)[:, None] * T2


@dataclass(frozen=True)
class FaceConnection:
    """Face frames, dual edges and the transport angle across every dual edge.

    Attributes
    ----------
    T1, T2, N : numpy.ndarray, (m, 3) float64
        The face frames (see :func:`face_frames`).
    edges : numpy.ndarray, (k,) int64
        Unique-edge index (``geotex.mesh.topology`` order) of every interior
        edge, ascending.  Interior means: exactly two faces, traversed once in
        each direction.  Boundary and non-manifold edges are not coupled.
    faces : numpy.ndarray, (k, 2) int64
        ``(f, g)``: ``f`` holds the half-edge ``lo -> hi`` of the unique edge
        ``(lo, hi)``, ``g`` the half-edge ``hi -> lo``.  Crossing from ``f`` to
        ``g`` turns counter-clockwise about ``hi`` (and clockwise about ``lo``).
    vertices : numpy.ndarray, (k, 2) int64
        ``(lo, hi)`` of every interior edge.
    angle : numpy.ndarray, (k,) float64
        Transport angle ``rho``: a vector at angle ``theta`` in ``f``'s frame is
        carried to ``theta + rho`` in ``g``'s frame.
    weight : numpy.ndarray, (k,) float64
        Dimensionless Dirichlet weight: edge length over ``dual_length``.
    dual_length : numpy.ndarray, (k,) float64
        Length of the dual path ``centroid(f) -> edge midpoint -> centroid(g)``.
    areas : numpy.ndarray, (m,) float64
        Face areas.
    interior_vertex : numpy.ndarray, (n,) bool
        Vertices all of whose edges are interior and whose faces form one fan
        (every other vertex is on a boundary or a non-manifold edge, is a
        non-manifold "bow tie" vertex, or is unreferenced).
    """

    T1: np.ndarray
    T2: np.ndarray
    N: np.ndarray
    edges: np.ndarray
    faces: np.ndarray
    vertices: np.ndarray
    angle: np.ndarray
    weight: np.ndarray
    dual_length: np.ndarray
    areas: np.ndarray
    interior_vertex: np.ndarray

    @property
    def n_faces(self) -> int:
        """Number of faces ``m``."""
        return int(self.T1.shape[0])


def face_connection(V, F) -> FaceConnection:
    """Compute face frames and the discrete Levi-Civita connection between faces.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64

    Returns
    -------
    FaceConnection

    Raises
    ------
    InputError
        If the arrays are malformed, a face is degenerate, or two faces that
        share an edge are oriented inconsistently (a field on such a mesh has
        no well-defined sense of rotation).

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> conn = face_connection(*grid_plane(2, 2))
    >>> f, g = conn.faces.T                 # flat: T1 of f is carried onto itself
    >>> moved = vectors_from_angles(conn.T1[g], conn.T2[g], conn.angle)
    >>> bool(np.allclose(moved, conn.T1[f]))
    True
    """
    V, F = _checked_arrays(V, F)
    return _connection(V, F)


def _connection(V: np.ndarray, F: np.ndarray) -> FaceConnection:
    n = V.shape[0]
    T1, T2, N = _frames(V, F)
    topo = edge_topology(F, n)
    bad = topo.inconsistent
    if bad.size:
        lo, hi = topo.edges[bad[0]]
        raise InputError(
            f"F is not consistently oriented: edge ({lo}, {hi}) is traversed twice in "
            "the same direction; orient the faces first, e.g. with "
            "geotex.repair.consistently_oriented")
    interior = topo.face_count == 2
    edges = np.flatnonzero(interior)
    # the two faces of each interior edge, split by half-edge direction
    he_from = F.ravel()
    he_to = np.roll(F, -1, axis=1).ravel()
    he_edge = topo.half_to_edge
    on_interior = interior[he_edge]
    forward = he_from < he_to
    slot = np.full(topo.edges.shape[0], -1, dtype=np.int64)
    f_of = slot.copy()
    g_of = slot.copy()
    h = np.flatnonzero(on_interior & forward)
    f_of[he_edge[h]] = h // 3
    h = np.flatnonzero(on_interior & ~forward)
    g_of[he_edge[h]] = h // 3
    faces = np.stack([f_of[edges], g_of[edges]], axis=1)
    verts = topo.edges[edges]
    d = V[verts[:, 1]] - V[verts[:, 0]]
    f, g = faces[:, 0], faces[:, 1]
    a_f = tangent_angles(T1[f], T2[f], d)
    a_g = tangent_angles(T1[g], T2[g], d)
    angle = a_g - a_f
    # dual path length: centroid -> edge midpoint -> centroid
    C = V[F].mean(axis=1)
    mid = 0.5 * (V[verts[:, 0]] + V[verts[:, 1]])
    dual = np.linalg.norm(C[f] - mid, axis=1) + np.linalg.norm(C[g] - mid, axis=1)
    weight = np.linalg.norm(d, axis=1) / dual
    areas = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]),
                                 axis=1)
    # interior vertices: referenced, and no incident edge is boundary/non-manifold
    interior_vertex = np.zeros(n, dtype=bool)
    interior_vertex[F.ravel()] = True
    interior_vertex[topo.edges[~interior].ravel()] = False
    interior_vertex[non_manifold_vertices(F, n, topo)] = False         # bow ties
    return FaceConnection(T1=T1, T2=T2, N=N, edges=edges, faces=faces, vertices=verts,
                          angle=angle, weight=weight, dual_length=dual, areas=areas,
                          interior_vertex=interior_vertex)
