"""Sparse factorization of the Hermitian positive definite systems of the field solvers.

SuperLU calls BLAS on small supernode blocks.  With a multi-threaded OpenBLAS
those calls gain nothing and, on a busy machine, spin-waiting BLAS threads made
one factorization of a 100k-face field 10-60 times slower (0.4 s became up to
40 s on a loaded 2-core machine).  Factorizations and solves therefore run with
BLAS limited to one thread: through ``threadpoolctl`` when it is installed,
otherwise by calling OpenBLAS's own ``*set_num_threads`` in the OpenBLAS
libraries bundled with scipy (a no-op when none is found).  The previous thread
count is restored afterwards.
"""

from __future__ import annotations

import ctypes
import glob
import os
from contextlib import contextmanager
from functools import lru_cache

import scipy
import scipy.sparse as sp
from scipy.sparse.linalg import splu

__all__ = ["factor_hpd", "HPDFactor", "single_threaded_blas"]


@lru_cache(maxsize=1)
def _openblas_controls() -> tuple:
    """(set, get) function pairs of the OpenBLAS libraries shipped with scipy."""
    root = os.path.dirname(os.path.dirname(scipy.__file__))
    paths = set()
    for pattern in ("scipy.libs/*openblas*", "scipy/.dylibs/*openblas*"):
        paths.update(glob.glob(os.path.join(root, pattern)))
    controls = []
    for path in sorted(paths):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for prefix in ("scipy_openblas", "openblas"):
            for suffix in ("", "64_"):
                try:
                    set_ = getattr(lib, f"{prefix}_set_num_threads{suffix}")
                    get = getattr(lib, f"{prefix}_get_num_threads{suffix}")
                except AttributeError:
                    continue
                set_.argtypes, set_.restype = [ctypes.c_int], None
                get.argtypes, get.restype = [], ctypes.c_int
                controls.append((set_, get))
                break
            else:
                continue
            break
    return tuple(controls)


@contextmanager
def single_threaded_blas():
    """Limit BLAS to one thread inside the ``with`` block (see module docstring)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        threadpool_limits = None
    if threadpool_limits is not None:
        with threadpool_limits(limits=1, user_api="blas"):
            yield
        return
    controls = _openblas_controls()
    previous = [get() for _, get in controls]
    for set_, _ in controls:
        set_(1)
    try:
        yield
    finally:
        for (set_, _), n in zip(controls, previous):
            set_(max(int(n), 1))


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
