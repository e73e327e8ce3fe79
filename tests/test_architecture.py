"""Import and error contracts of the geotex package (docs/architecture.md, "Conventions").

The rules are checked on the source text with :mod:`ast`, so they cost no import:

* no module imports a private name (a module or a symbol whose name starts with one
  underscore) from another top-level subpackage of geotex;
* the import graph between top-level subpackages has no cycle except the ones listed
  in ``ALLOWED_CYCLE_EDGES`` (each with its reason);
* every ``raise`` raises a :class:`geotex.errors.GeotexError` subclass, or re-raises
  (a bare ``raise``, a variable holding a caught exception), except the documented
  ``ALLOWED_RAISES``, ``ALLOWED_FACTORIES`` and ``ALLOWED_IN_FILE``;
* no ``assert`` statement (it vanishes under ``python -O``);
* outside ``geotex/cli/``, geotex modules are imported at the top of a module, not
  inside a function, except the documented ``ALLOWED_LAZY_IMPORTS``; a third-party
  import inside a function is one of the slow ``HEAVY_MODULES`` (or the standard
  library); ``import geotex`` and the ``geotex`` parser import none of them.
"""

from __future__ import annotations

import ast
import builtins
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import geotex
import geotex.errors

PACKAGE_DIR = Path(geotex.__file__).resolve().parent

#: Imports between subpackages that close a cycle on purpose: (importer, imported) -> reason.
#: Every edge here is a lazy (function-level) import.
ALLOWED_CYCLE_EDGES: dict[tuple[str, str], str] = {}

#: Exception names a ``raise`` may use anywhere although they are no GeotexError, with the reason.
ALLOWED_RAISES: dict[str, str] = {
    "NotImplementedError": "abstract hooks that subclasses must override",
    "KeyboardInterrupt": "re-raised after cleanup so Ctrl-C still stops the program",
    "SystemExit": "the command line's exit path",
    "StopIteration": "iterator protocol",
}

#: Functions that build the exception to raise (``raise factory(...)``), with the reason.
ALLOWED_FACTORIES: dict[str, str] = {
    "flag_error": "geotex.cli: returns a UsageError naming the flag, or the caught GeotexError",
    "_cli_error": "geotex/cli/pgp.py: flag_error, or a UsageError naming the mesh file",
}

#: (file, exception) pairs allowed in one file only, with the reason.
ALLOWED_IN_FILE: dict[tuple[str, str], str] = {
    ("geotex/testing.py", "AssertionError"):
        "the assertion helpers for users' tests fail the way pytest's own asserts do",
    ("geotex/tiles/__init__.py", "AttributeError"):
        "module-level __getattr__ protocol (lazy catalog names)",
    ("geotex/displace/__init__.py", "AttributeError"):
        "module-level __getattr__ protocol (names imported on first use)",
    ("geotex/shells/__init__.py", "AttributeError"):
        "module-level __getattr__ protocol (names imported on first use)",
    ("geotex/check/slicers.py", "ValueError"):
        "pending: geotex/check is being reworked; the parsers' ValueError on unreadable "
        "slicer output is caught in the same module and becomes an ExternalToolError",
}


#: Function-level imports of geotex modules outside geotex/cli/ that stay lazy:
#: (file, module) -> reason; ``module`` also covers its submodules.
ALLOWED_LAZY_IMPORTS: dict[tuple[str, str], str] = {
    ("geotex/batch/jobs.py", "geotex"):
        "`geotex --help` loads the job table (the --job choices); each job imports the "
        "libraries it runs (mapping, image, repair with pymeshlab, ...) when it runs",
    ("geotex/batch/manifest.py", "geotex.io"):
        "`geotex --help` imports geotex.batch; geotex.io (+ manifold3d) adds ~25-50 ms to it",
    ("geotex/batch/summary.py", "geotex.io"):
        "`geotex --help` imports geotex.batch; geotex.io (+ manifold3d) adds ~25-50 ms to it",
    ("geotex/displace/api.py", "geotex.displace.seamless"):
        "`geotex --help` imports geotex.displace (the --mapping choices); the pgp and lapped "
        "mappings pull in the field, patch and image machinery (networkx) only when used",
    ("geotex/displace/api.py", "geotex.displace.step"):
        "STEP input only: gmsh and the repair steps (pymeshlab, ~0.2 s)",
    ("geotex/displace/__init__.py", "geotex.displace.api"):
        "module __getattr__: the parser reads geotex.displace.choices for every command "
        "(`geotex --help`, `geotex map`); the displacement machinery (check, relief, image "
        "reading, ~0.15 s CPU) is imported on first use",
    ("geotex/displace/__init__.py", "geotex.displace.heightmap"):
        "module __getattr__: imported on first use (as geotex.displace.api)",
    ("geotex/displace/__init__.py", "geotex.displace.mappings"):
        "module __getattr__: imported on first use (as geotex.displace.api)",
    ("geotex/displace/__init__.py", "geotex.displace.masks"):
        "module __getattr__: imported on first use (as geotex.displace.api)",
    ("geotex/shells/__init__.py", "geotex.shells.build"):
        "module __getattr__: `geotex map` names a missing shell file (geotex.shells.catalog) "
        "before the polycube machinery (~0.3 s CPU) is imported on first use",
    ("geotex/shells/__init__.py", "geotex.shells.catalog"):
        "module __getattr__: imported on first use (as geotex.shells.build)",
    ("geotex/shells/__init__.py", "geotex.shells.store"):
        "module __getattr__: imported on first use (as geotex.shells.build)",
    ("geotex/shells/__init__.py", "geotex.shells.locate"):
        "module __getattr__: imported on first use (as geotex.shells.build)",
    ("geotex/shells/__init__.py", "geotex.shells.scale"):
        "module __getattr__: imported on first use (as geotex.shells.build)",
    ("geotex/shells/catalog.py", "geotex.shells.build"):
        "only rebuilding a catalog shell builds one; naming a shell file does not",
    ("geotex/shells/catalog.py", "geotex.shells.store"):
        "reading a shell file loads the polycube records; naming one (`geotex map`'s "
        "argument check) does not",
    ("geotex/heighttilt/refine.py", "geotex.mesh.meshlab"):
        "imports pymeshlab (~0.2 s), needed only when a base is remeshed",
    ("geotex/tiles/__init__.py", "geotex.tiles.catalog"):
        "module __getattr__: the catalog is imported on first use so that "
        "`python -m geotex.tiles.catalog` runs without a second copy of the module",
    ("geotex/tiles/__init__.py", "geotex.tiles.build"):
        "module __getattr__: building sets (quilting, exemplars, scipy.ndimage, ~0.12 s) "
        "is imported on first use; using a set (the main job) needs none of it",
    ("geotex/tiles/__init__.py", "geotex.tiles.verify"):
        "module __getattr__: the seam check is imported on first use (as build_tileset)",
    ("geotex/tiles/__init__.py", "geotex.tiles.tiling"):
        "module __getattr__: planar tilings are imported on first use (as build_tileset)",
    ("geotex/tiles/catalog.py", "geotex.exemplars"):
        "only rebuilding a catalog set builds an exemplar; loading one (the main job) does not",
    ("geotex/tiles/catalog.py", "geotex.tiles.build"):
        "only rebuilding a catalog set builds tiles; loading one (the main job) does not",
    ("geotex/tiles/catalog.py", "geotex.tiles.verify"):
        "only rebuilding the catalog checks seams; loading a set (the main job) does not",
}

#: Third-party modules a function may import lazily (they are slow to import), with the
#: cumulative ``python -X importtime`` cost measured after numpy and scipy.sparse.
#: The standard library may be imported lazily too (e.g. ``resource``: POSIX only).
HEAVY_MODULES: dict[str, str] = {
    "pyvista": "~0.3 s (VTK)",
    "vtkmodules": "part of pyvista's VTK",
    "dask": "~0.25 s",
    "distributed": "~0.6 s",
    "playwright": "a browser driver; only tests/test_viewer.py and test_docs_site.py use it",
    "pymeshlab": "~0.2 s",
    "networkx": "~0.25 s",
    "scipy.spatial": "~0.1 s",
    "scipy.ndimage": "~0.1 s",
    "scipy.signal": "~0.7 s (measured with python -X importtime); only tile building and "
                    "image hole filling correlate",
    "fast_simplification": "~50 ms, only when a relief is decimated",
    "gmsh": "optional (the 'step' extra): STEP input only",
    "numba": "~0.2 s, plus ~0.05 s per cached compiled function; geotex.jit loads it on "
             "the first call of a compiled loop (large inputs only)",
}

#: Modules that neither ``import geotex`` nor building the ``geotex`` parser may load.
NOT_AT_STARTUP = ("pyvista", "vtkmodules", "dask", "distributed", "playwright", "pymeshlab",
                  "networkx", "numba")


def _modules():
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        parts = path.relative_to(PACKAGE_DIR).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        name = ".".join(("geotex",) + parts)
        is_package = path.name == "__init__.py"
        yield name, is_package, path, ast.parse(path.read_text(encoding="utf-8"), str(path))


MODULES = list(_modules())
MODULE_NAMES = {name for name, *_ in MODULES}


def _top(module: str) -> str:
    """``geotex.fields.frames`` -> ``fields``; ``geotex`` -> ``""``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _imports(name: str, is_package: bool, tree: ast.Module):
    """Yield ``(imported module, imported symbol or None, line)`` of every geotex import."""
    base = name if is_package else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "geotex":
                    yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                pkg = base.split(".")
                pkg = pkg[: len(pkg) - node.level + 1]
                module = ".".join(pkg + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module.split(".")[0] != "geotex":
                continue
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                if sub in MODULE_NAMES:  # ``from geotex.x import submodule``
                    yield sub, None, node.lineno
                else:
                    yield module, alias.name, node.lineno


def _function_level_imports(name: str, is_package: bool, tree: ast.Module):
    """Yield ``(module, line)`` of every import statement inside a function body."""
    base = name if is_package else name.rpartition(".")[0]

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            inside = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
            if in_function and isinstance(child, ast.Import):
                for alias in child.names:
                    yield alias.name, child.lineno
            elif in_function and isinstance(child, ast.ImportFrom):
                module = child.module or ""
                if child.level:
                    pkg = base.split(".")
                    pkg = pkg[: len(pkg) - child.level + 1]
                    module = ".".join(pkg + ([module] if module else []))
                for alias in child.names:  # ``from geotex.x import submodule``
                    sub = f"{module}.{alias.name}"
                    yield (sub if sub in MODULE_NAMES else module), child.lineno
            yield from visit(child, inside)

    yield from visit(tree, False)


def _covered(module: str, prefix: str) -> bool:
    return module == prefix or module.startswith(prefix + ".")


def _private(module: str, symbol: str | None) -> bool:
    names = module.split(".") + ([symbol] if symbol else [])
    return any(n.startswith("_") and not n.startswith("__") for n in names)


def test_no_private_import_across_subpackages():
    bad = []
    for name, is_package, path, tree in MODULES:
        for module, symbol, line in _imports(name, is_package, tree):
            if _top(module) != _top(name) and _private(module, symbol):
                what = f"{module}.{symbol}" if symbol else module
                bad.append(f"{path.relative_to(PACKAGE_DIR.parent)}:{line} imports {what}")
    assert not bad, "private names imported across subpackages:\n" + "\n".join(bad)


def _subpackage_graph():
    graph: dict[str, set[str]] = {}
    for name, is_package, _path, tree in MODULES:
        src = _top(name)
        if not src:
            continue  # the package root re-exports everything; it is no layer
        for module, _symbol, _line in _imports(name, is_package, tree):
            dst = _top(module)
            if dst and dst != src and (src, dst) not in ALLOWED_CYCLE_EDGES:
                graph.setdefault(src, set()).add(dst)
    return graph


def _cycles(graph):
    """Strongly connected components with more than one node (Tarjan)."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle_between_subpackages():
    graph = _subpackage_graph()
    cycles = _cycles(graph)
    detail = []
    for comp in cycles:
        edges = sorted((a, b) for a in comp for b in graph.get(a, ()) if b in comp)
        detail.append(" ".join(f"{a}->{b}" for a, b in edges))
    assert not cycles, "import cycles between subpackages:\n" + "\n".join(detail)


def test_allowed_cycle_edges_are_used():
    """A documented exception that no longer exists is removed from the list."""
    seen = set()
    for name, is_package, _path, tree in MODULES:
        for module, _symbol, _line in _imports(name, is_package, tree):
            seen.add((_top(name), _top(module)))
    assert set(ALLOWED_CYCLE_EDGES) <= seen


def _geotex_error_names() -> set[str]:
    return {n for n, obj in inspect.getmembers(geotex.errors, inspect.isclass)
            if issubclass(obj, geotex.errors.GeotexError)}


def _local_error_names() -> set[str]:
    """Classes defined in geotex whose bases name a GeotexError subclass (transitively)."""
    known = _geotex_error_names()
    classes = []
    for _name, _is_package, _path, tree in MODULES:
        classes += [n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)]
    changed = True
    while changed:
        changed = False
        for cls in classes:
            bases = {b.attr if isinstance(b, ast.Attribute) else getattr(b, "id", None)
                     for b in cls.bases}
            if cls.name not in known and bases & known:
                known.add(cls.name)
                changed = True
    return known


def _exc_name(node: ast.expr) -> str | None:
    node = node.func if isinstance(node, ast.Call) else node
    if isinstance(node, ast.Attribute):
        return node.attr
    return getattr(node, "id", None)


def _stored_exceptions(tree: ast.Module, allowed: set[str]) -> set[str]:
    """Variables that hold a caught exception or a GeotexError built earlier.

    ``except X as exc`` binds ``exc``; ``error = exc`` or ``error = InputError(...)``
    makes ``error`` one too, so ``raise error`` is a re-raise or a GeotexError.
    """
    names = {h.name for h in ast.walk(tree) if isinstance(h, ast.ExceptHandler) and h.name}
    assigns = [n for n in ast.walk(tree) if isinstance(n, ast.Assign)
               and len(n.targets) == 1 and isinstance(n.targets[0], ast.Name)]
    changed = True
    while changed:
        changed = False
        for a in assigns:
            target, value = a.targets[0].id, a.value
            holds = (isinstance(value, ast.Name) and value.id in names) or (
                isinstance(value, ast.Call) and _exc_name(value) in allowed)
            if holds and target not in names:
                names.add(target)
                changed = True
    return names


def _private_control_flow(tree: ast.Module) -> set[str]:
    """Private exception classes (``_Name``) defined and caught in the same module."""
    defined = {c.name for c in ast.walk(tree)
               if isinstance(c, ast.ClassDef) and c.name.startswith("_")}
    caught = set()
    for h in ast.walk(tree):
        if isinstance(h, ast.ExceptHandler) and h.type is not None:
            types = h.type.elts if isinstance(h.type, ast.Tuple) else [h.type]
            caught |= {_exc_name(t) for t in types}
    return defined & caught


def test_every_raise_is_a_geotex_error():
    allowed = _local_error_names() | set(ALLOWED_RAISES)
    bad = []
    for _name, _is_package, path, tree in MODULES:
        rel = path.relative_to(PACKAGE_DIR.parent).as_posix()
        stored = _stored_exceptions(tree, allowed)
        local = _private_control_flow(tree)
        for node in ast.walk(tree):
            if not isinstance(node, ast.Raise) or node.exc is None:
                continue  # bare re-raise
            name = _exc_name(node.exc)
            call = isinstance(node.exc, ast.Call)
            if (name in allowed or name in local or (rel, name) in ALLOWED_IN_FILE
                    or (call and name in ALLOWED_FACTORIES)
                    or (not call and name in stored)):
                continue
            bad.append(f"{rel}:{node.lineno} raises {name or ast.unparse(node.exc)}")
    assert not bad, "raises that are no GeotexError:\n" + "\n".join(bad)


def test_allowed_lists_are_used():
    """A documented exception that no longer occurs is removed from its list."""
    used_files, used_factories = set(), set()
    for _name, _is_package, path, tree in MODULES:
        rel = path.relative_to(PACKAGE_DIR.parent).as_posix()
        for node in ast.walk(tree):
            if isinstance(node, ast.Raise) and node.exc is not None:
                used_files.add((rel, _exc_name(node.exc)))
                if isinstance(node.exc, ast.Call):
                    used_factories.add(_exc_name(node.exc))
    assert set(ALLOWED_IN_FILE) <= used_files
    assert set(ALLOWED_FACTORIES) <= used_factories


def test_no_assert_for_validation():
    """``assert`` vanishes under ``python -O``; validation raises an InputError instead."""
    bad = [f"{path.relative_to(PACKAGE_DIR.parent)}:{node.lineno}"
           for _name, _is_package, path, tree in MODULES
           for node in ast.walk(tree) if isinstance(node, ast.Assert)]
    assert not bad, "assert statements in geotex:\n" + "\n".join(bad)


@pytest.mark.parametrize("name", sorted(ALLOWED_RAISES))
def test_allowed_raises_are_builtin_exceptions(name):
    assert issubclass(getattr(builtins, name), BaseException)


def _lazy_imports():
    """``(file, module, line)`` of every function-level import outside geotex/cli/."""
    for name, is_package, path, tree in MODULES:
        rel = path.relative_to(PACKAGE_DIR.parent).as_posix()
        if rel.startswith("geotex/cli/"):
            continue  # subcommands import their library when they run: `geotex --help` stays fast
        for module, line in _function_level_imports(name, is_package, tree):
            yield rel, module, line


def test_geotex_imports_at_module_top():
    """A geotex import inside a function hides the dependency graph (and import cycles)."""
    bad = [f"{rel}:{line} imports {module} inside a function"
           for rel, module, line in _lazy_imports()
           if module.split(".")[0] == "geotex"
           and not any(f == rel and _covered(module, m) for f, m in ALLOWED_LAZY_IMPORTS)]
    assert not bad, ("move these imports to the top of the module (or list them in "
                     "ALLOWED_LAZY_IMPORTS with the reason):\n" + "\n".join(bad))


def test_allowed_lazy_imports_are_used():
    """A documented lazy import that no longer exists is removed from the list."""
    used = {(f, m) for f, m in ALLOWED_LAZY_IMPORTS
            for rel, module, _line in _lazy_imports() if f == rel and _covered(module, m)}
    assert used == set(ALLOWED_LAZY_IMPORTS)


def test_lazy_third_party_imports_are_heavy():
    """Only slow third-party modules are imported inside functions; the rest at the top."""
    bad = []
    for rel, module, line in _lazy_imports():
        top = module.split(".")[0]
        if top == "geotex" or top in sys.stdlib_module_names:
            continue
        if not any(_covered(module, heavy) for heavy in HEAVY_MODULES):
            bad.append(f"{rel}:{line} imports {module} inside a function")
    assert not bad, ("import these at the top of the module (or add a slow module to "
                     "HEAVY_MODULES with its measured import time):\n" + "\n".join(bad))


def test_startup_imports_no_heavy_module():
    """``import geotex`` and ``geotex --help`` (the parser) stay free of the heavy modules."""
    code = ("import sys, geotex, geotex.cli; geotex.cli.build_parser(); "
            f"print(sorted(m for m in {NOT_AT_STARTUP!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=PACKAGE_DIR.parent)
    assert out.stdout.strip() == "[]", f"heavy modules imported at startup: {out.stdout}"


#: Modules the ``geotex`` parser may not load: it reads displace's option names from
#: geotex.displace.choices, not through the displacement machinery.
NOT_IN_PARSER = ("geotex.displace.api", "geotex.displace.masks", "geotex.displace.mappings",
                 "geotex.relief", "geotex.check", "PIL")


def test_parser_leaves_the_displacement_machinery_out():
    """Building the parser (every command, ``geotex --help``) imports no displacement code,
    and ``geotex.displace`` still gives every public name on first use."""
    code = ("import sys, geotex.cli; geotex.cli.build_parser(); "
            f"print(sorted(m for m in {NOT_IN_PARSER!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=PACKAGE_DIR.parent)
    assert out.stdout.strip() == "[]", f"imported by the parser: {out.stdout}"
    import geotex.displace as gd
    from geotex.displace import choices, mappings, masks

    assert all(getattr(gd, name) is not None for name in gd.__all__)
    assert mappings.MAPPINGS is choices.MAPPINGS and masks.CURVES is choices.CURVES
    with pytest.raises(AttributeError):
        gd.no_such_name


def test_map_names_a_missing_shell_before_the_polycube_machinery_loads(tmp_path):
    """``geotex map --shell NAME`` with no such shell fails (exit 2, one line) without
    importing the polycube stack; ``geotex.shells`` still gives every public name."""
    code = ("import sys, geotex.cli\n"
            "print('exit', geotex.cli.main(['map', '--tiles', 'studs', '--shell', "
            f"'no-such-shell', '-o', {str(tmp_path / 'out.stl')!r}]))\n"
            "print(sorted(m for m in ('geotex.param.polycube', 'geotex.shells.build') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=PACKAGE_DIR.parent)
    assert "no-such-shell: no such shell file" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    assert out.stdout.split()[-1] == "[]", f"loaded before the error: {out.stdout}"
    assert out.stdout.startswith("exit 2\n")
    assert not (tmp_path / "out.stl").exists()
    import geotex.shells as gs

    assert all(getattr(gs, name) is not None for name in gs.__all__)
    with pytest.raises(AttributeError):
        gs.no_such_name


#: Modules that using a catalog tile set over a shell (the main job's imports) may not load:
#: they build tile sets (quilting, exemplars, image filters).
NOT_IN_MAIN_JOB = ("geotex.tiles.build", "geotex.quilting", "geotex.exemplars", "scipy.ndimage",
                   "scipy.signal")


def test_main_job_imports_no_tile_building():
    """The main job's imports (tile catalog, shells, mapping, printing) leave tile building out."""
    code = ("import sys, geotex.cli; geotex.cli.build_parser(); "
            "from geotex.tiles.catalog import load_named; load_named('studs'); "
            "import geotex.shells, geotex.mapping, geotex.printing, geotex.tiles; "
            f"print(sorted(m for m in {NOT_IN_MAIN_JOB!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=PACKAGE_DIR.parent)
    assert out.stdout.strip() == "[]", f"tile building imported by the main job: {out.stdout}"
