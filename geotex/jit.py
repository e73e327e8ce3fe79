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

__all__ = ["compiled", "helper", "preload", "on_first_compile", "JIT_MIN_SIZE"]

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
#: Module name -> the compiled functions defined there (see :func:`preload`).
_REGISTRY: dict[str, list] = {}
#: Callbacks of :func:`on_first_compile` not called yet; the listener installed.
_FIRST_COMPILE: list = []
_LISTENING: list = []


def on_first_compile(callback) -> None:
    """Call ``callback(name)`` once, when numba starts compiling a geotex loop in this process.

    Compiled code is cached on disk, so this happens only where the cache
    lacks the code (the first runs on a machine, or after an upgrade), and a
    command can say why a stage takes far longer than usual. ``name`` is the
    qualified name of the function being compiled. Loading cached code does
    not count.

    Parameters
    ----------
    callback : callable
        Called with one ``str``, from the thread that compiles, at most once.
    """
    with _LOCK:
        _FIRST_COMPILE.append(callback)
        if _LISTENING and not _LISTENING[0]:
            _install_listener()


def _install_listener() -> None:
    """Register the numba compile-event listener behind :func:`on_first_compile` (lock held)."""
    import numba.core.event as ev

    class FirstCompile(ev.Listener):
        def on_start(self, event):
            fn = getattr(event.data.get("dispatcher"), "py_func", None)
            if fn is None or not str(getattr(fn, "__module__", "")).startswith("geotex"):
                return
            with _LOCK:
                todo = _FIRST_COMPILE[:]
                _FIRST_COMPILE.clear()
            for cb in todo:
                cb(f"{fn.__module__}.{fn.__qualname__}")

        def on_end(self, event):
            pass

    ev.register("numba:compile", FirstCompile())
    _LISTENING[:] = [True]


def compiled(fn):
    """Decorate ``fn`` to be compiled with numba (nopython, no GIL, cached) on first call.

    Parameters
    ----------
    fn : callable
        A function numba can compile in nopython mode.

    Returns
    -------
    callable
        Calls the compiled function; ``.py_func`` is ``fn`` itself and
        ``.dispatcher()`` returns the numba dispatcher (created on first use).
    """
    holder: list = []

    def dispatcher():
        if not holder:
            with _LOCK:
                if not holder:
                    import numba

                    if not _LISTENING:             # numba is imported now
                        _LISTENING.append(False)
                        if _FIRST_COMPILE:
                            _install_listener()

                    namespace = fn.__globals__
                    for name, obj in list(namespace.items()):
                        if isinstance(obj, types.FunctionType) and getattr(
                                obj, "_geotex_helper", False):        # not compiled yet
                            namespace[name] = numba.njit(cache=True, nogil=True)(obj)
                    holder.append(numba.njit(cache=True, nogil=True, boundscheck=False)(fn))
        return holder[0]

    @functools.wraps(fn)
    def call(*args):
        return (holder[0] if holder else dispatcher())(*args)

    call.py_func = fn
    call.dispatcher = dispatcher
    _REGISTRY.setdefault(fn.__module__, []).append(call)
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


def _load_cached(dispatcher) -> int:
    """Add every overload of ``dispatcher`` found in numba's disk cache; never compiles.

    This is what :meth:`numba.core.dispatcher.Dispatcher.compile` does on a
    cache hit, for each signature in the cache index (the signatures earlier
    runs compiled). Returns how many were loaded.
    """
    from numba.core.compiler_lock import global_compiler_lock

    index = dispatcher._cache._cache_file._load_index()
    loaded = 0
    for key in index:
        sig = key[0]
        with global_compiler_lock:
            if dispatcher.overloads.get(tuple(sig)) is not None:
                continue
            cres = dispatcher._cache.load_overload(sig, dispatcher.targetctx)
            if cres is None:                     # another machine or source: compiled on call
                continue
            if not cres.objectmode:
                dispatcher.targetctx.insert_user_function(cres.entry_point, cres.fndesc,
                                                          [cres.library])
            dispatcher.add_overload(cres)
            loaded += 1
    return loaded


def preload(*packages: str) -> threading.Thread:
    """Start loading the cached machine code of compiled functions in a background thread.

    The first call of a compiled function in a fresh process loads numba and
    its cached code (~0.4 s, most of it initialising numba's compiler for the
    first function). A command that knows it will call them calls this first,
    and the loading runs while the command reads its input and builds (the
    parts in LLVM release the GIL; the rest competes with the main thread for
    it). A call that arrives before the loading is done waits for numba's
    compiler lock, then finds its code loaded. The code is the same the first
    call would load: results do not change. The loading uses numba internals
    (the cache index); should they change, it stops and the first calls load
    their code as before.

    Parameters
    ----------
    *packages : str
        Names of geotex modules or packages, in the order to load: the
        compiled functions of every module imported so far that is one of
        them or inside one. Importing the modules is left to the caller, so
        that two threads never import the same modules.

    Returns
    -------
    threading.Thread
        The started daemon thread (join it to wait for the loading).
    """
    calls = [c for p in packages for mod, cs in list(_REGISTRY.items())
             if mod == p or mod.startswith(p + ".") for c in cs]

    def load():
        for c in calls:
            try:
                _load_cached(c.dispatcher())
            except Exception:       # numba internals changed: the first call loads it instead
                return

    thread = threading.Thread(target=load, name="geotex-jit-preload", daemon=True)
    thread.start()
    return thread
