"""geotex.linalg: the one home of sparse factorizations."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from geotex.errors import SolverError
from geotex.linalg import factor


def _path_laplacian(n):
    main = np.full(n, 2.0)
    off = np.full(n - 1, -1.0)
    return sp.diags([off, main, off], [-1, 0, 1], format="csc")


@pytest.mark.parametrize("hpd", [True, False])
def test_factors_solve_vectors_and_blocks(hpd):
    A = _path_laplacian(50) + sp.identity(50)
    rng = np.random.default_rng(0)
    b = rng.standard_normal((50, 3))
    lu = factor(A, hpd=hpd)
    assert np.allclose(A @ lu.solve(b), b)
    assert np.allclose(A @ lu.solve(b[:, 0]), b[:, 0])


@pytest.mark.parametrize("hpd", [True, False])
def test_a_singular_system_is_a_solver_error_naming_what_was_solved(hpd):
    A = sp.csc_matrix((3, 3))
    with pytest.raises(SolverError, match="unit test system"):
        factor(A, hpd=hpd, what="unit test system")
