"""The catalog of ready-made shells shipped with geotex.

Shells live in ``geotex/shells/catalog/NAME.npz``; ``recipes.json`` beside
them holds each recipe (source mesh, its SHA-256, tile size), from which
:func:`rebuild` makes the same file byte for byte.  The source meshes of the
recipes that are not bundled with geotex (Bob, Blub) are read from the path
recorded in the recipe.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from geotex.catalogs import Catalog
from geotex.data import sample_path
from geotex.errors import InputError, MissingFileError
from geotex.io import read_mesh
from geotex.mesh.primitives import torus

__all__ = ["CATALOG_DIR", "recipes", "shell_path", "list_shells", "load_named", "rebuild",
           "source_mesh"]

CATALOG_DIR = Path(__file__).resolve().parent / "catalog"
CATALOG = Catalog(CATALOG_DIR, what="shell")
recipes = CATALOG.recipes
shell_path = CATALOG.path


def load_named(name_or_path):
    """Load a shell by catalog name or path."""
    from geotex.shells.store import load_shell

    return load_shell(shell_path(name_or_path))


def list_shells() -> list[dict]:
    """Catalog entries with the metadata stored in each shell file."""
    from geotex.shells.store import shell_file_metadata

    out = CATALOG.entries()
    for entry in out:
        if entry["bytes"]:
            entry.update(shell_file_metadata(entry["file"]))
    return out


def source_mesh(recipe: dict):
    """The base mesh ``(V, F)`` a recipe starts from.

    Raises
    ------
    InputError
        Unknown source kind, or a source file whose SHA-256 differs.
    MissingFileError
        The source file is not available.
    """
    src = recipe["source"]
    if src.startswith("primitive:torus"):
        return torus(**recipe.get("args", {}))
    if src.startswith("sample:"):
        path = sample_path(src.split(":", 1)[1])
    else:
        path = Path(src)
    if not path.is_file():
        raise MissingFileError(f"{path}: source mesh of the recipe not found")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if recipe.get("sha256") and digest != recipe["sha256"]:
        raise InputError(f"{path}: its SHA-256 differs from the recipe's; not the same mesh")

    m = read_mesh(path)
    return m.vertices, m.faces


def rebuild(name: str, path=None, *, progress=None):
    """Rebuild catalog shell ``name`` from its recipe; write it when ``path`` is given.

    Returns
    -------
    Shell
    """
    from geotex.shells.build import build_shell
    from geotex.shells.store import save_shell

    r = CATALOG.recipe(name)
    V, F = source_mesh(r)
    shell = build_shell(V, F, tile_size=r["tile_size"], name=name, source=r["source"],
                        recipe=r, progress=progress)
    if path is not None:
        save_shell(path, shell)
    return shell
