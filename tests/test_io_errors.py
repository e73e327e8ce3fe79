"""Every documented failure of geotex.io raises a clear, specific GeotexError."""

from __future__ import annotations

import json
import struct
import zipfile

import numpy as np
import pytest

from geotex.errors import (GeotexError, InputError, MeshFileError, MissingFileError,
                           UnsupportedFormatError)
from geotex.io import WRITE_FORMATS, read_mesh, write_mesh
from geotex.mesh import Mesh

ALL = ["stl", "obj", "ply", "off", "3mf", "glb"]
CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"


def tetra() -> Mesh:
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    return Mesh(V, F)


def write(tmp_path, name: str, content) -> str:
    path = tmp_path / name
    if isinstance(content, str):
        path.write_text(content)
    else:
        path.write_bytes(content)
    return path


def one_line(exc_info) -> str:
    message = str(exc_info.value)
    assert "\n" not in message
    return message


# --------------------------------------------------------------------------- paths


def test_missing_file(tmp_path):
    with pytest.raises(MissingFileError, match=r"nothing\.stl: no such file") as exc:
        read_mesh(tmp_path / "nothing.stl")
    one_line(exc)
    assert isinstance(exc.value, FileNotFoundError)


def test_directory_is_not_a_file(tmp_path):
    (tmp_path / "dir.obj").mkdir()
    with pytest.raises(MissingFileError, match=r"no such file \(a directory\)"):
        read_mesh(tmp_path / "dir.obj")


def test_unknown_extension_lists_supported(tmp_path):
    path = write(tmp_path, "mesh.xyz", "1 2 3\n")
    with pytest.raises(UnsupportedFormatError,
                       match=r"unsupported extension '\.xyz'; supported: \.stl, \.obj, "
                             r"\.ply, \.off, \.3mf, \.glb"):
        read_mesh(path)
    no_ext = write(tmp_path, "mesh", "1 2 3\n")
    with pytest.raises(UnsupportedFormatError, match="no file extension"):
        read_mesh(no_ext)
    with pytest.raises(UnsupportedFormatError, match="unsupported format 'vrml'"):
        read_mesh(path, format="vrml")


def test_unknown_extension_with_recognisable_content_gets_a_hint(tmp_path):
    data = write_mesh(tmp_path / "a.stl", tetra()).read_bytes()
    path = write(tmp_path, "a.bin", data)
    with pytest.raises(UnsupportedFormatError,
                       match="content looks like a binary STL file; rename it with the "
                             r"\.stl extension"):
        read_mesh(path)


@pytest.mark.parametrize("ext", ALL)
def test_empty_file(tmp_path, ext):
    path = write(tmp_path, f"empty.{ext}", b"")
    with pytest.raises(MeshFileError, match=r"empty\.\w+: file is empty$"):
        read_mesh(path)


# --------------------------------------------------------------------------- wrong content


@pytest.mark.parametrize("ext", ALL)
def test_binary_garbage(tmp_path, ext):
    garbage = np.random.default_rng(0).integers(0, 256, 1000, dtype=np.uint8).tobytes()
    path = write(tmp_path, f"garbage.{ext}", garbage)
    with pytest.raises(MeshFileError) as exc:
        read_mesh(path)
    message = one_line(exc)
    assert message.startswith(str(path) + ": ")


@pytest.mark.parametrize("actual,named", [
    ("stl", "ply"), ("stl", "obj"), ("obj", "stl"), ("ply", "off"), ("off", "obj"),
    ("3mf", "glb"), ("glb", "3mf"), ("ply", "stl")])
def test_wrong_extension_is_explained_not_parsed(tmp_path, actual, named):
    data = write_mesh(tmp_path / f"real.{actual}", tetra()).read_bytes()
    path = write(tmp_path, f"renamed.{named}", data)
    descriptions = {"stl": "a binary STL file", "obj": "an OBJ file", "ply": "a PLY file",
                    "off": "an OFF file", "3mf": r"a 3MF file \(zip archive\)",
                    "glb": r"a GLB \(binary glTF\) file"}
    with pytest.raises(MeshFileError,
                       match=f"content looks like {descriptions[actual]}; rename it with "
                             rf"the \.{actual} extension$") as exc:
        read_mesh(path)
    one_line(exc)


def test_ascii_stl_named_obj_is_not_read_as_empty_obj(tmp_path):
    data = write_mesh(tmp_path / "a.stl", tetra(), binary=False).read_bytes()
    path = write(tmp_path, "a.obj", data)
    with pytest.raises(MeshFileError, match="unknown statement 'solid'.*ASCII STL file"):
        read_mesh(path)


@pytest.mark.parametrize("ext,binary", [(e, b) for e in ALL for b in (True, False)])
def test_truncated_or_corrupted_files_raise_only_geotex_errors(tmp_path, ext, binary):
    rng = np.random.default_rng(1)
    V = rng.random((20, 3))
    F = rng.integers(0, 20, (30, 3))
    mesh = Mesh(V, F, uv=rng.random((20, 2)), uv_faces=F,
                texture=rng.integers(0, 256, (3, 4, 3), dtype=np.uint8))
    data = write_mesh(tmp_path / f"ok.{ext}", mesh, binary=binary).read_bytes()
    cuts = sorted(set(np.linspace(1, len(data) - 1, 25).astype(int).tolist()))
    path = tmp_path / f"bad.{ext}"
    for cut in cuts:
        for variant in (data[:cut], _flip(data, rng)):
            path.write_bytes(variant)
            try:
                read_mesh(path)
            except GeotexError as exc:
                assert "\n" not in str(exc)
                assert str(exc).startswith(str(path))


def _flip(data: bytes, rng) -> bytes:
    arr = bytearray(data)
    for j in rng.integers(0, len(arr), 4):
        arr[j] = int(rng.integers(0, 256))
    return bytes(arr)


# --------------------------------------------------------------------------- STL


def test_truncated_binary_stl_says_expected_size(tmp_path):
    data = write_mesh(tmp_path / "a.stl", tetra()).read_bytes()
    path = write(tmp_path, "cut.stl", data[:-7])
    with pytest.raises(MeshFileError,
                       match=r"binary STL is truncated: the header announces 4 triangles, "
                             r"which needs 284 bytes, but the file has 277 bytes"):
        read_mesh(path)


def test_binary_stl_with_trailing_bytes(tmp_path):
    data = write_mesh(tmp_path / "a.stl", tetra()).read_bytes()
    path = write(tmp_path, "long.stl", data + b"\0" * 10)
    with pytest.raises(MeshFileError, match=r"needs 284 bytes, but the file has 294 bytes"):
        read_mesh(path)


def test_short_non_stl(tmp_path):
    path = write(tmp_path, "short.stl", b"hello")
    with pytest.raises(MeshFileError, match="too short for a binary STL"):
        read_mesh(path)


def test_truncated_binary_stl_with_solid_header(tmp_path):
    data = write_mesh(tmp_path / "a.stl", tetra()).read_bytes()
    path = write(tmp_path, "cut.stl", b"solid " + data[6:-20])
    with pytest.raises(MeshFileError, match=r"not a binary STL either .*needs 284 bytes"):
        read_mesh(path)


@pytest.mark.parametrize("body,message", [
    ("facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n",
     r"ASCII STL line 2: malformed facet near 'facet'"),
    ("facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
     "vertex 1 1 1\nendloop\nendfacet\n", "line 2: malformed facet"),
    ("facet normal 0 0 1\nouter loop\nvertex 0 0 zero\nvertex 1 0 0\nvertex 0 1 0\n"
     "endloop\nendfacet\n", "malformed vertex coordinate 'zero'"),
    ("facet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\n"
     "endloop\nendfacet\n", r"non-finite coordinates at vertex 0 \(facet 0, corner 0\)"),
])
def test_malformed_ascii_stl(tmp_path, body, message):
    path = write(tmp_path, "bad.stl", "solid bad\n" + body + "endsolid bad\n")
    with pytest.raises(MeshFileError, match=message) as exc:
        read_mesh(path)
    one_line(exc)


def test_ascii_stl_structure_errors(tmp_path):
    facet = ("facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 "
             "endloop endfacet\n")
    missing_end = write(tmp_path, "a.stl", "solid a\n" + facet)
    with pytest.raises(MeshFileError, match="ends without 'endsolid'"):
        read_mesh(missing_end)
    outside = write(tmp_path, "b.stl", "solid a\nendsolid a\n" + facet)
    with pytest.raises(MeshFileError, match="facet outside a 'solid ... endsolid' block"):
        read_mesh(outside)
    nested = write(tmp_path, "c.stl", "solid a\nsolid b\n" + facet + "endsolid b\n")
    with pytest.raises(MeshFileError, match="line 2: 'solid' inside another solid"):
        read_mesh(nested)


def test_nonfinite_binary_stl_names_vertex(tmp_path):
    data = bytearray(write_mesh(tmp_path / "a.stl", tetra()).read_bytes())
    struct.pack_into("<f", data, 84 + 50 * 2 + 12 + 12 + 4, float("inf"))  # facet 2, corner 1, y
    path = write(tmp_path, "inf.stl", bytes(data))
    with pytest.raises(MeshFileError,
                       match=r"non-finite coordinates at vertex 7 \(facet 2, corner 1\)"):
        read_mesh(path)


# --------------------------------------------------------------------------- OBJ


@pytest.mark.parametrize("faces,message", [
    ("f 1 2 9\n", r"OBJ line 5: face vertex index 9 is out of range \(the file defines 4 "
                  r"vertices\)"),
    ("f 1 0 2\n", r"OBJ line 5: face vertex index 0 is invalid \(OBJ indices start at 1\)"),
    ("f -1 -2 -5\n", r"face vertex index -5 is out of range .*4 before this face"),
    ("f 1 2 x\n", r"OBJ line 5: bad vertex index 'x' in a face"),
    ("vt 0 0\nf 1/1 2/2 3/1\n", r"OBJ line 6: face texture index 2 is out of range"),
])
def test_obj_face_index_errors(tmp_path, faces, message):
    path = write(tmp_path, "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n" + faces)
    with pytest.raises(MeshFileError, match=message) as exc:
        read_mesh(path)
    one_line(exc)


def test_obj_vertex_errors(tmp_path):
    short = write(tmp_path, "a.obj", "v 0 0 0\nv 1 0\nf 1 2 1\n")
    with pytest.raises(MeshFileError, match=r"OBJ line 2: vertex needs x y z, got 2 values"):
        read_mesh(short)
    word = write(tmp_path, "b.obj", "# c\nv 0 0 0\nv 1 zero 0\n")
    with pytest.raises(MeshFileError, match=r"OBJ line 3: bad vertex coordinate 'zero'"):
        read_mesh(word)
    nan = write(tmp_path, "c.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(MeshFileError, match=r"non-finite coordinates at vertex 1"):
        read_mesh(nan)


def test_obj_binary_content(tmp_path):
    path = write(tmp_path, "bin.obj", b"v 0 0 0\n\x00\x01\x02")
    with pytest.raises(MeshFileError, match="binary content, not a text OBJ file"):
        read_mesh(path)


# --------------------------------------------------------------------------- PLY


@pytest.mark.parametrize("content,message", [
    (b"plx\nformat ascii 1.0\nend_header\n", "not a PLY file: the first line must be 'ply'"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n0 0 0\n",
     "PLY header has no 'end_header' line"),
    (b"ply\nformat ascii 2.0\nformat weird 1.0\nend_header\n",
     r"bad PLY header line 3: unknown format 'weird'"),
    (b"ply\nformat ascii 1.0\nelement vertex many\nend_header\n",
     r"bad PLY header line 3: expected 'element NAME COUNT'"),
    (b"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
     "bad PLY header line 3: property before any element"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
     r"bad PLY header line 4: unknown type 'quad'"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\nend_header\n",
     "list count type must be an integer type"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nsomething\nend_header\n",
     "unknown keyword 'something'"),
    (b"ply\nelement vertex 0\nend_header\n", "bad PLY header: no 'format' line"),
    (b"ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n",
     "PLY file has no 'vertex' element"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     b"end_header\n1 2\n", r"lacks the scalar properties z \(x, y, z are required\)"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     b"property float z\nelement face 1\nproperty int flags\nend_header\n0 0 0\n1\n",
     "face element has no 'vertex_indices' list property"),
])
def test_bad_ply_headers(tmp_path, content, message):
    path = write(tmp_path, "bad.ply", content)
    with pytest.raises(MeshFileError, match=message) as exc:
        read_mesh(path)
    one_line(exc)


def test_truncated_binary_ply_says_expected_bytes(tmp_path):
    data = write_mesh(tmp_path / "a.ply", tetra()).read_bytes()
    header_len = data.index(b"end_header\n") + len(b"end_header\n")
    cut = write(tmp_path, "cut.ply", data[:header_len + 50])
    with pytest.raises(MeshFileError,
                       match=r"binary PLY is truncated: element 'vertex' needs 96 bytes at "
                             rf"byte {header_len} but only 50 remain"):
        read_mesh(cut)
    faces_cut = write(tmp_path, "cut2.ply", data[:-5])
    with pytest.raises(MeshFileError, match=r"element 'face' needs 52 bytes .* only 47 remain"):
        read_mesh(faces_cut)


def test_truncated_binary_ply_with_variable_lists(tmp_path):
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 2\n"
              b"property list uchar int vertex_indices\nend_header\n")
    body = np.zeros(9, "<f4").tobytes() + struct.pack("<B4i", 4, 0, 1, 2, 0)
    path = write(tmp_path, "v.ply", header + body + struct.pack("<B2i", 3, 0, 1))
    with pytest.raises(MeshFileError, match="binary PLY is truncated: element 'face'"):
        read_mesh(path)


def test_truncated_ascii_ply(tmp_path):
    path = write(tmp_path, "a.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                 "property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1\n")
    with pytest.raises(MeshFileError,
                       match="ASCII PLY is truncated: element 'vertex' needs at least 9 values"):
        read_mesh(path)


def test_ply_out_of_range_index_and_bad_number(tmp_path):
    base = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n")
    path = write(tmp_path, "r.ply", base + "3 0 1 3\n")
    with pytest.raises(MeshFileError, match=r"r\.ply: faces references vertex indices "
                                            r"outside \[0, 3\)") as exc:
        read_mesh(path)
    assert exc.value.path == str(path)
    bad = write(tmp_path, "n.ply", base.replace("0 1 0\n", "0 one 0\n") + "3 0 1 2\n")
    with pytest.raises(MeshFileError, match="ASCII PLY has a bad number 'one'"):
        read_mesh(bad)


def test_ply_nonfinite_vertex(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]], dtype="<f8")
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n"
              b"property double y\nproperty double z\nend_header\n")
    path = write(tmp_path, "inf.ply", header + V.tobytes())
    with pytest.raises(MeshFileError, match=r"non-finite coordinates at vertex 2: "
                                            r"\[0\.0, inf, 0\.0\]"):
        read_mesh(path)


def test_huge_finite_coordinates_are_fine(tmp_path):
    V = np.array([[3.4e38, 0, 0], [-3.4e38, 0, 0], [0, 1e308, 0]])
    mesh = Mesh(V, [[0, 1, 2]])
    for ext in ("ply", "obj", "off", "3mf"):
        back = read_mesh(write_mesh(tmp_path / f"big.{ext}", mesh))
        assert np.array_equal(back.vertices, V), ext


# --------------------------------------------------------------------------- OFF


@pytest.mark.parametrize("content,message", [
    ("# only a comment\n", "OFF file has no content"),
    ("OBJ\n3 1 0\n", "not an OFF file: it must start with 'OFF', found 'OBJ'"),
    ("OFF\n3 one 0\n", r"bad OFF counts on line 2"),
    ("OFF\n-3 1 0\n", r"bad OFF counts on line 2"),
    ("OFF\n3 1 0 7\n", r"bad OFF counts on line 2"),
    ("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
     "OFF header announces 4 vertices and 1 faces but the file has only 4 data lines"),
    ("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "OFF line 4: vertex needs x y z, got 2"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n",
     "OFF line 6: face announces 4 corners but lists 3 values"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
     r"OFF line 6: vertex index 3 out of range \(the file has 3 vertices\)"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 x\n", "OFF line 6: bad vertex index 'x'"),
    ("OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", "OFF line 4: bad number 'zero'"),
    ("OFF BINARY\n", "binary OFF is not supported"),
    ("4OFF\n1 0 0\n0 0 0 0\n", r"4OFF \(4D / n-dimensional OFF\) is not supported"),
])
def test_bad_off(tmp_path, content, message):
    path = write(tmp_path, "bad.off", content)
    with pytest.raises(MeshFileError, match=message) as exc:
        read_mesh(path)
    one_line(exc)


# --------------------------------------------------------------------------- 3MF


def _zip(path, members: dict):
    with zipfile.ZipFile(path, "w") as z:
        for name, text in members.items():
            z.writestr(name, text)
    return path


def _model(body: str, unit="millimeter") -> str:
    return f'<model unit="{unit}" xmlns="{CORE}">{body}</model>'


_TRI = ('<resources><object id="1" type="model"><mesh><vertices>'
        '<vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/>'
        '</vertices><triangles><triangle v1="0" v2="1" v3="{last}"/></triangles></mesh>'
        '</object></resources><build><item objectid="1"{transform}/></build>')


@pytest.mark.parametrize("members,message", [
    ({"3D/other.model": "<model/>"},
     r"3MF archive has no model part \(3D/3dmodel\.model\)"),
    ({"3D/3dmodel.model": "<model><resources></model>"},
     r"malformed XML in 3D/3dmodel\.model: mismatched tag: line 1"),
    ({"3D/3dmodel.model": "<notmodel/>"}, "is not a 3MF model"),
    ({"3D/3dmodel.model": _model(_TRI.format(last=2, transform=""), unit="furlong")},
     "unknown 3MF unit 'furlong'"),
    ({"3D/3dmodel.model": _model(_TRI.format(last=3, transform=""))},
     r"object 1: triangle 0 references vertex \[0, 1, 3\] but the object has 3 vertices"),
    ({"3D/3dmodel.model": _model(_TRI.format(last=2, transform=' transform="1 0 0"'))},
     r"bad transform '1 0 0' \(expected 12 numbers\)"),
    ({"3D/3dmodel.model": _model(_TRI.format(last=2, transform="").replace(
        'objectid="1"', 'objectid="5"'))}, "no object with id '5'"),
    ({"3D/3dmodel.model": _model(_TRI.format(last=2, transform="").replace(
        'x="1"', 'x="one"'))}, "bad vertex coordinate 'one'"),
    ({"3D/3dmodel.model": _model(
        '<resources><object id="1"><components><component objectid="2"/></components>'
        '</object><object id="2"><components><component objectid="1"/></components>'
        '</object></resources><build><item objectid="1"/></build>')},
     "contains itself through its components"),
    ({"_rels/.rels": "<Relationships", "3D/3dmodel.model": "<model/>"},
     r"malformed XML in _rels/\.rels"),
])
def test_bad_3mf(tmp_path, members, message):
    path = _zip(tmp_path / "bad.3mf", members)
    with pytest.raises(MeshFileError, match=message) as exc:
        read_mesh(path)
    one_line(exc)


def test_3mf_not_a_zip(tmp_path):
    path = write(tmp_path, "text.3mf", "<model/>")
    with pytest.raises(MeshFileError, match="not a 3MF file: it is not a zip archive"):
        read_mesh(path)


def test_3mf_nonfinite_vertex(tmp_path):
    model = _model(_TRI.format(last=2, transform="").replace('y="1"', 'y="INF"'))
    path = _zip(tmp_path / "inf.3mf", {"3D/3dmodel.model": model})
    with pytest.raises(MeshFileError, match=r"non-finite coordinates at vertex 2"):
        read_mesh(path)


# --------------------------------------------------------------------------- GLB


def _glb_bytes(doc: dict, binary: bytes = b"") -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    if binary:
        binary += b"\0" * (-len(binary) % 4)
        body += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def test_glb_header_errors(tmp_path):
    good = write_mesh(tmp_path / "ok.glb", tetra()).read_bytes()
    cases = [
        (b"GLTF" + good[4:], r"not a GLB file: bad magic b'GLTF' \(expected b'glTF'\)"),
        (good[:4] + struct.pack("<I", 1) + good[8:], "GLB version 1 is not supported"),
        (good[:-8], rf"GLB is truncated: the header announces {len(good)} bytes but the "
                    rf"file has {len(good) - 8}"),
        (good + b"\0\0\0\0", "GLB is damaged: the header announces"),
        (good[:8], "shorter than the 12-byte GLB header"),
    ]
    for i, (data, message) in enumerate(cases):
        path = write(tmp_path, f"bad{i}.glb", data)
        with pytest.raises(MeshFileError, match=message):
            read_mesh(path)


def test_glb_chunk_and_json_errors(tmp_path):
    bad_json = b"{not json"
    bad_json += b" " * (-len(bad_json) % 4)
    body = struct.pack("<II", len(bad_json), 0x4E4F534A) + bad_json
    path = write(tmp_path, "j.glb", struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    with pytest.raises(MeshFileError, match="GLB has malformed JSON"):
        read_mesh(path)
    long_chunk = struct.pack("<II", 400, 0x4E4F534A) + b"{}  "
    path = write(tmp_path, "c.glb",
                 struct.pack("<4sII", b"glTF", 2, 12 + len(long_chunk)) + long_chunk)
    with pytest.raises(MeshFileError, match="chunk at byte 12 announces 400 bytes"):
        read_mesh(path)


def test_glb_accessor_outside_buffer(tmp_path):
    doc = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": 12}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 12}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}
    path = write(tmp_path, "a.glb", _glb_bytes(doc, np.zeros(3, "<f4").tobytes()))
    with pytest.raises(MeshFileError, match=r"accessors\[0\] needs 36 bytes but its "
                                            r"bufferView has 12"):
        read_mesh(path)
    doc["bufferViews"][0]["byteLength"] = 64
    path = write(tmp_path, "b.glb", _glb_bytes(doc, np.zeros(3, "<f4").tobytes()))
    with pytest.raises(MeshFileError, match=r"bufferViews\[0\] .* lies outside its 12-byte "
                                            "buffer"):
        read_mesh(path)
    doc["accessors"][0]["bufferView"] = 3
    path = write(tmp_path, "c.glb", _glb_bytes(doc, np.zeros(3, "<f4").tobytes()))
    with pytest.raises(MeshFileError, match=r"bufferViews\[3\] does not exist"):
        read_mesh(path)


def test_glb_index_out_of_range(tmp_path):
    P = np.zeros((3, 3), "<f4")
    idx = np.array([0, 1, 3], "<u4")
    doc = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": 48}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                           {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                         {"bufferView": 1, "componentType": 5125, "count": 3,
                          "type": "SCALAR"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]}
    path = write(tmp_path, "i.glb", _glb_bytes(doc, P.tobytes() + idx.tobytes()))
    with pytest.raises(MeshFileError, match=r"index 3 out of range \(3 vertices\)"):
        read_mesh(path)


# --------------------------------------------------------------------------- writing


def test_write_errors(tmp_path):
    mesh = tetra()
    with pytest.raises(UnsupportedFormatError, match=r"unsupported extension '\.dae'"):
        write_mesh(tmp_path / "a.dae", mesh)
    with pytest.raises(MeshFileError, match="directory .* does not exist"):
        write_mesh(tmp_path / "missing" / "a.stl", mesh)
    (tmp_path / "taken.stl").mkdir()
    with pytest.raises(MeshFileError, match="the path is a directory"):
        write_mesh(tmp_path / "taken.stl", mesh)
    with pytest.raises(InputError, match="mesh must be a geotex.mesh.Mesh, got tuple"):
        write_mesh(tmp_path / "a.stl", (mesh.vertices, mesh.faces))
    huge = Mesh(np.array([[1e39, 0, 0], [0, 1, 0], [0, 0, 1]]), [[0, 1, 2]])
    with pytest.raises(MeshFileError, match="float32 range of binary STL; write an ASCII"):
        write_mesh(tmp_path / "huge.stl", huge)
    with pytest.raises(MeshFileError, match="float32 range of glTF"):
        write_mesh(tmp_path / "huge.glb", huge)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken.stl"]
    assert read_mesh(write_mesh(tmp_path / "huge_ascii.stl", huge, binary=False)).vertices[
        0, 0] == 1e39


@pytest.mark.parametrize("ext", [e.lstrip(".") for e in WRITE_FORMATS])
def test_failed_write_of_each_format_leaves_nothing(tmp_path, monkeypatch, ext):
    import geotex.io as gio
    from geotex.io import obj as obj_module

    def fail(*args, **kwargs):
        raise RuntimeError("interrupted")

    if ext == "obj":
        monkeypatch.setattr(obj_module, "format_rows", fail)
    else:
        monkeypatch.setitem(gio._WRITERS, ext, fail)
    with pytest.raises(RuntimeError, match="interrupted"):
        write_mesh(tmp_path / f"x.{ext}", tetra())
    assert list(tmp_path.iterdir()) == []
