"""Shells: base solids with their polycube map, ready to receive tiles.

Build one with :func:`build_shell`, save and load with :func:`save_shell` /
:func:`load_shell`, use the catalog shipped with geotex (:func:`list_shells`,
:func:`shell_path`, :func:`load_named`), and map tile points onto the base
with :func:`locate_on_quads` / :func:`quad_points_to_shell`.

The names below are imported on first use (module ``__getattr__``), so that
``geotex map`` names a missing shell file (:func:`shell_path`) before the
polycube machinery loads (~0.3 s CPU).
"""

__all__ = ["Shell", "build_shell", "offset_directions", "max_offset_height", "SHELL_STAGES",
           "bare_area", "bare_warning", "save_shell", "load_shell", "list_shells", "shell_path",
           "load_named", "locate_on_quads", "quad_points_to_base", "quad_points_to_shell",
           "scaled_shell"]

_HOMES = {
    "build": ("Shell", "build_shell", "offset_directions", "max_offset_height", "SHELL_STAGES",
              "bare_area", "bare_warning"),
    "store": ("save_shell", "load_shell"),
    "catalog": ("list_shells", "shell_path", "load_named"),
    "locate": ("locate_on_quads", "quad_points_to_base", "quad_points_to_shell"),
    "scale": ("scaled_shell",),
}


def __getattr__(name):
    if name in _HOMES["catalog"]:
        from geotex.shells import catalog as home
    elif name in _HOMES["build"]:
        from geotex.shells import build as home
    elif name in _HOMES["store"]:
        from geotex.shells import store as home
    elif name in _HOMES["locate"]:
        from geotex.shells import locate as home
    elif name in _HOMES["scale"]:
        from geotex.shells import scale as home
    else:
        raise AttributeError(f"module 'geotex.shells' has no attribute {name!r}")
    return getattr(home, name)


def __dir__():
    return sorted(set(globals()) | set(__all__))
