"""The compiled loops (geotex.jit) give what the numpy paths give.

Large inputs take compiled loops; here the size threshold is lowered so small
meshes take them too, and every result is compared with the numpy path.
"""

import numpy as np
import pytest

import geotex.heighttilt._kernels as kernels
import geotex.mesh.topology as topology
from geotex.heighttilt import apply_texture, extract_texture, spiky_sphere
from geotex.heighttilt.validation import base_geometry
from geotex.errors import InputError
from geotex.mesh.primitives import grid_plane, torus

TOPOLOGY_FIELDS = ("edges", "half_to_edge", "face_count", "forward_count", "half_order")


def _both_topologies(monkeypatch, F, n=None):
    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 0)
    fast = topology.edge_topology(F, n)
    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 10 ** 12)
    slow = topology.edge_topology(F, n)
    return fast, slow


def _assert_same_topology(fast, slow):
    for name in TOPOLOGY_FIELDS:
        a, b = getattr(fast, name), getattr(slow, name)
        assert a.dtype == b.dtype == np.int64, name
        assert np.array_equal(a, b), name


def test_topology_of_a_shuffled_torus(monkeypatch):
    V, F = torus(1.0, 0.3, n_major=40, n_minor=17)
    rng = np.random.default_rng(3)
    perm = rng.permutation(len(V))
    F = np.argsort(perm)[F][rng.permutation(len(F))]
    fast, slow = _both_topologies(monkeypatch, F, len(V))
    _assert_same_topology(fast, slow)
    assert (fast.face_count == 2).all() and (fast.forward_count == 1).all()


def test_topology_of_open_non_manifold_and_inconsistent_faces(monkeypatch):
    V, F = grid_plane(9, 7)
    # a fin: three faces on one edge; a flipped face; a degenerate face; an unused vertex
    a, b = F[0, 0], F[0, 1]
    F = np.vstack([F, [[a, b, len(V)]], [[a, a, b]]])
    F[40] = F[40, ::-1]
    fast, slow = _both_topologies(monkeypatch, F, len(V) + 2)
    _assert_same_topology(fast, slow)
    assert (fast.face_count > 2).any() and (fast.face_count == 1).any()
    assert len(fast.inconsistent) > 0


def test_topology_of_many_faces_on_few_vertices(monkeypatch):
    # long per-vertex lists (> 64 half-edges) take the merge-sort branch
    rng = np.random.default_rng(0)
    F = rng.integers(0, 8, size=(3000, 3))
    fast, slow = _both_topologies(monkeypatch, F, 8)
    _assert_same_topology(fast, slow)


def test_topology_with_too_small_vertex_count_stays_in_bounds(monkeypatch):
    # a wrong (too small) vertex count: the loops index by vertex and must not
    # run past their arrays; they give the topology of the faces as they are
    V, F = torus(1.0, 0.3, n_major=12, n_minor=8)
    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 0)
    fast = topology.edge_topology(F, 5)
    _, slow = _both_topologies(monkeypatch, F, len(V))
    _assert_same_topology(fast, slow)


@pytest.fixture
def lychee():
    V, F, Vs = spiky_sphere(subdivisions=3, spikes=12, seed=4)
    return V, F, Vs


def _paths(monkeypatch, fn):
    monkeypatch.setattr(kernels, "JIT_MIN_SIZE", 0)
    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 0)
    fast = fn()
    monkeypatch.setattr(kernels, "JIT_MIN_SIZE", 10 ** 12)
    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 10 ** 12)
    slow = fn()
    return fast, slow


def test_decoder_rows_equal_bit_for_bit(monkeypatch, lychee):
    _, F, Vs = lychee

    # the same base geometry (normals, frames) for both: only the rows' loops differ
    monkeypatch.setattr(kernels, "JIT_MIN_SIZE", 10 ** 12)
    geometries = [base_geometry(Vs, F, name="Vs") for _ in range(2)]

    def rows(g):
        return g.decoder_transpose()[0].toarray()

    a = rows(geometries[0])
    monkeypatch.setattr(kernels, "JIT_MIN_SIZE", 0)
    b = rows(geometries[1])
    assert np.array_equal(a, b)


def test_base_face_geometry_equals_numpy_path_bit_for_bit(monkeypatch, lychee):
    _, F, Vs = lychee

    def arrays():
        g = kernels.BaseGeometry(Vs, F)
        return [*(x for e in g.e for x in e), *g.N, g.N2, g.flat, g.valence]

    a, b = _paths(monkeypatch, arrays)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))


def test_face_and_edge_loops_equal_numpy_path(monkeypatch, lychee):
    _, F, Vs = lychee
    t = np.random.default_rng(5).normal(size=Vs.shape) * 3.0     # large: some clip

    def loops():
        g = base_geometry(Vs, F, name="Vs")
        return (g.gradients(), g.unit_sum_normals(),
                kernels.edge_encode_and_lengths(Vs, g.topo.edges, t))

    (Ga, Na, Ca), (Gb, Nb, Cb) = _paths(monkeypatch, loops)
    assert all(np.array_equal(x, y) for a, b in zip(Ga, Gb) for x, y in zip(a, b))
    assert np.allclose(Na, Nb, rtol=0, atol=1e-13)
    assert np.array_equal(Ca[0], Cb[0]) and np.array_equal(Ca[1], Cb[1])
    assert (np.abs(Ca[0]) == Ca[1]).any()          # some coefficients were clipped


def test_decode_equals_numpy_path(monkeypatch, lychee):
    _, F, Vs = lychee
    c = np.random.default_rng(1).normal(size=3 * len(F) // 2)

    def decoded():
        return base_geometry(Vs, F, name="Vs").decode(c)

    a, b = _paths(monkeypatch, decoded)
    assert np.allclose(a, b, rtol=0, atol=1e-12 * np.abs(b).max())


def test_least_squares_tilt_equals_numpy_path(monkeypatch, lychee):
    V, F, Vs = lychee

    def extracted():
        tex, _ = extract_texture(V, F, base=Vs, encode="lsq")
        return tex, apply_texture(Vs, F, tex)

    (ta, Va), (tb, Vb) = _paths(monkeypatch, extracted)
    # normals summed face by face instead of corner column by column: round-off
    assert np.allclose(ta.height, tb.height, rtol=0, atol=1e-13)
    # the same iteration with sums in another order: equal to round-off
    assert np.linalg.norm(ta.tilt - tb.tilt) <= 1e-10 * np.linalg.norm(tb.tilt)
    # the bound |c_e| <= |e| was active somewhere, so the masked rounds ran
    g = base_geometry(Vs, F, name="Vs")
    lengths = np.linalg.norm(Vs[g.topo.edges[:, 1]] - Vs[g.topo.edges[:, 0]], axis=1)
    assert np.isclose(np.abs(ta.tilt), lengths, rtol=1e-12).any()
    # both reconstruct the textured surface exactly
    scale = np.ptp(V, axis=0).max()
    assert np.abs(Va - V).max() <= 1e-12 * scale
    assert np.abs(Vb - V).max() <= 1e-12 * scale


def test_per_edge_damping_branch_matches_scalar_damping(monkeypatch, lychee):
    V, F, Vs = lychee
    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 0)
    g = base_geometry(Vs, F, name="Vs")
    AT, X1, X2 = g.decoder_transpose()
    data = AT.data.reshape(-1, 4)
    diag = np.einsum("ij,ij->i", data, data)
    reg = kernels.LSQ_DAMPING * diag
    Kd = diag + reg
    sq = np.sqrt(Kd)
    rng = np.random.default_rng(2)
    e = len(diag)
    c0, lim = rng.normal(size=e) * 0.01, np.full(e, 0.05)
    t2 = rng.normal(size=2 * len(Vs)) * 0.1
    args = (g.topo.edges, len(Vs), c0, lim, t2, sq, 1.0 / sq, reg, Kd)
    scalar = kernels._lsq_fit_compiled(data.copy(), *args, True)      # rescales its rows
    per_edge = kernels._lsq_fit_compiled(data.copy(), *args, False)
    assert np.allclose(scalar, per_edge, rtol=0, atol=1e-9 * np.abs(scalar).max())


def test_suites_pass_on_the_compiled_loops(tmp_path):
    # the self-intersection, invariant, height-and-tilt, topology and file format suites with every
    # compiled path taken whatever the size (GEOTEX_JIT_MIN_SIZE=0)
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, GEOTEX_JIT_MIN_SIZE="0")
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--no-header", "-n", "0",
         "tests/test_intersections.py", "tests/test_invariants.py", "tests/test_heighttilt.py",
         "tests/test_topology.py", "tests/test_io_formats.py", "tests/test_needles.py",
         "tests/test_check.py"],
        cwd=root, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_weld_by_hash_table_equals_sorted_weld(monkeypatch, dtype):
    import geotex.io._common as common

    rng = np.random.default_rng(7)
    rows = rng.normal(size=(500, 3)).astype(dtype)
    rows[0] = 0.0
    P = rows[rng.integers(0, len(rows), 4000)]
    P[1::9, 2] = -0.0                     # -0.0 and 0.0 weld
    P[2::9, 2] = 0.0
    monkeypatch.setattr(common, "JIT_MIN_SIZE", 0)
    fast = common.weld_exact(P)
    monkeypatch.setattr(common, "JIT_MIN_SIZE", 10 ** 12)
    slow = common.weld_exact(P)
    assert fast[0].dtype == slow[0].dtype == dtype
    assert np.array_equal(fast[0], slow[0]) and np.array_equal(fast[1], slow[1])
    assert np.array_equal(fast[0][fast[1]], P + dtype(0.0))


def test_needle_heights_equal_numpy_path(monkeypatch):
    import geotex.mesh.needles as needles

    V, F = torus(1.0, 0.3, n_major=30, n_minor=11)
    V = V + np.random.default_rng(1).normal(size=V.shape) * 1e-3
    F = np.vstack([F, [[0, 0, 1]], [[0, 1, 2]]])         # a degenerate and a stray face
    monkeypatch.setattr(needles, "JIT_MIN_SIZE", 0)
    fast = needles._heights(V, F)
    monkeypatch.setattr(needles, "JIT_MIN_SIZE", 10 ** 12)
    slow = needles._heights(V, F)
    assert np.array_equal(fast, slow) and fast[-2] == 0.0


def test_a_bad_threshold_in_the_environment_falls_back_with_a_warning():
    import os
    import subprocess
    import sys

    env = dict(os.environ, GEOTEX_JIT_MIN_SIZE="lots")
    proc = subprocess.run([sys.executable, "-c", "import geotex.jit as j; print(j.JIT_MIN_SIZE)"],
                          env=env, capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.strip() == "300000"
    assert "GEOTEX_JIT_MIN_SIZE='lots'" in proc.stderr and "Traceback" not in proc.stderr


def _both(monkeypatch, module, fn):
    monkeypatch.setattr(module, "JIT_MIN_SIZE", 0)
    fast = fn()
    monkeypatch.setattr(module, "JIT_MIN_SIZE", 10 ** 12)
    return fast, fn()


def test_degenerate_faces_equal_numpy_path(monkeypatch):
    import geotex.mesh.geometry as geometry

    V, F = torus(1.0, 0.3, n_major=30, n_minor=11)
    V = np.vstack([V, [[0.5, 0.5, 0.5]], [[1.5, 1.5, 1.5]], [[1.0, 1.0, 1.0 + 1e-14]]])
    n = len(V)
    F = np.vstack([F, [[0, 0, 1]], [[n - 3, n - 2, n - 1]], [[2, 3, 2]]])   # repeats, a sliver
    fast, slow = _both(monkeypatch, geometry, lambda: geometry.degenerate_faces(V, F))
    assert fast.dtype == slow.dtype == np.int64
    assert np.array_equal(fast, slow) and set(fast.tolist()) >= {len(F) - 3, len(F) - 1}
    assert len(F) - 2 in fast.tolist()                                   # collinear


def test_components_and_volumes_equal_numpy_path(monkeypatch):
    import geotex.mesh.geometry as geometry
    from geotex.mesh.primitives import icosphere

    V1, F1 = torus(1.0, 0.3, n_major=20, n_minor=9)
    V2, F2 = icosphere(2)
    V2 = V2 * 0.2
    rng = np.random.default_rng(5)
    # interleave the two bodies' faces and leave an unused vertex in between
    V = np.vstack([V1, [[9.0, 9.0, 9.0]], V2])
    F = np.vstack([F1, F2 + len(V1) + 1])[rng.permutation(len(F1) + len(F2))]
    fast, slow = _both(monkeypatch, topology, lambda: topology.vertex_components(F, len(V)))
    assert fast[0] == slow[0] == 2 and np.array_equal(fast[1], slow[1])
    assert fast[1][len(V1)] == -1
    labels = fast[1][F[:, 0]]
    vf, vs = _both(monkeypatch, geometry, lambda: geometry.component_volumes(V, F, labels, 2))
    assert np.allclose(vf, vs, rtol=1e-12, atol=0) and (vf > 0).all()


def test_radix_grouping_by_cell_keeps_input_order_within_a_cell():
    import geotex.check.intersections as si

    rng = np.random.default_rng(2)
    shift = 20
    keys = (rng.integers(0, 5000, 20000) << shift) | rng.integers(0, 1 << shift, 20000)
    out = si._sorted_by_high_bits(keys, shift, int(keys.max() >> shift).bit_length())
    order = np.argsort(keys >> shift, kind="stable")
    assert np.array_equal(out, keys[order])


def test_duplicate_faces_found_by_topology_as_by_sorting(monkeypatch):
    import geotex.check.intersections as si
    from geotex.mesh.primitives import icosphere

    V, F = icosphere(2)
    # a detached "pillow" (a face and its reverse) and a crossing face
    V = np.vstack([V, [[0, 0, 0], [0.5, 0, 0], [0, 0.5, 0]],
                   [[0.1, 0.1, -0.5], [0.1, 0.1, 0.5], [0.3, 0.05, 0.0]]])
    n = len(V)
    F = np.vstack([F, [[n - 6, n - 5, n - 4]], [[n - 6, n - 4, n - 5]], [[n - 3, n - 2, n - 1]]])
    fast, slow = _both(monkeypatch, si, lambda: si.self_intersecting_pairs(V, F))
    m = len(F)
    assert np.array_equal(fast, slow)
    assert fast.tolist() == [[m - 3, m - 1], [m - 2, m - 1]]     # both copies cross it
    plain = F[:-3]
    fast, slow = _both(monkeypatch, si, lambda: si.self_intersecting_pairs(V, plain))
    assert np.array_equal(fast, slow)


def test_first_use_order_equals_numpy_path(monkeypatch):
    rng = np.random.default_rng(4)
    F = rng.integers(0, 300, size=(400, 3))
    F[F == 7] = 8                                    # vertex 7 unused
    for start in (0, 5, 300):
        fast, slow = _both(monkeypatch, topology,
                           lambda: topology.first_use_order(F, 310, start=start))
        assert np.array_equal(fast, slow) and np.array_equal(np.sort(fast), np.arange(310))
        assert np.array_equal(fast[:start], np.arange(start))


def test_numbered_by_first_use_equals_numpy_path(monkeypatch):
    rng = np.random.default_rng(6)
    F = rng.integers(0, 120, size=(200, 3))
    order = topology.first_use_order(F, 120)
    rank = np.empty(120, dtype=np.int64)
    rank[order] = np.arange(120)
    G = rank[F]
    n = int(np.unique(G).size)
    cases = [(G, n), (G, n + 1), (G[::-1].copy(), n), (G[:, [0, 2, 1]].copy(), n)]
    H = G.copy()
    H[50, 1] = H.max() + 1                          # a vertex that skips the next number
    cases.append((H, n + 1))
    seen = set()
    for Fx, k in cases:
        fast, slow = _both(monkeypatch, topology, lambda: topology.numbered_by_first_use(Fx, k))
        assert fast == slow
        seen.add(fast)
    assert seen == {True, False}


def test_relief_vertex_normals_equal_numpy_path(monkeypatch):
    import geotex.relief.core as core
    from geotex.mesh.primitives import closed_cylinder
    from geotex.relief import refined_by_edge_splits

    V, F = closed_cylinder(10.0, 20.0, n_theta=24, n_height=6, n_cap_rings=3)
    R = refined_by_edge_splits(V, F, 1.5, corner_bary=True)
    monkeypatch.setattr(core, "JIT_MIN_SIZE", 0)
    fast = core._vertex_normals(V, F, R, 30.0)
    monkeypatch.setattr(core, "JIT_MIN_SIZE", 10 ** 12)
    slow = core._vertex_normals(V, F, R, 30.0)
    assert fast.tobytes() == slow.tobytes()
    assert np.allclose(np.linalg.norm(fast, axis=1), 1.0)


_PRELOAD_SCRIPT = """
import numpy as np
import geotex.check.intersections as ci
from geotex.jit import preload
from geotex.mesh.primitives import torus

V, F = torus(1.0, 0.3, n_major=40, n_minor=17)
V2 = np.vstack([V, V + [0.5, 0.1, 0.0]])
F2 = np.vstack([F, F + len(V)])
ci.JIT_MIN_SIZE = 0                        # the compiled path at this small size
if {first}:                                # fills the disk cache (compiles on a fresh clone)
    print(ci.self_intersecting_pairs(V2, F2).tolist())
else:
    funcs = [ci._entry_pair_loops, ci._fan_term_loops, ci._grid_count, ci._grid_rows,
             ci._face_loops]
    preload("geotex.check").join()
    loaded = [len(f.dispatcher().overloads) for f in funcs]
    assert all(k >= 1 for k in loaded), loaded
    pairs = ci.self_intersecting_pairs(V2, F2).tolist()
    # the call found its code loaded: nothing compiled or loaded again
    assert [len(f.dispatcher().overloads) for f in funcs] == loaded
    assert not any(f.dispatcher().stats.cache_hits for f in funcs)
    print(pairs)
"""


def test_preload_loads_the_cached_code_before_the_first_call():
    """geotex.jit.preload (the main job's CLI commands) loads what the first call needs."""
    import subprocess
    import sys

    def run(first):
        proc = subprocess.run([sys.executable, "-c", _PRELOAD_SCRIPT.format(first=first)],
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return proc.stdout

    expected = run(True)
    assert expected.strip() not in ("", "[]")
    assert run(False) == expected


@pytest.mark.parametrize("three_mf", [True, False])
def test_main_job_preload_leaves_the_3mf_text_loops_to_3mf_files(monkeypatch, three_mf):
    """``geotex map`` to an STL does not load the 3MF number-text loops; the rest of
    geotex.io (the weld, the STL writer) and the job's packages are loaded."""
    import threading

    import geotex.jit as jit
    from geotex.cli import _common

    asked = []

    def spy(*packages):
        asked.append(packages)
        return threading.Thread(target=lambda: None)

    monkeypatch.setattr(jit, "preload", spy)
    monkeypatch.setattr(_common, "PRELOADS", [])
    _common.preload_compiled(three_mf=three_mf)
    loaded = {mod for mod in jit._REGISTRY for p in asked[0]
              if mod == p or mod.startswith(p + ".")}
    assert {"geotex.io._common", "geotex.io.stl", "geotex.check.intersections",
            "geotex.mapping.shape", "geotex.mesh.topology"} <= loaded
    assert ("geotex.io.numtext" in loaded) == three_mf


def _refined_both(monkeypatch, V, F, L, **kw):
    import geotex.relief.subdivide as subdivide

    monkeypatch.setattr(subdivide, "JIT_MIN_SIZE", 0)
    fast = subdivide.refined_by_edge_splits(V, F, L, **kw)
    monkeypatch.setattr(subdivide, "JIT_MIN_SIZE", 10 ** 12)
    slow = subdivide.refined_by_edge_splits(V, F, L, **kw)
    return fast, slow


def _same_refinement(a, b):
    return (a.vertices.tobytes() == b.vertices.tobytes() and np.array_equal(a.faces, b.faces)
            and np.array_equal(a.parent, b.parent) and a.rounds == b.rounds
            and ((a.corner_bary is None and b.corner_bary is None)
                 or a.corner_bary.tobytes() == b.corner_bary.tobytes()))


@pytest.mark.parametrize("length", [0.3, 0.9, 2.5])
def test_edge_splits_per_face_equal_numpy_rounds(monkeypatch, length):
    # the compiled refinement (one base face at a time, vertices on base edges shared
    # through a table) gives the numpy rounds' arrays bit for bit: faces grouped by
    # base face in the rounds' order, midpoints numbered by first use, float32
    # barycentrics by the same sums
    from geotex.mesh.primitives import closed_cylinder

    V, F = closed_cylinder(10.0, 20.0, n_theta=24, n_height=6, n_cap_rings=3)
    V = V + np.random.default_rng(5).normal(size=V.shape) * 0.05      # uneven sides
    fast, slow = _refined_both(monkeypatch, V, F, length, corner_bary=True)
    assert fast.rounds >= 1 and fast.faces.shape[0] > F.shape[0]
    assert _same_refinement(fast, slow)
    fast, slow = _refined_both(monkeypatch, V, F, length)
    assert fast.corner_bary is None and _same_refinement(fast, slow)


def test_edge_splits_per_face_on_a_soup_and_the_cap(monkeypatch):
    import geotex.relief.subdivide as subdivide

    rng = np.random.default_rng(11)
    V = rng.normal(size=(60, 3)) * np.array([4.0, 1.0, 0.2])
    F = np.array([rng.choice(60, 3, replace=False) for _ in range(90)])  # edges of any kind
    monkeypatch.setattr(subdivide, "JIT_MIN_SIZE", 0)
    assert subdivide._per_face_ok(V, F, 0.16)                  # the compiled path is taken
    fast, slow = _refined_both(monkeypatch, V, F, 0.4, corner_bary=True)
    assert _same_refinement(fast, slow)
    # the cap: the same error on both paths, and nothing made past it
    monkeypatch.setattr(subdivide, "JIT_MIN_SIZE", 0)
    with pytest.raises(InputError, match="face cap"):
        subdivide.refined_by_edge_splits(V, F, 0.4, max_faces=fast.faces.shape[0] - 1)
    assert subdivide.refined_by_edge_splits(
        V, F, 0.4, max_faces=fast.faces.shape[0]).faces.shape == fast.faces.shape


def test_edge_splits_fall_back_where_base_faces_share_all_corners(monkeypatch):
    import geotex.relief.subdivide as subdivide

    V = np.array([[0.0, 0, 0], [3, 0, 0], [0, 3, 0], [0, 0, 3]])
    pillow = np.array([[0, 1, 2], [0, 2, 1]])                 # two faces on one vertex set
    repeated = np.array([[0, 1, 2], [0, 1, 1], [0, 3, 1]])    # a face repeating a vertex
    monkeypatch.setattr(subdivide, "JIT_MIN_SIZE", 0)
    assert not subdivide._per_face_ok(V, pillow, 0.25)
    assert not subdivide._per_face_ok(V, repeated, 0.25)
    assert subdivide._per_face_ok(V, np.array([[0, 1, 2], [0, 3, 1]]), 0.25)
    for F in (pillow, repeated):
        fast, slow = _refined_both(monkeypatch, V, F, 0.5, corner_bary=True)
        assert _same_refinement(fast, slow)


def test_binary_stl_writer_in_chunks_equals_numpy_path(monkeypatch):
    import io

    import geotex.io.stl as stl
    from geotex.mesh.record import Mesh

    V, F = torus(1.0, 0.3, n_major=40, n_minor=13)
    V = V * 37.0 + np.random.default_rng(2).normal(size=V.shape)
    F = np.vstack([F, [[0, 0, 1]], [[0, 1, 1]], [[5, 6, 7]]])     # degenerate faces: zero normals
    V[7] = V[5] + 0.5 * (V[6] - V[5])                               # a collinear face
    monkeypatch.setattr(stl, "WRITE_CHUNK", 257)                    # several chunks, a short last one
    out = []
    for size in (0, 10 ** 12):
        monkeypatch.setattr(stl, "JIT_MIN_SIZE", size)
        buf = io.BytesIO()
        stl.write_stl(buf, Mesh(V, F), path="t.stl")
        out.append(buf.getvalue())
    assert out[0] == out[1] and len(out[0]) == 84 + 50 * F.shape[0]
    back = stl.read_stl("t.stl", out[0])
    assert back.faces.shape == F.shape


def test_needle_free_region_and_splice_equal_numpy_path(monkeypatch):
    """The compiled region and splice of needle_free give the numpy path's arrays
    (darts at many edges, a stray unreferenced vertex that must drop out)."""
    import geotex.mesh.needles as needles
    from geotex.mesh.primitives import icosphere

    V, F = icosphere(3)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    E = np.unique(E, axis=0)
    rng = np.random.default_rng(3)
    used = np.zeros(len(V), dtype=bool)
    for a, b in E[rng.permutation(len(E))]:
        if used[a] or used[b] or used.sum() > 120:
            continue
        fa = np.flatnonzero(np.isin(F, [a, b]).sum(axis=1) == 2)
        if fa.size != 2 or used[F[fa].ravel()].any():
            continue
        used[F[fa].ravel()] = True
        p = len(V)
        V = np.vstack([V, V[a] + 1e-7 * (V[b] - V[a])])
        new = []
        for f in F[fa]:
            i = list(f).index(a)
            if f[(i + 1) % 3] == b:              # (a, b, c) -> (a, p, c), (p, b, c)
                c = f[(i + 2) % 3]
                new += [[a, p, c], [p, b, c]]
            else:                                # (b, a, d) -> (b, p, d), (p, a, d)
                d = f[(i + 1) % 3]
                new += [[b, p, d], [p, a, d]]
        F = np.vstack([np.delete(F, fa, axis=0), new])
    V = np.vstack([V[:5], [[9.0, 9.0, 9.0]], V[5:]])     # unreferenced vertex 5
    F = np.where(F >= 5, F + 1, F)
    monkeypatch.setattr(needles, "JIT_MIN_SIZE", 0)
    fast = needles.needle_free(V, F, tolerance=1e-5)
    monkeypatch.setattr(needles, "JIT_MIN_SIZE", 10 ** 12)
    slow = needles.needle_free(V, F, tolerance=1e-5)
    assert fast[2] == slow[2] >= 10
    assert np.array_equal(fast[0], slow[0]) and np.array_equal(fast[1], slow[1])
    assert len(fast[0]) == len(V) - 1 - fast[2]          # the stray and the collapsed
    assert not np.any((fast[0] == 9.0).all(axis=1))


_FIRST_COMPILE_SCRIPT = """
import geotex.mesh.geometry as geometry
from geotex.jit import on_first_compile
from geotex.mesh.primitives import torus

names = []
on_first_compile(names.append)
on_first_compile(names.append)          # two callbacks: each called once
geometry.JIT_MIN_SIZE = 0
V, F = torus(1.0, 0.3, n_major=30, n_minor=11)
geometry.degenerate_faces(V, F)
geometry.degenerate_faces(V, F)
print(names)
"""


def test_first_compile_is_reported_once_and_never_for_cached_code(tmp_path):
    """geotex.jit.on_first_compile: what the command line uses to say why a first run is slow."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))     # a cache with nothing in it

    def run():
        proc = subprocess.run([sys.executable, "-c", _FIRST_COMPILE_SCRIPT], env=env,
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return eval(proc.stdout.strip().splitlines()[-1])

    first = run()
    assert first == ["geotex.mesh.geometry._degenerate_loops"] * 2
    assert run() == []                                          # loaded from the cache


@pytest.fixture(scope="module")
def torus_shell_small():
    from geotex.shells import build_shell

    V, F = torus(1.0, 0.4, n_major=48, n_minor=24)
    return build_shell(V, F, tile_size=0.4, name="torus")


def test_walked_feet_and_interpolation_equal_numpy_path(monkeypatch, torus_shell_small):
    import geotex.mapping.shape as shape
    import geotex.shells.locate as locate

    pc = torus_shell_small.polycube
    rng = np.random.default_rng(5)
    k = 4000
    quads = rng.integers(0, pc.layout.n_quads, k)
    uv = rng.uniform(-0.1, 1.1, (k, 2))                    # some outside the quad: clamped
    face, bary = pc.locate(quads, np.clip(uv, 0, 1))
    base = locate.interpolated(pc.Y, pc.F, face, bary)
    # targets near their quad's surface (walks that settle or leave the quad) and far
    # from it (lost); one exactly on a vertex
    target = base + rng.normal(size=(k, 3)) * np.where(rng.random(k) < 0.8, 0.05, 0.5)[:, None]
    target[0] = pc.Y[pc.F[face[0], 0]]
    values = np.hstack([pc.Y, torus_shell_small.D])
    monkeypatch.setattr(shape, "JIT_MIN_SIZE", 0)
    monkeypatch.setattr(locate, "JIT_MIN_SIZE", 0)
    fast = shape._walked_feet(pc, quads, uv, target)
    fast_i = locate.interpolated(values, pc.F, face, bary)
    monkeypatch.setattr(shape, "JIT_MIN_SIZE", 10 ** 12)
    monkeypatch.setattr(locate, "JIT_MIN_SIZE", 10 ** 12)
    slow = shape._walked_feet(pc, quads, uv, target)
    slow_i = locate.interpolated(values, pc.F, face, bary)
    for a, b in zip(fast, slow):
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
    assert fast_i.dtype == slow_i.dtype and fast_i.tobytes() == slow_i.tobytes()
    lost = slow[2]
    assert lost.any() and (~lost).any()


def test_shaped_map_equals_numpy_path(monkeypatch, torus_shell_small, shared_tileset):
    # the whole shaped map (spread, leaned and cast shapes, re-seating) through the
    # compiled walk and interpolation gives the same positions bit for bit
    import geotex.mapping.shape as shape
    import geotex.shells.locate as locate
    from geotex.exemplars import exemplar
    from geotex.mapping import edge_colors, mapped_tiles, tiles_for_quads
    from geotex.tiles import build_tileset

    tiles = shared_tileset("studs-res6-1-seed0-paste", lambda: build_tileset(
        exemplar("studs", seed=1, resolution=6), colors=1, seed=0, interior="paste"))
    pc = torus_shell_small.polycube
    colors = edge_colors(pc.layout.edge_axis, tiles.n_colors, seed=0)
    toq = tiles_for_quads(tiles, pc.layout.quad_axes, pc.layout.quad_edge, colors)
    runs = []
    for size in (0, 10 ** 12):
        monkeypatch.setattr(shape, "JIT_MIN_SIZE", size)
        monkeypatch.setattr(locate, "JIT_MIN_SIZE", size)
        runs.append(mapped_tiles(torus_shell_small, tiles, toq, scale=0.1, anchor=0.05))
    fast, slow = runs
    assert fast.vertices.tobytes() == slow.vertices.tobytes()
    assert np.array_equal(fast.faces, slow.faces) and np.array_equal(fast.leaned, slow.leaned)


@pytest.mark.parametrize("n", [2, 400])
@pytest.mark.parametrize("layout", ["none", "c", "across"])
def test_spread_rounds_equal_numpy_path(monkeypatch, layout, n):
    # np.einsum's order of summing follows the layout of the ideal maps: both
    # layouts the compiled round takes (C order, and the one shaped_positions makes)
    import geotex.mapping.shape as shape

    rng = np.random.default_rng(11)
    centre = rng.uniform(0, 10, (n, 3)) * [1, 1, 0.1]
    centre[1] = centre[0] + [0.1, 0.05, 0.0]
    if n > 2:
        centre[3] = centre[2]                             # a pair at distance zero
    normal = rng.normal(size=(n, 3)) * 0.1 + [0, 0, 1]
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    radius = rng.uniform(0.2, 0.5, n)
    M = rng.uniform(1.2, 1.6, (n, 1, 1)) * np.eye(2, 3)[None] + rng.normal(size=(n, 2, 3)) * 0.05
    ideal = {"none": None, "c": M,
             "across": np.transpose(np.ascontiguousarray(np.transpose(M, (0, 2, 1))), (0, 2, 1))
             }[layout]
    if layout == "across":
        assert not ideal.flags.c_contiguous and np.array_equal(ideal, M)
    runs = []
    for size in (0, 10 ** 12):
        monkeypatch.setattr(shape, "JIT_MIN_SIZE", size)
        runs.append(shape.spread_centres(centre, radius, normal, rounds=20, ideal=ideal))
    assert runs[0].tobytes() == runs[1].tobytes()
    assert np.abs(runs[0]).max() > 0.01                   # discs were pushed
