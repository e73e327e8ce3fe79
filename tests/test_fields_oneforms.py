"""Discrete 1-forms: encoding, Whitney decoding, evaluation, line integrals."""

import igl
import numpy as np
import pytest
from scipy.optimize import lsq_linear

from geotex.errors import InputError
from geotex.fields.oneforms import (circulation, decode_one_form, decode_one_form_at_vertices,
                                    encode_one_form, evaluate_one_form, exterior_derivative,
                                    integrate_edges, line_integrals, segment_samples,
                                    whitney_corner_vectors)
from geotex.mesh.primitives import grid_plane, icosphere, torus
from geotex.mesh.topology import edge_topology


def tilted_plane(nx=9, ny=7, *, jitter=0.25, seed=0):
    """A jittered planar grid embedded in a tilted plane; returns V, F, unit normal, basis."""
    V, F = grid_plane(nx, ny, size=(1.3, 0.9))
    rng = np.random.default_rng(seed)
    h = 1.3 / nx
    inner = (V[:, 0] > 0) & (V[:, 0] < 1.3 - 1e-9) & (V[:, 1] > 0) & (V[:, 1] < 0.9 - 1e-9)
    V[inner, :2] += rng.uniform(-jitter * h, jitter * h, size=(inner.sum(), 2))
    u = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])
    w = np.cross(u, [0.0, 0.0, 1.0])
    w /= np.linalg.norm(w)
    n = np.cross(u, w)
    P = V[:, :1] * u + V[:, 1:2] * w + np.array([0.3, -0.2, 1.1])
    return P, F, n, (u, w)


def edge_vectors(V, F):
    E = edge_topology(F, len(V)).edges
    return E, V[E[:, 1]] - V[E[:, 0]]


def vertex_normals(V, F):
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    acc = np.zeros_like(V)
    for k in range(3):
        np.add.at(acc, F[:, k], N)
    return acc / np.linalg.norm(acc, axis=1, keepdims=True)


CURVED = [icosphere(3), torus(1.0, 0.35, n_major=24, n_minor=12)]


# ---------------------------------------------------------------- round trips

@pytest.mark.parametrize("flat", [False, True])
def test_constant_field_round_trip_on_planar_mesh(flat):
    if flat:
        V, F = grid_plane(8, 5)
        u, w = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    else:
        V, F, _, (u, w) = tilted_plane()
    X = 0.37 * u - 0.81 * w
    for at, rows in (("faces", len(F)), ("vertices", len(V))):
        c = encode_one_form(V, F, np.tile(X, (rows, 1)), at=at)
        assert np.abs(decode_one_form(V, F, c) - X).max() < 1e-12
        assert np.abs(decode_one_form_at_vertices(V, F, c) - X).max() < 1e-12
        assert np.abs(decode_one_form_at_vertices(V, F, c, weighting="area") - X).max() < 1e-12


def test_normal_component_is_ignored():
    V, F, n, (u, w) = tilted_plane()
    X = 0.2 * u + 0.5 * w
    c1 = encode_one_form(V, F, np.tile(X + 3.0 * n, (len(F), 1)), bound=False)
    c2 = encode_one_form(V, F, np.tile(X - 2.0 * n, (len(V), 1)), at="vertices", bound=False)
    assert np.abs(decode_one_form(V, F, c1) - X).max() < 1e-12
    assert np.abs(decode_one_form(V, F, c2) - X).max() < 1e-12


@pytest.mark.parametrize("mesh", CURVED)
def test_gradient_of_linear_function_encodes_to_differences(mesh):
    V, F = mesh
    a = np.array([0.3, -0.45, 0.6])
    f = V @ a
    c = encode_one_form(V, F, np.tile(a, (len(F), 1)))
    assert np.abs(c - exterior_derivative(F, f)).max() < 1e-14
    E, _ = edge_vectors(V, F)
    assert np.abs(c - (f[E[:, 1]] - f[E[:, 0]])).max() < 1e-14
    assert np.abs(circulation(F, c)).max() < 1e-14


@pytest.mark.parametrize("mesh", CURVED)
def test_gradient_of_piecewise_linear_function_is_exact_and_closed(mesh):
    V, F = mesh
    g = np.sin(3 * V[:, 0]) + V[:, 1] * V[:, 2]
    G = (igl.grad(V, F) @ g).reshape(3, -1).T            # per-face gradient (m, 3)
    c = encode_one_form(V, F, G, bound=False)
    assert np.abs(c - exterior_derivative(F, g)).max() < 1e-12
    assert np.abs(circulation(F, c)).max() < 1e-12
    # Whitney decoding of an exact 1-form gives back the face gradients
    assert np.abs(decode_one_form(V, F, c) - G).max() < 1e-10 * np.abs(G).max()


def test_vertex_encoding_of_gradient_on_planar_mesh_is_exact():
    V, F, _, (u, w) = tilted_plane(seed=3)
    a = 0.4 * u - 0.7 * w
    c = encode_one_form(V, F, np.tile(a, (len(V), 1)), at="vertices")
    assert np.abs(c - exterior_derivative(F, V @ a)).max() < 1e-13


def test_face_encoding_is_per_edge_average():
    V, F = icosphere(1)
    rng = np.random.default_rng(1)
    X = rng.normal(size=(len(F), 3))
    c = encode_one_form(V, F, X, bound=False)
    topo = edge_topology(F, len(V))
    expect = np.zeros(len(topo.edges))
    count = np.zeros(len(topo.edges))
    for f in range(len(F)):
        for k in range(3):
            a, b = F[f, k], F[f, (k + 1) % 3]
            e = topo.half_to_edge[3 * f + k]
            lo, hi = min(a, b), max(a, b)
            expect[e] += X[f] @ (V[hi] - V[lo])
            count[e] += 1
    assert np.allclose(c, expect / count, rtol=0, atol=1e-14)


# ---------------------------------------------------------------- vertex least squares

def _reference_operator(V, F, weighting="uniform"):
    """Columns = vertex decode of unit 1-forms, projected on vertex tangent planes."""
    E, _ = edge_vectors(V, F)
    cols = []
    for e in range(len(E)):
        c = np.zeros(len(E))
        c[e] = 1.0
        cols.append(decode_one_form_at_vertices(V, F, c, weighting=weighting))
    M = np.stack(cols, axis=-1)                              # (n, 3, e)
    nv = vertex_normals(V, F)
    M = M - nv[:, :, None] * np.einsum("nd,nde->ne", nv, M)[:, None, :]
    return M.reshape(-1, len(E))


@pytest.mark.parametrize("scale, bound", [(0.8, False), (0.8, True), (2.5, True), (1.5, 0.7)])
def test_vertex_encoding_solves_the_documented_least_squares(scale, bound):
    V, F = icosphere(2)
    damping = 1e-2
    E, ev = edge_vectors(V, F)
    X = scale * np.stack([np.sin(3 * V[:, 1]), np.cos(2 * V[:, 0]), V[:, 0] * V[:, 1]], 1)
    nv = vertex_normals(V, F)
    Xt = X - nv * (X * nv).sum(1, keepdims=True)
    c0 = 0.5 * ((Xt[E[:, 0]] + Xt[E[:, 1]]) * ev).sum(1)
    M = _reference_operator(V, F)
    reg = np.sqrt(damping * (M * M).sum(0))
    A = np.vstack([M, np.diag(reg)])
    rhs = np.concatenate([Xt.ravel(), reg * c0])
    L = np.linalg.norm(ev, axis=1)
    beta = {False: None, True: 1.0}.get(bound, bound)
    if beta is None:
        ref = np.linalg.lstsq(A, rhs, rcond=None)[0]
    else:
        ref = lsq_linear(A, rhs, bounds=(-beta * L, beta * L), method="bvls", tol=1e-14).x
    c = encode_one_form(V, F, X, at="vertices", bound=bound, damping=damping)
    assert np.abs(c - ref).max() < 1e-6 * np.abs(ref).max()
    if beta is not None:
        assert np.all(np.abs(c) <= beta * L)
        if scale > 1:
            assert np.sum(np.abs(c) == beta * L) > len(E) // 4     # the bound is active


def test_vertex_least_squares_beats_local_encoding_on_curved_mesh():
    V, F = torus(1.0, 0.35, n_major=40, n_minor=20)
    X = np.stack([np.sin(3 * V[:, 1]), np.cos(2 * V[:, 0]), V[:, 0] * V[:, 1]], 1)
    nv = vertex_normals(V, F)
    Xt = X - nv * (X * nv).sum(1, keepdims=True)
    E, ev = edge_vectors(V, F)
    c0 = 0.5 * ((Xt[E[:, 0]] + Xt[E[:, 1]]) * ev).sum(1)

    def tangential_error(c):
        r = decode_one_form_at_vertices(V, F, c) - Xt
        r -= nv * (r * nv).sum(1, keepdims=True)
        return np.linalg.norm(r) / np.linalg.norm(Xt)

    c = encode_one_form(V, F, X, at="vertices", bound=False)
    assert tangential_error(c) < tangential_error(c0) / 10
    finer = encode_one_form(V, F, X, at="vertices", bound=False, damping=1e-4)
    assert tangential_error(finer) < tangential_error(c)


def test_huge_field_respects_bound_exactly():
    V, F = torus(1.0, 0.35, n_major=30, n_minor=14)
    E, ev = edge_vectors(V, F)
    L = np.linalg.norm(ev, axis=1)
    rng = np.random.default_rng(2)
    Xf = 1e6 * rng.normal(size=(len(F), 3))
    Xv = 1e6 * rng.normal(size=(len(V), 3))
    for at, X in (("faces", Xf), ("vertices", Xv)):
        c = encode_one_form(V, F, X, at=at)
        assert np.all(np.abs(c) <= L)
        c = encode_one_form(V, F, X, at=at, bound=0.25)
        assert np.all(np.abs(c) <= 0.25 * L)
        assert np.abs(encode_one_form(V, F, X, at=at, bound=False)).max() > 1e3 * L.max()
    # a field of magnitude <= 1 encoded per face is untouched by the bound
    unit = Xf / np.linalg.norm(Xf, axis=1, keepdims=True)
    assert np.array_equal(encode_one_form(V, F, unit), encode_one_form(V, F, unit, bound=False))


# ---------------------------------------------------------------- evaluation

def test_evaluate_constant_field_at_random_points():
    V, F, _, (u, w) = tilted_plane(seed=5)
    X = -0.3 * u + 0.9 * w
    c = encode_one_form(V, F, np.tile(X, (len(F), 1)))
    rng = np.random.default_rng(0)
    faces = rng.integers(0, len(F), 500)
    bary = rng.dirichlet([1, 1, 1], 500)
    assert np.abs(evaluate_one_form(V, F, c, faces, bary) - X).max() < 1e-12


@pytest.mark.parametrize("mesh", CURVED)
def test_evaluate_matches_corner_formula_and_paper_formula(mesh):
    V, F = mesh
    topo = edge_topology(F, len(V))
    E = topo.edges
    rng = np.random.default_rng(4)
    c = rng.normal(size=len(E)) * 0.05
    T = whitney_corner_vectors(V, F, c, topology=topo)
    faces = np.arange(len(F))
    for k in range(3):
        bary = np.zeros((len(F), 3))
        bary[:, k] = 1.0
        assert np.array_equal(evaluate_one_form(V, F, c, faces, bary, topology=topo), T[:, k])
    cen = evaluate_one_form(V, F, c, faces, np.full((len(F), 3), 1 / 3))
    assert np.abs(cen - decode_one_form(V, F, c)).max() < 1e-13
    # the paper's point formula, written out independently with rotated edges
    idx = rng.integers(0, len(F), 200)
    al = rng.dirichlet([1, 1, 1], 200)
    i, j, k = F[idx, 0], F[idx, 1], F[idx, 2]
    key = {(a, b): e for e, (a, b) in enumerate(E.tolist())}

    def coef(a, b):
        return np.array([c[key[(min(x, y), max(x, y))]] * (1 if x < y else -1)
                         for x, y in zip(a, b)])

    cij, cjk, cki = coef(i, j), coef(j, k), coef(k, i)
    N = np.cross(V[j] - V[i], V[k] - V[i])
    A2 = np.linalg.norm(N, axis=1)
    n = N / A2[:, None]

    def perp(e):
        return np.cross(n, e)

    paper = ((cki * al[:, 2] - cij * al[:, 1])[:, None] * perp(V[k] - V[j])
             + (cij * al[:, 0] - cjk * al[:, 2])[:, None] * perp(V[i] - V[k])
             + (cjk * al[:, 1] - cki * al[:, 0])[:, None] * perp(V[j] - V[i])) / A2[:, None]
    ours = evaluate_one_form(V, F, c, idx, al)
    assert np.abs(ours - paper).max() < 1e-12 * np.abs(paper).max()
    # vertex decode = uniform mean of the corner vectors
    Xv = decode_one_form_at_vertices(V, F, c)
    acc = np.zeros_like(V)
    cnt = np.zeros(len(V))
    for kk in range(3):
        np.add.at(acc, F[:, kk], T[:, kk])
        np.add.at(cnt, F[:, kk], 1)
    assert np.abs(Xv - acc / cnt[:, None]).max() < 1e-13


def test_whitney_field_integrates_to_the_coefficients_along_face_edges():
    V, F = icosphere(2)
    topo = edge_topology(F, len(V))
    c = np.random.default_rng(7).normal(size=len(topo.edges))
    q = 3
    t, _ = np.polynomial.legendre.leggauss(q)
    t = 0.5 * (t + 1)
    for k in range(3):
        # points along half-edge k of every face: phi_k = 1 - t, phi_{k+1} = t
        bary = np.zeros((len(F), q, 3))
        bary[:, :, k] = 1 - t
        bary[:, :, (k + 1) % 3] = t
        faces = np.repeat(np.arange(len(F)), q)
        vals = evaluate_one_form(V, F, c, faces, bary.reshape(-1, 3)).reshape(len(F), q, 3)
        a, b = F[:, k], F[:, (k + 1) % 3]
        got = line_integrals(vals, V[a], V[b], samples=q)
        sign = np.where(a < b, 1.0, -1.0)
        assert np.abs(got - sign * c[topo.half_to_edge[3 * np.arange(len(F)) + k]]).max() < 1e-12


def test_decode_is_independent_of_face_orientation():
    V, F = icosphere(2)
    c = np.random.default_rng(8).normal(size=len(edge_topology(F, len(V)).edges))
    G = F.copy()
    G[::3] = G[::3, ::-1]
    assert np.allclose(decode_one_form(V, G, c), decode_one_form(V, F, c), atol=1e-14)
    assert np.allclose(decode_one_form_at_vertices(V, G, c),
                       decode_one_form_at_vertices(V, F, c), atol=1e-14)


def test_degenerate_face_decodes_to_zero():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], dtype=float)
    F = np.array([[0, 1, 2], [0, 3, 1]])                      # second face is flat
    c = encode_one_form(V, F, np.tile([0.5, 0.25, 0.0], (2, 1)))
    X = decode_one_form(V, F, c)
    assert np.allclose(X[0], [0.5, 0.25, 0.0], atol=1e-15) and np.all(X[1] == 0)
    Xv = decode_one_form_at_vertices(V, F, c)
    assert np.allclose(Xv[:3], [0.5, 0.25, 0.0], atol=1e-15) and np.all(Xv[3] == 0)


@pytest.mark.parametrize("s", [1e-6, 1e6])
def test_scaling_the_mesh(s):
    V, F = icosphere(2)
    X = np.random.default_rng(9).normal(size=(len(F), 3))
    c = encode_one_form(V, F, X, bound=False)
    cs = encode_one_form(s * V, F, X, bound=False)
    assert np.allclose(cs, s * c, rtol=1e-12, atol=0)
    assert np.allclose(decode_one_form(s * V, F, cs), decode_one_form(V, F, c), rtol=1e-10,
                       atol=1e-12)
    Xv = np.random.default_rng(9).normal(size=(len(V), 3))
    cv = encode_one_form(V, F, Xv, at="vertices", bound=False)
    cvs = encode_one_form(s * V, F, Xv, at="vertices", bound=False)
    assert np.allclose(cvs, s * cv, rtol=1e-7, atol=1e-9 * s * np.abs(cv).max())


# ---------------------------------------------------------------- line integrals

@pytest.mark.parametrize("rule", ["gauss", "trapezoid"])
def test_line_integrals_exact_for_linear_field(rule):
    rng = np.random.default_rng(10)
    A = rng.normal(size=(3, 3))
    b = rng.normal(size=3)
    P0 = rng.normal(size=(100, 3))
    P1 = rng.normal(size=(100, 3))
    calls = []

    def field(p):
        calls.append(p.shape)
        return p @ A.T + b

    got = line_integrals(field, P0, P1, samples=5, rule=rule)
    d = P1 - P0
    exact = np.einsum("sd,sd->s", (P0 + 0.5 * d) @ A.T + b, d)
    assert np.abs(got - exact).max() < 1e-13 * np.abs(exact).max()
    assert calls == [(500, 3)]


def test_line_integral_of_gradient_is_potential_difference():
    rng = np.random.default_rng(11)
    S = rng.normal(size=(3, 3))

    def phi(p):                    # cubic potential: gradient is quadratic
        return (p @ S * p).sum(1) * p[:, 0] + p[:, 1]

    def grad(p):
        Sp = p @ (S + S.T)
        g = Sp * p[:, :1]
        g[:, 0] += (p @ S * p).sum(1)
        g[:, 1] += 1.0
        return g

    P0 = rng.normal(size=(50, 3))
    P1 = rng.normal(size=(50, 3))
    exact = phi(P1) - phi(P0)
    for q in (2, 5):               # Gauss with q points: exact up to degree 2q - 1
        assert np.abs(line_integrals(grad, P0, P1, samples=q) - exact).max() < 1e-12 * \
            np.abs(exact).max()
    trap = line_integrals(grad, P0, P1, samples=5, rule="trapezoid")
    assert np.abs(trap - exact).max() > 1e-6          # trapezoid is only exact for linear


def test_segment_samples_layout():
    P0 = np.array([[0.0, 0, 0], [1, 1, 1]])
    P1 = np.array([[1.0, 0, 0], [1, 1, 3]])
    pts, w = segment_samples(P0, P1, samples=3, rule="trapezoid")
    assert pts.shape == (2, 3, 3) and np.allclose(w, [0.25, 0.5, 0.25])
    assert np.allclose(pts[0, :, 0], [0, 0.5, 1]) and np.allclose(pts[1, :, 2], [1, 2, 3])
    pts, w = segment_samples(P0, P1, samples=5)
    assert np.isclose(w.sum(), 1.0) and np.all((pts[0, :, 0] > 0) & (pts[0, :, 0] < 1))


def test_integrate_edges_of_constant_field_matches_face_encoding():
    V, F = torus(1.0, 0.35, n_major=20, n_minor=10)
    a = np.array([0.2, 0.5, -0.3])
    c = integrate_edges(V, F, lambda p: np.tile(a, (len(p), 1)))
    assert np.abs(c - encode_one_form(V, F, np.tile(a, (len(F), 1)))).max() < 1e-14
    E, ev = edge_vectors(V, F)
    big = integrate_edges(V, F, lambda p: np.tile(100 * a, (len(p), 1)), bound=True)
    assert np.all(np.abs(big) <= np.linalg.norm(ev, axis=1))


# ---------------------------------------------------------------- determinism, inputs, errors

def test_deterministic_and_inputs_untouched():
    V, F = torus(1.0, 0.35, n_major=24, n_minor=12)
    rng = np.random.default_rng(12)
    Xv = 2 * rng.normal(size=(len(V), 3))
    Xf = rng.normal(size=(len(F), 3))
    for arr in (V, F, Xv, Xf):
        arr.setflags(write=False)
    copies = [x.copy() for x in (V, F, Xv, Xf)]
    r1 = encode_one_form(V, F, Xv, at="vertices")
    r2 = encode_one_form(V, F, Xv, at="vertices")
    assert r1.tobytes() == r2.tobytes()
    c = encode_one_form(V, F, Xf)
    c.setflags(write=False)
    out = [decode_one_form(V, F, c), decode_one_form_at_vertices(V, F, c),
           evaluate_one_form(V, F, c, np.arange(5), np.full((5, 3), 1 / 3)),
           circulation(F, c)]
    again = [decode_one_form(V, F, c), decode_one_form_at_vertices(V, F, c),
             evaluate_one_form(V, F, c, np.arange(5), np.full((5, 3), 1 / 3)),
             circulation(F, c)]
    assert all(a.tobytes() == b.tobytes() for a, b in zip(out, again))
    for arr, ref in zip((V, F, Xv, Xf), copies):
        assert np.array_equal(arr, ref)


def test_topology_reuse_and_mismatch():
    V, F = icosphere(2)
    topo = edge_topology(F, len(V))
    X = np.random.default_rng(13).normal(size=(len(F), 3))
    c = encode_one_form(V, F, X, topology=topo)
    assert np.array_equal(c, encode_one_form(V, F, X))
    assert np.array_equal(decode_one_form(V, F, c, topology=topo), decode_one_form(V, F, c))
    V2, F2 = icosphere(1)
    with pytest.raises(InputError, match="topology does not belong to F"):
        decode_one_form(V2, F2, np.zeros(len(edge_topology(F2).edges)), topology=topo)


def test_errors():
    V, F = icosphere(1)
    e = len(edge_topology(F, len(V)).edges)
    Xf = np.zeros((len(F), 3))
    with pytest.raises(InputError, match=r"vectors must have shape \(80, 3\), one vector per face"):
        encode_one_form(V, F, np.zeros((len(V), 3)))
    with pytest.raises(InputError, match="one vector per vertex"):
        encode_one_form(V, F, Xf, at="vertices")
    with pytest.raises(InputError, match="vectors has non-finite"):
        encode_one_form(V, F, np.full((len(F), 3), np.nan))
    with pytest.raises(InputError, match="at must be"):
        encode_one_form(V, F, Xf, at="edges")
    with pytest.raises(InputError, match="bound must be"):
        encode_one_form(V, F, Xf, bound=-1.0)
    with pytest.raises(InputError, match="damping must be a positive"):
        encode_one_form(V, F, Xf, damping=0.0)
    with pytest.raises(InputError, match="weighting must be"):
        decode_one_form_at_vertices(V, F, np.zeros(e), weighting="angle")
    with pytest.raises(InputError, match=rf"c must have shape \({e},\)"):
        decode_one_form(V, F, np.zeros(e + 1))
    with pytest.raises(InputError, match="c has non-finite"):
        decode_one_form(V, F, np.full(e, np.inf))
    with pytest.raises(InputError, match="faces has indices outside"):
        evaluate_one_form(V, F, np.zeros(e), [len(F)], [[1, 0, 0]])
    with pytest.raises(InputError, match="bary rows must sum to 1"):
        evaluate_one_form(V, F, np.zeros(e), [0], [[1, 1, 0]])
    with pytest.raises(InputError, match=r"bary must have shape \(2, 3\)"):
        evaluate_one_form(V, F, np.zeros(e), [0, 1], [[1, 0, 0]])
    with pytest.raises(InputError, match="F references vertex indices"):
        decode_one_form(V, F + 100, np.zeros(e))
    P = np.zeros((2, 3))
    with pytest.raises(InputError, match="P0 and P1 must have the same shape"):
        line_integrals(lambda p: p, P, np.zeros((3, 3)))
    with pytest.raises(InputError, match=r"field returned shape \(10, 2\)"):
        line_integrals(lambda p: p[:, :2], P, P)
    with pytest.raises(InputError, match=r"field values must have shape \(2, 5, 3\)"):
        line_integrals(np.zeros((2, 4, 3)), P, P)
    with pytest.raises(InputError, match="field has non-finite"):
        line_integrals(lambda p: p * np.nan, P, P)
    with pytest.raises(InputError, match="rule must be"):
        line_integrals(lambda p: p, P, P, rule="simpson")
    with pytest.raises(InputError, match="samples must be >= 2"):
        line_integrals(lambda p: p, P, P, samples=1, rule="trapezoid")
    with pytest.raises(InputError, match="samples must be an integer"):
        line_integrals(lambda p: p, P, P, samples=2.5)
    with pytest.raises(InputError, match="values must have shape"):
        exterior_derivative(F, np.zeros((len(V), 2)))
