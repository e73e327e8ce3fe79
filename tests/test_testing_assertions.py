import numpy as np
import pytest

from geotex.io import write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import icosphere
from geotex.testing import (assert_manifold, assert_meshes_close, assert_no_self_intersections,
                            assert_printable, assert_watertight, hausdorff_distance)


def test_assertions_pass_on_a_good_mesh(sphere, tmp_path):
    V, F = sphere
    assert assert_printable(V, F).printable
    assert_printable(Mesh(V, F))
    assert_printable((V, F))
    path = write_mesh(tmp_path / "s.ply", Mesh(V, F))
    assert_printable(path)
    assert_watertight(V, F)
    assert_manifold(V, F)
    assert_no_self_intersections(V, F)


def test_failure_messages_say_what_and_where(sphere):
    V, F = sphere
    with pytest.raises(AssertionError, match=r"3 boundary edges, first \[\["):
        assert_watertight(V, F[1:])
    with pytest.raises(AssertionError, match="not printable:\n  - not watertight"):
        assert_printable(V, F[1:])
    F3 = np.vstack([F, F[:1]])
    with pytest.raises(AssertionError, match="non-manifold edges, first"):
        assert_manifold(V, F3)
    Vb, Fb = icosphere(2, center=(0.5, 0, 0))
    with pytest.raises(AssertionError, match=r"self-intersecting face pairs, first \[\["):
        assert_no_self_intersections(np.vstack([V, Vb]), np.vstack([F, Fb + len(V)]))


def test_meshes_close_measures_hausdorff(sphere):
    V, F = sphere
    assert assert_meshes_close((V, F), (V, F)) < 1e-12
    moved = V.copy()
    moved[0] *= 1.1
    d, where = hausdorff_distance(moved, F, V, F)
    assert d == pytest.approx(0.1, rel=1e-6) and np.allclose(where, moved[0])
    with pytest.raises(AssertionError, match="Hausdorff distance 0.1"):
        assert_meshes_close((moved, F), (V, F), atol=1e-3)
    assert_meshes_close((V * (1 + 1e-9), F), (V, F))
