import json

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.errors import InputError
from geotex.mesh.primitives import box, icosphere


def test_tetrahedron_is_printable(tet):
    V, F = tet
    r = check_mesh(V, F)
    assert r.printable and r.reasons == []
    assert r.genus == 0 and r.euler_characteristic == 2 and r.components == 1
    assert r.volume == pytest.approx(1 / 6)
    assert r.outward is True and r.manifold3d_status == "NoError"
    assert r.bbox_size == [1.0, 1.0, 1.0]


def test_torus_genus(ring):
    V, F = ring
    r = check_mesh(V, F)
    assert r.printable and r.genus == 1 and r.euler_characteristic == 0


def test_inside_out_is_not_printable(sphere):
    V, F = sphere
    r = check_mesh(V, F[:, ::-1])
    assert not r.printable and r.outward is False
    assert any("inward" in x for x in r.reasons)


def test_hollow_sphere_with_inward_cavity_is_printable():
    Vo, Fo = icosphere(2, radius=2.0)
    Vi, Fi = icosphere(2, radius=1.0)
    V = np.vstack([Vo, Vi])
    F = np.vstack([Fo, Fi[:, ::-1] + len(Vo)])
    r = check_mesh(V, F)
    assert r.printable, r.reasons
    # the same cavity facing outward is a wrongly oriented shell
    r2 = check_mesh(V, np.vstack([Fo, Fi + len(Vo)]))
    assert not r2.printable and r2.examples["inward_components"] == [1]


def test_open_mesh_reports_boundary_with_examples(sphere):
    V, F = sphere
    r = check_mesh(V, F[1:])
    assert not r.printable and r.boundary_edges == 3 and r.genus is None
    assert len(r.examples["boundary_edges"]) == 3
    assert "not watertight: 3 boundary edges" in r.reasons


def test_two_overlapping_spheres_self_intersect():
    Va, Fa = icosphere(2)
    Vb, Fb = icosphere(2, center=(0.5, 0.1, 0.0))
    r = check_mesh(np.vstack([Va, Vb]), np.vstack([Fa, Fb + len(Va)]))
    assert not r.printable and r.self_intersecting_pairs > 0
    assert any("self-intersecting" in x for x in r.reasons)


def test_skipping_self_intersections_is_never_printable(tet):
    V, F = tet
    r = check_mesh(V, F, self_intersections=False)
    assert not r.printable and r.self_intersecting_pairs is None
    assert r.reasons == ["self-intersections were not checked"]


def test_json_has_required_keys_and_is_valid(cube):
    V, F = cube
    d = json.loads(check_mesh(V, F).to_json())
    assert d["printable"] is True and d["reasons"] == []
    for key in ("vertices", "faces", "components", "boundary_edges", "non_manifold_edges",
                "non_manifold_vertices", "orientation_consistent", "outward", "volume",
                "degenerate_faces", "duplicate_faces", "self_intersecting_pairs",
                "euler_characteristic", "genus", "bbox_min", "bbox_max", "bbox_size"):
        assert key in d


def test_empty_and_point_cloud():
    r = check_mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    assert not r.printable and r.reasons == ["the mesh has no faces"]
    r = check_mesh(np.random.default_rng(0).random((5, 3)), np.zeros((0, 3), np.int64))
    assert r.reasons == ["the mesh has no faces (a point cloud)"]


def test_report_is_scale_invariant():
    V, F = box(divisions=3)
    base = check_mesh(V, F)
    for s in (1e-6, 1e6):
        r = check_mesh(V * s, F)
        assert r.printable == base.printable and r.genus == base.genus
        assert r.volume == pytest.approx(s ** 3, rel=1e-9)


def test_summary_ends_with_verdict(sphere):
    V, F = sphere
    text = check_mesh(V, F[2:]).summary()
    assert "printable: no" in text and text.splitlines()[-1].startswith("  - ")


def test_malformed_arrays_raise():
    with pytest.raises(InputError):
        check_mesh(np.zeros((3, 3)), [[0, 1, 3]])


def test_progress_callback_sees_every_stage(sphere):
    from geotex.check.report import CHECK_STAGES
    from geotex.repair import REPAIR_STAGES, repair_mesh
    V, F = sphere
    seen = []
    check_mesh(V, F, progress=seen.append)
    assert tuple(seen) == CHECK_STAGES
    seen.clear()
    repair_mesh(V, F, progress=seen.append)
    assert tuple(seen) == REPAIR_STAGES


# ---------------------------------------------------------------------------
# local re-check after moved vertices

ALL = 2 ** 62


def _bumpy_sphere(seed=0):
    V, F = icosphere(4)
    rng = np.random.default_rng(seed)
    return V * (1.0 + 0.02 * rng.random(len(V)))[:, None], F


def _assert_recheck_is_full(V0, V1, F, k=5):
    from geotex.check.report import recheck_moved

    before = check_mesh(V0, F, manifold3d=False, max_examples=ALL)
    got = recheck_moved(V0, V1, F, before, max_examples=k)
    assert got is not None
    full = check_mesh(V1, F, manifold3d=False, max_examples=k)
    assert got == full                   # every field: counts, volume, examples, digest
    assert got.to_json() == full.to_json()
    return got


def test_recheck_after_moves_equals_the_full_check():
    V0, F = _bumpy_sphere()
    rng = np.random.default_rng(1)
    inner = np.flatnonzero(np.abs(V0[:, 2]) < 0.5)       # away from the box's extremes
    # small moves: still clean
    V1 = V0.copy()
    moved = rng.choice(inner, 40, replace=False)
    V1[moved] *= 0.99
    assert _assert_recheck_is_full(V0, V1, F, k=ALL).printable
    # a few vertices pushed along the surface over their neighbours: crossings
    V2 = V0.copy()
    V2[moved[:5], 2] += 0.3
    rep = _assert_recheck_is_full(V0, V2, F)
    assert rep.self_intersecting_pairs > 0 and not rep.printable
    rep = _assert_recheck_is_full(V0, V2, F, k=ALL)
    # from crossings back to clean, and to other crossings
    assert _assert_recheck_is_full(V2, V1, F).printable
    V3 = V2.copy()
    V3[moved[:2]] = V0[moved[:2]]
    V3[moved[10:13], 2] -= 0.3
    assert _assert_recheck_is_full(V2, V3, F).self_intersecting_pairs > 0
    # a vertex moved onto its face's opposite edge: a degenerate face
    V4 = V0.copy()
    a, b, c = F[np.flatnonzero((F == inner[0]).any(axis=1))[0]]
    q, r = sorted({int(a), int(b), int(c)} - {int(inner[0])})
    V4[inner[0]] = 0.5 * (V0[q] + V0[r])
    rep = _assert_recheck_is_full(V0, V4, F)
    assert rep.degenerate_faces > 0
    # nothing moved
    assert _assert_recheck_is_full(V0, V0.copy(), F).printable


def test_recheck_declines_what_it_cannot_do_locally():
    from geotex.check.report import recheck_moved

    V0, F = _bumpy_sphere()
    before = check_mesh(V0, F, manifold3d=False, max_examples=ALL)
    top = int(np.argmax(V0[:, 2]))
    V1 = V0.copy()
    V1[top, 2] += 0.1                                     # the box grows
    assert recheck_moved(V0, V1, F, before) is None
    V1 = V0.copy()
    V1[5] = V0[7]                                         # lands on another vertex
    assert recheck_moved(V0, V1, F, before) is None
    V1 = V0.copy()
    V1[5] *= 0.999
    assert recheck_moved(V0 * 1.0001, V1, F, before) is None          # not the judged arrays
    assert recheck_moved(V0, V1, F, check_mesh(V0, F, max_examples=ALL)) is None   # manifold3d
    few = check_mesh(V0, F, manifold3d=False, max_examples=0)
    V2 = V0.copy()
    inner = np.flatnonzero(np.abs(V0[:, 2]) < 0.5)
    V2[np.random.default_rng(1).choice(inner, 40, replace=False)[:5], 2] += 0.3
    crossing = check_mesh(V2, F, manifold3d=False, max_examples=2)
    assert crossing.self_intersecting_pairs > 2
    assert recheck_moved(V2, V0, F, crossing) is None     # incomplete example lists
    assert recheck_moved(V0, V1, F, few) is not None      # nothing to list: complete
    with pytest.raises(InputError):
        recheck_moved(V0[:-1], V1, F, before)


def test_duplicate_faces_still_expand_their_crossing_pairs():
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(2, radius=0.8, center=(0.9, 0.1, 0.05))
    V = np.concatenate([V1, V2])
    F = np.concatenate([F1, F2 + len(V1)])
    F = np.concatenate([F, F[:40]])                     # duplicates of faces near the crossing
    r = check_mesh(V, F, manifold3d=False, max_examples=2 ** 62)
    from geotex.check.intersections import self_intersecting_pairs

    assert r.duplicate_faces == 40
    assert r.examples["self_intersecting_pairs"] == self_intersecting_pairs(V, F).tolist()
