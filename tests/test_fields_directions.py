"""Tangent direction fields: frames, projected / principal / smooth / RBF fields,
singularities and combing."""

from __future__ import annotations

from fractions import Fraction

import igl
import numpy as np
import pytest

from geotex.errors import InputError
from geotex.fields.combing import comb_direction_field, combed_vectors
from geotex.fields.directions import (Constraint, DirectionField, principal_direction_field,
                                      projected_direction_field, smooth_direction_field)
from geotex.fields.frames import (face_connection, face_frames, tangent_angles,
                                  vectors_from_angles, wrap_angle)
from geotex.fields.rbf import KERNELS, rbf_direction_field, surface_distances
from geotex.fields.singularities import index_sum, singularities, vertex_indices
from geotex.mesh.primitives import box, grid_plane, icosphere, torus
from geotex.mesh.solid import arrays_of_manifold, manifold_of


# --------------------------------------------------------------------------- meshes

@pytest.fixture(scope="module")
def sphere():
    return icosphere(3)


@pytest.fixture(scope="module")
def ring():
    return torus(1.0, 0.35, n_major=48, n_minor=24)


@pytest.fixture(scope="module")
def genus2():
    V1, F1 = torus(1.0, 0.35, n_major=48, n_minor=16)
    solid = manifold_of(V1, F1) + manifold_of(V1 + np.array([1.6, 0.0, 0.0]), F1)
    V, F = arrays_of_manifold(solid)
    assert V.shape[0] - F.shape[0] // 2 == -2           # chi = V - E + F = V - F / 2
    return V, F


@pytest.fixture(scope="module")
def plane():
    return grid_plane(8, 6, size=(2.0, 1.5))


def _rotation(seed=3):
    q, r = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def _angle_between(a, b):
    """Unsigned angle between rows of a and b, (k,)."""
    c = np.einsum("ij,ij->i", a, b)
    s = np.linalg.norm(np.cross(a, b), axis=1)
    return np.arctan2(s, c)


def _euler(V, F):
    E = igl.edges(F).shape[0]
    return V.shape[0] - E + F.shape[0]


# --------------------------------------------------------------------------- frames

@pytest.mark.parametrize("mesh", ["sphere", "ring", "genus2"])
def test_frames_orthonormal_right_handed_along_first_edge(mesh, request):
    V, F = request.getfixturevalue(mesh)
    T1, T2, N = face_frames(V, F)
    for X in (T1, T2, N):
        np.testing.assert_allclose(np.linalg.norm(X, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("ij,ij->i", T1, T2), 0.0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("ij,ij->i", T1, N), 0.0, atol=1e-14)
    np.testing.assert_allclose(np.cross(T1, T2), N, atol=1e-14)
    e = V[F[:, 1]] - V[F[:, 0]]
    np.testing.assert_allclose(T1, e / np.linalg.norm(e, axis=1, keepdims=True), atol=1e-15)
    n = np.cross(e, V[F[:, 2]] - V[F[:, 0]])
    np.testing.assert_allclose(N, n / np.linalg.norm(n, axis=1, keepdims=True), atol=1e-14)


def test_frames_reject_degenerate_face_with_its_index(sphere):
    V, F = sphere
    F = F.copy()
    F[7] = [F[7, 0], F[7, 0], F[7, 1]]
    with pytest.raises(InputError, match=r"degenerate .*first at face 7"):
        face_frames(V, F)
    V2 = np.vstack([V, V[0], V[0] + [1e-20, 0, 0], V[0] + [2e-20, 0, 0]])
    F2 = np.vstack([F[:7], sphere[1][7:], [[len(V), len(V) + 1, len(V) + 2]]])
    with pytest.raises(InputError, match=f"first at face {len(F2) - 1}"):
        face_frames(V2, F2)


def test_frames_do_not_modify_inputs(sphere):
    V, F = sphere
    V0, F0 = V.copy(), F.copy()
    face_frames(V, F)
    smooth_direction_field(V, F, symmetry=2, constraints=[{"face": 0, "direction": [1, 0, 0]}])
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


def test_connection_is_flat_on_a_plane_and_holonomy_is_the_angle_defect(plane, sphere):
    conn = face_connection(*plane)
    f, g = conn.faces.T
    # on a plane, transport is the identity in space: T1 of f lands on itself in g
    moved = vectors_from_angles(conn.T1[g], conn.T2[g], conn.angle)
    np.testing.assert_allclose(moved, conn.T1[f], atol=1e-15)
    # holonomy around every vertex of the sphere equals its angle defect (mod 2 pi)
    V, F = sphere
    conn = face_connection(V, F)
    n = V.shape[0]
    hol = (np.bincount(conn.vertices[:, 1], conn.angle, n)
           - np.bincount(conn.vertices[:, 0], conn.angle, n))
    defect = 2 * np.pi - np.bincount(F.ravel(), igl.internal_angles(V, F).ravel(), n)
    np.testing.assert_allclose(wrap_angle(hol - defect), 0.0, atol=1e-12)


def test_inconsistent_orientation_is_rejected(sphere):
    V, F = sphere
    F = F.copy()
    F[3] = F[3, ::-1]
    with pytest.raises(InputError, match="not consistently oriented"):
        smooth_direction_field(V, F)


# --------------------------------------------------------------------------- projected

def test_projected_constant_direction_on_plane_is_exact(plane):
    V, F = plane
    vec, undefined = projected_direction_field(V, F, [0.0, 1.0, 5.0])
    assert not undefined.any()
    assert np.array_equal(vec, np.tile([0.0, 1.0, 0.0], (F.shape[0], 1)))
    d = np.array([3.0, -4.0, 0.0])
    vec, _ = projected_direction_field(V, F, d)
    np.testing.assert_allclose(vec, np.tile(d / 5.0, (F.shape[0], 1)), rtol=0, atol=1e-16)


def test_projected_fills_normal_faces_from_neighbours():
    V, F = box(divisions=3)
    vec, undefined = projected_direction_field(V, F, [0.0, 0.0, 1.0])
    T1, T2, N = face_frames(V, F)
    assert np.array_equal(undefined, np.abs(N[:, 2]) > 0.5)      # top and bottom
    np.testing.assert_allclose(np.linalg.norm(vec, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("ij,ij->i", vec, N), 0.0, atol=1e-12)
    side = ~undefined
    np.testing.assert_allclose(vec[side], np.tile([0, 0, 1.0], (side.sum(), 1)), atol=1e-15)
    assert index_sum(V, F, vec) == 2


def test_projected_up_on_sphere_has_two_poles(sphere):
    V, F = sphere
    vec, undefined = projected_direction_field(V, F, [0, 0, 1])
    sing = singularities(V, F, vec)
    assert [i for _, i in sing] == [1.0, 1.0]
    poles = V[[v for v, _ in sing]]
    np.testing.assert_allclose(np.abs(poles[:, 2]), 1.0, atol=1e-12)


def test_projected_rotation_and_scale_invariance(ring):
    V, F = ring
    R = _rotation()
    d = np.array([0.3, -0.5, 0.8])
    vec, _ = projected_direction_field(V, F, d)
    rot, _ = projected_direction_field(V @ R.T, F, R @ d)
    np.testing.assert_allclose(rot, vec @ R.T, atol=1e-12)
    for s in (1e-3, 1e3):
        sc, _ = projected_direction_field(V * s, F, d)
        np.testing.assert_allclose(sc, vec, atol=1e-12)


def test_projected_errors(plane):
    V, F = plane
    with pytest.raises(InputError, match="direction is zero"):
        projected_direction_field(V, F, [0, 0, 0])
    with pytest.raises(InputError, match="finite"):
        projected_direction_field(V, F, [np.nan, 0, 1])
    with pytest.raises(InputError, match="shape"):
        projected_direction_field(V, F, [1, 0])


# --------------------------------------------------------------------------- principal

def test_principal_directions_on_torus(ring):
    V, F = ring
    pd = principal_direction_field(V, F, radius=2)
    C = V[F].mean(axis=1)
    phi = np.arctan2(C[:, 1], C[:, 0])
    toroidal = np.stack([-np.sin(phi), np.cos(phi), 0 * phi], axis=1)
    # maximal curvature runs around the tube (the minor circle), minimal along the ring
    assert np.abs(np.einsum("ij,ij->i", pd.directions, toroidal)).max() < 0.1
    mn = principal_direction_field(V, F, which="min", radius=2)
    assert np.abs(np.einsum("ij,ij->i", mn.directions, toroidal)).min() > 0.99
    np.testing.assert_allclose(np.einsum("ij,ij->i", mn.directions, pd.directions), 0, atol=1e-14)
    # k_max ~ 1 / minor radius everywhere; k_min ~ cos(v) / (R + r cos v)
    np.testing.assert_allclose(pd.k_max, 1 / 0.35, rtol=0.1)
    rho = np.hypot(C[:, 0], C[:, 1])
    cosv = (rho - 1.0) / 0.35
    np.testing.assert_allclose(pd.k_min, cosv / (1.0 + 0.35 * cosv), atol=0.1)
    assert np.all(pd.k_max >= pd.k_min) and pd.coherence.min() > 0.9


def test_principal_directions_are_line_fields_and_invariant(ring):
    V, F = ring
    V = V * np.array([1.0, 1.3, 0.8])                  # break the rotational symmetry
    pd = principal_direction_field(V, F)
    assert singularities(V, F, pd.directions, symmetry=2) == []
    R = _rotation(5)
    rot = principal_direction_field(V @ R.T, F)
    good = pd.coherence > 0.9
    assert good.mean() > 0.9
    dots = np.abs(np.einsum("ij,ij->i", rot.directions, pd.directions @ R.T))
    assert dots[good].min() > 1 - 1e-6
    np.testing.assert_allclose(rot.k_max, pd.k_max, rtol=1e-6, atol=1e-9)
    for s in (1e-3, 1e3):
        sc = principal_direction_field(V * s, F)
        dots = np.abs(np.einsum("ij,ij->i", sc.directions, pd.directions))
        assert dots[good].min() > 1 - 1e-6
        np.testing.assert_allclose(sc.k_max * s, pd.k_max, rtol=1e-6, atol=1e-9)


def test_principal_errors(ring):
    with pytest.raises(InputError, match="which"):
        principal_direction_field(*ring, which="mean")
    with pytest.raises(InputError, match="radius"):
        principal_direction_field(*ring, radius=1)


# --------------------------------------------------------------------------- smooth fields

@pytest.mark.parametrize("mesh, chi", [("sphere", 2), ("ring", 0), ("genus2", -2)])
def test_smoothest_vector_field_index_sum_is_euler_characteristic(mesh, chi, request):
    V, F = request.getfixturevalue(mesh)
    assert _euler(V, F) == chi
    field = smooth_direction_field(V, F)
    assert isinstance(field, DirectionField) and field.symmetry == 1
    total = index_sum(V, F, field)
    assert isinstance(total, Fraction) and total == chi
    assert sum(i for _, i in field.singularities) == chi
    assert field.index_sum == chi


@pytest.mark.parametrize("N", [2, 4])
@pytest.mark.parametrize("mesh, chi", [("sphere", 2), ("genus2", -2)])
def test_smoothest_n_field_has_fractional_indices_summing_to_chi(N, mesh, chi, request):
    V, F = request.getfixturevalue(mesh)
    field = smooth_direction_field(V, F, symmetry=N)
    assert field.symmetry == N
    idx = np.array([i for _, i in field.singularities])
    assert np.array_equal(idx * N, np.rint(idx * N))              # multiples of 1/N
    assert index_sum(V, F, field) == chi
    if mesh == "sphere":     # the smoothest field splits into 2N singularities of +1/N
        assert np.array_equal(idx, np.full(2 * N, 1.0 / N))


def test_indices_agree_with_libigl_for_cross_fields(sphere, ring):
    for V, F in (sphere, ring):
        field = smooth_direction_field(V, F, symmetry=4)
        PD2 = np.cross(field.normals, field.vectors)
        is_sing, k = igl.find_cross_field_singularities(V, F, field.vectors, PD2, False)
        mine = np.zeros(V.shape[0], dtype=np.int64)
        for v, i in field.singularities:
            mine[v] = round(4 * i)
        assert np.array_equal(np.flatnonzero(is_sing), np.flatnonzero(mine))
        assert np.array_equal(np.mod(mine, 4), np.mod(k, 4))


@pytest.mark.parametrize("N", [1, 2, 4])
def test_one_constraint_on_plane_gives_the_constant_field(plane, N):
    V, F = plane
    d = np.array([2.0, 1.0, 0.0]) / np.sqrt(5.0)
    field = smooth_direction_field(V, F, symmetry=N, constraints=[{"face": 17, "direction": d}])
    np.testing.assert_allclose(np.abs(field.values), 1.0, atol=1e-12)
    reps = field.representatives()                               # (m, N, 3)
    err = np.min(np.linalg.norm(reps - d, axis=2), axis=1)
    assert err.max() < 1e-12
    assert field.singularities == ()
    idx = vertex_indices(V, F, field)
    assert np.all(np.isnan(idx[[0, 6, 56, 62]])) and idx[8] == 0    # corners / interior
    assert np.isnan(idx).sum() == 2 * (8 + 6)                        # the boundary loop


def test_soft_constraint_on_plane_and_soft_averaging(plane):
    V, F = plane
    field = smooth_direction_field(V, F, constraints=[{"face": 3, "direction": [0, 1, 0]}],
                                   mode="soft")
    np.testing.assert_allclose(field.vectors, np.tile([0, 1.0, 0], (F.shape[0], 1)), atol=1e-12)
    both = [{"face": 3, "direction": [1, 0, 0]}, {"face": 3, "direction": [0, 1, 0]}]
    field = smooth_direction_field(V, F, constraints=both, mode="soft")
    np.testing.assert_allclose(field.vectors[3], np.sqrt([0.5, 0.5, 0.0]), atol=1e-12)


@pytest.mark.parametrize("N", [1, 2, 4])
def test_hard_constraints_are_reproduced(sphere, N):
    V, F = sphere
    cons = [Constraint(face=5, direction=(1.0, 0.2, -0.3)),
            {"face": 400, "direction": [0.0, 1.0, 0.0], "weight": 3.0},
            {"point": [0.0, 0.0, 1.0], "direction": [1.0, 1.0, 0.0]}]
    field = smooth_direction_field(V, F, symmetry=N, constraints=cons)
    sq, faces, _ = igl.point_mesh_squared_distance(np.array([[0.0, 0, 1]]), V, F)
    fc = [5, 400, int(faces[0])]
    assert np.array_equal(field.constrained, np.sort(fc))
    T1, T2, Nrm = face_frames(V, F)
    dirs = np.array([[1.0, 0.2, -0.3], [0, 1.0, 0], [1.0, 1.0, 0]])
    tang = dirs - np.einsum("ij,ij->i", dirs, Nrm[fc])[:, None] * Nrm[fc]
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    assert _angle_between(field.vectors[fc], tang).max() < 1e-8
    theta = tangent_angles(T1[fc], T2[fc], tang)
    assert np.abs(wrap_angle(np.angle(field.values[fc]) - N * theta)).max() < 1e-8
    assert index_sum(V, F, field) == 2


def test_smooth_field_rotation_and_scale_invariance(genus2):
    V, F = genus2
    cons = [{"face": 0, "direction": [1.0, 0.0, 0.0]}, {"face": 900, "direction": [0, 1.0, 0]}]
    ref = smooth_direction_field(V, F, symmetry=2, constraints=cons)
    R = _rotation(7)
    rcons = [{"face": c["face"], "direction": R @ np.array(c["direction"])} for c in cons]
    rot = smooth_direction_field(V @ R.T, F, symmetry=2, constraints=rcons)
    np.testing.assert_allclose(rot.values, ref.values, atol=1e-9)
    np.testing.assert_allclose(rot.vectors, ref.vectors @ R.T, atol=1e-9)
    for s in (1e-3, 1e3):
        sc = smooth_direction_field(V * s, F, symmetry=2, constraints=cons)
        np.testing.assert_allclose(sc.values, ref.values, atol=1e-9)
        assert sc.singularities == ref.singularities
    # the unconstrained field is intrinsic too
    a = smooth_direction_field(V, F, symmetry=4)
    b = smooth_direction_field(V * 1e3, F, symmetry=4)
    np.testing.assert_allclose(b.values, a.values, atol=1e-7)


def test_smooth_field_is_deterministic(ring):
    V, F = ring
    a = smooth_direction_field(V, F, symmetry=4)
    b = smooth_direction_field(V, F, symmetry=4)
    assert a.vectors.tobytes() == b.vectors.tobytes()
    assert a.values.tobytes() == b.values.tobytes()
    c = smooth_direction_field(V, F, seed=11)
    d = smooth_direction_field(V, F, seed=11)
    assert c.values.tobytes() == d.values.tobytes()
    cons = [{"face": 9, "direction": [0, 0, 1]}]
    e = smooth_direction_field(V, F, constraints=cons, seed=1)
    f = smooth_direction_field(V, F, constraints=cons, seed=2)      # seed unused here
    assert e.values.tobytes() == f.values.tobytes()


def test_smooth_field_energy_is_minimal(sphere):
    """The constrained solution beats random perturbations of its free values."""
    V, F = sphere
    cons = [{"face": 0, "direction": [1, 0, 0]}, {"face": 700, "direction": [0, 1, 0]}]
    field = smooth_direction_field(V, F, symmetry=2, constraints=cons)
    conn = face_connection(V, F)
    f, g = conn.faces.T

    def energy(z):
        return float(np.sum(conn.weight * np.abs(z[g] - np.exp(2j * conn.angle) * z[f]) ** 2))

    e0 = energy(field.values)
    rng = np.random.default_rng(0)
    free = np.setdiff1d(np.arange(F.shape[0]), [0, 700])
    for _ in range(5):
        z = field.values.copy()
        z[free] += 1e-3 * (rng.standard_normal(free.size) + 1j * rng.standard_normal(free.size))
        assert energy(z) > e0


def test_components_without_constraints_get_the_smoothest_field(sphere):
    V, F = sphere
    V2 = np.vstack([V, V + [3.0, 0, 0]])
    F2 = np.vstack([F, F + V.shape[0]])
    field = smooth_direction_field(V2, F2, constraints=[{"face": 0, "direction": [0, 1, 0]}])
    assert index_sum(V2, F2, field) == 4
    assert np.all(np.abs(field.values) > 0)
    np.testing.assert_allclose(np.linalg.norm(field.vectors, axis=1), 1.0, atol=1e-12)


def test_representatives_are_rotations_about_the_normal(sphere):
    V, F = sphere
    field = smooth_direction_field(V, F, symmetry=4)
    reps = field.representatives()
    assert reps.shape == (F.shape[0], 4, 3)
    np.testing.assert_allclose(reps[:, 0], field.vectors)
    np.testing.assert_allclose(np.einsum("ikj,ij->ik", reps, field.normals), 0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("ij,ij->i", reps[:, 1], reps[:, 0]), 0, atol=1e-14)
    np.testing.assert_allclose(reps[:, 2], -reps[:, 0], atol=1e-14)


# --------------------------------------------------------------------------- invalid constraints

@pytest.mark.parametrize("constraint, message", [
    ({"face": 10_000, "direction": [1, 0, 0]}, r"constraints\[0\] face 10000 is out of range"),
    ({"face": -1, "direction": [1, 0, 0]}, r"out of range \[0, 1280\)"),
    ({"face": 2.0, "direction": [1, 0, 0]}, "face must be an integer"),
    ({"face": 3, "direction": [0, 0, 0]}, "direction is zero"),
    ({"face": 3, "direction": [np.inf, 0, 0]}, "direction must be finite"),
    ({"face": 3, "direction": [1, 0]}, "direction must be three numbers"),
    ({"face": 3}, "needs a 'direction'"),
    ({"direction": [1, 0, 0]}, "exactly one of 'face' and 'point'"),
    ({"face": 3, "point": [0, 0, 1], "direction": [1, 0, 0]}, "exactly one of"),
    ({"point": [0, 0, 1.5], "direction": [1, 0, 0]}, "from the surface, farther than"),
    ({"point": [0, 0, np.nan], "direction": [1, 0, 0]}, "point must be finite"),
    ({"face": 3, "direction": [1, 0, 0], "weight": 0}, "weight must be a positive"),
    ({"face": 3, "direction": [1, 0, 0], "radius": -1.0}, "radius must be a positive"),
    ({"face": 3, "dir": [1, 0, 0]}, "unknown key 'dir'"),
    ("face 3", "must be a Constraint or a dict"),
])
def test_invalid_constraints_raise(sphere, constraint, message):
    V, F = sphere
    with pytest.raises(InputError, match=message):
        smooth_direction_field(V, F, constraints=[constraint])
    with pytest.raises(InputError, match=message):
        rbf_direction_field(V, F, [constraint])


def test_direction_parallel_to_normal_raises(sphere):
    V, F = sphere
    T1, T2, N = face_frames(V, F)
    with pytest.raises(InputError, match=r"parallel to the normal of face 12"):
        smooth_direction_field(V, F, constraints=[{"face": 12, "direction": 3 * N[12]}])
    nearly = N[12] + 1e-8 * T1[12]
    with pytest.raises(InputError, match="parallel to the normal"):
        rbf_direction_field(V, F, [{"face": 12, "direction": nearly}])
    ok = N[12] + 1e-4 * T1[12]
    field = smooth_direction_field(V, F, constraints=[{"face": 12, "direction": ok}])
    assert _angle_between(field.vectors[[12]], T1[[12]])[0] < 1e-8


def test_other_invalid_arguments(sphere):
    V, F = sphere
    with pytest.raises(InputError, match="must be a list"):
        smooth_direction_field(V, F, constraints={"face": 0, "direction": [1, 0, 0]})
    with pytest.raises(InputError, match="different directions for face 4"):
        smooth_direction_field(V, F, constraints=[{"face": 4, "direction": [1, 0, 0]},
                                                  {"face": 4, "direction": [0, 1, 0]}])
    T1, T2, _ = face_frames(V, F)
    same = [{"face": 4, "direction": T1[4]}, {"face": 4, "direction": -T2[4]}]
    smooth_direction_field(V, F, symmetry=4, constraints=same)   # agree as crosses
    with pytest.raises(InputError, match="symmetry must be a positive integer"):
        smooth_direction_field(V, F, symmetry=0)
    with pytest.raises(InputError, match="mode must be"):
        smooth_direction_field(V, F, mode="firm")
    with pytest.raises(InputError, match="max_snap_distance"):
        smooth_direction_field(V, F, constraints=[{"point": [0, 0, 1.05], "direction": [1, 0, 0]}],
                               max_snap_distance=0.01)
    field = smooth_direction_field(V, F, constraints=[{"point": [0, 0, 1.05],
                                                       "direction": [1, 0, 0]}],
                                   max_snap_distance=0.1)
    assert field.constrained.size == 1
    with pytest.raises(InputError, match="kernel must be one of"):
        rbf_direction_field(V, F, [{"face": 0, "direction": [1, 0, 0]}], kernel="cubic")
    with pytest.raises(InputError, match="constraints is empty"):
        rbf_direction_field(V, F, [])
    with pytest.raises(InputError, match="radius cannot be used with kernel='thin_plate'"):
        rbf_direction_field(V, F, [{"face": 0, "direction": [1, 0, 0], "radius": 0.3}],
                            kernel="thin_plate")
    with pytest.raises(InputError, match="smoothing"):
        rbf_direction_field(V, F, [{"face": 0, "direction": [1, 0, 0]}], smoothing=-1.0)
    with pytest.raises(InputError, match="shape"):
        singularities(V, F, np.zeros((3, 3)))
    with pytest.raises(InputError, match="disagrees"):
        singularities(V, F, smooth_direction_field(V, F, symmetry=2), symmetry=4)


# --------------------------------------------------------------------------- combing

@pytest.mark.parametrize("N", [2, 4])
def test_combing_a_constant_field_with_random_representatives(plane, N):
    V, F = plane
    field = smooth_direction_field(V, F, symmetry=N, constraints=[{"face": 0,
                                                                   "direction": [1, 2, 0]}])
    pick = np.random.default_rng(4).integers(0, N, F.shape[0])
    scrambled = field.representatives()[np.arange(F.shape[0]), pick]
    combed = comb_direction_field(V, F, scrambled, symmetry=N)
    np.testing.assert_allclose(combed.vectors, np.tile(combed.vectors[0], (F.shape[0], 1)),
                               atol=1e-14)
    assert combed.cut_edges.size == 0 and combed.jumps.size == 0
    # face 0 is the root: it keeps its representative
    np.testing.assert_allclose(combed.vectors[0], scrambled[0], atol=1e-15)
    assert combed.tree_parent[0] == -1 and np.all(combed.tree_parent[1:] >= 0)


def test_combing_on_sphere_moves_mismatch_to_cut_edges(sphere):
    V, F = sphere
    field = smooth_direction_field(V, F, symmetry=4)
    combed = comb_direction_field(V, F, field)
    conn = face_connection(V, F)
    theta = tangent_angles(conn.T1, conn.T2, combed.vectors)
    f, g = conn.faces.T
    jump = np.mod(np.rint((theta[f] + conn.angle - theta[g]) * 4 / (2 * np.pi)), 4)
    assert np.array_equal(conn.edges[jump != 0], combed.cut_edges)
    assert np.array_equal(jump[jump != 0], combed.jumps)
    child = np.flatnonzero(combed.tree_parent >= 0)
    pairs = set(zip(np.minimum(child, combed.tree_parent[child]),
                    np.maximum(child, combed.tree_parent[child])))
    cut_pairs = {(min(a, b), max(a, b)) for a, b in conn.faces[jump != 0]}
    assert not (pairs & cut_pairs)                   # tree edges never jump
    assert combed.cut_edges.size > 0                  # singularities need cuts
    # combed vectors are among the field's representatives and agree with igl's index
    reps = field.representatives()
    assert np.min(np.linalg.norm(reps - combed.vectors[:, None], axis=2), axis=1).max() < 1e-12
    assert index_sum(V, F, combed.vectors, symmetry=4) == 2
    assert np.array_equal(combed_vectors(V, F, field), combed.vectors)


def test_combing_vector_field_is_identity(sphere):
    V, F = sphere
    field = smooth_direction_field(V, F)
    combed = comb_direction_field(V, F, field)
    assert np.array_equal(combed.rotations, np.zeros(F.shape[0], dtype=np.int64))
    np.testing.assert_allclose(combed.vectors, field.vectors, atol=1e-15)


# --------------------------------------------------------------------------- RBF

@pytest.mark.parametrize("kernel", KERNELS)
def test_rbf_reproduces_constraints_and_is_smooth(plane, kernel):
    V, F = plane
    cons = [{"face": 0, "direction": [1, 0, 0]}, {"face": 95, "direction": [0, 1, 0]},
            {"point": [1.0, 0.75, 0.0], "direction": [1, 1, 0]}]
    if kernel != "thin_plate":
        cons[2]["radius"] = 0.8
    field = rbf_direction_field(V, F, cons, kernel=kernel)
    sq, pf, _ = igl.point_mesh_squared_distance(np.array([[1.0, 0.75, 0.0]]), V, F)
    fc = [0, 95, int(pf[0])]
    want = np.array([[1.0, 0, 0], [0, 1.0, 0], [np.sqrt(0.5), np.sqrt(0.5), 0]])
    assert _angle_between(field.vectors[fc], want).max() < 1e-8
    conn = face_connection(V, F)
    f, g = conn.faces.T
    turn = _angle_between(field.vectors[f], field.vectors[g])
    assert turn.max() < 0.35                        # smooth: neighbours turn little
    assert field.singularities == ()
    np.testing.assert_allclose(field.vectors[:, 2], 0.0, atol=1e-15)


def test_rbf_on_sphere_is_tangent_unit_and_satisfies_gauss_bonnet(sphere):
    V, F = sphere
    cons = [{"face": 0, "direction": [1, 0, 0]}, {"face": 600, "direction": [0, 0, 1]},
            {"face": 1100, "direction": [0, 1, 0]}]
    for kernel in KERNELS:
        field = rbf_direction_field(V, F, cons, kernel=kernel)
        np.testing.assert_allclose(np.linalg.norm(field.vectors, axis=1), 1, atol=1e-12)
        np.testing.assert_allclose(np.einsum("ij,ij->i", field.vectors, field.normals), 0,
                                   atol=1e-12)
        assert index_sum(V, F, field) == 2


def test_rbf_invariance_and_determinism(ring):
    V, F = ring
    cons = [{"face": 0, "direction": [0, 0, 1]}, {"face": 1000, "direction": [1, 0, 0]}]
    ref = rbf_direction_field(V, F, cons)
    again = rbf_direction_field(V, F, cons)
    assert ref.vectors.tobytes() == again.vectors.tobytes()
    for s in (1e-3, 1e3):
        sc = rbf_direction_field(V * s, F, cons)
        np.testing.assert_allclose(sc.vectors, ref.vectors, atol=1e-9)
    R = _rotation(2)
    rcons = [{"face": c["face"], "direction": R @ np.array(c["direction"], float)} for c in cons]
    rot = rbf_direction_field(V @ R.T, F, rcons)
    np.testing.assert_allclose(rot.vectors, ref.vectors @ R.T, atol=1e-9)


def test_rbf_smoothing_uses_weights(plane):
    V, F = plane
    cons = [{"face": 0, "direction": [1, 0, 0], "weight": 100.0},
            {"face": 1, "direction": [0, 1, 0], "weight": 0.01}]
    field = rbf_direction_field(V, F, cons, smoothing=0.5)
    # faces keep their constraints; the heavy one dominates its surroundings
    assert np.dot(field.vectors[2], [1, 0, 0]) > np.dot(field.vectors[2], [0, 1, 0])


def test_surface_distances_on_plane(plane):
    V, F = plane
    D = surface_distances(V, F, [0])
    C = V[F].mean(axis=1)
    straight = np.linalg.norm(C - C[0], axis=1)
    assert D.shape == (1, F.shape[0]) and D[0, 0] == 0
    assert np.all(D[0] >= straight - 1e-12) and np.all(D[0] <= 1.5 * straight + 1e-12)


def test_bow_tie_vertex_has_no_index(sphere):
    V, F = sphere
    n = V.shape[0]
    mirror = V * np.array([1.0, 1.0, -1.0]) + np.array([0.0, 0.0, 2.0])   # its vertex 0 = V[0]
    V2 = np.vstack([V, mirror[1:]])
    remap = np.concatenate([[0], np.arange(n, 2 * n - 1)])
    F2 = np.vstack([F, remap[F[:, ::-1]]])                 # reflected: reverse the faces
    field = smooth_direction_field(V2, F2)
    idx = vertex_indices(V2, F2, field)
    assert np.isnan(idx[0]) and np.isnan(idx).sum() == 1
    m = F.shape[0]
    one, two = field.vectors[:m], field.vectors[m:]
    assert index_sum(V, F, one) == 2 and index_sum(mirror, F[:, ::-1], two) == 2
    at_tie = vertex_indices(V, F, one)[0] + vertex_indices(mirror, F[:, ::-1], two)[0]
    assert index_sum(V2, F2, field) == 4 - Fraction(at_tie)
