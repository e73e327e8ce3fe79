"""Scalar fields: harmonic interpolation with locked values, clamping, averaging."""

import igl
import numpy as np
import pytest

from geotex.errors import InputError
from geotex.fields.scalar import interpolate_scalar, material_field, scale_field, vertex_to_face
from geotex.mesh.primitives import grid_plane, icosphere, torus


def boundary_vertices(V, size):
    x, y = V[:, 0], V[:, 1]
    return np.flatnonzero(np.isclose(x, 0) | np.isclose(y, 0) | np.isclose(x, size[0])
                          | np.isclose(y, size[1]))


def linear(P):
    return 2.0 * P[:, 0] - 3.0 * P[:, 1] + 0.5


@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_linear_boundary_values_give_linear_interior(jitter):
    size = (1.5, 1.0)
    V, F = grid_plane(30, 20, size=size)
    b = boundary_vertices(V, size)
    if jitter:
        rng = np.random.default_rng(0)
        inner = np.setdiff1d(np.arange(len(V)), b)
        V[inner, :2] += rng.uniform(-jitter, jitter, (inner.size, 2)) * (size[0] / 30)
    u = interpolate_scalar(V, F, b, linear(V[b]))
    assert np.abs(u - linear(V)).max() < 1e-10


def test_harmonic_equation_holds_at_free_vertices(sphere):
    V, F = sphere
    locked = np.array([0, 17, 300, 511])
    vals = np.array([1.0, -2.0, 0.5, 3.0])
    for kind in ("cotan", "uniform"):
        u = interpolate_scalar(V, F, locked, vals, laplacian=kind)
        if kind == "cotan":
            L = igl.cotmatrix(V, F)
        else:
            A = igl.adjacency_matrix(F).astype(float)
            L = A - np.diag(np.asarray(A.sum(1)).ravel())
        r = np.asarray(L @ u).ravel()
        free = np.setdiff1d(np.arange(len(V)), locked)
        assert np.abs(r[free]).max() < 1e-10
        assert np.array_equal(u[locked], vals)


def test_locked_values_reproduced_exactly_and_maximum_principle(ring):
    V, F = ring
    rng = np.random.default_rng(1)
    locked = rng.choice(len(V), 25, replace=False)
    vals = rng.uniform(-3, 7, 25)
    for kind in ("uniform", "cotan"):
        u = interpolate_scalar(V, F, locked, vals, laplacian=kind)
        assert np.array_equal(u[locked], vals)
        if kind == "uniform":   # non-negative weights: the maximum principle holds exactly
            assert u.min() >= vals.min() and u.max() <= vals.max()
    # cotan weights on the (Delaunay) planar grid are non-negative too
    V, F = grid_plane(20, 20)
    locked = rng.choice(len(V), 15, replace=False)
    vals = rng.uniform(0, 1, 15)
    u = interpolate_scalar(V, F, locked, vals)
    assert u.min() >= vals.min() - 1e-14 and u.max() <= vals.max() + 1e-14


def test_duplicate_locks_with_equal_values_are_accepted():
    V, F = icosphere(2)
    a = interpolate_scalar(V, F, [0, 5, 5], [1.0, 2.0, 2.0])
    b = interpolate_scalar(V, F, [5, 0], [2.0, 1.0])
    assert np.array_equal(a, b)


def test_every_component_locked_is_solved_independently():
    V1, F1 = icosphere(2)
    V2, F2 = torus(n_major=16, n_minor=8)
    V = np.vstack([V1, V2 + [5, 0, 0]])
    F = np.vstack([F1, F2 + len(V1)])
    u = interpolate_scalar(V, F, [0, len(V1)], [3.0, -1.0])
    assert np.allclose(u[:len(V1)], 3.0, rtol=0, atol=1e-12)
    assert np.allclose(u[len(V1):], -1.0, rtol=0, atol=1e-12)


def test_clamps_are_honoured():
    V, F = icosphere(3)
    rng = np.random.default_rng(2)
    locked = rng.choice(len(V), 12, replace=False)
    vals = rng.uniform(0, 1, 12)
    raw = interpolate_scalar(V, F, locked, vals)
    lo, hi = np.quantile(vals, [0.1, 0.9])
    vals_in = np.clip(vals, lo, hi)
    clamped = interpolate_scalar(V, F, locked, vals_in, clamp=(lo, hi))
    assert clamped.min() >= lo and clamped.max() <= hi
    assert np.array_equal(clamped, np.clip(interpolate_scalar(V, F, locked, vals_in), lo, hi))
    only_low = interpolate_scalar(V, F, locked, vals, clamp=(0.5 * vals.min(), None))
    assert np.array_equal(only_low, np.maximum(raw, 0.5 * vals.min()))
    m = material_field(V, F, locked, vals)
    assert m.min() >= 0 and m.max() <= 1 and np.array_equal(m, np.clip(raw, 0, 1))
    s = scale_field(V, F, locked, vals + 0.1, epsilon=0.2)
    assert s.min() >= 0.2
    s_default = scale_field(V, F, locked, vals + 0.1)
    assert s_default.min() >= 1e-3 * (vals.max() + 0.1)


def test_material_clamp_catches_cotan_overshoot():
    # very obtuse triangles give negative cotan weights and values outside the locks
    rng = np.random.default_rng(3)
    V, F = grid_plane(12, 12)
    V[:, 1] *= 0.02                      # squash: long thin obtuse triangles
    V[:, :2] += rng.uniform(-0.004, 0.004, (len(V), 2)) * [1, 0.02]
    locked = np.array([0, len(V) - 1, 40, 100])
    vals = np.array([0.0, 1.0, 1.0, 0.0])
    raw = interpolate_scalar(V, F, locked, vals)
    m = material_field(V, F, locked, vals)
    assert np.array_equal(m, np.clip(raw, 0, 1)) and m.min() >= 0 and m.max() <= 1
    assert raw.min() < 0 or raw.max() > 1     # the case the clamp exists for


def test_vertex_to_face():
    V, F = icosphere(1)
    vals = np.arange(len(V), dtype=float) ** 2
    out = vertex_to_face(F, vals)
    assert out.shape == (len(F),) and np.allclose(out, vals[F].mean(1), rtol=0, atol=1e-12)
    vec = np.stack([vals, -vals], 1)
    assert np.allclose(vertex_to_face(F, vec), vec[F].mean(1), rtol=0, atol=1e-12)
    with pytest.raises(InputError, match="F references vertex indices"):
        vertex_to_face(F, vals[:5])
    with pytest.raises(InputError, match="values must have one row per vertex"):
        vertex_to_face(F, 1.0)


def test_deterministic_and_inputs_untouched():
    V, F = icosphere(3)
    locked = np.array([3, 99, 400])
    vals = np.array([0.2, 0.9, 0.4])
    for arr in (V, F, locked, vals):
        arr.setflags(write=False)
    a = material_field(V, F, locked, vals)
    b = material_field(V, F, locked, vals)
    assert a.tobytes() == b.tobytes()
    assert np.array_equal(locked, [3, 99, 400]) and np.array_equal(vals, [0.2, 0.9, 0.4])


def test_errors():
    V, F = icosphere(1)
    n = len(V)
    with pytest.raises(InputError, match=rf"locked_vertices has index {n} outside \[0, {n}\)"):
        interpolate_scalar(V, F, [0, n], [1.0, 2.0])
    with pytest.raises(InputError, match="locked_values has 1 entries but locked_vertices has 2"):
        interpolate_scalar(V, F, [0, 1], [1.0])
    with pytest.raises(InputError, match="locked_values has a non-finite value"):
        interpolate_scalar(V, F, [0, 1], [1.0, np.nan])
    with pytest.raises(InputError, match="vertex 1 more than once with different values"):
        interpolate_scalar(V, F, [1, 1], [1.0, 2.0])
    with pytest.raises(InputError, match="locked_vertices must hold integer"):
        interpolate_scalar(V, F, [0.5], [1.0])
    with pytest.raises(InputError, match="laplacian must be"):
        interpolate_scalar(V, F, [0], [1.0], laplacian="graph")
    with pytest.raises(InputError, match="clamp must satisfy low <= high"):
        interpolate_scalar(V, F, [0], [1.0], clamp=(1.0, 0.0))
    with pytest.raises(InputError, match="outside clamp"):
        interpolate_scalar(V, F, [0], [5.0], clamp=(0.0, 1.0))
    with pytest.raises(InputError, match="component 0 .* has no locked vertex"):
        interpolate_scalar(V, F, [], [])
    V2, F2 = torus(n_major=8, n_minor=4)
    VV = np.vstack([V, V2 + 5])
    FF = np.vstack([F, F2 + n])
    with pytest.raises(InputError, match=rf"component 1 \({len(V2)} vertices, e.g. vertex {n}\) "
                                         "has no locked vertex"):
        interpolate_scalar(VV, FF, [0], [1.0])
    with pytest.raises(InputError, match=f"vertex {n} is used by no face and is not locked"):
        interpolate_scalar(np.vstack([V, [[9.0, 9, 9]]]), F, [0], [1.0])
    assert interpolate_scalar(np.vstack([V, [[9.0, 9, 9]]]), F, [0, n], [1.0, 4.0])[n] == 4.0
    with pytest.raises(InputError, match="epsilon must be a positive number"):
        scale_field(V, F, [0], [1.0], epsilon=0.0)
    with pytest.raises(InputError, match="epsilon must be a positive number"):
        scale_field(V, F, [0], [1.0], epsilon=-1e-3)
    with pytest.raises(InputError, match="is below epsilon"):
        scale_field(V, F, [0, 1], [1.0, 1e-5], epsilon=1e-3)
    with pytest.raises(InputError, match="needs positive values"):
        scale_field(V, F, [0], [-1.0])
    with pytest.raises(InputError, match="outside clamp"):
        material_field(V, F, [0, 1], [0.5, 1.5])
    bad = V.copy()
    bad[F[0, 1]] = bad[F[0, 0]]                         # collapse a triangle
    with pytest.raises(InputError, match="cotangent Laplacian is not finite"):
        interpolate_scalar(bad, F, [0], [1.0])
