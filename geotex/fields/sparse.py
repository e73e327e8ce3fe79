"""Sparse factorization of the Hermitian positive definite systems of the field solvers.

SuperLU calls BLAS on small supernode blocks.  With a multi-threaded OpenBLAS
those calls gain nothing and, on a busy machine, spin-waiting BLAS threads made
one factorization of a 100k-face field 10-60 times slower (0.4 s became up to
40 s on a loaded 2-core machine).  Factorizations and solves therefore run with
BLAS limited to one thread (``threadpoolctl``); the previous limit is restored
afterwards.
"""

from __future__ import annotations

from contextlib import contextmanager

import scipy.sparse as sp
from scipy.sparse.linalg import splu
from threadpoolctl import threadpool_limits

__all__ = ["factor_hpd", "HPDFactor", "single_threaded_blas"]


@contextmanager
def single_threaded_blas():
    """Limit BLAS to one thread inside the ``with`` block (see module docstring)."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield


class HPDFactor:
    """A factorization of a Hermitian positive definite matrix; see :func:`factor_hpd`."""

    def __init__(self, A: sp.spmatrix):
        with single_threaded_blas():
            self._lu = splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A",
                            diag_pivot_thresh=0.0, relax=1, panel_size=10,
                            options={"SymmetricMode": True})

    def solve(self, b):
        """Return ``A^{-1} b`` for a vector or an ``(k, r)`` block of right-hand sides."""
        with single_threaded_blas():
            return self._lu.solve(b)


def factor_hpd(A: sp.spmatrix) -> HPDFactor:
    """Factor a Hermitian positive definite sparse matrix with SuperLU.

    The matrix is structurally symmetric and needs no pivoting, so SuperLU runs
    in symmetric mode (minimum-degree ordering of ``A + A^T``, diagonal
    pivots).  ``relax=1`` avoids a SuperLU pathology where the default
    supernode relaxation made some factorizations hundreds of times slower.

    Returns
    -------
    HPDFactor
        Use ``.solve(b)``.
    """
    return HPDFactor(A)
