"""Height-map relief for makers: ``geotex displace`` as Python.

A grey image (a file or one of the procedural library's seamless maps) is
laid on a part by a mapping (triplanar, cubic, cylindrical, spherical,
planar, uv, pgp, lapped), masked, and displaced through the shared relief
core :func:`geotex.relief.displaced_solid`.
"""

from geotex.displace.api import (DISPLACE_STAGES, DisplaceResult, depth_warnings,
                                 displace_file, displaced_mesh, refuse_broken_part)
from geotex.displace.heightmap import filtered_height_map, load_height_map, sample_periodic
from geotex.displace.mappings import MAPPINGS, MappingOptions, mapping_options
from geotex.displace.masks import MaskOptions, face_selection, mask_options, painted_faces

__all__ = ["displaced_mesh", "displace_file", "DisplaceResult", "depth_warnings",
           "DISPLACE_STAGES", "MAPPINGS", "MappingOptions", "mapping_options", "MaskOptions",
           "mask_options", "face_selection", "painted_faces", "refuse_broken_part",
           "load_height_map", "filtered_height_map", "sample_periodic"]
