"""Reproducers of issue #15: hostile files are refused quickly, with one-line messages.

Every hostile file is generated here (nothing large is committed).
"""

import io
import json
import os
import struct
import zipfile

import numpy as np
import pytest

from geotex.cli import main
from geotex.errors import InputError, MeshFileError
from geotex.io import read_mesh, write_mesh
from geotex.io.limits import RefusedInput, inflate_member, read_bounded, sidecar_file
from geotex.mesh import Mesh
from geotex.mesh.polygons import polygon_triangle_corners
from geotex.mesh.primitives import box


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_error_line(err):
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("geotex: error: "), err
    return lines[0]


# --------------------------------------------------------------------------- GLB / OBJ references


def glb_bytes(doc, binary=b""):
    text = json.dumps(doc).encode() if not isinstance(doc, bytes) else doc
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    if binary:
        binary += b"\0" * (-len(binary) % 4)
        body += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def triangle_doc(uri, byte_length=36):
    return {"asset": {"version": "2.0"},
            "buffers": [{"uri": uri, "byteLength": byte_length}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3,
                           "type": "VEC3"}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}


TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes()


@pytest.mark.parametrize("uri, words", [
    ("/dev/zero", "absolute paths are not allowed"),
    ("../outside.bin", "'..' leaves the folder"),
    ("sub/../../outside.bin", "'..' leaves the folder"),
    ("file:///dev/zero", "only relative file references"),
    ("%2Fdev%2Fzero", "absolute paths are not allowed"),
    ("missing.bin", "not found"),
])
def test_glb_buffer_uri_outside_the_folder_is_refused(tmp_path, capsys, uri, words):
    folder = tmp_path / "models"
    folder.mkdir()
    (tmp_path / "outside.bin").write_bytes(TRIANGLE)
    path = folder / "t.glb"
    path.write_bytes(glb_bytes(triangle_doc(uri)))
    with pytest.raises(MeshFileError, match=words):
        read_mesh(path)
    code, _, err = run(capsys, "check", path)
    assert code == 2 and words in one_error_line(err)


def test_glb_buffer_uri_next_to_the_file_is_read_up_to_its_declared_size(tmp_path):
    (tmp_path / "t.bin").write_bytes(TRIANGLE + b"\0" * 1000)
    path = tmp_path / "t.glb"
    path.write_bytes(glb_bytes(triangle_doc("t.bin")))
    mesh = read_mesh(path)
    assert mesh.n_faces == 1 and mesh.n_vertices == 3


def test_glb_buffer_shorter_than_declared_is_refused(tmp_path):
    (tmp_path / "t.bin").write_bytes(TRIANGLE)
    path = tmp_path / "t.glb"
    path.write_bytes(glb_bytes(triangle_doc("t.bin", byte_length=1000)))
    with pytest.raises(MeshFileError, match="fewer than the 1000 declared"):
        read_mesh(path)


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="needs symlinks")
def test_glb_buffer_symlink_out_of_the_folder_is_refused(tmp_path):
    folder = tmp_path / "models"
    folder.mkdir()
    (tmp_path / "secret.bin").write_bytes(TRIANGLE)
    os.symlink(tmp_path / "secret.bin", folder / "t.bin")
    path = folder / "t.glb"
    path.write_bytes(glb_bytes(triangle_doc("t.bin")))
    with pytest.raises(MeshFileError, match="outside the folder"):
        read_mesh(path)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_glb_buffer_that_is_not_a_regular_file_is_refused(tmp_path):
    os.mkfifo(tmp_path / "t.bin")
    path = tmp_path / "t.glb"
    path.write_bytes(glb_bytes(triangle_doc("t.bin")))
    with pytest.raises(MeshFileError, match="not a regular file"):
        read_mesh(path)


def test_glb_data_uri_longer_than_declared_is_refused(tmp_path):
    import base64
    uri = "data:application/octet-stream;base64," + base64.b64encode(b"\0" * 4000).decode()
    path = tmp_path / "t.glb"
    path.write_bytes(glb_bytes(triangle_doc(uri)))
    with pytest.raises(MeshFileError, match="more than the 36 bytes declared"):
        read_mesh(path)


def test_obj_material_library_outside_the_folder_is_a_warning(tmp_path):
    folder = tmp_path / "models"
    folder.mkdir()
    (tmp_path / "m.mtl").write_text("newmtl a\nmap_Kd t.png\n")
    for lib, words in (("../m.mtl", "'..'"), (str(tmp_path / "m.mtl"), "absolute")):
        path = folder / "t.obj"
        path.write_text(f"mtllib {lib}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")
        mesh = read_mesh(path)
        assert mesh.texture is None
        assert "refused" in mesh.metadata["texture_warning"]
        assert words in mesh.metadata["texture_warning"]


def test_obj_texture_path_outside_the_folder_is_a_warning(tmp_path):
    (tmp_path / "m.mtl").write_text("newmtl a\nmap_Kd /etc/passwd\n")
    path = tmp_path / "t.obj"
    path.write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")
    mesh = read_mesh(path)
    assert mesh.texture is None and "absolute" in mesh.metadata["texture_warning"]


def test_sidecar_rules_directly(tmp_path):
    (tmp_path / "a.bin").write_bytes(b"12345")
    mesh = tmp_path / "m.glb"
    assert sidecar_file(mesh, "a.bin", what="x") == (tmp_path / "a.bin").resolve()
    assert sidecar_file(mesh, "./a.bin", what="x") == (tmp_path / "a.bin").resolve()
    with pytest.raises(RefusedInput, match="absolute"):
        sidecar_file(mesh, "C:/a.bin", what="x", uri=True)
    with pytest.raises(RefusedInput, match="regular file"):
        sidecar_file(mesh, ".", what="x")
    with pytest.raises(RefusedInput, match="more than the 4 bytes"):
        read_bounded(tmp_path / "a.bin", 4, what="x")
    assert read_bounded(tmp_path / "a.bin", 4, what="x", exact=True) == b"1234"


# --------------------------------------------------------------------------- zip bombs


def zip_of(members, compression=zipfile.ZIP_DEFLATED):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression) as z:
        for name, payload in members.items():
            z.writestr(name, payload)
    return buf.getvalue()


def test_3mf_zip_bomb_is_refused_before_inflating(tmp_path, capsys):
    data = zip_of({"3D/3dmodel.model": b" " * (64 << 20)})
    assert len(data) < 1 << 20                  # 64 MiB from well under 1 MiB
    path = tmp_path / "bomb.3mf"
    path.write_bytes(data)
    with pytest.raises(MeshFileError, match="zip bomb"):
        read_mesh(path)
    code, _, err = run(capsys, "check", path)
    assert code == 2 and "zip bomb" in one_error_line(err)


def test_inflate_member_bounds():
    data = zip_of({"a": b"x" * 5000, "b": b"hello"})
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        with pytest.raises(RefusedInput, match="more than the 4.9 KiB allowed"):
            inflate_member(z, "a", cap=5000 - 1)
        assert inflate_member(z, "b") == b"hello"
        with pytest.raises(KeyError):
            inflate_member(z, "c")


def test_3mf_part_declaring_a_smaller_size_is_not_inflated_beyond_it(tmp_path):
    payload = b"<model>" + b" " * 100000 + b"</model>"
    blob = bytearray(zip_of({"3D/3dmodel.model": payload}))
    at = blob.rfind(b"PK\x01\x02")
    struct.pack_into("<I", blob, at + 24, 10)    # central directory: 10 bytes inflated
    path = tmp_path / "lie.3mf"
    path.write_bytes(bytes(blob))
    with pytest.raises(MeshFileError):
        read_mesh(path)


# --------------------------------------------------------------------------- polygons


def test_polygon_of_many_corners_from_few_vertices_is_triangulated():
    rng = np.random.default_rng(0)
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    k = 10000                       # ear-clipped: the flat-triangle pass is linear
    corners, dropped = polygon_triangle_corners([k], V[rng.integers(0, 5, k)])
    assert corners.shape == (k - 2, 3) and dropped == 0
    assert corners.min() >= 0 and corners.max() < k
    k = 20000                       # beyond the ear-clipping limit: refused at once
    with pytest.raises(InputError, match="20000 corners and is not convex"):
        polygon_triangle_corners([k], V[rng.integers(0, 5, k)])


def test_obj_face_with_many_corners_reads(tmp_path):
    rng = np.random.default_rng(1)
    lines = ["v 0 0 0", "v 1 0 0", "v 1 1 0", "v 0 1 0", "v 0.5 0.5 0"]
    lines.append("f " + " ".join(str(i) for i in rng.integers(1, 6, 1000)))
    path = tmp_path / "p.obj"
    path.write_text("\n".join(lines) + "\n")
    assert read_mesh(path).n_faces == 998


def test_huge_convex_polygon_is_fanned_and_huge_tangled_one_refused():
    k = 30000
    a = np.linspace(0, 2 * np.pi, k, endpoint=False)
    circle = np.c_[np.cos(a), np.sin(a), np.zeros(k)]
    corners, _ = polygon_triangle_corners([k], circle)
    assert (corners[:, 0] == 0).all()                        # a fan
    star = circle * (1 + 0.5 * (np.arange(k) % 2))[:, None]
    with pytest.raises(InputError, match="30000 corners and is not convex"):
        polygon_triangle_corners([k], star)


def test_huge_tangled_obj_polygon_is_one_line_error(tmp_path, capsys):
    k = 12000
    a = np.linspace(0, 2 * np.pi, k, endpoint=False)
    r = 1 + 0.5 * (np.arange(k) % 2)
    xy = zip((r * np.cos(a)).tolist(), (r * np.sin(a)).tolist())
    lines = [f"v {x!r} {y!r} 0" for x, y in xy]
    lines.append("f " + " ".join(str(i + 1) for i in range(k)))
    path = tmp_path / "star.obj"
    path.write_text("\n".join(lines) + "\n")
    code, _, err = run(capsys, "check", path)
    line = one_error_line(err)
    assert code == 2 and "star.obj" in line and "not convex" in line


# --------------------------------------------------------------------------- counts, JSON, types


@pytest.mark.parametrize("name, data", [
    ("count.stl", b"\0" * 80 + struct.pack("<I", 2 ** 32 - 1) + b"\0" * 100),
    ("count.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 1099511627776\n"
                  b"property float x\nproperty float y\nproperty float z\nend_header\n"
                  + b"\0" * 100),
    ("counta.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                   b"property float y\nproperty float z\nelement face 1099511627776\n"
                   b"property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n"
                   b"0 1 0\n3 0 1 2\n"),
    ("count.off", b"OFF\n1000000000000 1 0\n0 0 0\n"),
    ("size.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1e300 0 1 2\n"),
    ("index.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                  b"property float y\nproperty float z\nelement face 1\n"
                  b"property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n"
                  b"0 1 0\n3 0 1 1e300\n"),
    ("deep.glb", glb_bytes(b'{"asset":' + b"[" * 100000 + b"]" * 100000 + b"}")),
    ("ctype.glb", glb_bytes({**triangle_doc("x.bin"), "accessors": [
        {"bufferView": 0, "componentType": [5126], "count": 3, "type": "VEC3"}]})),
    ("zeros.glb", glb_bytes({**triangle_doc("x.bin"), "accessors": [
        {"componentType": 5126, "count": 2 ** 40, "type": "VEC3"}]})),
    ("stride.glb", glb_bytes({**triangle_doc("data:application/octet-stream;base64,"),
                              "bufferViews": [{"buffer": 0, "byteLength": 0,
                                               "byteStride": 2 ** 70}]})),
])
def test_hostile_headers_and_documents_are_one_line_errors(tmp_path, capsys, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    code, out, err = run(capsys, "check", path)
    line = one_error_line(err)
    assert code == 2 and name in line and "malformed" not in line   # a named problem


def test_glb_deep_json_and_bad_types_name_the_problem(tmp_path):
    path = tmp_path / "deep.glb"
    path.write_bytes(glb_bytes(b"[" * 50000 + b"]" * 50000))
    with pytest.raises(MeshFileError, match="nested too deeply"):
        read_mesh(path)
    doc = triangle_doc("x.bin")
    doc["meshes"][0]["primitives"][0]["material"] = [1]
    (tmp_path / "x.bin").write_bytes(TRIANGLE)
    path = tmp_path / "mat.glb"
    path.write_bytes(glb_bytes(doc))
    with pytest.raises(MeshFileError, match=r"material \[1\] is not an index"):
        read_mesh(path)


# --------------------------------------------------------------------------- exit codes, flags


def test_out_of_memory_is_exit_2_not_an_internal_error(tmp_path, capsys, monkeypatch):
    import geotex.io as gio
    path = write_mesh(tmp_path / "b.stl", Mesh(*box()))

    def boom(*a, **k):
        raise MemoryError

    monkeypatch.setattr(gio, "read_mesh", boom)
    code, _, err = run(capsys, "check", path)
    assert code == 2 and "out of memory" in one_error_line(err)


def test_messages_name_cli_flags_not_python_arguments(tmp_path, capsys):
    path = tmp_path / "noext"
    write_mesh(tmp_path / "b.stl", Mesh(*box()))
    path.write_bytes((tmp_path / "b.stl").read_bytes())
    code, _, err = run(capsys, "check", path)
    assert code == 2 and "format=" not in one_error_line(err)
    code, _, err = run(capsys, "shell", "build", tmp_path / "b.stl", "-o", tmp_path / "s.npz",
                       "--tile-size", "100")
    line = one_error_line(err)
    assert code == 2 and "--tile-size 100 is too large" in line and "tile_size" not in line


def test_library_messages_stay_neutral():
    from geotex.param.polycube import polycube
    V, F = box()
    with pytest.raises(InputError) as info:
        polycube(V, F, tile_size=100.0)
    assert "tile size 100 is too large" in str(info.value) and "--" not in str(info.value)


# --------------------------------------------------------------------------- repair


def figure_eight_tube(n=150, m=16, r=0.1):
    """A closed tube along a figure-eight: one shell crossing itself."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    C = np.c_[np.cos(t), np.sin(t) * np.cos(t), np.zeros(n)]
    T = np.gradient(C, axis=0)
    T /= np.linalg.norm(T, axis=1)[:, None]
    Z = np.array([0.0, 0.0, 1.0])
    N = np.cross(T, Z)
    N /= np.linalg.norm(N, axis=1)[:, None]
    s = np.linspace(0, 2 * np.pi, m, endpoint=False)
    V = (C[:, None] + r * (np.cos(s)[None, :, None] * N[:, None]
                           + np.sin(s)[None, :, None] * Z)).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, ((i + 1) % n) * m + j
    c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
    F = np.r_[np.c_[a.ravel(), b.ravel(), c.ravel()], np.c_[a.ravel(), c.ravel(), d.ravel()]]
    return V, F


def test_repair_that_splits_shells_or_loses_volume_is_flagged():
    from geotex.repair import repair_mesh
    result = repair_mesh(*figure_eight_tube())
    assert not result.faithful
    assert any("shells" in w for w in result.warnings)
    assert any("of the volume" in w for w in result.warnings)


def test_repair_cli_refuses_a_repair_that_changed_the_solid(tmp_path, capsys):
    path = write_mesh(tmp_path / "loop.stl", Mesh(*figure_eight_tube()))
    out = tmp_path / "fixed.stl"
    code, _, err = run(capsys, "repair", path, "-o", out)
    assert code == 1 and not out.exists()
    lines = err.splitlines()
    assert len(lines) == 1 and "changed the solid" in lines[0] and "--force" in lines[0]
    code, _, _ = run(capsys, "repair", path, "-o", out, "--force")
    assert code == 0 and out.exists()


@pytest.mark.parametrize("loader", [
    "geotex.shells.store:load_shell", "geotex.fields.store:load_direction_field",
    "geotex.heighttilt.texture:load_texture", "geotex.exemplars.store:load_exemplar",
    "geotex.image.records:load_lapped"])
def test_npz_bombs_are_refused_before_inflating(tmp_path, loader):
    import importlib
    module, name = loader.split(":")
    load = getattr(importlib.import_module(module), name)
    path = tmp_path / "bomb.npz"
    path.write_bytes(zip_of({"metadata.npy": b"\0" * (64 << 20)}))
    with pytest.raises(InputError, match="zip bomb"):
        load(path)


def test_error_messages_stay_one_bounded_line(capsys):
    from geotex.cli._common import MAX_MESSAGE, fail
    assert fail("bytes b'\\x00'\nnext line " + "x" * 5000) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and len(err) <= len("geotex: error: ") + MAX_MESSAGE + 1


def test_damaged_zip_member_name_is_not_dumped_into_the_message(tmp_path, capsys):
    data = bytearray(write_mesh(tmp_path / "ok.3mf", Mesh(*box())).read_bytes())
    at = data.find(b"_rels/.rels")                  # the local header's copy of the name
    data[at + 8:at + 11] = b"XYZ"
    path = tmp_path / "bad.3mf"
    path.write_bytes(bytes(data))
    code, _, err = run(capsys, "check", path)
    assert code == 2 and len(one_error_line(err)) < 400
