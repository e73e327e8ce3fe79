"""Material-space tiles (geotex.image.material) and ``geotex material``."""

import json

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import InputError
from geotex.fields.directions import projected_direction_field
from geotex.fields.scalar import material_field
from geotex.image.material.mapping import (bake_material_texture, default_material,
                                           material_locks, modulated_material, update_material)
from geotex.image.material.morph import morph_masks, periodic_signed_distance
from geotex.image.material.synthesis import indirection_colors, synthesize_layers
from geotex.image.material.tile import (TILE_FORMAT, MaterialTile, build_material_tile,
                                        build_periodicity_tile, load_tile, sample_tile,
                                        save_tile, tile_slices_image)
from geotex.image.material.tileable import luminance_of, tileable_image
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import icosphere
from geotex.param.pgp import periodic_parameterization


def _dots(n=48, seed=0):
    """Dark dots on a light beige ground, with noise and a left-right brightness ramp."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:n, 0:n]
    img = np.empty((n, n, 3))
    img[:] = [0.85, 0.75, 0.55]
    img *= (0.8 + 0.2 * xx / n)[:, :, None]
    for cy, cx in rng.uniform(0, n, size=(10, 2)):
        d = np.hypot(yy - cy, xx - cx)
        img[d < 3.5] = [0.15, 0.1, 0.08]
    img += rng.normal(0, 0.03, img.shape)
    return np.clip(np.rint(img * 255), 0, 255).astype(np.uint8)


def _stripes(n=48, seed=1):
    """Bright diagonal stripes on a dark blue ground, with noise."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:n, 0:n]
    on = ((xx + yy) % 12) < 4
    img = np.where(on[:, :, None], [0.95, 0.9, 0.3], [0.1, 0.15, 0.45])
    img = img + rng.normal(0, 0.03, img.shape)
    return np.clip(np.rint(img * 255), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def tile32():
    return build_material_tile(_dots(), _stripes(), size=32, layers=5, seed=3)


# ---------------------------------------------------------------- tileable inputs

def test_graph_cut_of_a_periodic_image_returns_its_period_exactly():
    rng = np.random.default_rng(0)
    period = rng.uniform(0, 1, size=(16, 16, 3))
    img = np.tile(period, (5, 5, 1))                   # 80 x 80 = size 64 + overlap 16
    t = tileable_image(np.rint(img * 255).astype(np.uint8), size=64, overlap=16)
    want = np.rint(np.tile(period, (4, 4, 1)) * 255) / 255
    assert np.abs(t.colors - want).max() < 1e-3


def test_tileable_wrap_difference_is_an_ordinary_neighbour_difference():
    img = _dots(96)
    t = tileable_image(img, size=64)
    c = t.colors
    inner = np.abs(np.diff(c, axis=1)).mean()
    wrap = np.abs(c[:, -1] - c[:, 0]).mean()
    wrap_v = np.abs(c[-1] - c[0]).mean()
    naive = img[:64, :64].astype(np.float64) / 255
    naive_wrap = np.abs(naive[:, -1] - naive[:, 0]).mean()
    assert wrap < 1.5 * inner and wrap_v < 1.5 * inner
    assert naive_wrap > 2 * wrap                       # the ramp shows on a plain crop
    assert t.mask.shape == (64, 64) and 0 < t.mask.mean() < 0.5


def test_mask_image_follows_the_same_cut_and_must_match_in_size():
    img = _dots(64)
    lum = luminance_of(img.astype(np.float64) / 255)
    mask = (lum < 0.4).astype(np.uint8) * 255
    t = tileable_image(img, size=32, mask=mask)
    # the cut mask marks the dark dots of the cut tile
    assert luminance_of(t.colors)[t.mask].mean() < luminance_of(t.colors)[~t.mask].mean() - 0.3
    with pytest.raises(InputError, match="same size"):
        tileable_image(img, size=32, mask=mask[:40])
    with pytest.raises(InputError, match="threshold"):
        tileable_image(img, size=32, threshold=1.5)


# ---------------------------------------------------------------- morph

def test_signed_distance_is_periodic_and_signed():
    m = np.zeros((20, 20), bool)
    m[0:3, 0:3] = True                                 # a feature across the corner
    d = periodic_signed_distance(m)
    assert d[1, 1] > 0 and d[10, 10] < 0
    assert d[19, 19] == pytest.approx(d[3, 3])         # wraps: same distance both sides


@pytest.mark.parametrize("area", ["linear", "monotone"])
def test_morph_ends_on_the_inputs_with_monotone_area(area):
    a = np.zeros((32, 32), bool)
    a[4:9, 4:9] = a[20:25, 18:23] = True
    b = np.zeros((32, 32), bool)
    b[:, 10:16] = True
    mm = morph_masks(a, b, layers=6, area=area)
    assert np.array_equal(mm.masks[0], a) and np.array_equal(mm.masks[-1], b)
    d = np.diff(mm.areas)
    assert (d >= 0).all() or (d <= 0).all()
    assert mm.areas[0] == a.sum() and mm.areas[-1] == b.sum()
    assert (np.diff(mm.steps) >= 0).all() and mm.steps[0] == 0


def test_morph_errors():
    a = np.zeros((8, 8), bool)
    a[2:4, 2:4] = True
    with pytest.raises(InputError, match="same size"):
        morph_masks(a, np.ones((9, 9), bool))
    with pytest.raises(InputError, match="empty or full"):
        morph_masks(a, np.zeros((8, 8), bool))


# ---------------------------------------------------------------- synthesis and tiles

def test_synthesis_follows_the_target_mask():
    src = tileable_image(_dots(64), size=32)
    stripes = np.zeros((32, 32), bool)
    stripes[:, ::8] = stripes[:, 1::8] = stripes[:, 2::8] = True
    maps = synthesize_layers(src.colors, src.mask, np.stack([src.mask, stripes]), seed=0)
    col = indirection_colors(src.colors, maps)
    assert np.array_equal(col[0], src.colors)          # own mask: the identity stays
    lum = luminance_of(col[1])
    assert lum[stripes].mean() < lum[~stripes].mean() - 0.2


def test_tile_periodic_to_the_texel_and_smooth_in_m(tile32):
    rng = np.random.default_rng(0)
    s, t, m = rng.uniform(-2, 2, 200), rng.uniform(-2, 2, 200), rng.uniform(0, 1, 200)
    base = sample_tile(tile32, s, t, m)
    # wrapped lookups agree up to the rounding of s mod 1 (about 1e-16 of a tile)
    assert np.abs(base - sample_tile(tile32, s + 1.0, t, m)).max() < 1e-9
    assert np.abs(base - sample_tile(tile32, s, t - 3.0, m)).max() < 1e-9
    # the tile's own texels: the last column is followed by the first (zero wrap difference)
    n = tile32.size
    row = sample_tile(tile32, (np.arange(2 * n) + 0.5) / n, np.full(2 * n, 0.5 / n),
                      np.zeros(2 * n))
    assert np.array_equal(row[:n], row[n:])
    # texel centres sample the layer exactly; between layers: the linear blend
    n = tile32.size
    i, j = 5, 7
    c = sample_tile(tile32, [(j + 0.5) / n], [(i + 0.5) / n], [0.125])[0]
    want = 0.5 * (tile32.layers[1, i, j].astype(float) + tile32.layers[0, i, j])
    assert np.allclose(c, want, atol=1e-3)


def test_tile_ends_are_the_inputs_and_areas_are_monotone(tile32):
    assert tile32.layers.shape == (5, 32, 32, 3) and tile32.masks.shape == (5, 32, 32)
    a = np.asarray(tile32.metadata["mask_areas"])
    assert (np.diff(a) >= 0).all() or (np.diff(a) <= 0).all()
    fresh = tileable_image(_dots(), size=32)
    assert np.array_equal(tile32.layers[0], np.clip(np.rint(fresh.colors * 255), 0, 255)
                          .astype(np.uint8))


def test_histogram_distance_beats_a_cross_fade_with_the_select_blend(tile32):
    sel = build_material_tile(_dots(), _stripes(), size=32, layers=5, seed=3, blend="select")
    ours = np.asarray(sel.metadata["histogram_distance"][1:-1])
    fade = np.asarray(sel.metadata["cross_fade_histogram_distance"][1:-1])
    assert (ours < fade).all()
    # same masks, same syntheses: only the combination differs
    assert np.array_equal(sel.masks, tile32.masks)
    assert np.array_equal(sel.layers[[0, -1]], tile32.layers[[0, -1]])


def test_tile_is_deterministic(tile32):
    again = build_material_tile(_dots(), _stripes(), size=32, layers=5, seed=3)
    assert again.layers.tobytes() == tile32.layers.tobytes()
    assert again.masks.tobytes() == tile32.masks.tobytes()


def test_periodicity_tile_shares_the_mask_and_varies_the_details():
    t = build_periodicity_tile(_dots(64), size=32, layers=3, seed=0)
    assert (t.masks == t.masks[0]).all()
    assert not np.array_equal(t.layers[0], t.layers[1])
    again = build_periodicity_tile(_dots(64), size=32, layers=3, seed=0)
    assert again.layers.tobytes() == t.layers.tobytes()


def test_tile_file_round_trip_and_errors(tmp_path, tile32):
    p = save_tile(tmp_path / "t.npz", tile32)
    again = save_tile(tmp_path / "again.npz", build_material_tile(_dots(), _stripes(), size=32,
                                                                   layers=5, seed=3))
    assert p.read_bytes() == again.read_bytes()        # no timings in the file
    back = load_tile(p)
    assert np.array_equal(back.layers, tile32.layers) and np.array_equal(back.masks,
                                                                         tile32.masks)
    with np.load(p) as data:
        assert json.loads(str(data["metadata"]))["format"] == TILE_FORMAT
    np.savez(tmp_path / "other.npz", metadata=np.array('{"format": "something/9"}'),
             layers=tile32.layers)
    with pytest.raises(InputError, match="not a geotex material tile"):
        load_tile(tmp_path / "other.npz")
    with pytest.raises(InputError, match="no such"):
        load_tile(tmp_path / "missing.npz")
    img = tile_slices_image(tile32)
    assert img.shape == (2 * 32 + 4, 5 * 32 + 4 * 4, 3)


# ---------------------------------------------------------------- mapping

def _two_colour_tile():
    layers = np.zeros((2, 8, 8, 3), np.uint8)
    layers[0, :, :] = [255, 0, 0]
    layers[1, :, :] = [0, 0, 255]
    return MaterialTile(layers=layers, masks=np.zeros((2, 8, 8), bool))


def test_bake_puts_the_material_where_the_constraints_say():
    V, F = icosphere(3)
    vec, _ = projected_direction_field(V, F, [0.0, 0.0, 1.0])
    p = periodic_parameterization(V, F, vec, scale=0.5)
    m = default_material(V, F, up=[0, 0, 1])
    mesh = bake_material_texture(V, F, p, m, _two_colour_tile(), field=vec, resolution=256)
    assert mesh.texture.shape[2] == 3 and mesh.uv.min() >= 0 and mesh.uv.max() <= 1
    H, W = mesh.texture.shape[:2]
    uvc = mesh.uv[mesh.uv_faces].mean(axis=1)
    px = mesh.texture[((1 - uvc[:, 1]) * H).astype(int).clip(0, H - 1),
                      (uvc[:, 0] * W).astype(int).clip(0, W - 1)].astype(float)
    z = V[F].mean(axis=1)[:, 2]
    top, bottom = z > 0.8, z < -0.8
    assert px[top, 2].mean() > 200 and px[top, 0].mean() < 60
    assert px[bottom, 0].mean() > 200 and px[bottom, 2].mean() < 60


def test_material_locks_and_errors():
    V, F = icosphere(2)
    v, val = material_locks(V, F, [{"point": [0, 0, 1], "material": 1.0, "radius": 0.3},
                                   {"face": 0, "material": 0.25},
                                   {"face": 1, "direction": [1, 0, 0]}])
    assert set(val) == {1.0, 0.25} and np.isin(F[0], v).all()
    with pytest.raises(InputError, match=r"constraints\[0\] material 1.5 lies outside"):
        material_locks(V, F, [{"vertex": 0, "material": 1.5}])
    with pytest.raises(InputError, match="no 'vertex'"):
        material_locks(V, F, [{"material": 0.5}])


def test_local_update_changes_only_the_effect_area():
    V, F = icosphere(4)
    top = int(np.argmax(V[:, 2]))
    bottom = int(np.argmin(V[:, 2]))
    m0 = material_field(V, F, [top, bottom], [1.0, 0.0])
    east = int(np.argmax(V[:, 0]))
    up = update_material(V, F, m0, [east], [0.0], max_distance=0.6,
                         keep_vertices=[top, bottom])
    inside = np.zeros(len(V), bool)
    inside[F[up.faces].ravel()] = True
    assert np.array_equal(up.material[~inside], m0[~inside])
    assert up.material[east] == 0.0 and up.free_vertices.size > 0
    assert np.abs(up.material - m0)[inside].max() > 0.1
    # an unbounded brush re-solves everything: the global solution
    full = update_material(V, F, m0, [east], [0.0], max_distance=np.inf,
                           keep_vertices=[top, bottom])
    want = material_field(V, F, [top, bottom, east], [1.0, 0.0, 0.0])
    assert np.allclose(full.material, want, atol=1e-9)


def test_modulated_material_stays_in_range_and_is_seeded():
    V, _ = icosphere(3)
    a = modulated_material(V, np.full(len(V), 0.5), amplitude=0.5, wavelength=0.7, seed=1)
    b = modulated_material(V, np.full(len(V), 0.5), amplitude=0.5, wavelength=0.7, seed=1)
    assert np.array_equal(a, b) and a.min() >= 0 and a.max() <= 1 and np.ptp(a) > 0.5
    with pytest.raises(InputError, match="wavelength"):
        modulated_material(V, a, wavelength=0.0)


# ---------------------------------------------------------------- CLI

def _png(path, img):
    from PIL import Image

    Image.fromarray(img).save(path)
    return str(path)


def test_cli_tile_and_map(tmp_path, capsys):
    a = _png(tmp_path / "a.png", _dots())
    b = _png(tmp_path / "b.png", _stripes())
    tile = tmp_path / "tile.npz"
    prev = tmp_path / "slices.png"
    assert main(["material", "tile", a, b, "-o", str(tile), "--size", "32", "--layers", "3",
                 "--preview", str(prev), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["layers"] == 3 and tile.is_file() and prev.is_file()
    V, F = icosphere(2)
    mesh_path = tmp_path / "s.obj"
    write_mesh(mesh_path, Mesh(V, F))
    cons = tmp_path / "c.json"
    cons.write_text(json.dumps([{"point": V[0].tolist(), "material": 1.0},
                                {"point": V[5].tolist(), "material": 0.0},
                                {"face": 3, "direction": [1, 0, 0]}]))
    glb = tmp_path / "out.glb"
    assert main(["material", "map", str(mesh_path), "--tile", str(tile), "--constraints",
                 str(cons), "--scale", "0.5", "--resolution", "128", "-o", str(glb),
                 "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["material_range"] == [0.0, 1.0]
    back = read_mesh(glb)
    assert back.texture is not None and back.n_faces == F.shape[0]
    # the relief: the baked texture's luminance through the shared displacement path
    stl = tmp_path / "relief.stl"
    assert main(["material", "map", str(mesh_path), "--tile", str(tile), "--constraints",
                 str(cons), "--scale", "0.5", "--resolution", "128", "--displace", "0.05",
                 "--faces", "20000", "-o", str(stl)]) == 0
    relief = read_mesh(stl)
    assert check_mesh(relief.vertices, relief.faces).printable
    assert np.linalg.norm(relief.vertices, axis=1).max() > 1.01
    capsys.readouterr()
    assert main(["material", "map", str(mesh_path), "--tile", str(tile), "--up", "0,0,1",
                 "--scale", "0.5", "--displace", "0.05", "-o", str(tmp_path / "x.glb")]) == 2
    assert "--displace" in capsys.readouterr().err


@pytest.mark.parametrize("case, needle", [
    ("mask", "--mask-a"), ("threshold", "--threshold-a"), ("tile", "--tile"),
    ("material", "lies outside [0, 1]"), ("overwrite", "refusing to overwrite"),
    ("size", "--size"),
])
def test_cli_errors_are_one_line(tmp_path, capsys, case, needle):
    a = _png(tmp_path / "a.png", _dots())
    b = _png(tmp_path / "b.png", _stripes())
    V, F = icosphere(1)
    mesh_path = tmp_path / "s.obj"
    write_mesh(mesh_path, Mesh(V, F))
    if case == "mask":
        mk = _png(tmp_path / "m.png", np.zeros((20, 20, 3), np.uint8))
        argv = ["material", "tile", a, b, "--mask-a", mk, "-o", str(tmp_path / "t.npz")]
    elif case == "threshold":
        argv = ["material", "tile", a, b, "--threshold-a", "2", "-o", str(tmp_path / "t.npz")]
    elif case == "size":
        argv = ["material", "tile", a, b, "--size", "30", "-o", str(tmp_path / "t.npz")]
    elif case == "tile":
        bad = tmp_path / "bad.npz"
        np.savez(bad, x=np.zeros(2))
        argv = ["material", "map", str(mesh_path), "--tile", str(bad), "--up", "0,0,1",
                "--scale", "0.5", "-o", str(tmp_path / "o.glb")]
    elif case == "material":
        save_tile(tmp_path / "t.npz", _two_colour_tile())
        cons = tmp_path / "c.json"
        cons.write_text(json.dumps([{"vertex": 0, "material": 2.0}]))
        argv = ["material", "map", str(mesh_path), "--tile", str(tmp_path / "t.npz"),
                "--constraints", str(cons), "--scale", "0.5", "-o", str(tmp_path / "o.glb")]
    else:
        argv = ["material", "tile", a, b, "-o", a]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("geotex: error:") and needle in err
    assert not (tmp_path / "o.glb").exists()


def test_field_arms_predict_the_corner_coordinates():
    from geotex.image.material.mapping import field_arms

    V, F = icosphere(3)
    vec, _ = projected_direction_field(V, F, [0.0, 0.0, 1.0])
    p = periodic_parameterization(V, F, vec, scale=0.4)
    a, b, S = field_arms(V, F, p, vec)
    ok = ~p.singular
    d = V[F[:, 1]] - V[F[:, 0]]
    pred = np.stack([np.einsum("fd,fd->f", d, a), np.einsum("fd,fd->f", d, b)], axis=1) / S[:, None]
    got = p.coords[:, 1] - p.coords[:, 0]
    err = np.linalg.norm(pred - got, axis=1)[ok]
    step = np.linalg.norm(got, axis=1)[ok]
    # PGP trades size for seamlessness (its scale error is ~0.35 here): loose bound
    assert np.median(err) < 0.4 * np.median(step)
    # a flipped t arm would not predict them
    flip = np.stack([pred[:, 0], -pred[:, 1]], axis=1)
    assert np.median(np.linalg.norm(flip - got, axis=1)[ok]) > 3 * np.median(err)
