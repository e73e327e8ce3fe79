"""Compiled loops: the one place geotex uses numba.

Some hot paths are loops that numpy cannot express without sorting or large
temporaries (grouping half-edges by edge, scattering per-face values into
per-edge rows, a matrix-free operator applied once per iteration).  They are
written as plain Python functions over arrays and compiled with numba on first
use by :func:`compiled`:

* numba is imported only when a compiled function is first called (importing
  it costs ~0.2 s, loading a cached function ~0.05 s), so ``import geotex`` and
  small inputs, which keep their numpy path, do not pay for it;
* compiled code is cached on disk (numba's ``cache=True``: next to the source
  when writable, else in the user cache), so only the first call on a machine
  compiles;
* functions run without the GIL and single-threaded, in a fixed order:
  results are deterministic and equal the numpy paths' bit for bit where both
  exist (tested).

A compiled function may not call another one (each is compiled on its own).
"""

from __future__ import annotations

import functools
import threading

__all__ = ["compiled", "JIT_MIN_SIZE"]

#: Inputs from this many items (half-edges, faces) up take a compiled path
#: where a numpy path exists too: below it, loading numba and the cached code
#: (~0.25 s in a fresh process) costs more than the loop saves.
JIT_MIN_SIZE = 300_000

_LOCK = threading.Lock()


def compiled(fn):
    """Decorate ``fn`` to be compiled with numba (nopython, no GIL, cached) on first call.

    Parameters
    ----------
    fn : callable
        A function numba can compile in nopython mode.

    Returns
    -------
    callable
        Calls the compiled function; ``.py_func`` is ``fn`` itself.
    """
    holder: list = []

    @functools.wraps(fn)
    def call(*args):
        if not holder:
            with _LOCK:
                if not holder:
                    import numba

                    holder.append(numba.njit(cache=True, nogil=True, boundscheck=False)(fn))
        return holder[0](*args)

    call.py_func = fn
    return call
