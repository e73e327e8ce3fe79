"""Tests of height-and-tilt reapplication after deformation and texture transfer."""

from __future__ import annotations

import igl
import numpy as np
import pytest

from geotex.errors import InputError
from geotex.heighttilt import (apply_texture, base_normals, extract_texture, spiky_sphere,
                               tentacle_stick)
from geotex.heighttilt.deform import (bend, deformed_texture, naive_space_deformation,
                                      reapplied, scale_base, twist)
from geotex.heighttilt.transfer import (check_correspondence, closest_point_correspondence,
                                        transfer_texture)
from geotex.mesh.primitives import icosphere


@pytest.fixture(scope="module")
def stick():
    V0, F, Vs = tentacle_stick(seed=2)
    tex, _ = extract_texture(V0, F, base=Vs)
    return V0, F, Vs, tex


@pytest.fixture(scope="module")
def sphere():
    V0, F, Vs = spiky_sphere(subdivisions=3, spikes=6, seed=0, height=0.2, width=0.4,
                             lean_degrees=30.0)
    tex, _ = extract_texture(V0, F, base=Vs)
    return V0, F, Vs, tex


def _lengths_angles(V, B, F, mask):
    """Displacement lengths and angles to the base normal at the masked vertices."""
    d = (V - B)[mask]
    n = base_normals(B, F)[mask]
    L = np.linalg.norm(d, axis=1)
    return L, np.arccos(np.clip(np.einsum("kd,kd->k", d, n) / L, -1.0, 1.0))


def _identity_correspondence(F, n):
    faces = np.zeros(n, dtype=np.int64)
    bary = np.zeros((n, 3))
    f_of = np.full(n, -1)
    k_of = np.zeros(n, dtype=np.int64)
    for k in range(3):                       # any incident face will do
        f_of[F[:, k]] = np.arange(F.shape[0])
        k_of[F[:, k]] = k
    faces[:] = f_of
    bary[np.arange(n), k_of] = 1.0
    return faces, bary


# --------------------------------------------------------------------------- deformation

def test_bend_keeps_heights_and_angles_naive_does_not(stick):
    V0, F, Vs, tex = stick
    mask = np.abs(tex.height) > 1e-6
    assert mask.sum() > 100
    Vd = bend(Vs, angle=np.pi / 2)
    V = reapplied(Vd, F, tex, base=Vs)
    np.testing.assert_allclose(np.linalg.norm(V - Vd, axis=1), np.abs(tex.height),
                               rtol=0, atol=1e-9)
    L0, a0 = _lengths_angles(V0, Vs, F, mask)
    L1, a1 = _lengths_angles(V, Vd, F, mask)
    assert np.abs(a1 - a0).max() < 1e-6              # measured ~3.5e-11
    assert a0.max() > 0.7                            # there are real lean angles (~45 deg)
    # naive 1: the space map applied to the detailed mesh changes the elements
    Ln, an = _lengths_angles(bend(V0, angle=np.pi / 2, origin=Vs[:, 2].min(),
                                  length=np.ptp(Vs[:, 2])), Vd, F, mask)
    assert np.abs(Ln - L0).max() > 5e-3              # measured 8.0e-3 (7.0 % relative)
    assert (np.abs(Ln - L0) / L0).max() > 0.05
    assert np.abs(an - a0).max() > 0.05              # measured 0.099 rad
    # naive 2: displacement vectors carried over unrotated keep lengths, not angles
    Lt, at = _lengths_angles(naive_space_deformation(V0, Vs, Vd, F), Vd, F, mask)
    np.testing.assert_allclose(Lt, L0, atol=1e-12)
    assert np.abs(at - a0).max() > 1.0               # measured 1.42 rad


def test_twist_keeps_heights_and_angles(stick):
    V0, F, Vs, tex = stick
    mask = np.abs(tex.height) > 1e-6
    Vd = twist(Vs, turns=0.5)
    L0, a0 = _lengths_angles(V0, Vs, F, mask)
    L1, a1 = _lengths_angles(reapplied(Vd, F, tex, base=Vs), Vd, F, mask)
    np.testing.assert_allclose(L1, L0, atol=1e-9)
    assert np.abs(a1 - a0).max() < 1e-6


@pytest.mark.parametrize("s", [0.5, 1.5])
def test_uniform_scaling_keeps_angles_exactly(stick, s):
    V0, F, Vs, tex = stick
    mask = np.abs(tex.height) > 1e-6
    Vd = scale_base(Vs, s)
    L0, a0 = _lengths_angles(V0, Vs, F, mask)
    L1, a1 = _lengths_angles(reapplied(Vd, F, tex, base=Vs), Vd, F, mask)
    np.testing.assert_allclose(L1, L0, atol=1e-12)
    assert np.abs(a1 - a0).max() < 1e-9              # round-off (~1e-11)
    # the rescaled 1-form alone already keeps the vertex tilts under uniform scaling
    t2 = deformed_texture(Vs, Vd, F, tex)
    np.testing.assert_allclose(t2.tilt, s * tex.tilt, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(t2.residual, tex.residual, atol=1e-9)
    # without the rescaling the angles change a lot
    _, a2 = _lengths_angles(reapplied(Vd, F, tex, keep_angles=False), Vd, F, mask)
    assert np.abs(a2 - a0).max() > 0.2


def test_reapplied_on_same_or_rigidly_moved_base_reproduces(stick):
    V0, F, Vs, tex = stick
    np.testing.assert_allclose(reapplied(Vs, F, tex, base=Vs), V0, atol=1e-9)
    q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    shift = np.array([0.3, -1.0, 2.0])
    np.testing.assert_allclose(reapplied(Vs @ q.T + shift, F, tex, base=Vs), V0 @ q.T + shift,
                               atol=1e-9)


def test_deformation_helpers():
    V = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 2.0], [0.0, -0.5, 2.0]])
    V_in = V.copy()
    np.testing.assert_array_equal(bend(V, angle=0.0), V)
    B = bend(V, angle=np.pi / 2, toward=1)
    np.testing.assert_array_equal(V, V_in)           # no input mutation
    R = 2.0 / (np.pi / 2)
    np.testing.assert_allclose(B[2], [0.0, R, R], atol=1e-12)   # end of the arc
    np.testing.assert_allclose(np.linalg.norm(B[3] - [0, R, 0]), R + 0.5, atol=1e-12)
    T = twist(V + [1.0, 0.0, 0.0], turns=0.25)
    np.testing.assert_allclose(T[2], [0.0, 1.0, 2.0], atol=1e-12)       # quarter turn at the end
    np.testing.assert_allclose(T[1], [np.sqrt(0.5), np.sqrt(0.5), 1.0], atol=1e-12)
    np.testing.assert_allclose(scale_base(V, 2.0, center=[0, 0, 0]), 2 * V)
    np.testing.assert_allclose(scale_base(V, 3.0).mean(axis=0), V.mean(axis=0))
    with pytest.raises(InputError, match="s must be a positive"):
        scale_base(V, 0.0)
    with pytest.raises(InputError, match="toward must differ"):
        bend(V, angle=1.0, axis=1, toward=1)
    with pytest.raises(InputError, match="axis must be"):
        twist(V, turns=1.0, axis=3)
    with pytest.raises(InputError, match="angle must be a finite"):
        bend(V, angle=np.nan)


def test_reapplied_errors(stick):
    V0, F, Vs, tex = stick
    with pytest.raises(InputError, match="base .* is required"):
        reapplied(bend(Vs, angle=1.0), F, tex)
    with pytest.raises(InputError, match="connectivity mismatch"):
        reapplied(Vs, F[::-1], tex, base=Vs)
    with pytest.raises(InputError, match="must have the shape"):
        naive_space_deformation(V0, Vs[:-1], Vs, F)


# --------------------------------------------------------------------------- transfer

def test_transfer_identity_reproduces(sphere):
    V0, F, Vs, tex = sphere
    corr = _identity_correspondence(F, Vs.shape[0])
    F_in, Vs_in = F.copy(), Vs.copy()
    out = transfer_texture(Vs, F, tex, Vs, F, correspondence=corr)
    np.testing.assert_array_equal(F, F_in)
    np.testing.assert_array_equal(Vs, Vs_in)
    np.testing.assert_array_equal(out.height, tex.height)
    np.testing.assert_allclose(apply_texture(Vs, F, out), V0, atol=1e-9)
    # closest points of the vertices themselves are an identity correspondence too
    cp = closest_point_correspondence(Vs, Vs, F)
    np.testing.assert_allclose(apply_texture(Vs, F, transfer_texture(
        Vs, F, tex, Vs, F, correspondence=cp)), V0, atol=1e-9)


def test_transfer_to_finer_sphere_is_close(sphere):
    V0, F, Vs, tex = sphere
    Vd, Fd = icosphere(4)
    corr = closest_point_correspondence(Vd, Vs, F)
    out = transfer_texture(Vs, F, tex, Vd, Fd, correspondence=corr)
    assert out.tilt.shape == (3 * Fd.shape[0] // 2,)
    Vr = apply_texture(Vd, Fd, out)
    d_rs = np.sqrt(igl.point_mesh_squared_distance(Vr, V0, F)[0]).max()
    d_sr = np.sqrt(igl.point_mesh_squared_distance(V0, Vr, Fd)[0]).max()
    hmax = np.abs(tex.height).max()                  # ~0.198
    assert max(d_rs, d_sr) < 0.1 * hmax              # measured 0.0128 and 3.4e-4
    # the tilt matters: heights alone (no lean) land much farther away
    Vh = apply_texture(Vd, Fd, out.replace(tilt=np.zeros_like(out.tilt), residual=None))
    d_h = np.sqrt(igl.point_mesh_squared_distance(Vh, V0, F)[0]).max()
    assert d_h > 3 * d_rs                            # measured 0.052
    # the transferred 1-form carries most of the tilt; the residual only the rest
    from geotex.heighttilt import decode_tilt
    t_full = decode_tilt(Vd, Fd, out.tilt, out.residual)
    t_form = decode_tilt(Vd, Fd, out.tilt)
    assert np.linalg.norm(t_full - t_form) < 0.15 * np.linalg.norm(t_full)   # measured 0.067


def test_transfer_samples_and_determinism(sphere):
    V0, F, Vs, tex = sphere
    Vd, Fd = icosphere(4)
    corr = closest_point_correspondence(Vd, Vs, F)
    a = transfer_texture(Vs, F, tex, Vd, Fd, correspondence=corr)
    b = transfer_texture(Vs, F, tex, Vd, Fd, correspondence=corr)
    np.testing.assert_array_equal(a.tilt, b.tilt)
    c = transfer_texture(Vs, F, tex, Vd, Fd, correspondence=corr, samples=2)
    # decode at vertices is exact whatever the samples: same reconstruction
    np.testing.assert_allclose(apply_texture(Vd, Fd, c), apply_texture(Vd, Fd, a), atol=1e-9)


def test_transfer_bad_correspondence(sphere):
    V0, F, Vs, tex = sphere
    Vd, Fd = icosphere(2)
    fc, B = closest_point_correspondence(Vd, Vs, F)
    n = Vd.shape[0]

    def run(corr):
        transfer_texture(Vs, F, tex, Vd, Fd, correspondence=corr)

    with pytest.raises(InputError, match="pair"):
        run(fc)
    with pytest.raises(InputError, match=r"faces must have shape"):
        run((fc[:-1], B))
    with pytest.raises(InputError, match=r"bary must have shape"):
        run((fc, B[:, :2]))
    with pytest.raises(InputError, match="must be integers"):
        run((fc.astype(float), B))
    bad = fc.copy()
    bad[3] = F.shape[0]
    with pytest.raises(InputError, match=r"faces must be in \[0, "):
        run((bad, B))
    bad[3] = -1
    with pytest.raises(InputError, match=r"faces must be in \[0, "):
        run((bad, B))
    B2 = B.copy()
    B2[5] *= 1.1
    with pytest.raises(InputError, match="sum to 1"):
        run((fc, B2))
    B2[5] = np.nan
    with pytest.raises(InputError, match="non-finite"):
        run((fc, B2))
    with pytest.raises(InputError, match="samples must be"):
        transfer_texture(Vs, F, tex, Vd, Fd, correspondence=(fc, B), samples=0)
    with pytest.raises(InputError, match="connectivity mismatch"):
        transfer_texture(Vd, Fd, tex, Vd, Fd, correspondence=(fc, B))
    assert check_correspondence((fc, B), n, F.shape[0])[0].dtype == np.int64


# --------------------------------------------------------------------------- invariance

def _motion(seed=4):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q)), 1.7, np.array([0.4, -2.0, 1.1])


def test_edits_are_invariant_under_rigid_motion_and_uniform_scaling(sphere):
    from geotex.heighttilt import displacements, set_tilt, wiggle, wrap
    V0, F, Vs, tex = sphere
    R, s, shift = _motion()
    Ts = s * Vs @ R.T + shift
    tex2, _ = extract_texture(s * V0 @ R.T + shift, F, base=Ts)
    d = [u @ [0.3, 1.0, 0.2] for u in (np.eye(3), R)]
    cases = [
        (lambda B, t, k: set_tilt(B, F, t, angle_degrees=30.0, direction=d[k])),
        (lambda B, t, k: set_tilt(B, F, t, angle_degrees=20.0)),
        # wrap leans by k |h| radians: k is per unit of height, so it scales by 1 / s
        (lambda B, t, k: wrap(B, F, t, k=2.0 / (s if k else 1.0), direction=d[k])),
        # the default wavelength follows the base's size, the wave starts at the base
        (lambda B, t, k: wiggle(B, F, t, amplitude=25.0, phase=0.7,
                                direction=[u @ [0.0, 0.3, 1.0] for u in (np.eye(3), R)][k])),
    ]
    for edit in cases:
        a = displacements(Vs, F, edit(Vs, tex, 0))
        b = displacements(Ts, F, edit(Ts, tex2, 1))
        np.testing.assert_allclose(b, s * a @ R.T, atol=1e-9 * s)


def test_transfer_is_invariant_under_rigid_motion_and_uniform_scaling(sphere):
    V0, F, Vs, tex = sphere
    Vd, Fd = icosphere(4)
    R, s, shift = _motion(5)

    def moved(X):
        return s * X @ R.T + shift

    out = transfer_texture(Vs, F, tex, Vd, Fd,
                           correspondence=closest_point_correspondence(Vd, Vs, F))
    tex2, _ = extract_texture(moved(V0), F, base=moved(Vs))
    out2 = transfer_texture(moved(Vs), F, tex2, moved(Vd), Fd,
                            correspondence=closest_point_correspondence(moved(Vd), moved(Vs), F))
    np.testing.assert_allclose(out2.height, s * out.height, atol=1e-9 * s)
    np.testing.assert_allclose(out2.tilt, s * out.tilt, atol=1e-9 * s)
    np.testing.assert_allclose(apply_texture(moved(Vd), Fd, out2),
                               moved(apply_texture(Vd, Fd, out)), atol=1e-9 * s)


# ---------------------------------------------------------------- different shapes

def _ellipsoid(sub=4, axes=(1.0, 1.0, 1.8)):
    from geotex.mesh.primitives import icosphere
    V, F = icosphere(sub)
    return V * np.array(axes), F


def test_transfer_between_shapes_keeps_element_heights_and_lean_directions():
    from geotex.heighttilt import spiky_sphere
    from geotex.heighttilt.transfer import transfer_between_shapes
    V0, F, Vs = spiky_sphere(subdivisions=3, spikes=8, width=0.3, height=0.3,
                             lean_degrees=40.0, seed=2)
    tex, _ = extract_texture(V0, F, base=Vs)
    Vd, Fd = _ellipsoid()
    out, rep = transfer_between_shapes(Vs, F, tex, Vd, Fd)
    assert out.height.shape == (len(Vd),) and out.metadata["map"] == "sphere"
    # one of the 7 spikes peaks near the fixed 0.25 element threshold: resampled on the
    # ellipsoid its peak lands just above or below it depending on the last bits of the
    # map (6 or 7 found on different CPUs); losing more than that one is a failure
    assert rep.source.elements - 1 <= rep.target.elements <= rep.source.elements
    # measured: 7 elements, mean element height 0.281 -> 0.261-0.267, tilt direction
    # median 2.6-3.2 deg
    assert abs(rep.target.mean_element_height / rep.source.mean_element_height - 1) < 0.1
    assert rep.tilt_direction_error_deg[0] < 10.0
    assert rep.distortion.angle.mean < 0.02            # near-conformal map
    from geotex.mesh.topology import edge_topology
    E = edge_topology(Fd, len(Vd)).edges
    assert (np.abs(out.tilt) <= np.linalg.norm(Vd[E[:, 1]] - Vd[E[:, 0]], axis=1) + 1e-15).all()
    # the textured target: every displacement keeps its source height and lean angle
    D = apply_texture(Vd, Fd, out) - Vd
    np.testing.assert_allclose(np.linalg.norm(D, axis=1), np.abs(out.height), atol=1e-12)
    assert "elements" in "\n".join(rep.lines())


def test_transfer_between_shapes_onto_a_rotated_copy_follows_the_rotation():
    # a texture moved onto a rotated and re-meshed copy of its own base lands where
    # the rotation takes it: the carried lean directions are the rotated ones
    from geotex.heighttilt import spiky_sphere
    from geotex.heighttilt.transfer import transfer_between_shapes
    V0, F, Vs = spiky_sphere(subdivisions=4, spikes=6, width=0.35, height=0.3,
                             lean_degrees=40.0, seed=4)
    stretch = np.array([1.0, 0.8, 1.5])
    Vs, V0 = Vs * stretch, Vs * stretch + (V0 - Vs)   # an ellipsoid base, asymmetric axes
    Vs = Vs + 0.25 * Vs[:, [2]] ** 2 * np.array([[1.0, 0.0, 0.0]])   # and no mirror symmetry
    V0 = Vs + (V0 - Vs)
    tex, _ = extract_texture(V0, F, base=Vs)
    q = np.random.default_rng(1).normal(size=4)
    a, b, c, d = q / np.linalg.norm(q)
    R = np.array([[a*a + b*b - c*c - d*d, 2*(b*c - a*d), 2*(b*d + a*c)],
                  [2*(b*c + a*d), a*a - b*b + c*c - d*d, 2*(c*d - a*b)],
                  [2*(b*d - a*c), 2*(c*d + a*b), a*a - b*b - c*c + d*d]])
    out, rep = transfer_between_shapes(Vs, F, tex, Vs @ R.T, F)
    np.testing.assert_allclose(out.height, tex.height, atol=1e-6)
    np.testing.assert_allclose(apply_texture(Vs @ R.T, F, out), V0 @ R.T, atol=1e-3)


def test_transfer_between_shapes_input_errors():
    from geotex.heighttilt import spiky_sphere
    from geotex.heighttilt.transfer import transfer_between_shapes
    from geotex.mesh.primitives import torus
    V0, F, Vs = spiky_sphere(subdivisions=2, spikes=4, seed=0)
    tex, _ = extract_texture(V0, F, base=Vs)
    with pytest.raises(InputError, match="genus"):
        transfer_between_shapes(Vs, F, tex, *torus(n_major=12, n_minor=8))
    Vd, Fd = _ellipsoid(2)
    with pytest.raises(InputError, match="landmarks"):
        transfer_between_shapes(Vs, F, tex, Vd, Fd, landmarks=[[[0, 0, 1], [0, 0, 2]]])
    with pytest.raises(InputError, match="landmarks"):
        transfer_between_shapes(Vs, F, tex, Vd, Fd, landmarks=[[0, 0, 1], [0, 0, 2]])
    out, rep = transfer_between_shapes(Vs, F, tex, Vd, Fd,
                                       landmarks=[[[0, 0, 1], [0, 0, 1.8]], [[1, 0, 0], [1, 0, 0]],
                                                  [[0, 1, 0], [0, 1, 0]]])
    assert rep.aligned_by == "landmarks"
