"""Image textures on meshes: lapped textures (Praun, Finkelstein, Hoppe 2000).

==============  ============================================================
``patches``     texture patches from an image: splotch / circle / user masks
``hull``        conservative polygon hulls and the growth edge test
``paste``       one paste: grow, triangle extension, field-aligned least squares
``coverage``    face coverage by rasterization on a per-face sample lattice
``lapped``      the pasting loop, placement priority, alignment errors
``records``     paste records and their ``.npz`` file
``composite``   the composited colour of all pastes at surface points
``atlas``       a packed texture atlas (xatlas) with the pastes composited in
``displace``    the composited texture as a height field: a printable solid
``material``    material-space (s, t, m) tiles (subpackage, imported on demand)
==============  ============================================================
"""

from geotex.image.atlas import Atlas, build_atlas, composite_atlas, rasterize_triangles, textured_mesh
from geotex.image.composite import background_color, composite_at, luminance
from geotex.image.coverage import Coverage, sample_lattice
from geotex.image.displace import displace, height_at, surface_points
from geotex.image.hull import HullTest, points_in_polygon, segments_meet_polygon, star_hull
from geotex.image.lapped import (alignment_errors, default_scale, lapped_texture,
                                 placement_priority)
from geotex.image.patches import (MASKS, TexturePatch, circle_mask, load_image, mask_from_image,
                                  sample_alpha, sample_patch, splotch_mask, texture_patches)
from geotex.image.records import LappedTexture, Paste, load_lapped, save_lapped

__all__ = [
    "TexturePatch", "MASKS", "load_image", "circle_mask", "splotch_mask", "mask_from_image",
    "texture_patches", "sample_patch", "sample_alpha",
    "star_hull", "HullTest", "points_in_polygon", "segments_meet_polygon",
    "Coverage", "sample_lattice",
    "lapped_texture", "default_scale", "placement_priority", "alignment_errors",
    "Paste", "LappedTexture", "save_lapped", "load_lapped",
    "composite_at", "background_color", "luminance",
    "Atlas", "build_atlas", "rasterize_triangles", "composite_atlas", "textured_mesh",
    "displace", "height_at", "surface_points",
]
