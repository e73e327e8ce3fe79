"""Sphere maps of closed genus-0 meshes (geotex.param.sphere)."""

import numpy as np
import pytest

from geotex.errors import InputError
from geotex.mesh.primitives import grid_plane, icosphere, torus
from geotex.param.sphere import (aligned_sphere_map, landmark_rotation, point_on_sphere,
                                 principal_frame, sphere_map)


def _pear(sub=3):
    V, F = icosphere(sub)
    r = 1.0 + 0.3 * V[:, 2] + 0.05 * np.sin(3.0 * V[:, 0])
    return V * r[:, None] * np.array([1.0, 0.8, 1.5]), F


def _rotation(seed):
    q = np.random.default_rng(seed).normal(size=4)
    a, b, c, d = q / np.linalg.norm(q)
    return np.array([[a*a + b*b - c*c - d*d, 2*(b*c - a*d), 2*(b*d + a*c)],
                     [2*(b*c + a*d), a*a - b*b + c*c - d*d, 2*(c*d - a*b)],
                     [2*(b*d - a*c), 2*(c*d + a*b), a*a - b*b - c*c + d*d]])


def _angle_error(V, F, S):
    """Mean conformal error (s1/s2 + s2/s1)/2 - 1 of the map V -> S, and flipped faces."""
    def frame2(P):
        e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
        x = e1 / np.linalg.norm(e1, axis=1)[:, None]
        n = np.cross(e1, e2)
        y = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x)
        return np.stack([np.stack([(e1 * x).sum(1), (e2 * x).sum(1)], 1),
                         np.stack([(e1 * y).sum(1), (e2 * y).sum(1)], 1)], 1)
    J = frame2(S[F]) @ np.linalg.inv(frame2(V[F]))
    s = np.linalg.svd(J, compute_uv=False)
    P = S[F]
    flips = int(((np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) * P.mean(1)).sum(1) <= 0).sum())
    return float(np.mean((s[:, 0] / s[:, 1] + s[:, 1] / s[:, 0]) / 2 - 1)), flips


@pytest.mark.parametrize("shape", ["ellipsoid", "pear"])
def test_sphere_map_is_near_conformal_centred_and_unflipped(shape):
    V, F = icosphere(3)
    if shape == "ellipsoid":
        V = V * np.array([1.0, 1.0, 2.0])
    else:
        V, F = _pear()
    S = sphere_map(V, F)
    np.testing.assert_allclose(np.linalg.norm(S, axis=1), 1.0, atol=1e-12)
    err, flips = _angle_error(V, F, S)
    assert flips == 0
    assert err < 0.02                 # measured 0.004 / 0.003 (a similarity gives 0)
    from geotex.mesh.geometry import face_areas
    w = np.bincount(F.ravel(), weights=np.repeat(face_areas(V, F) / 3, 3), minlength=len(V))
    assert np.linalg.norm((w[:, None] * S).sum(0) / w.sum()) < 1e-8


def test_principal_alignment_follows_a_rotated_copy():
    # the pear and a rotated, shifted copy: the aligned sphere maps agree point for point
    V, F = _pear()
    R = _rotation(3)
    S1 = aligned_sphere_map(V, F)
    S2 = aligned_sphere_map(V @ R.T + [1.0, -2.0, 0.5], F)
    assert np.abs(S1 - S2).max() < 1e-6
    c, axes, sigma = principal_frame(V, F)
    assert np.allclose(axes @ axes.T, np.eye(3)) and np.linalg.det(axes) > 0
    assert sigma[0] >= sigma[1] >= sigma[2] > 0


def test_landmarks_fix_the_rotation():
    V, F = _pear()
    S = aligned_sphere_map(V, F)
    R = _rotation(5)
    marks = V[[0, 40, 200, 500]]
    a = point_on_sphere(V, F, S, marks)
    np.testing.assert_allclose(landmark_rotation(a, a @ R.T), R, atol=1e-12)
    with pytest.raises(InputError, match="at least two"):
        landmark_rotation(a[:1], a[:1])
    with pytest.raises(InputError, match="one line"):
        line = np.array([[0, 0, 1.0], [0, 0, -1.0]])
        landmark_rotation(line, line)


def test_sphere_map_rejects_other_topologies():
    with pytest.raises(InputError, match="genus 1"):
        sphere_map(*torus(n_major=12, n_minor=8))
    with pytest.raises(InputError, match="boundary"):
        sphere_map(*grid_plane(4, 4))
    V, F = icosphere(1)
    flipped = F.copy()
    flipped[0] = flipped[0, ::-1]
    with pytest.raises(InputError, match="oriented"):
        sphere_map(V, flipped)
    with pytest.raises(InputError, match="2 components"):
        sphere_map(np.vstack([V, V + 5]), np.vstack([F, F + len(V)]))
