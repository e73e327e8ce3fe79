import numpy as np
import pytest
from scipy.spatial import Delaunay

from geotex.errors import InputError
from geotex.mesh import edge_topology, face_areas, face_normals
from geotex.mesh.primitives import box, grid_plane, icosphere, torus
from geotex.patches import (boundary_loops, cluster_hierarchy, disc_clusters, effect_area,
                            face_adjacency, grow_patch, is_disc, is_disc_partition)


def jittered_disc(n=300, seed=0):
    """Irregular planar triangulation (Delaunay of random points), ccw faces, z = 0."""
    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.uniform(-1, 1, (n, 2)), [[-1, -1], [1, -1], [1, 1], [-1, 1]]])
    F = Delaunay(pts).simplices.astype(np.int64)
    a, b, c = pts[F[:, 0]], pts[F[:, 1]], pts[F[:, 2]]
    neg = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[neg] = F[neg][:, ::-1]
    V = np.column_stack([pts, np.zeros(len(pts))])
    return V, F


def euler_and_loops(F):
    t = edge_topology(F, int(F.max()) + 1)
    nv = np.unique(F).size
    return nv - len(t.edges) + len(F), len(boundary_loops(F)), int(t.face_count.max())


def assert_disc(patch, F):
    sub = F[patch.faces]
    chi, loops, maxc = euler_and_loops(sub)
    assert chi == 1 and loops == 1 and maxc <= 2
    assert patch.is_disc
    assert np.array_equal(patch.vertices[patch.F], sub)
    # the boundary loop is a closed cycle of boundary edges of the patch
    t = edge_topology(sub, int(F.max()) + 1)
    bnd = {tuple(e) for e in t.edges[t.face_count == 1].tolist()}
    lp = patch.boundary_loop.tolist()
    assert len(lp) == len(bnd) == len(set(lp))
    assert {tuple(sorted((lp[i], lp[(i + 1) % len(lp)]))) for i in range(len(lp))} == bnd


# ---------------------------------------------------------------------------
# grow_patch
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("radius", [0.05, 0.3, 0.8, 1.5, 2.5, 4.0, None])
def test_grow_patch_gives_discs_on_sphere(sphere, radius):
    V, F = sphere
    adj = face_adjacency(V, F)
    C = V[F].mean(axis=1)
    for seed in range(0, len(F), 97):
        p = grow_patch(V, F, seed, max_radius=radius, adjacency=adj)
        assert p.faces[0] == seed and p.seed_face == seed
        assert np.unique(p.faces).size == p.n_faces
        assert_disc(p, F)
        # Dijkstra distances: each face is reached from a neighbour added before it
        pos = {f: i for i, f in enumerate(p.faces.tolist())}
        for i, f in enumerate(p.faces.tolist()[1:], start=1):
            via = [p.distances[pos[g]] + w for g, w in zip(adj.face_neighbors[f],
                                                          adj.neighbor_distance[f])
                   if g >= 0 and pos.get(int(g), i) < i]
            assert via and p.distances[i] == pytest.approx(min(via), abs=1e-12)
        # faces join by distance, except those held back by the disc test
        assert np.all(p.distances >= 0)
        if radius is not None:
            assert p.distances.max() <= radius
            # Euclidean is below the dual-graph distance
            assert np.linalg.norm(C[p.faces] - C[seed], axis=1).max() <= radius + 1e-12
    # an unbounded patch covers everything but the face that would close the sphere
    if radius is None:
        assert p.n_faces == len(F) - 1


def test_grow_patch_is_distance_ball_on_plane():
    import scipy.sparse as sp
    from scipy.sparse.csgraph import dijkstra
    V, F = jittered_disc(400, seed=3)
    adj = face_adjacency(V, F)
    C = V[F].mean(axis=1)
    seed = int(np.argmin(np.linalg.norm(C, axis=1)))
    m = len(F)
    rows = np.repeat(np.arange(m), 3)
    cols = adj.face_neighbors.ravel()
    k = cols >= 0
    G = sp.csr_matrix((adj.neighbor_distance.ravel()[k], (rows[k], cols[k])), shape=(m, m))
    d = dijkstra(G, indices=seed)
    for radius in (0.3, 0.5, 0.8):
        p = grow_patch(V, F, seed, max_radius=radius, adjacency=adj)
        assert_disc(p, F)
        # on a planar disc nothing blocks growth: the patch is the dual-distance ball
        assert sorted(p.faces.tolist()) == np.flatnonzero(d <= radius).tolist()
        assert np.allclose(p.distances, d[p.faces], rtol=0, atol=1e-12)


def test_grow_patch_on_torus_stays_disc(ring):
    V, F = ring
    for seed in (0, 77, 400):
        p = grow_patch(V, F, seed, max_radius=100.0)
        assert_disc(p, F)
        assert p.n_faces > 0.8 * len(F)      # grew a lot, but never closed around a loop
        assert p.n_faces < len(F)


def test_grow_patch_on_open_box_and_grid():
    V, F = grid_plane(8, 8)
    p = grow_patch(V, F, 0)
    assert p.n_faces == len(F) and p.is_disc   # the whole square is a disc
    V, F = box(divisions=3)
    p = grow_patch(V, F, 5)
    assert_disc(p, F) and p.n_faces == len(F) - 1


def test_grow_patch_normal_cone(sphere):
    V, F = sphere
    N = face_normals(V, F)
    for angle in (0.2, 0.6, 1.2):
        p = grow_patch(V, F, 10, max_normal_angle=angle)
        assert_disc(p, F)
        cos = np.clip(N[p.faces] @ N[10], -1, 1)
        assert np.arccos(cos).max() <= angle + 1e-9
        assert p.n_faces > 1
    # a cube face: a cone of 0.1 rad keeps exactly the side the seed is on
    V, F = box(divisions=4)
    p = grow_patch(V, F, 0, max_normal_angle=0.1)
    N = face_normals(V, F)
    side = np.flatnonzero(N @ N[0] > 0.99)
    assert sorted(p.faces.tolist()) == side.tolist()


def test_grow_patch_accept_predicate_and_batches(sphere):
    V, F = sphere
    C = V[F].mean(axis=1)
    calls = []

    def upper(ids):
        calls.append(ids.copy())
        return C[ids, 2] > -0.2

    seed = int(np.argmax(C[:, 2]))
    p = grow_patch(V, F, seed, accept=upper)
    assert_disc(p, F)
    assert np.all(C[p.faces[1:], 2] > -0.2)
    seen = np.concatenate(calls)
    assert np.unique(seen).size == seen.size           # every face asked once
    assert all(1 <= len(c) <= 3 for c in calls)
    assert seed not in seen
    # faces above the cut that the disc constraint allows are all present
    assert p.n_faces >= np.count_nonzero(C[:, 2] > -0.1)


def test_grow_patch_max_faces_and_determinism(sphere):
    V, F = sphere
    p = grow_patch(V, F, 3, max_faces=50)
    assert p.n_faces == 50 and p.is_disc
    q = grow_patch(V, F, 3, max_faces=50)
    assert np.array_equal(p.faces, q.faces) and np.array_equal(p.boundary_loop, q.boundary_loop)
    full = grow_patch(V, F, 3)
    assert np.array_equal(full.faces[:50], p.faces)


def test_grow_patch_does_not_mutate_inputs(sphere):
    V, F = sphere
    V0, F0 = V.copy(), F.copy()
    grow_patch(V, F, 1, max_radius=0.5, max_normal_angle=1.0, accept=lambda ids: ids >= 0)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


def test_grow_patch_errors(sphere):
    V, F = sphere
    with pytest.raises(InputError, match="seed_face"):
        grow_patch(V, F, len(F))
    with pytest.raises(InputError, match="seed_face"):
        grow_patch(V, F, 1.5)
    with pytest.raises(InputError, match="max_radius"):
        grow_patch(V, F, 0, max_radius=-1)
    with pytest.raises(InputError, match="max_normal_angle"):
        grow_patch(V, F, 0, max_normal_angle=4.0)
    with pytest.raises(InputError, match="max_faces"):
        grow_patch(V, F, 0, max_faces=0)
    with pytest.raises(InputError, match="accept"):
        grow_patch(V, F, 0, accept=lambda ids: np.ones(len(ids) + 1, bool))
    with pytest.raises(InputError, match="accept"):
        grow_patch(V, F, 0, accept=3)
    with pytest.raises(InputError, match="adjacency"):
        grow_patch(V, F, 0, adjacency=face_adjacency(*icosphere(1)))
    bad = F.copy()
    bad[0, 1] = bad[0, 0]
    with pytest.raises(InputError, match="repeated vertex"):
        grow_patch(V, bad, 0)


def test_is_disc():
    assert is_disc(grid_plane(3, 3)[1])
    assert not is_disc(icosphere(1)[1])
    V, F = grid_plane(4, 4)
    hole = np.ones(len(F), bool)
    hole[[5, 5 + 16]] = False                          # an interior quad removed
    assert not is_disc(F[hole])
    assert not is_disc(torus(n_major=8, n_minor=6)[1])
    two = np.vstack([F, F + F.max() + 1])               # two discs
    assert not is_disc(two)


# ---------------------------------------------------------------------------
# cluster hierarchy
# ---------------------------------------------------------------------------

# The face-cluster hierarchy itself is tested in tests/test_hpm.py.


def test_is_disc_partition_detects_bad_clusters(sphere):
    V, F = sphere
    z = V[F].mean(axis=1)[:, 2]
    band = (np.abs(z) < 0.3).astype(np.int64)         # an equatorial band is an annulus
    assert not is_disc_partition(F, band)
    # label 0 is the two polar caps (two pieces), label 1 the band (an annulus)
    assert disc_clusters(F, band).tolist() == [False, False]
    halves = (z > 0).astype(np.int64)
    assert is_disc_partition(F, halves)
    assert not is_disc_partition(F, np.zeros(len(F), np.int64))   # closed sphere
    two_caps = np.where(np.abs(z) > 0.5, 0, 1)         # cluster 0 has two pieces
    assert not is_disc_partition(F, two_caps)
    with pytest.raises(InputError, match="labels"):
        is_disc_partition(F, np.zeros(3, np.int64))


# ---------------------------------------------------------------------------
# effect area
# ---------------------------------------------------------------------------

def _connected(F, faces, n):
    from geotex.mesh import face_components
    k, _ = face_components(F[faces], n)
    return k


def test_effect_area_budget_and_distance(sphere):
    V, F = sphere
    A = face_areas(V, F)
    faces, d = effect_area(V, F, [7], budget_area=1.5, return_distance=True)
    assert faces[0] == 7 and d[0] == 0
    assert A[faces].sum() <= 1.5
    assert np.all(np.diff(d) >= 0)
    # greedy by distance: the next face would have broken the budget
    all_faces, all_d = effect_area(V, F, [7], max_distance=np.inf, return_distance=True)
    k = len(faces)
    assert np.array_equal(all_faces[:k], faces)
    assert A[all_faces[:k + 1]].sum() > 1.5
    assert _connected(F, faces, len(V)) == 1
    near = effect_area(V, F, [7], max_distance=0.4)
    C = V[F].mean(axis=1)
    assert np.linalg.norm(C[near] - C[7], axis=1).max() <= 0.4
    both = effect_area(V, F, [7], max_distance=0.4, budget_area=0.2)
    assert set(both) <= set(near) and A[both].sum() <= 0.2


def test_effect_area_blocked_faces_and_edges():
    V, F = grid_plane(10, 10)
    C = V[F].mean(axis=1)
    wall = np.flatnonzero(np.abs(C[:, 0] - 0.5) < 0.05)       # a column of faces
    seed = int(np.argmin(np.linalg.norm(C - [0.2, 0.5, 0], axis=1)))
    faces = effect_area(V, F, seed, max_distance=np.inf, blocked=wall)
    assert np.all(C[faces, 0] < 0.5) and not np.isin(wall, faces).any()
    # block the vertical grid line x = 0.5 by its edges
    t = edge_topology(F, len(V))
    xs = V[t.edges][:, :, 0]
    line = t.edges[np.all(np.abs(xs - 0.5) < 1e-9, axis=1)]
    faces = effect_area(V, F, seed, max_distance=np.inf, blocked_edges=line)
    assert np.all(C[faces, 0] < 0.5) and len(faces) == len(F) // 2
    ids = np.flatnonzero(np.all(np.abs(xs - 0.5) < 1e-9, axis=1))
    assert np.array_equal(effect_area(V, F, seed, max_distance=np.inf, blocked_edges=ids), faces)


def test_effect_area_errors_and_purity(sphere):
    V, F = sphere
    V0, F0 = V.copy(), F.copy()
    with pytest.raises(InputError, match="budget_area or max_distance"):
        effect_area(V, F, [0])
    with pytest.raises(InputError, match="seed_faces"):
        effect_area(V, F, [], max_distance=1)
    with pytest.raises(InputError, match="seed_faces"):
        effect_area(V, F, [len(F)], max_distance=1)
    with pytest.raises(InputError, match="blocked"):
        effect_area(V, F, [0], max_distance=1, blocked=[0])
    with pytest.raises(InputError, match="budget_area"):
        effect_area(V, F, [0], budget_area=-1)
    with pytest.raises(InputError, match="not an edge"):
        effect_area(V, F, [0], max_distance=1, blocked_edges=[[0, 0]])
    a = effect_area(V, F, [0, 9], budget_area=2.0)
    b = effect_area(V, F, [9, 0], budget_area=2.0)
    assert np.array_equal(a, b) and set(a[:2]) == {0, 9}
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


def fins():
    """Three 4x4 grids (fins) sharing their x = 0 side: that side is non-manifold."""
    V0, F0 = grid_plane(4, 4)
    Vs = [np.column_stack([V0[:, 0] * np.cos(a), V0[:, 1], V0[:, 0] * np.sin(a)])
          for a in (0.0, 2.0, 4.0)]
    V = np.vstack(Vs)
    F = np.vstack([F0 + k * len(V0) for k in range(3)])
    key = np.round(V * 1000).astype(np.int64)           # weld the shared column
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return V[first], inv.ravel()[F]


def test_non_manifold_edges_are_never_crossed():
    V, F = fins()
    t = edge_topology(F, len(V))
    assert t.non_manifold.size == 4
    p = grow_patch(V, F, 0)
    assert_disc(p, F)
    assert p.n_faces == 32                       # one fin only
    H = cluster_hierarchy(V, F)
    for lv in H.levels:
        assert is_disc_partition(F, lv.labels)
    assert H[0].n_clusters == 3                  # one top cluster per fin
    faces = effect_area(V, F, 0, max_distance=np.inf)
    assert len(faces) == 32


@pytest.mark.parametrize("factor", [1e-6, 1e6])
def test_scale_invariance(sphere, factor):
    V, F = sphere
    # break the icosphere's symmetry so no two distances or costs tie exactly
    V = V * np.random.default_rng(7).uniform(0.97, 1.03, (len(V), 1))
    Vs = V * factor
    p = grow_patch(V, F, 4, max_radius=0.7, max_normal_angle=1.0)
    q = grow_patch(Vs, F, 4, max_radius=0.7 * factor, max_normal_angle=1.0)
    assert np.array_equal(p.faces, q.faces)
    a = cluster_hierarchy(V, F)
    b = cluster_hierarchy(Vs, F)
    assert len(a) == len(b)
    assert all(np.array_equal(x.labels, y.labels) for x, y in zip(a.levels, b.levels))
    e1 = effect_area(V, F, [3], budget_area=0.8)
    e2 = effect_area(Vs, F, [3], budget_area=0.8 * factor**2)
    assert np.array_equal(e1, e2)
