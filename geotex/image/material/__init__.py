"""Material-space textures (Ray, Levy, Wang, Turk, Vallet 2009): periodic (s, t, m) tiles.

==============  ============================================================
``tileable``    a periodic tile and its feature mask from an image (graph cut)
``morph``       feature-mask morphing by enhanced level-set advection
``synthesis``   constrained per-layer synthesis (indirection-map pyramids)
``tile``        the (s, t, m) tile: build, sample, ``.npz`` file, pictures
``mapping``     material field, periodicity hiding, local update, atlas bake
==============  ============================================================
"""

from geotex.image.material.mapping import (MaterialUpdate, bake_material_texture,
                                           default_material, material_locks,
                                           modulated_material, update_material)
from geotex.image.material.morph import MaskMorph, morph_masks, periodic_signed_distance
from geotex.image.material.synthesis import SynthesisOptions, synthesize_layers
from geotex.image.material.tile import (TILE_FORMAT, MaterialTile, blend_weights,
                                        build_material_tile, build_periodicity_tile,
                                        histogram_distance, load_tile, sample_tile, save_tile,
                                        tile_slices_image)
from geotex.image.material.tileable import TileableImage, feature_mask, tileable_image

__all__ = [
    "TileableImage", "tileable_image", "feature_mask",
    "MaskMorph", "morph_masks", "periodic_signed_distance",
    "SynthesisOptions", "synthesize_layers",
    "TILE_FORMAT", "MaterialTile", "build_material_tile", "build_periodicity_tile",
    "blend_weights", "sample_tile", "save_tile", "load_tile", "tile_slices_image",
    "histogram_distance",
    "MaterialUpdate", "material_locks", "default_material", "modulated_material",
    "update_material", "bake_material_texture",
]
