"""geotex.mesh.geometry.face_cross: numpy.cross's bits, every dtype and shape it meets."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.mesh.geometry import face_cross


def _numpy_cross(V, F):
    v0 = V[F[:, 0]]
    return np.cross(V[F[:, 1]] - v0, V[F[:, 2]] - v0)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_face_cross_has_the_bits_of_numpy_cross(dtype):
    rng = np.random.default_rng(7)
    V = (rng.normal(size=(300, 3)) * rng.choice([1e-8, 1.0, 1e8], size=(300, 1))).astype(dtype)
    V[:5] = [[0.0, 0.0, 0.0], [-0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]]
    F = rng.integers(0, 300, size=(1000, 3))
    F[:3] = [[0, 1, 2], [0, 0, 1], [0, 3, 4]]          # plain, repeated index, collinear
    got, want = face_cross(V, F), _numpy_cross(V, F)
    assert got.dtype == want.dtype and got.shape == want.shape == (1000, 3)
    assert got.tobytes() == want.tobytes()
    assert got[0].tolist() == [0.0, 0.0, -1.0] and not got[1].any() and not got[2].any()


def test_face_cross_of_no_faces_and_of_a_strided_vertex_array():
    assert face_cross(np.zeros((3, 3)), np.zeros((0, 3), dtype=np.int64)).shape == (0, 3)
    rng = np.random.default_rng(3)
    V = rng.normal(size=(3, 50)).T                      # Fortran-ordered rows
    F = rng.integers(0, 50, size=(40, 3))
    assert face_cross(V, F).tobytes() == _numpy_cross(V, F).tobytes()
    assert face_cross(V, F[:, ::-1]).tobytes() == _numpy_cross(V, F[:, ::-1]).tobytes()
