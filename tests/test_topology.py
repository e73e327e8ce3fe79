import numpy as np
import pytest

from geotex.errors import InputError
from geotex.mesh import (Mesh, as_faces, as_vertices, degenerate_faces, duplicate_face_groups,
                         edge_topology, face_components, non_manifold_vertices, signed_volume)
from geotex.mesh.primitives import box, grid_plane, icosphere, torus


def test_closed_sphere_topology(sphere):
    V, F = sphere
    t = edge_topology(F, len(V))
    assert t.boundary.size == 0 and t.non_manifold.size == 0 and t.inconsistent.size == 0
    assert len(V) - len(t.edges) + len(F) == 2
    assert np.all(t.edges[:, 0] < t.edges[:, 1])
    # lexicographic order of unique edges
    assert np.all(np.diff(t.edges[:, 0] * len(V) + t.edges[:, 1]) > 0)


def test_half_edge_to_edge_map_is_consistent(ring):
    V, F = ring
    t = edge_topology(F, len(V))
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    assert np.array_equal(np.sort(he, axis=1), t.edges[t.half_to_edge])
    ef = t.edge_faces()
    assert np.all(ef >= 0)
    for e in range(0, len(t.edges), 97):
        for f in ef[e]:
            assert set(t.edges[e]) <= set(F[f])


def test_euler_characteristic_of_torus(ring):
    V, F = ring
    t = edge_topology(F, len(V))
    assert len(V) - len(t.edges) + len(F) == 0


def test_open_plane_has_boundary():
    V, F = grid_plane(3, 2)
    t = edge_topology(F, len(V))
    assert t.boundary.size == 2 * (3 + 2)


def test_flipped_face_is_inconsistent(tet):
    V, F = tet
    F = F.copy()
    F[0] = F[0, ::-1]
    assert edge_topology(F, 4).inconsistent.size == 3


def test_bowtie_vertex_is_non_manifold(tet):
    V, F = tet
    V2 = np.vstack([V, V[1:] + [0, 0, -2]])
    F2 = np.vstack([F, np.where(F == 0, 0, F + 3)])
    assert non_manifold_vertices(F2, len(V2)).tolist() == [0]
    assert non_manifold_vertices(F, 4).size == 0


def test_components_and_volume(tet):
    V, F = tet
    V2 = np.vstack([V, V + 5.0])
    F2 = np.vstack([F, F + 4])
    count, labels = face_components(F2, 8)
    assert count == 2 and labels.tolist() == [0] * 4 + [1] * 4
    assert signed_volume(V2, F2) == pytest.approx(2 / 6)


def test_volume_far_from_origin_is_accurate():
    V, F = box(divisions=3)
    assert signed_volume(V + 1e7, F) == pytest.approx(1.0, rel=1e-9)


def test_degenerate_and_duplicate_faces(tet):
    V, F = tet
    V2 = np.vstack([V, [[0.5, 0, 0]]])
    F2 = np.vstack([F, [[0, 1, 4]], [[0, 0, 2]], F[:1][:, ::-1]])
    assert degenerate_faces(V2, F2).tolist() == [4, 5]
    assert duplicate_face_groups(F2).tolist() == [6]


def test_degenerate_test_is_scale_invariant(sphere):
    V, F = sphere
    for s in (1e-6, 1.0, 1e6):
        assert degenerate_faces(V * s, F).size == 0


def test_array_validation_errors():
    with pytest.raises(InputError, match=r"shape \(n, 3\)"):
        as_vertices(np.zeros((3, 2)))
    with pytest.raises(InputError, match="non-finite"):
        as_vertices([[0, 0, np.nan]])
    with pytest.raises(InputError, match="outside"):
        as_faces([[0, 1, 5]], 3)
    with pytest.raises(InputError, match="integer"):
        as_faces([[0, 1, 1.5]], 3)
    with pytest.raises(InputError, match="uv and uv_faces"):
        Mesh(np.zeros((3, 3)), [[0, 1, 2]], uv=np.zeros((3, 2)))


def test_mesh_record_does_not_alias_or_mutate(tet):
    V, F = tet
    V0, F0 = V.copy(), F.copy()
    m = Mesh(V.astype(np.float32), F.astype(np.int32))
    assert m.vertices.dtype == np.float64 and m.faces.dtype == np.int64
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


def test_primitives_are_closed_and_outward():
    for V, F in (icosphere(2), torus(), box(divisions=3)):
        t = edge_topology(F, len(V))
        assert t.boundary.size == 0 and t.inconsistent.size == 0
        assert signed_volume(V, F) > 0


def _fans_reference(F, n):
    """Per-vertex fan count by union-find over corners (slow, obviously right)."""
    from collections import defaultdict
    edge_faces = defaultdict(list)
    for f, tri in enumerate(F.tolist()):
        for k in range(3):
            edge_faces[frozenset((tri[k], tri[(k + 1) % 3]))].append(f)
    parent = {}

    def find(x):
        while parent.setdefault(x, x) != x:
            x = parent[x]
        return x
    for e, fs in edge_faces.items():
        if len(fs) != 2 or len(e) != 2:
            continue
        for v in e:
            ca = (fs[0], F[fs[0]].tolist().index(v))
            cb = (fs[1], F[fs[1]].tolist().index(v))
            parent[find(ca)] = find(cb)
    fans = np.zeros(n, dtype=np.int64)
    roots = {(v, find((f, k))) for f, tri in enumerate(F.tolist()) for k, v in enumerate(tri)}
    for v, _ in roots:
        fans[v] += 1
    on_nm = {v for e, fs in edge_faces.items() if len(fs) > 2 for v in e}
    return np.array([v for v in range(n) if fans[v] > 1 and v not in on_nm], dtype=np.int64)


def _cone(k, apex, base0, up):
    """Closed double cone: ``apex``, ring ``base0 .. base0 + k - 1``, tip ``base0 + k``."""
    i = np.arange(k)
    ring = base0 + i
    nxt = base0 + (i + 1) % k
    top = np.stack([np.full(k, apex), ring, nxt], axis=1)
    bottom = np.stack([np.full(k, base0 + k), nxt, ring], axis=1)
    return np.concatenate([top, bottom]) if up else np.concatenate([top, bottom])[:, ::-1]


@pytest.mark.parametrize("k", [5, 100])
def test_non_manifold_vertices_walk_and_general_paths_agree(k):
    # two closed cones pinched at a shared apex: a bow tie found by the fan walk
    # (k = 5) or, beyond the walk's corner limit, by the general test (k = 100)
    F = np.concatenate([_cone(k, 0, 1, True), _cone(k, 0, k + 2, True)])
    n = 2 * k + 3
    assert non_manifold_vertices(F, n).tolist() == [0]
    assert _fans_reference(F, n).tolist() == [0]
    # one cone alone is manifold everywhere
    assert non_manifold_vertices(_cone(k, 0, 1, True), k + 2).size == 0
    # flip one cone: its edges stay consistent, the pinch is still a bow tie
    F2 = np.concatenate([_cone(k, 0, 1, True), _cone(k, 0, k + 2, False)])
    assert non_manifold_vertices(F2, n).tolist() == [0]


def test_non_manifold_vertices_match_reference_on_random_damage(sphere):
    V, F0 = sphere
    rng = np.random.default_rng(7)
    n = V.shape[0]
    for trial in range(40):
        F = F0.copy()
        idx = rng.choice(len(F), size=5, replace=False)
        if trial % 4 == 0:
            F[idx] = F[idx][:, ::-1]
        elif trial % 4 == 1:
            F = np.delete(F, idx, axis=0)
        elif trial % 4 == 2:
            M = np.arange(n)
            M[rng.choice(n, 4)] = rng.choice(n, 4)
            F = M[F]
        else:
            F = np.concatenate([F, F[idx]])
        assert non_manifold_vertices(F, n).tolist() == _fans_reference(F, n).tolist()


def test_grouped_half_edges_are_stable(ring):
    _, F = ring
    topo = edge_topology(F)
    assert np.array_equal(topo.half_order, np.argsort(topo.half_to_edge, kind="stable"))


def test_greedy_colouring_matches_networkx_largest_first():
    """Same colours as networkx's greedy_color(strategy="largest_first") on random graphs,
    and no edge joins two nodes of one colour."""
    import networkx as nx

    from geotex.mesh.topology import greedy_colouring

    rng = np.random.default_rng(7)
    for _ in range(200):
        n = int(rng.integers(1, 40))
        pairs = rng.integers(0, n, size=(int(rng.integers(0, 90)), 2))
        g = nx.Graph()
        g.add_nodes_from(range(n))
        g.add_edges_from((a, b) for a, b in pairs.tolist() if a != b)
        ref = nx.greedy_color(g, strategy="largest_first")
        got = greedy_colouring(n, pairs)
        assert got.tolist() == [ref[i] for i in range(n)]
        loops = pairs[:, 0] == pairs[:, 1]
        assert not np.any(got[pairs[~loops, 0]] == got[pairs[~loops, 1]])


def test_packed_key_sort_matches_the_general_path_and_a_reference():
    # edge_topology sorts int64 keys with the half-edge index packed into the low
    # bits when they fit in 63 bits, else argsorts the keys; both must agree with
    # each other and with np.unique, also on repeated, non-manifold and
    # inconsistently oriented faces
    rng = np.random.default_rng(7)
    for _ in range(50):
        n = int(rng.integers(3, 30))
        F = rng.integers(0, n, size=(int(rng.integers(1, 60)), 3))
        packed = edge_topology(F, n)
        general = edge_topology(F, 2 ** 40)           # (2^40)^2 needs 80 bits: argsort path
        for name in ("edges", "half_to_edge", "face_count", "forward_count", "half_order"):
            assert np.array_equal(getattr(packed, name), getattr(general, name)), name
        a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
        pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)
        edges, inv, counts = np.unique(pairs, axis=0, return_inverse=True, return_counts=True)
        assert np.array_equal(packed.edges, edges)
        assert np.array_equal(packed.half_to_edge, inv.ravel())
        assert np.array_equal(packed.face_count, counts)
        assert np.array_equal(packed.half_order, np.argsort(inv.ravel(), kind="stable"))


def _with_pillow(V, F):
    """``(V, F)`` plus a detached face and its reverse (two faces, one vertex set)."""
    n = len(V)
    V = np.vstack([V, [[5.0, 0, 0], [6.0, 0, 0], [5.0, 1.0, 0]]])
    return V, np.vstack([F, [[n, n + 1, n + 2]], [[n, n + 2, n + 1]]])


def test_has_twin_faces_finds_faces_with_one_vertex_set():
    from geotex.mesh.topology import edge_topology, has_twin_faces

    V, F = torus(1.0, 0.3, n_major=12, n_minor=7)
    assert not has_twin_faces(edge_topology(F, len(V)))
    V2, F2 = _with_pillow(V, F)
    assert has_twin_faces(edge_topology(F2, len(V2)))
    # one face across two edges only (a fan of two faces sharing an edge) is no twin
    F3 = np.array([[0, 1, 2], [0, 2, 3]])
    assert not has_twin_faces(edge_topology(F3, 4))
    with pytest.raises(InputError):
        has_twin_faces(edge_topology(np.vstack([F, F[:1]]), len(V)))


@pytest.mark.parametrize("jit", [True, False])
def test_duplicate_faces_with_topology_equal_sorting(monkeypatch, jit):
    import geotex.mesh.topology as topology

    monkeypatch.setattr(topology, "JIT_MIN_SIZE", 0 if jit else 10 ** 12)
    V, F = torus(1.0, 0.3, n_major=12, n_minor=7)
    cases = [F, _with_pillow(V, F)[1], np.vstack([F, F[5:6, ::-1]]),      # an edge of 3+ faces
             np.vstack([F, [[0, 0, 1]], [[0, 1, 0]]])]                      # repeated indices
    for G in cases:
        n = int(G.max()) + 1
        ref = duplicate_face_groups(G)
        got = duplicate_face_groups(G, topology.edge_topology(G, n))
        assert got.dtype == np.int64 and np.array_equal(got, ref)
    assert duplicate_face_groups(cases[1]).tolist() == [len(F) + 1]
    assert duplicate_face_groups(cases[2]).tolist() == [len(F)]


def test_unpaired_edge_vertices_marks_bad_edges_only():
    from geotex.mesh.topology import unpaired_edge_vertices

    V, F = icosphere(2)
    assert not unpaired_edge_vertices(edge_topology(F, len(V)), len(V)).any()
    # a hole: the three corners of the removed face are on boundary edges
    out = unpaired_edge_vertices(edge_topology(F[1:], len(V)), len(V))
    assert set(np.flatnonzero(out)) == set(F[0])
    # a flipped face: its three edges run twice the same way
    G = F.copy()
    G[5] = G[5, ::-1]
    out = unpaired_edge_vertices(edge_topology(G, len(V)), len(V))
    assert set(np.flatnonzero(out)) == set(F[5])
    # an open grid: exactly its border vertices
    V, F = grid_plane(4, 3)
    border = (V[:, 0] == V[:, 0].min()) | (V[:, 0] == V[:, 0].max()) | \
        (V[:, 1] == V[:, 1].min()) | (V[:, 1] == V[:, 1].max())
    assert np.array_equal(unpaired_edge_vertices(edge_topology(F, len(V)), len(V)), border)
