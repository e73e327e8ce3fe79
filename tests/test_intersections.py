"""Tests of geotex.check.intersections.self_intersecting_pairs."""

from __future__ import annotations

import itertools

import igl
import numpy as np
import pytest

import geotex.check.intersections as gi
from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import InputError
from geotex.mesh import primitives
from geotex.mesh.geometry import degenerate_faces

# ---------------------------------------------------------------------------
# mesh generators


def icosphere(level: int, *, radius: float = 1.0, center=(0.0, 0.0, 0.0)):
    """Subdivided icosahedron projected on a sphere, outward-facing."""
    return primitives.icosphere(level, radius=radius, center=center)


def torus(nu: int, nv: int, *, R: float = 1.0, r: float = 0.35):
    """Closed torus grid, two triangles per quad."""
    return primitives.torus(R, r, n_major=nu, n_minor=nv)


def two_spheres(level=2, offset=(0.9, 0.13, 0.07)):
    V1, F1 = icosphere(level)
    V2, F2 = icosphere(level, radius=0.8, center=offset)
    return np.concatenate([V1, V2]), np.concatenate([F1, F2 + len(V1)]), len(F1)


def random_soup(seed, m=200, *, pool=None, sizes=(0.05, 0.4)):
    """Random triangles in the unit cube; ``pool`` vertices shared if given."""
    rng = np.random.default_rng(seed)
    if pool is None:
        centers = rng.random((m, 1, 3))
        scale = np.exp(rng.uniform(np.log(sizes[0]), np.log(sizes[1]), (m, 1, 1)))
        V = (centers + scale * rng.normal(size=(m, 3, 3))).reshape(-1, 3)
        F = np.arange(3 * m).reshape(m, 3)
    else:
        V = rng.random((pool, 3))
        F = np.array([rng.choice(pool, 3, replace=False) for _ in range(m)])
    return V, F


# ---------------------------------------------------------------------------
# references


def as_set(pairs):
    return {tuple(p) for p in np.asarray(pairs).tolist()}


def brute_force(V, F):
    """All pairs through the narrow phase, no broad phase (O(m^2))."""
    faces = gi._FaceData(gi._normalized(V, F), F)
    act = faces.active
    i, j = np.triu_indices(act.size, k=1)
    i, j = act[i], act[j]
    hit = gi._intersecting(faces, i, j)
    return np.stack([i[hit], j[hit]], axis=1)


def igl_hit(V, fa, fb):
    """igl's verdict for one pair, plus the length of its intersection segment."""
    tri = [V[k][None, :].astype(float) for k in (*fa, *fb)]
    hit, coplanar, source, target = igl.tri_tri_intersection_test_3d(*tri)
    length = float(np.linalg.norm(np.asarray(source) - np.asarray(target))) if hit else 0.0
    return bool(hit), bool(coplanar), length


def independent_reference(V, F):
    """Slow per-pair reference built on igl, for meshes in general position.

    No shared vertex: igl's test.  One shared vertex ``p``: igl's intersection
    segment must be longer than a point.  Two or three shared vertices: never
    (a fold needs exact coplanarity, which random data does not produce).
    """
    out = []
    scale = np.ptp(V, axis=0).max()
    for a, b in itertools.combinations(range(len(F)), 2):
        shared = len(set(F[a].tolist()) & set(F[b].tolist()))
        if shared >= 2:
            continue
        hit, coplanar, length = igl_hit(V, F[a], F[b])
        assert not coplanar
        if hit and (shared == 0 or length > 1e-9 * scale):
            out.append((a, b))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def check_output(pairs, m):
    assert pairs.dtype == np.int64
    assert pairs.ndim == 2 and pairs.shape[1] == 2
    assert np.all(pairs[:, 0] < pairs[:, 1])
    assert np.all((pairs >= 0) & (pairs < m))
    keys = pairs[:, 0] * m + pairs[:, 1]
    assert np.all(np.diff(keys) > 0), "rows must be sorted and unique"


# ---------------------------------------------------------------------------
# input handling


def test_empty_input():
    out = self_intersecting_pairs(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    assert out.shape == (0, 2) and out.dtype == np.int64
    V, F = icosphere(0)
    assert self_intersecting_pairs(V, F[:1]).shape == (0, 2)
    assert self_intersecting_pairs(V, F[:0]).shape == (0, 2)


def test_bad_input_raises():
    V, F = icosphere(1)
    with pytest.raises(InputError):
        self_intersecting_pairs(V[:, :2], F)
    with pytest.raises(InputError):
        self_intersecting_pairs(V, F + len(V))
    bad = V.copy()
    bad[0, 0] = np.nan
    with pytest.raises(InputError):
        self_intersecting_pairs(bad, F)
    for value in (-1, 1.5, "3", True):
        with pytest.raises(InputError):
            self_intersecting_pairs(V, F, max_pairs=value)


def test_inputs_not_modified_and_lists_accepted():
    V, F, _ = two_spheres()
    V0, F0 = V.copy(), F.copy()
    out = self_intersecting_pairs(V, F)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)
    assert np.array_equal(self_intersecting_pairs(V.tolist(), F.tolist()), out)
    assert np.array_equal(self_intersecting_pairs(V.astype(np.float32), F.astype(np.int32)),
                          self_intersecting_pairs(V.astype(np.float32).astype(float), F))


# ---------------------------------------------------------------------------
# clean meshes


@pytest.mark.parametrize("level", [0, 1, 2, 3, 4, 5])
def test_icosphere_is_clean(level):
    V, F = icosphere(level)
    assert self_intersecting_pairs(V, F).shape == (0, 2)


@pytest.mark.parametrize("nu,nv", [(12, 6), (60, 20), (40, 120), (200, 70)])
def test_torus_is_clean(nu, nv):
    V, F = torus(nu, nv)
    assert self_intersecting_pairs(V, F).shape == (0, 2)


def test_flat_grid_is_clean():
    # coplanar neighbours everywhere: exercises the coplanar tests
    V, F = igl.triangulated_grid(40, 30)
    V = np.column_stack([V, np.zeros(len(V))])
    assert self_intersecting_pairs(V, F.astype(np.int64)).shape == (0, 2)
    # and a cube made of flat grids (coplanar fans, right-angle edges)
    cube_V, cube_F = [], []
    g, gf = igl.triangulated_grid(8, 8)
    g = g * 2 - 1
    for axis in range(3):
        for sign in (-1.0, 1.0):
            P = np.insert(g, axis, sign, axis=1)
            f = gf if sign > 0 else gf[:, ::-1]
            cube_F.append(f + sum(len(v) for v in cube_V))
            cube_V.append(P)
    V = np.concatenate(cube_V)
    F = np.concatenate(cube_F).astype(np.int64)
    # weld the duplicated boundary vertices of the six grids
    key = np.round(V * 1e6).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    V, F = V[first], inv.ravel()[F]
    assert len(degenerate_faces(V, F)) == 0
    assert self_intersecting_pairs(V, F).shape == (0, 2)


# ---------------------------------------------------------------------------
# the cases of the semantics


def tri_pair(A, B, shared=0):
    """Two faces with corners ``A`` and ``B``; the first ``shared`` corners shared."""
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    V = np.concatenate([A, B[shared:]])
    F = np.array([[0, 1, 2], [*range(shared), *range(3, 6 - shared)]], dtype=np.int64)
    return V, F


def hits(V, F):
    return self_intersecting_pairs(V, F).shape[0] == 1


A0 = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]


def test_no_shared_vertex_piercing_and_separate():
    assert hits(*tri_pair(A0, [[0.5, 0.5, -1], [0.6, 0.4, 1], [3, 3, 1]]))
    assert not hits(*tri_pair(A0, [[0.5, 0.5, 0.1], [0.6, 0.4, 1], [3, 3, 1]]))
    # an edge of each crosses the other (neither contains a whole edge)
    assert hits(*tri_pair(A0, [[1.5, 1.5, -1], [1.5, 1.5, 1], [-1, -1, 0.2]]))
    # crossing planes but disjoint triangles
    assert not hits(*tri_pair(A0, [[3, 3, -1], [3, 3, 1], [2.5, 0.6, 0]]))


def test_touching_at_a_point():
    # a corner of B exactly on A's interior, B above
    assert hits(*tri_pair(A0, [[0.5, 0.5, 0], [1, 1, 1], [0, 1, 1]]))
    # corner on A's edge, corner on A's corner
    assert hits(*tri_pair(A0, [[1, 0, 0], [1, -1, 1], [0, -1, 1]]))
    assert hits(*tri_pair(A0, [[2, 0, 0], [3, 0, 1], [3, 1, 1]]))
    # edge touching edge at one point (crossing edges, one above the other... at z=0)
    assert hits(*tri_pair(A0, [[1.5, 1.5, 0], [0.5, -0.5, 0.0], [1, 1, 2]]))
    # just apart
    assert not hits(*tri_pair(A0, [[0.5, 0.5, 1e-6], [1, 1, 1], [0, 1, 1]]))
    assert not hits(*tri_pair(A0, [[2 + 1e-6, 0, 0], [3, 0, 1], [3, 1, 1]]))


def test_coplanar_no_shared_vertex():
    # overlapping
    assert hits(*tri_pair(A0, [[0.5, 0.5, 0], [3, 0.5, 0], [0.5, 3, 0]]))
    # one inside the other (no edge crossings at all)
    assert hits(*tri_pair(A0, [[0.2, 0.2, 0], [0.6, 0.2, 0], [0.2, 0.6, 0]]))
    assert hits(*tri_pair([[0.2, 0.2, 0], [0.6, 0.2, 0], [0.2, 0.6, 0]], A0))
    # touching along an edge, at a corner, corner on edge
    assert hits(*tri_pair(A0, [[2, 0, 0], [0, 2, 0], [2, 2, 0]]))
    assert hits(*tri_pair(A0, [[2, 0, 0], [3, 0, 0], [3, 1, 0]]))
    assert hits(*tri_pair(A0, [[1, 1, 0], [3, 1, 0], [1, 3, 0]]))
    # separate, and separated by a hair
    assert not hits(*tri_pair(A0, [[1.1, 1.1, 0], [3, 1, 0], [1, 3, 0]]))
    assert not hits(*tri_pair(A0, [[2 + 1e-7, 0, 0], [0, 2 + 1e-7, 0], [2, 2, 0]]))


def test_shared_vertex_piercing():
    # B's opposite edge crosses A's interior
    assert hits(*tri_pair(A0, [[0, 0, 0], [0.5, 0.4, 1], [0.5, 0.4, -1]], shared=1))
    # B's opposite edge misses A, but A's opposite edge crosses B: the
    # intersection segment runs from p to A's far edge
    assert hits(*tri_pair(A0, [[0, 0, 0], [3, 1, 1], [3, 1, -1]], shared=1))
    # B lies in a plane through p and slices A from p onwards
    assert hits(*tri_pair(A0, [[0, 0, 0], [0.3, 0.3, 1], [0.4, 0.2, -1]], shared=1))


def test_shared_vertex_edge_on_the_other_face():
    # B's edge at p runs along A's edge p-a1, B standing up: touching beyond p
    assert hits(*tri_pair(A0, [[0, 0, 0], [1, 0, 0], [0, 0, 1]], shared=1))
    # B's edge at p lies inside A, B standing up
    assert hits(*tri_pair(A0, [[0, 0, 0], [1, 1, 0], [0, -1, 1]], shared=1))


def test_shared_vertex_not_intersecting():
    # B above A, its projection overlapping A: meets A's plane only at p
    assert not hits(*tri_pair(A0, [[0, 0, 0], [1, 1, 1], [1, 0.2, 1]], shared=1))
    # B through A's plane but outside A
    assert not hits(*tri_pair(A0, [[0, 0, 0], [-1, -1, 1], [-1, -0.5, -1]], shared=1))
    # B's opposite edge crosses A's plane outside A, and the plane of B cuts A
    # only at p
    assert not hits(*tri_pair(A0, [[0, 0, 0], [-1, 1, 1], [-1, 1, -1]], shared=1))
    # a sphere's fan: neighbours meeting at one vertex only
    V, F = icosphere(0)
    assert self_intersecting_pairs(V, F).shape == (0, 2)


def test_shared_vertex_coplanar_wedges():
    # wedges overlap
    assert hits(*tri_pair(A0, [[0, 0, 0], [1, 0.5, 0], [3, -1, 0]], shared=1))
    # one wedge inside the other
    assert hits(*tri_pair(A0, [[0, 0, 0], [1, 0.2, 0], [0.2, 1, 0]], shared=1))
    # wedges sharing a boundary ray (collinear edges from p): touch beyond p
    assert hits(*tri_pair(A0, [[0, 0, 0], [0, -1, 0], [1, 0, 0]], shared=1))
    # wedges meeting only at p
    assert not hits(*tri_pair(A0, [[0, 0, 0], [-1, 0.5, 0], [-1, -1, 0]], shared=1))
    assert not hits(*tri_pair(A0, [[0, 0, 0], [1, -1e-6, 0], [1, -1, 0]], shared=1))


def test_shared_edge_fold():
    # B = (a1, p, b): shares edge p-a1 with A
    # A = (p, a1, a2), B = (a1, p, b) shares the edge p-a1; only b moves
    for b, expected in [([1, -1, 0], False),      # flat, on the other side
                        ([1, 1, 0], True),        # folded onto A
                        ([5, 3, 0], True),        # folded, reaching beyond A
                        ([1, 1, 0.05], False),    # bent, not folded
                        ([1, 1, 1e-7], False),    # nearly folded
                        ([3, 0, 0], False)]:      # collinear: degenerate B
        V = np.concatenate([np.asarray(A0, float), [b]])
        assert hits(V, np.array([[0, 1, 2], [1, 0, 3]])) == expected, b
    # folded with inconsistent orientation
    V = np.concatenate([np.asarray(A0, float), [[1, 1, 0]]])
    assert hits(V, np.array([[0, 1, 2], [0, 1, 3]]))
    # a sharp but open dihedral angle is not an intersection
    V = np.concatenate([np.asarray(A0, float), [[1, 1, 0.001]]])
    assert not hits(V, np.array([[0, 1, 2], [1, 0, 3]]))


def test_duplicates_and_degenerates_excluded():
    V, F = icosphere(2)
    n = len(F)
    extra = np.array([F[5][::-1], F[7][[1, 2, 0]]])              # duplicates
    # degenerate faces crossing the sphere: a repeated index, collinear corners
    V2 = np.concatenate([V, [[-2, 0.01, 0.02], [2, 0.01, 0.02], [0, 0.01, 0.02]]])
    k = len(V)
    degen = np.array([[k, k + 1, k + 1], [k, k + 1, k + 2]])
    F2 = np.concatenate([F, extra, degen])
    assert set(degenerate_faces(V2, F2).tolist()) == {n + 2, n + 3}
    assert self_intersecting_pairs(V2, F2).shape == (0, 2)
    # a duplicate face is still tested against the other faces
    V3 = np.concatenate([V2, [[0, 0, -2], [0.01, 0.02, 2], [0.03, -0.02, 2]]])
    F3 = np.concatenate([F2, [[k + 3, k + 4, k + 5]]])
    out = self_intersecting_pairs(V3, F3)
    assert out.shape[0] > 0 and np.all(out[:, 1] == len(F3) - 1)


# ---------------------------------------------------------------------------
# meshes with intersections, against references


def test_two_spheres_against_igl():
    V, F, m1 = two_spheres(level=2)
    out = self_intersecting_pairs(V, F)
    check_output(out, len(F))
    assert out.shape[0] > 0
    # every pair crosses between the two spheres
    assert np.all((out[:, 0] < m1) & (out[:, 1] >= m1))
    expected = []
    for a in range(m1):
        for b in range(m1, len(F)):
            if igl_hit(V, F[a], F[b])[0]:
                expected.append((a, b))
    assert as_set(out) == set(expected)


def test_reported_pairs_really_intersect_large():
    V, F, m1 = two_spheres(level=5, offset=(0.7, 0.31, -0.2))
    out = self_intersecting_pairs(V, F)
    check_output(out, len(F))
    assert out.shape[0] > 100
    rng = np.random.default_rng(0)
    for a, b in out[rng.choice(len(out), 300, replace=False)]:
        assert igl_hit(V, F[a], F[b])[0]


@pytest.mark.parametrize("seed", range(6))
def test_random_soup_matches_igl(seed):
    V, F = random_soup(seed)
    out = self_intersecting_pairs(V, F)
    check_output(out, len(F))
    assert out.shape[0] > 0
    assert np.array_equal(out, independent_reference(V, F))


@pytest.mark.parametrize("seed", range(4))
def test_random_shared_vertex_soup_matches_igl(seed):
    V, F = random_soup(seed, m=120, pool=40)
    out = self_intersecting_pairs(V, F)
    check_output(out, len(F))
    assert np.array_equal(out, independent_reference(V, F))


@pytest.mark.parametrize("seed", range(6))
def test_broad_phase_matches_brute_force(seed, monkeypatch):
    levels = []
    level_tasks = gi._level_tasks

    def spy(faces, cell, cur, low, **kw):
        levels.append(cell)
        return level_tasks(faces, cell, cur, low, **kw)

    monkeypatch.setattr(gi, "_level_tasks", spy)
    # mostly small triangles and a few up to 500 times larger: several levels
    Vs, Fs = random_soup(seed, m=400, sizes=(0.002, 0.01))
    Vb, Fb = random_soup(seed + 100, m=30, sizes=(0.01, 1.0))
    V = np.concatenate([Vs, Vb])
    F = np.concatenate([Fs, Fb + len(Vs)])
    out = self_intersecting_pairs(V, F)
    assert len(levels) >= 3
    assert out.shape[0] > 0
    assert np.array_equal(out, brute_force(V, F))
    V, F = random_soup(seed, m=300, sizes=(0.002, 0.8))
    assert np.array_equal(self_intersecting_pairs(V, F), brute_force(V, F))
    V, F = random_soup(seed, m=300, pool=80)
    assert np.array_equal(self_intersecting_pairs(V, F), brute_force(V, F))


def spread_clusters(seed=3):
    """Tiny triangles in far-apart clusters: too many cells for a dense key."""
    rng = np.random.default_rng(seed)
    centers = rng.random((400, 1, 3)) * 1e7
    centers[200:] = centers[:200] + rng.normal(size=(200, 1, 3)) * 0.5
    centers[:20] *= 1e-3                             # a few faces of a lower level
    V = (centers + rng.normal(size=(400, 3, 3)) * np.where(
        np.arange(400) % 50 == 0, 30.0, 1.0)[:, None, None]).reshape(-1, 3)
    return V, np.arange(1200).reshape(400, 3)


def test_broad_phase_far_apart_clusters(monkeypatch):
    fits = []
    original = gi._fits

    def spy(size, shift):
        fits.append(original(size, shift))
        return fits[-1]

    monkeypatch.setattr(gi, "_fits", spy)
    V, F = spread_clusters()
    out = self_intersecting_pairs(V, F)
    assert out.shape[0] > 0
    assert False in fits and True in fits            # numbered used cells, packed
    assert np.array_equal(out, brute_force(V, F))


@pytest.mark.parametrize("key_bits", [40, 20])
def test_broad_phase_unpacked_fallbacks(monkeypatch, key_bits):
    # fewer key bits: 40 numbers the used cells, 20 sorts coordinates
    monkeypatch.setattr(gi, "_KEY_BITS", key_bits)
    for V, F in (spread_clusters(), random_soup(1, m=300, pool=80),
                 icosphere(3), two_spheres(level=3)[:2]):
        assert np.array_equal(self_intersecting_pairs(V, F), brute_force(V, F))


def test_mixed_sizes_levels():
    # a fine sphere pierced by a few huge triangles
    V, F = icosphere(4)
    big = np.array([[-3, -3, 0.1], [3, -3, 0.2], [0, 4, -0.1],
                    [0.3, -3, -3], [0.2, 3, -3], [-0.1, 0, 4]])
    V2 = np.concatenate([V, big])
    F2 = np.concatenate([F, [[len(V), len(V) + 1, len(V) + 2], [len(V) + 3, len(V) + 4, len(V) + 5]]])
    out = self_intersecting_pairs(V2, F2)
    assert np.array_equal(out, brute_force(V2, F2))
    assert set(np.unique(out[:, 1]).tolist()) == {len(F), len(F) + 1}
    assert np.any(out[:, 0] == len(F))  # the two big triangles cross each other


def _overlap_area(P, Q):
    """Area of the intersection of two 2D triangles (Sutherland-Hodgman)."""
    def ccw(T):
        T = [tuple(p) for p in T]
        cross = ((T[1][0] - T[0][0]) * (T[2][1] - T[0][1])
                 - (T[1][1] - T[0][1]) * (T[2][0] - T[0][0]))
        return T if cross > 0 else T[::-1]

    def left(a, b, p):
        return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])

    poly, clipper = ccw(P), ccw(Q)
    for k in range(3):
        a, b = clipper[k], clipper[(k + 1) % 3]
        src, poly = poly, []
        for u, v in zip(src, src[1:] + src[:1]):
            du, dv = left(a, b, u), left(a, b, v)
            if du >= 0:
                poly.append(u)
            if (du >= 0) != (dv >= 0):
                t = du / (du - dv)
                poly.append((u[0] + (v[0] - u[0]) * t, u[1] + (v[1] - u[1]) * t))
        if not poly:
            return 0.0
    return 0.5 * abs(sum(u[0] * v[1] - v[0] * u[1]
                         for u, v in zip(poly, poly[1:] + poly[:1])))


@pytest.mark.parametrize("seed", range(3))
def test_flat_jittered_grid_matches_polygon_clipping(seed):
    # in-plane jitter flips triangles: coplanar overlaps with 0, 1 and 2
    # shared vertices, checked against the overlap area of each pair
    rng = np.random.default_rng(seed)
    g, F = igl.triangulated_grid(18, 18)
    g = g + rng.normal(scale=0.02, size=g.shape)
    V = np.column_stack([g, np.zeros(len(g))])
    F = F.astype(np.int64)
    out = self_intersecting_pairs(V, F)
    shared = [len(set(F[a].tolist()) & set(F[b].tolist())) for a, b in out]
    assert set(shared) == {0, 1, 2}
    T = g[F]
    lo, hi = T.min(axis=1), T.max(axis=1)
    a, b = np.triu_indices(len(F), k=1)
    near = np.all((lo[a] <= hi[b]) & (lo[b] <= hi[a]), axis=1)
    expected = {(x, y) for x, y in zip(a[near].tolist(), b[near].tolist())
                if _overlap_area(T[x], T[y]) > 1e-12}
    assert as_set(out) == expected


# ---------------------------------------------------------------------------
# scale, position, determinism, early stop


def test_scale_and_translation_invariance():
    V, F, _ = two_spheres(level=3, offset=(0.83, 0.11, 0.05))
    ref = self_intersecting_pairs(V, F)
    assert ref.shape[0] > 0
    for scale in (1e-6, 1e6):
        assert np.array_equal(self_intersecting_pairs(V * scale, F), ref)
    assert np.array_equal(self_intersecting_pairs(V + [1e4, -2e4, 3e3], F), ref)
    Vs, Fs = random_soup(11, m=250, pool=90)
    ref = self_intersecting_pairs(Vs, Fs)
    for scale in (1e-6, 1e6):
        assert np.array_equal(self_intersecting_pairs(Vs * scale, Fs), ref)


def test_exact_contacts_at_any_scale():
    V, F = tri_pair(A0, [[0.5, 0.5, 0], [1, 1, 1], [0, 1, 1]])
    Vc, Fc = tri_pair(A0, [[0, 0, 0], [1, 0, 0], [0, 0, 1]], shared=1)
    for scale in (1e-6, 1.0, 1e6, 1e30, 1e-30):
        assert hits(V * scale, F)
        assert hits(Vc * scale, Fc)


def test_huge_coordinates():
    V, F, _ = two_spheres(level=2)
    ref = self_intersecting_pairs(V, F)
    huge = V / np.abs(V).max() * 3.4e38
    with np.errstate(all="raise"):
        out = self_intersecting_pairs(huge, F)
    assert np.array_equal(out, ref)
    Vc, Fc = icosphere(3)
    assert self_intersecting_pairs(Vc * 3.4e38, Fc).shape == (0, 2)
    assert self_intersecting_pairs(Vc * 1e300, Fc).shape == (0, 2)


def test_unreferenced_far_vertex_does_not_matter():
    V, F, _ = two_spheres(level=2)
    ref = self_intersecting_pairs(V, F)
    V2 = np.concatenate([V, [[1e30, 1e30, 1e30]]])
    assert np.array_equal(self_intersecting_pairs(V2, F), ref)


def test_deterministic_and_chunk_independent(monkeypatch):
    V, F, _ = two_spheres(level=4, offset=(0.5, 0.4, 0.3))
    ref = self_intersecting_pairs(V, F)
    assert np.array_equal(self_intersecting_pairs(V, F), ref)
    monkeypatch.setattr(gi, "_PAIR_CHUNK", 997)
    monkeypatch.setattr(gi, "_FACE_BLOCK", 333)
    assert np.array_equal(self_intersecting_pairs(V, F), ref)
    monkeypatch.setattr(gi, "_MAX_WORKERS", 1)
    assert np.array_equal(self_intersecting_pairs(V, F), ref)


def test_max_pairs(monkeypatch):
    monkeypatch.setattr(gi, "_PAIR_CHUNK", 1000)      # many chunks: a real early stop
    V, F, _ = two_spheres(level=4, offset=(0.5, 0.4, 0.3))
    full = self_intersecting_pairs(V, F)
    assert full.shape[0] > 300
    full_set = as_set(full)
    for k in (1, 7, 100, 300):
        part = self_intersecting_pairs(V, F, max_pairs=k)
        check_output(part, len(F))
        assert 1 <= part.shape[0] <= k
        assert as_set(part) <= full_set
        assert np.array_equal(self_intersecting_pairs(V, F, max_pairs=k), part)
    assert self_intersecting_pairs(V, F, max_pairs=0).shape == (0, 2)
    assert np.array_equal(self_intersecting_pairs(V, F, max_pairs=len(full)), full)
    assert np.array_equal(self_intersecting_pairs(V, F, max_pairs=10 ** 9), full)
    assert np.array_equal(self_intersecting_pairs(V, F, max_pairs=np.int64(10 ** 9)), full)


def test_max_pairs_stops_early(monkeypatch):
    monkeypatch.setattr(gi, "_PAIR_CHUNK", 1000)
    calls = []
    task = gi._pair_task

    def counting(faces, level, s, e):
        calls.append(e - s)
        return task(faces, level, s, e)

    monkeypatch.setattr(gi, "_pair_task", counting)
    V, F, _ = two_spheres(level=4, offset=(0.5, 0.4, 0.3))
    self_intersecting_pairs(V, F)
    everything = len(calls)
    calls.clear()
    self_intersecting_pairs(V, F, max_pairs=1)
    assert len(calls) < everything / 2


# ---------------------------------------------------------------------------
# many faces on few vertices, vertex fans


def cube_corner_faces(m, seed=0):
    """``m`` random faces on the 8 corners of a cube (many duplicates)."""
    rng = np.random.default_rng(seed)
    V = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    F = np.argsort(rng.random((m, 8)), axis=1)[:, :3].astype(np.int64)
    return V, F


@pytest.mark.parametrize("seed", range(3))
def test_faces_on_cube_corners_match_brute_force(seed):
    V, F = cube_corner_faces(150, seed)
    out = self_intersecting_pairs(V, F)
    check_output(out, len(F))
    expected = brute_force(V, F)
    assert expected.shape[0] > 1000
    assert np.array_equal(out, expected)


def test_faces_on_cube_corners_max_pairs():
    V, F = cube_corner_faces(400, 5)
    full = self_intersecting_pairs(V, F)
    full_set = as_set(full)
    for k in (1, 10, 1000, len(full) - 1):
        part = self_intersecting_pairs(V, F, max_pairs=k)
        check_output(part, len(F))
        assert part.shape[0] == k
        assert as_set(part) <= full_set
        assert np.array_equal(self_intersecting_pairs(V, F, max_pairs=k), part)
    assert np.array_equal(self_intersecting_pairs(V, F, max_pairs=len(full)), full)


def test_many_faces_on_cube_corners_are_grouped(monkeypatch):
    # the narrow phase sees the distinct vertex sets only, not all pairs
    calls = []
    narrow = gi._intersecting

    def counting(faces, i, j):
        calls.append(i.size)
        return narrow(faces, i, j)

    monkeypatch.setattr(gi, "_intersecting", counting)
    V, F = cube_corner_faces(4000, 1)
    out = self_intersecting_pairs(V, F)
    assert sum(calls) <= 56 * 55 // 2
    check_output(out, len(F))
    reps = np.unique(np.sort(F, axis=1), axis=0, return_index=True)[1]
    small = brute_force(V, F[np.sort(reps)])
    assert out.shape[0] > 100 * small.shape[0]


@pytest.mark.parametrize("seed", range(6))
def test_lattice_soup_matches_brute_force(seed):
    # few vertices on a small integer lattice: shared vertices and edges,
    # duplicates, coplanar overlaps, touching and degenerate faces
    rng = np.random.default_rng(seed)
    V = rng.integers(0, 3, size=(14, 3)).astype(float)
    V[:, 2] *= seed % 2                     # every other seed: all in a plane
    F = rng.integers(0, len(V), size=(220, 3))
    out = self_intersecting_pairs(V, F)
    check_output(out, len(F))
    assert out.shape[0] > 0
    assert np.array_equal(out, brute_force(V, F))


def cone(k, *, height=1.0, seed=None):
    """A closed cone: apex fan of ``k`` faces over a polygon, and its base fan."""
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    ring = np.column_stack([np.cos(t), np.sin(t), np.zeros(k)])
    if seed is not None:
        ring[:, :2] += np.random.default_rng(seed).normal(scale=0.3 / k, size=(k, 2))
    V = np.concatenate([ring, [[0, 0, height], [0, 0, 0]]])
    i = np.arange(k)
    F = np.concatenate([np.column_stack([i, (i + 1) % k, np.full(k, k)]),
                        np.column_stack([(i + 1) % k, i, np.full(k, k + 1)])])
    return V, F.astype(np.int64)


@pytest.mark.parametrize("height", [1.0, 1e-3, 0.0])
def test_high_valence_fans(height):
    # a flat double fan (height 0) folds onto itself everywhere; low cones
    # are nearly flat fans that must stay clean
    V, F = cone(300, height=height, seed=1)
    out = self_intersecting_pairs(V, F)
    assert np.array_equal(out, brute_force(V, F))
    assert (out.shape[0] > 0) == (height == 0.0)


def test_separated_fans_certify_smooth_meshes_only():
    V, F = icosphere(3)
    faces = gi._FaceData(gi._normalized(V, F), F)
    assert gi._separated_fans(faces).all()
    V, F = torus(40, 20)
    faces = gi._FaceData(gi._normalized(V, F), F)
    assert gi._separated_fans(faces).all()
    # a vertex pulled through the sphere: its spikes pierce the far side
    V, F = icosphere(2)
    V = V.copy()
    V[0] *= -1.5
    out = self_intersecting_pairs(V, F)
    assert out.shape[0] > 0
    assert np.array_equal(out, brute_force(V, F))
    # a flat grid with an interior vertex moved past its neighbours: the
    # fans there do not wind once around their vertex
    g, F = igl.triangulated_grid(6, 6)
    V = np.column_stack([g, np.zeros(len(g))])
    F = F.astype(np.int64)
    sep = gi._separated_fans(gi._FaceData(gi._normalized(V, F), F))
    inner = (g > 0.01).all(axis=1) & (g < 0.99).all(axis=1)
    assert sep[inner].all() and not sep[~inner].any()      # boundary: open fans
    V[14, :2] += [0.5, 0.1]
    sep = gi._separated_fans(gi._FaceData(gi._normalized(V, F), F))
    assert not sep[14]
    out = self_intersecting_pairs(V, F)
    assert out.shape[0] > 0
    assert np.array_equal(out, brute_force(V, F))
    # flipped face (inconsistent orientation) and an open boundary: not certified
    V, F = icosphere(2)
    F2 = F.copy()
    F2[0] = F2[0][::-1]
    sep = gi._separated_fans(gi._FaceData(gi._normalized(V, F2), F2))
    assert not sep[F2[0]].any()
    sep = gi._separated_fans(gi._FaceData(gi._normalized(V, F[1:]), F[1:]))
    assert not sep[F[0]].any()


@pytest.mark.parametrize("seed", range(4))
def test_folded_and_thin_fans_match_brute_force(seed):
    # a jittered flat grid with some vertices pushed across neighbours, and
    # some nearly degenerate slivers: fans fail the bound or fold
    rng = np.random.default_rng(seed)
    g, F = igl.triangulated_grid(14, 14)
    g = g + rng.normal(scale=0.01, size=g.shape)
    z = rng.normal(scale=0.02, size=len(g)) * (seed % 2)
    V = np.column_stack([g, z])
    k = rng.choice(len(V), 6, replace=False)
    V[k[:3], :2] += rng.normal(scale=0.08, size=(3, 2))          # folds
    V[k[3:], :2] = V[k[3:] + 1, :2] + 1e-9                       # slivers
    F = F.astype(np.int64)
    out = self_intersecting_pairs(V, F)
    assert np.array_equal(out, brute_force(V, F))


# ---------------------------------------------------------------------------
# pairs touching a subset of faces


def _touching_reference(V, F, faces):
    full = self_intersecting_pairs(V, F)
    keep = np.zeros(len(F), dtype=bool)
    keep[np.asarray(faces, dtype=np.int64)] = True
    return full[keep[full[:, 0]] | keep[full[:, 1]]]


def _bumpy_torus(seed, amplitude):
    """A fine torus with jittered vertices: folds and crossings for large amplitudes."""
    V, F = torus(60, 24)
    return V + amplitude * np.random.default_rng(seed).normal(size=V.shape), F


@pytest.mark.parametrize("jit", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_touching_pairs_equal_the_filtered_full_search(seed, jit, monkeypatch):
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0 if jit else 10 ** 12)
    rng = np.random.default_rng(seed)
    cases = [_bumpy_torus(seed, 0.06), _bumpy_torus(seed, 0.005), two_spheres(level=3)[:2],
             random_soup(seed, m=300, sizes=(0.002, 0.8)), spread_clusters(seed)]
    V, F = _bumpy_torus(seed, 0.06)
    assert len(self_intersecting_pairs(V, F)) > 0          # the folded torus crosses itself
    for V, F in cases:
        for size in (1, 17, len(F) // 3):
            faces = rng.choice(len(F), size, replace=False)
            got = gi.self_intersecting_pairs_touching(V, F, faces)
            assert got.dtype == np.int64 and got.shape[1] == 2
            assert np.array_equal(got, _touching_reference(V, F, faces))
        every = gi.self_intersecting_pairs_touching(V, F, np.arange(len(F)))
        assert np.array_equal(every, self_intersecting_pairs(V, F))


def test_touching_pairs_with_large_faces_and_duplicates():
    # huge faces of a higher level than the chosen ones, and a duplicated face (full search)
    V, F = icosphere(4)
    big = np.array([[-3, -3, 0.1], [3, -3, 0.2], [0, 4, -0.1]])
    V2 = np.concatenate([V, big])
    F2 = np.concatenate([F, [[len(V), len(V) + 1, len(V) + 2]]])
    chosen = np.flatnonzero(np.abs(V2[F2].mean(axis=1)[:, 2]) < 0.2)[:40]
    got = gi.self_intersecting_pairs_touching(V2, F2, chosen)
    assert len(got) > 0 and np.array_equal(got, _touching_reference(V2, F2, chosen))
    F3 = np.concatenate([F2, F2[chosen[:2]][:, ::-1]])
    got = gi.self_intersecting_pairs_touching(V2, F3, chosen)
    assert np.array_equal(got, _touching_reference(V2, F3, chosen))
    assert gi.self_intersecting_pairs_touching(V2, F2, []).shape == (0, 2)
    with pytest.raises(InputError):
        gi.self_intersecting_pairs_touching(V2, F2, [len(F2)])


@pytest.mark.parametrize("jit", [True, False])
def test_a_given_box_normalises_like_a_mesh_of_that_box(jit, monkeypatch):
    # box=: the coordinates normalised by that box, as if the mesh reached its
    # corners; the touching search with the same box gives rows of that answer
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0 if jit else 10 ** 12)
    V, F = _bumpy_torus(1, 0.06)
    lo, hi = V.min(axis=0), V.max(axis=0)
    assert np.array_equal(self_intersecting_pairs(V, F, box=[lo, hi]),
                          self_intersecting_pairs(V, F))
    box = np.stack([lo - [0.3, 0.1, 0.5], hi + [0.2, 0.7, 0.1]])
    # the same box made by two far corners on a degenerate face of their own
    n = len(V)
    V2 = np.concatenate([V, box])
    F2 = np.concatenate([F, [[n, n, n + 1]]])
    want = self_intersecting_pairs(V2, F2)
    got = self_intersecting_pairs(V, F, box=box)
    assert len(got) > 0 and np.array_equal(got, want)
    faces = np.random.default_rng(4).choice(len(F), 40, replace=False)
    keep = np.zeros(len(F), dtype=bool)
    keep[faces] = True
    assert np.array_equal(gi.self_intersecting_pairs_touching(V, F, faces, box=box),
                          got[keep[got[:, 0]] | keep[got[:, 1]]])
    for bad in ([lo + 0.01, hi], [hi, lo], [[0, 0, 0]], [lo, hi + np.inf]):
        with pytest.raises(InputError, match="box"):
            self_intersecting_pairs(V, F, box=bad)
        with pytest.raises(InputError, match="box"):
            gi.self_intersecting_pairs_touching(V, F, faces, box=bad)


def test_offset_surface_pairs_are_the_stacked_search_by_the_grown_box():
    V, F = _bumpy_torus(2, 0.005)
    D = np.zeros_like(V)
    D[:, 2] = 1.0
    h = 0.2
    Vs, pairs, box = gi.offset_surface_pairs(V, F, D, h)
    np.testing.assert_array_equal(box, [V.min(axis=0) - h, V.max(axis=0) + h])
    FF = np.concatenate([F, F[:, ::-1] + len(V)])
    assert len(pairs) > 0 and np.array_equal(Vs, np.concatenate([V, V + h * D]))
    np.testing.assert_array_equal(pairs, self_intersecting_pairs(Vs, FF, box=box))
    for args in ((D[1:], h), (D, np.nan), (np.where(D > 0, np.inf, D), h)):
        with pytest.raises(InputError):
            gi.offset_surface_pairs(V, F, *args)
    with pytest.raises(InputError, match="box"):
        gi.offset_surface_pairs(V, F, D, h, box=[[0, 0, 0]])


def test_distinct_faces_hint_skips_only_the_grouping():
    for V, F in (_bumpy_torus(0, 0.06), two_spheres(level=3)[:2], random_soup(2, m=300, pool=80)):
        from geotex.mesh.topology import duplicate_face_groups

        assert duplicate_face_groups(F).size == 0
        assert np.array_equal(self_intersecting_pairs(V, F, distinct_faces=True),
                              self_intersecting_pairs(V, F))


# parts=: the sweep by parts gives the grid's answer


def _parts_cases():
    """(V, F, parts) meshes of many small parts: overlapping and touching
    spheres, a folded sphere, a chain of cubes sharing faces, duplicates."""
    from geotex.mesh.primitives import box as cube
    from geotex.mesh.topology import concatenated, face_components

    rng = np.random.default_rng(13)
    Vs, Fs = icosphere(1)
    cases = []
    for _ in range(3):                        # spheres, some overlapping
        centres = rng.uniform(0.0, 3.0, size=(25, 3))
        radii = rng.uniform(0.2, 0.6, size=25)
        V, F = concatenated([(Vs * r + c, Fs) for c, r in zip(centres, radii)])
        cases.append((V, F))
    # a sphere folded onto itself (one vertex pushed through the far side),
    # touching one neighbour exactly at a vertex
    Vf = Vs.copy()
    top = int(np.argmax(Vf[:, 2]))
    Vf[top] = (0.0, 0.0, -1.3)
    lo, hi = Vs[int(np.argmin(Vs[:, 2]))], Vs[int(np.argmax(Vs[:, 2]))]
    Vt = Vs + (hi - lo)                       # its lowest vertex on the other's highest
    cases.append(concatenated([(Vf, Fs), (Vs + (3.0, 0.0, 0.0), Fs), (Vt + (3.0, 0, 0), Fs)]))
    # a chain of unit cubes sharing faces (coplanar overlaps), unwelded
    cases.append(concatenated([cube((k, 0.0, 0.0), (k + 1.0, 1.0, 1.0), divisions=2)
                               for k in range(6)]))
    out = [(V, F, face_components(F, V.shape[0])[1]) for V, F in cases]
    # the same spheres with arbitrary parts (not components) and a duplicated face
    V, F = cases[0]
    Fd = np.vstack([F, F[5:6, ::-1]])
    out.append((V, Fd, rng.integers(0, 40, size=len(Fd))))
    return out


@pytest.mark.parametrize("case", range(6))
def test_parts_sweep_gives_the_grid_answer(case, monkeypatch):
    V, F, parts = _parts_cases()[case]
    reference = self_intersecting_pairs(V, F)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)         # the sweep is compiled only
    calls = []
    real = gi._part_loops

    def spy(*args):
        calls.append(1)
        return real(*args)

    monkeypatch.setattr(gi, "_part_loops", spy)
    got = self_intersecting_pairs(V, F, parts=parts)
    assert calls                                           # the sweep answered
    assert np.array_equal(got, reference)
    assert reference.size                                  # every case has contacts


@pytest.mark.parametrize("piece", [65_536, 7])
def test_parts_sweep_gives_the_grid_answer_on_random_soup(monkeypatch, piece):
    # piece=7: the parts' sort and boxes split in pieces on the pool
    monkeypatch.setattr(gi, "_GRID_PIECE", piece)
    rng = np.random.default_rng(5)
    V = rng.uniform(0.0, 1.0, size=(120, 3))
    F = rng.integers(0, 120, size=(200, 3))
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    reference = self_intersecting_pairs(V, F)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)
    for n_parts in (1, 7, len(F)):
        parts = rng.integers(0, n_parts, size=len(F))
        assert np.array_equal(self_intersecting_pairs(V, F, parts=parts), reference)


def _spied(monkeypatch, name):
    """Calls of ``gi.<name>`` counted in the returned list."""
    calls = []
    real = getattr(gi, name)

    def spy(*args, **kw):
        calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(gi, name, spy)
    return calls


@pytest.mark.parametrize("run", [1, 7, 64])
def test_parts_too_large_are_swept_in_runs(monkeypatch, run):
    V, F = icosphere(2)
    W = V + 0.3
    V2, F2 = np.vstack([V, W]), np.vstack([F, F + len(V)])
    reference = self_intersecting_pairs(V2, F2)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)
    monkeypatch.setattr(gi, "_PART_MAX_FACES", 100)
    monkeypatch.setattr(gi, "_PART_RUN", run)
    runs, sweeps = _spied(monkeypatch, "_runs_of_large_parts"), _spied(monkeypatch, "_part_loops")
    got = self_intersecting_pairs(V2, F2, parts=np.repeat([0, 1], len(F)))
    assert runs and sweeps and np.array_equal(got, reference) and reference.size


@pytest.mark.parametrize("jit", [True, False])
@pytest.mark.parametrize("case", range(6))
def test_pairs_between_sides_are_the_filtered_full_search(case, jit, monkeypatch):
    V, F, parts = _parts_cases()[case]
    reference = self_intersecting_pairs(V, F)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0 if jit else 10 ** 12)   # the reference's path
    rng = np.random.default_rng(case)
    n = int(parts.max()) + 1
    side_of = np.arange(n) % 3
    within_of = rng.random(n) < 0.4
    side, within = side_of[parts], within_of[parts]
    i, j = reference[:, 0], reference[:, 1]
    cross = side[i] != side[j]
    own = (parts[i] == parts[j]) & within[i]
    for serial in (0, 10 ** 6):                      # on the pool, and in this thread
        monkeypatch.setattr(gi, "_SERIAL_FACES", serial)
        got = gi.self_intersecting_pairs_between(V, F, parts, side=side)
        assert got.dtype == np.int64 and np.array_equal(got, reference[cross])
        got = gi.self_intersecting_pairs_between(V, F, parts, side=side, within=within)
        assert np.array_equal(got, reference[cross | own])
        # one part, every pair within it: the whole test
        one = np.zeros(len(F), dtype=np.int64)
        got = gi.self_intersecting_pairs_between(V, F, one, within=np.ones(len(F), bool))
        assert np.array_equal(got, reference)
        assert gi.self_intersecting_pairs_between(V, F, one).shape == (0, 2)
    assert reference[cross].size                     # the cases meet across sides


def test_per_face_data_compiled_equal_numpy_bit_for_bit():
    # self_intersecting_pairs_between takes the compiled per-face data at any size
    rng = np.random.default_rng(4)
    V, F = random_soup(3, m=400, sizes=(0.001, 0.9))
    Vd = rng.normal(size=(300, 3)) * 1e3
    Fd = rng.integers(0, 300, size=(800, 3))
    Fd[:40, 1] = Fd[:40, 0]                          # degenerate rows too
    for V, F in (icosphere(3), torus(40, 17), (V, F), (Vd, Fd)):
        Vn = gi._normalized(V, F)
        a = gi._FaceData(Vn, F, compiled=False)
        b = gi._FaceData(Vn, F, compiled=True)
        for name in ("plane", "tol", "E", "box32", "active"):
            assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name


def test_pairs_between_parts_too_large_are_swept_in_runs(monkeypatch):
    V, F = icosphere(2)
    V2, F2 = np.vstack([V, V + 0.3]), np.vstack([F, F + len(V)])
    parts = np.repeat([0, 1], len(F))
    reference = self_intersecting_pairs(V2, F2)
    monkeypatch.setattr(gi, "_PART_MAX_FACES", 100)
    monkeypatch.setattr(gi, "_PART_RUN", 16)
    monkeypatch.setattr(gi, "self_intersecting_pairs", None)     # no full search
    runs = _spied(monkeypatch, "_runs_of_large_parts")
    cross = parts[reference[:, 0]] != parts[reference[:, 1]]
    got = gi.self_intersecting_pairs_between(V2, F2, parts, side=parts)
    assert runs and np.array_equal(got, reference[cross]) and got.size
    # one part marked within: the whole answer, pairs of its runs included
    one = np.zeros(len(F2), dtype=np.int64)
    got = gi.self_intersecting_pairs_between(V2, F2, one, within=np.ones(len(F2), bool))
    assert np.array_equal(got, reference)


def _run_cases():
    """Meshes with every kind of contact, for the runs of large parts: random
    soups (general position, and on few shared vertices), coplanar overlapping
    grids, spheres crossing and touching, and degenerate faces."""
    rng = np.random.default_rng(21)
    cases = [random_soup(31, m=600), random_soup(32, m=500, pool=60),
             random_soup(33, m=400, sizes=(0.001, 0.9))]
    # coplanar: two grids in one plane, one shifted and turned a little; a third
    # sharing the first grid's vertices along its edge (an unwelded seam)
    Vg, Fg = primitives.grid_plane(12, 9)
    c, s_ = np.cos(0.3), np.sin(0.3)
    Vr = Vg @ np.array([[c, s_, 0.0], [-s_, c, 0.0], [0.0, 0.0, 1.0]]) + (0.31, 0.17, 0.0)
    V = np.vstack([Vg, Vr, Vg + (1.0, 0.0, 0.0)])
    n = len(Vg)
    F = np.vstack([Fg, Fg + n, Fg + 2 * n])
    cases.append((V, F))
    # spheres crossing, touching at a vertex, and faces sharing vertices of both
    V1, F1 = icosphere(2)
    top = V1[int(np.argmax(V1[:, 2]))]
    V2 = V1 - V1[int(np.argmin(V1[:, 2]))] + top            # lowest on the other's highest
    V, F = np.vstack([V1, V2 + (0.0, 0.0, 0.0), V1 + (0.7, 0.2, 0.1)]), np.vstack(
        [F1, F1 + len(V1), F1 + 2 * len(V1)])
    mixed = rng.integers(0, len(V), size=(60, 3))             # across the spheres
    mixed = mixed[(mixed[:, 0] != mixed[:, 1]) & (mixed[:, 1] != mixed[:, 2])
                  & (mixed[:, 0] != mixed[:, 2])]
    cases.append((V, np.vstack([F, mixed])))
    # degenerate faces (a repeated index, three collinear points) among a soup
    V, F = random_soup(34, m=300)
    V = np.vstack([V, [[0.2, 0.2, 0.2], [0.4, 0.4, 0.4], [0.6, 0.6, 0.6]]])
    k = len(V) - 3
    F = np.vstack([F, [[k, k + 1, k + 2], [0, 0, 5], [k, 7, 7]]])
    cases.append((V, F))
    return cases


@pytest.mark.parametrize("case", range(6))
def test_runs_of_large_parts_give_the_filtered_full_search(case, monkeypatch):
    # parts cut into runs find the pairs of the plain path (the full search,
    # filtered) on every kind of contact, for any run length and any parts
    V, F = _run_cases()[case]
    reference = self_intersecting_pairs(V, F)
    assert reference.size
    m = len(F)
    rng = np.random.default_rng(100 + case)
    monkeypatch.setattr(gi, "_PART_MAX_FACES", 40)
    numpy_size = gi.JIT_MIN_SIZE
    runs = _spied(monkeypatch, "_runs_of_large_parts")
    i, j = reference[:, 0], reference[:, 1]
    layouts = [np.zeros(m, dtype=np.int64),                        # one part
               rng.integers(0, 3, size=m),                        # three large, interleaved
               np.where(rng.random(m) < 0.5, 0, rng.integers(1, 200, size=m))]  # large + small
    for run in (1, 5, 32):
        monkeypatch.setattr(gi, "_PART_RUN", run)
        for parts in layouts:
            n = int(parts.max()) + 1
            side, within = (rng.integers(0, 2, size=n)[parts], (rng.random(n) < 0.5)[parts])
            got = gi.self_intersecting_pairs_between(V, F, parts, side=side, within=within)
            keep = (side[i] != side[j]) | ((parts[i] == parts[j]) & within[i])
            assert np.array_equal(got, reference[keep])
            got = gi.self_intersecting_pairs_between(V, F, parts, within=np.ones(m, bool))
            assert np.array_equal(got, reference[parts[i] == parts[j]])
            monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)           # the full search's sweep
            got = self_intersecting_pairs(V, F, parts=parts)
            monkeypatch.setattr(gi, "JIT_MIN_SIZE", numpy_size)
            assert np.array_equal(got, reference)
    assert runs


def test_runs_of_large_parts_are_compact_patches(monkeypatch):
    # a large part is cut in Morton order, not in face order: each run's box is
    # far smaller than the part's (faces shuffled), and the runs partition its faces
    V, F = torus(60, 30)
    F = F[np.random.default_rng(3).permutation(len(F))]
    m = len(F)
    monkeypatch.setattr(gi, "_PART_RUN", 64)
    monkeypatch.setattr(gi, "_PART_MAX_FACES", 100)
    faces = gi._FaceData(gi._normalized(V, F), F, compiled=True)
    act = faces.active
    part = np.r_[np.zeros(m - 10, np.int64), np.arange(1, 11)]   # one large part, ten small
    count = np.bincount(part)
    sub, first, cnt, origin = gi._runs_of_large_parts(faces.box32, act, part, count)
    assert cnt.sum() == act.size and np.array_equal(np.bincount(sub), cnt)
    assert np.all(cnt[origin == 0] <= 64) and np.array_equal(cnt[origin > 0], np.ones(10))
    assert np.array_equal(origin, np.r_[np.zeros(origin.size - 10, np.int64), np.arange(1, 11)])
    assert np.array_equal(origin[sub], part)
    box = faces.box32[act]
    whole = box[part == 0]
    span = (whole[:, 3:].max(axis=0) - whole[:, :3].min(axis=0)).max()
    spans = [(box[sub == r][:, 3:].max(axis=0) - box[sub == r][:, :3].min(axis=0)).max()
             for r in np.flatnonzero(origin == 0)]
    assert np.median(spans) < 0.5 * span


@pytest.mark.parametrize("bad", [dict(parts=np.zeros(3, int)), dict(side=np.zeros(3)),
                                 dict(within=np.zeros(4, int))])
def test_pairs_between_need_one_value_per_face(bad):
    V, F = icosphere(0)
    args = dict(parts=np.zeros(len(F), int), side=np.zeros(len(F), int),
                within=np.zeros(len(F), bool))
    args.update({k: np.resize(v, len(F) if k == "within" else len(v)) for k, v in bad.items()})
    with pytest.raises(InputError):
        gi.self_intersecting_pairs_between(V, F, args.pop("parts"), **args)


@pytest.mark.parametrize("parts", [np.zeros(3, int), np.zeros((4, 1), int), np.zeros(4)])
def test_parts_must_be_one_integer_per_face(parts):
    V, F = icosphere(0)
    with pytest.raises(InputError):
        self_intersecting_pairs(V, F[:4], parts=parts)


def test_parts_sweep_with_max_pairs_gives_a_subset(monkeypatch):
    V, F, parts = _parts_cases()[0]
    full = self_intersecting_pairs(V, F)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)
    got = self_intersecting_pairs(V, F, parts=parts, max_pairs=3)
    assert len(got) == 3 and np.array_equal(got, full[:3])


@pytest.mark.parametrize("occ_cells", [0, 1 << 28])
def test_compiled_level_grid_matches_brute_force(monkeypatch, occ_cells):
    # several levels on the compiled grid: the smaller faces' entries filtered
    # through the bit per cell, or (occ_cells=0) by binary search
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)
    monkeypatch.setattr(gi, "_OCC_CELLS", occ_cells)
    calls = []
    grid = gi._level_grid

    def spy(*args, **kw):
        out = grid(*args, **kw)
        calls.append((bool(out[0]), args[3].size))
        return out

    monkeypatch.setattr(gi, "_level_grid", spy)
    for seed in range(3):
        Vs, Fs = random_soup(seed, m=400, sizes=(0.002, 0.01))
        Vb, Fb = random_soup(seed + 100, m=30, sizes=(0.01, 1.0))
        V = np.concatenate([Vs, Vb])
        F = np.concatenate([Fs, Fb + len(Vs)])
        out = self_intersecting_pairs(V, F)
        assert out.shape[0] > 0
        assert np.array_equal(out, brute_force(V, F))
    assert all(ok for ok, _ in calls) and sum(n > 0 for _, n in calls) >= 3


def test_compiled_level_grid_gives_the_numpy_pairs_on_an_overlapping_solid(monkeypatch):
    # two interpenetrating copies of a torus, shifted and scaled: many hits on the
    # compiled grid, the same pairs as the numpy grid (and max_pairs a subset of them)
    V, F = torus(60, 24)
    V2 = np.vstack([V, V * 1.01 + [0.05, 0.02, 0.01]])
    F2 = np.vstack([F, F + len(V)])
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 10 ** 12)
    slow = self_intersecting_pairs(V2, F2)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)
    monkeypatch.setattr(gi, "_PAIR_CHUNK", 500)
    fast = self_intersecting_pairs(V2, F2)
    assert slow.shape[0] > 100 and np.array_equal(fast, slow)
    part = self_intersecting_pairs(V2, F2, max_pairs=50)
    assert 1 <= part.shape[0] <= 50 and as_set(part) <= as_set(slow)


@pytest.mark.parametrize("big", [False, True])
def test_unpaired_vertices_given_or_computed_same_pairs(big, monkeypatch):
    # an open, crossing mesh: a pierced sphere with a hole, on both paths
    from geotex.mesh.topology import edge_topology, unpaired_edge_vertices

    if big:
        monkeypatch.setattr(gi, "JIT_MIN_SIZE", 1)
    V, F, _ = two_spheres()
    F = F[1:]
    want = self_intersecting_pairs(V, F)
    assert want.shape[0] > 0
    un = unpaired_edge_vertices(edge_topology(F, len(V)), len(V))
    assert un.any()
    got = self_intersecting_pairs(V, F, unpaired_vertices=un, distinct_faces=True)
    assert np.array_equal(got, want)
    with pytest.raises(InputError):
        self_intersecting_pairs(V, F, unpaired_vertices=un[1:])
    with pytest.raises(InputError):
        self_intersecting_pairs(V, F, unpaired_vertices=un.astype(np.int64))


@pytest.mark.parametrize("occ_cells", [0, 1 << 28])
def test_level_grid_in_pieces_is_the_grid_in_one_piece(monkeypatch, occ_cells):
    # pieces of a few hundred items: the extent, entries, smaller faces, radix
    # passes and rows each split on the pool give the one-piece arrays bit for bit
    from concurrent.futures import ThreadPoolExecutor

    monkeypatch.setattr(gi, "_GRID_PIECE", 200)
    Vs, Fs = random_soup(5, m=1500, sizes=(0.002, 0.01))
    Vb, Fb = random_soup(105, m=200, sizes=(0.01, 1.0))
    V = np.concatenate([Vs, Vb])
    F = np.concatenate([Fs, Fb + len(Vs)])
    faces = gi._FaceData(gi._normalized(V, F), F)
    cell0, level = gi._grid_levels(faces)
    act = faces.active
    row_bits = max(1, int(act.size - 1).bit_length())
    assert np.unique(level).size >= 3
    with ThreadPoolExecutor(max_workers=3) as pool:
        for lev in np.unique(level):
            cur = np.flatnonzero(level == lev)
            low = gi._near(faces, cur, np.flatnonzero(level < lev))
            args = (faces.box32, act, cur, low, cell0 * 2.0 ** lev, row_bits, gi._KEY_BITS,
                    50, occ_cells)
            one = gi._level_grid(*args)
            assert one[0] and one[1].size > 0
            for split in (2, 3, 5):
                got = gi._level_grid(*args, mapper=pool.map, split=split)
                assert got[0]
                for a, b in zip(one[1:], got[1:]):
                    assert a.dtype == b.dtype and np.array_equal(a, b)


def test_compiled_normal_sums_are_the_bincount_sums():
    # the vertex normal sums of the compiled fan stage, in any split of the
    # vertices: np.bincount's per-column sums added to 0 in column order, bit
    # for bit (signed zeros and degenerate faces' zero rows included)
    rng = np.random.default_rng(7)
    n, m = 300, 4000
    F = rng.integers(0, n, size=(m, 3))
    plane = rng.normal(size=(m, 4)) * 10.0 ** rng.integers(-8, 8, size=(m, 1))
    plane[::7] = 0.0
    plane[::11, :3] = -0.0
    want = [sum(np.bincount(F[:, k], weights=np.ascontiguousarray(plane[:, a]), minlength=n)
                for k in range(3)) for a in range(3)]
    want_count = sum(np.bincount(F[:, k], minlength=n) for k in range(3))
    for cuts in ([0, n], [0, 1, 150, 299, n]):
        N = np.full((3, n), np.nan)
        count = np.full(n, -1, np.int64)
        for v0, v1 in zip(cuts[:-1], cuts[1:]):
            gi._normal_sums(F, plane, v0, v1, N, count)
        assert np.array_equal(count, want_count)
        for a in range(3):
            assert np.array_equal(N[a].view(np.int64), want[a].view(np.int64))
