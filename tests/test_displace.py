"""geotex displace: relief core, mappings, masks, library, API and CLI."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from geotex.displace import displaced_mesh, mask_options, mapping_options
from geotex.displace.heightmap import sample_periodic
from geotex.displace.library import library_height_map, library_names
from geotex.displace.mappings import projected_heights
from geotex.displace.masks import bucket_fill_faces
from geotex.errors import InputError
from geotex.mesh.primitives import box, closed_cylinder, icosphere
from geotex.mesh.topology import edge_topology
from geotex.relief import ReliefPoints, displaced_solid, refined_by_edge_splits, relief_points


@pytest.fixture(scope="module")
def cylinder():
    return closed_cylinder(10.0, 20.0, n_theta=48, n_height=12, n_cap_rings=4)


def _closed(F, n):
    t = edge_topology(F, n)
    return len(t.boundary) == 0 and len(t.non_manifold) == 0


def test_edge_splits_keep_the_surface_and_close_the_mesh(cylinder):
    V, F = cylinder
    R = refined_by_edge_splits(V, F, 0.8, corner_bary=True)
    assert R.faces.shape[0] > 4 * F.shape[0]
    assert _closed(R.faces, R.vertices.shape[0])
    e = R.vertices[R.faces] - np.roll(R.vertices[R.faces], -1, axis=1)
    assert np.linalg.norm(e, axis=2).max() <= 0.8 + 1e-12
    # every refined corner is its barycentric combination of its base face
    P = np.einsum("kcj,kjx->kcx", R.corner_bary.astype(np.float64), V[F[R.parent]])
    assert np.abs(P - R.vertices[R.faces]).max() < 1e-5
    # same area: the shape did not change
    def area(V, F):
        return 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]),
                                    axis=1).sum()
    assert area(R.vertices, R.faces) == pytest.approx(area(V, F), rel=1e-12)


def test_refinement_cap_is_a_clear_error(cylinder):
    V, F = cylinder
    with pytest.raises(InputError, match="face cap"):
        refined_by_edge_splits(V, F, 0.05, max_faces=10_000)


def test_displaced_cylinder_is_printable_and_bed_stays_flat(cylinder):
    V, F = cylinder
    r = displaced_mesh(V, F, "bricks", depth=0.6, target_faces=40_000)
    assert r.report.printable, r.report.reasons
    assert _closed(r.faces, r.vertices.shape[0])
    Vr = r.vertices
    assert Vr[:, 2].min() == 0.0                      # the bed face did not move
    bed = np.abs(Vr[:, 2]) < 1e-9
    assert bed.sum() > 100
    assert np.hypot(Vr[bed, 0], Vr[bed, 1]).max() <= 10.0 + 1e-5
    # the side did move outward, by at most the depth
    rad = np.hypot(Vr[:, 0], Vr[:, 1])
    assert rad.max() > 10.3 and rad.max() <= 10.6 + 1e-4


def test_displacement_is_deterministic(cylinder):
    V, F = cylinder
    a = displaced_mesh(V, F, "voronoi", depth=0.5, target_faces=20_000, judge=False)
    b = displaced_mesh(V, F, "voronoi", depth=0.5, target_faces=20_000, judge=False)
    assert a.vertices.tobytes() == b.vertices.tobytes()
    assert a.faces.tobytes() == b.faces.tobytes()


def test_symmetric_grey_does_not_move_the_surface(cylinder):
    V, F = cylinder
    grey = np.full((16, 16), 0.5)
    r = displaced_mesh(V, F, grey, depth=1.0, symmetric=True, target_faces=10_000,
                       judge=False, masks=mask_options(bottom_angle=0))
    rad = np.hypot(r.vertices[:, 0], r.vertices[:, 1])
    side = (r.vertices[:, 2] > 0.5) & (r.vertices[:, 2] < 19.5)
    assert np.abs(rad[side] - 10.0).max() < 0.025      # sagitta of the 48-gon: 0.0214


def _ring_points(theta, z, radius=10.0):
    P = np.column_stack([radius * np.cos(theta), radius * np.sin(theta), z])
    N = np.column_stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)])
    Vb = np.array([[-radius, -radius, 0.0], [radius, radius, 20.0]])
    k = len(theta)
    return ReliefPoints(P, N, np.zeros(k, np.int64), np.tile([1.0, 0, 0], (k, 1)),
                        np.zeros((0, 3), np.int64), np.zeros(0, np.int64), Vb,
                        np.zeros((0, 3), np.int64))


def test_cylindrical_mapping_has_no_seam():
    H = library_height_map("noise", size=64)
    z = np.linspace(1, 19, 50)
    eps = 1e-7
    before = _ring_points(np.full(50, np.pi - eps), z)
    after = _ring_points(np.full(50, -np.pi + eps), z)
    for scale in (7.0, 13.0):                # not whole divisors of the circumference
        opt = mapping_options("cylindrical", scale_u=scale, offset_u=1.3)
        hb = projected_heights(before, H, opt)
        ha = projected_heights(after, H, opt)
        assert np.abs(hb - ha).max() < 1e-4


def test_triplanar_repeats_with_the_tile_size():
    H = library_height_map("noise", size=64)
    rng = np.random.default_rng(0)
    theta = rng.uniform(-np.pi, np.pi, 200)
    z = rng.uniform(1, 19, 200)
    p = _ring_points(theta, z)
    opt = mapping_options("triplanar", scale_u=6.0, sharpness=4.0)
    h0 = projected_heights(p, H, opt)
    shifted = ReliefPoints(p.positions + [6.0, 12.0, 18.0], p.normals, p.face, p.bary, p.faces,
                           p.parent, p.base_vertices + [6.0, 12.0, 18.0], p.base_faces)
    assert np.abs(projected_heights(shifted, H, opt) - h0).max() < 1e-9
    assert h0.std() > 0.05


def test_sample_periodic_wraps():
    H = library_height_map("dots", size=32)
    u = np.linspace(-2, 2, 101)
    v = np.linspace(0.3, 0.7, 101)
    assert np.allclose(sample_periodic(H, u, v), sample_periodic(H, u + 3, v - 2))


def test_library_has_twenty_deterministic_maps():
    names = library_names()
    assert len(names) >= 20
    for n in names:
        a = library_height_map(n, size=64)
        assert a.shape == (64, 64) and a.dtype == np.float32
        assert 0.0 <= a.min() and a.max() <= 1.0 and a.std() > 0.02
        assert np.array_equal(a, library_height_map(n, size=64))
    with pytest.raises(InputError, match="not a library texture"):
        library_height_map("nope")


def test_box_mask_moves_only_the_selected_faces(cylinder):
    V, F = cylinder
    m = mask_options(bottom_angle=0, box=(-20, -20, 8, 20, 20, 12))
    r = displaced_mesh(V, F, "dots", depth=0.5, target_faces=20_000, masks=m, judge=False)
    rad = np.hypot(r.vertices[:, 0], r.vertices[:, 1])
    z = r.vertices[:, 2]
    outside = ((z < 7) | (z > 13)) & (z > 0.01) & (z < 19.99)
    assert rad[outside].max() <= 10.0 + 1e-6
    assert rad[(z > 8.5) & (z < 11.5)].max() > 10.2


def test_mask_transition_is_soft(cylinder):
    V, F = cylinder
    hard = mask_options(bottom_angle=0, box=(-20, -20, 10, 20, 20, 25))
    soft = mask_options(bottom_angle=0, box=(-20, -20, 10, 20, 20, 25), width=3.0,
                        curve="linear")
    ones = np.ones((8, 8))
    a = displaced_mesh(V, F, ones, depth=0.5, target_faces=20_000, masks=hard, judge=False)
    b = displaced_mesh(V, F, ones, depth=0.5, target_faces=20_000, masks=soft, judge=False)
    def offset_at(r, z0):
        z = r.vertices[:, 2]
        sel = np.abs(z - z0) < 0.4
        return np.hypot(r.vertices[sel, 0], r.vertices[sel, 1]).max() - 10.0
    assert offset_at(a, 11.5) > 0.45
    assert 0.1 < offset_at(b, 11.5) < 0.4                # inside the 3 mm ramp


def test_bucket_fill_stops_at_creases():
    V, F = box(divisions=3)
    sel = bucket_fill_faces(V, F, [0], max_angle=30.0)
    assert sel.sum() == F.shape[0] // 6                  # one side of the cube
    assert bucket_fill_faces(V, F, [0], max_angle=95.0).all()


def test_absurd_depth_is_refused_and_large_depth_warned(cylinder):
    V, F = cylinder
    with pytest.raises(InputError, match="absurd"):
        displaced_mesh(V, F, "dots", depth=8.0, target_faces=5000, judge=False)
    r = displaced_mesh(V, F, "dots", depth=2.5, target_faces=5000, judge=False)
    assert any("10 %" in w for w in r.warnings)


def test_core_with_a_height_array_on_an_icosphere():
    V, F = icosphere(2, radius=10.0)
    pts = relief_points(V, F, edge_length=1.0)
    h = 0.5 + 0.5 * np.sin(pts.positions[:, 0])
    r = displaced_solid(V, F, points=pts, heights_array=h, depth=0.5)
    rad = np.linalg.norm(r.vertices, axis=1)
    assert rad.min() > 9.4 and rad.max() <= 10.5 + 1e-9
    with pytest.raises(InputError, match="heights must be"):
        displaced_solid(V, F, points=pts, heights_array=h[:-1], depth=0.5)


def test_pgp_mapping_on_an_icosphere_is_printable():
    V, F = icosphere(3, radius=15.0)
    r = displaced_mesh(V, F, "hexagons", depth=0.5, mapping="pgp", scale_u=8.0,
                       target_faces=30_000, masks=mask_options(bottom_angle=0))
    assert r.report.printable, r.report.reasons


def test_uv_mapping_needs_coordinates(cylinder):
    V, F = cylinder
    with pytest.raises(InputError, match="texture coordinates"):
        displaced_mesh(V, F, "dots", depth=0.5, mapping="uv", judge=False)


def _geotex(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "geotex", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd)


@pytest.fixture(scope="module")
def cylinder_file(tmp_path_factory, cylinder):
    from geotex.io import write_mesh
    from geotex.mesh.record import Mesh

    p = tmp_path_factory.mktemp("displace") / "cyl.stl"
    write_mesh(p, Mesh(*cylinder))
    return p


def test_cli_writes_a_printable_relief_and_a_report(cylinder_file, tmp_path):
    out, rep = tmp_path / "out.stl", tmp_path / "rep.json"
    res = _geotex("displace", cylinder_file, "--image", "knurling", "--depth", "0.5",
                  "--faces", "20000", "--mapping", "cylindrical", "-o", out, "--report", rep)
    assert res.returncode == 0, res.stderr
    assert out.is_file()
    doc = json.loads(rep.read_text())
    assert doc["check"]["printable"] and doc["stats"]["faces"] > 10_000


@pytest.mark.parametrize("args,words", [
    (["--image", "nope", "--depth", "1"], "--image nope"),
    (["--image", "dots", "--depth", "-1"], "--depth"),
    (["--image", "dots", "--depth", "9"], "--depth 9 mm is absurd"),
    (["--image", "dots", "--depth", "1", "--scale-u", "0"], "--scale-u"),
    (["--image", "dots", "--depth", "1", "--mask-box", "1,2"], "--mask-box"),
    (["--image", "dots", "--depth", "1", "--mapping", "uv"], "--mapping uv"),
    (["--image", "dots", "--depth", "1", "--edge-mm", "0.01", "--max-faces", "1000"],
     "--edge-mm"),
])
def test_cli_errors_are_one_line(cylinder_file, tmp_path, args, words):
    out = tmp_path / "x.stl"
    res = _geotex("displace", cylinder_file, *args, "-o", out)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("geotex: error:") and words in lines[0], \
        res.stderr
    assert not out.exists()


def test_cli_lists_the_library():
    res = _geotex("displace", "--list")
    assert res.returncode == 0
    assert len(res.stdout.strip().splitlines()) == len(library_names())


def test_cli_refuses_to_overwrite_the_input(cylinder_file):
    res = _geotex("displace", cylinder_file, "--image", "dots", "--depth", "1", "-o",
                  cylinder_file)
    assert res.returncode == 2 and "overwrite" in res.stderr


def _step_part(path):
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addBox(0, 0, 0, 30, 20, 10)
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def test_step_parts_are_tessellated_closed(tmp_path):
    from geotex.check.report import check_mesh
    from geotex.displace.step import read_step

    part = tmp_path / "box.step"
    _step_part(part)
    counts = []
    for q in ("coarse", "fine"):
        V, F = read_step(part, quality=q)
        assert check_mesh(V, F).printable
        assert np.allclose(np.ptp(V, axis=0), [30, 20, 10])
        counts.append(F.shape[0])
    assert counts[1] > counts[0]
    out = tmp_path / "box.stl"
    res = _geotex("displace", part, "--image", "grid", "--depth", "0.5", "--faces", "20000",
                  "--step-quality", "coarse", "-o", out)
    assert res.returncode == 0, res.stderr
    bad = tmp_path / "bad.step"
    bad.write_text("not a step file")
    res = _geotex("displace", bad, "--image", "grid", "--depth", "0.5", "-o", out)
    assert res.returncode == 2 and "bad.step" in res.stderr


def test_lapped_mapping_is_printable_and_refuses_a_named_field():
    V, F = icosphere(2, radius=15.0)
    r = displaced_mesh(V, F, "bricks", depth=0.4, mapping="lapped", scale_u=12.0,
                       target_faces=20_000, masks=mask_options(bottom_angle=0))
    assert r.report.printable, r.report.reasons
    moved = np.linalg.norm(r.vertices, axis=1) - 15.0
    assert moved.max() > 0.2
    with pytest.raises(InputError, match="needs a direction"):
        displaced_mesh(V, F, "bricks", depth=0.4, mapping="lapped", field="smooth",
                       judge=False, target_faces=5000)


def test_broken_bases_give_one_line_and_no_file(tmp_path):
    """An empty file and a part with a repeated-index face are refused at once (exit 2,
    one line naming the problem, before any relief is built), by the Python API too;
    with the base check turned off, degenerate faces leave vertices without a normal,
    which do not move (no NaN coordinates)."""
    from geotex.io import write_mesh
    from geotex.mesh.record import Mesh

    empty = tmp_path / "empty.stl"
    empty.write_bytes(b"\0" * 80 + b"\0\0\0\0")
    out = tmp_path / "x.stl"
    res = _geotex("displace", empty, "--image", "dots", "--depth", "0.5", "-o", out)
    assert res.returncode == 2 and "no faces" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not out.exists()
    V, F = box((0, 0, 0), (10, 10, 10), divisions=2)
    V = np.vstack([V, V[:1]])                              # a zero-area face on a corner
    F = np.vstack([F, [[0, V.shape[0] - 1, 0]]])
    bad = tmp_path / "bad.obj"
    write_mesh(bad, Mesh(V, F))
    res = _geotex("displace", bad, "--image", "dots", "--depth", "0.5", "--faces", "5000",
                  "-o", out)
    assert res.returncode == 2, res.stderr
    assert "not a closed solid to displace: open" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not out.exists()
    from geotex.displace import displaced_mesh
    with pytest.raises(InputError, match="not a closed solid to displace: open"):
        displaced_mesh(V, F, "dots", depth=0.5, target_faces=5000, judge=False)
    r = displaced_mesh(V, F, "dots", depth=0.5, target_faces=5000, judge=False,
                       check_base=False)
    assert np.isfinite(r.vertices).all()


def test_lowered_relief_is_rejudged_locally_and_exactly(monkeypatch):
    # a fat torus displaced inwards around its hole crosses itself: the relief is
    # lowered there and judged again; the local re-judge must give the full verdict
    import geotex.displace.api as api
    from geotex.check.report import check_mesh
    from geotex.mesh.primitives import torus
    from geotex.printing import stored_form

    calls = []
    original = api.recheck_moved

    def spy(*args, **kwargs):
        calls.append(original(*args, **kwargs))
        return calls[-1]

    monkeypatch.setattr(api, "recheck_moved", spy)
    V, F = torus(4.0, 3.0, n_major=40, n_minor=24)
    pts = relief_points(V, F, edge_length=0.5)
    h = 0.5 + 0.5 * np.sin(3.0 * pts.positions[:, 0]) * np.cos(3.0 * pts.positions[:, 1])
    r = displaced_solid(V, F, points=pts, heights_array=h, depth=1.6,
                        judge=api.stored_judge(np.float32), precision=np.float32)
    assert r.stats["relief_reduced_rounds"] > 0
    assert calls and all(c is not None for c in calls)
    full = check_mesh(r.vertices, r.faces, manifold3d=False, max_examples=2 ** 62)
    assert r.report == full and r.report.printable
    Vs, Fs = stored_form(r.vertices, r.faces, precision=np.float32)
    assert np.array_equal(Vs, r.vertices) and np.array_equal(Fs, r.faces)


@pytest.mark.parametrize("shape,sigma", [((64, 80), 0.31), ((64, 80), 2.7), ((6, 90), 9.0),
                                          ((33, 33), 16.5)])
def test_height_map_blur_equals_scipy_gaussian_filter(shape, sigma):
    # the periodic blur is scipy.ndimage.gaussian_filter(mode="wrap") bit for bit, without
    # importing scipy.ndimage (a radius beyond the image wraps more than once)
    from scipy.ndimage import gaussian_filter

    from geotex.displace.heightmap import filtered_height_map

    H = np.random.default_rng(4).random(shape).astype(np.float32)
    want = gaussian_filter(H, sigma=min(sigma, 0.5 * max(shape)), mode="wrap")
    got = filtered_height_map(H, sigma_pixels=sigma)
    assert got.dtype == np.float32 and got.tobytes() == want.tobytes()
    assert np.array_equal(filtered_height_map(H, sigma_pixels=sigma, invert=True), 1.0 - want)
    assert filtered_height_map(H, sigma_pixels=0.2).tobytes() == H.tobytes()      # no blur


@pytest.mark.parametrize("name,options", [
    ("triplanar", {}), ("cubic", {}),
    ("triplanar", dict(rotation=33.0, offset_u=3.1, offset_v=-7.0, scale_v=13.0,
                       sharpness=2.5)),
    ("cubic", dict(rotation=-120.0, blend=0.4, offset_v=500.0))])
def test_blended_projections_compiled_equal_numpy(monkeypatch, name, options):
    # the compiled triplanar / cubic loop gives the numpy path's heights bit for bit
    # (points below the origin and far beyond one tile: the periodic wrap both ways)
    import geotex.displace.mappings as mp
    from geotex.mesh.primitives import torus

    V, F = torus(30.0, 12.0, n_major=48, n_minor=24)
    pts = relief_points(V - 5.0, F, edge_length=2.0)
    H = np.random.default_rng(7).random((37, 53)).astype(np.float32)
    opt = mp.mapping_options(name, scale_u=9.0, **options)
    monkeypatch.setattr(mp, "JIT_MIN_SIZE", 0)
    fast = mp.projected_heights(pts, H, opt)
    monkeypatch.setattr(mp, "JIT_MIN_SIZE", 10 ** 12)
    slow = mp.projected_heights(pts, H, opt)
    assert fast.dtype == slow.dtype == np.float64
    assert fast.tobytes() == slow.tobytes()
    assert 0.0 <= fast.min() and fast.max() <= 1.0 and np.ptp(fast) > 0.5


def test_relief_lowering_compiled_rings_equal_numpy(monkeypatch):
    # the lowering rounds grow their rings by a compiled pass from JIT_MIN_SIZE on, and
    # search crossings on the local vertices only: the same gains as the numpy rings
    import geotex.relief.core as core
    from geotex.check.intersections import self_intersecting_pairs
    from geotex.mesh.primitives import torus

    V, F = torus(4.0, 3.0, n_major=40, n_minor=24)
    pts = relief_points(V, F, edge_length=0.5)
    h = 0.5 + 0.5 * np.sin(3.0 * pts.positions[:, 0]) * np.cos(3.0 * pts.positions[:, 1])
    D = (1.6 * h)[:, None] * pts.normals
    P, Fr = pts.positions, pts.faces
    pairs = self_intersecting_pairs((P + D).astype(np.float32).astype(np.float64), Fr)
    assert len(pairs) > 0
    got = []
    for size in (0, 10 ** 12):
        monkeypatch.setattr(core, "JIT_MIN_SIZE", size)
        got.append(core._lowered_where_crossing(P, Fr, D, np.ones(P.shape[0]), pairs,
                                                np.float32))
    (g0, r0), (g1, r1) = got
    assert r0 == r1 > 0 and g0.tobytes() == g1.tobytes() and (g0 < 1).any()
    # what the rounds left is clean on the whole mesh where they looked
    Vr = (P + g0[:, None] * D).astype(np.float32).astype(np.float64)
    left = self_intersecting_pairs(Vr, Fr)
    assert not np.isin(np.asarray(left).ravel(), np.unique(np.asarray(pairs).ravel())).any()


def test_crossings_found_near_folds_before_the_judge(monkeypatch):
    # the search near folded faces finds only true crossings; when it finds all of the
    # judge's, the relief is lowered before the first verdict, the judge runs once and
    # the solid equals the one lowered after the judge's own search, bit for bit
    import geotex.displace.api as api
    import geotex.relief.core as core
    from geotex.check.intersections import self_intersecting_pairs
    from geotex.check.report import check_mesh
    from geotex.mesh.primitives import torus

    V, F = torus(4.0, 3.0, n_major=40, n_minor=24)
    pts = relief_points(V, F, edge_length=0.5)
    h = 0.5 + 0.5 * np.sin(3.0 * pts.positions[:, 0]) * np.cos(3.0 * pts.positions[:, 1])
    D = (1.6 * h)[:, None] * pts.normals
    P, Fr = pts.positions, pts.faces
    full = self_intersecting_pairs((P + D).astype(np.float32).astype(np.float64), Fr)
    near = core._likely_crossings(P, Fr, D, np.float32)
    assert len(near) > 0
    assert {tuple(p) for p in near.tolist()} == {tuple(p) for p in full.tolist()}
    judged = []
    original = api.check_mesh

    def spy(*args, **kwargs):
        judged.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(api, "check_mesh", spy)
    rejudged = []
    recheck = api.recheck_moved
    monkeypatch.setattr(api, "recheck_moved",
                        lambda *a, **k: rejudged.append(1) or recheck(*a, **k))
    out = {}
    for floor in (10 ** 12, 0):
        monkeypatch.setattr(core, "PRESEARCH_MIN_FACES", floor)
        judged.clear()
        rejudged.clear()
        r = displaced_solid(V, F, points=pts, heights_array=h, depth=1.6,
                            judge=api.stored_judge(np.float32), precision=np.float32)
        out[floor] = (r, len(judged) + len(rejudged))
    (late, n_late), (early, n_early) = out[10 ** 12], out[0]
    assert n_late == 2 and n_early == 1 and early.stats["relief_reduced_rounds"] > 0
    assert early.report == check_mesh(early.vertices, early.faces, manifold3d=False,
                                      max_examples=2 ** 62) and early.report.printable
    assert early.vertices.tobytes() == late.vertices.tobytes()
    assert np.array_equal(early.faces, late.faces)
    assert early.stats["relief_reduced_rounds"] == late.stats["relief_reduced_rounds"]


def test_judge_gets_faces_in_first_use_order_and_shares_them():
    # the relief numbers its vertices by first use before judging, so the stored form's
    # faces equal the judged ones and the judge keeps one copy (the memory peak is there)
    import geotex.displace.api as api
    from geotex.mesh.topology import first_use_order

    V, F = icosphere(3)
    V = 10.0 * V
    seen = []
    judge = api.stored_judge(np.float32)

    def spy(Vx, Fx):
        out = judge(Vx, Fx)
        seen.append((Fx, out[1]))
        return out

    heights = lambda p: 0.5 + 0.5 * np.sin(2.0 * p.positions[:, 0])  # noqa: E731
    r = displaced_solid(V, F, heights, depth=0.3, edge_length=0.6, judge=spy,
                        precision=np.float32)
    Fx, Fs = seen[0]
    assert Fs is Fx and Fx.dtype == np.int64
    n = int(Fx.max()) + 1
    assert np.array_equal(first_use_order(Fx, n), np.arange(n))
    plain = displaced_solid(V, F, heights, depth=0.3, edge_length=0.6, precision=np.float32)
    # the same solid as without a judge, vertices renumbered only
    a = r.vertices[r.faces]
    b = plain.vertices[plain.faces].astype(np.float32).astype(np.float64)
    assert r.report.printable and a.tobytes() == b.tobytes()
