"""Tile sets mapped over shells: the textured, printable solid.

:func:`textured_solid` runs the whole job; its steps are :func:`edge_colors`
and :func:`tiles_for_quads` (which tile where), :func:`mapped_tiles` (tile
geometry into shell space, welded; small elements mapped as similar shapes of
one size, :mod:`geotex.mapping.shape`), :func:`element_contacts` and
:func:`reseated_elements` (elements the map folds, shrunk in place where that
helps), :mod:`~geotex.mapping.seat` (folded elements laid back on a locally
smoothed map or smoothed, floating ones lowered onto the base or stood on it
with a post) and :func:`united_with_base` (one solid).
"""

from geotex.mapping.assign import edge_colors, tiles_for_quads
from geotex.mapping.place import MappedTiles, mapped_tiles, reseated_elements, shell_positions
from geotex.mapping.seat import (floating_elements, lowered_elements, propped_elements,
                                 remapped_folds, smoothed_folds)
from geotex.mapping.texture import (MAP_PROGRESS, MAP_STAGES, TexturedSolid, TextureStats,
                                    texture_height, textured_solid)
from geotex.mapping.union import ElementContacts, UnionStats, element_contacts, united_with_base

__all__ = ["textured_solid", "TexturedSolid", "TextureStats", "MAP_STAGES", "MAP_PROGRESS", "texture_height",
           "edge_colors", "tiles_for_quads", "mapped_tiles", "MappedTiles", "shell_positions",
           "element_contacts", "ElementContacts",
           "reseated_elements", "united_with_base", "UnionStats", "floating_elements",
           "lowered_elements", "propped_elements", "remapped_folds", "smoothed_folds"]
