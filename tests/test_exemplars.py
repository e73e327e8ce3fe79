"""Procedural exemplar geometric textures (geotex.exemplars) and `geotex exemplar`."""

import json

import igl
import manifold3d
import numpy as np
import pytest
from scipy.spatial import Delaunay

from geotex.check import check_mesh
from geotex.check.intersections import self_intersecting_pairs
from geotex.cli import main
from geotex.errors import InputError, MeshFileError
from geotex.exemplars import (EXEMPLAR_KINDS, Exemplar, describe, exemplar, kind_parameters,
                              load_exemplar, save_exemplar)
from geotex.exemplars.builders import assemble, loop_faces, stack_faces, stack_vertices
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh, component_volumes, edge_topology, face_components
from geotex.mesh.primitives import box, icosphere
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.testing import assert_printable

SMALL = (2.0, 2.0)


@pytest.fixture(scope="module", params=EXEMPLAR_KINDS)
def small(request):
    return exemplar(request.param, size=SMALL, seed=1)


def test_registry_names_and_descriptions():
    assert EXEMPLAR_KINDS == ("studs", "scales", "knurl", "weave", "chainmail", "bark")
    for name in EXEMPLAR_KINDS:
        text = describe(name)
        assert text and "\n" not in text
        names = {p.name for p in kind_parameters(name)}
        assert {"depth", "jitter", "resolution"} <= names
        assert "height" in names or name == "chainmail"     # rings: height from radius, wire


def test_elements_are_closed_outward_and_disjoint(small):
    V, F = small.vertices, small.faces
    assert V.dtype == np.float64 and F.dtype == np.int64
    report = check_mesh(V, F)
    assert report.printable, report.reasons
    assert report.boundary_edges == 0 and report.non_manifold_edges == 0
    assert report.non_manifold_vertices == 0 and report.degenerate_faces == 0
    # no intersections at all, neither inside an element nor between two elements
    assert self_intersecting_pairs(V, F).shape[0] == 0
    el = small.elements()
    count, labels = face_components(F, V.shape[0])
    assert np.array_equal(el, labels) and el.dtype == np.int64 and count == small.n_elements
    assert count >= 4
    first = np.unique(el, return_index=True)[1]
    assert np.all(np.diff(first) > 0)                        # ordered by first face
    vols = component_volumes(V, F, el, count)
    assert np.all(vols > 0)
    # every element is closed on its own: each of its edges has exactly two faces
    for e in range(count):
        topo = edge_topology(F[el == e], V.shape[0])
        assert topo.boundary.size == 0 and topo.non_manifold.size == 0


def test_elements_inside_footprint_and_z_range(small):
    V = small.vertices
    lx, ly = small.size
    assert small.size == SMALL
    assert V[:, 0].min() >= 0 and V[:, 1].min() >= 0
    assert V[:, 0].max() <= lx and V[:, 1].max() <= ly
    assert small.height == V[:, 2].max() and small.depth == -V[:, 2].min()
    assert 0.05 <= small.height <= 0.35
    assert small.depth == pytest.approx(small.params["depth"], rel=0.05)
    el = small.elements()
    # every element reaches below z = 0 (fuses with a base) and stands above it
    for e in range(small.n_elements):
        z = V[np.unique(small.faces[el == e]), 2]
        assert z.min() < -0.5 * small.depth and z.max() > 0.05


def test_union_with_a_slab_is_printable(small):
    lx, ly = small.size
    slab = manifold_of(*box((0.0, 0.0, -0.2), (lx, ly, 0.0)))
    solid = manifold3d.Manifold.batch_boolean(
        [slab, manifold_of(small.vertices, small.faces)], manifold3d.OpType.Add)
    V, F = arrays_of_manifold(solid)
    report = assert_printable(V, F)
    assert report.components == 1                 # every element fused with the slab
    assert V[:, 2].max() == pytest.approx(small.height)


def _min_gap(ex):
    """Smallest distance from an element's vertices and edge midpoints to the others."""
    V, F, el = ex.vertices, ex.faces, ex.elements()
    best = np.inf
    for e in range(ex.n_elements):
        tri = V[F[el == e]]
        P = np.vstack([tri.reshape(-1, 3), ((tri + np.roll(tri, -1, 1)) / 2).reshape(-1, 3)])
        d2, _, _ = igl.point_mesh_squared_distance(P, V, F[el != e])
        best = min(best, float(np.sqrt(d2.min())))
    return best


def test_elements_keep_a_gap(small):
    assert _min_gap(small) >= 0.01


@pytest.mark.parametrize("name", EXEMPLAR_KINDS)
def test_full_jitter_keeps_elements_apart(name):
    for seed in (3, 4):
        ex = exemplar(name, size=(2.5, 2.2), seed=seed, jitter=1.0)
        assert self_intersecting_pairs(ex.vertices, ex.faces).shape[0] == 0
        assert _min_gap(ex) >= 0.01
        assert ex.vertices[:, :2].min() >= 0
        assert np.all(ex.vertices[:, :2].max(axis=0) <= (2.5, 2.2))


def test_same_seed_same_bytes_and_other_seed_differs(small):
    again = exemplar(small.name, size=SMALL, seed=1)
    assert again.vertices.tobytes() == small.vertices.tobytes()
    assert again.faces.tobytes() == small.faces.tobytes()
    rebuilt = exemplar(small.name, **small.params)
    assert rebuilt.vertices.tobytes() == small.vertices.tobytes()
    other = exemplar(small.name, size=SMALL, seed=2)
    assert (other.vertices.shape != small.vertices.shape
            or not np.array_equal(other.vertices, small.vertices))


def test_npz_round_trip_is_exact(small, tmp_path):
    path = save_exemplar(tmp_path / f"{small.name}.npz", small)
    back = load_exemplar(path)
    assert back.vertices.tobytes() == small.vertices.tobytes()
    assert back.faces.tobytes() == small.faces.tobytes()
    assert (back.size, back.height, back.depth, back.name) == \
        (small.size, small.height, small.depth, small.name)
    assert back.params == small.params
    assert back.period == small.period
    json.dumps(back.params)
    assert exemplar(back.name, **back.params).vertices.tobytes() == small.vertices.tobytes()


@pytest.mark.parametrize("name", EXEMPLAR_KINDS)
def test_default_patch_face_budget(name):
    ex = exemplar(name)
    assert ex.size == (4.0, 4.0)
    assert 5_000 <= ex.faces.shape[0] <= 40_000
    assert ex.n_elements >= 16
    assert ex.params["size"] == [4.0, 4.0] and ex.params["seed"] == 0


def test_studs_default_is_the_quilting_benchmark_size():
    ex = exemplar("studs")
    assert ex.n_elements == 64 and 5_000 <= ex.faces.shape[0] <= 7_000


def test_parameters_change_the_geometry():
    a = exemplar("knurl", size=SMALL, pattern="hex")
    b = exemplar("knurl", size=SMALL, pattern="diamond")
    assert a.n_elements != b.n_elements
    tall = exemplar("studs", size=SMALL, height=0.3)
    assert tall.height == pytest.approx(0.3)
    coarse = exemplar("studs", size=SMALL)
    fine = exemplar("studs", size=SMALL, resolution=24)
    assert coarse.faces.shape[0] == 16 * 2 * 12 * 4      # 12 around, wall + 3 dome rings
    assert fine.faces.shape[0] == 16 * 2 * 24 * 7        # 24 around, wall + 6 dome rings
    regular = exemplar("studs", size=SMALL, jitter=0.0, seed=1)
    assert np.array_equal(regular.vertices, exemplar("studs", size=SMALL, jitter=0.0,
                                                     seed=5).vertices)


def _shifted_elements_match(ex, shift):
    """Fraction of elements whose copy moved by ``shift`` is an element of ``ex``.

    Elements are compared by centroid and second moments (which a random
    spin of a ring's vertices about its axis leaves unchanged).
    """
    V, F, el = ex.vertices, ex.faces, ex.elements()
    parts = [V[np.unique(F[el == e])] for e in range(ex.n_elements)]
    cent = np.array([P.mean(axis=0) for P in parts])
    cov = np.array([np.cov(P.T) for P in parts])
    hits = tested = 0
    for e in range(ex.n_elements):
        target = cent[e] + [shift[0], shift[1], 0.0]
        if not (0.3 < target[0] < ex.size[0] - 0.3 and 0.3 < target[1] < ex.size[1] - 0.3):
            continue
        tested += 1
        k = int(np.argmin(np.linalg.norm(cent - target, axis=1)))
        hits += bool(np.linalg.norm(cent[k] - target) < 1e-9
                     and np.abs(cov[k] - cov[e]).max() < 1e-6)
    return hits / max(tested, 1), tested


@pytest.mark.parametrize("name, symmetries, not_symmetries", [
    # chain mail: one ring spacing along a row, two rows across (rows alternate their tilt)
    ("chainmail", [(1, 0), (0, 1), (1, 1)], [(0, 0.5), (0.5, 0.5)]),
    # scales: odd rows are offset by half a pitch, so the symmetries are the cell
    # multiples (m, n) with m + n even
    ("scales", [(2, 0), (1, 1), (0, 2), (-1, 1)], [(1, 0), (0, 1)]),
])
def test_period_lattice_holds_the_pattern_symmetries(name, symmetries, not_symmetries):
    ex = exemplar(name, size=(3.0, 3.0), jitter=0.0)
    px, py = ex.period
    for m, n in symmetries:
        frac, tested = _shifted_elements_match(ex, (m * px, n * py))
        assert tested >= 3 and frac == 1.0, ((m, n), frac)
    for m, n in not_symmetries:
        frac, tested = _shifted_elements_match(ex, (m * px, n * py))
        assert tested >= 3 and frac == 0.0, ((m, n), frac)
    assert exemplar("studs", size=SMALL).period is None       # the pitch serves


def test_weave_strands_run_across_the_patch():
    ex = exemplar("weave", size=SMALL, seed=3)
    V, F, el = ex.vertices, ex.faces, ex.elements()
    spans = []
    for e in range(ex.n_elements):
        P = V[np.unique(F[el == e])]
        spans.append(np.ptp(P[:, :2], axis=0).max())
    assert min(spans) > 0.95 * SMALL[0]


def test_chainmail_rings_are_linked_four_in_one():
    ex = exemplar("chainmail", size=(3.0, 3.0), seed=0, jitter=0.0)
    V, F, el = ex.vertices, ex.faces, ex.elements()
    k = ex.params["resolution"]
    m = max(6, k // 2)
    # centre line of every ring: mean of each of its k cross-section rings
    rings = np.stack([V[np.unique(F[el == e])] for e in range(ex.n_elements)])
    centre = rings.reshape(ex.n_elements, k, m, 3).mean(axis=2)

    def linking(A, B):
        dA, dB = np.roll(A, -1, 0) - A, np.roll(B, -1, 0) - B
        r = (A + dA / 2)[:, None] - (B + dB / 2)[None]
        cr = np.cross(dA[:, None], dB[None])
        return np.sum(np.einsum("ijk,ijk->ij", r, cr)
                      / np.linalg.norm(r, axis=2) ** 3) / (4 * np.pi)

    middle = np.argmin(np.linalg.norm(centre.mean(axis=1)[:, :2] - 1.5, axis=1))
    links = [abs(linking(centre[middle], centre[e])) for e in range(ex.n_elements)
             if e != middle]
    assert sum(x > 0.5 for x in links) == 4
    assert all(x < 0.2 or x > 0.8 for x in links)


def test_scales_overlap_in_plan_but_not_in_3d():
    ex = exemplar("scales", size=SMALL, seed=0)
    V, F, el = ex.vertices, ex.faces, ex.elements()
    pts = [V[np.unique(F[el == e])] for e in range(ex.n_elements)]
    overlapping = 0
    for e, P in enumerate(pts):
        outline = Delaunay(P[:, :2])                     # scales are convex in plan view
        others = np.vstack([Q for k, Q in enumerate(pts) if k != e])
        inside = outline.find_simplex(others[:, :2]) >= 0
        overlapping += inside.sum() >= 10
    assert overlapping >= ex.n_elements // 2
    # ... yet they pass above or below each other, never through, and keep a gap
    assert self_intersecting_pairs(V, F).shape[0] == 0
    assert _min_gap(ex) >= 0.01


@pytest.mark.parametrize("call, words", [
    (lambda: exemplar("nope"), ["unknown exemplar 'nope'", "studs", "bark"]),
    (lambda: exemplar("studs", bogus=1), ["no parameter 'bogus'", "pitch", "radius"]),
    (lambda: exemplar("studs", pitch=-1), ["pitch", "[0.1, 4]"]),
    (lambda: exemplar("studs", pitch="0.5"), ["pitch", "must be a number"]),
    (lambda: exemplar("studs", jitter=True), ["jitter", "must be a number"]),
    (lambda: exemplar("studs", resolution=12.5), ["resolution", "integer"]),
    (lambda: exemplar("knurl", pattern="square"), ["pattern", "diamond, hex"]),
    (lambda: exemplar("studs", seed=-1), ["seed", "non-negative integer"]),
    (lambda: exemplar("studs", seed=1.5), ["seed", "non-negative integer"]),
    (lambda: exemplar("studs", size=(0, 1)), ["size", "positive"]),
    (lambda: exemplar("studs", size=(0.05, 0.05)), ["radius", "too large"]),
    (lambda: exemplar("studs", radius=0.3), ["radius", "too large"]),
    (lambda: exemplar("weave", width=0.5), ["width", "gap"]),
    (lambda: exemplar("weave", thickness=0.2), ["touch"]),
    (lambda: exemplar("chainmail", wire=0.2), ["wire", "too thick"]),
    (lambda: exemplar("scales", row_spacing=0.1), ["row_spacing"]),
    (lambda: exemplar("scales", thickness=0.2), ["touch"]),
    (lambda: exemplar("bark", width=0.3), ["width", "too large"]),
    (lambda: exemplar("knurl", size=(0.2, 0.2)), ["pitch", "too large"]),
])
def test_bad_arguments_raise_input_errors(call, words):
    with pytest.raises(InputError) as info:
        call()
    for w in words:
        assert w in str(info.value)


def test_load_plain_mesh_infers_size_height_depth(tmp_path):
    ex = exemplar("studs", size=SMALL, seed=4)
    shifted = ex.vertices + np.array([5.0, -3.0, 0.0])
    path = write_mesh(tmp_path / "studs.ply", Mesh(shifted, ex.faces))   # float64: exact
    back = load_exemplar(path)
    lo = ex.vertices[:, :2].min(axis=0)
    hi = ex.vertices[:, :2].max(axis=0)
    assert back.size == pytest.approx(tuple(hi - lo), abs=1e-12)
    assert np.allclose(back.vertices[:, :2].min(axis=0), 0.0)
    assert back.height == ex.height and back.depth == ex.depth
    assert back.name == "studs" and back.params == {}
    assert back.n_elements == ex.n_elements
    stl = save_exemplar(tmp_path / "studs.stl", ex)
    assert read_mesh(stl).n_faces == ex.faces.shape[0]


def test_load_rejects_open_elements_and_bad_files(tmp_path):
    V, F = icosphere(1)
    open_path = write_mesh(tmp_path / "open.obj", Mesh(V, F[1:]))
    with pytest.raises(MeshFileError, match="must be closed"):
        load_exemplar(open_path)
    bad = tmp_path / "bad.npz"
    np.savez(bad, vertices=V)
    with pytest.raises(MeshFileError, match="missing array"):
        load_exemplar(bad)
    with pytest.raises(InputError, match="no such file"):
        load_exemplar(tmp_path / "missing.npz")
    with pytest.raises(InputError, match="Exemplar"):
        save_exemplar(tmp_path / "x.npz", (V, F))


def test_exemplar_record_converts_arrays():
    V, F = icosphere(1)
    ex = Exemplar(V.astype(np.float32), F.astype(np.int32), size=[1, 1], height=1, depth=1,
                  name="ball")
    assert ex.vertices.dtype == np.float64 and ex.faces.dtype == np.int64
    assert ex.size == (1.0, 1.0) and ex.n_elements == 1
    assert np.array_equal(ex.elements(), np.zeros(F.shape[0], np.int64))
    assert "ball" in repr(ex)


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_list(capsys):
    code, out, err = run(capsys, "exemplar", "--list")
    assert code == 0 and err == ""
    for name in EXEMPLAR_KINDS:
        assert any(line.startswith(name + " ") and describe(name) in line
                   for line in out.splitlines())


def test_cli_writes_npz_and_mesh(capsys, tmp_path):
    out = tmp_path / "k.npz"
    code, text, _ = run(capsys, "exemplar", "knurl", "-o", out, "--seed", "3", "--size", "2",
                        "1.5", "--param", "pattern=hex", "--param", "pitch=0.35")
    assert code == 0 and "wrote" in text
    ex = load_exemplar(out)
    ref = exemplar("knurl", size=(2, 1.5), seed=3, pattern="hex", pitch=0.35)
    assert ex.vertices.tobytes() == ref.vertices.tobytes() and ex.params == ref.params
    stl = tmp_path / "w.stl"
    code, text, _ = run(capsys, "exemplar", "weave", "-o", stl, "--size", "2", "2")
    assert code == 0 and read_mesh(stl).n_faces == exemplar("weave", size=SMALL).faces.shape[0]


@pytest.mark.parametrize("argv, message", [
    (["exemplar", "nope", "-o", "{out}"], "unknown exemplar 'nope'; valid names: studs"),
    (["exemplar", "studs", "-o", "{out}", "--param", "bogus=1"], "valid parameters: pitch"),
    (["exemplar", "studs", "-o", "{out}", "--param", "pitch=abc"], "must be a number"),
    (["exemplar", "studs", "-o", "{out}", "--param", "pitch"], "KEY=VALUE"),
    (["exemplar", "studs", "-o", "{out}", "--param", "radius=0.4"], "too large"),
    (["exemplar", "studs"], "-o FILE is required"),
    (["exemplar"], "--list"),
    (["exemplar", "studs", "-o", "{bad}"], "unsupported extension"),
])
def test_cli_errors_are_one_line_and_write_nothing(capsys, tmp_path, argv, message):
    out, bad = tmp_path / "x.stl", tmp_path / "x.xyz"
    argv = [a.format(out=out, bad=bad) for a in argv]
    code, text, err = run(capsys, *argv)
    assert code == 2 and text == ""
    assert err.startswith("geotex: error: ") and err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("k, n", [(1, 3), (2, 5), (6, 12)])
def test_ring_stack_templates_are_closed_spheres_and_tori(k, n):
    F = stack_faces(k, n)
    topo = edge_topology(F, k * n + 2)
    assert np.all(topo.face_count == 2) and topo.inconsistent.size == 0
    assert (k * n + 2) - topo.edges.shape[0] + F.shape[0] == 2           # sphere
    if k >= 3:
        T = loop_faces(k, n)
        topo = edge_topology(T, k * n)
        assert np.all(topo.face_count == 2) and topo.inconsistent.size == 0
        assert k * n - topo.edges.shape[0] + T.shape[0] == 0              # torus


def test_assemble_orients_every_copy_outward():
    k, n = 3, 8
    t = 2 * np.pi * np.arange(n) / n
    z = np.array([-0.5, 0.0, 0.5])
    r = np.array([0.8, 1.0, 0.8])
    ring = np.stack([r[:, None] * np.cos(t), r[:, None] * np.sin(t),
                     np.broadcast_to(z[:, None], (k, n))], -1)
    rings = np.stack([ring, ring * np.array([1.0, -1.0, 1.0])])          # second is mirrored
    P = stack_vertices(rings, np.array([[0, 0, -1.0]] * 2), np.array([[0, 0, 1.0]] * 2))
    P[1] += 5.0
    V, F = assemble(P, stack_faces(k, n))
    count, labels = face_components(F, V.shape[0])
    assert count == 2
    assert np.all(component_volumes(V, F, labels, count) > 0)
    assert_printable(V, F)
