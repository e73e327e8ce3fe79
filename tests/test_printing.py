"""Print export: the verdict is computed on what the file stores, read back to verify."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.errors import InputError, NotPrintableError
from geotex.io import read_mesh
from geotex.mesh.primitives import box, icosphere
from geotex.mesh.topology import edge_topology
from geotex.printing import (export_printable, printable_stored_solid, stored_form,
                             stored_precision, written_form)


def _box_with_short_edge(eps=1e-9, size=50.0):
    """A closed box whose edge a-b is split at ``a + eps (b - a)``: a sliver in float32."""
    V, F = box((100, 100, 100), (100 + size, 100 + size, 100 + size))
    topo = edge_topology(F, V.shape[0])
    a, b = topo.edges[0]
    m = V.shape[0]
    V = np.vstack([V, V[a] + eps * (V[b] - V[a])])
    out = []
    for f in F:
        f = list(f)
        for k in range(3):
            i, j = f[k], f[(k + 1) % 3]
            if {i, j} == {a, b}:
                c = f[(k + 2) % 3]
                out += [[i, m, c], [m, j, c]]
                break
        else:
            out.append(f)
    return V, np.array(out, dtype=np.int64)


def test_the_sliver_box_is_printable_in_float64_but_not_as_float32():
    V, F = _box_with_short_edge()
    assert check_mesh(V, F).printable
    Vs, Fs = stored_form(V, F, precision=np.float32)
    rep = check_mesh(Vs, Fs)
    assert not rep.printable and rep.degenerate_faces > 0
    # float64 storage keeps it as it is
    Vd, Fd = stored_form(V, F, precision=np.float64)
    assert check_mesh(Vd, Fd).printable


def test_stored_form_rounds_and_welds_like_the_stl_reader(tmp_path):
    V, F = _box_with_short_edge()
    Vs, Fs = stored_form(V, F, precision=np.float32)
    assert np.array_equal(Vs.astype(np.float32).astype(np.float64), Vs)
    assert Vs.shape[0] == V.shape[0] - 1          # the short edge's ends became one point
    assert stored_precision(".STL") is np.float32 and stored_precision(".3mf") is np.float64


def test_printable_stored_solid_collapses_what_rounding_broke():
    V, F = _box_with_short_edge()
    solid = printable_stored_solid(V, F, precision=np.float32)
    assert solid.report.printable, solid.report.reasons
    assert solid.rebuilt and solid.collapsed_faces == 2
    assert np.array_equal(solid.vertices.astype(np.float32).astype(np.float64), solid.vertices)
    assert abs(solid.report.volume - 50.0 ** 3) < 1e-6 * 50.0 ** 3


@pytest.mark.parametrize("ext", [".stl", ".3mf", ".obj", ".ply", ".off"])
def test_export_writes_what_passes_on_re_read(tmp_path, ext):
    V, F = _box_with_short_edge()
    path = tmp_path / f"part{ext}"
    rep = export_printable(path, V, F)
    assert rep.printable
    mesh = read_mesh(path)
    again = check_mesh(mesh.vertices, mesh.faces)
    assert again.printable, again.reasons
    Vb, Fb = written_form(path)
    assert rep.digest == check_mesh(Vb, Fb).digest
    assert not list(tmp_path.glob(".*"))                 # no temporary files left


def test_a_report_of_other_arrays_is_not_trusted(tmp_path):
    V, F = icosphere(2)
    good = check_mesh(V, F)
    assert good.printable
    # an open mesh with a report that says "printable" but describes other arrays
    with pytest.raises(NotPrintableError) as err:
        export_printable(tmp_path / "open.stl", V, F[1:], report=good)
    assert "boundary" in str(err.value) and "force" not in str(err.value)
    assert not (tmp_path / "open.stl").exists()
    # forced: written, and the report returned describes the file
    rep = export_printable(tmp_path / "open.stl", V, F[1:], force=True)
    assert not rep.printable and (tmp_path / "open.stl").is_file()


def test_a_matching_report_is_reused(tmp_path):
    V, F = icosphere(2)
    Vs, Fs = stored_form(V, F, precision=np.float32)
    rep = check_mesh(Vs, Fs)
    assert export_printable(tmp_path / "s.stl", Vs, Fs, report=rep) is rep


def test_float32_overflow_is_a_clear_error(tmp_path):
    V, F = icosphere(1)
    with pytest.raises(InputError, match="float32 range"):
        export_printable(tmp_path / "huge.stl", V * 1e39, F)
    assert not (tmp_path / "huge.stl").exists()


@pytest.mark.parametrize("ext", [".stl", ".3mf"])
def test_a_report_of_the_stored_arrays_is_reused_and_the_file_matches_it(tmp_path, ext):
    solid = printable_stored_solid(*icosphere(2), precision=np.float32)
    path = tmp_path / f"part{ext}"
    rep = export_printable(path, solid.vertices, solid.faces, report=solid.report)
    assert rep is solid.report
    assert rep.digest == check_mesh(*written_form(path)).digest


def test_judged_arrays_that_are_not_in_stored_form_are_judged_again(tmp_path):
    # two vertices at one position: judged unwelded the report would describe
    # other arrays than the file holds, so it must not be reused as it is
    V, F = icosphere(1)
    V = np.vstack([V, V[:1]]).astype(np.float32).astype(np.float64)
    F = F.copy()
    F[F[:, 0] == 0, 0] = V.shape[0] - 1
    rep = check_mesh(V, F)
    out = export_printable(tmp_path / "part.stl", V, F, report=rep)
    assert out.digest != rep.digest and out.printable
    assert out.digest == check_mesh(*written_form(tmp_path / "part.stl")).digest


def _leftovers(tmp_path, out):
    return sorted(p.name for p in tmp_path.iterdir() if p.name != out.name)


@pytest.mark.parametrize("ext", [".stl", ".3mf"])
def test_a_staged_write_is_renamed_once_its_arrays_are_judged_printable(tmp_path, ext,
                                                                         monkeypatch):
    import geotex.printing
    from geotex.printing import StagedWrite

    def no_second_write(*args):
        raise AssertionError("written again although the staged file holds the arrays")

    monkeypatch.setattr(geotex.printing, "_verified_write", no_second_write)
    V, F = icosphere(2)
    out = tmp_path / f"ball{ext}"
    with StagedWrite(out, name="ball") as staged:
        solid = printable_stored_solid(V * 10.0, F, precision=stored_precision(ext),
                                       on_stored=staged)
        assert not out.exists()                         # nothing under the name before the verdict
        rep = export_printable(out, solid.vertices, solid.faces, report=solid.report,
                               staged=staged)
    assert rep is solid.report and rep.printable
    assert written_form(out)[0].shape == solid.vertices.shape
    assert np.array_equal(written_form(out)[1], solid.faces)
    assert _leftovers(tmp_path, out) == []


def test_a_staged_write_of_other_arrays_is_deleted_and_the_judged_ones_written(tmp_path):
    from geotex.printing import StagedWrite

    V, F = icosphere(2)
    out = tmp_path / "ball.stl"
    with StagedWrite(out) as staged:
        staged(*stored_form(V * 20.0, F))              # staged: another solid
        solid = printable_stored_solid(V * 10.0, F)
        export_printable(out, solid.vertices, solid.faces, report=solid.report, staged=staged)
    back = written_form(out)
    assert np.array_equal(back[0], solid.vertices) and np.array_equal(back[1], solid.faces)
    assert _leftovers(tmp_path, out) == []


def test_a_staged_write_of_an_unprintable_solid_leaves_nothing(tmp_path):
    from geotex.printing import StagedWrite

    from geotex.mesh.topology import concatenated

    V, F = concatenated([box((0, 0, 0), (2, 2, 2)), box((1, 1, 1), (3, 3, 3))])  # overlapping
    out = tmp_path / "box.stl"
    with StagedWrite(out) as staged:
        solid = printable_stored_solid(V, F, on_stored=staged)
        assert not solid.report.printable
        with pytest.raises(NotPrintableError):
            export_printable(out, solid.vertices, solid.faces, report=solid.report,
                             staged=staged)
    assert not out.exists() and _leftovers(tmp_path, out) == []


def test_a_staged_write_left_unused_is_deleted(tmp_path):
    from geotex.printing import StagedWrite

    V, F = icosphere(1)
    out = tmp_path / "ball.stl"
    with StagedWrite(out) as staged:
        staged(*stored_form(V, F))
        staged(*stored_form(2.0 * V, F))               # replaces the first
    assert not out.exists() and _leftovers(tmp_path, out) == []


@pytest.mark.parametrize("precision", [np.float32, np.float64])
def test_stored_form_is_the_corner_weld_in_order_of_first_appearance(precision):
    from geotex.io import weld_exact

    rng = np.random.default_rng(5)
    V = rng.normal(size=(300, 3))
    V[::7] = V[3::7][: len(V[::7])]                       # repeated positions
    V[10:20] += 1e-12                                     # equal once rounded to float32
    V[5] = [-0.0, 0.0, 1.0]
    V[6] = [0.0, -0.0, 1.0]                               # -0.0 welds with 0.0
    F = rng.integers(0, 250, size=(400, 3))               # 250..299 unreferenced
    Vs, Fs = stored_form(V, F, precision=precision)
    unique, inverse = weld_exact(V.astype(precision)[F].reshape(-1, 3))
    assert np.array_equal(Fs, inverse.reshape(-1, 3))
    assert Vs.tobytes() == unique.astype(np.float64).tobytes()    # bit for bit (+0.0)
    Ve, Fe = stored_form(np.zeros((4, 3)), np.zeros((0, 3), dtype=np.int64))
    assert Ve.shape == (0, 3) and Fe.shape == (0, 3)


@pytest.mark.parametrize("precision", [np.float32, np.float64])
def test_stored_form_of_a_mesh_already_in_stored_order_is_the_corner_weld(precision):
    from geotex.io import weld_exact
    from geotex.mesh.topology import first_use_order

    rng = np.random.default_rng(7)
    V = rng.normal(size=(200, 3))
    V[4] = [-0.0, 0.5, -0.0]                              # stored as +0.0
    F = rng.integers(0, 200, size=(500, 3))
    order = first_use_order(F, 200)
    rank = np.empty(200, dtype=np.int64)
    rank[order] = np.arange(200)
    V, F = V[order], rank[F]                              # numbered by first use, all used
    Vs, Fs = stored_form(V, F, precision=precision)
    unique, inverse = weld_exact(V.astype(precision)[F].reshape(-1, 3))
    assert np.array_equal(Fs, inverse.reshape(-1, 3)) and np.array_equal(Fs, F)
    assert Vs.tobytes() == unique.astype(np.float64).tobytes()    # bit for bit (+0.0)
    V[7] = V[3]                                           # now two vertices weld
    Vs, Fs = stored_form(V, F, precision=precision)
    unique, inverse = weld_exact(V.astype(precision)[F].reshape(-1, 3))
    assert Vs.shape[0] == 199 and np.array_equal(Fs, inverse.reshape(-1, 3))
    assert Vs.tobytes() == unique.astype(np.float64).tobytes()


def test_numbered_by_first_use_is_an_identity_first_use_order():
    from geotex.mesh.topology import first_use_order, numbered_by_first_use

    rng = np.random.default_rng(11)
    hits = 0
    for trial in range(300):
        n = int(rng.integers(1, 9))
        F = rng.integers(0, n, size=(int(rng.integers(1, 5)), 3))
        if trial % 2:                                     # half of them renumbered
            order = first_use_order(F, n)
            rank = np.empty(n, dtype=np.int64)
            rank[order] = np.arange(n)
            F = rank[F]
        expected = (np.array_equal(first_use_order(F, n), np.arange(n))
                    and np.unique(F).size == n)
        assert numbered_by_first_use(F, n) == expected
        hits += expected
    assert 0 < hits < 300
    assert numbered_by_first_use(np.zeros((0, 3), dtype=np.int64), 0)
    assert not numbered_by_first_use(np.zeros((0, 3), dtype=np.int64), 2)
