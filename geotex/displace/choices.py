"""The names and defaults of ``geotex displace``'s options that its parser shows.

Kept apart from the modules that use them (:mod:`geotex.displace.mappings`,
:mod:`geotex.displace.masks`, which re-export them), so that building the
``geotex`` parser (``geotex --help``, and every other command) reads them
without importing the displacement machinery.
"""

__all__ = ["MAPPINGS", "CURVES", "PAINT_TOLERANCE"]

#: How an image is laid on a part (``mapping_options``' ``name``).
MAPPINGS = ("triplanar", "cubic", "cylindrical", "spherical", "planar-xy", "planar-xz",
            "planar-yz", "uv", "pgp", "lapped")
#: Fall-off curves of soft mask borders.
CURVES = ("linear", "smoothstep", "ease-in")
#: Two colours match when no channel (0..255) differs by more than this.
PAINT_TOLERANCE = 30.0
