"""Needle triangles removed by local collapses and flips (geotex.mesh.needles)."""

import numpy as np

from geotex.check.report import check_mesh
from geotex.mesh.geometry import signed_volume
from geotex.mesh.needles import needle_faces, needle_free
from geotex.mesh.primitives import icosphere
from geotex.mesh.topology import edge_topology

TOL = 1e-5


def _edge_with_faces(F):
    """One interior edge (a, b) with its faces (a, b, c) and (b, a, d)."""
    f = F[0]
    a, b, c = (int(x) for x in f)
    g = next(i for i, t in enumerate(F.tolist())
             if i != 0 and a in t and b in t)
    d = int(np.setdiff1d(F[g], [a, b])[0])
    return a, b, c, d, g


def _dart_sphere():
    """Edge (a, b) split right next to ``a``: two darts with a 1e-7 edge."""
    V, F = icosphere(2)
    a, b, c, d, g = _edge_with_faces(F)
    p = V.shape[0]
    V = np.vstack([V, V[a] + 1e-7 * (V[b] - V[a])])
    F = np.vstack([np.delete(F, [0, g], axis=0),
                   [[a, p, c], [p, b, c], [b, p, d], [p, a, d]]])
    return V, F


def _cap_sphere():
    """Face (b, a, d) replaced by a cap (b, a, p) and two faces on ``p``, which
    lies 1e-7 of an edge length off the midpoint of (a, b)."""
    V, F = icosphere(2)
    a, b, c, d, g = _edge_with_faces(F)
    mid = 0.5 * (V[a] + V[b])
    p = V.shape[0]
    V = np.vstack([V, mid + 1e-7 * (V[d] - mid)])
    F = np.vstack([np.delete(F, [g], axis=0), [[b, a, p], [b, p, d], [p, a, d]]])
    return V, F


def test_dart_is_collapsed_and_the_solid_stays_closed():
    V, F = _dart_sphere()
    assert len(needle_faces(V, F, tolerance=TOL)) == 2
    assert check_mesh(V, F).printable
    V2, F2, ops = needle_free(V, F, tolerance=TOL)
    assert ops == 1
    assert len(needle_faces(V2, F2, tolerance=TOL)) == 0
    assert F2.shape[0] == F.shape[0] - 2
    assert check_mesh(V2, F2).printable
    assert abs(signed_volume(V2, F2) - signed_volume(V, F)) < 1e-9


def test_cap_is_flipped_and_the_solid_stays_closed():
    V, F = _cap_sphere()
    assert len(needle_faces(V, F, tolerance=TOL)) == 1
    V2, F2, ops = needle_free(V, F, tolerance=TOL)
    assert ops >= 1
    assert len(needle_faces(V2, F2, tolerance=TOL)) == 0
    assert F2.shape[0] == F.shape[0]
    rep = check_mesh(V2, F2)
    assert rep.printable
    et = edge_topology(F2, V2.shape[0])
    assert et.edges.shape[0] == 3 * F2.shape[0] // 2


def test_clean_mesh_is_returned_unchanged():
    V, F = icosphere(2)
    V2, F2, ops = needle_free(V, F, tolerance=TOL)
    assert ops == 0
    assert np.array_equal(V2, V) and np.array_equal(F2, F)
    assert V2 is not V


def test_collapse_refused_when_the_link_condition_fails():
    """A tetrahedron: collapsing any edge would leave two faces on three vertices."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1e-7]], dtype=float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    V2, F2, ops = needle_free(V, F, tolerance=1e-3)
    assert F2.shape == F.shape
    assert np.array_equal(np.sort(F2, axis=None), np.sort(F, axis=None))



def test_dart_length_collapses_a_needle_on_an_edge_longer_than_the_tolerance():
    # the dart sphere's short edge, with a tolerance just under it: its two
    # faces are needles (heights ~0.9 of the edge) but no darts by default
    V, F = _dart_sphere()
    short = float(np.sort(np.linalg.norm(V - V[-1], axis=1))[1])
    tol = 0.99 * short
    assert len(needle_faces(V, F, tolerance=tol)) == 2
    V1, F1, _ = needle_free(V, F, tolerance=tol)
    assert len(needle_faces(V1, F1, tolerance=tol)) == 2
    V2, F2, ops = needle_free(V, F, tolerance=tol, dart_length=2 * short)
    assert ops == 1
    assert len(needle_faces(V2, F2, tolerance=tol)) == 0
    assert F2.shape[0] == F.shape[0] - 2
    assert check_mesh(V2, F2).printable
    # no rounds, nothing done
    V3, F3, ops = needle_free(V, F, tolerance=tol, dart_length=2 * short, rounds=0)
    assert ops == 0 and np.array_equal(F3, F)
