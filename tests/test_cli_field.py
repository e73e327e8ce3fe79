import json

import numpy as np
import pytest

from geotex.cli import main
from geotex.errors import MeshFileError
from geotex.fields.store import load_direction_field
from geotex.io import write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import icosphere, torus


@pytest.fixture
def sphere_file(tmp_path):
    return write_mesh(tmp_path / "s.ply", Mesh(*icosphere(3)))


@pytest.fixture
def torus_file(tmp_path):
    return write_mesh(tmp_path / "t.ply", Mesh(*torus(n_major=40, n_minor=20)))


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("symmetry", [1, 2, 4])
def test_smooth_field_json_index_sum(capsys, tmp_path, sphere_file, symmetry):
    cons = tmp_path / "c.json"
    cons.write_text(json.dumps([{"face": 3, "direction": [0, 0, 1]},
                                {"point": [0, 1, 0], "direction": [1, 0, 0]}]))
    out = tmp_path / "f.npz"
    code, text, err = run(capsys, "field", sphere_file, "--constraints", cons,
                          "--symmetry", symmetry, "-o", out, "--json")
    assert code == 0, err
    d = json.loads(text)
    assert d["index_sum"] == pytest.approx(2.0) and d["euler_characteristic"] == 2
    assert all({"vertex", "index"} <= set(s) for s in d["singularities"])
    assert sum(s["index"] for s in d["singularities"]) == pytest.approx(2.0)
    ff = load_direction_field(out)
    assert ff.field.symmetry == symmetry and ff.metadata["method"] == "smooth"
    assert ff.field.vectors.shape == (len(icosphere(3)[1]), 3) and ff.scale is None


def test_constraint_scales_become_a_scale_field(capsys, tmp_path, sphere_file):
    cons = tmp_path / "c.json"
    cons.write_text(json.dumps([{"face": 3, "direction": [0, 0, 1], "scale": 2.0},
                                {"point": [0, 0, -1], "direction": [1, 0, 0], "scale": 0.5}]))
    out = tmp_path / "f.npz"
    code, text, _ = run(capsys, "field", sphere_file, "--constraints", cons, "-o", out, "--json")
    assert code == 0 and json.loads(text)["scale_range"] == [0.5, 2.0]
    ff = load_direction_field(out)
    assert ff.scale.shape == (len(icosphere(3)[0]),)
    assert ff.scale.min() == pytest.approx(0.5) and ff.scale.max() == pytest.approx(2.0)


def test_up_and_curvature_fields_on_torus(capsys, tmp_path, torus_file):
    code, text, _ = run(capsys, "field", torus_file, "--up", "1,0,0", "-o", tmp_path / "a.npz",
                        "--json")
    assert code == 0 and json.loads(text)["index_sum"] == pytest.approx(0.0)
    code, text, _ = run(capsys, "field", torus_file, "--curvature", "--symmetry", "4",
                        "-o", tmp_path / "b.npz", "--json")
    assert code == 0 and json.loads(text)["index_sum"] == pytest.approx(0.0)


@pytest.mark.parametrize("argv, message", [
    (["--up", "1,2"], "three comma-separated"),
    (["--curvature", "--symmetry", "1"], "use --symmetry 2 or 4"),
    (["--constraints", "missing.json"], "no such constraints file"),
])
def test_field_usage_errors(capsys, tmp_path, sphere_file, argv, message):
    code, out, err = run(capsys, "field", sphere_file, *argv, "-o", tmp_path / "f.npz")
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "f.npz").exists()


@pytest.mark.parametrize("payload, message", [
    ("{not json", "not valid JSON"),
    ('[{"face": 99999, "direction": [1, 0, 0]}]', "face"),
    ('[{"face": 0, "direction": [0, 0, 0]}]', "direction"),
    ('[{"face": 0, "direction": [1, 0, 0], "scale": -1}]', "scale"),
    ('[{"face": 0, "direction": [1, 0, 0], "colour": 1}]', "unknown key"),
])
def test_bad_constraint_files(capsys, tmp_path, sphere_file, payload, message):
    cons = tmp_path / "c.json"
    cons.write_text(payload)
    code, _, err = run(capsys, "field", sphere_file, "--constraints", cons,
                       "-o", tmp_path / "f.npz")
    assert code == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "f.npz").exists()


def test_damaged_field_file(tmp_path):
    bad = tmp_path / "x.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(MeshFileError, match="damaged or not a field file"):
        load_direction_field(bad)
    np.savez(tmp_path / "y.npz", metadata=np.array(json.dumps({"format": "other"})))
    with pytest.raises(MeshFileError, match="not a geotex direction field"):
        load_direction_field(tmp_path / "y.npz")
