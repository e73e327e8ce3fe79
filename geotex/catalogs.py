"""What the tile-set and shell catalogs share: recipes beside the files, name lookup.

A catalog is a package folder holding ``NAME.npz`` files and ``recipes.json``
(``{name: recipe}``); a user names an entry or gives a file path.
"""

from __future__ import annotations

import json
from pathlib import Path

from geotex.errors import MissingFileError

__all__ = ["catalog_recipes", "catalog_file"]


def catalog_recipes(folder: Path) -> dict:
    """``{name: recipe}`` of the catalog in ``folder`` (empty if it has none)."""
    f = Path(folder) / "recipes.json"
    if not f.is_file():
        return {}
    return json.loads(f.read_text())


def catalog_file(name_or_path, folder: Path, *, what: str) -> Path:
    """Resolve an existing file path, or a catalog name, to a file.

    Raises
    ------
    MissingFileError
        Neither an existing file nor a catalog name; the message names ``what``
        and lists the catalog.
    """
    p = Path(name_or_path)
    if p.is_file():
        return p
    q = Path(folder) / f"{name_or_path}.npz"
    if p.suffix == "" and q.is_file():
        return q
    names = ", ".join(sorted(catalog_recipes(folder))) or "none"
    raise MissingFileError(f"{p}: no such {what} file or catalog name (catalog: {names})")
