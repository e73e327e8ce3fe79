"""Geometric Wang tile sets: colours, edge strips, frames, interiors, tilings.

Build a set from an exemplar (:func:`build_tileset`: planar, complete or
isotropic, interiors by constrained quilting or paste), verify that every pair
of tiles that may meet is seamless (:func:`check_seams`), lay out random legal
tilings of the plane (:func:`random_arrangement`, :func:`planar_tiling`), save
and load sets (:func:`save_tileset`, :func:`load_tileset`), and use the catalog
shipped with geotex (:func:`list_tilesets`, :func:`load_named`).
"""

from geotex.tiles.colors import COMPLETE_GROUPS, PLANAR_GROUPS, tile_count
from geotex.tiles.tileset import TileSet, load_tileset, save_tileset

__all__ = ["build_tileset", "check_seams", "TileSet", "load_tileset", "save_tileset",
           "random_arrangement", "planar_tiling", "on_slab", "list_tilesets", "load_named",
           "tileset_path", "tile_count", "PLANAR_GROUPS", "COMPLETE_GROUPS"]

_CATALOG = ("list_tilesets", "load_named", "tileset_path")


def __getattr__(name):
    # the catalog module is imported on first use, so that
    # ``python -m geotex.tiles.catalog`` runs it without a second copy
    if name in _CATALOG:
        from geotex.tiles import catalog
        return getattr(catalog, name)
    # building, checking and tiling sets (quilting, exemplars, scipy.ndimage: ~0.12 s
    # to import) are imported on first use: using a set (the main job) needs none of it
    if name == "build_tileset":
        from geotex.tiles.build import build_tileset
        return build_tileset
    if name == "check_seams":
        from geotex.tiles.verify import check_seams
        return check_seams
    if name in ("random_arrangement", "planar_tiling", "on_slab"):
        from geotex.tiles import tiling
        return getattr(tiling, name)
    raise AttributeError(f"module 'geotex.tiles' has no attribute {name!r}")
