"""``geotex quilt``: exemplar kinds and mesh files in, mesh + JSON report out, one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from geotex.cli import main
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import icosphere


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def stud_texture():
    parts = []
    for i in range(3):
        for j in range(3):
            V, F = icosphere(2)
            V = V * [0.15, 0.15, 1.0]
            V[:, 2] = np.where(V[:, 2] > 0, V[:, 2] * 0.12, np.maximum(V[:, 2], -0.04))
            parts.append((V + [0.25 + 0.5 * i, 0.25 + 0.5 * j, 0.0], F))
    V = np.concatenate([p[0] for p in parts])
    F = np.concatenate([p[1] + k * len(parts[0][0]) for k, p in enumerate(parts)])
    return V, F


def test_quilt_exemplar_kind_with_report(capsys, tmp_path):
    out, rep = tmp_path / "q.ply", tmp_path / "r.json"
    code, stdout, err = run(capsys, "quilt", "studs", "--size", 3, 3, "-o", out,
                            "--report", rep, "--seed", 2, "--boundary", "clip")
    assert code == 0, err
    mesh = read_mesh(out)
    data = json.loads(rep.read_text())
    assert data["bad_elements"] == 0 and data["intersecting_element_pairs"] == 0
    assert data["elements"] >= 20
    assert mesh.n_faces > 0 and (mesh.vertices[:, :2] >= 0).all()
    assert (mesh.vertices[:, :2] <= 3).all()
    assert "elements" in stdout and str(out) in stdout


def test_quilt_mesh_file_is_deterministic(capsys, tmp_path):
    src = write_mesh(tmp_path / "ex.ply", Mesh(*stud_texture()))
    a, b = tmp_path / "a.ply", tmp_path / "b.ply"
    assert run(capsys, "quilt", src, "--size", 2.5, 2, "-o", a, "--seed", 4)[0] == 0
    assert run(capsys, "quilt", src, "--size", 2.5, 2, "-o", b, "--seed", 4)[0] == 0
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("argv, message", [
    (["quilt", "nothing-such", "--size", "2", "2"], "not an exemplar kind"),
    (["quilt", "studs", "--size", "2", "0"], "--size"),
    (["quilt", "studs", "--size", "2", "2", "--cell", "-1"], "--cell"),
])
def test_quilt_errors_are_one_line(capsys, tmp_path, argv, message):
    out = tmp_path / "o.ply"
    code, _, err = run(capsys, *argv, "-o", out)
    assert code == 2 and message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_quilt_refuses_to_overwrite_its_input(capsys, tmp_path):
    src = write_mesh(tmp_path / "ex.ply", Mesh(*stud_texture()))
    before = src.read_bytes()
    code, _, err = run(capsys, "quilt", src, "--size", 2, 2, "-o", src)
    assert code == 2 and "refusing to overwrite" in err
    assert src.read_bytes() == before
    code, _, err = run(capsys, "quilt", src, "--size", 2, 2, "-o", tmp_path / "x.ply",
                       "--report", tmp_path / "x.ply")
    assert code == 2 and "different files" in err


def test_progress_bar_counts_filled_cells_and_stays_off_without_a_terminal(capsys, tmp_path):
    from geotex.cli.quilt import cell_bar
    with cell_bar(10, "quilt studs", enabled=True) as bar:
        bar("placement 1: 0/10 cells")
        bar("placement 2: 4/10 cells")
    err = capsys.readouterr().err
    assert "4/10" in err and "placement 2" in err and "cell/s" in err
    # under pytest stderr is not a terminal: the command prints no bar
    code, _, err = run(capsys, "quilt", "studs", "--size", 2, 2, "-o", tmp_path / "q.ply")
    assert code == 0 and err == ""


def test_quilt_library_reports_filled_cells(tmp_path):
    from geotex.exemplars import exemplar
    from geotex.quilting import quilt_texture
    stages = []
    quilt_texture(exemplar("studs", size=(1.5, 1.5)), out_size=(2.0, 2.0), progress=stages.append)
    counts = [tuple(map(int, s.split(": ")[1].split()[0].split("/"))) for s in stages]
    assert counts[0] == (0, 16) and all(a[0] <= b[0] for a, b in zip(counts, counts[1:]))
    assert stages[-1].startswith(f"placement {len(stages)}:")
