"""The catalog of ready-made tile sets shipped with geotex.

Sets live in ``geotex/tiles/catalog/NAME.npz`` (package data); ``recipes.json``
beside them holds the recipe of each (exemplar and its parameters, colours,
kind, interior method, seed, ...), from which :func:`rebuild` makes the same
file byte for byte. ``python -m geotex.tiles.catalog [NAME ...]`` rebuilds
the files (all of them by default) and checks each one.
"""

from __future__ import annotations

import sys
from pathlib import Path

from geotex.catalogs import Catalog
from geotex.tiles.tileset import load_tileset, save_tileset

__all__ = ["CATALOG_DIR", "MAX_BYTES", "recipes", "tileset_path", "list_tilesets",
           "rebuild", "load_named", "main"]

CATALOG_DIR = Path(__file__).resolve().parent / "catalog"
MAX_BYTES = 2_000_000          # size limit of one catalog file
CATALOG = Catalog(CATALOG_DIR, what="tile set")
recipes = CATALOG.recipes
tileset_path = CATALOG.path


def load_named(name_or_path):
    """Load a tile set by catalog name or path.

    Returns
    -------
    TileSet
    """
    return load_tileset(tileset_path(name_or_path))


def _kind(recipe: dict) -> str:
    if recipe.get("directional"):
        return "directional"
    if recipe.get("isotropic"):
        return "isotropic"
    return "planar" if recipe.get("planar") else "complete"


def list_tilesets() -> list[dict]:
    """Catalog entries: name, kind, file, size in bytes, tiles, colours, exemplar, description.

    ``kind`` is ``"planar"``, ``"complete"``, ``"isotropic"`` or ``"directional"``
    (:mod:`geotex.tiles.directional`: planar base tiles turned to a flow when mapped).
    """
    out = []
    for e in CATALOG.entries():
        recipe = e["recipe"]
        out.append({"name": e["name"], "kind": _kind(recipe), "file": e["file"],
                    "bytes": e["bytes"], "tiles": recipe.get("tiles"),
                    "colors": recipe.get("colors"), "planar": recipe.get("planar", False),
                    "isotropic": recipe.get("isotropic", False),
                    "directional": recipe.get("directional", False),
                    "exemplar": recipe.get("exemplar", {}).get("name"),
                    "description": recipe.get("description", "")})
    return out


def rebuild(name: str, *, progress=None, table: dict | None = None, map_tiles=None):
    """Build the catalog set ``name`` from its recipe.

    Parameters
    ----------
    name : str
    progress : callable, optional
        Passed to :func:`~geotex.tiles.build.build_tileset`.
    table : dict, optional
        Recipes to use instead of ``recipes.json``.
    map_tiles : callable, optional
        Where the tiles are built (:func:`~geotex.tiles.build.build_tileset`);
        the set is the same byte for byte.

    Returns
    -------
    TileSet

    Raises
    ------
    InputError
        Unknown name.
    """
    from geotex.exemplars import exemplar
    from geotex.tiles.build import QUILT_ATTEMPTS, build_tileset

    r = CATALOG.recipe(name, table)
    ex = exemplar(r["exemplar"]["name"], **r["exemplar"].get("params", {}))
    return build_tileset(ex, colors=r["colors"], planar=r.get("planar", False),
                         isotropic=r.get("isotropic", False), lattice=r.get("lattice", False),
                         directional=r.get("directional", False),
                         corner_patch=r.get("corner_patch", False),
                         corner_merge=r.get("corner_merge", False),
                         quilt_attempts=r.get("quilt_attempts", QUILT_ATTEMPTS),
                         quilt_best_of=r.get("quilt_best_of", 1),
                         quilted_source=r.get("quilted_source", False),
                         seed=r["seed"], interior=r.get("interior", "paste"), name=name,
                         progress=progress, map_tiles=map_tiles)


def main(argv=None) -> int:
    """Rebuild catalog files from ``recipes.json`` (all, or the names given).

    Each set is built, checked for seams (:func:`~geotex.tiles.verify.check_seams`)
    and written to ``CATALOG_DIR/NAME.npz`` when seamless and at most
    :data:`MAX_BYTES`. Returns 0 when every set passed, 1 otherwise.
    """
    import time

    from geotex.tiles.verify import check_seams

    names = list(argv if argv is not None else sys.argv[1:]) or sorted(recipes())
    status = 0
    for name in names:
        start = time.perf_counter()
        tiles = rebuild(name)
        elapsed = time.perf_counter() - start
        rep = check_seams(tiles)
        out = CATALOG.file(name)
        if not rep.ok:
            print(f"{name}: NOT seamless: {rep.problems[0]}", file=sys.stderr)
            status = 1
            continue
        save_tileset(out, tiles)
        size = out.stat().st_size
        print(f"{name}: {tiles.kind}, {len(tiles)} tiles, {size / 1e6:.2f} MB, "
              f"{elapsed:.1f} s ({elapsed / len(tiles):.2f} s per tile), "
              f"{rep.pairs_checked} side pairs seamless, coverage "
              f"{tiles.metadata['coverage_mean']:.0%}, "
              f"{tiles.metadata.get('paste_fallbacks', 0)} tiles pasted after quilting failed")
        if size > MAX_BYTES:
            print(f"{name}: {size} bytes is over the {MAX_BYTES} byte limit", file=sys.stderr)
            status = 1
    return status


if __name__ == "__main__":
    raise SystemExit(main())
