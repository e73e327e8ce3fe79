"""Lapped textures: atlas, compositing, textured files, relief solids, the CLI."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import InputError
from geotex.image import (build_atlas, composite_at, displace, lapped_texture,
                          rasterize_triangles, texture_patches, textured_mesh)
from geotex.io import read_mesh, write_mesh
from geotex.mesh.primitives import icosphere
from geotex.mesh.record import Mesh


def _image(seed=0, size=48):
    return (np.random.default_rng(seed).random((size, size, 3)) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def sphere_lapped():
    V, F = icosphere(3)
    lt = lapped_texture(V, F, texture_patches(_image()), scale=0.8, seed=2)
    return V, F, lt


def test_atlas_charts_do_not_overlap(sphere_lapped):
    V, F, _ = sphere_lapped
    at = build_atlas(V, F, resolution=256)
    assert at.uv.min() >= 0.0 and at.uv.max() <= 1.0 and at.n_charts >= 1
    Q = at.uv[at.uv_faces]
    tri = np.stack([Q[..., 0] * at.width, (1.0 - Q[..., 1]) * at.height], axis=-1)
    texel, face, _ = rasterize_triangles(tri, at.width, at.height, strict=True)
    assert np.unique(face).size > 0.9 * len(F)           # nearly every face gets texels
    assert np.unique(texel).size == texel.size            # no texel inside two faces
    # and exactly: no two faces' uv triangles overlap (sampled finely)
    fine = rasterize_triangles(tri * 4, at.width * 4, at.height * 4, strict=True)[0]
    assert np.unique(fine).size == fine.size
    area = 0.5 * np.abs((Q[:, 1, 0] - Q[:, 0, 0]) * (Q[:, 2, 1] - Q[:, 0, 1])
                        - (Q[:, 2, 0] - Q[:, 0, 0]) * (Q[:, 1, 1] - Q[:, 0, 1]))
    assert (area > 0).all()


def test_rasterize_counts_the_texels_of_a_square():
    tri = np.array([[[0, 0], [8, 0], [8, 8]], [[0, 0], [8, 8], [0, 8]]], dtype=float)
    texel, face, bary = rasterize_triangles(tri, 8, 8)
    assert np.unique(texel).size == 64
    assert np.allclose(bary.sum(axis=1), 1.0)


def test_compiled_rasterizer_gives_the_same_texels_bit_for_bit():
    rng = np.random.default_rng(3)
    for trial in range(40):
        T = rng.uniform(-6.0, 30.0, (int(rng.integers(0, 25)), 3, 2))
        if trial % 2:
            T = np.round(T)                      # edges through texel centres
        if T.shape[0] > 1:
            T[0, 2] = T[0, 1]                    # a degenerate triangle
            T[1] = T[1, ::-1]                    # a reversed one
        for strict in (False, True):
            a = rasterize_triangles(T, 24, 20, strict=strict)
            b = rasterize_triangles(T, 24, 20, strict=strict, fast=True)
            for x, y in zip(a, b):
                assert x.dtype == y.dtype and x.shape == y.shape
                assert x.tobytes() == y.tobytes()


def test_single_colour_texture_composites_to_that_colour(sphere_lapped):
    V, F, _ = sphere_lapped
    img = np.zeros((32, 32, 3), np.uint8)
    img[...] = (200, 40, 10)
    lt = lapped_texture(V, F, texture_patches(img, mask="circle"), scale=0.8, seed=0)
    m = textured_mesh(V, F, lt, resolution=128)
    assert m.texture.shape[2] == 3
    assert np.abs(m.texture.astype(int) - [200, 40, 10]).max() <= 1


def test_composite_is_opaque_everywhere_on_a_complete_texture(sphere_lapped):
    V, F, lt = sphere_lapped
    rng = np.random.default_rng(0)
    faces = rng.integers(0, len(F), 2000)
    b = rng.dirichlet(np.ones(3), 2000)
    rgba = composite_at(lt, faces, b)
    assert rgba.shape == (2000, 4) and rgba[:, 3].min() > 0.99
    with pytest.raises(InputError):
        composite_at(lt, [len(F)], [[1.0, 0, 0]])


@pytest.mark.parametrize("ext", [".glb", ".obj"])
def test_textured_files_round_trip(sphere_lapped, tmp_path, ext):
    V, F, lt = sphere_lapped
    m = textured_mesh(V, F, lt, resolution=128)
    path = write_mesh(tmp_path / f"tex{ext}", m)
    back = read_mesh(path)
    assert back.n_faces == len(F) and back.has_uv and back.texture is not None
    assert back.texture.shape[:2] == m.texture.shape[:2]
    if ext == ".obj":
        assert (tmp_path / "tex.mtl").is_file() and (tmp_path / "tex.png").is_file()


def test_relief_is_printable_and_raised(sphere_lapped):
    V, F, lt = sphere_lapped
    Vd, Fd = displace(V, F, lt, depth=0.05, edge_length=0.05)
    report = check_mesh(Vd, Fd)
    assert report.printable, report.reasons
    r = np.linalg.norm(Vd, axis=1)
    assert r.min() > 0.98 and 1.02 < r.max() <= 1.05 + 1e-9
    with pytest.raises(InputError, match="depth"):
        displace(V, F, lt, depth=0.0)
    V2, F2 = icosphere(2)
    with pytest.raises(InputError, match="made for"):
        displace(V2, F2, lt, depth=0.01)


# ------------------------------------------------------------------ CLI

@pytest.fixture()
def files(tmp_path):
    V, F = icosphere(3)
    base = write_mesh(tmp_path / "ball.obj", Mesh(V, F))
    img = tmp_path / "tex.png"
    Image.fromarray(_image()).save(img)
    return tmp_path, base, img


def test_cli_writes_a_textured_glb_and_is_deterministic(files, capsys):
    tmp, base, img = files
    args = ["lapped", str(base), "--image", str(img), "--scale", "0.9", "--resolution", "128"]
    assert main(args + ["-o", str(tmp / "a.glb"), "--pastes", str(tmp / "a.npz")]) == 0
    assert main(args + ["-o", str(tmp / "b.glb")]) == 0
    assert (tmp / "a.glb").read_bytes() == (tmp / "b.glb").read_bytes()
    assert (tmp / "a.npz").is_file()
    assert main(args + ["--seed", "1", "-o", str(tmp / "c.glb")]) == 0
    assert (tmp / "a.glb").read_bytes() != (tmp / "c.glb").read_bytes()
    assert "wrote" in capsys.readouterr().out


def test_cli_field_options(files):
    tmp, base, img = files
    for field in ("up", "curvature"):
        out = tmp / f"{field}.obj"
        assert main(["lapped", str(base), "--image", str(img), "--field", field, "--scale",
                     "0.9", "--resolution", "64", "-o", str(out)]) == 0
        assert out.is_file() and (tmp / f"{field}.png").is_file()
    field_file = tmp / "f.npz"
    assert main(["field", str(base), "--up", "0,0,1", "-o", str(field_file)]) == 0
    assert main(["lapped", str(base), "--image", str(img), "--field", str(field_file),
                 "--scale", "0.9", "--resolution", "64", "-o", str(tmp / "ff.glb")]) == 0


def test_cli_relief_is_printable(files, capsys):
    tmp, base, img = files
    out = tmp / "relief.stl"
    assert main(["lapped", str(base), "--image", str(img), "--scale", "0.9",
                 "--displace", "0.03", "-o", str(out)]) == 0
    assert check_mesh(read_mesh(out).vertices, read_mesh(out).faces).printable
    assert "printable" in capsys.readouterr().out


@pytest.mark.parametrize("case,message", [
    ("broken", "cannot read the image"),
    ("missing", "no such image file"),
    ("emptymask", "the mask is empty"),
    ("ext", "written as .glb or .obj"),
    ("dispext", "use .stl or .3mf"),
    ("overwrite", "refusing to overwrite"),
    ("field", "--field"),
])
def test_cli_errors_are_one_line(files, capsys, case, message):
    tmp, base, img = files
    out = tmp / "out.glb"
    args = ["lapped", str(base), "--image", str(img), "-o", str(out)]
    if case == "broken":
        bad = tmp / "bad.png"
        bad.write_text("no pixels here")
        args[3] = str(bad)
    elif case == "missing":
        args[3] = str(tmp / "nothere.png")
    elif case == "emptymask":
        mask = tmp / "mask.png"
        Image.fromarray(np.zeros((48, 48), np.uint8)).save(mask)
        args += ["--mask", str(mask)]
    elif case == "ext":
        args[-1] = str(tmp / "out.stl")
    elif case == "dispext":
        args += ["--displace", "0.1"]
    elif case == "overwrite":
        args[-1] = str(tmp / "tex.obj")                  # would write tex.png over the image
    elif case == "field":
        args += ["--field", "sideways"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("geotex: error:") and message in err and "\n" not in err
    assert "Traceback" not in err
    assert not out.exists() and not (tmp / "out.stl").exists()
    assert sorted(p.name for p in tmp.iterdir() if p.suffix in (".glb", ".stl", ".obj")) \
        == ["ball.obj"]
