"""geotex displace: painted face selections (PLY/OBJ colours) and the early refusal of
broken bases.  Every mesh here is generated; painted files are written with numpy."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

from geotex.displace import displace_file, displaced_mesh, face_selection, painted_faces
from geotex.errors import InputError
from geotex.io import read_mesh, read_mesh_colors, write_mesh
from geotex.mesh.primitives import closed_cylinder, icosphere
from geotex.mesh.record import Mesh

RED = (220, 30, 30)
GREY = (180, 180, 180)


@pytest.fixture(scope="module")
def part():
    V, F = closed_cylinder(10.0, 20.0, n_theta=32, n_height=10, n_cap_rings=3)
    return V, F


def _band(V, F):
    """The faces painted in these tests: side faces between z = 12 and 18."""
    C = V[F].mean(axis=1)
    return (C[:, 2] > 12) & (C[:, 2] < 18) & (np.hypot(C[:, 0], C[:, 1]) > 9.0)


def _ply(path, V, F, *, face_rgb=None, vertex_rgb=None, fmt="ascii", kind="uchar"):
    """A PLY with optional per-face / per-vertex colours of PLY type ``kind``."""
    ctype = {"uchar": "u1", "float": "f4"}[kind]
    head = ["ply", f"format {fmt} 1.0", f"element vertex {len(V)}",
            "property float x", "property float y", "property float z"]
    if vertex_rgb is not None:
        head += [f"property {kind} {c}" for c in ("red", "green", "blue")]
    head += [f"element face {len(F)}", "property list uchar int vertex_indices"]
    if face_rgb is not None:
        head += [f"property {kind} {c}" for c in ("red", "green", "blue")]
    head.append("end_header")
    text = "\n".join(head) + "\n"
    if fmt == "ascii":
        vcols = [V] + ([vertex_rgb] if vertex_rgb is not None else [])
        rows = [" ".join(f"{x:.9g}" for x in r) for r in np.hstack(vcols).tolist()]
        frows = []
        for i, f in enumerate(F.tolist()):
            line = "3 " + " ".join(map(str, f))
            if face_rgb is not None:
                line += " " + " ".join(f"{x:.9g}" for x in face_rgb[i])
            frows.append(line)
        path.write_text(text + "\n".join(rows + frows) + "\n")
        return path
    e = "<" if fmt == "binary_little_endian" else ">"
    vd = [("x", e + "f4"), ("y", e + "f4"), ("z", e + "f4")]
    if vertex_rgb is not None:
        vd += [(c, e + ctype) for c in ("r", "g", "b")]
    vrec = np.zeros(len(V), dtype=vd)
    vrec["x"], vrec["y"], vrec["z"] = V.T
    if vertex_rgb is not None:
        vrec["r"], vrec["g"], vrec["b"] = np.asarray(vertex_rgb).T
    fd = [("n", "u1"), ("i", e + "i4", (3,))]
    if face_rgb is not None:
        fd += [(c, e + ctype) for c in ("r", "g", "b")]
    frec = np.zeros(len(F), dtype=fd)
    frec["n"] = 3
    frec["i"] = F
    if face_rgb is not None:
        frec["r"], frec["g"], frec["b"] = np.asarray(face_rgb).T
    path.write_bytes(text.encode() + vrec.tobytes() + frec.tobytes())
    return path


def _obj(path, V, F, vertex_rgb):
    rows = [f"v {x:.9g} {y:.9g} {z:.9g} {r:.6g} {g:.6g} {b:.6g}"
            for (x, y, z), (r, g, b) in zip(V.tolist(), np.asarray(vertex_rgb).tolist())]
    rows += ["f " + " ".join(str(i + 1) for i in f) for f in F.tolist()]
    path.write_text("\n".join(rows) + "\n")
    return path


def _face_colors(sel, *, paint=RED, base=GREY, scale=1.0):
    return np.where(sel[:, None], np.array(paint), np.array(base)) * scale


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian", "binary_big_endian"])
@pytest.mark.parametrize("kind", ["uchar", "float"])
def test_per_face_ply_colours_select_the_painted_faces(part, tmp_path, fmt, kind):
    V, F = part
    want = _band(V, F)
    scale = 1.0 / 255.0 if kind == "float" else 1.0
    p = _ply(tmp_path / "painted.ply", V, F, face_rgb=_face_colors(want, scale=scale),
             fmt=fmt, kind=kind)
    mesh, fc, vc = read_mesh_colors(p)
    assert vc is None and fc.shape == (F.shape[0], 3)
    assert np.abs(fc[want] - RED).max() < 1e-3 and np.abs(fc[~want] - GREY).max() < 1e-3
    assert np.array_equal(painted_faces(p, V, F), want)
    # the paint named explicitly gives the same faces; naming the base colour the others
    assert np.array_equal(painted_faces(p, V, F, color=(225, 25, 35)), want)
    assert np.array_equal(painted_faces(p, V, F, color=GREY), ~want)


def test_polygon_colours_reach_each_of_its_triangles(tmp_path):
    """A painted quad gives its colour to both of its triangles."""
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float)
    text = "\n".join(["ply", "format ascii 1.0", "element vertex 6", "property double x",
                      "property double y", "property double z", "element face 2",
                      "property list uchar int vertex_indices", "property uchar red",
                      "property uchar green", "property uchar blue", "end_header"]
                     + [" ".join(map(str, v)) for v in V.tolist()]
                     + ["4 0 1 2 3 255 0 0", "4 1 4 5 2 9 9 9"]) + "\n"
    (tmp_path / "q.ply").write_text(text)
    mesh, fc, _ = read_mesh_colors(tmp_path / "q.ply")
    assert mesh.n_faces == 4
    assert fc.tolist() == [[255, 0, 0]] * 2 + [[9, 9, 9]] * 2
    assert np.array_equal(mesh.faces, read_mesh(tmp_path / "q.ply").faces)


def test_per_vertex_ply_colours_select_faces_by_majority(part, tmp_path):
    V, F = part
    on_v = np.zeros(V.shape[0], dtype=bool)
    on_v[F[_band(V, F)].ravel()] = True
    rgb = np.where(on_v[:, None], np.array(RED), np.array(GREY))
    p = _ply(tmp_path / "painted.ply", V, F, vertex_rgb=rgb, fmt="binary_little_endian")
    want = on_v[F].sum(axis=1) >= 2
    got = painted_faces(p, V, F)
    assert np.array_equal(got, want)
    # the majority rule: the band, plus only border faces with two painted corners
    assert (got & ~_band(V, F)).sum() < (on_v[F].any(axis=1) & ~_band(V, F)).sum()


@pytest.mark.parametrize("scale", [1.0 / 255.0, 1.0])
def test_obj_vertex_colours(part, tmp_path, scale):
    V, F = part
    on_v = np.zeros(V.shape[0], dtype=bool)
    on_v[F[_band(V, F)].ravel()] = True
    rgb = np.where(on_v[:, None], np.array(RED), np.array(GREY)) * scale
    p = _obj(tmp_path / "painted.obj", V, F, rgb)
    _, fc, vc = read_mesh_colors(p)
    assert fc is None and np.abs(vc - np.where(on_v[:, None], RED, GREY)).max() < 1e-3
    assert np.array_equal(painted_faces(p, V, F), on_v[F].sum(axis=1) >= 2)
    # the geometry reader still ignores the colour columns
    assert np.array_equal(read_mesh(p).vertices, read_mesh_colors(p)[0].vertices)


def test_reindexed_painted_mesh_is_transferred_by_centroids(part, tmp_path):
    """An editor that renumbers vertices and faces and rotates corners: same selection."""
    V, F = part
    want = _band(V, F)
    rng = np.random.default_rng(3)
    pv = rng.permutation(V.shape[0])
    inv = np.argsort(pv)
    pf = rng.permutation(F.shape[0])
    F2 = np.roll(inv[F[pf]], 1, axis=1)
    p = _ply(tmp_path / "renumbered.ply", V[pv], F2, face_rgb=_face_colors(want[pf]),
             fmt="binary_big_endian")
    assert np.array_equal(painted_faces(p, V, F), want)
    # a finer remesh of the same part (every face split in four) transfers too
    Vf, Ff = closed_cylinder(10.0, 20.0, n_theta=64, n_height=20, n_cap_rings=6)
    fine = _ply(tmp_path / "fine.ply", Vf, Ff, face_rgb=_face_colors(_band(Vf, Ff)))
    got = painted_faces(fine, V, F)
    assert (got == want).mean() > 0.97


def test_refusals_name_the_problem(part, tmp_path):
    V, F = part
    plain = _ply(tmp_path / "plain.ply", V, F)
    with pytest.raises(InputError, match="face selection .*no colours"):
        painted_faces(plain, V, F)
    one = _ply(tmp_path / "one.ply", V, F, face_rgb=_face_colors(np.zeros(F.shape[0], bool)))
    with pytest.raises(InputError, match="same colour .*nothing is painted"):
        painted_faces(one, V, F)
    half = np.arange(F.shape[0]) % 2 == 0
    tie = _ply(tmp_path / "tie.ply", V, F, face_rgb=_face_colors(half))
    with pytest.raises(InputError, match="equally common"):
        painted_faces(tie, V, F)
    assert np.array_equal(painted_faces(tie, V, F, color=RED), half)
    good = _ply(tmp_path / "good.ply", V, F, face_rgb=_face_colors(_band(V, F)))
    with pytest.raises(InputError, match="no colour within 30 of mask color 0,0,255"):
        painted_faces(good, V, F, color=(0, 0, 255))
    for bad in [(300, 0, 0), (1, 2), ("a", 0, 0), (float("nan"), 0, 0)]:
        with pytest.raises(InputError, match="^mask color"):
            painted_faces(good, V, F, color=bad)
    with pytest.raises(InputError, match="^mask tolerance"):
        painted_faces(good, V, F, tolerance=-1)
    # another shape, and the same part moved away, are not the base
    Vs, Fs = icosphere(3)
    sphere = _ply(tmp_path / "sphere.ply", Vs * 3.0, Fs,
                  face_rgb=_face_colors(Vs[Fs].mean(axis=1)[:, 2] > 0.5))
    with pytest.raises(InputError, match="painted mesh is not the base"):
        painted_faces(sphere, V, F)
    moved = _ply(tmp_path / "moved.ply", V + [0, 0, 5.0], F, face_rgb=_face_colors(_band(V, F)))
    with pytest.raises(InputError, match="painted mesh is not the base"):
        painted_faces(moved, V, F)
    with pytest.raises(InputError, match="face selection .*read from PLY .* and OBJ"):
        face_selection(tmp_path / "x.stl", V, F)
    nan = tmp_path / "nan.obj"
    nan.write_text("v 0 0 0 nan nan nan\nv 1 0 0 1 0 0\nv 0 1 0 1 0 0\nf 1 2 3\n")
    with pytest.raises(InputError, match="face selection .*line 1: vertex colour"):
        painted_faces(nan, V, F)


def test_huge_declared_counts_are_refused_at_once(part, tmp_path):
    V, F = part
    p = tmp_path / "huge.ply"
    p.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\n"
                  b"property float x\nproperty float y\nproperty float z\n"
                  b"element face 3000000000\nproperty list uchar int vertex_indices\n"
                  b"property uchar red\nproperty uchar green\nproperty uchar blue\n"
                  b"end_header\n" + b"\0" * 64)
    t = time.perf_counter()
    with pytest.raises(InputError, match="face selection .*truncated"):
        painted_faces(p, V, F)
    assert time.perf_counter() - t < 2.0


def test_json_selections_still_work(part, tmp_path):
    V, F = part
    (tmp_path / "sel.json").write_text("[0, 5, 7]")
    assert face_selection(tmp_path / "sel.json", V, F).nonzero()[0].tolist() == [0, 5, 7]
    (tmp_path / "far.json").write_text(f"[{F.shape[0]}]")
    with pytest.raises(InputError, match="face selection .*index"):
        face_selection(tmp_path / "far.json", V, F)
    with pytest.raises(InputError, match="mask color"):
        face_selection(tmp_path / "sel.json", V, F, color=RED)


def _geotex(*args):
    return subprocess.run([sys.executable, "-m", "geotex", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_cli_painted_selection_textures_only_the_paint(part, tmp_path):
    V, F = part
    base = write_mesh(tmp_path / "part.stl", Mesh(V, F))
    Vb, Fb = read_mesh(base).vertices, read_mesh(base).faces     # the STL as welded
    want = _band(Vb, Fb)
    rng = np.random.default_rng(0)
    pf = rng.permutation(Fb.shape[0])
    painted = _ply(tmp_path / "painted.ply", Vb, Fb[pf], face_rgb=_face_colors(want[pf]),
                   fmt="binary_little_endian")
    out = tmp_path / "out.stl"
    res = _geotex("displace", base, "--image", "dots", "--depth", "0.5", "--faces", "20000",
                  "--mask-faces", painted, "-o", out)
    assert res.returncode == 0, res.stderr
    assert f"{int(want.sum())} base faces selected" in res.stdout
    R = read_mesh(out).vertices
    r = np.hypot(R[:, 0], R[:, 1])
    side = r > 9.5
    # outside the painted band (z 12..18 give or take one base row) the wall is untouched
    away = side & ((R[:, 2] < 10) | (R[:, 2] > 20 - 1e-3))
    assert np.abs(r[away] - r[away].clip(max=10.0)).max() < 1e-3
    inside = side & (R[:, 2] > 12.5) & (R[:, 2] < 17.5)
    assert r[inside].max() > 10.2


@pytest.mark.parametrize("args, flag", [
    (["--mask-color", "300,0,0"], "--mask-color"),
    (["--mask-color", "1,2"], "--mask-color"),
    (["--mask-tolerance", "-3"], "--mask-tolerance"),
    (["--mask-color", "0,0,255"], "--mask-faces"),
])
def test_cli_bad_mask_colours_are_one_line(part, tmp_path, args, flag):
    V, F = part
    base = write_mesh(tmp_path / "part.obj", Mesh(V, F))
    painted = _ply(tmp_path / "painted.ply", V, F, face_rgb=_face_colors(_band(V, F)))
    out = tmp_path / "out.stl"
    res = _geotex("displace", base, "--image", "dots", "--depth", "0.5", "--mask-faces",
                  painted, *args, "-o", out)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and flag in lines[0] and "Traceback" not in res.stderr
    assert not out.exists()


def test_cli_painted_file_without_colours_names_the_flag(part, tmp_path):
    V, F = part
    base = write_mesh(tmp_path / "part.obj", Mesh(V, F))
    plain = write_mesh(tmp_path / "plain.ply", Mesh(V, F))
    out = tmp_path / "out.stl"
    res = _geotex("displace", base, "--image", "dots", "--depth", "0.5", "--mask-faces",
                  plain, "-o", out)
    assert res.returncode == 2
    assert res.stderr.startswith("geotex: error: --mask-faces ") and "no colours" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not out.exists()


def test_open_base_is_refused_before_any_relief_work(part, tmp_path, monkeypatch):
    """No refinement, no mapping, no painted file read: the refusal comes first."""
    import geotex.displace.api as api

    def boom(*a, **k):
        raise AssertionError("relief work started on a broken base")

    monkeypatch.setattr(api, "displaced_solid", boom)
    monkeypatch.setattr(api, "load_height_map", boom)
    monkeypatch.setattr(api, "edge_length_for_faces", boom)
    monkeypatch.setattr(api, "face_selection", boom)
    V, F = part
    open_F = F[1:]                                           # one face missing
    with pytest.raises(InputError, match="not a closed solid to displace: open"):
        displaced_mesh(V, open_F, "dots", depth=0.5)
    base = write_mesh(tmp_path / "open.obj", Mesh(V, open_F))
    out = tmp_path / "out.stl"
    painted = _ply(tmp_path / "painted.ply", V, F, face_rgb=_face_colors(_band(V, F)))
    with pytest.raises(InputError, match="open.obj: not a closed solid to displace: open"):
        displace_file(base, "dots", out, depth=0.5, mask_file=painted)
    assert not out.exists()
    # a self-intersecting one too (a second copy of the part pushed half into it)
    V2 = np.vstack([V, V + [5.0, 0, 10.0]])
    F2 = np.vstack([F, F + V.shape[0]])
    with pytest.raises(InputError, match="self-intersecting face pairs"):
        displaced_mesh(V2, F2, "dots", depth=0.5)


def test_coordinates_beyond_what_the_output_stores_are_refused_first(part, monkeypatch):
    """A closed box at +-3.4e38 (FLT_MAX) is refused before the mapping casts it."""
    import geotex.displace.api as api

    monkeypatch.setattr(api, "load_height_map", lambda *a, **k: pytest.fail("work started"))
    V, F = part
    with pytest.raises(InputError, match="coordinates reach 3.4e\\+38 mm"):
        displaced_mesh(V * 1.7e37, F, "dots", depth=1.0)
    with pytest.raises(InputError, match="coordinates reach"):
        displaced_mesh(V * 1e14, F, "dots", depth=1.0, precision=np.float64)
