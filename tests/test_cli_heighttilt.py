import numpy as np
import pytest

from geotex.cli import main
from geotex.heighttilt import base_normals, load_texture, spiky_sphere
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh


@pytest.fixture
def files(tmp_path):
    V0, F, Vs = spiky_sphere(subdivisions=3, spikes=10, seed=2)
    return (write_mesh(tmp_path / "spiky.ply", Mesh(V0, F)),
            write_mesh(tmp_path / "base.ply", Mesh(Vs, F)), V0, F, Vs)


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_extract_apply_round_trip(capsys, tmp_path, files):
    textured, base, V0, F, Vs = files
    tex = tmp_path / "t.npz"
    assert run(capsys, "heighttilt", "extract", textured, "--base", base, "-o", tex)[0] == 0
    out = tmp_path / "back.ply"
    assert run(capsys, "heighttilt", "apply", tex, "--base", base, "-o", out)[0] == 0
    V = read_mesh(out).vertices
    assert np.abs(V - V0).max() <= 1e-9 * np.linalg.norm(np.ptp(V0, axis=0))


def test_set_tilt_from_the_command_line(capsys, tmp_path, files):
    textured, base, V0, F, Vs = files
    tex, tilted, out = tmp_path / "t.npz", tmp_path / "t30.npz", tmp_path / "o.ply"
    run(capsys, "heighttilt", "extract", textured, "--base", base, "-o", tex)
    assert run(capsys, "heighttilt", "edit", tex, "--set-tilt", "30", "--base", base,
               "-o", tilted)[0] == 0
    run(capsys, "heighttilt", "apply", tilted, "--base", base, "-o", out)
    d = read_mesh(out).vertices - Vs
    h = load_texture(tilted).height
    big = np.abs(h) > 0.2 * np.abs(h).max()
    n = base_normals(Vs, F)
    cos = np.einsum("ij,ij->i", d[big], n[big]) / np.linalg.norm(d[big], axis=1)
    angles = np.degrees(np.arccos(np.clip(np.abs(cos), -1, 1)))
    assert np.allclose(angles, 30.0, atol=1.0)


def test_smoothed_base_and_scale_height(capsys, tmp_path, files):
    textured, base, *_ = files
    tex, base_out, half = tmp_path / "t.npz", tmp_path / "b.stl", tmp_path / "h.npz"
    code, text, _ = run(capsys, "heighttilt", "extract", textured, "--smooth-steps", "2",
                        "-o", tex, "--base-out", base_out)
    assert code == 0 and base_out.exists()
    assert run(capsys, "heighttilt", "edit", tex, "--scale-height", "0.5", "-o", half)[0] == 0
    assert np.allclose(load_texture(half).height, 0.5 * load_texture(tex).height)


@pytest.mark.parametrize("argv, message", [
    (["edit", "{tex}", "--wrap", "2", "-o", "{out}"], "need --base"),
    (["edit", "{tex}", "--wiggle", "10", "--base", "{base}", "-o", "{out}"], "--direction"),
    (["edit", "{tex}", "--scale-height", "2", "-o", "{tmp}/x.ply"], ".npz"),
    (["apply", "{tex}", "--base", "{tmp}/missing.ply", "-o", "{tmp}/o.ply"], "no such file"),
    (["extract", "{textured}", "--smooth-steps", "0", "-o", "{out}"], "at least 1"),
])
def test_usage_errors(capsys, tmp_path, files, argv, message):
    textured, base, *_ = files
    tex = tmp_path / "t.npz"
    run(capsys, "heighttilt", "extract", textured, "--base", base, "-o", tex)
    subs = dict(tex=tex, out=tmp_path / "o.npz", base=base, tmp=tmp_path, textured=textured)
    code, out, err = run(capsys, "heighttilt", *[a.format(**subs) for a in argv])
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "o.npz").exists() and not (tmp_path / "o.ply").exists()


def test_connectivity_mismatch(capsys, tmp_path, files):
    textured, base, V0, F, Vs = files
    other = write_mesh(tmp_path / "other.ply", Mesh(Vs, F[:, [0, 2, 1]]))
    code, _, err = run(capsys, "heighttilt", "extract", textured, "--base", other,
                       "-o", tmp_path / "t.npz")
    assert code == 2 and "same faces" in err


def test_transfer_onto_a_finer_sphere(capsys, tmp_path):
    from geotex.mesh.primitives import icosphere
    from geotex.testing import hausdorff_distance
    V0, F, Vs = spiky_sphere(subdivisions=3, spikes=6, height=0.2, width=0.4, lean_degrees=30,
                             seed=1)
    src = write_mesh(tmp_path / "src.ply", Mesh(V0, F))
    base = write_mesh(tmp_path / "base.ply", Mesh(Vs, F))
    Vd, Fd = icosphere(4)
    dst = write_mesh(tmp_path / "dst.ply", Mesh(Vd, Fd))
    tex, out, mesh = tmp_path / "t.npz", tmp_path / "t2.npz", tmp_path / "moved.ply"
    run(capsys, "heighttilt", "extract", src, "--base", base, "-o", tex)
    code, text, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                          "--target", dst, "-o", out, "--apply", mesh)
    assert code == 0, err
    assert load_texture(out).height.shape == (len(Vd),)
    moved = read_mesh(mesh)
    d, _ = hausdorff_distance(moved.vertices, moved.faces, V0, F)
    assert d < 0.25 * 0.2          # within a quarter of the bump height


@pytest.fixture
def planar_files(tmp_path, capsys):
    from geotex.heighttilt import bumpy_plane
    from geotex.mesh.primitives import icosphere
    V0, F, Vs = bumpy_plane(12, 12, seed=1, periodic=True, radius=0.15, bumps=5, height=0.1)
    src = write_mesh(tmp_path / "plane.ply", Mesh(V0, F))
    base = write_mesh(tmp_path / "flat.ply", Mesh(Vs, F))
    Vd, Fd = icosphere(1)
    dst = write_mesh(tmp_path / "ball.ply", Mesh(Vd, Fd))
    tex = tmp_path / "t.npz"
    assert run(capsys, "heighttilt", "extract", src, "--base", base, "-o", tex)[0] == 0
    return tex, base, dst


def test_planar_transfer_onto_a_sphere(capsys, tmp_path, planar_files):
    from geotex.heighttilt import apply_texture
    tex, base, dst = planar_files
    out, refined, mesh = tmp_path / "s.npz", tmp_path / "refined.ply", tmp_path / "bumpy.ply"
    code, text, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                          "--target", dst, "--planar", "--scale", "1.2", "--field", "smooth",
                          "-o", out, "--base-out", refined, "--apply", mesh)
    assert code == 0, err
    assert "refined to" in text and "patches" in text
    b, m = read_mesh(refined), read_mesh(mesh)
    t = load_texture(out)
    assert t.height.shape == (b.n_vertices,) and np.array_equal(m.faces, b.faces)
    assert np.allclose(apply_texture(b.vertices, b.faces, t), m.vertices, atol=1e-9)
    assert np.abs(t.height).max() > 0.5 * 1.2 * 0.1      # bumps arrived, scaled


@pytest.mark.parametrize("extra, message", [
    (["--planar", "-o", "{tmp}/o.npz", "--base-out", "{tmp}/b.ply"], "--scale"),
    (["--planar", "--scale", "1", "-o", "{tmp}/o.npz"], "--base-out"),
    (["--scale", "1", "-o", "{tmp}/o.npz"], "--planar"),
    (["--planar", "--scale", "1", "--field", "x.txt", "-o", "{tmp}/o.npz",
      "--base-out", "{tmp}/b.ply"], "field file"),
    (["--planar", "--scale", "-1", "-o", "{tmp}/o.npz", "--base-out", "{tmp}/b.ply"], "scale"),
])
def test_planar_usage_errors(capsys, tmp_path, planar_files, extra, message):
    tex, base, dst = planar_files
    code, _, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                       "--target", dst, *[a.format(tmp=tmp_path) for a in extra])
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "o.npz").exists() and not (tmp_path / "b.ply").exists()


def test_planar_transfer_with_a_field_file(capsys, tmp_path, planar_files):
    tex, base, dst = planar_files
    field, out, refined = tmp_path / "f.npz", tmp_path / "s.npz", tmp_path / "r.ply"
    assert run(capsys, "field", dst, "--up", "1,0,0", "-o", field)[0] == 0
    code, _, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                       "--target", dst, "--planar", "--scale", "1.2", "--field", field,
                       "--refine", "subdivide", "-o", out, "--base-out", refined)
    assert code == 0, err
    assert load_texture(out).height.shape == (read_mesh(refined).n_vertices,)


@pytest.mark.parametrize("argv, message", [
    (["extract", "{textured}", "-o", "{tmp}/o.npz", "--base-out", "{tmp}/b.xyz"], ".xyz"),
    (["transfer", "{tex}", "--source-base", "{base}", "--target", "{base}", "-o", "{tmp}/o.npz",
      "--apply", "{tmp}/b.npz"], ".npz"),
    (["apply", "{tex}", "--base", "{base}", "-o", "{tmp}/b.xyz"], ".xyz"),
    (["edit", "{tex}", "--set-tilt", "30", "--direction", "0,0,0", "--base", "{base}",
      "-o", "{tmp}/o.npz"], "non-zero"),
    (["edit", "{tex}", "--scale-height", "2", "--phase", "1", "-o", "{tmp}/o.npz"],
     "--phase belongs to --wiggle"),
    (["edit", "{tex}", "--set-tilt", "20", "--phase", "1", "--base", "{base}",
      "-o", "{tmp}/o.npz"], "--phase belongs to --wiggle"),
    (["edit", "{tex}", "--scale-height", "2", "--direction", "1,0,0", "-o", "{tmp}/o.npz"],
     "--direction belongs"),
    (["apply", "{textured}", "--base", "{base}", "-o", "{tmp}/b.ply"], "not a zip archive"),
])
def test_bad_outputs_and_options_fail_before_writing_anything(capsys, tmp_path, files, argv,
                                                              message):
    textured, base, *_ = files
    tex = tmp_path / "t.npz"
    run(capsys, "heighttilt", "extract", textured, "--base", base, "-o", tex)
    before = sorted(p.name for p in tmp_path.iterdir())
    subs = dict(tex=tex, base=base, tmp=tmp_path, textured=textured)
    code, out, err = run(capsys, "heighttilt", *[a.format(**subs) for a in argv])
    assert code == 2 and message in err and err.count("\n") == 1, err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before     # nothing written


def test_a_failing_second_output_removes_the_first(capsys, tmp_path, files, monkeypatch):
    import geotex.heighttilt as ht
    from geotex.errors import MeshFileError
    textured, base, *_ = files

    def broken(path, tex):
        raise MeshFileError(path, "cannot write: disk full")

    monkeypatch.setattr(ht, "save_texture", broken)
    code, _, err = run(capsys, "heighttilt", "extract", textured, "--smooth-steps", "1",
                       "-o", tmp_path / "t.npz", "--base-out", tmp_path / "b.ply")
    assert code == 2 and "disk full" in err
    assert not (tmp_path / "b.ply").exists() and not (tmp_path / "t.npz").exists()


def test_wrap_and_wiggle_frames_from_the_command_line(capsys, tmp_path, files):
    from geotex.heighttilt import wiggle, wrap
    textured, base, V0, F, Vs = files
    tex = tmp_path / "t.npz"
    run(capsys, "heighttilt", "extract", textured, "--base", base, "-o", tex)
    t = load_texture(tex)
    frames = []
    for k, phase in enumerate(("0", "1.5")):
        out = tmp_path / f"w{k}.npz"
        assert run(capsys, "heighttilt", "edit", tex, "--wiggle", "25", "--phase", phase,
                   "--direction", "0,0,1", "--base", base, "-o", out)[0] == 0
        ref = wiggle(Vs, F, t, amplitude=25, phase=float(phase), direction=[0, 0, 1])
        np.testing.assert_allclose(load_texture(out).tilt, ref.tilt, atol=1e-12)
        frames.append(load_texture(out).tilt)
    assert np.abs(frames[0] - frames[1]).max() > 1e-3          # the phase moves the wave
    out = tmp_path / "wrap.npz"
    assert run(capsys, "heighttilt", "edit", tex, "--wrap", "2", "--base", base, "-o", out)[0] == 0
    np.testing.assert_allclose(load_texture(out).tilt, wrap(Vs, F, t, k=2.0).tilt, atol=1e-12)


def test_apply_on_a_deformed_base_keeps_elements_with_original(capsys, tmp_path, files):
    from geotex.heighttilt import displacements, reapplied, scale_base
    textured, base, V0, F, Vs = files
    tex = tmp_path / "t.npz"
    run(capsys, "heighttilt", "extract", textured, "--base", base, "-o", tex)
    Vd = scale_base(Vs, 2.0)
    big = write_mesh(tmp_path / "big.ply", Mesh(Vd, F))
    kept, plain = tmp_path / "kept.ply", tmp_path / "plain.ply"
    assert run(capsys, "heighttilt", "apply", tex, "--base", big, "--original", base,
               "-o", kept)[0] == 0
    assert run(capsys, "heighttilt", "apply", tex, "--base", big, "-o", plain)[0] == 0
    t = load_texture(tex)
    np.testing.assert_allclose(read_mesh(kept).vertices, reapplied(Vd, F, t, base=Vs),
                               atol=1e-12)
    # with the original the elements are the original ones, rotated with the surface
    # (here: unchanged, a uniform scaling); without it the lean angles shrink
    d_kept = read_mesh(kept).vertices - Vd
    np.testing.assert_allclose(d_kept, displacements(Vs, F, t), atol=1e-9)
    assert np.abs((read_mesh(plain).vertices - Vd) - d_kept).max() > 1e-2
    other = write_mesh(tmp_path / "other.ply", Mesh(Vs, F[:, [0, 2, 1]]))
    code, _, err = run(capsys, "heighttilt", "apply", tex, "--base", big, "--original", other,
                       "-o", tmp_path / "x.ply")
    assert code == 2 and "same faces" in err and not (tmp_path / "x.ply").exists()


def test_transfer_onto_another_shape_uses_the_sphere_map(capsys, tmp_path):
    import json

    from geotex.mesh.primitives import icosphere
    V0, F, Vs = spiky_sphere(subdivisions=3, spikes=6, height=0.2, width=0.4, lean_degrees=30,
                             seed=1)
    src = write_mesh(tmp_path / "src.ply", Mesh(V0, F))
    base = write_mesh(tmp_path / "base.ply", Mesh(Vs, F))
    Vd, Fd = icosphere(3)
    dst = write_mesh(tmp_path / "egg.ply", Mesh(Vd * np.array([1.0, 1.0, 2.0]), Fd))
    tex, out = tmp_path / "t.npz", tmp_path / "t2.npz"
    run(capsys, "heighttilt", "extract", src, "--base", base, "-o", tex)
    code, text, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                          "--target-base", dst, "-o", out)
    assert code == 0, err
    assert "map: sphere, aligned by principal axes" in text and "elements" in text
    assert load_texture(out).metadata["map"] == "sphere"
    marks = tmp_path / "marks.json"
    marks.write_text(json.dumps([[[0, 0, 1], [0, 0, 2]], [[1, 0, 0], [1, 0, 0]]]))
    code, text, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                          "--target-base", dst, "--landmarks", marks, "-o", out)
    assert code == 0, err
    assert "aligned by landmarks" in text
    # closest points on request; landmark errors are one line, nothing written
    code, text, _ = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                        "--target-base", dst, "--map", "closest", "-o", out)
    assert code == 0 and "closest" in text
    marks.write_text(json.dumps([[[0, 0, 1], [0, 0, 2]]]))
    bad = tmp_path / "bad.npz"
    code, _, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                       "--target-base", dst, "--landmarks", marks, "-o", bad)
    assert code != 0 and "at least two" in err and len(err.strip().splitlines()) == 1
    assert not bad.exists()


def test_sphere_transfer_onto_a_torus_is_a_one_line_error(capsys, tmp_path):
    from geotex.mesh.primitives import torus
    V0, F, Vs = spiky_sphere(subdivisions=2, spikes=4, seed=1)
    base = write_mesh(tmp_path / "base.ply", Mesh(Vs, F))
    src = write_mesh(tmp_path / "src.ply", Mesh(V0, F))
    ring = write_mesh(tmp_path / "ring.ply", Mesh(*torus(n_major=16, n_minor=8)))
    tex, out = tmp_path / "t.npz", tmp_path / "t2.npz"
    run(capsys, "heighttilt", "extract", src, "--base", base, "-o", tex)
    code, _, err = run(capsys, "heighttilt", "transfer", tex, "--source-base", base,
                       "--target-base", ring, "--map", "sphere", "-o", out)
    assert code != 0 and "--target-base" in err and "genus 1" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()
