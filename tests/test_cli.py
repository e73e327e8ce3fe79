import json
import subprocess
import sys

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.cli import main
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import box, icosphere


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def good(tmp_path, sphere):
    return write_mesh(tmp_path / "good.stl", Mesh(*sphere))


@pytest.fixture
def holed(tmp_path, sphere):
    V, F = sphere
    return write_mesh(tmp_path / "holed.obj", Mesh(V, F[1:]))


def test_check_exit_codes_and_json(capsys, good, holed, tmp_path):
    code, out, _ = run(capsys, "check", str(good))
    assert code == 0 and out.strip().endswith("printable: yes")
    code, out, _ = run(capsys, "check", str(holed), "--json")
    d = json.loads(out)
    assert code == 1 and d["printable"] is False and "not watertight: 3 boundary edges" in d["reasons"]
    code, out, err = run(capsys, "check", str(tmp_path / "missing.stl"))
    assert code == 2 and out == "" and err.startswith("geotex: error: ") and err.count("\n") == 1


def test_usage_errors_are_one_line(capsys):
    for argv in ([], ["check"], ["nope"], ["repair", "a.stl"], ["render", "x.stl", "--size", "a", "b"]):
        code, out, err = run(capsys, *argv)
        assert code == 2 and err.startswith("geotex: error: ") and err.count("\n") == 1, argv


def test_repair_writes_printable_result(capsys, holed, tmp_path):
    out = tmp_path / "fixed.stl"
    code, text, _ = run(capsys, "repair", str(holed), "-o", str(out))
    assert code == 0 and "filled holes" in text and out.exists()
    code, _, _ = run(capsys, "check", str(out))
    assert code == 0


def test_repair_refuses_to_overwrite_input(capsys, holed):
    before = holed.read_bytes()
    code, _, err = run(capsys, "repair", str(holed), "-o", str(holed))
    assert code == 2 and "refusing to overwrite the input" in err
    assert holed.read_bytes() == before


def test_repair_unfixable_writes_nothing_unless_forced(capsys, tmp_path):
    # a single triangle: hole filling makes a double-sided sheet that cancels out
    path = write_mesh(tmp_path / "tri.obj", Mesh(np.eye(3), [[0, 1, 2]]))
    out = tmp_path / "o.stl"
    code, _, err = run(capsys, "repair", str(path), "-o", str(out))
    assert code == 1 and not out.exists() and "not written" in err
    code, _, _ = run(capsys, "repair", str(path), "-o", str(out), "--force", "--json")
    assert code == 1


def test_render_and_convert(capsys, good, tmp_path):
    png = tmp_path / "g.png"
    code, _, _ = run(capsys, "render", str(good), "-o", str(png), "--size", "200", "150",
                     "--highlight")
    assert code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, err = run(capsys, "render", str(good), "-o", str(tmp_path / "g.jpg"))
    assert code == 2 and "PNG" in err
    code, _, _ = run(capsys, "convert", str(good), str(tmp_path / "g.3mf"))
    m = read_mesh(tmp_path / "g.3mf")
    assert code == 0 and m.n_faces == read_mesh(good).n_faces


@pytest.mark.slow
def test_demo_writes_real_files(capsys, tmp_path):
    out = tmp_path / "demo"
    code, text, _ = run(capsys, "demo", "-o", str(out))
    assert code == 0, text
    for name in ("spot_studs.stl", "spot_studs.3mf", "spot_studs.png", "report.json"):
        assert (out / name).stat().st_size > 0, name
    assert "printable: yes" in text and str(out / "spot_studs.stl") in text
    report = json.loads((out / "report.json").read_text())
    assert report["check"]["printable"] and report["map"]["elements"] > 100
    solid = read_mesh(out / "spot_studs.3mf")
    assert check_mesh(solid.vertices, solid.faces).printable
    # the STL (staged during the check) holds the same solid; no hidden file is left
    stl = read_mesh(out / "spot_studs.stl")
    assert np.array_equal(stl.vertices, solid.vertices) and np.array_equal(stl.faces, solid.faces)
    assert sorted(p.name for p in out.iterdir()) == [
        "report.json", "spot_studs.3mf", "spot_studs.png", "spot_studs.stl"]
    size = solid.vertices.max(axis=0) - solid.vertices.min(axis=0)
    # the body is 80 mm long; the studs stand out by at most their height
    assert 80.0 < size.max() < 80.0 + 2 * report["map"]["height"] + 1e-9
    assert solid.vertices[:, 2].min() == pytest.approx(0.0, abs=2 * report["map"]["height"])


def test_real_process_no_traceback(tmp_path):
    garbage = tmp_path / "g.stl"
    garbage.write_bytes(bytes(range(256)) * 3)
    p = subprocess.run([sys.executable, "-m", "geotex", "check", str(garbage)],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert p.stderr.startswith("geotex: error: ") and p.stderr.count("\n") == 1
