"""PolyCube parameterization: exact cases, validity invariants, errors."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.errors import GeotexError, InputError
from geotex.mesh.primitives import box, icosphere, torus
from geotex.param.polycube import polycube
from geotex.param.polycube_quads import chart_axes, face_coords_2d


def _assert_valid(pc):
    V, F, P = pc.V, pc.F, pc.P
    a = pc.labels // 2
    rows = np.arange(F.shape[0])
    # every triangle flat in its chart plane, which is on the grid
    plane = pc.planes[pc.chart]
    assert np.all(P[F[:, 0], a] == plane) and np.all(P[F[:, 1], a] == plane)
    assert np.all(P[F[:, 2], a] == plane)
    assert np.all(pc.planes == np.round(pc.planes))
    # positive orientation w.r.t. the outward label normal (no flips, no slivers)
    T = face_coords_2d(P, F, pc.labels)
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    assert np.all(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 1e-9)
    # quads: corners on the integer grid, inside their chart plane, right-handed frame
    c = pc.quad_corners
    qa, qa1, qa2 = chart_axes(pc.chart_label[pc.quad_chart])
    q = np.arange(pc.n_quads)
    assert np.all(c[q, 0, qa] == pc.planes[pc.quad_chart])
    e1 = (c[:, 1] - c[:, 0]).astype(float)
    e2 = (c[:, 3] - c[:, 0]).astype(float)
    nrm = np.cross(e1, e2)
    sign = np.where(pc.chart_label[pc.quad_chart] % 2 == 0, 1, -1)
    assert np.all(nrm[q, qa] == sign) and np.all(np.abs(nrm).sum(axis=1) == 1)
    # quad edge ids: each global edge in exactly two quads, traversed oppositely
    counts = np.bincount(pc.quad_edge.ravel(), minlength=pc.edge_axis.size)
    assert np.all(counts == 2)
    fw = pc.quad_edge_forward
    qa_, qb_ = pc.edge_quads[:, 0], pc.edge_quads[:, 1]
    sa, sb = pc.edge_sides[:, 0], pc.edge_sides[:, 1]
    assert np.all(fw[qa_, sa] != fw[qb_, sb])
    assert np.all(pc.quad_edge[qa_, sa] == np.arange(pc.edge_axis.size))
    # every quad lies in its chart: its centre is inside a chart triangle
    from geotex.param.polycube_quads import QuadLocator

    loc = QuadLocator.build(P, F, pc.labels, pc.chart, pc.quad_chart, pc.quad_ij)
    f, b = loc.locate(q, np.full((q.size, 2), 0.5))
    assert np.all(pc.chart[f] == pc.quad_chart)
    # total polycube area = quad count * tile^2 (the quads tile the surface exactly)
    area = 0.5 * np.abs(np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])).sum(axis=1)
    assert area.sum() == pytest.approx(pc.n_quads, rel=1e-9)
    del rows


def test_box_is_exact():
    V, F = box((0, 0, 0), (2, 1, 1), divisions=4)
    pc = polycube(V, F, tile_size=0.25)
    normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    expected = np.argmax(normals @ np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0],
                                             [0, 0, 1], [0, 0, -1]]).T, axis=1)
    assert np.array_equal(pc.labels, expected)
    assert pc.chart_label.size == 6
    assert np.allclose(pc.positions, V, atol=1e-12)
    assert pc.n_quads == (2 * (2 * 1 + 2 * 1 + 1 * 1)) / 0.25 ** 2
    assert pc.distortion["area_mean"] < 1e-12 and pc.distortion["angle_mean"] < 1e-12
    _assert_valid(pc)


def test_icosphere_valid():
    V, F = icosphere(3)
    pc = polycube(V, F, tile_size=0.25)
    assert pc.chart_label.size == 6
    assert sorted(pc.chart_label.tolist()) == [0, 1, 2, 3, 4, 5]
    _assert_valid(pc)
    assert pc.distortion["angle_mean"] < 0.2


def test_torus_genus_one():
    V, F = torus(n_major=64, n_minor=32)
    pc = polycube(V, F, tile_size=0.2)
    _assert_valid(pc)
    # genus 1 polycube: Euler characteristic of the quad surface is 0
    qv = np.unique(pc.quad_corners.reshape(-1, 3), axis=0).shape[0]
    assert qv - pc.edge_axis.size + pc.n_quads == 0
    # input vertices keep their indices and positions
    assert np.array_equal(pc.V[:V.shape[0]], V)


@pytest.mark.parametrize("tile", [0.175, 0.225, 0.35])
def test_torus_reflex_corners_need_cuts(tile):
    # the hole's corners are reflex for the top and bottom charts: a plain harmonic
    # map folds there at these tile sizes; the reflex-corner cuts remove the folds
    V, F = torus(n_major=64, n_minor=32)
    pc = polycube(V, F, tile_size=tile)
    _assert_valid(pc)


def test_scale_invariant_layout():
    V, F = icosphere(2)
    a = polycube(V, F, tile_size=0.5)
    b = polycube(V * 1e3, F, tile_size=500.0)
    assert np.array_equal(a.labels, b.labels) and np.array_equal(a.planes, b.planes)
    assert a.n_quads == b.n_quads


def test_open_mesh_error():
    V, F = icosphere(2)
    with pytest.raises(InputError, match="open.*geotex repair"):
        polycube(V, F[1:], tile_size=0.5)


def test_non_manifold_error():
    V, F = box(divisions=1)
    V2 = np.vstack([V, V + [1.0, 1.0, 1.0]])
    F2 = np.vstack([F, F + V.shape[0]])
    # glue the two cubes on a shared corner vertex and edge: not one component anyway
    with pytest.raises(InputError, match="geotex repair"):
        polycube(V2, F2, tile_size=0.25)
    F3 = np.vstack([F, F[:2]])  # duplicated faces -> edges with 3+ faces
    with pytest.raises(InputError, match="non-manifold"):
        polycube(V, F3, tile_size=0.25)


def test_self_intersecting_error():
    V, F = icosphere(2)
    V = V.copy()
    V[0] = -V[0] * 1.5  # pull one vertex through the sphere
    with pytest.raises(InputError, match="self-intersecting"):
        polycube(V, F, tile_size=0.5)


def test_tile_size_errors():
    V, F = icosphere(2)
    with pytest.raises(InputError, match="too large"):
        polycube(V, F, tile_size=5.0)
    with pytest.raises(InputError, match="positive"):
        polycube(V, F, tile_size=-1.0)
    with pytest.raises(GeotexError, match="tile size too large"):
        # a slab thinner than a fifth of a tile would need planes moved > max_shift
        Vs, Fs = box((0, 0, 0), (4, 4, 0.05), divisions=2)
        polycube(Vs, Fs, tile_size=1.0, max_shift=0.5, min_chart_area=0.01)
