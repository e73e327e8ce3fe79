"""Sparse factorizations: the one place geotex factors a matrix.

SuperLU calls BLAS on small supernode blocks.  With a multi-threaded OpenBLAS
those calls gain nothing and, on a busy machine, spin-waiting BLAS threads made
one factorization of a 100k-face field 10-60 times slower (0.4 s became up to
40 s on a loaded 2-core machine).  Factorizations and solves therefore run with
BLAS limited to one thread (``threadpoolctl``); the previous limit is restored
afterwards.  A factorization that fails (a singular matrix) raises
:class:`geotex.errors.SolverError` naming what was being solved.
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu
from threadpoolctl import ThreadpoolController

from geotex.errors import SolverError

__all__ = ["factor", "SparseFactor", "single_threaded_blas"]

#: SuperLU options for Hermitian positive definite matrices (see :func:`factor`).
_HPD_OPTIONS = dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, relax=1, panel_size=10,
                    options={"SymmetricMode": True})


_CONTROLLER: list = []


def _controller() -> ThreadpoolController:
    """One ``ThreadpoolController`` for the process, made on first use.

    Making one scans the loaded libraries (about 2 ms, which an inverse
    iteration of eight solves paid eight times); the BLAS libraries of numpy
    and scipy are loaded by then (this module imports ``scipy.sparse.linalg``).
    """
    if not _CONTROLLER:
        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0]


@contextmanager
def single_threaded_blas():
    """Limit BLAS to one thread inside the ``with`` block (see module docstring)."""
    with _controller().limit(limits=1, user_api="blas"):
        yield


class SparseFactor:
    """A SuperLU factorization whose solves run with one BLAS thread.

    Made by :func:`factor`.
    """

    def __init__(self, A, what: str, **options):
        self.what = what
        with single_threaded_blas():
            try:
                self._lu = splu(sp.csc_matrix(A), **options)
            except RuntimeError as exc:             # "Factor is exactly singular"
                raise SolverError(f"{what}: the sparse system could not be factored "
                                  f"({exc}); the mesh may have isolated parts or "
                                  "degenerate faces") from None

    def solve(self, b) -> np.ndarray:
        """Return ``A^{-1} b`` for a vector or an ``(k, r)`` block of right-hand sides.

        Raises
        ------
        SolverError
            If the solution is not finite.
        """
        with single_threaded_blas():
            x = self._lu.solve(np.ascontiguousarray(b))
        if not np.isfinite(x).all():
            raise SolverError(f"{self.what}: the sparse solve gave non-finite values")
        return x


def factor(A, *, hpd: bool = False, what: str = "solve") -> SparseFactor:
    """Factor a square sparse matrix with SuperLU.

    With ``hpd`` the matrix is Hermitian positive definite: structurally
    symmetric and needing no pivoting, so SuperLU runs in symmetric mode
    (minimum-degree ordering of ``A + A^T``, diagonal pivots), and
    ``relax=1`` avoids a SuperLU pathology where the default supernode
    relaxation made some factorizations hundreds of times slower.  Otherwise
    SuperLU's defaults (COLAMD ordering, partial pivoting).

    Parameters
    ----------
    A : scipy.sparse matrix, (n, n)
    hpd : bool, optional
        ``A`` is Hermitian positive definite.
    what : str, optional
        What is being solved, for the error message.

    Returns
    -------
    SparseFactor
        Use ``.solve(b)``.

    Raises
    ------
    SolverError
        If the matrix is singular.
    """
    return SparseFactor(A, what, **(_HPD_OPTIONS if hpd else {}))
