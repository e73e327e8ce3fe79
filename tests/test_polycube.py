"""PolyCube parameterization: exact cases, validity invariants, any genus, errors."""

from __future__ import annotations

import re

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.errors import GeotexError, InputError
from geotex.mesh.primitives import box, icosphere, torus
from geotex.param.polycube import bare_fraction, polycube
from geotex.param.polycube_fit import SurfaceProjector
from geotex.param.polycube_quads import chart_axes
from geotex.param.voxels import MANIFOLD_BLOCKS, manifold_solid, non_manifold_corners


def _double_torus():
    import manifold3d

    from geotex.mesh.solid import arrays_of_manifold, manifold_of

    V, F = torus(1.0, 0.35, n_major=48, n_minor=24)
    a = manifold_of(V, F)
    b = manifold_of(V + [1.6, 0.0, 0.0], F)
    return arrays_of_manifold(manifold3d.Manifold.batch_boolean([a, b], manifold3d.OpType.Add))


def _assert_valid(pc, V, F):
    r = pc.res
    c = pc.layout.quad_corners
    a, a1, a2 = chart_axes(pc.layout.quad_label)
    q = np.arange(pc.layout.n_quads)
    # quads: unit squares on the integer grid, right-handed about their outward normal
    e1 = c[:, 1] - c[:, 0]
    e2 = c[:, 3] - c[:, 0]
    assert np.array_equal(e1, np.eye(3, dtype=np.int64)[a1])
    assert np.array_equal(e2, np.eye(3, dtype=np.int64)[a2])
    assert np.array_equal(c[:, 2], c[:, 0] + e1 + e2)
    sign = np.where(pc.layout.quad_label % 2 == 0, 1, -1)
    assert np.all(np.cross(e1, e2)[q, a] == sign)
    # every global edge in exactly two quads, traversed in opposite directions
    assert np.all(np.bincount(pc.layout.quad_edge.ravel(), minlength=pc.layout.edge_axis.size) == 2)
    fw = pc.layout.quad_edge_forward
    qa, qb = pc.layout.edge_quads[:, 0], pc.layout.edge_quads[:, 1]
    sa, sb = pc.layout.edge_sides[:, 0], pc.layout.edge_sides[:, 1]
    assert np.all(fw[qa, sa] != fw[qb, sb])
    assert np.array_equal(pc.layout.quad_edge[qa, sa], np.arange(pc.layout.edge_axis.size))
    # the sub-grid: grid vertex (i, j) of quad q sits at c0 + (i e1 + j e2) / res exactly
    i, j = np.meshgrid(np.arange(r + 1), np.arange(r + 1), indexing="ij")
    want = (c[:, 0, None, None, :] + (i[None, :, :, None] * e1[:, None, None, :]
                                      + j[None, :, :, None] * e2[:, None, None, :]) / r)
    assert np.array_equal(pc.P[pc.layout.quad_grid], want)
    # ... and forms one closed, consistently oriented surface of area = number of quads
    rep = check_mesh(pc.positions, pc.F, self_intersections=False)
    assert rep.boundary_edges == 0 and rep.non_manifold_edges == 0
    assert rep.orientation_consistent and rep.outward
    cross = np.cross(pc.P[pc.F[:, 1]] - pc.P[pc.F[:, 0]], pc.P[pc.F[:, 2]] - pc.P[pc.F[:, 0]])
    assert 0.5 * np.linalg.norm(cross, axis=1).sum() == pytest.approx(pc.layout.n_quads, rel=1e-12)
    # same topology as the input
    assert rep.euler_characteristic == check_mesh(V, F).euler_characteristic
    # the fitted surface lies on the base and does not fold
    C, _ = SurfaceProjector(V, F).closest(pc.Y)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    assert np.abs(C - pc.Y).max() < 1e-9 * diag
    assert not pc.quad_folded.any() and pc.diagnostics.distortion["folded_faces"] == 0
    # tile points locate in their own quad's sub-grid, at the right polycube point
    rng = np.random.default_rng(0)
    qq = rng.integers(0, pc.layout.n_quads, 3000)
    uv = rng.random((3000, 2))
    uv[:8] = [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5]]
    f, b = pc.locate(qq, uv)
    assert np.all(pc.layout.face_quad[f] == qq)
    assert np.all(b >= -1e-15) and np.allclose(b.sum(axis=1), 1.0)
    p = np.einsum("ki,kij->kj", b, pc.P[pc.F[f]])
    cq = c[qq].astype(float)
    expected = cq[:, 0] + uv[:, :1] * (cq[:, 1] - cq[:, 0]) + uv[:, 1:] * (cq[:, 3] - cq[:, 0])
    assert np.abs(p - expected).max() < 1e-12


def test_manifold_block_table():
    assert MANIFOLD_BLOCKS[0] and MANIFOLD_BLOCKS[255]
    assert MANIFOLD_BLOCKS[0b00000001] and MANIFOLD_BLOCKS[0b00000011]   # corner, edge pair
    assert not MANIFOLD_BLOCKS[0b00001001]           # two cells sharing only an edge
    assert not MANIFOLD_BLOCKS[0b10000001]           # two cells sharing only a corner
    assert not MANIFOLD_BLOCKS[0b11110110]           # the complement of an edge contact
    assert int(MANIFOLD_BLOCKS.sum()) == 256 - int((~MANIFOLD_BLOCKS).sum())


@pytest.mark.parametrize("strategy", ["flip", "fill"])
def test_manifold_repair_removes_edge_and_corner_contacts(strategy):
    S = np.zeros((6, 6, 6), dtype=bool)
    S[1, 1, 1] = S[2, 2, 1] = True        # edge contact
    S[1, 1, 3] = S[2, 2, 4] = True        # corner contact
    assert len(non_manifold_corners(S)) == 3     # both ends of the edge, and the corner
    w = np.where(S, 0.9, 0.1)
    out, changed = manifold_solid(S, w, strategy=strategy)
    assert len(non_manifold_corners(out)) == 0 and changed >= 1
    if strategy == "fill":
        assert np.all(out[S])


def test_box_is_exact():
    V, F = box((0, 0, 0), (2, 1, 1), divisions=4)
    pc = polycube(V, F, tile_size=0.25)
    assert pc.layout.n_quads == 2 * (2 * 1 + 2 * 1 + 1 * 1) / 0.25 ** 2
    assert np.abs(pc.Y - pc.positions).max() < 1e-12
    d = pc.diagnostics.distortion
    assert d["area_mean"] < 1e-9 and d["angle_mean"] < 1e-9
    _assert_valid(pc, V, F)


def test_icosphere_valid():
    V, F = icosphere(3)
    pc = polycube(V, F, tile_size=0.25)
    assert sorted(set(pc.layout.quad_label.tolist())) == [0, 1, 2, 3, 4, 5]
    _assert_valid(pc, V, F)
    d = pc.diagnostics.distortion
    assert d["angle_mean"] < 0.2 and d["area_mean"] < 0.4
    assert pc.diagnostics.coverage["within_quarter_tile"] > 0.999


def test_torus_genus_one():
    V, F = torus(n_major=64, n_minor=32)
    pc = polycube(V, F, tile_size=0.2)
    _assert_valid(pc, V, F)
    qv = np.unique(pc.layout.quad_corners.reshape(-1, 3), axis=0).shape[0]
    assert qv - pc.layout.edge_axis.size + pc.layout.n_quads == 0


def test_double_torus_genus_two():
    V, F = _double_torus()
    assert check_mesh(V, F).genus == 2
    pc = polycube(V, F, tile_size=0.15)
    _assert_valid(pc, V, F)


def test_rigid_translation_and_scaling():
    V, F = icosphere(2)
    a = polycube(V, F, tile_size=0.5)
    b = polycube(V * 1e3 + [7.0, -3.0, 2.0], F, tile_size=500.0)
    c = polycube(V * 0.25, F, tile_size=0.125)
    for other in (b, c):
        assert np.array_equal(a.layout.quad_corners, other.layout.quad_corners)
        assert np.array_equal(a.layout.quad_label, other.layout.quad_label)
    # a power-of-two scale changes no bit of the computation
    assert np.array_equal(c.Y * 4, a.Y)
    # otherwise the closest-point map from inside a faceted surface is discontinuous
    # across the bisector of two faces, so round-off moves a few points: by far less
    # than a fiftieth of a tile once the fit has relaxed (or converged)
    assert np.abs((b.Y - [7.0, -3.0, 2.0]) / 1e3 - a.Y).max() < 0.02 * 0.5


def test_deterministic():
    V, F = torus(n_major=40, n_minor=20)
    a = polycube(V, F, tile_size=0.25)
    b = polycube(V, F, tile_size=0.25)
    assert a.Y.tobytes() == b.Y.tobytes() and np.array_equal(a.F, b.F)


def test_open_mesh_error():
    V, F = icosphere(2)
    with pytest.raises(InputError, match="open.*geotex repair"):
        polycube(V, F[1:], tile_size=0.5)


def test_non_manifold_and_components_errors():
    V, F = box(divisions=1)
    V2 = np.vstack([V, V + [2.0, 2.0, 2.0]])
    F2 = np.vstack([F, F + V.shape[0]])
    with pytest.raises(InputError, match="2 connected components.*geotex repair"):
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
    with pytest.raises(InputError, match="too small"):
        polycube(V, F, tile_size=1e-4)
    with pytest.raises(InputError, match="positive"):
        polycube(V, F, tile_size=-1.0)
    with pytest.raises(InputError, match="tiles_per_cell"):
        polycube(V, F, tile_size=0.5, tiles_per_cell=0)


def test_tile_too_large_for_the_hole_says_why():
    V, F = torus(1.0, 0.45, n_major=48, n_minor=24)        # hole of radius 0.55
    with pytest.raises(GeotexError, match="genus 1 but its voxel polycube has genus 0.*"
                                          "narrowest gap 1\\.1.* near.*resolves it") as err:
        polycube(V, F, tile_size=1.2)
    # the size it names does resolve the hole
    works = float(re.search(r"tile size ([0-9.]+) resolves it", str(err.value)).group(1))
    assert works < 1.2
    assert polycube(V, F, tile_size=works).layout.n_quads > 0        # raises if it did not


def _tilted_plate(genus, **kw):
    """A plate with ``genus`` small holes, tilted so no grid axis lines up with them."""
    from scipy.spatial.transform import Rotation

    from geotex.mesh.primitives import plate_with_holes

    V, F = plate_with_holes(genus, **kw)
    return V @ Rotation.from_euler("zx", [30, 20], degrees=True).as_matrix().T, F


@pytest.mark.parametrize("genus", [0, 1, 3, 12])
def test_plate_with_holes_is_closed_with_its_genus(genus):
    from geotex.mesh.primitives import plate_with_holes

    V, F = plate_with_holes(genus, cell=0.15)
    r = check_mesh(V, F, self_intersections=True)
    assert r.boundary_edges == 0 and r.non_manifold_edges == 0 and r.components == 1
    assert r.outward is True and r.degenerate_faces == 0 and r.self_intersecting_pairs == 0
    assert r.euler_characteristic == 2 - 2 * genus


def test_sphere_with_rod_is_closed():
    from geotex.mesh.primitives import sphere_with_rod

    V, F = sphere_with_rod(cell=0.05)
    r = check_mesh(V, F)
    assert r.boundary_edges == 0 and r.euler_characteristic == 2 and r.outward is True
    assert V[:, 0].max() > 1.9                                 # the rod sticks out


def test_automatic_tile_size_resolves_the_genus():
    V, F = _tilted_plate(3, hole=0.2, bar=0.6, thickness=0.4, cell=0.06)
    extent = float(np.ptp(V, axis=0).max())
    with pytest.raises(GeotexError, match="genus 3.*resolves it"):
        polycube(V, F, tile_size=extent / 12)                  # the old default fails
    pc = polycube(V, F)
    search = pc.diagnostics.tile_search
    assert search["automatic"] and search["chosen"] == pc.tile_size < extent / 12
    assert search["attempts"][0]["tile_size"] == pytest.approx(extent / 12)
    assert search["attempts"][0]["result"].startswith("voxel polycube has genus")
    assert search["attempts"][-1]["result"] == "ok"
    assert not pc.quad_folded.any()
    assert pc.diagnostics.coverage["within_tile"] >= 0.99
    # the chosen size given explicitly builds the same polycube
    again = polycube(V, F, tile_size=pc.tile_size)
    assert np.array_equal(again.Y, pc.Y)


def test_coverage_within_one_tile_on_a_generated_shape():
    from geotex.mesh.primitives import plate_with_holes

    V, F = plate_with_holes(2, cell=0.1)
    pc = polycube(V, F)
    assert pc.diagnostics.coverage["within_tile"] >= 0.99
    assert pc.diagnostics.coverage["within_quarter_tile"] <= pc.diagnostics.coverage["within_tile"]
    assert not pc.quad_folded.any()


def test_bare_fraction_is_the_area_outside_beyond_the_depth():
    from geotex.param.polycube import bare_fraction

    V, F = icosphere(3)
    assert bare_fraction(V, F, V, F) == 0.0                        # on the surface
    assert bare_fraction(V, F, 2.0 * V, F) == 0.0                  # inside it
    assert bare_fraction(V, F, 0.5 * V, F) == pytest.approx(1.0)   # half a unit outside
    assert bare_fraction(V, F, 0.5 * V, F, depth=0.6) == 0.0       # ... within reach
    half = V.copy()
    half[V[:, 0] > 0.5] *= 0.5                                     # a cap outside
    share = bare_fraction(V, F, half, F, depth=0.1)
    assert 0.05 < share < 0.5


def test_rod_out_of_the_fitted_surface_is_reported_bare():
    from geotex.mesh.primitives import sphere_with_rod
    from geotex.param.polycube_size import MAX_BARE

    V, F = sphere_with_rod(cell=0.05)
    coarse = polycube(V, F, tile_size=0.2)          # the voxels lose part of the rod
    assert coarse.diagnostics.coverage["bare"] > MAX_BARE
    attempt = coarse.diagnostics.tile_search["attempts"][0]
    assert attempt["result"] != "ok"
    assert attempt["bare_area"] == coarse.diagnostics.coverage["bare"]
    fine = polycube(V, F, tile_size=0.12)
    assert fine.diagnostics.coverage["bare"] <= MAX_BARE
    assert fine.diagnostics.tile_search["attempts"][0]["result"] == "ok"


def test_spot_horns_within_a_tile_are_reached_by_the_fitted_surface(monkeypatch):
    """Spot's horns stay inside one tile of the plain fit at tile 0.12 but out of
    the texture's reach; the fit moved out to them covers them, bare no quad and
    keeps the first grid shift."""
    import geotex.param.polycube as module
    from geotex.data import sample_path
    from geotex.io import read_mesh
    from geotex.param.polycube_size import MAX_BARE

    m = read_mesh(sample_path("spot"))
    pc = polycube(m.vertices, m.faces, tile_size=0.12)
    cov = pc.diagnostics.coverage
    assert cov["within_tile"] >= 0.99 and cov["bare"] <= MAX_BARE
    assert bare_fraction(m.vertices, m.faces, pc.Y, pc.F, depth=0.125 * 0.12) < 1e-4
    assert pc.diagnostics.tile_search["attempts"][0]["result"] == "ok"
    assert pc.diagnostics.voxels["fitted"] == 1
    assert pc.diagnostics.distortion["reached"] > 0 and not pc.quad_folded.any()
    assert pc.diagnostics.distortion["folded_faces"] == 0

    monkeypatch.setattr(module, "reached_surface", lambda fit, *a, **k: fit)
    plain = polycube(m.vertices, m.faces, tile_size=0.12)
    cov = plain.diagnostics.coverage
    assert cov["within_tile"] >= 0.99 and cov["bare"] > MAX_BARE
    assert plain.diagnostics.tile_search["attempts"][0]["result"] == "out of reach"
    assert plain.diagnostics.voxels["fitted"] > 1        # the other grid shifts were tried
    assert plain.diagnostics.distortion["reached"] == 0


def _bumped_sphere():
    """An icosphere with a narrow bump (0.4 out) at +x, and a coarser sphere
    projected onto it (on its own side): its vertices miss the bump's top."""
    from geotex.mesh.geometry import vertex_normals
    from geotex.param.polycube_fit import SurfaceFit

    V, F = icosphere(4)
    B = V * (1.0 + 0.4 * np.clip((V[:, 0] - 0.95) / 0.05, 0.0, 1.0))[:, None]
    P, Fp = icosphere(3)
    projector = SurfaceProjector(B, F)
    Y, face = projector.project(P, vertex_normals(P, Fp))
    fit = SurfaceFit(Y=Y, base_face=face, folded=np.zeros(Fp.shape[0], dtype=bool), repaired=0)
    return B, F, P, Fp, projector, fit


def test_reached_surface_moves_out_to_a_protrusion():
    from geotex.param.polycube import _face_samples
    from geotex.param.polycube_fit import folded_faces, reached_surface

    B, F, P, Fp, projector, fit = _bumped_sphere()
    before = bare_fraction(B, F, fit.Y, Fp, depth=0.05)
    assert before > 0.02
    out = reached_surface(fit, P, Fp, projector, *_face_samples(B, F), depth=0.02)
    assert bare_fraction(B, F, out.Y, Fp, depth=0.05) < 0.01 * before
    assert out.reached > 0 and out.reached == int((out.Y != fit.Y).any(axis=1).sum())
    assert not folded_faces(out.Y, Fp, projector, out.base_face).any() and not out.folded.any()
    far = P[:, 0] < -0.3                                         # the far side does not move
    assert far.sum() > 100 and np.array_equal(out.Y[far], fit.Y[far])
    C, _ = projector.closest(out.Y)                              # still on the base
    assert np.abs(C - out.Y).max() < 1e-9
    assert fit.Y.flags.writeable and np.array_equal(fit.Y, _bumped_sphere()[5].Y)  # not mutated


def test_winding_numbers_are_the_signed_ray_crossings():
    """Integers equal to libigl's fast winding number rounded, on a sphere and on
    two overlapping spheres as one self-crossing surface (2 in the overlap)."""
    import igl

    V, F = icosphere(3)
    rng = np.random.default_rng(5)
    dirs = rng.normal(size=(300, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    X = dirs * rng.choice([0.2, 0.7, 1.3, 4.0], size=(300, 1))
    wn = SurfaceProjector(V, F).winding_numbers(X)
    np.testing.assert_array_equal(wn, np.round(igl.fast_winding_number(V, F, X)))
    np.testing.assert_array_equal(wn, (np.linalg.norm(X, axis=1) < 0.9).astype(float))
    W = np.vstack([V, V + [0.8, 0.0, 0.0]])
    FF = np.vstack([F, F + V.shape[0]])
    pts = np.array([[0.4, 0.0, 0.0], [-0.5, 0.1, 0.0], [1.3, 0.0, 0.2], [3.0, 0.0, 0.0],
                    [0.4, 0.0, 0.95]])
    np.testing.assert_array_equal(SurfaceProjector(W, FF).winding_numbers(pts),
                                  [2.0, 1.0, 1.0, 0.0, 0.0])
    assert SurfaceProjector(V, F).winding_numbers(np.zeros((0, 3))).shape == (0,)


def test_winding_numbers_ask_libigl_where_a_ray_meets_an_edge(monkeypatch):
    """A ray through a vertex (a crossing on the faces' edges) is not counted:
    the point gets libigl's fast winding number."""
    import geotex.param.polycube_fit as module

    V, F = icosphere(3)
    d = module._RAYS[0]
    k = int(np.argmax(V @ d))                        # the ray leaves through vertex k
    X = np.array([V[k] - 0.5 * d, [0.0, 0.0, 0.1], [3.0, 0.0, 0.0]])
    asked = []
    real = module.igl.fast_winding_number
    monkeypatch.setattr(module.igl, "fast_winding_number",
                        lambda V_, F_, Q: asked.append(Q.copy()) or real(V_, F_, Q))
    wn = SurfaceProjector(V, F).winding_numbers(X)
    assert len(asked) == 1 and np.array_equal(asked[0], X[:1])
    assert wn[0] > 0.5 and wn[1] == 1.0 and wn[2] == 0.0


def test_reached_surface_with_the_callers_tree_is_the_same():
    from geotex.param.polycube import _face_samples
    from geotex.param.polycube_fit import reached_surface

    B, F, P, Fp, projector, fit = _bumped_sphere()
    S, w = _face_samples(B, F)
    out = reached_surface(fit, P, Fp, projector, S, w, depth=0.02)
    surface = SurfaceProjector(fit.Y, Fp)
    again = reached_surface(fit, P, Fp, projector, S, w, depth=0.02, surface=surface,
                            closest=surface.closest(S))
    assert again.reached == out.reached > 0
    for key in ("Y", "base_face", "folded"):
        np.testing.assert_array_equal(getattr(again, key), getattr(out, key))


def test_reached_surface_leaves_a_covering_fit_as_it_is():
    from geotex.param.polycube import _face_samples
    from geotex.param.polycube_fit import reached_surface

    B, F, P, Fp, projector, fit = _bumped_sphere()
    assert reached_surface(fit, P, Fp, projector, *_face_samples(B, F), depth=0.5) is fit


def test_automatic_tile_size_too_thin_fails_naming_the_place(monkeypatch):
    import geotex.param.polycube as module

    monkeypatch.setattr(module, "MAX_QUADS", 3000)          # keep the test fast
    from scipy.spatial.transform import Rotation

    V, F = torus(1.0, 0.99, n_major=64, n_minor=32)         # a hole 0.02 across, tilted
    V = V @ Rotation.from_euler("zx", [30, 20], degrees=True).as_matrix().T
    with pytest.raises(GeotexError, match=r"too thin.*genus 1.*3000 quads.*narrowest gap "
                                          r"0\.0[0-9]* near \(0"):
        polycube(V, F)


def test_same_voxel_polycube_is_fitted_once(monkeypatch):
    """A candidate equal to one fitted before reuses its fit: same answer, one fit less."""
    import geotex.param.polycube as module

    V, F = torus(n_major=48, n_minor=24)
    plain = polycube(V, F, tile_size=0.25)
    real_candidates, real_fit = module._candidates, module.fitted_surface
    fits = []

    def twice(*args, **kwargs):               # every candidate comes twice in a row
        for c in real_candidates(*args, **kwargs):
            yield c
            yield {**c, "info": {**c["info"], "strategy": "again"}}

    def counted(P, F, projector, **kwargs):
        fits.append(P.shape[0])
        return real_fit(P, F, projector, **kwargs)

    monkeypatch.setattr(module, "_candidates", twice)
    monkeypatch.setattr(module, "fitted_surface", counted)
    # every fit reports bare quads, so the search goes on to the copy (the torus
    # has no other candidate at this size)
    real_bad = module._bad_quads

    def all_bad(*args, **kwargs):
        bad, state = real_bad(*args, **kwargs)
        return bad | True, state

    monkeypatch.setattr(module, "_bad_quads", all_bad)
    polycube(V, F, tile_size=0.25)
    assert len(fits) == 1                     # the copy reused, not fitted again
    monkeypatch.setattr(module, "_bad_quads", real_bad)
    fits.clear()
    again = polycube(V, F, tile_size=0.25)
    assert len(fits) == 1
    np.testing.assert_array_equal(again.Y, plain.Y)
    assert module._same_polycube({"origin": np.zeros(3), "corners": np.ones((2, 4)),
                                  "labels": np.arange(2)},
                                 {"origin": np.zeros(3), "corners": np.ones((2, 4)),
                                  "labels": np.arange(2)})
    assert not module._same_polycube({"origin": np.zeros(3), "corners": np.ones((2, 4)),
                                      "labels": np.arange(2)},
                                     {"origin": np.ones(3), "corners": np.ones((2, 4)),
                                      "labels": np.arange(2)})
