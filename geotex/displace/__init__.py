"""Height-map relief for makers: ``geotex displace`` as Python.

A grey image (a file or one of the procedural library's seamless maps) is
laid on a part by a mapping (triplanar, cubic, cylindrical, spherical,
planar, uv, pgp, lapped), masked, and displaced through the shared relief
core :func:`geotex.relief.displaced_solid`.

The names below are imported on first use (module ``__getattr__``): the
``geotex`` parser reads :mod:`geotex.displace.choices` for every command,
and that must not import the displacement machinery (check, relief, image
reading: ~0.15 s CPU of ``geotex --help``).
"""

__all__ = ["displaced_mesh", "displace_file", "DisplaceResult", "depth_warnings",
           "DISPLACE_STAGES", "MAPPINGS", "MappingOptions", "mapping_options", "MaskOptions",
           "mask_options", "face_selection", "painted_faces", "refuse_broken_part",
           "load_height_map", "filtered_height_map", "sample_periodic"]

_HOMES = {
    "api": ("DISPLACE_STAGES", "DisplaceResult", "depth_warnings", "displace_file",
            "displaced_mesh", "refuse_broken_part"),
    "heightmap": ("filtered_height_map", "load_height_map", "sample_periodic"),
    "mappings": ("MAPPINGS", "MappingOptions", "mapping_options"),
    "masks": ("MaskOptions", "face_selection", "mask_options", "painted_faces"),
}


def __getattr__(name):
    if name in _HOMES["api"]:
        from geotex.displace import api as home
    elif name in _HOMES["heightmap"]:
        from geotex.displace import heightmap as home
    elif name in _HOMES["mappings"]:
        from geotex.displace import mappings as home
    elif name in _HOMES["masks"]:
        from geotex.displace import masks as home
    else:
        raise AttributeError(f"module 'geotex.displace' has no attribute {name!r}")
    return getattr(home, name)


def __dir__():
    return sorted(set(globals()) | set(__all__))
