import numpy as np
import pytest
from scipy.spatial import Delaunay

from geotex.errors import InputError
from geotex.mesh.primitives import grid_plane, icosphere, torus
from geotex.param import (distortion_summary, face_distortion, face_jacobians,
                          field_aligned_parameterization, harmonic_parameterization,
                          lscm_parameterization, singular_values)
from geotex.patches import boundary_loops, grow_patch


def jittered_disc(n=200, seed=0):
    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.uniform(-1, 1, (n, 2)), [[-1, -1], [1, -1], [1, 1], [-1, 1]]])
    F = Delaunay(pts).simplices.astype(np.int64)
    a, b, c = pts[F[:, 0]], pts[F[:, 1]], pts[F[:, 2]]
    neg = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[neg] = F[neg][:, ::-1]
    return np.column_stack([pts, np.zeros(len(pts))]), F


def rotation(seed=0):
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def planar_mesh_in_space(seed=0):
    V, F = jittered_disc(200, seed)
    R = rotation(seed)
    return V @ R.T + [0.3, -2.0, 5.0], F, R


def signed_areas(uv, F):
    a, b, c = uv[F[:, 0]], uv[F[:, 1]], uv[F[:, 2]]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


def dmat(X):
    return np.linalg.norm(X[:, None] - X[None], axis=2)


def cylinder_strip(n_theta=12, n_z=6, angle=2.0):
    t = np.linspace(0, angle, n_theta + 1)
    z = np.linspace(0, 1, n_z + 1)
    tt, zz = np.meshgrid(t, z, indexing="ij")
    V = np.stack([np.cos(tt), np.sin(tt), zz], -1).reshape(-1, 3)
    _, F = grid_plane(n_theta, n_z)
    return V, F


# ---------------------------------------------------------------------------
# field-aligned least squares
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("scale", [1.0, 0.25, 3.0])
def test_field_aligned_planar_patch_is_scaled_rigid_motion(scale):
    V, F, R = planar_mesh_in_space(1)
    a = 0.7
    S = R @ np.array([np.cos(a), np.sin(a), 0.0])
    N = R @ np.array([0.0, 0.0, 1.0])
    T = np.cross(N, S)
    field = np.tile(S, (len(F), 1))
    faces = np.arange(len(F))
    uv, verts = field_aligned_parameterization(V, F, faces, field, scale=scale)
    assert np.array_equal(verts, np.arange(len(V)))
    X = V[verts]
    assert np.abs(dmat(uv) * scale - dmat(X)).max() < 1e-10
    # u follows the field, v follows N x field
    d3 = X - X[0]
    expect = np.column_stack([d3 @ S, d3 @ T]) / scale
    assert np.abs((uv - uv[0]) - expect).max() < 1e-10
    # the seed (first) face's centroid sits at the default centre (0.5, 0.5)
    assert np.allclose(uv[np.searchsorted(verts, F[0])].mean(axis=0), [0.5, 0.5], atol=1e-12)
    s = distortion_summary(V, F, uv[np.searchsorted(verts, np.arange(len(V)))])
    assert s.n_flipped == 0 and s.angle.max < 1e-12
    assert s.area_ratio == pytest.approx(1 / scale**2, rel=1e-10)


def test_field_aligned_on_grown_patch_and_non_tangent_field():
    V, F, R = planar_mesh_in_space(2)
    C = V[F].mean(axis=1)
    seed = int(np.argmin(np.linalg.norm(C - V.mean(axis=0), axis=1)))
    p = grow_patch(V, F, seed, max_radius=0.6)
    S = R @ np.array([1.0, 0.0, 0.0])
    N = R @ np.array([0.0, 0.0, 1.0])
    tangent = np.tile(S * 2.5, (len(F), 1))
    tilted = tangent + 4.0 * N                       # the normal part is projected away
    uv1, v1 = field_aligned_parameterization(V, F, p.faces, tangent, center_uv=(0, 0))
    uv2, v2 = field_aligned_parameterization(V, F, p.faces, tilted, center_uv=(0, 0))
    assert np.array_equal(v1, p.vertices) and np.array_equal(v1, v2)
    assert np.abs(uv1 - uv2).max() < 1e-12
    assert np.abs(dmat(uv1) - dmat(V[v1])).max() < 1e-10
    assert np.allclose(uv1[p.F[0]].mean(axis=0), 0.0, atol=1e-12)
    # another centre face only translates the map
    uv3, _ = field_aligned_parameterization(V, F, p.faces, tangent, center_face=p.faces[5],
                                            center_uv=(0, 0))
    shift = uv3 - uv1
    assert np.allclose(shift, shift[0], atol=1e-12)
    assert np.allclose(uv3[p.F[5]].mean(axis=0), 0.0, atol=1e-12)


def test_field_aligned_per_face_scale_matches_scalar():
    V, F, R = planar_mesh_in_space(3)
    field = np.tile(R[:, 0], (len(F), 1))
    faces = np.arange(0, len(F))
    a, _ = field_aligned_parameterization(V, F, faces, field, scale=2.0)
    b, _ = field_aligned_parameterization(V, F, faces, field, scale=np.full(len(F), 2.0))
    assert np.abs(a - b).max() < 1e-12


def test_field_aligned_developable_cylinder_is_isometric():
    V, F = cylinder_strip()
    field = np.tile([0.0, 0.0, 1.0], (len(F), 1))       # along the rulings
    uv, verts = field_aligned_parameterization(V, F, np.arange(len(F)), field)
    s = distortion_summary(V, F, uv)
    assert s.n_flipped == 0
    assert s.angle.max < 1e-10 and s.area.max < 1e-10
    # u is the height, v the arc length (up to translation)
    assert np.allclose(uv[:, 0] - uv[0, 0], V[:, 2] - V[0, 2], atol=1e-10)


def test_field_aligned_curved_patch_is_close_and_fold_free(sphere):
    V, F = sphere
    p = grow_patch(V, F, 0, max_radius=0.8)
    C = V[F].mean(axis=1)
    field = np.cross(C, [1.0, 0.3, 0.0])                 # smooth tangent field near the seed
    uv, verts = field_aligned_parameterization(V, F, p.faces, field)
    Vl, Fl = p.local_mesh(V)
    s = distortion_summary(Vl, Fl, uv)
    assert s.n_flipped == 0 and s.angle.p95 < 0.05 and abs(np.log(s.area_ratio)) < 0.05


def test_field_aligned_determinism_and_purity(sphere):
    V, F = sphere
    field = np.cross(V[F].mean(axis=1), [0.0, 0.0, 1.0]) + [1e-3, 0, 0]
    faces = grow_patch(V, F, 17, max_radius=0.5).faces
    args = [a.copy() for a in (V, F, faces, field)]
    u1, v1 = field_aligned_parameterization(V, F, faces, field, scale=0.3)
    u2, v2 = field_aligned_parameterization(V, F, faces, field, scale=0.3)
    assert np.array_equal(u1, u2) and np.array_equal(v1, v2)
    for a, b in zip(args, (V, F, faces, field)):
        assert np.array_equal(a, b)


def test_field_aligned_errors(sphere):
    V, F = sphere
    field = np.tile([1.0, 0.0, 0.0], (len(F), 1))
    faces = np.arange(10)
    with pytest.raises(InputError, match="field must have shape"):
        field_aligned_parameterization(V, F, faces, field[:5])
    with pytest.raises(InputError, match="patch_faces"):
        field_aligned_parameterization(V, F, [], field)
    with pytest.raises(InputError, match="patch_faces"):
        field_aligned_parameterization(V, F, [0, 0, 1], field)
    with pytest.raises(InputError, match="patch_faces"):
        field_aligned_parameterization(V, F, [len(F)], field)
    with pytest.raises(InputError, match="scale"):
        field_aligned_parameterization(V, F, faces, field, scale=0.0)
    with pytest.raises(InputError, match="center_face"):
        field_aligned_parameterization(V, F, faces, field, center_face=500)
    zero = field.copy()
    zero[3] = 0.0
    with pytest.raises(InputError, match="field is zero or normal to face 3"):
        field_aligned_parameterization(V, F, faces, zero)
    normal = field.copy()
    normal[4] = np.cross(V[F[4, 1]] - V[F[4, 0]], V[F[4, 2]] - V[F[4, 0]])
    with pytest.raises(InputError, match="face 4"):
        field_aligned_parameterization(V, F, faces, normal)
    far = [0, int(np.argmin(V[F].mean(axis=1)[:, 2]))]   # two faces on opposite poles
    with pytest.raises(InputError, match="separate pieces"):
        field_aligned_parameterization(V, F, far, field)
    Vd = V.copy()
    Vd[F[2, 2]] = 0.5 * (Vd[F[2, 0]] + Vd[F[2, 1]])
    with pytest.raises(InputError, match="degenerate"):
        field_aligned_parameterization(Vd, F, [2], field)


# ---------------------------------------------------------------------------
# distortion
# ---------------------------------------------------------------------------

def test_distortion_zero_for_isometry():
    V, F, R = planar_mesh_in_space(4)
    a = 1.1
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    local = (V - V[0]) @ R                               # back to the xy plane
    uv = local[:, :2] @ rot.T + [3.0, -1.0]
    d = face_distortion(V, F, uv)
    assert np.abs(d.s1 - 1).max() < 1e-12 and np.abs(d.s2 - 1).max() < 1e-12
    assert np.abs(d.log_area).max() < 1e-12 and np.abs(d.conformal_error).max() < 1e-12
    assert np.abs(d.stretch_ratio - 1).max() < 1e-12 and not d.flipped.any()
    s = distortion_summary(V, F, uv)
    for st in (s.area, s.area_normalized, s.angle):
        assert st.mean < 1e-12 and st.p95 < 1e-12 and st.max < 1e-12
    assert s.n_flipped == 0 and s.n_collapsed == 0 and s.area_ratio == pytest.approx(1.0)


def test_distortion_known_stretch_and_flip():
    V, F = jittered_disc(100, seed=5)
    uv = V[:, :2] * [2.0, 1.0]
    d = face_distortion(V, F, uv)
    assert np.allclose(d.s1, 2) and np.allclose(d.s2, 1)
    assert np.allclose(d.area_ratio, 2) and np.allclose(d.stretch_ratio, 2)
    assert np.allclose(d.conformal_error, 0.25)
    assert np.allclose(d.log_area_normalized, 0, atol=1e-12)     # uniform scale removed
    s = distortion_summary(V, F, uv)
    assert s.area.mean == pytest.approx(np.log(2)) and s.angle.max == pytest.approx(0.25)
    assert s.area_normalized.max < 1e-12
    mirrored = V[:, :2] * [1.0, -1.0]
    assert distortion_summary(V, F, mirrored).n_flipped == len(F)
    assert face_distortion(V, F, mirrored).flipped.all()


def test_distortion_area_weighted_statistics_with_uv_faces():
    V, F = grid_plane(4, 4, size=(2.0, 1.0))              # equal-area faces
    C = V[F].mean(axis=1)
    left = C[:, 0] < 1.0
    corners = V[F].reshape(-1, 3)[:, :2].copy()           # one uv per face corner
    corners[np.repeat(left, 3), 0] *= 3.0
    FT = np.arange(3 * len(F)).reshape(-1, 3)
    s = distortion_summary(V, F, corners, uv_faces=FT)
    assert s.area.mean == pytest.approx(np.log(3) / 2)
    assert s.area.max == pytest.approx(np.log(3)) and s.area.p95 == pytest.approx(np.log(3))
    e = (3 + 1 / 3) / 2 - 1
    assert s.angle.mean == pytest.approx(e / 2) and s.stretch.max == pytest.approx(3.0)
    assert s.area_ratio == pytest.approx(2.0)


def test_singular_values_closed_form_matches_numpy():
    rng = np.random.default_rng(0)
    J = rng.normal(size=(500, 2, 2))
    s1, s2, det = singular_values(J)
    ref = np.linalg.svd(J, compute_uv=False)
    assert np.allclose(s1, ref[:, 0]) and np.allclose(s2, ref[:, 1])
    assert np.allclose(det, np.linalg.det(J))
    V, F = grid_plane(2, 2)
    Jf, area = face_jacobians(V, F, V[:, :2])
    # the identity map is a rotation in every face frame
    assert np.allclose(np.transpose(Jf, (0, 2, 1)) @ Jf, np.eye(2), atol=1e-14)
    assert np.allclose(np.linalg.det(Jf), 1.0)
    assert np.allclose(area, 0.125)


def test_distortion_errors():
    V, F = grid_plane(2, 2)
    with pytest.raises(InputError, match="uv"):
        face_distortion(V, F, V)
    with pytest.raises(InputError, match="uv_faces"):
        face_distortion(V, F, V[:3, :2])
    with pytest.raises(InputError, match="uv_faces"):
        face_distortion(V, F, V[:, :2], uv_faces=F[:2])
    bad = V[:, :2].copy()
    bad[0, 0] = np.nan
    with pytest.raises(InputError, match="non-finite"):
        distortion_summary(V, F, bad)


# ---------------------------------------------------------------------------
# harmonic and LSCM
# ---------------------------------------------------------------------------

@pytest.fixture
def sphere_cap():
    V, F = icosphere(3)
    p = grow_patch(V, F, 0, max_radius=1.0)
    assert p.is_disc
    return p.local_mesh(V)


@pytest.mark.parametrize("weights", ["cotan", "uniform"])
def test_harmonic_circle_on_sphere_cap(sphere_cap, weights):
    V, F = sphere_cap
    uv = harmonic_parameterization(V, F, weights=weights)
    assert uv.shape == (len(V), 2)
    assert np.all(signed_areas(uv, F) > 0)
    loop = boundary_loops(F)[0]
    assert np.allclose(np.linalg.norm(uv[loop], axis=1), 1.0)
    inner = np.setdiff1d(np.arange(len(V)), loop)
    assert np.all(np.linalg.norm(uv[inner], axis=1) < 1.0)
    assert distortion_summary(V, F, uv).n_flipped == 0


def test_harmonic_square_boundary(sphere_cap):
    V, F = sphere_cap
    uv = harmonic_parameterization(V, F, boundary="square")
    loop = boundary_loops(F)[0]
    b = uv[loop]
    on_side = np.min(np.stack([b[:, 0], 1 - b[:, 0], b[:, 1], 1 - b[:, 1]]), axis=0)
    assert np.allclose(on_side, 0.0, atol=1e-12)
    for corner in ([0, 0], [1, 0], [1, 1], [0, 1]):
        assert np.any(np.all(np.abs(b - corner) < 1e-12, axis=1))
    inner = np.setdiff1d(np.arange(len(V)), loop)
    assert np.all((uv[inner] > 0) & (uv[inner] < 1))
    assert np.all(signed_areas(uv, F) >= -1e-15)


def test_lscm_on_sphere_cap_and_plane(sphere_cap):
    V, F = sphere_cap
    uv = lscm_parameterization(V, F)
    assert np.all(signed_areas(uv, F) > 0)
    s = distortion_summary(V, F, uv)
    assert s.n_flipped == 0 and s.angle.max < 0.01
    # on a planar mesh LSCM is an exact similarity
    Vp, Fp, _ = planar_mesh_in_space(6)
    uvp = lscm_parameterization(Vp, Fp)
    sp_ = distortion_summary(Vp, Fp, uvp)
    assert sp_.angle.max < 1e-9 and sp_.area_normalized.max < 1e-9 and sp_.n_flipped == 0
    assert np.allclose(lscm_parameterization(Vp, Fp), uvp)


def test_wrappers_reject_non_discs():
    V, F = icosphere(2)
    for fn in (harmonic_parameterization, lscm_parameterization):
        with pytest.raises(InputError, match="closed surface"):
            fn(V, F)
    Vg, Fg = grid_plane(6, 6)
    C = Vg[Fg].mean(axis=1)
    annulus = Fg[np.abs(C[:, :2] - 0.5).max(axis=1) > 0.2]
    used = np.unique(annulus)
    Va, Fa = Vg[used], np.searchsorted(used, annulus)
    for fn in (harmonic_parameterization, lscm_parameterization):
        with pytest.raises(InputError, match="2 boundary loops"):
            fn(Va, Fa)
    Vt, Ft = torus(n_major=12, n_minor=8)
    with pytest.raises(InputError, match="must be a topological disc"):
        harmonic_parameterization(Vt, Ft)
    with pytest.raises(InputError, match="components"):
        lscm_parameterization(np.vstack([Vg, Vg + 5]), np.vstack([Fg, Fg + len(Vg)]))
    with pytest.raises(InputError, match="no face uses"):
        harmonic_parameterization(np.vstack([Vg, [[9.0, 9, 9]]]), Fg)
    with pytest.raises(InputError, match="boundary"):
        harmonic_parameterization(Vg, Fg, boundary="triangle")
    with pytest.raises(InputError, match="weights"):
        harmonic_parameterization(Vg, Fg, weights="mean")


def test_wrappers_do_not_mutate(sphere_cap):
    V, F = sphere_cap
    V0, F0 = V.copy(), F.copy()
    harmonic_parameterization(V, F, boundary="square")
    lscm_parameterization(V, F)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


@pytest.mark.parametrize("factor", [1e-6, 1e6])
def test_param_scale_invariance(sphere_cap, factor):
    V, F = sphere_cap
    field = np.cross(V[F].mean(axis=1), [1.0, 0.2, 0.0])
    faces = np.arange(len(F))
    a, _ = field_aligned_parameterization(V, F, faces, field, scale=0.5)
    b, _ = field_aligned_parameterization(V * factor, F, faces, field, scale=0.5 * factor)
    assert np.allclose(a, b, rtol=0, atol=1e-9)
    s1 = distortion_summary(V, F, a)
    s2 = distortion_summary(V * factor, F, a * factor)
    assert s1.angle.max == pytest.approx(s2.angle.max, rel=1e-6)
    assert s1.area.mean == pytest.approx(s2.area.mean, rel=1e-6)
    h1 = harmonic_parameterization(V, F)
    h2 = harmonic_parameterization(V * factor, F)
    assert np.allclose(h1, h2, atol=1e-9)
    l1 = lscm_parameterization(V, F)
    l2 = lscm_parameterization(V * factor, F)
    assert np.allclose(l1 * factor, l2, rtol=1e-7, atol=1e-9 * factor)
