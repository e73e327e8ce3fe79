"""The local union of a base with elements that cross only the base (no boolean)."""

from __future__ import annotations

import manifold3d
import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.errors import InputError
from geotex.mapping.crossing import crossing_union
from geotex.mesh.needles import needle_faces
from geotex.mesh.primitives import box, closed_cylinder, icosphere
from geotex.mesh.solid import manifold_of
from geotex.mesh.topology import concatenated, edge_topology


def _stud(centre, axis, *, bottom, height=0.8, radius=0.3, n_height=2):
    """A 12-sided closed cylinder from ``bottom`` along ``axis`` through ``centre``."""
    V, F = closed_cylinder(radius, height, n_theta=12, n_height=n_height, n_cap_rings=1)
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    # a rotation taking z to axis (and turning the stud a little about it)
    helper = np.array([0.3, 0.7, 0.1])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    R = np.stack([u, v, axis], axis=1)
    return (V + (0, 0, bottom)) @ R.T + np.asarray(centre, dtype=np.float64), F


def _reference(V, F, parts):
    return manifold3d.Manifold.batch_boolean(
        [manifold_of(V, F)] + [manifold_of(X, G) for X, G in parts], manifold3d.OpType.Add)


def _assert_solid_equal(V2, F2, ref):
    topo = edge_topology(F2, len(V2))
    assert np.all(topo.face_count == 2) and topo.inconsistent.size == 0
    got = manifold_of(V2, F2)
    assert got.status() == manifold3d.Error.NoError
    assert got.volume() == pytest.approx(ref.volume(), rel=1e-9)
    assert got.genus() == ref.genus()
    rep = check_mesh(V2, F2)
    assert rep.printable, rep


def _elements(parts):
    X, G = concatenated(parts)
    element = np.repeat(np.arange(len(parts)), [len(g) for _, g in parts])
    return X, G, element


def test_studs_on_a_plane_are_cut_classified_and_stitched():
    V, F = box((0, 0, 0), (4, 4, 1), divisions=8)
    # walls cross the top (z = 1) between the rings at 0.63 and 1.03; one stud
    # lies across several base faces, one sits on a base edge's line
    centres = np.array([(1.2345, 0.987), (2.5, 2.5), (3.1, 1.05)])
    parts = [_stud((x, y, 0.0), (0, 0, 1), bottom=0.63) for x, y in centres]
    X, G, element = _elements(parts)
    V2, F2, left = crossing_union(V, F, X, G, element=element)
    assert left.size == 0
    _assert_solid_equal(V2, F2, _reference(V, F, parts))
    # the pieces inside were dropped: no vertex of the result below the top
    # within a stud's footprint (its lower ring at z = 0.63 is gone)
    near = np.linalg.norm(V2[:, None, :2] - centres[None], axis=2).min(axis=1) < 0.31
    assert not np.any(near & (V2[:, 2] > 0.5) & (V2[:, 2] < 1.0 - 1e-9))
    assert np.count_nonzero(near & (np.abs(V2[:, 2] - 1.0) < 1e-9)) >= 3 * 12
    # same inputs, same bytes
    V3, F3, _ = crossing_union(V, F, X, G, element=element)
    assert V3.tobytes() == V2.tobytes() and F3.tobytes() == F2.tobytes()


def test_studs_on_a_sphere():
    V, F = icosphere(3)
    dirs = np.array([[0.3, 0.2, 1.0], [1.0, -0.4, 0.1], [-0.6, 0.9, -0.5], [0.1, -1.0, -0.7]])
    parts = [_stud(np.zeros(3), d, bottom=0.83, height=0.5, radius=0.12) for d in dirs]
    X, G, element = _elements(parts)
    V2, F2, left = crossing_union(V, F, X, G, element=element)
    assert left.size == 0
    _assert_solid_equal(V2, F2, _reference(V, F, parts))


def test_a_stud_inside_one_base_face_is_bridged_to_its_edges():
    # an undivided box: the stud's whole footprint lies inside one top triangle
    V, F = box((0, 0, 0), (4, 4, 1))
    parts = [_stud((2.9, 1.1, 0.0), (0, 0, 1), bottom=0.63, radius=0.2)]
    X, G, element = _elements(parts)
    V2, F2, left = crossing_union(V, F, X, G, element=element)
    assert left.size == 0
    _assert_solid_equal(V2, F2, _reference(V, F, parts))


def test_an_element_with_a_corner_on_the_base_is_left_out():
    V, F = box((0, 0, 0), (4, 4, 1), divisions=8)
    # rings at 0.6, 1.0 and 1.4: the middle ring lies on the top face
    flush = _stud((1.2345, 0.987, 0.0), (0, 0, 1), bottom=0.6)
    assert np.any(flush[0][:, 2] == 1.0)
    parts = [flush, _stud((2.7, 2.6, 0.0), (0, 0, 1), bottom=0.63)]
    X, G, element = _elements(parts)
    V2, F2, left = crossing_union(V, F, X, G, element=element)
    assert left.tolist() == [0]
    _assert_solid_equal(V2, F2, _reference(V, F, parts[1:]))


def test_elements_that_cross_nothing():
    V, F = box((0, 0, 0), (4, 4, 1), divisions=8)
    parts = [_stud((1.2345, 0.987, 0.0), (0, 0, 1), bottom=0.63),
             _stud((2.5, 2.5, 0.0), (0, 0, 1), bottom=1.3),        # floats above
             _stud((3.1, 1.1, 0.0), (0, 0, 1), bottom=0.05, height=0.5)]   # inside
    X, G, element = _elements(parts)
    V2, F2, left = crossing_union(V, F, X, G, element=element)
    assert left.size == 0
    # the floating one is kept whole (a loose piece), the inside one dropped
    ref = _reference(V, F, parts)
    assert manifold_of(V2, F2).volume() == pytest.approx(ref.volume(), rel=1e-9)
    topo = edge_topology(F2, len(V2))
    assert np.all(topo.face_count == 2) and topo.inconsistent.size == 0
    floating = (np.linalg.norm(V2[:, :2] - (2.5, 2.5), axis=1) < 0.31) & (V2[:, 2] > 1.29)
    assert np.count_nonzero(floating) == len(parts[1][0])          # kept whole


def test_bad_element_labels():
    V, F = box((0, 0, 0), (1, 1, 1))
    X, G = _stud((0.5, 0.5, 0.0), (0, 0, 1), bottom=0.63)
    with pytest.raises(InputError):
        crossing_union(V, F, X, G, element=np.zeros(len(G) - 1, dtype=np.int64))
    with pytest.raises(InputError):
        crossing_union(V, F, X, G, element=np.full(len(G), -1))


def test_a_chain_of_nearly_collinear_cut_points_leaves_no_flat_piece():
    # the tilted stud's walls cross the finely divided top along lines, each
    # through many base edges: ear clipping alone fanned two pieces over such
    # a chain (heights 8e-7 and 1e-6 of the diagonal, which the float32
    # rounding can fold); flipped within their face they are gone
    V, F = box((0, 0, 0), (4, 4, 1), divisions=32)
    parts = [_stud((3.4653977281237016, 2.6052852063343552, 0.0),
                   (0.018860747641344634, 0.010390772698803199, 1.0),
                   bottom=0.811301114448697, radius=0.11946453843763682, n_height=3)]
    X, G, element = _elements(parts)
    V2, F2, left = crossing_union(V, F, X, G, element=element, flat_test=False)
    assert left.size == 0
    _assert_solid_equal(V2, F2, _reference(V, F, parts))
    diag = np.linalg.norm(np.ptp(np.vstack([V, X]), axis=0))
    assert needle_faces(V2, F2, tolerance=1e-5 * diag).size == 0
