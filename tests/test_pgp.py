"""Periodic global parameterization (geotex.param.pgp) and ``geotex pgp``."""

import json

import numpy as np
import pytest

from geotex.cli import main
from geotex.errors import InputError
from geotex.fields.directions import smooth_direction_field
from geotex.fields.frames import face_connection
from geotex.io import write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import grid_plane, icosphere, plate_with_holes, torus
from geotex.param.pgp import periodic_parameterization


def _rot(c, r):
    u, v = c[..., 0], c[..., 1]
    return np.stack([[u, -v, -u, v][r], [v, u, -v, -u][r]], axis=-1)


def _edge_residuals(p, V, F):
    """Independent check: per interior edge, min over rotations of the deviation."""
    conn = face_connection(V, F)
    out = []
    for (f, g), (lo, hi) in zip(conn.faces, conn.vertices):
        if p.singular[f] or p.singular[g]:
            continue
        cf = np.array([p.coords[f, list(F[f]).index(x)] for x in (lo, hi)])
        cg = np.array([p.coords[g, list(F[g]).index(x)] for x in (lo, hi)])
        best = np.inf
        for r in range(4):
            d = cg - _rot(cf, r)
            best = min(best, np.abs(d - np.rint(d[0])).max())
        out.append(best)
    return np.array(out)


def test_flat_grid_constant_field_is_an_exact_affine_grid():
    V, F = grid_plane(12, 9, size=(2.0, 1.5))
    V = V + [0.3, -0.2, 0.0]
    scale = 0.37
    p = periodic_parameterization(V, F, np.tile([1.0, 0.0, 0.0], (len(F), 1)), scale=scale)
    assert p.coords.shape == (len(F), 3, 2) and p.coords.dtype == np.float64
    assert not p.singular.any() and p.cones == () and p.dislocations == ()
    d = (p.coords - V[F][:, :, :2] / scale).reshape(-1, 2)
    d = d - d[0]
    assert np.abs(d - np.rint(d)).max() < 1e-9           # one global shift, modulo tiles
    within = p.coords - p.coords[:, [0]] - (V[F][:, :, :2] - V[F][:, [0], :2]) / scale
    assert np.abs(within).max() < 1e-9                    # affine inside every face
    assert p.seam_residual < 1e-9 and p.gradient_error < 1e-9
    assert max(p.distortion.values()) < 1e-6


@pytest.mark.parametrize("solver", ["direct", "multilevel"])
def test_rotated_field_and_per_vertex_scale_on_flat_grid(solver):
    V, F = grid_plane(20, 20)
    a = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    p = periodic_parameterization(V, F, np.tile(a, (len(F), 1)), scale=np.full(len(V), 0.25),
                                  solver=solver)
    b = np.array([-a[1], a[0], 0.0])
    want = np.stack([V[F] @ a, V[F] @ b], axis=-1) / 0.25
    d = (p.coords - want).reshape(-1, 2)
    d = d - d[0]
    assert np.abs(d - np.rint(d)).max() < 1e-9


@pytest.mark.parametrize("solver", ["direct", "multilevel"])
@pytest.mark.parametrize("name, mesh, chi", [
    ("sphere", lambda: icosphere(3), 2),
    ("torus", lambda: torus(n_major=40, n_minor=20), 0),
    ("genus2", lambda: plate_with_holes(2, cell=0.15), -2),
])
def test_curved_closed_meshes(name, mesh, chi, solver):
    V, F = mesh()
    field = smooth_direction_field(V, F, symmetry=4)
    p = periodic_parameterization(V, F, field, scale=0.3, solver=solver)
    assert p.index_sum == pytest.approx(chi) == field.index_sum
    assert p.seam_residual <= 1e-6
    res = _edge_residuals(p, V, F)
    assert res.size > 0.8 * (1.5 * len(F)) and res.max() <= 1e-6
    assert 0 < p.singular.sum() < 0.25 * len(F)
    cone_faces = np.isin(F, [v for v, _ in p.cones]).any(axis=1)
    assert p.singular[cone_faces].all()
    assert p.gradient_error < 0.3
    d = p.distortion
    assert 0 < d["scale_error_mean"] <= d["scale_error_p95"] < 1.0
    assert 0 < d["angle_mean_deg"] <= d["angle_p95_deg"] < 45.0


def test_singular_faces_are_needed():
    """The check is honest: unmarking the singular faces breaks the seam measure."""
    V, F = icosphere(3)
    p = periodic_parameterization(V, F, smooth_direction_field(V, F, symmetry=4), scale=0.3)
    from dataclasses import replace
    q = replace(p, singular=np.zeros_like(p.singular))
    assert _edge_residuals(q, V, F).max() > 1e-3


def test_deterministic():
    V, F = torus(n_major=30, n_minor=14)
    field = smooth_direction_field(V, F, symmetry=4)
    for solver in ("direct", "multilevel"):
        a = periodic_parameterization(V, F, field, scale=0.3, solver=solver)
        b = periodic_parameterization(V, F, field, scale=0.3, solver=solver)
        assert a.coords.tobytes() == b.coords.tobytes()
        assert a.singular.tobytes() == b.singular.tobytes() and a.cones == b.cones


def test_inputs_not_modified():
    V, F = icosphere(2)
    V0, F0 = V.copy(), F.copy()
    vec = np.tile([0.0, 0.0, 1.0], (len(F), 1))
    periodic_parameterization(V, F, vec, scale=0.5)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


@pytest.mark.parametrize("kwargs, message", [
    (dict(scale=0.0), "scale must be a positive"),
    (dict(scale=-1.0), "scale must be a positive"),
    (dict(scale=float("nan")), "scale must be a positive"),
    (dict(scale=np.ones(3)), "scale must be a positive number or have shape"),
    (dict(scale=1.0, field=np.ones((2, 3))), "field must have one vector per face"),
    (dict(scale=1.0, solver="cg"), "solver must be"),
])
def test_bad_inputs(kwargs, message):
    V, F = icosphere(1)
    kwargs.setdefault("field", np.tile([1.0, 0.0, 0.0], (len(F), 1)))
    with pytest.raises(InputError, match=message) as err:
        periodic_parameterization(V, F, **kwargs)
    assert "\n" not in str(err.value)


def test_non_manifold_mesh_refused():
    V, F = grid_plane(2, 1)
    V = np.vstack([V, [[0.5, 0.5, 1.0]]])
    F = np.vstack([F, [[0, 4, len(V) - 1]]])        # third face on edge (0, 4)
    with pytest.raises(InputError, match="non-manifold"):
        periodic_parameterization(V, F, np.tile([1.0, 0.0, 0.0], (len(F), 1)), scale=1.0)


# ---- command line -------------------------------------------------------------------------

def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_pgp_json_and_file(capsys, tmp_path):
    mesh = write_mesh(tmp_path / "t.ply", Mesh(*torus(n_major=30, n_minor=14)))
    cons = tmp_path / "c.json"
    cons.write_text("[]")
    out = tmp_path / "p.npz"
    code, text, err = _run(capsys, "pgp", mesh, "--constraints", cons, "--scale", "0.3",
                           "-o", out, "--json")
    assert code == 0, err
    d = json.loads(text)
    assert d["index_sum"] == pytest.approx(0.0) and d["seam_residual"] <= 1e-6
    assert {"singularities", "timings", "gradient_error"} <= set(d)
    with np.load(out) as z:
        assert z["coords"].shape == (d["faces"], 3, 2) and z["singular"].dtype == bool
        assert json.loads(str(z["metadata"]))["format"] == "geotex-pgp/1"
    code, text, err = _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.3",
                           "--solver", "multilevel", "-o", tmp_path / "q.npz")
    assert code == 0 and "seam residual" in text


@pytest.mark.parametrize("argv, message", [
    (["--up", "0,0,1", "--scale", "0"], "--scale"),
    (["--up", "0,0,1", "--scale", "abc"], "--scale"),
    (["--up", "1,2", "--scale", "1"], "--up"),
    (["--scale", "1"], "--up"),
    (["--up", "0,0,1", "--scale", "1", "--solver", "cg"], "--solver"),
])
def test_cli_pgp_errors(capsys, tmp_path, argv, message):
    mesh = write_mesh(tmp_path / "s.ply", Mesh(*icosphere(1)))
    code, out, err = _run(capsys, "pgp", mesh, *argv, "-o", tmp_path / "p.npz")
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "p.npz").exists()


@pytest.mark.parametrize("solver", ["direct", "multilevel"])
def test_two_components_and_an_unreferenced_vertex(solver):
    V1, F1 = icosphere(2)
    V2, F2 = torus(n_major=24, n_minor=12)
    V = np.vstack([V1, V2 + [4.0, 0.0, 0.0], [[9.0, 9.0, 9.0]]])
    F = np.vstack([F1, F2 + len(V1)])
    field = smooth_direction_field(V, F, symmetry=4)
    p = periodic_parameterization(V, F, field, scale=0.4, solver=solver)
    assert p.index_sum == pytest.approx(2.0) and p.seam_residual <= 1e-6
    assert np.isfinite(p.coords).all()
    # both components got a periodic function (not one left at zero)
    assert (~p.singular[:len(F1)]).sum() > len(F1) // 2
    assert (~p.singular[len(F1):]).sum() > len(F2) // 2


def test_cli_constraint_scales_override_scale(capsys, tmp_path):
    mesh = write_mesh(tmp_path / "t.ply", Mesh(*torus(n_major=30, n_minor=14)))
    cons = tmp_path / "c.json"
    V, F = torus(n_major=30, n_minor=14)
    C = V[F].mean(axis=1)
    f0, f1 = int(np.argmax(C[:, 0])), int(np.argmin(C[:, 0]))      # outer equator: normal ~x
    cons.write_text(json.dumps([{"face": f0, "direction": [0, 1, 0], "scale": 0.2},
                                {"face": f1, "direction": [0, 0, 1], "scale": 0.4}]))
    code, text, err = _run(capsys, "pgp", mesh, "--constraints", cons, "--scale", "9",
                           "-o", tmp_path / "p.npz", "--json")
    assert code == 0, err
    assert json.loads(text)["scale_range"] == pytest.approx([0.2, 0.4])


def test_singular_faces_carry_the_fields_local_map():
    """Baked singular faces show one correctly sized, oriented piece of the tile."""
    V, F = icosphere(3)
    field = smooth_direction_field(V, F, symmetry=4)
    p = periodic_parameterization(V, F, field, scale=0.3)
    conn = face_connection(V, F)
    s = np.flatnonzero(p.singular)
    P = V[F[s]]
    E = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]], axis=1)          # (k, 2, 3)
    dC = p.coords[s, 1:] - p.coords[s, :1]                                 # (k, 2, 2)
    # the corner steps have the length the scale asks for (0.3 surface units per tile)
    surface = np.linalg.norm(E, axis=2)
    tile = np.linalg.norm(dC, axis=2)
    assert np.allclose(tile * 0.3, surface, rtol=1e-9)
    assert conn.areas[s].sum() < 0.25 * conn.areas.sum()


def test_pgp_file_round_trip_and_tile_image(capsys, tmp_path):
    from PIL import Image

    from geotex.io import read_mesh
    from geotex.param.pgp_store import load_parameterization

    mesh = write_mesh(tmp_path / "s.obj", Mesh(*icosphere(2)))
    pgp = tmp_path / "p.npz"
    code, _, err = _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.4", "-o", pgp)
    assert code == 0, err
    back = load_parameterization(pgp)
    assert back.coords.shape == (320, 3, 2) and back.metadata["scale"] == 0.4
    img = np.zeros((8, 8, 3), np.uint8)
    img[:4] = 200
    Image.fromarray(img).save(tmp_path / "stripes.png")
    for ext in (".glb", ".obj"):
        out = tmp_path / f"t{ext}"
        code, text, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "stripes.png",
                               "--param", pgp, "-o", out)
        assert code == 0, err
        m = read_mesh(out)
        assert m.texture is not None and m.texture.shape[:2] == (8, 8)
        uv = m.uv[m.uv_faces]
        assert np.allclose(np.sort(uv.reshape(-1, 2), axis=0),
                           np.sort(back.coords.reshape(-1, 2), axis=0), atol=1e-6)
    # a photo that is not periodic is made tileable first (graph-cut wrap)
    rng = np.random.default_rng(0)
    Image.fromarray(rng.integers(0, 255, (40, 50, 3), dtype=np.uint8)).save(tmp_path / "ph.png")
    out = tmp_path / "ph.glb"
    code, _, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "ph.png",
                        "--param", pgp, "--make-tileable", "16", "-o", out)
    assert code == 0, err
    assert read_mesh(out).texture.shape[:2] == (16, 16)
    code, _, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "ph.png",
                        "--param", pgp, "--make-tileable", "4", "-o", tmp_path / "no.glb")
    assert code == 2 and "--make-tileable" in err and not (tmp_path / "no.glb").exists()


def test_cli_pgp_errors_name_the_mesh_file_or_the_flag(capsys, tmp_path):
    # corpus sweep: a zero --up and a non-manifold or unoriented mesh were refused with the
    # library's words ("direction is zero", "F has ..."), naming neither the flag nor the file
    V, F = icosphere(1)
    i, j = int(np.argmax(V[:, 0])), int(np.argmin(V[:, 0]))
    F2 = F + len(V)
    F2[F2 == j + len(V)] = i                     # a second sphere touching the first at i
    bowtie = write_mesh(tmp_path / "bowtie.obj",
                        Mesh(np.vstack([V, V + (V[i] - V[j])]), np.vstack([F, F2])))
    flipped = F.copy()
    flipped[0] = flipped[0, ::-1]
    unoriented = write_mesh(tmp_path / "flip.obj", Mesh(V, flipped))
    good = write_mesh(tmp_path / "s.obj", Mesh(V, F))
    cases = [(good, ["--up", "0,0,0"], "--up '0,0,0': give a non-zero direction"),
             (bowtie, ["--up", "0,0,1"], f"{bowtie}: the mesh has 1 non-manifold vertex"),
             (unoriented, ["--up", "0,0,1"], f"{unoriented}: the mesh is not consistently"),
             (unoriented, ["--curvature"], f"{unoriented}: the mesh is not consistently")]
    for mesh, field, start in cases:
        out = tmp_path / "p.npz"
        code, _, err = _run(capsys, "pgp", mesh, *field, "--scale", "0.4", "-o", out)
        lines = err.strip().splitlines()
        assert code == 2 and not out.exists(), err
        assert len(lines) == 1 and lines[0].startswith("geotex: error: " + start), err


def test_make_tileable_refuses_a_tile_larger_than_a_texture(capsys, tmp_path, monkeypatch):
    # --make-tileable 100000 asked for a 10^10-texel tile and was killed for lack of memory
    # (corpus sweep); the limit is the texture limit, lowered here to keep the test small
    from PIL import Image

    import geotex.image.material.tileable as tileable

    monkeypatch.setattr(tileable, "MAX_TEXTURE_PIXELS", 32 * 32)
    mesh = write_mesh(tmp_path / "s.obj", Mesh(*icosphere(1)))
    pgp = tmp_path / "p.npz"
    assert _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.4", "-o", pgp)[0] == 0
    rng = np.random.default_rng(0)
    Image.fromarray(rng.integers(0, 255, (40, 40, 3), dtype=np.uint8)).save(tmp_path / "i.png")
    out = tmp_path / "big.glb"
    code, _, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "i.png", "--param",
                        pgp, "--make-tileable", "33", "-o", out)
    assert code == 2 and not out.exists()
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("geotex: error: --make-tileable 33:")
    assert "too large" in lines[0]
    code, _, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "i.png", "--param",
                        pgp, "--make-tileable", "32", "-o", out)
    assert code == 0, err


def test_make_tileable_is_capped_and_tiny_tiles_warn(capsys, tmp_path):
    from PIL import Image

    from geotex.cli.tile_image import MAX_TILEABLE_PX

    mesh = write_mesh(tmp_path / "s.obj", Mesh(*icosphere(2)))
    pgp = tmp_path / "p.npz"
    # tiles far smaller than the triangles: written, with a one-line warning
    code, _, err = _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.01", "-o", pgp)
    assert code == 0 and pgp.exists()
    assert err.startswith("geotex: warning: tiles of 0.01 are smaller than the mesh's")
    code, _, err = _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.5", "-o", pgp)
    assert code == 0 and "warning" not in err
    Image.fromarray(np.full((40, 40, 3), 128, np.uint8)).save(tmp_path / "i.png")
    out = tmp_path / "t.glb"
    code, _, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "i.png", "--param",
                        pgp, "--make-tileable", str(MAX_TILEABLE_PX + 1), "-o", out)
    assert code == 2 and not out.exists()
    assert err.strip() == (f"geotex: error: --make-tileable {MAX_TILEABLE_PX + 1}: at most "
                           f"{MAX_TILEABLE_PX} texels a side (the graph cut would take minutes)")


@pytest.mark.parametrize("argv, message", [
    (["--param", "{other}"], "made for a mesh of"),
    (["--param", "{junk}"], "not a geotex PGP file"),
    (["--param", "{image}"], "unreadable PGP file (not an .npz archive)"),
    (["--image", "{junk}"], "--image"),
])
def test_tile_image_errors_name_the_flag(capsys, tmp_path, argv, message):
    from PIL import Image

    mesh = write_mesh(tmp_path / "s.obj", Mesh(*icosphere(1)))
    other = write_mesh(tmp_path / "o.obj", Mesh(*icosphere(2)))
    pgp, opgp = tmp_path / "p.npz", tmp_path / "op.npz"
    assert _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.5", "-o", pgp)[0] == 0
    assert _run(capsys, "pgp", other, "--up", "0,0,1", "--scale", "0.5", "-o", opgp)[0] == 0
    junk = tmp_path / "junk.npz"
    np.savez(junk, x=np.zeros(3))
    Image.fromarray(np.zeros((4, 4, 3), np.uint8)).save(tmp_path / "i.png")
    args = {"--param": str(pgp), "--image": str(tmp_path / "i.png")}
    for flag, value in zip(argv[::2], argv[1::2]):
        args[flag] = value.format(other=opgp, junk=junk, image=tmp_path / "i.png")
    code, _, err = _run(capsys, "tile-image", mesh, *sum(args.items(), ()),
                        "-o", tmp_path / "out.glb")
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "out.glb").exists()


def test_local_update_keeps_the_outside_and_follows_the_new_field_inside():
    from geotex.param.pgp_update import updated_parameterization
    from geotex.patches.effect import effect_area

    V, F = torus(n_major=60, n_minor=24)
    field = smooth_direction_field(V, F, symmetry=4)
    p = periodic_parameterization(V, F, field, scale=0.2)
    # same field: the update reproduces the previous parameterization
    area = effect_area(V, F, [0], max_distance=0.8)
    q = updated_parameterization(V, F, p, field, scale=0.2, faces=area)
    outside = np.ones(len(F), bool)
    outside[area] = False
    assert np.array_equal(q.coords[outside], p.coords[outside])
    assert q.seam_residual <= 1e-6
    assert np.abs(q.coords - p.coords).max() < 0.05
    # a turned field inside the area: the outside keeps its coordinates exactly,
    # the seams stay exact and the inside follows the new orientation
    vec = field.vectors.copy()
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    vec[area] = c * vec[area] + s * np.cross(N[area], vec[area])
    r = updated_parameterization(V, F, p, vec, scale=0.2, faces=area)
    # outside: the same coordinates up to the grid symmetry the new combing picks
    keep = outside & ~p.singular & ~r.singular
    assert keep.sum() > 0.9 * outside.sum()
    best = np.full(len(F), np.inf)
    for turn in range(4):
        d = r.coords - _rot(p.coords, turn)
        best = np.minimum(best, np.abs(d - np.rint(d[:, :1])).max(axis=(1, 2)))
    assert best[keep].max() < 1e-9
    assert r.seam_residual <= 1e-6
    full = periodic_parameterization(V, F, vec, scale=0.2)
    assert r.gradient_error < max(2 * full.gradient_error, 0.3)


@pytest.mark.parametrize("multilevel", [False, True])
def test_local_update_is_local_and_agrees_with_a_global_check(monkeypatch, multilevel, tmp_path):
    import geotex.param.pgp_update as pgp_update
    from geotex.fields.singularities import vertex_indices
    from geotex.param.pgp_store import load_parameterization, save_parameterization
    from geotex.patches.effect import effect_area

    if multilevel:
        monkeypatch.setattr(pgp_update, "LOCAL_MULTILEVEL_VERTICES", 0)
    V, F = torus(n_major=64, n_minor=26)
    field = smooth_direction_field(V, F, symmetry=4)
    p = periodic_parameterization(V, F, field, scale=0.15)
    area = effect_area(V, F, [0], max_distance=0.9)
    inside = np.zeros(len(F), bool)
    inside[area] = True
    vec = field.vectors.copy()
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    vec[inside] = 0.6 * vec[inside] + 0.8 * np.cross(N[inside], vec[inside])
    scale = np.full(len(V), 0.15)
    scale[F[area]] = 0.12                                  # a new tile size in the area
    q = pgp_update.updated_parameterization(V, F, p, vec, scale=scale, faces=area)
    # every interior edge without a singular face, checked independently
    assert _edge_residuals(q, V, F).max() <= 1e-6
    assert q.seam_residual <= 1e-6
    # the cones are those of the field the update uses (new inside, previous outside)
    used = np.where(inside[:, None], vec, p.axes)
    index = np.nan_to_num(vertex_indices(V, F, used, symmetry=4))
    assert [v for v, _ in q.cones] == np.flatnonzero(index).tolist()
    assert q.index_sum == pytest.approx(0.0)
    # outside the area and its ring nothing moves; the axes inside follow the field
    ring = np.zeros(len(V), bool)
    ring[F[area]] = True
    far = ~ring[F].any(axis=1)
    assert np.array_equal(q.coords[far], p.coords[far])
    assert np.array_equal(q.singular[far], p.singular[far])
    assert np.array_equal(q.axes[~inside], p.axes[~inside])
    turn = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", q.axes, vec)
                                               / np.linalg.norm(vec, axis=1)), 0, 1)))
    assert (np.minimum(turn, 90 - turn)[inside] < 1e-3).all()
    assert q.gradient_error < 0.3
    # the functions are in the frames of the returned axes: a second update with
    # the same field changes nothing
    r = pgp_update.updated_parameterization(V, F, q, vec, scale=scale, faces=area)
    assert np.array_equal(r.coords[~inside], q.coords[~inside])
    assert np.abs(r.coords - q.coords).max() < 0.05
    # a PGP file (no residual stored in it) gives the same update
    save_parameterization(tmp_path / "p.npz", p)
    f = load_parameterization(tmp_path / "p.npz")
    qf = pgp_update.updated_parameterization(V, F, f, vec, scale=scale, faces=area)
    assert np.array_equal(qf.coords, q.coords) and qf.seam_residual == q.seam_residual


def test_local_update_errors():
    from geotex.param.pgp_update import updated_parameterization

    V, F = grid_plane(6, 6)
    f = np.tile([1.0, 0, 0], (len(F), 1))
    p = periodic_parameterization(V, F, f, scale=0.5)
    with pytest.raises(InputError, match="nothing to update"):
        updated_parameterization(V, F, p, f, scale=0.5, faces=[])
    V2, F2 = grid_plane(5, 5)
    with pytest.raises(InputError, match="another mesh"):
        updated_parameterization(V2, F2, p, np.tile([1.0, 0, 0], (len(F2), 1)), scale=0.5,
                                 faces=[0])


def test_cli_local_update(capsys, tmp_path):
    from geotex.param.pgp_store import load_parameterization

    mesh = write_mesh(tmp_path / "t.ply", Mesh(*torus(n_major=40, n_minor=16)))
    old, new = tmp_path / "old.npz", tmp_path / "new.npz"
    assert _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "0.3", "-o", old)[0] == 0
    code, text, err = _run(capsys, "pgp", mesh, "--up", "1,0,0", "--scale", "0.3",
                           "--update", old, "--around", "1.35,0,0", "--radius", "0.4",
                           "-o", new, "--json")
    assert code == 0, err
    d = json.loads(text)
    a, b = load_parameterization(old), load_parameterization(new)
    area = d["update"]["area_faces"]
    assert 0 < area < 0.5 * d["faces"] and d["seam_residual"] <= 1e-6
    dev = np.full(len(a.coords), np.inf)
    for turn in range(4):                       # equal up to a grid symmetry per face
        diff = b.coords - _rot(a.coords, turn)
        dev = np.minimum(dev, np.abs(diff - np.rint(diff[:, :1])).max(axis=(1, 2)))
    changed = (dev > 1e-9) & ~a.singular & ~b.singular
    assert 0 < changed.sum() <= area
    code, _, err = _run(capsys, "pgp", mesh, "--up", "1,0,0", "--scale", "0.3",
                        "--update", old, "-o", tmp_path / "x.npz")
    assert code == 2 and "--around" in err


def test_tile_image_relief_through_the_shared_displacement_path(capsys, tmp_path):
    from PIL import Image

    from geotex.check import check_mesh
    from geotex.io import read_mesh

    mesh = write_mesh(tmp_path / "s.obj", Mesh(*icosphere(2, radius=10.0)))
    pgp = tmp_path / "p.npz"
    assert _run(capsys, "pgp", mesh, "--up", "0,0,1", "--scale", "4", "-o", pgp)[0] == 0
    img = np.zeros((16, 16), np.uint8)
    img[:, :8] = 255                                     # stripes: half the tile raised
    Image.fromarray(img).save(tmp_path / "h.png")
    out = tmp_path / "r.stl"
    code, text, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "h.png",
                           "--param", pgp, "--displace", "0.5", "--faces", "20000",
                           "-o", out)
    assert code == 0, err
    m = read_mesh(out)
    assert check_mesh(m.vertices, m.faces).printable
    r = np.linalg.norm(m.vertices, axis=1)
    assert r.max() > 10.3 and r.min() > 9.5              # raised where white, nowhere sunk
    code, _, err = _run(capsys, "tile-image", mesh, "--image", tmp_path / "h.png",
                        "--param", pgp, "--displace", "0.5", "-o", tmp_path / "r.glb")
    assert code == 2 and "--displace" in err


def test_edge_contrast_is_about_one_without_seams_and_larger_with_one():
    from geotex.image.seams import edge_contrast

    V, F = grid_plane(30, 30)
    x = (np.arange(64) + 0.5) / 64
    img = (127.5 + 127.5 * np.sin(2 * np.pi * x)[None, :, None] * np.ones((64, 1, 3)))
    img = img.astype(np.uint8)
    uv = V[:, :2] * 3.0                                    # three periods, continuous
    smooth = edge_contrast(V, F, uv, F, img)
    assert 0.8 < smooth.ratio < 1.25
    # a seam: the right half's coordinates shifted by a quarter period
    right = V[F].mean(axis=1)[:, 0] > 0.5
    uvc = uv[F].copy()
    uvc[right, :, 0] += 0.25
    seam = edge_contrast(V, F, uvc.reshape(-1, 2), np.arange(3 * len(F)).reshape(-1, 3), img)
    assert seam.ratio > 1.1 * smooth.ratio          # one seam line among 2640 edges


def _s_gradients(V, F, coords):
    """Per-face gradient of the s coordinate, (m, 3)."""
    P = V[F]
    G = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]], axis=1)
    rhs = np.stack([coords[:, 1, 0] - coords[:, 0, 0], coords[:, 2, 0] - coords[:, 0, 0]], axis=1)
    a = np.linalg.solve(np.einsum("mij,mkj->mik", G, G), rhs[..., None])[..., 0]
    return np.einsum("mi,mij->mj", a, G)


def test_half_turn_symmetry_keeps_s_along_the_field():
    from geotex.data import sample_path
    from geotex.fields.directions import projected_direction_field
    from geotex.io import read_mesh

    m = read_mesh(sample_path("spot"))
    V, F = m.vertices, m.faces
    vec, _ = projected_direction_field(V, F, np.array([0.0, 1.0, 0.0]))     # Spot is y-up
    scale = float(np.linalg.norm(np.ptp(V, axis=0))) / 25
    across = {}
    for sym in (4, 2):
        p = periodic_parameterization(V, F, vec, scale=scale, seed=0, symmetry=sym)
        assert p.seam_residual <= 1e-9 and p.index_sum == 2
        g = _s_gradients(V, F, p.coords)
        ok = ~p.singular & (np.linalg.norm(vec, axis=1) > 0.5)
        cos = np.abs(np.einsum("ij,ij->i", g, vec)) / (
            np.linalg.norm(g, axis=1) * np.linalg.norm(vec, axis=1))
        across[sym] = int((cos[ok] < 0.5).sum())
    # quarter-turn combing swaps s and t over whole regions (measured 80 of 1260
    # faces); half turns keep s along the field (or against it) everywhere
    assert across[4] > 20 and across[2] == 0, across


def test_half_turn_symmetry_refuses_a_cross_field_and_bad_values():
    V, F = icosphere(2)
    cross = smooth_direction_field(V, F, symmetry=4, constraints=[], seed=0)
    with pytest.raises(InputError, match="symmetry 2 needs a field of symmetry 1 or 2"):
        periodic_parameterization(V, F, cross, scale=0.5, symmetry=2)
    for bad in (3, True, 1):
        with pytest.raises(InputError, match="symmetry must be 4"):
            periodic_parameterization(V, F, cross, scale=0.5, symmetry=bad)
