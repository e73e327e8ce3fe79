"""Every committed broken file gets the expected report or a one-line error."""

import json
import shutil

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import MeshFileError, MissingFileError
from geotex.io import read_mesh
from geotex.repair import repair_mesh

from conftest import BROKEN

# file -> (exit status of `geotex check`, text expected in the reasons or warnings)
EXPECTED = {
    "soup_trimesh.stl": (1, "300 boundary edges"),
    "shared_edge_two_cubes_trimesh.STL": (1, "1 non-manifold edges"),
    "multibody_ascii_trimesh.stl": (1, "inconsistent face orientation"),
    "joined_tetrahedra_trimesh.obj": (1, "non-manifold edges"),
    "wallhole_backslash_ngons_trimesh.obj": (1, "unwelded seams"),
    "suzanne_unwelded_quads_trimesh.ply": (1, "boundary edges"),
    "teapot_open_trimesh.stl": (1, "64 boundary edges"),
    "nancolor_trimesh.obj": (0, None),
    "empty_trimesh.stl": (1, "the mesh has no faces"),
    "fan3_nonmanifold_edge_gc.obj": (1, "1 non-manifold edges"),
    "moebius_nonorientable_gc.obj": (1, "inconsistent face orientation"),
    "stl_box_ascii_gc.stl": (0, None),
    "stl_box_binary_gc.stl": (0, None),
    "flt_max_coords_manifold.obj": (0, "very large coordinates"),
    "self_intersect_manifold.obj": (1, "self-intersecting face pairs"),
    "plate_holes_trimesh.STL": (0, None),
}


def test_corpus_is_complete():
    assert sorted(p.name for p in BROKEN.iterdir()) == sorted(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_check_reports_expected_outcome(name, capsys):
    code_expected, text = EXPECTED[name]
    code = main(["check", str(BROKEN / name), "--json"])
    out, err = capsys.readouterr()
    assert err == ""
    report = json.loads(out)
    assert code == code_expected, report["reasons"]
    assert report["printable"] is (code == 0)
    if text:
        assert any(text in r for r in report["reasons"] + report["warnings"]), report


def test_box_ascii_and_binary_agree():
    a = read_mesh(BROKEN / "stl_box_ascii_gc.stl")
    b = read_mesh(BROKEN / "stl_box_binary_gc.stl")
    assert np.array_equal(a.faces, b.faces)
    assert np.allclose(a.vertices, b.vertices)
    assert check_mesh(a.vertices, a.faces).genus == 0


def test_plate_with_holes_has_genus_five():
    m = read_mesh(BROKEN / "plate_holes_trimesh.STL")
    assert check_mesh(m.vertices, m.faces).genus == 5


@pytest.mark.parametrize("name", ["joined_tetrahedra_trimesh.obj", "multibody_ascii_trimesh.stl",
                                  "wallhole_backslash_ngons_trimesh.obj",
                                  "teapot_open_trimesh.stl",
                                  "shared_edge_two_cubes_trimesh.STL"])
def test_repairable_files_become_printable(name):
    m = read_mesh(BROKEN / name)
    res = repair_mesh(m.vertices, m.faces)
    assert res.printable, (name, res.changes, res.report.reasons)


def test_soup_cannot_be_repaired_and_says_so():
    m = read_mesh(BROKEN / "soup_trimesh.stl")
    res = repair_mesh(m.vertices, m.faces)
    assert not res.printable and res.report.reasons


def test_cubes_touching_along_an_edge_are_split_into_two_shells():
    # splitting the shared edge gives two closed cubes that meet along a line,
    # the same representation manifold3d uses for such a union; the report
    # keeps a warning about the coinciding vertex positions
    m = read_mesh(BROKEN / "shared_edge_two_cubes_trimesh.STL")
    res = repair_mesh(m.vertices, m.faces)
    assert res.printable and res.report.components == 2 and res.report.faces == 24
    assert res.report.duplicate_vertex_positions == 2
    assert any("repeat another vertex" in w for w in res.report.warnings)


# generated bad inputs: (file name, bytes) -> expected error text
GENERATED = {
    "empty.stl": (b"", "file is empty"),
    "garbage.stl": (bytes(range(256)) * 5, ""),
    "garbage.ply": (b"\x00\xff" * 300, ""),
    "garbage.obj": (bytes(range(256)) * 5, ""),
    "nan.obj": (b"v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", "non-finite"),
    "badindex.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", ""),
    "notazip.3mf": (b"hello", ""),
    "trunc.ply": (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                  b"property float x\nproperty float y\nproperty float z\nend_header\n\x00\x00", ""),
    "model.xyz": (b"1 2 3\n", "unsupported"),
}


@pytest.mark.parametrize("name", sorted(GENERATED))
def test_generated_bad_files_give_one_line_errors(name, tmp_path, capsys):
    data, text = GENERATED[name]
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(MeshFileError) as exc:
        read_mesh(path)
    assert "\n" not in str(exc.value) and text.lower() in str(exc.value).lower()
    code = main(["check", str(path)])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.startswith("geotex: error: ") and err.count("\n") == 1


def test_wrong_extension_is_diagnosed(tmp_path):
    path = tmp_path / "box.obj"
    shutil.copy(BROKEN / "stl_box_binary_gc.stl", path)
    with pytest.raises(MeshFileError, match="STL"):
        read_mesh(path)


def test_point_cloud_and_huge_coordinates(tmp_path, capsys):
    cloud = tmp_path / "cloud.obj"
    cloud.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    assert main(["check", str(cloud), "--json"]) == 1
    assert "point cloud" in json.loads(capsys.readouterr().out)["reasons"][0]
    huge = tmp_path / "huge.obj"
    huge.write_text("v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nv 0 0 1e300\n"
                    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    assert main(["check", str(huge)]) == 0
    assert "very large coordinates" in capsys.readouterr().out


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(MissingFileError):
        read_mesh(tmp_path / "nope.stl")
    with pytest.raises(MissingFileError):
        read_mesh(tmp_path)
