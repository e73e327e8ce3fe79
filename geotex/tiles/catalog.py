"""The catalog of ready-made tile sets shipped with geotex.

Sets live in ``geotex/tiles/catalog/NAME.npz``; ``recipes.json`` beside them
holds the recipe of each (exemplar, its parameters, colours, seed, ...), from
which :func:`rebuild` makes the same file byte for byte.
"""

from __future__ import annotations

import json
from pathlib import Path

from geotex.errors import InputError, MissingFileError

__all__ = ["CATALOG_DIR", "recipes", "tileset_path", "list_tilesets", "rebuild",
           "load_named"]

CATALOG_DIR = Path(__file__).resolve().parent / "catalog"


def recipes() -> dict:
    """Return ``{name: recipe}`` of the catalog (empty if it has none)."""
    f = CATALOG_DIR / "recipes.json"
    if not f.is_file():
        return {}
    return json.loads(f.read_text())


def tileset_path(name_or_path) -> Path:
    """Resolve a catalog name or a file path to a tile set file.

    Raises
    ------
    MissingFileError
        Neither an existing file nor a catalog name (the message lists the names).
    """
    p = Path(name_or_path)
    if p.is_file():
        return p
    q = CATALOG_DIR / f"{name_or_path}.npz"
    if q.is_file() and p.suffix == "":
        return q
    names = ", ".join(sorted(recipes())) or "none"
    raise MissingFileError(p, f"no such tile set file or catalog name (catalog: {names})")


def load_named(name_or_path):
    """Load a tile set by catalog name or path."""
    from geotex.tiles.tileset import load_tileset

    return load_tileset(tileset_path(name_or_path))


def list_tilesets() -> list[dict]:
    """Catalog entries: name, file, size in bytes, tiles, colours, recipe."""
    out = []
    for name, recipe in sorted(recipes().items()):
        f = CATALOG_DIR / f"{name}.npz"
        out.append({"name": name, "file": str(f), "bytes": f.stat().st_size if f.is_file()
                    else 0, "tiles": recipe.get("tiles"), "colors": recipe.get("colors"),
                    "planar": recipe.get("planar", False),
                    "exemplar": recipe.get("exemplar", {}).get("name"),
                    "description": recipe.get("description", "")})
    return out


def rebuild(name: str, *, progress=None):
    """Build the catalog set ``name`` from its recipe.

    Returns
    -------
    TileSet

    Raises
    ------
    InputError
        Unknown name.
    """
    from geotex.exemplars import exemplar
    from geotex.tiles.build import build_tileset

    table = recipes()
    if name not in table:
        raise InputError(f"{name!r} is not in the tile catalog ({', '.join(sorted(table))})")
    r = table[name]
    ex = exemplar(r["exemplar"]["name"], **r["exemplar"].get("params", {}))
    return build_tileset(ex, colors=r["colors"], planar=r.get("planar", False),
                         seed=r["seed"], interior=r.get("interior", "paste"), name=name,
                         progress=progress)
