"""Per-fit helpers of hierarchical pattern mapping (hpm_faces, hpm_kernels, hpm_fit)."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from geotex.image.fftmatch import opponent_colors
from geotex.image.hpm_state import _State
from geotex.image.hpm_fit import _relax, _rigid_fit
from geotex.image.hpm_kernels import _relax_error_compiled, _sample, _window_minima
from geotex.image.hpm_faces import field_coefficients, textured_band, vertex_faces
from geotex.mesh import edge_topology
from geotex.mesh.primitives import torus


@pytest.fixture(scope="module")
def mesh():
    V, F = torus(1.0, 0.4, n_major=40, n_minor=14)
    rng = np.random.default_rng(3)
    return V + rng.normal(scale=0.01, size=V.shape), F


def test_vertex_faces_lists_every_face_under_its_corners(mesh):
    V, F = mesh
    ptr, faces = vertex_faces(F, len(V))
    assert ptr[0] == 0 and ptr[-1] == 3 * len(F)
    for v in (0, 7, len(V) - 1):
        got = faces[ptr[v]:ptr[v + 1]]
        assert np.array_equal(got, np.flatnonzero((F == v).any(axis=1)))


def test_textured_band_equals_the_scipy_search(mesh):
    V, F = mesh
    E = edge_topology(F, len(V)).edges
    ew = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    G = sp.csr_matrix((np.concatenate([ew, ew]), (np.concatenate([E[:, 0], E[:, 1]]),
                                                  np.concatenate([E[:, 1], E[:, 0]]))),
                      shape=(len(V),) * 2)
    graph = (G.indptr.astype(np.int64), G.indices.astype(np.int64), G.data)
    vf = vertex_faces(F, len(V))
    rng = np.random.default_rng(0)
    sizes = []
    for _ in range(200):
        done = rng.random(len(F)) < rng.random()
        src = np.unique(F[rng.integers(len(F), size=rng.integers(1, 5))])
        limit = rng.uniform(0.0, 0.6)
        ref = np.flatnonzero(done & np.isfinite(dijkstra(
            G, directed=True, indices=src, min_only=True, limit=limit))[F].all(axis=1))
        got = textured_band(graph, src, limit, vf, F, done)
        assert got.dtype == np.int64 and np.array_equal(got, ref)
        sizes.append(got.size)
    assert min(sizes) == 0 and max(sizes) > 50          # empty and wide bands were drawn


def test_field_coefficients_are_the_per_fit_solve(mesh):
    V, F = mesh
    rng = np.random.default_rng(1)
    fvec = rng.normal(size=F.shape)
    coef = field_coefficients(V, F, fvec)
    assert coef.shape == (len(F), 2, 1)
    for _ in range(50):
        faces = rng.integers(len(F), size=rng.integers(1, 40))
        P = V[F[faces]]
        E = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]], axis=2)
        G = np.einsum("kji,kjl->kil", E, E)
        G = G + 1e-12 * np.trace(G, axis1=1, axis2=2)[:, None, None] * np.eye(2)
        ref = np.linalg.solve(G, np.einsum("kji,kj->ki", E, fvec[faces])[:, :, None])
        assert coef[faces].tobytes() == ref.tobytes()
    # the field vector in the face's plane is E coef
    E0 = np.stack([V[F[0, 1]] - V[F[0, 0]], V[F[0, 2]] - V[F[0, 0]]], axis=1)
    n = np.cross(E0[:, 0], E0[:, 1])
    n /= np.linalg.norm(n)
    assert np.allclose(E0 @ coef[0, :, 0], fvec[0] - n * (fvec[0] @ n))
    # a face collapsed to a point has no direction (and no singular solve)
    Vc = np.vstack([V, V[:1], V[:1], V[:1]])
    Fc = np.vstack([F, [[len(V), len(V) + 1, len(V) + 2]]])
    c2 = field_coefficients(Vc, Fc, np.vstack([fvec, [[1.0, 0.0, 0.0]]]))
    assert np.array_equal(c2[-1], np.zeros((2, 1))) and np.array_equal(c2[:-1], coef)


def test_compiled_relaxation_error_equals_the_numpy_path():
    rng = np.random.default_rng(0)
    full = opponent_colors(rng.random((37, 51, 3)))
    ts = np.array([0.0, 0.25, 0.5, 0.75])
    for _ in range(100):
        nv, ne = int(rng.integers(1, 6)), int(rng.integers(1, 20))
        owner = rng.integers(nv, size=ne)
        b = rng.uniform(-3.0, 55.0, (ne, 2))
        cand = rng.uniform(-3.0, 55.0, (nv, 2))
        target = rng.normal(size=(ne * ts.size, 3))
        x = cand[owner][:, None, :] * (1 - ts)[None, :, None] + b[:, None, :] * ts[None, :, None]
        d = _sample(full, x.reshape(-1, 2)) - target
        per = np.sum(d * d, axis=1) * np.broadcast_to((1 - ts)[None, :], x.shape[:2]).ravel()
        ref = np.bincount(np.repeat(owner, ts.size), weights=per, minlength=nv)
        assert _relax_error_compiled(full, cand, owner, b, target, ts, nv).tobytes() == \
            ref.tobytes()


def test_compiled_relaxation_search_equals_the_numpy_loop(mesh):
    # the greedy search of the edge relaxation in one compiled loop: the same moves (and
    # the same random stream) as the numpy loop, on a cluster next to a textured region
    V, F = mesh
    rng = np.random.default_rng(2)
    full = opponent_colors(rng.random((64, 64, 3)))
    m = len(F)
    done = np.arange(m // 2)
    corner = V[F[done]][:, :, :2] * 20.0 + 30.0
    st = _State(V, F, m)
    st.mark(F, done, corner, 0, 0)
    faces = np.arange(m // 2, m // 2 + 60)
    verts = np.unique(F[faces])
    P = V[verts][:, :2] * 20.0 + 30.0 + rng.normal(scale=0.4, size=(verts.size, 2))
    movable = st.vcnt[verts] > 0
    assert movable.sum() >= 5
    for f in (1.0, 3.0):
        slow = _relax(P, verts, faces, movable, F, st, full, np.random.default_rng(5), f)
        fast = _relax(P, verts, faces, movable, F, st, full, np.random.default_rng(5), f,
                      fast=True)
        assert fast.tobytes() == slow.tobytes()
        assert not np.array_equal(slow, P) and np.array_equal(slow[~movable], P[~movable])


def test_rigid_fit_is_the_svd_rotation():
    # the closed-form 2 x 2 Kabsch rotation equals the SVD's V U^T where that is a
    # rotation, and gives None where it is a reflection
    rng = np.random.default_rng(7)
    kept = refused = 0
    for _ in range(300):
        X = rng.normal(size=(int(rng.integers(3, 15)), 2))
        th = rng.uniform(-np.pi, np.pi)
        R0 = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        Y = X @ R0.T + rng.normal(size=2) + 0.3 * rng.normal(size=X.shape)
        if rng.random() < 0.3:
            Y[:, 0] *= -1.0
        xm, ym = X.mean(axis=0), Y.mean(axis=0)
        U, _, Wt = np.linalg.svd((X - xm).T @ (Y - ym))
        R = (U @ Wt).T
        got = _rigid_fit(X, Y)
        if np.linalg.det(R) > 0:
            kept += 1
            assert got is not None
            assert np.allclose(got[0], R, atol=1e-12)
            assert np.allclose(got[1], ym - R @ xm, atol=1e-12)
        else:
            refused += 1
            assert got is None
    assert kept > 100 and refused > 30
    # no direction at all: None
    assert _rigid_fit(np.zeros((4, 2)), np.ones((4, 2))) is None


def test_window_minima_equal_argmin_of_each_window():
    rng = np.random.default_rng(8)
    E = rng.random((23, 31))
    E[rng.random(E.shape) < 0.3] = np.inf
    E[:8, :9] = np.inf                       # a corner with no finite value
    E[15, 20] = E[16, 21] = 0.0              # a tie: the first in row-major order
    ix = np.array([0, 5, 20, 30, 40, -6, 3, 21], np.int64)
    iy = np.array([0, 3, 16, 22, 10, -6, 2, 15], np.int64)
    for fn in (_window_minima, _window_minima.py_func):
        for win in (0, 1, 3):
            val, by, bx = fn(E, ix, iy, win)
            for i in range(ix.size):
                y0, x0 = max(iy[i] - win, 0), max(ix[i] - win, 0)
                blk = E[y0:max(iy[i] + win + 1, 0), x0:max(ix[i] + win + 1, 0)]
                if blk.size == 0 or not np.isfinite(blk).any():
                    assert val[i] == np.inf
                    continue
                y, x = np.unravel_index(int(np.argmin(blk)), blk.shape)
                assert (val[i], by[i], bx[i]) == (blk[y, x], y0 + y, x0 + x)
