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

A compiled function may call functions of its module marked with
:func:`helper`: on the first compiled call in a module, every marked function
of that module is compiled too and replaces its plain version in the module's
namespace (numba resolves the names of called functions there).
"""

from __future__ import annotations

import functools
import os
import threading
import types

__all__ = ["compiled", "helper", "JIT_MIN_SIZE"]

#: Inputs from this many items (half-edges, edges, candidate pairs) up take a
#: compiled path where a numpy path exists too: below it, loading numba and the
#: cached code (~0.4 s in a fresh process) costs more than the loop saves.
#: The environment variable ``GEOTEX_JIT_MIN_SIZE`` sets it (0: always compiled;
#: the tests run both paths this way).
def _min_size(default: int = 300_000) -> int:
    """``GEOTEX_JIT_MIN_SIZE`` as a non-negative integer; the default (with a
    one-line warning) for anything else, so a typo cannot stop every command."""
    text = os.environ.get("GEOTEX_JIT_MIN_SIZE")
    if text is None:
        return default
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        import warnings

        warnings.warn(f"GEOTEX_JIT_MIN_SIZE={text!r} is not a non-negative integer; "
                      f"using {default}", stacklevel=2)
        return default
    return value


JIT_MIN_SIZE = _min_size()

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

                    namespace = fn.__globals__
                    for name, obj in list(namespace.items()):
                        if isinstance(obj, types.FunctionType) and getattr(
                                obj, "_geotex_helper", False):        # not compiled yet
                            namespace[name] = numba.njit(cache=True, nogil=True)(obj)
                    holder.append(numba.njit(cache=True, nogil=True, boundscheck=False)(fn))
        return holder[0](*args)

    call.py_func = fn
    return call


def helper(fn):
    """Mark ``fn`` as called from compiled functions of its module (see the module notes).

    Parameters
    ----------
    fn : callable
        A function numba can compile in nopython mode.

    Returns
    -------
    callable
        ``fn`` itself, marked.
    """
    fn._geotex_helper = True
    return fn
