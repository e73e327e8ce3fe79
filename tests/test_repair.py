import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.mesh.primitives import box, icosphere
from geotex.repair import (repair_mesh, welded, without_duplicate_faces,
                           without_unreferenced_vertices)


def test_weld_exact_and_tolerance():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0], [1, 1e-9, 0]], dtype=np.float64)
    F = np.array([[0, 1, 2], [2, 3, 1]])
    V1, F1, k = welded(V, F)
    assert k == 1 and len(V1) == 3 and F1.tolist() == [[0, 1, 0], [0, 2, 1]]
    V2, F2, k = welded(V, F, tolerance=1e-6)
    assert k == 2 and np.array_equal(V2, V[:2])


def test_unreferenced_vertices_removed_in_order():
    V = np.arange(15, dtype=np.float64).reshape(5, 3)
    V2, F2, k = without_unreferenced_vertices(V, np.array([[4, 0, 2]]))
    assert k == 2 and np.array_equal(V2, V[[0, 2, 4]]) and F2.tolist() == [[2, 0, 1]]


def test_opposite_duplicates_cancel(tet):
    _, F = tet
    F2 = np.vstack([F, F[:1][:, ::-1], F[1:2]])
    out, k = without_duplicate_faces(F2)
    assert k == 3 and out.tolist() == F[1:].tolist()


def test_repair_keeps_a_printable_mesh_unchanged(sphere):
    V, F = sphere
    res = repair_mesh(V, F)
    assert res.printable and res.changes == []
    assert np.array_equal(res.vertices, V) and np.array_equal(res.faces, F)


def test_repair_does_not_modify_inputs(sphere):
    V, F = sphere
    V0, F0 = V.copy(), F.copy()
    repair_mesh(V, F[::-1][:, ::-1])
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


def test_repair_unwelded_inside_out_box_with_hole():
    V, F = box(divisions=2)
    soup_V = V[F].reshape(-1, 3)           # every face its own vertices
    soup_F = np.arange(len(soup_V)).reshape(-1, 3)[:, ::-1]   # inside out
    soup_F = soup_F[1:]                    # and a hole
    assert not check_mesh(soup_V, soup_F).printable
    res = repair_mesh(soup_V, soup_F)
    assert res.printable, res.report.reasons
    assert res.report.volume == pytest.approx(1.0, rel=1e-9)
    joined = " | ".join(res.changes)
    assert "welded" in joined and "filled holes" in joined and "outward" in joined


def test_repair_unions_overlapping_shells():
    Va, Fa = icosphere(2)
    Vb, Fb = icosphere(2, center=(0.6, 0.0, 0.0))
    V = np.vstack([Va, Vb])
    F = np.vstack([Fa, Fb + len(Va)])
    res = repair_mesh(V, F)
    assert res.printable, res.report.reasons
    assert res.report.components == 1
    assert any("boolean union" in c for c in res.changes)
    single = check_mesh(Va, Fa).volume
    assert single < res.report.volume < 2 * single


def test_flipped_faces_are_made_consistent(sphere):
    V, F = sphere
    F = F.copy()
    F[::7] = F[::7, ::-1]
    res = repair_mesh(V, F)
    assert res.printable and res.report.volume > 0
