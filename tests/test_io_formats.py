"""Round trips and content checks for geotex.io (STL, OBJ, PLY, OFF, 3MF, GLB)."""

from __future__ import annotations

import json
import os
import struct
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from geotex.io import READ_FORMATS, WRITE_FORMATS, read_mesh, write_mesh
from geotex.io.atomic import atomic_group, atomic_output
from geotex.io.sniff import mismatch_hint, sniff_format
from geotex.mesh import Mesh, signed_volume

# --------------------------------------------------------------------------- meshes


def octahedron() -> tuple[np.ndarray, np.ndarray]:
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                 dtype=float)
    F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return V, F


def sphere(level: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Subdivided octahedron projected on the unit sphere (closed, outward)."""
    V, F = octahedron()
    for _ in range(level):
        edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        mid = V[unique].mean(axis=1)
        m = F.shape[0]
        inverse = inverse.reshape(3, m).T + V.shape[0]
        a, b, c = F.T
        ab, bc, ca = inverse.T
        F = np.concatenate([np.c_[a, ab, ca], np.c_[b, bc, ab], np.c_[c, ca, bc],
                            np.c_[ab, bc, ca]])
        V = np.concatenate([V, mid])
    V = V / np.linalg.norm(V, axis=1, keepdims=True)
    return V, F


def first_appearance(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Renumber vertices in order of first appearance in F (dropping unused ones)."""
    flat = F.ravel()
    _, first = np.unique(flat, return_index=True)
    order = flat[np.sort(first)]
    remap = np.full(V.shape[0], -1)
    remap[order] = np.arange(order.shape[0])
    return V[order], remap[F]


def float32_sphere(level: int = 2, scale: float = 12.5, shift=(3.0, -2.0, 40.0)):
    """A sphere with float32-representable, distinct vertices in first-appearance order."""
    V, F = sphere(level)
    V = (V * scale + np.asarray(shift)).astype(np.float32).astype(np.float64)
    assert np.unique(V, axis=0).shape[0] == V.shape[0]
    return first_appearance(V, F)


def float64_sphere(level: int = 2):
    """Coordinates that need all 17 digits (not float32-representable)."""
    V, F = sphere(level)
    V = V * np.pi + np.array([1e-7, 123456.789, -1.0 / 3.0])
    return first_appearance(V, F)


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("ext,binary", [("stl", True), ("glb", True)])
def test_float32_formats_round_trip_exactly(tmp_path, ext, binary):
    V, F = float32_sphere()
    out = write_mesh(tmp_path / f"s.{ext}", Mesh(V, F), binary=binary)
    assert out == tmp_path / f"s.{ext}"
    back = read_mesh(out)
    assert np.array_equal(back.vertices, V)
    assert np.array_equal(back.faces, F)


@pytest.mark.parametrize("ext,binary", [
    ("stl", False), ("obj", True), ("ply", True), ("ply", False), ("off", True),
    ("3mf", True)])
def test_float64_formats_round_trip_exactly(tmp_path, ext, binary):
    V, F = float64_sphere()
    back = read_mesh(write_mesh(tmp_path / f"s.{ext}", Mesh(V, F), binary=binary))
    assert np.array_equal(back.vertices, V)
    assert np.array_equal(back.faces, F)
    assert back.metadata["format"] == ext


@pytest.mark.parametrize("ext", ["obj", "ply", "off", "3mf", "glb"])
def test_indexed_formats_keep_vertex_order_and_unused_vertices(tmp_path, ext):
    V, F = float32_sphere(1)
    V = V[::-1].copy()
    F = (V.shape[0] - 1) - F
    V = np.concatenate([V, [[7.0, 8.0, 9.0]]])          # an unreferenced vertex
    back = read_mesh(write_mesh(tmp_path / f"r.{ext}", Mesh(V, F)))
    assert np.array_equal(back.vertices, V)
    assert np.array_equal(back.faces, F)


def test_all_formats_preserve_volume(tmp_path):
    V, F = sphere(3)
    volume = signed_volume(V, F)
    assert volume > 4.0
    for ext in WRITE_FORMATS:
        back = read_mesh(write_mesh(tmp_path / f"v{ext}", Mesh(V * 10, F)))
        assert signed_volume(back.vertices, back.faces) == pytest.approx(
            1000 * volume, rel=1e-6), ext


def test_read_and_write_formats_lists():
    assert READ_FORMATS == (".stl", ".obj", ".ply", ".off", ".3mf", ".glb")
    assert set(WRITE_FORMATS) == set(READ_FORMATS)


def test_extension_is_case_insensitive_and_format_overrides(tmp_path):
    V, F = float32_sphere(1)
    upper = write_mesh(tmp_path / "UP.STL", Mesh(V, F))
    assert np.array_equal(read_mesh(upper).faces, F)
    odd = write_mesh(tmp_path / "mesh.data", Mesh(V, F), format="ply")
    back = read_mesh(odd, format="PLY")
    assert np.array_equal(back.vertices, V)
    assert back.name == "mesh"


def test_empty_mesh_round_trips(tmp_path):
    empty = Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    for ext in WRITE_FORMATS:
        back = read_mesh(write_mesh(tmp_path / f"e{ext}", empty))
        assert back.n_vertices == 0 and back.n_faces == 0, ext


@pytest.mark.parametrize("ext", ["obj", "ply", "off", "3mf", "glb"])
def test_point_cloud_is_read_with_no_faces(tmp_path, ext):
    V = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [-1.5, 0.25, 8.0]])
    back = read_mesh(write_mesh(tmp_path / f"p.{ext}", Mesh(V, np.zeros((0, 3), int))))
    assert np.array_equal(back.vertices, V)
    assert back.n_faces == 0


# --------------------------------------------------------------------------- STL


def _binary_stl(triangles: np.ndarray, header: bytes) -> bytes:
    rec = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                          ("a", "<u2")])
    rec["v"] = triangles
    rec["n"] = 0.0
    return header.ljust(80, b"\0")[:80] + struct.pack("<I", len(triangles)) + rec.tobytes()


def test_binary_stl_with_solid_header_is_read_as_binary(tmp_path):
    V, F = float32_sphere(1)
    data = _binary_stl(V[F], b"solid exported by a CAD tool")
    path = tmp_path / "solid_header.stl"
    path.write_bytes(data)
    back = read_mesh(path)
    assert back.metadata["stl_encoding"] == "binary"
    assert np.array_equal(back.vertices, V)
    assert np.array_equal(back.faces, F)


def test_binary_stl_header_does_not_start_with_solid(tmp_path):
    V, F = float32_sphere(1)
    path = write_mesh(tmp_path / "h.stl", Mesh(V, F))
    data = path.read_bytes()
    assert not data[:80].lstrip().lower().startswith(b"solid")
    assert len(data) == 84 + 50 * F.shape[0]
    assert struct.unpack_from("<I", data, 80)[0] == F.shape[0]
    rec = np.frombuffer(data, dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")],
                        offset=84)
    normals = rec["n"].astype(float)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)
    centers = V[F].mean(axis=1) - V.mean(axis=0)
    assert (np.einsum("ij,ij->i", normals, centers) > 0).all()    # outward


def test_ascii_stl_multiple_solids_whitespace_and_notation(tmp_path):
    text = (
        "solid first part\r\n"
        "  facet normal 0 0 1\r\n    outer loop\r\n"
        "      vertex 0 0 0\r\n      vertex 1.0E+00 0 0\r\n      vertex 0 1e0 0\r\n"
        "    endloop\r\n  endfacet\r\n"
        "endsolid first part\r\n"
        "SOLID second\n\tFACET NORMAL 0.0 0.0 -1.0 OUTER LOOP\n"
        "\tVERTEX 0 0 0 VERTEX 0 1 0\tVERTEX -2.5e-1 -0.0 +0\n"
        "\tENDLOOP ENDFACET\n"
        "facet normal 0 0 0 outer loop vertex 1 0 0 vertex 1 1 0 vertex 0 1 0 endloop endfacet\n"
        "ENDSOLID second")
    path = tmp_path / "multi.stl"
    path.write_text(text)
    mesh = read_mesh(path)
    assert mesh.metadata["stl_encoding"] == "ascii"
    expected_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-0.25, 0, 0], [1, 1, 0]], float)
    assert np.array_equal(mesh.vertices, expected_V)
    assert np.array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3], [1, 4, 2]])


def test_ascii_stl_on_one_line_and_empty_solid(tmp_path):
    one = tmp_path / "one.stl"
    one.write_text("solid t facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 "
                   "vertex 0 1 0 endloop endfacet endsolid t")
    assert read_mesh(one).n_faces == 1
    empty = tmp_path / "empty.stl"
    empty.write_text("solid nothing\nendsolid nothing\n")
    mesh = read_mesh(empty)
    assert mesh.n_faces == 0 and mesh.n_vertices == 0


def test_stl_welds_exactly_equal_coordinates_only(tmp_path):
    tris = np.array([
        [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
        [[1, 0, 0], [1, 1, 0], [0, 1, 0]],
        [[-0.0, 0, 0], [0, 1, 0], [0, 0, 1]],              # -0.0 equals 0.0
        [[1, 0, 0], [np.float32(1) + np.float32(1e-7), 0, 0], [0, 0, 1]],  # near, distinct
    ], dtype=np.float32)
    path = tmp_path / "weld.stl"
    path.write_bytes(_binary_stl(tris, b"weld test"))
    mesh = read_mesh(path)
    assert mesh.n_vertices == 6
    assert mesh.faces.tolist() == [[0, 1, 2], [1, 3, 2], [0, 2, 4], [1, 5, 4]]


def test_stl_weld_is_deterministic_and_fast_path_matches_exact_sort():
    from geotex.io import _common

    rng = np.random.default_rng(5)
    pool = rng.integers(-3, 4, (40, 3)).astype(np.float32)
    P = pool[rng.integers(0, 40, 3000)]
    unique, inverse = _common.weld_exact(P)
    assert np.array_equal(unique[inverse], P)
    assert np.unique(unique, axis=0).shape[0] == unique.shape[0]
    firsts = np.array([np.flatnonzero(inverse == i)[0] for i in range(unique.shape[0])])
    assert (np.diff(firsts) > 0).all()                     # first-appearance order
    again = _common.weld_exact(P.copy())
    assert np.array_equal(again[0], unique) and np.array_equal(again[1], inverse)


def test_stl_weld_survives_hash_collisions(monkeypatch):
    from geotex.io import _common

    rng = np.random.default_rng(6)
    P = rng.integers(0, 5, (500, 3)).astype(np.float64)
    expected = _common.weld_exact(P)
    monkeypatch.setattr(_common, "_hash_columns",
                        lambda cols: np.zeros(cols[0].shape[0], dtype=np.uint64))
    unique, inverse = _common.weld_exact(P)
    assert np.array_equal(unique, expected[0])
    assert np.array_equal(inverse, expected[1])


def test_stl_reads_huge_finite_coordinates(tmp_path):
    big = np.float32(3.4e38)
    tris = np.array([[[big, 0, 0], [-big, 0, 0], [0, big, 0]]], dtype=np.float32)
    path = tmp_path / "big.stl"
    path.write_bytes(_binary_stl(tris, b"big"))
    mesh = read_mesh(path)
    assert mesh.vertices.max() == float(big)
    ascii_path = tmp_path / "big_ascii.stl"
    ascii_path.write_text("solid b\nfacet normal 0 0 1\nouter loop\nvertex 1e300 0 0\n"
                          "vertex -1e300 0 0\nvertex 0 1.7976931348623157e308 0\n"
                          "endloop\nendfacet\nendsolid b\n")
    assert read_mesh(ascii_path).vertices.max() == 1.7976931348623157e308


def test_ascii_stl_write_uses_exact_text(tmp_path):
    V = np.array([[0.1, 0.2, 0.3], [1 / 3, 2 / 3, 1.0], [1e-300, -5e17, 2.0]])
    F = np.array([[0, 1, 2]])
    path = write_mesh(tmp_path / "a.stl", Mesh(V, F, name="my part"), binary=False)
    text = path.read_text()
    assert text.startswith("solid my part\n") and text.endswith("endsolid my part\n")
    assert "vertex 0.1 0.2 0.3" in text
    assert np.array_equal(read_mesh(path).vertices, V)


# --------------------------------------------------------------------------- OBJ


def test_obj_ngons_negative_indices_uv_and_continuations(tmp_path):
    text = (
        "# exported by a scanner\n"
        "mtllib missing.mtl\n"
        "o thing\ng group1\ns off\n"
        "v 0 0 0 1 0 0\n"
        "v 1 0 0 nan nan nan\n"
        "v 1 1 0\n"
        "v 0 1 0 # a comment\n"
        "v 0.5 \\\n  1.5 0\n"                      # continued line
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 1 0\n"
        "vn 0 0 1\n"
        "usemtl skin\n"
        "f 1/1/1 2/2/1 3/3/1 4/4/1\n"              # quad -> 2 triangles (fan)
        "f -2/-2 -3/-3 \\\n -1/-1\n"                # relative, continued
        "f 4/4 3/3 5/5\n")
    path = tmp_path / "ngon.obj"
    path.write_text(text)
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                                          [0.5, 1.5, 0]])
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [3, 2, 4], [3, 2, 4]]
    assert mesh.uv_faces.tolist() == mesh.faces.tolist()
    assert np.array_equal(mesh.uv, [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 1]])
    assert mesh.texture is None
    assert "not found" in mesh.metadata["texture_warning"]


def _signed_areas(V, F):
    return 0.5 * np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2]


def test_obj_hexagon_and_vertex_normal_corners(tmp_path):
    ring = "".join(f"v {float(np.cos(a))!r} {float(np.sin(a))!r} 0\n"
                   for a in np.linspace(0, 2 * np.pi, 6, endpoint=False))
    path = tmp_path / "hex.obj"
    path.write_text(ring + "vn 0 0 1\nf 1//1 2//1 3//1 4//1 5//1 6//1\n")
    mesh = read_mesh(path)
    assert mesh.n_faces == 4 and mesh.uv is None
    A = _signed_areas(mesh.vertices, mesh.faces)
    assert (A > 0).all() and np.isclose(A.sum(), 1.5 * np.sqrt(3))


@pytest.mark.parametrize("ext", ["obj", "ply", "off"])
def test_concave_polygons_are_split_without_overlap(tmp_path, ext):
    comb = np.array([[0, 0, 0], [5, 0, 0], [5, 3, 0], [4, 3, 0], [4, 1, 0], [3, 1, 0],
                     [3, 3, 0], [2, 3, 0], [2, 1, 0], [1, 1, 0], [1, 3, 0], [0, 3, 0]], float)
    dart = np.array([[0, 0, 0], [2, 1, 0], [0, 2, 0], [0.5, 1, 0]]) + [10, 0, 0]
    V = np.concatenate([comb, dart])
    rows = [list(range(12)), [12, 13, 14, 15]]
    path = tmp_path / f"concave.{ext}"
    coords = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
    if ext == "obj":
        text = "".join("v " + line + "\n" for line in coords.splitlines())
        text += "".join("f " + " ".join(str(i + 1) for i in r) + "\n" for r in rows)
    elif ext == "off":
        text = f"OFF\n{len(V)} 2 0\n" + coords
        text += "".join(f"{len(r)} " + " ".join(map(str, r)) + "\n" for r in rows)
    else:
        text = (f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty double x\n"
                "property double y\nproperty double z\nelement face 2\n"
                "property list uchar int vertex_indices\nend_header\n" + coords)
        text += "".join(f"{len(r)} " + " ".join(map(str, r)) + "\n" for r in rows)
    path.write_text(text)
    mesh = read_mesh(path)
    assert mesh.n_faces == 10 + 2
    A = _signed_areas(mesh.vertices, mesh.faces)
    assert (A > 0).all()                          # same orientation: no folded triangles
    assert np.isclose(A[:10].sum(), 11.0) and np.isclose(A[10:].sum(), 1.5)


def test_obj_mixed_corner_forms_and_partial_uv(tmp_path):
    path = tmp_path / "mixed.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\n"
                    "f 1/1 2/1/1 3\nf 2 4 3\n")
    mesh = read_mesh(path)
    assert mesh.faces.tolist() == [[0, 1, 2], [1, 3, 2]]
    assert mesh.uv is None                    # not every face has texture coordinates


def test_obj_skips_degenerate_face_statements(tmp_path):
    path = tmp_path / "line.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\nl 1 2\n")
    mesh = read_mesh(path)
    assert mesh.faces.tolist() == [[0, 1, 2]]
    assert mesh.metadata["skipped_faces"] == 1


def test_obj_writes_uv_and_exact_coordinates(tmp_path):
    V, F = float64_sphere(1)
    uv = np.c_[np.linspace(0, 1, V.shape[0]), np.linspace(1, 0, V.shape[0]) / 3]
    mesh = Mesh(V, F, uv=uv, uv_faces=F)
    path = write_mesh(tmp_path / "uv.obj", mesh)
    assert not (tmp_path / "uv.mtl").exists()
    back = read_mesh(path)
    assert np.array_equal(back.vertices, V)
    assert np.array_equal(back.uv, uv)
    assert np.array_equal(back.uv_faces, F)


def _textured_mesh():
    V, F = float64_sphere(1)
    rng = np.random.default_rng(3)
    uv = rng.random((2 * F.shape[0], 2))
    FT = rng.integers(0, uv.shape[0], F.shape)
    texture = rng.integers(0, 256, (16, 24, 3), dtype=np.uint8)
    return Mesh(V, F, uv=uv, uv_faces=FT, texture=texture, name="textured")


def test_textured_obj_mtl_png_triple_round_trip(tmp_path):
    mesh = _textured_mesh()
    path = write_mesh(tmp_path / "skin.obj", mesh)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["skin.mtl", "skin.obj", "skin.png"]
    mtl = (tmp_path / "skin.mtl").read_text()
    assert "map_Kd skin.png" in mtl
    assert "mtllib skin.mtl" in path.read_text()
    back = read_mesh(path)
    assert np.array_equal(back.texture, mesh.texture)
    assert np.array_equal(back.uv, mesh.uv)
    assert np.array_equal(back.uv_faces, mesh.uv_faces)
    assert np.array_equal(back.vertices, mesh.vertices)
    assert back.metadata["texture_file"] == str(tmp_path / "skin.png")


def test_textured_obj_rgba_texture_and_map_options(tmp_path):
    from PIL import Image

    rgba = np.random.default_rng(4).integers(0, 256, (5, 7, 4), dtype=np.uint8)
    Image.fromarray(rgba).save(tmp_path / "tex image.png")
    (tmp_path / "mat.mtl").write_text(
        "newmtl other\nKd 1 0 0\nnewmtl used\nmap_Kd -s 1 1 1 -o 0 0 -clamp on tex image.png\n")
    path = tmp_path / "m.obj"
    path.write_text("mtllib mat.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                    "usemtl used\nf 1/1 2/2 3/3\n")
    mesh = read_mesh(path)
    assert np.array_equal(mesh.texture, rgba)


def test_obj_with_missing_texture_image_is_not_an_error(tmp_path):
    (tmp_path / "a.mtl").write_text("newmtl m\nmap_Kd nowhere.png\n")
    path = tmp_path / "a.obj"
    path.write_text("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    mesh = read_mesh(path)
    assert mesh.texture is None and mesh.n_faces == 1
    assert "nowhere.png" in mesh.metadata["texture_warning"]
    (tmp_path / "nowhere.png").write_bytes(b"not an image")
    mesh = read_mesh(path)
    assert mesh.texture is None and "unreadable" in mesh.metadata["texture_warning"]


# --------------------------------------------------------------------------- PLY


def _ply_header(fmt, vertex_props, n_vertices, face_decl, n_faces, extra=""):
    lines = ["ply", f"format {fmt} 1.0", "comment made by a test",
             f"element vertex {n_vertices}"]
    lines += [f"property {t} {n}" for t, n in vertex_props]
    lines += [extra] if extra else []
    lines += [f"element face {n_faces}", face_decl, "end_header"]
    return ("\n".join(lines) + "\n").encode("ascii")


@pytest.mark.parametrize("endian", ["<", ">"])
def test_binary_ply_mixed_polygons_and_types(tmp_path, endian):
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    V = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [1, 3, 0]], dtype=float)
    header = _ply_header(fmt, [("float32", "x"), ("uchar", "red"), ("float32", "y"),
                               ("double", "z")], 5,
                         "property list uint8 uint32 vertex_indices", 2)
    vrec = np.zeros(5, dtype=[("x", endian + "f4"), ("r", "u1"), ("y", endian + "f4"),
                              ("z", endian + "f8")])
    vrec["x"], vrec["y"], vrec["z"], vrec["r"] = V[:, 0], V[:, 1], V[:, 2], 200
    faces = (struct.pack(endian + "B4I", 4, 0, 1, 2, 3)
             + struct.pack(endian + "B3I", 3, 3, 2, 4))
    path = tmp_path / f"mixed{endian == '<'}.ply"
    path.write_bytes(header + vrec.tobytes() + faces)
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, V)
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [3, 2, 4]]


def test_binary_big_endian_ply_all_triangles_fast_path(tmp_path):
    V, F = float64_sphere(2)
    header = _ply_header("binary_big_endian", [("double", "x"), ("double", "y"),
                                               ("double", "z")], V.shape[0],
                         "property list ushort int vertex_index", F.shape[0])
    vrec = V.astype(">f8").tobytes()
    frec = np.zeros(F.shape[0], dtype=[("n", ">u2"), ("i", ">i4", 3)])
    frec["n"], frec["i"] = 3, F
    path = tmp_path / "be.ply"
    path.write_bytes(header + vrec + frec.tobytes())
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, V)
    assert np.array_equal(mesh.faces, F)


def test_binary_ply_skips_other_elements_and_list_properties(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        "obj_info some tool\n"
        "element material 2\nproperty uchar ambient_red\nproperty float power\n"
        "element vertex 4\nproperty int16 flags\nproperty float x\nproperty float y\n"
        "property float z\nproperty list uchar float weights\nproperty uint id\n"
        "element face 4\nproperty uchar kind\nproperty list uchar int vertex_indices\n"
        "property list uchar float texcoord\n"
        "element edge 2\nproperty int vertex1\nproperty int vertex2\n"
        "end_header\n").encode()
    body = b"".join(struct.pack("<Bf", 9, 1.5) for _ in range(2))
    for i, (x, y, z) in enumerate(V):
        k = i % 3                                  # list lengths differ per vertex
        body += struct.pack("<h3fB", -1, x, y, z, k) + struct.pack(f"<{k}f", *range(k))
        body += struct.pack("<I", 1000 + i)
    for tri in F:
        body += struct.pack("<BB3iB6f", 7, 3, *tri, 6, *([0.5] * 6))
    body += struct.pack("<4i", 0, 1, 2, 3)
    path = tmp_path / "extra.ply"
    path.write_bytes(header + body)
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, V)
    assert np.array_equal(mesh.faces, F)


def test_ascii_ply_extra_elements_quads_and_uv(tmp_path):
    text = (
        "ply\nformat ascii 1.0\ncomment quads and uv\n"
        "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
        "property float s\nproperty float t\nproperty list uchar int ring\n"
        "element face 2\nproperty list uchar int vertex_indices\nproperty uchar flag\n"
        "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
        "end_header\n"
        "0 0 0 0 0 0\n1 0 0 1 0 2 7 8\n1 1 0 1 1 1 3\n0 1 0 0 1 0\n"
        "0.5 1.5 0 0.5 1 0\n"
        "4 0 1 2 3 1\n3 3 2 4 0\n"
        "0 1\n")
    path = tmp_path / "a.ply"
    path.write_text(text)
    mesh = read_mesh(path)
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [3, 2, 4]]
    assert np.array_equal(mesh.uv, [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 1]])
    assert np.array_equal(mesh.uv_faces, mesh.faces)


def test_ply_writes_binary_doubles_and_uchar_int_lists(tmp_path):
    V, F = float64_sphere(1)
    path = write_mesh(tmp_path / "w.ply", Mesh(V, F))
    data = path.read_bytes()
    header, _, body = data.partition(b"end_header\n")
    assert b"format binary_little_endian 1.0" in header
    assert b"property double x" in header
    assert b"property list uchar int vertex_indices" in header
    assert len(body) == 24 * V.shape[0] + 13 * F.shape[0]
    text = write_mesh(tmp_path / "a.ply", Mesh(V, F), binary=False).read_text()
    assert "format ascii 1.0" in text


def test_ply_per_vertex_uv_round_trip(tmp_path):
    V, F = float64_sphere(1)
    uv = np.c_[V[:, 0] / 7, V[:, 2] / 5]
    back = read_mesh(write_mesh(tmp_path / "uv.ply", Mesh(V, F, uv=uv, uv_faces=F)))
    assert np.array_equal(back.uv, uv)
    assert np.array_equal(back.uv_faces, F)


# --------------------------------------------------------------------------- OFF


def test_off_comments_variants_colours_and_polygons(tmp_path):
    text = (
        "# leading comment\n"
        "COFF # colours follow\n"
        "\n"
        "5 2 0\n"
        "0 0 0 255 0 0 255\n"
        "1 0 0   0 255 0 255 # green\n"
        "1 1 0 0 0 255 255\n"
        "0 1 0 9 9 9 9\n"
        "0.5 1.5 0 1 1 1 1\n"
        "4 0 1 2 3 0.5 0.5 0.5\n"
        "3 3 2 4\n")
    path = tmp_path / "c.off"
    path.write_text(text)
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                                          [0.5, 1.5, 0]])
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [3, 2, 4]]


def test_off_counts_on_keyword_line_and_noff(tmp_path):
    path = tmp_path / "n.off"
    path.write_text("NOFF 3 1 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n")
    mesh = read_mesh(path)
    assert mesh.faces.tolist() == [[0, 1, 2]]
    assert np.array_equal(mesh.vertices[1], [1, 0, 0])


# --------------------------------------------------------------------------- 3MF


_CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"


def _write_3mf(path, model: str, *, rels: str | None = "default", part="3D/3dmodel.model",
               extra: dict | None = None):
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("[Content_Types].xml", "<Types/>")
        if rels == "default":
            rels = ('<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/'
                    'relationships"><Relationship Target="/' + part + '" Id="r0" '
                    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>'
                    '</Relationships>')
        if rels is not None:
            z.writestr("_rels/.rels", rels)
        z.writestr(part, model)
        for name, text in (extra or {}).items():
            z.writestr(name, text)


def _tetra_object(oid, *, prefix="", order="xyz"):
    pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    tris = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
    p = prefix
    verts = "".join(
        f"<{p}vertex " + " ".join(f'{a}="{dict(zip("xyz", v))[a]}"' for a in order) + "/>"
        for v in pts)
    tri = "".join(f'<{p}triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in tris)
    return (f'<{p}object id="{oid}" type="model"><{p}mesh><{p}vertices>{verts}</{p}vertices>'
            f"<{p}triangles>{tri}</{p}triangles></{p}mesh></{p}object>"), np.array(pts, float), \
        np.array(tris)


def test_3mf_centimetre_unit_build_transform_and_components(tmp_path):
    obj, P, T = _tetra_object(1)
    # Object 2 is an assembly: object 1 scaled by 2 along x, shifted by (5, 0, 0).
    assembly = ('<object id="2" type="model"><components>'
                '<component objectid="1" transform="2 0 0 0 1 0 0 0 1 5 0 0"/>'
                "</components></object>")
    model = (f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="centimeter" xmlns="{_CORE}">'
             f"<resources>{obj}{assembly}</resources><build>"
             '<item objectid="1" transform="0 1 0 -1 0 0 0 0 1 10 20 30"/>'
             '<item objectid="2" transform="1 0 0 0 1 0 0 0 1 0 0 -1"/>'
             "</build></model>")
    path = tmp_path / "cm.3mf"
    _write_3mf(path, model)
    mesh = read_mesh(path)
    R = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], float)
    first = (P @ R + [10, 20, 30]) * 10.0                  # row vectors: p @ M + t
    second = ((P * [2, 1, 1] + [5, 0, 0]) + [0, 0, -1]) * 10.0
    assert np.allclose(mesh.vertices, np.concatenate([first, second]))
    assert np.array_equal(mesh.faces, np.concatenate([T, T + 4]))
    assert mesh.metadata["unit"] == "millimeter"
    assert mesh.metadata["source_unit"] == "centimeter"
    assert signed_volume(mesh.vertices, mesh.faces) > 0


@pytest.mark.parametrize("unit,factor", [("micron", 1e-3), ("millimeter", 1.0),
                                         ("inch", 25.4), ("foot", 304.8),
                                         ("meter", 1000.0)])
def test_3mf_units(tmp_path, unit, factor):
    obj, P, _ = _tetra_object(3)
    model = (f'<model unit="{unit}" xmlns="{_CORE}"><resources>{obj}</resources>'
             '<build><item objectid="3"/></build></model>')
    path = tmp_path / "u.3mf"
    _write_3mf(path, model)
    assert np.allclose(read_mesh(path).vertices, P * factor)


def test_3mf_mirror_transform_keeps_faces_outward(tmp_path):
    obj, P, T = _tetra_object(1)
    model = (f'<model xmlns="{_CORE}"><resources>{obj}</resources><build>'
             '<item objectid="1" transform="-1 0 0 0 1 0 0 0 1 0 0 0"/></build></model>')
    path = tmp_path / "mirror.3mf"
    _write_3mf(path, model)
    mesh = read_mesh(path)
    assert signed_volume(mesh.vertices, mesh.faces) > 0


def test_3mf_prefixes_attribute_order_comments_and_default_part(tmp_path):
    obj, P, T = _tetra_object(7, prefix="m:", order="zxy")
    obj = obj.replace("<m:vertices>", "<m:vertices><!-- scanned -->")
    model = (f"<?xml version='1.0'?><m:model xmlns:m='{_CORE}'><m:resources>{obj}"
             "</m:resources><m:build><m:item objectid='7'/></m:build></m:model>")
    path = tmp_path / "prefixed.3mf"
    _write_3mf(path, model, rels=None)
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, P)
    assert np.array_equal(mesh.faces, T)


def test_3mf_start_part_from_rels_and_production_path(tmp_path):
    obj, P, T = _tetra_object(4)
    prod = "http://schemas.microsoft.com/3dmanufacturing/production/2015/06"
    sub = f'<model unit="millimeter" xmlns="{_CORE}"><resources>{obj}</resources><build/></model>'
    root = (f'<model unit="millimeter" xmlns="{_CORE}" xmlns:p="{prod}"><resources>'
            '<object id="9" type="model"><components>'
            '<component p:path="/3D/Objects/part.model" objectid="4" '
            'transform="1 0 0 0 1 0 0 0 1 0 0 2"/>'
            "</components></object></resources>"
            '<build><item objectid="9"/></build></model>')
    path = tmp_path / "prod.3mf"
    _write_3mf(path, root, part="3D/main.model", extra={"3D/Objects/part.model": sub})
    mesh = read_mesh(path)
    assert np.array_equal(mesh.vertices, P + [0, 0, 2])
    assert np.array_equal(mesh.faces, T)


def test_3mf_written_package_is_valid(tmp_path):
    V, F = float64_sphere(1)
    path = write_mesh(tmp_path / "w.3mf", Mesh(V, F, name='a "quoted" <name>'))
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        assert names[0] == "[Content_Types].xml"
        assert set(names) == {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"}
        types = ET.fromstring(z.read("[Content_Types].xml"))
        exts = {d.get("Extension"): d.get("ContentType") for d in types}
        assert exts["model"] == "application/vnd.ms-package.3dmanufacturing-3dmodel+xml"
        rels = ET.fromstring(z.read("_rels/.rels"))
        assert rels[0].get("Target") == "/3D/3dmodel.model"
        model = ET.fromstring(z.read("3D/3dmodel.model"))
    ns = {"c": _CORE}
    assert model.tag == f"{{{_CORE}}}model"
    assert model.get("unit") == "millimeter"
    objects = model.findall("c:resources/c:object", ns)
    assert len(objects) == 1 and objects[0].get("type") == "model"
    assert objects[0].get("name") == 'a "quoted" <name>'
    assert len(model.findall("c:build/c:item", ns)) == 1
    verts = model.findall("c:resources/c:object/c:mesh/c:vertices/c:vertex", ns)
    assert np.array_equal([[float(v.get(a)) for a in "xyz"] for v in verts], V)
    again = write_mesh(tmp_path / "w2.3mf", Mesh(V, F, name='a "quoted" <name>'))
    assert again.read_bytes() == path.read_bytes()          # deterministic bytes


# --------------------------------------------------------------------------- GLB


def _parse_glb(data: bytes):
    magic, version, length = struct.unpack_from("<4sII", data)
    assert magic == b"glTF" and version == 2 and length == len(data)
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A and jlen % 4 == 0
    doc = json.loads(data[20:20 + jlen])
    binary = b""
    if 20 + jlen < length:
        blen, btype = struct.unpack_from("<II", data, 20 + jlen)
        assert btype == 0x004E4942 and blen % 4 == 0
        assert 20 + jlen + 8 + blen == length
        binary = data[28 + jlen:28 + jlen + blen]
    return doc, binary


def _check_gltf_structure(doc, binary):
    assert doc["asset"]["version"] == "2.0"
    assert doc["buffers"][0]["byteLength"] <= len(binary)
    assert len(binary) - doc["buffers"][0]["byteLength"] < 4
    for view in doc["bufferViews"]:
        assert view["byteOffset"] % 4 == 0
        assert view["byteOffset"] + view["byteLength"] <= doc["buffers"][0]["byteLength"]
    sizes = {5126: 4, 5125: 4}
    widths = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}
    for acc in doc["accessors"]:
        view = doc["bufferViews"][acc["bufferView"]]
        assert acc["count"] * sizes[acc["componentType"]] * widths[acc["type"]] \
            == view["byteLength"]
    prim = doc["meshes"][0]["primitives"][0]
    pos = doc["accessors"][prim["attributes"]["POSITION"]]
    assert pos["type"] == "VEC3" and pos["componentType"] == 5126
    idx = doc["accessors"][prim["indices"]]
    assert idx["componentType"] == 5125 and idx["type"] == "SCALAR"
    assert idx["count"] % 3 == 0
    view = doc["bufferViews"][pos["bufferView"]]
    P = np.frombuffer(binary, "<f4", pos["count"] * 3, view["byteOffset"]).reshape(-1, 3)
    assert P.min(axis=0).tolist() == pos["min"] and P.max(axis=0).tolist() == pos["max"]
    iview = doc["bufferViews"][idx["bufferView"]]
    I = np.frombuffer(binary, "<u4", idx["count"], iview["byteOffset"])
    assert I.max() < pos["count"]
    return P, I.reshape(-1, 3)


def test_glb_structure(tmp_path):
    V, F = float32_sphere(2)
    data = write_mesh(tmp_path / "s.glb", Mesh(V, F)).read_bytes()
    doc, binary = _parse_glb(data)
    P, I = _check_gltf_structure(doc, binary)
    assert np.array_equal(P, V) and np.array_equal(I, F)
    assert "TEXCOORD_0" not in doc["meshes"][0]["primitives"][0]["attributes"]
    assert doc["scenes"][doc["scene"]]["nodes"] == [0]


def test_glb_texture_uv_split_and_round_trip(tmp_path):
    mesh = _textured_mesh()
    data = write_mesh(tmp_path / "t.glb", mesh).read_bytes()
    doc, binary = _parse_glb(data)
    P, I = _check_gltf_structure(doc, binary)
    prim = doc["meshes"][0]["primitives"][0]
    material = doc["materials"][prim["material"]]
    tex_index = material["pbrMetallicRoughness"]["baseColorTexture"]["index"]
    image = doc["images"][doc["textures"][tex_index]["source"]]
    assert image["mimeType"] == "image/png"
    back = read_mesh(tmp_path / "t.glb")
    assert np.array_equal(back.texture, mesh.texture)
    # Every corner keeps its position and its uv (float32 precision).
    assert np.allclose(back.vertices[back.faces], mesh.vertices[mesh.faces], atol=1e-6)
    assert np.allclose(back.uv[back.uv_faces], mesh.uv[mesh.uv_faces], atol=1e-6)
    # glTF stores v flipped (origin at the top left).
    acc = doc["accessors"][prim["attributes"]["TEXCOORD_0"]]
    view = doc["bufferViews"][acc["bufferView"]]
    stored = np.frombuffer(binary, "<f4", acc["count"] * 2, view["byteOffset"]).reshape(-1, 2)
    assert np.allclose(stored[:, 1], 1.0 - back.uv[:, 1], atol=1e-7)
    # Split vertices: one per distinct (vertex, uv) pair.
    pairs = np.unique(np.c_[mesh.faces.ravel(), mesh.uv_faces.ravel()], axis=0)
    assert back.n_vertices == pairs.shape[0]


def test_glb_reader_handles_strips_uint16_and_several_primitives(tmp_path):
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype="<f4")
    strip = np.array([0, 1, 2, 3], dtype="<u2")
    tri8 = np.array([0, 1, 2], dtype="u1")
    binary = positions.tobytes() + strip.tobytes() + tri8.tobytes() + b"\0"
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 8},
                        {"buffer": 0, "byteOffset": 56, "byteLength": 3}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 1, "componentType": 5123, "count": 4, "type": "SCALAR"},
                      {"bufferView": 2, "componentType": 5121, "count": 3, "type": "SCALAR"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 5}]},
                   {"primitives": [{"attributes": {"POSITION": 0}, "indices": 2}]}],
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    body += struct.pack("<II", len(binary), 0x004E4942) + binary
    path = tmp_path / "strip.glb"
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    mesh = read_mesh(path)
    assert mesh.n_vertices == 8
    assert mesh.faces.tolist() == [[0, 1, 2], [2, 1, 3], [4, 5, 6]]


def test_glb_loads_in_trimesh(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    V, F = float32_sphere(2)
    path = write_mesh(tmp_path / "s.glb", Mesh(V, F))
    loaded = trimesh.load(path, force="mesh", process=False)
    assert np.array_equal(np.asarray(loaded.vertices), V)
    assert np.array_equal(np.asarray(loaded.faces), F)
    textured = write_mesh(tmp_path / "t.glb", _textured_mesh())
    scene = trimesh.load(textured, process=False)
    geometry = list(scene.geometry.values())[0]
    assert geometry.visual.uv.shape == (geometry.vertices.shape[0], 2)


@pytest.mark.parametrize("ext", ["stl", "obj", "ply", "off", "3mf"])
def test_other_formats_load_in_trimesh(tmp_path, ext):
    trimesh = pytest.importorskip("trimesh")
    if ext == "3mf":
        pytest.importorskip("lxml")  # trimesh's 3MF reader needs it
    V, F = float32_sphere(1)
    path = write_mesh(tmp_path / f"x.{ext}", Mesh(V, F))
    loaded = trimesh.load(path, force="mesh", process=False)
    assert loaded.faces.shape == F.shape
    assert abs(loaded.volume - signed_volume(V, F)) < 1e-3


# --------------------------------------------------------------------------- sniffing


def test_sniff_recognises_every_format(tmp_path):
    V, F = float32_sphere(1)
    mesh = Mesh(V, F)
    expected = {"stl": "stl-binary", "obj": "obj", "ply": "ply", "off": "off",
                "3mf": "3mf", "glb": "glb"}
    for ext, kind in expected.items():
        data = write_mesh(tmp_path / f"s.{ext}", mesh).read_bytes()
        assert sniff_format(data) == kind, ext
        assert mismatch_hint(data, ext) is None
    ascii_stl = write_mesh(tmp_path / "a.stl", mesh, binary=False).read_bytes()
    assert sniff_format(ascii_stl) == "stl-ascii"
    assert sniff_format(b"\x00\x01garbage") is None


# --------------------------------------------------------------------------- atomic writes


def test_write_leaves_no_temporary_files(tmp_path):
    V, F = float32_sphere(1)
    for ext in WRITE_FORMATS:
        write_mesh(tmp_path / f"x{ext}", Mesh(V, F))
    write_mesh(tmp_path / "t.obj", _textured_mesh())
    names = sorted(p.name for p in tmp_path.iterdir())
    assert not [n for n in names if n.startswith(".") or n.endswith(".tmp")]
    assert len(names) == len(WRITE_FORMATS) + 3


def test_failed_write_leaves_nothing_and_keeps_old_file(tmp_path, monkeypatch):
    import geotex.io as gio

    V, F = float32_sphere(1)
    target = tmp_path / "keep.ply"
    target.write_bytes(b"old content")

    def explode(fh, mesh, *, path, binary=True):
        fh.write(b"ply\nformat binary_little_endian 1.0\n")
        raise RuntimeError("disk on fire")

    monkeypatch.setitem(gio._WRITERS, "ply", explode)
    with pytest.raises(RuntimeError, match="disk on fire"):
        write_mesh(target, Mesh(V, F))
    assert target.read_bytes() == b"old content"
    with pytest.raises(RuntimeError, match="disk on fire"):
        write_mesh(tmp_path / "new.ply", Mesh(V, F))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.ply"]


def test_failed_textured_obj_write_leaves_none_of_the_three_files(tmp_path, monkeypatch):
    from geotex.io import obj as obj_module

    def broken_png(texture):
        raise OSError("encoder failure")

    monkeypatch.setattr(obj_module, "texture_to_png_bytes", broken_png)
    with pytest.raises(OSError, match="encoder failure"):
        write_mesh(tmp_path / "skin.obj", _textured_mesh())
    assert list(tmp_path.iterdir()) == []


def test_atomic_output_text_mode_and_permissions(tmp_path):
    from geotex.io import atomic

    path = tmp_path / "out.json"
    with atomic_output(path, "w") as fh:
        fh.write('{"a": 1}')
        assert not path.exists()
    assert json.loads(path.read_text()) == {"a": 1}
    assert os.stat(path).st_mode & 0o777 == 0o666 & ~atomic._UMASK
    with pytest.raises(ValueError):
        with atomic_output(tmp_path / "x.bin", "rb"):
            pass
    with pytest.raises(KeyError):
        with atomic_output(tmp_path / "y.bin") as fh:
            fh.write(b"partial")
            raise KeyError("stop")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_atomic_group_commits_all_or_nothing(tmp_path):
    with atomic_group() as group:
        group.open(tmp_path / "a.txt", "w").write("a")
        group.open(tmp_path / "b.bin").write(b"b")
    assert (tmp_path / "a.txt").read_text() == "a"
    with pytest.raises(ZeroDivisionError):
        with atomic_group() as group:
            group.open(tmp_path / "a.txt", "w").write("changed")
            group.open(tmp_path / "c.txt", "w").write("c")
            1 / 0
    assert (tmp_path / "a.txt").read_text() == "a"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.bin"]


def test_atomic_output_keeps_extension_for_format_sniffing_writers(tmp_path):
    from PIL import Image

    image = np.arange(48, dtype=np.uint8).reshape(4, 4, 3)
    with atomic_output(tmp_path / "pic.png") as fh:
        assert fh.name.endswith(".png")
        Image.fromarray(image).save(fh)                 # format inferred from the name
    with atomic_output(tmp_path / "arrays.npz") as fh:
        np.savez(fh, a=np.arange(5))
    assert np.array_equal(np.asarray(Image.open(tmp_path / "pic.png")), image)
    assert np.array_equal(np.load(tmp_path / "arrays.npz")["a"], np.arange(5))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arrays.npz", "pic.png"]
